//! Arc-length load control of a quasi-static analysis (docs/theory.md §21): the load
//! factor joins the unknowns of each step, and the step is held to a length Δl of the
//! displacement increment instead of to a load factor, so the analysis follows the load
//! past a limit point and down a softening branch.
//!
//! The constraint is Crisfield's cylindrical arc (Crisfield 1981, "A fast incremental/
//! iterative solution procedure that handles snap-through", Comput. Struct. 13): ‖Δu‖ = Δl
//! over the free dofs. Each Newton correction solves the tangent twice, K δu_R = −R and
//! K δu_F = ∂f_ext/∂λ, and takes δu = δu_R + δλ δu_F with the δλ that keeps the increment on
//! the arc. A step starts from the secant predictor: the last converged increment (Δu, Δλ)
//! scaled to the new length, which carries the direction of travel through a limit point
//! without a test of the tangent's determinant. The first step is load-controlled (the
//! analysis's first load step) and sets the first length.

use crate::cutback::{CutBack, StepScale};
use crate::points::PointUpdateError;
use crate::quasi_static::QuasiStatic;
use crate::{StepError, StepReport};
use loam_model::LoadLevel;
use loam_solve::{norm, NewtonControl, NewtonError, NewtonReport};
use std::time::Instant;

/// The settings of arc-length control.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcLengthSettings {
    /// The most steps of the analysis, the first (load-controlled) one included. The
    /// analysis also ends once the load factor reaches 1 (the last step is then
    /// load-controlled onto 1) or falls back to 0.
    pub steps: usize,
    /// The Newton corrections a step aims at: after each step the length is scaled by
    /// √(iterations / corrections taken), within [½, 2].
    pub iterations: usize,
    /// The longest step, as a multiple of the first step's length.
    pub max_growth: f64,
}

impl Default for ArcLengthSettings {
    fn default() -> Self {
        Self { steps: 100, iterations: 6, max_growth: 10.0 }
    }
}

/// The most load carried along an arc-length path: the load factor and the step that
/// reached it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Peak {
    pub step: usize,
    pub load_factor: f64,
}

/// What an arc-length analysis carries from step to step beside its model and the
/// quasi-static state (a checkpoint's).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcLengthState {
    /// The length of the next step, and the longest a step may take.
    pub length: f64,
    pub max_length: f64,
    pub peak: Peak,
}

/// The scratch of the arc-length steps: ∂f_ext/∂λ, the two solves' solutions and the
/// right-hand side −R.
#[derive(Debug, Default)]
pub(crate) struct ArcScratch {
    load: Vec<f64>,
    du_r: Vec<f64>,
    du_f: Vec<f64>,
    rhs: Vec<f64>,
}

/// How an arc-length attempt ended.
pub(crate) enum ArcOutcome {
    /// Converged on the arc and committed.
    Committed(NewtonReport),
    /// Converged beyond the full load (or within 1e-9 of it): nothing committed; the step
    /// goes onto λ = 1 by load control instead.
    BeyondFullLoad,
}

impl<const D: usize> QuasiStatic<D> {
    /// One arc-length step of length `length`, cut back (halved) on failure: connect, then
    /// attempt the step on the arc; a step that would pass the full load is taken by load
    /// control onto λ = 1 instead. The next length follows the corrections this one took.
    pub(crate) fn arc_step(
        &mut self,
        step: usize,
        arc: ArcLengthSettings,
        state: ArcLengthState,
        start: Instant,
    ) -> Result<StepReport, StepError> {
        let mut control = CutBack::new(0.0, 1.0, StepScale::LoadFactor, self.settings.max_cutbacks);
        let (mut done, mut taken) = (0.0, (state.length, arc.iterations));
        while let Some(fraction) = control.next(done) {
            self.engine.connect(step)?;
            let active = self.engine.conn.active_nodes().len();
            match self.arc_attempt(fraction * state.length) {
                Ok(ArcOutcome::Committed(report)) => {
                    taken = (fraction * state.length, report.iterations());
                    control.converged(report, active);
                    done = 1.0;
                }
                Ok(ArcOutcome::BeyondFullLoad) => return self.load_step(step, 1.0, start),
                Err(e) => {
                    let tried = self.arc_tried;
                    control.failed(step, self.load_factor, tried, e.to_string(), e.report())?
                }
            }
        }
        let scale = (arc.iterations as f64 / taken.1.max(1) as f64).sqrt().clamp(0.5, 2.0);
        let length = (taken.0 * scale).min(state.max_length);
        tracing::info!(step, load_factor = self.load_factor, length = taken.0, next = length, "arc-length step");
        self.arc = Some(ArcLengthState { length, ..state });
        let lambda = self.load_factor;
        let reactions = self.engine.reactions.clone();
        Ok(control.into_report(step, lambda, lambda, reactions, D, start))
    }

