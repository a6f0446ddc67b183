//! Newton's method for a nodal system R(Δu) = 0 (docs/theory.md §6), as the control that
//! the caller's loop consults: the loop itself — update points and residual, assemble,
//! solve, check — is written out in the implicit step, where it can be read.
//!
//! Each iteration solves K δ = −R, adds δ to the increment and re-evaluates. Where the
//! correction raised the residual's norm (a point crossed a yield surface's corner, a
//! mechanism opened, the first iterate of a plastic step overshot), the caller backtracks
//! along it ([`NewtonControl::backtrack`]): a line search on ½‖R‖² (Dennis & Schnabel,
//! Numerical Methods for Unconstrained Optimization, 1983, §6.3.2), whose slope at the
//! start is −‖R‖² for a Newton direction. A step is
//! converged when the relative residual ‖R‖ / ‖reference force‖ and the relative correction
//! ‖δ‖ / ‖Δu‖ are both below their tolerances, after at least one correction — or, for a
//! step that starts in equilibrium, when its first correction keeps the residual there. It
//! fails — and the caller must cut the step back — on a non-finite residual, a residual
//! that grows past `divergence_factor` times the initial one, a failed factorisation or the
//! iteration limit. An unconverged step is never reported as converged.
//!
//! The line search is off by default: where whole corrections converge they converge
//! quadratically, and shortening them near a corner of a yield surface can cost more
//! corrections than it saves. But a solve that fails with whole corrections is started
//! again from the same increment with the line search ([`NewtonSettings::retry`]) before
//! the caller cuts the step back: the first iterate of a step in which many points yield
//! at once can overshoot so far that whole corrections never recover, where a shortened
//! one does (a refined 3D slope's first load step).
//!
//! An iterative linear solver is asked for the relative residual of
//! [`NewtonControl::linear_tolerance`], an inexact-Newton forcing term (Eisenstat & Walker,
//! SIAM J. Sci. Comput. 17, 1996, choice 2): loose while Newton is far from the solution,
//! tightening as it converges quadratically, and never tighter than what takes the next
//! residual below Newton's own tolerance.

use crate::LinearSolveError;

/// Convergence settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonSettings {
    /// Relative residual tolerance ‖R‖ / ‖f_ref‖.
    pub residual_tolerance: f64,
    /// Relative correction tolerance ‖δ‖ / ‖Δu‖.
    pub increment_tolerance: f64,
    /// Most corrections per step.
    pub max_iterations: usize,
    /// A relative residual this many times the initial one counts as divergence.
    pub divergence_factor: f64,
    /// Most backtracks along one correction that raised the residual's norm (the line
    /// search, module docs); 0 (the default) takes every correction whole.
    pub max_backtracks: usize,
    /// Where a solve that takes every correction whole fails, it is started again from
    /// the same increment with this many backtracks a correction before the caller cuts
    /// the step back (module docs); 0: no second try.
    pub retry_backtracks: usize,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            residual_tolerance: 1e-9,
            increment_tolerance: 1e-6,
            max_iterations: 20,
            divergence_factor: 1e8,
            max_backtracks: 0,
            retry_backtracks: 4,
        }
    }
}

impl NewtonSettings {
    /// The settings of the second try after a solve with whole corrections failed, or
    /// `None` when there is none: the solve already backtracked, or no retry is asked for.
    pub fn retry(&self) -> Option<Self> {
        (self.max_backtracks == 0 && self.retry_backtracks > 0)
            .then_some(Self { max_backtracks: self.retry_backtracks, ..*self })
    }
}

/// What one Newton solve did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NewtonReport {
    /// Relative residual before the first correction and after each one.
    pub residuals: Vec<f64>,
    /// Relative correction ‖δ‖ / ‖Δu‖ of each correction.
    pub increments: Vec<f64>,
    /// Krylov iterations of the corrections' linear solves (0 with a direct solver).
    pub linear_iterations: usize,
    /// Seconds spent preparing the linear solves: factorisations, or multigrid set-up.
    pub linear_setup_s: f64,
    /// Corrections whose Krylov solve failed and were solved by a direct solver instead.
    pub direct_fallbacks: u32,
    /// Corrections of a first try with whole corrections that failed, before this solve
    /// started again with the line search ([`NewtonSettings::retry_backtracks`]); the
    /// residuals and increments above are the second try's. (This and `direct_fallbacks`
    /// are `u32`s, which keeps `NewtonError` within 128 bytes.)
    pub abandoned: u32,
}

impl NewtonReport {
    /// Number of corrections (linear solves) made, those of an abandoned first try
    /// included.
    pub fn iterations(&self) -> usize {
        self.abandoned as usize + self.increments.len()
    }

