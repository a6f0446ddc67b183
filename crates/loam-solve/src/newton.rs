//! Newton's method for a nodal system R(Δu) = 0 (THEORY.md §7).
//!
//! Each iteration solves K δ = −R, adds δ to the increment and re-evaluates. A step is
//! converged when the relative residual ‖R‖ / ‖reference force‖ and the relative correction
//! ‖δ‖ / ‖Δu‖ are both below their tolerances, after at least one correction — or, for a
//! step that starts in equilibrium, when its first correction keeps the residual there. It fails —
//! and the caller must cut the step back — on a non-finite residual, a residual that grows
//! past `divergence_factor` times the initial one, a failed factorisation or the iteration
//! limit. An unconverged step is never reported as converged.

use crate::{BlockPattern, LinearSolveError, SparseDirectSolver};

/// The problem side of Newton's method.
pub trait NewtonProblem {
    type Error: std::error::Error + Send + Sync + 'static;
    /// Number of unknowns.
    fn num_dofs(&self) -> usize;
    /// Evaluate the state at increment `du`: write the residual (zero on constrained dofs)
    /// into `r` and return the reference force norm used to make it relative. Material
    /// tangents needed by `assemble` are computed here.
    fn evaluate(&mut self, du: &[f64], r: &mut [f64]) -> Result<f64, Self::Error>;
    /// Assemble the tangent at the state of the last `evaluate`.
    fn assemble(&mut self);
    /// The assembled tangent.
    fn matrix(&self) -> (&BlockPattern, &[f64]);
}

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
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self { residual_tolerance: 1e-9, increment_tolerance: 1e-6, max_iterations: 20, divergence_factor: 1e8 }
    }
}

/// What one Newton solve did.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NewtonReport {
    /// Relative residual before the first correction and after each one.
    pub residuals: Vec<f64>,
    /// Relative correction ‖δ‖ / ‖Δu‖ of each correction.
    pub increments: Vec<f64>,
}

impl NewtonReport {
    /// Number of corrections (linear solves) made.
    pub fn iterations(&self) -> usize {
        self.increments.len()
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

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// Newton's method with reusable scratch buffers and a reusable linear solver.
pub struct NewtonSolver {
    pub settings: NewtonSettings,
    linear: SparseDirectSolver,
    residual: Vec<f64>,
    correction: Vec<f64>,
}

impl NewtonSolver {
    pub fn new(settings: NewtonSettings, linear: SparseDirectSolver) -> Self {
        Self { settings, linear, residual: Vec::new(), correction: Vec::new() }
    }

    pub fn linear_solver(&self) -> &SparseDirectSolver {
        &self.linear
    }

    /// Replace the linear solver (e.g. when a material's tangent symmetry asks for LU).
    pub fn set_linear_solver(&mut self, linear: SparseDirectSolver) {
        self.linear = linear;
    }

    /// Solve R(du) = 0 starting from `du` (usually zero), which holds the converged
    /// increment on success.
    pub fn solve<P: NewtonProblem>(
        &mut self,
        problem: &mut P,
        du: &mut [f64],
    ) -> Result<NewtonReport, NewtonError<P::Error>> {
        let n = problem.num_dofs();
        assert_eq!(du.len(), n);
        self.residual.resize(n, 0.0);
        self.correction.resize(n, 0.0);
        let mut report = NewtonReport::default();
        let s = self.settings;

        let mut reference = match problem.evaluate(du, &mut self.residual) {
            Ok(f) => f,
            Err(source) => return Err(NewtonError::Problem { source, report }),
        };
        let relative = |r: f64, reference: f64| if r == 0.0 { 0.0 } else { r / reference.max(f64::MIN_POSITIVE) };
        let r0 = relative(norm(&self.residual), reference);
        report.residuals.push(r0);
        if !r0.is_finite() {
            return Err(NewtonError::NonFinite(report));
        }
        for _ in 0..s.max_iterations {
            problem.assemble();
            let (pattern, values) = problem.matrix();
            if let Err(source) = self.linear.factorize(pattern, values) {
                return Err(NewtonError::Linear { source, report });
            }
            for (c, r) in self.correction.iter_mut().zip(&self.residual) {
                *c = -r;
            }
            if let Err(source) = self.linear.solve_in_place(&mut self.correction) {
                return Err(NewtonError::Linear { source, report });
            }
            for (u, c) in du.iter_mut().zip(&self.correction) {
                *u += c;
            }
            let dnorm = norm(&self.correction);
            let unorm = norm(du);
            report.increments.push(relative(dnorm, unorm));
            reference = match problem.evaluate(du, &mut self.residual) {
                Ok(f) => f,
                Err(source) => return Err(NewtonError::Problem { source, report }),
            };
            let rk = relative(norm(&self.residual), reference);
            report.residuals.push(rk);
            tracing::debug!(iteration = report.iterations(), residual = rk, correction = dnorm, "newton");
            if !rk.is_finite() {
                return Err(NewtonError::NonFinite(report));
            }
            if rk > s.divergence_factor * r0.max(s.residual_tolerance) {
                return Err(NewtonError::Diverged(report));
            }
            // The relative correction means nothing when the step started in equilibrium
            // (a geostatic state, a load step that adds nothing): Δu is then round-off
            // itself, and ‖δ‖/‖Δu‖ ≈ 1 for ever. Such a step is converged when its one
            // correction kept the residual within tolerance.
            let inc = *report.increments.last().unwrap();
            if rk <= s.residual_tolerance && (inc <= s.increment_tolerance || r0 <= s.residual_tolerance) {
                return Ok(report);
            }
        }
        Err(NewtonError::IterationLimit(report))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::tests::Chain;
    use crate::{Couplings, LinearSolverKind};

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

    impl NewtonProblem for Springs {
        type Error = Never;
        fn num_dofs(&self) -> usize {
            self.chain.num_nodes()
        }
        fn evaluate(&mut self, du: &[f64], r: &mut [f64]) -> Result<f64, Never> {
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
            Ok(self.load.abs())
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
        fn matrix(&self) -> (&BlockPattern, &[f64]) {
            (&self.pattern, &self.values)
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
        let mut newton = NewtonSolver::new(
            NewtonSettings { residual_tolerance: 1e-12, increment_tolerance: 1e-10, ..Default::default() },
            SparseDirectSolver::new(LinearSolverKind::Cholesky),
        );
        let mut du = vec![0.0; 4];
        let report = newton.solve(&mut p, &mut du).unwrap();
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
        let mut newton = NewtonSolver::new(
            NewtonSettings { max_iterations: 2, ..Default::default() },
            SparseDirectSolver::new(LinearSolverKind::Cholesky),
        );
        let mut du = vec![0.0; 4];
        let err = newton.solve(&mut p, &mut du).unwrap_err();
        assert!(matches!(err, NewtonError::IterationLimit(_)), "{err}");
        assert_eq!(err.report().iterations(), 2);
    }
}