    /// One attempt at an arc-length step of length `length` from the committed state:
    /// the load direction, the secant predictor, then Newton on displacement and load
    /// factor together — assemble, two solves, the correction on the arc, update points,
    /// check. On success the state is committed; on failure nothing changes.
    fn arc_attempt(&mut self, length: f64) -> Result<ArcOutcome, NewtonError<PointUpdateError>> {
        let mut s = std::mem::take(&mut self.arc_scratch);
        let result = self.arc_newton(length, &mut s);
        self.arc_scratch = s;
        let (report, lambda) = result?;
        // Beyond or within round-off of the full load: the step is taken onto it exactly.
        if lambda > 1.0 - 1e-9 {
            return Ok(ArcOutcome::BeyondFullLoad);
        }
        self.remember_increment(lambda);
        self.engine.commit();
        self.load_factor = lambda;
        Ok(ArcOutcome::Committed(report))
    }

    /// Newton's method on the arc: returns the report and the load factor reached, the
    /// increment in the engine's `du`.
    fn arc_newton(
        &mut self,
        length: f64,
        s: &mut ArcScratch,
    ) -> Result<(NewtonReport, f64), NewtonError<PointUpdateError>> {
        let no_report = |source| NewtonError::Problem { source, report: NewtonReport::default() };
        self.engine.size_buffers();
        let mut lambda = self.load_factor + self.secant_predictor(length);
        self.arc_tried = lambda;
        let e = &mut self.engine;
        e.load_direction(lambda, &mut s.load);
        let reference = e.update_points_and_residual(None).map_err(no_report)?;
        let mut newton = NewtonControl::start(self.settings.newton, norm(e.residual()), reference)?;
        s.du_r.resize(s.load.len(), 0.0);
        s.du_f.resize(s.load.len(), 0.0);
        loop {
            newton.next_iteration()?;
            e.assemble(None);
            let fallbacks = e.direct_fallbacks();
            let setup = e.prepare_solver().map_err(|x| newton.linear_failure(x))?;
            s.rhs.clear();
            s.rhs.extend(e.residual().iter().map(|r| -r));
            let tolerance = newton.linear_tolerance();
            let solved = e.solve_prepared(&s.rhs, &mut s.du_r, tolerance).and_then(|i| {
                let j = e.solve_prepared(&s.load, &mut s.du_f, tolerance)?;
                Ok((i.iterations + j.iterations, setup + i.factorised + j.factorised))
            });
            let (iterations, setup) = solved.map_err(|x| newton.linear_failure(x))?;
            newton.linear_solved(iterations, setup, e.direct_fallbacks() > fallbacks);
            let dl = arc_correction(&e.du, &s.du_r, &s.du_f, length);
            let mut squares = 0.0;
            for ((u, r), f) in e.du.iter_mut().zip(&s.du_r).zip(&s.du_f) {
                let delta = r + dl * f;
                squares += delta * delta;
                *u += delta;
            }
            lambda += dl;
            self.arc_tried = lambda;
            newton.corrected(squares.sqrt(), norm(&e.du));
            e.external_forces(LoadLevel::Factor(lambda));
            let reference = e.update_points_and_residual(None).map_err(|x| newton.problem_failure(x))?;
            if newton.converged(norm(e.residual()), reference)? {
                return Ok((newton.into_report(), lambda));
            }
        }
    }