    /// This report of a second try, after a first try whose report is `first` failed:
    /// its corrections and linear work are counted here.
    pub fn after_failed_try(mut self, first: &NewtonReport) -> Self {
        self.abandoned += u32::try_from(first.iterations()).unwrap_or(u32::MAX);
        self.linear_iterations += first.linear_iterations;
        self.linear_setup_s += first.linear_setup_s;
        self.direct_fallbacks += first.direct_fallbacks;
        self
    }

    pub fn final_residual(&self) -> f64 {
        self.residuals.last().copied().unwrap_or(f64::NAN)
    }
}

/// Why a Newton solve failed. The report holds the residual history up to the failure.
#[derive(Debug, thiserror::Error)]
pub enum NewtonError<E: std::error::Error + 'static> {
    #[error("no convergence in {} iterations (relative residual {:.3e})", .0.iterations(), .0.final_residual())]
    IterationLimit(NewtonReport),
    #[error("diverged: relative residual {:.3e} after {} iterations", .0.final_residual(), .0.iterations())]
    Diverged(NewtonReport),
    #[error("residual is NaN or infinite after {} iterations", .0.iterations())]
    NonFinite(NewtonReport),
    #[error("linear solver: {source}")]
    Linear { source: LinearSolveError, report: NewtonReport },
    #[error("{source}")]
    Problem { source: E, report: NewtonReport },
}

impl<E: std::error::Error + 'static> NewtonError<E> {
    pub fn report(&self) -> &NewtonReport {
        match self {
            NewtonError::IterationLimit(r) | NewtonError::Diverged(r) | NewtonError::NonFinite(r) => r,
            NewtonError::Linear { report, .. } | NewtonError::Problem { report, .. } => report,
        }
    }
}

/// Forcing term of the first Newton iteration, and the loosest of any: four digits. A
/// Newton iteration (points, assembly, multigrid set-up) costs about twenty Krylov
/// iterations, so over-solving is cheap and an extra Newton iteration is not. With the
/// 10⁻¹ cap of the usual choice the plastic footing of `examples/footing_von_mises.ron`
/// took 491 Newton iterations instead of the direct solver's 437; with 10⁻⁴, 437.
const FORCING_FIRST: f64 = 1e-4;
const FORCING_MAX: f64 = 1e-4;
/// The tightest: near the round-off of a Krylov solve in double precision.
const FORCING_MIN: f64 = 1e-12;

/// The Euclidean norm of a vector, summed in index order.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// The control of one Newton solve: its residual history and its convergence, divergence
/// and iteration-limit tests, consulted by the caller's loop. See the module docs.
#[derive(Debug, Clone)]
pub struct NewtonControl {
    settings: NewtonSettings,
    report: NewtonReport,
    /// The relative residual of the starting increment.
    initial: f64,
}

impl NewtonControl {
    /// Start a solve whose starting increment left a residual of norm `residual` against
    /// the reference force norm `reference`; fails if that residual is not finite.
    pub fn start<E: std::error::Error>(
        settings: NewtonSettings,
        residual: f64,
        reference: f64,
    ) -> Result<Self, NewtonError<E>> {
        let initial = relative(residual, reference);
        let report = NewtonReport { residuals: vec![initial], ..Default::default() };
        if !initial.is_finite() {
            return Err(NewtonError::NonFinite(report));
        }
        Ok(Self { settings, report, initial })
    }

    /// Make room for one more correction: fails once `max_iterations` corrections have not
    /// converged.
    pub fn next_iteration<E: std::error::Error>(&self) -> Result<(), NewtonError<E>> {
        if self.report.iterations() >= self.settings.max_iterations {
            return Err(NewtonError::IterationLimit(self.report.clone()));
        }
        Ok(())
    }

    /// Record a correction of norm `correction` that left an increment of norm `increment`.
    pub fn corrected(&mut self, correction: f64, increment: f64) {
        self.report.increments.push(relative(correction, increment));
    }

    /// The line search (module docs): a correction taken at step length `alpha` left a
    /// residual of norm `after` (infinite where the problem could not be evaluated there)
    /// where it was `before`. Returns the shorter length to try next — the minimiser of the
    /// quadratic that matches ½‖R‖² at 0 (value and slope −‖R₀‖²) and at `alpha`, kept
    /// within [0.1, 0.5] `alpha` — or `None` to keep `alpha`: the residual did not grow, or
    /// this correction has had its `max_backtracks`.
    pub fn backtrack(&self, before: f64, after: f64, alpha: f64, backtracks: usize) -> Option<f64> {
        if after <= before || backtracks >= self.settings.max_backtracks {
            return None;
        }
        let (r0, ra) = (before * before, after * after);
        let minimiser = if ra.is_finite() { alpha * alpha * r0 / (ra - r0 + 2.0 * r0 * alpha) } else { 0.0 };
        Some(minimiser.clamp(0.1 * alpha, 0.5 * alpha))
    }

    /// Record the Krylov iterations and the set-up time of the last linear solve, and
    /// whether a direct solver had to take it over.
    pub fn linear_solved(&mut self, iterations: usize, setup: std::time::Duration, fell_back: bool) {
        self.report.linear_iterations += iterations;
        self.report.linear_setup_s += setup.as_secs_f64();
        self.report.direct_fallbacks += u32::from(fell_back);
    }

    /// Check the residual after the last correction: `Ok(true)` when converged, `Ok(false)`
    /// when another correction is needed, an error when the residual is not finite or has
    /// diverged.
    pub fn converged<E: std::error::Error>(&mut self, residual: f64, reference: f64) -> Result<bool, NewtonError<E>> {
        let s = self.settings;
        let rk = relative(residual, reference);
        self.report.residuals.push(rk);
        tracing::debug!(iteration = self.report.iterations(), residual = rk, "newton");
        if !rk.is_finite() {
            return Err(NewtonError::NonFinite(self.report.clone()));
        }
        if rk > s.divergence_factor * self.initial.max(s.residual_tolerance) {
            return Err(NewtonError::Diverged(self.report.clone()));
        }
        // The relative correction means nothing when the step started in equilibrium
        // (a geostatic state, a load step that adds nothing): Δu is then round-off
        // itself, and ‖δ‖/‖Δu‖ ≈ 1 for ever. Such a step is converged when its one
        // correction kept the residual within tolerance.
        let inc = self.report.increments.last().copied().unwrap_or(f64::INFINITY);
        Ok(rk <= s.residual_tolerance && (inc <= s.increment_tolerance || self.initial <= s.residual_tolerance))
    }

    /// The relative residual the next linear solve must reach (see the module docs):
    /// η = 0.9 (r_k / r_{k−1})² (Eisenstat–Walker choice 2, γ = 0.9, α = 2) once it is
    /// below `FORCING_MAX`, `FORCING_FIRST`
    /// for the first solve, at least half the ratio of Newton's tolerance to the current
    /// residual (no solve more exact than the step needs), within
    /// [`FORCING_MIN`, `FORCING_MAX`].
    pub fn linear_tolerance(&self) -> f64 {
        let r = &self.report.residuals;
        let current = *r.last().expect("a solve has a starting residual");
        let eta = match r.len() {
            0 | 1 => FORCING_FIRST,
            k => 0.9 * (current / r[k - 2]).powi(2),
        };
        let sufficient = 0.5 * self.settings.residual_tolerance / current;
        let eta = if eta.is_finite() { eta.max(sufficient) } else { FORCING_FIRST };
        eta.clamp(FORCING_MIN, FORCING_MAX)
    }

    /// The failure of a linear solve, with the history so far.
    pub fn linear_failure<E: std::error::Error>(&self, source: LinearSolveError) -> NewtonError<E> {
        NewtonError::Linear { source, report: self.report.clone() }
    }

    /// The failure of the problem's own evaluation (a point's update), with the history so
    /// far.
    pub fn problem_failure<E: std::error::Error>(&self, source: E) -> NewtonError<E> {
        NewtonError::Problem { source, report: self.report.clone() }
    }

    pub fn into_report(self) -> NewtonReport {
        self.report
    }
}