    /// The secant predictor of a step of length `length`: the last converged increment,
    /// carried to the active nodes by their grid numbers and scaled to the length, in the
    /// engine's `du`; returns the load-factor increment, scaled alike (0 where nothing of
    /// the last increment is left on the active nodes).
    fn secant_predictor(&mut self, length: f64) -> f64 {
        self.engine.du.iter_mut().for_each(|u| *u = 0.0);
        self.carry_previous(1.0);
        let carried = norm(&self.engine.du);
        if carried == 0.0 {
            return 0.0;
        }
        let scale = length / carried;
        self.engine.du.iter_mut().for_each(|u| *u *= scale);
        scale * self.previous_increment.unwrap_or(0.0)
    }
}

/// The load-factor correction δλ of a correction δu = δu_R + δλ δu_F that keeps the
/// increment on the arc, ‖Δu + δu‖ = Δl: of the two roots of the quadratic, the one whose
/// new increment turns least from Δu (Crisfield's choice); where the arc has no real root
/// (the linearisation misses it), the δλ that comes closest to it, −b / 2a.
pub(crate) fn arc_correction(du: &[f64], du_r: &[f64], du_f: &[f64], length: f64) -> f64 {
    let (mut a, mut b, mut c, mut d) = (0.0, 0.0, 0.0, 0.0);
    for ((u, r), f) in du.iter().zip(du_r).zip(du_f) {
        let w = u + r;
        a += f * f;
        b += 2.0 * w * f;
        c += w * w;
        d += f * u;
    }
    c -= length * length;
    if a == 0.0 {
        return 0.0;
    }
    let discriminant = b * b - 4.0 * a * c;
    if discriminant < 0.0 {
        return -b / (2.0 * a);
    }
    // Roots by the stable pair (no cancellation between −b and the square root).
    let q = -0.5 * (b + b.signum() * discriminant.sqrt());
    let (r1, r2) = if q == 0.0 { (0.0, 0.0) } else { (q / a, c / q) };
    if r1 * d >= r2 * d {
        r1
    } else {
        r2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Both roots lie on the arc; the one kept continues the direction of Δu.
    #[test]
    fn the_correction_stays_on_the_arc_and_keeps_its_direction() {
        let du = [1.0, 0.5];
        let (du_r, du_f) = ([0.1, -0.2], [0.3, 0.4]);
        let length = 1.2;
        let dl = arc_correction(&du, &du_r, &du_f, length);
        let next: Vec<f64> = (0..2).map(|i| du[i] + du_r[i] + dl * du_f[i]).collect();
        // Exact up to the rounding of a quadratic's roots.
        assert!((norm(&next) - length).abs() < 1e-14, "‖Δu + δu‖ = {}", norm(&next));
        // The other root: by Vieta, product c / a.
        let (a, w) = (0.25, [1.1, 0.3]);
        let c = w[0] * w[0] + w[1] * w[1] - length * length;
        let other = c / a / dl;
        let turn = |x: f64| (0..2).map(|i| (w[i] + x * du_f[i]) * du[i]).sum::<f64>();
        assert!(turn(dl) > turn(other), "kept {dl}, other {other}");
    }

    /// Where the linearised step misses the arc, δλ brings the increment as close as it
    /// can: the minimum of ‖w + δλ δu_F‖.
    #[test]
    fn an_arc_out_of_reach_is_approached() {
        let (du, du_r, du_f) = ([0.0, 0.0], [3.0, 0.0], [0.0, 1.0]);
        assert_eq!(arc_correction(&du, &du_r, &du_f, 1.0), 0.0);
        let (du_r, du_f) = ([3.0, 0.0], [1.0, 1.0]);
        assert!((arc_correction(&du, &du_r, &du_f, 1.0) + 1.5).abs() < 1e-15);
    }
}