/// `r / reference`, 0 for a zero residual whatever the reference.
fn relative(r: f64, reference: f64) -> f64 {
    if r == 0.0 {
        0.0
    } else {
        r / reference.max(f64::MIN_POSITIVE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::tests::Chain;
    use crate::{BlockPattern, LinearSolverKind, SparseDirectSolver};

    /// A chain of nonlinear springs, force k (e + e³) for elongation e, node 0 fixed,
    /// load P at the last node: each spring carries P, so e solves e + e³ = P / k.
    struct Springs {
        chain: Chain,
        pattern: BlockPattern,
        values: Vec<f64>,
        u: Vec<f64>,
        load: f64,
        fixed: Vec<bool>,
    }

    #[derive(Debug, thiserror::Error)]
    #[error("never")]
    struct Never;

    impl Springs {
        /// The residual at `du` (zero on fixed dofs), into `r`; the reference force is the load.
        fn residual(&mut self, du: &[f64], r: &mut [f64]) -> f64 {
            self.u.copy_from_slice(du);
            r.iter_mut().for_each(|v| *v = 0.0);
            for (e, nodes) in self.chain.elems.iter().enumerate() {
                let (a, b) = (nodes[0] as usize, nodes[1] as usize);
                let k = 1.0 + e as f64;
                let el = self.u[b] - self.u[a];
                let f = k * (el + el * el * el);
                r[a] -= f;
                r[b] += f;
            }
            let last = r.len() - 1;
            r[last] -= self.load;
            for (ri, &fx) in r.iter_mut().zip(&self.fixed) {
                if fx {
                    *ri = 0.0;
                }
            }
            self.load.abs()
        }

        fn assemble(&mut self) {
            let u = self.u.clone();
            let elems = self.chain.elems.clone();
            self.pattern.assemble(&self.chain, &self.fixed, &mut self.values, |e, a, b, out| {
                let (na, nb) = (elems[e][0] as usize, elems[e][1] as usize);
                let el = u[nb] - u[na];
                let k = (1.0 + e as f64) * (1.0 + 3.0 * el * el);
                out[0] += if a == b { k } else { -k };
            });
        }

        /// Newton's loop as the implicit step writes it: residual, then until converged
        /// assemble, solve, correct, residual, check.
        fn solve(&mut self, settings: NewtonSettings, du: &mut [f64]) -> Result<NewtonReport, NewtonError<Never>> {
            let mut linear = SparseDirectSolver::new(LinearSolverKind::Cholesky);
            let mut r = vec![0.0; du.len()];
            let reference = self.residual(du, &mut r);
            let mut newton = NewtonControl::start(settings, norm(&r), reference)?;
            loop {
                newton.next_iteration()?;
                self.assemble();
                linear.factorize(&self.pattern, &self.values).map_err(|e| newton.linear_failure(e))?;
                let mut delta: Vec<f64> = r.iter().map(|v| -v).collect();
                linear.solve_in_place(&mut delta).map_err(|e| newton.linear_failure(e))?;
                du.iter_mut().zip(&delta).for_each(|(u, d)| *u += d);
                newton.corrected(norm(&delta), norm(du));
                let reference = self.residual(du, &mut r);
                if newton.converged(norm(&r), reference)? {
                    return Ok(newton.into_report());
                }
            }
        }
    }

    #[test]
    fn nonlinear_springs_converge_quadratically_to_the_closed_form() {
        let chain = Chain::new(3);
        let mut pattern = BlockPattern::new(1);
        pattern.update(&chain);
        let mut fixed = vec![false; 4];
        fixed[0] = true;
        let mut p = Springs { chain, pattern, values: vec![], u: vec![0.0; 4], load: 2.0, fixed };
        let settings = NewtonSettings { residual_tolerance: 1e-12, increment_tolerance: 1e-10, ..Default::default() };
        let mut du = vec![0.0; 4];
        let report = p.solve(settings, &mut du).unwrap();
        // Closed form: e_k solves e + e³ = P / k (Cardano via Newton on the scalar is not
        // independent, so check the defining equation itself to rounding).
        let mut x = 0.0;
        for k in 1..=3 {
            let e = du[k] - du[k - 1];
            assert!((k as f64 * (e + e * e * e) - 2.0).abs() < 1e-11);
            x += e;
        }
        assert!((du[3] - x).abs() < 1e-15);
        // Quadratic convergence: once in the asymptotic range, log r_{k+1} / log r_k ≈ 2.
        // The rate is read on the last pair above the round-off floor (1e-13 here).
        let r: Vec<f64> = report.residuals.iter().copied().filter(|&v| v > 1e-13).collect();
        let n = r.len();
        assert!(n >= 3);
        let rate = r[n - 1].ln() / r[n - 2].ln();
        assert!(rate > 1.7, "residuals {r:?}");
    }

    #[test]
    fn iteration_limit_is_an_error_not_a_result() {
        let chain = Chain::new(3);
        let mut pattern = BlockPattern::new(1);
        pattern.update(&chain);
        let mut fixed = vec![false; 4];
        fixed[0] = true;
        let mut p = Springs { chain, pattern, values: vec![], u: vec![0.0; 4], load: 50.0, fixed };
        let mut du = vec![0.0; 4];
        let err = p.solve(NewtonSettings { max_iterations: 2, ..Default::default() }, &mut du).unwrap_err();
        assert!(matches!(err, NewtonError::IterationLimit(_)), "{err}");
        assert_eq!(err.report().iterations(), 2);
    }

    /// Newton on r(x) = atan x − atan 1 from x = 3, the loop of the implicit step with its
    /// line search: the full corrections overshoot ever further (3 → −1.64 → 5.0 → …,
    /// the classic divergence of Newton on arctan) and fail; backtracking along them
    /// converges to the root x = 1, quadratically once the full step is taken again.
    #[test]
    fn the_line_search_turns_a_diverging_newton_into_a_converging_one() {
        let residual = |x: f64| x.atan() - 1f64.atan();
        let solve = |max_backtracks: usize| -> Result<(f64, NewtonReport, usize), NewtonError<Never>> {
            let settings = NewtonSettings { max_backtracks, residual_tolerance: 1e-12, ..Default::default() };
            let (mut x, mut shortened) = (3.0, 0);
            let mut newton = NewtonControl::start(settings, residual(x).abs(), 1.0)?;
            loop {
                newton.next_iteration()?;
                let before = residual(x).abs();
                let correction = -residual(x) * (1.0 + x * x);
                let (mut alpha, mut backtracks) = (1.0, 0);
                x += correction;
                while let Some(shorter) = newton.backtrack(before, residual(x).abs(), alpha, backtracks) {
                    x -= (alpha - shorter) * correction;
                    (alpha, backtracks) = (shorter, backtracks + 1);
                }
                shortened += backtracks;
                newton.corrected((alpha * correction).abs(), x.abs());
                if newton.converged(residual(x).abs(), 1.0)? {
                    return Ok((x, newton.into_report(), shortened));
                }
            }
        };
        assert!(solve(0).is_err(), "full Newton steps from x = 3 diverge");
        let (x, report, shortened) = solve(4).unwrap();
        assert!((x - 1.0).abs() < 1e-12, "{x}");
        assert!(shortened > 0);
        let r = &report.residuals;
        let n = r.len();
        assert!(r[n - 1].ln() / r[n - 2].ln() > 1.7, "quadratic at the end: {r:?}");
    }

    /// The step the line search proposes: none where the residual did not grow or the
    /// backtracks are spent; the quadratic model's minimiser (exact for a quadratic ½‖R‖²)
    /// within [0.1, 0.5] of the last length; a tenth where the residual is not finite.
    #[test]
    fn the_backtrack_is_the_quadratic_models_minimiser_within_its_safeguards() {
        let settings = NewtonSettings { max_backtracks: 4, ..Default::default() };
        let newton = NewtonControl::start::<Never>(settings, 1.0, 1.0).unwrap();
        assert_eq!(newton.backtrack(1.0, 0.9, 1.0, 0), None);
        assert_eq!(newton.backtrack(1.0, 2.0, 1.0, 4), None);
        // ½‖R(α)‖² = ½(1 − α)² + ½ c α² with c = 3: ‖R(1)‖ = √3, minimiser 1/(1 + c) = 0.25.
        assert!((newton.backtrack(1.0, 3f64.sqrt(), 1.0, 0).unwrap() - 0.25).abs() < 1e-15);
        // A residual barely grown: 1 / (1.01² + 1), just under a half.
        assert!((newton.backtrack(1.0, 1.01, 1.0, 0).unwrap() - 1.0 / 2.0201).abs() < 1e-15);
        // From α = 0.5 with a residual that exploded: the model's minimiser is far below
        // the last length, so a tenth of it.
        assert_eq!(newton.backtrack(1.0, 1e9, 0.5, 1), Some(0.05));
        assert_eq!(newton.backtrack(1.0, f64::INFINITY, 1.0, 0), Some(0.1));
        assert_eq!(newton.backtrack(1.0, f64::NAN, 1.0, 0), Some(0.1));
    }

    /// The second try backtracks only where the first took whole corrections, and its
    /// report counts the first try's corrections and linear work.
    #[test]
    fn a_second_try_follows_only_whole_corrections_and_counts_the_first() {
        let whole = NewtonSettings::default();
        assert_eq!(whole.retry().map(|r| r.max_backtracks), Some(4));
        assert_eq!(NewtonSettings { retry_backtracks: 0, ..whole }.retry(), None);
        assert_eq!(NewtonSettings { max_backtracks: 2, ..whole }.retry(), None);
        let first = NewtonReport {
            residuals: vec![1.0, 2.0, 3.0],
            increments: vec![1.0, 1.0],
            linear_iterations: 7,
            direct_fallbacks: 1,
            ..Default::default()
        };
        let second = NewtonReport { residuals: vec![1.0, 1e-12], increments: vec![1e-9], ..Default::default() };
        let both = second.after_failed_try(&first);
        assert_eq!((both.iterations(), both.abandoned, both.linear_iterations, both.direct_fallbacks), (3, 2, 7, 1));
        assert_eq!(both.final_residual(), 1e-12);
    }
}
