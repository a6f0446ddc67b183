//! Automatic cut-back of an implicit step (docs/theory.md §6), the one rule of quasi-static
//! and dynamic analyses: try the whole increment; halve it after a failed attempt, and
//! double it again after two converged sub-steps in a row, so that one hard stretch does
//! not hold the rest of the step at the smallest size. An attempt that fails at
//! `max_cutbacks` halvings (or whose halved increment would fall below a floor: a limit
//! load's resolution) stops the run with the step, the load factor and the residual
//! history. An unconverged state is never committed: the caller only commits a converged
//! attempt.

use crate::{StepError, StepReport};
use loam_solve::NewtonReport;
use std::time::Instant;

/// An increment below this fraction of the load (or of the time step) is one whose failure
/// may be round-off rather than mechanics.
const TINY_INCREMENT: f64 = 1e-7;

/// The sub-step control of one step, from the committed position (load factor or time) to
/// its target. The caller asks [`next`](Self::next) for the size of its next attempt and
/// reports each attempt's outcome.
#[derive(Debug)]
pub struct CutBack {
    /// The step's whole increment.
    full: f64,
    target: f64,
    /// What the step advances, and its scale: the round-off allowance on reaching the
    /// target.
    scale: StepScale,
    max_cutbacks: usize,
    /// The smallest increment an attempt may take (0: none but `max_cutbacks`).
    floor: f64,
    /// Halvings of the current sub-step, and converged sub-steps since the last change.
    depth: usize,
    streak: usize,
    done: Tally,
}

/// What reaching one step's target took so far.
#[derive(Debug, Default)]
struct Tally {
    substeps: usize,
    cutbacks: usize,
    iterations: usize,
    linear_iterations: usize,
    linear_setup: std::time::Duration,
    direct_fallbacks: usize,
    /// Relative residuals of the last sub-step.
    residuals: Vec<f64>,
    /// Relative residuals of the converged sub-step with the most corrections, and the
    /// corrections of the first try it abandoned.
    hardest_residuals: Vec<f64>,
    hardest_abandoned: usize,
    active_nodes: usize,
}

/// What a step advances: the load factor (scale 1), or the time by steps of Δt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StepScale {
    LoadFactor,
    Time(f64),
}

impl StepScale {
    fn value(self) -> f64 {
        match self {
            StepScale::LoadFactor => 1.0,
            StepScale::Time(dt) => dt,
        }
    }
}

impl CutBack {
    /// Control a step from `position` to `target`.
    pub fn new(position: f64, target: f64, scale: StepScale, max_cutbacks: usize) -> Self {
        let full = target - position;
        Self { full, target, scale, max_cutbacks, floor: 0.0, depth: 0, streak: 0, done: Tally::default() }
    }

    /// No attempt below `floor`: a failure whose halved increment would be smaller stops
    /// the step, however few halvings it took (the search for a limit load resolved to a
    /// fraction of the load rather than to 2^-max_cutbacks of a step).
    pub fn with_floor(mut self, floor: f64) -> Self {
        self.floor = floor;
        self
    }

    /// The size of the next attempt from `position`, or `None` once the target is reached.
    pub fn next(&self, position: f64) -> Option<f64> {
        let reached = position >= self.target - 1e-12 * self.target.abs().max(self.scale.value());
        (!reached).then(|| self.full * 0.5f64.powi(self.depth as i32))
    }

    /// Where the next attempt from `position` ends, or `None` once the target is reached:
    /// `position` plus [`next`](Self::next)'s size, landing on the target where it ends
    /// within round-off of it (no sliver sub-step after it).
    pub fn next_end(&self, position: f64) -> Option<f64> {
        let end = position + self.next(position)?;
        Some(if end >= self.target - 4.0 * f64::EPSILON * self.target.abs() { self.target } else { end })
    }

    /// An attempt on `active_nodes` active nodes converged with `report`.
    pub fn converged(&mut self, report: NewtonReport, active_nodes: usize) {
        let done = &mut self.done;
        done.substeps += 1;
        done.iterations += report.iterations();
        done.linear_iterations += report.linear_iterations;
        done.linear_setup += std::time::Duration::from_secs_f64(report.linear_setup_s);
        done.direct_fallbacks += report.direct_fallbacks as usize;
        let most = done.hardest_abandoned + done.hardest_residuals.len().saturating_sub(1);
        if done.hardest_residuals.is_empty() || report.iterations() > most {
            done.hardest_residuals.clone_from(&report.residuals);
            done.hardest_abandoned = report.abandoned as usize;
        }
        done.residuals = report.residuals;
        done.active_nodes = active_nodes;
        self.advance();
    }

    /// After a converged attempt: two in a row double the size back. Called by
    /// [`converged`](Self::converged), and alone to replay a saved record (a
    /// strength-reduction search resumed), which tallies nothing.
    pub fn advance(&mut self) {
        self.streak += 1;
        if self.depth > 0 && self.streak >= 2 {
            self.depth -= 1;
            self.streak = 0;
        }
    }

    /// After a failed attempt: halve the size. Called by [`failed`](Self::failed), and
    /// alone to replay a saved record.
    pub fn cut(&mut self) {
        self.streak = 0;
        self.depth += 1;
    }

    /// An attempt of step `step` from `position` to `load_factor` failed for `reason`
    /// with the report `report` (its residual history, and the direct fallbacks it took):
    /// cut the step back, or stop with `NotConverged` once it was already at its smallest
    /// size.
    pub fn failed(
        &mut self,
        step: usize,
        position: f64,
        load_factor: f64,
        reason: String,
        report: &NewtonReport,
    ) -> Result<(), StepError> {
        let residuals = &report.residuals;
        self.done.cutbacks += 1;
        self.done.direct_fallbacks += report.direct_fallbacks as usize;
        // A cut-back is the step control doing its job (the run log and the progress
        // count them; strength reduction fails trials on purpose), so it is information,
        // not a warning; a run that cannot go on returns an error.
        let increment = self.full * 0.5f64.powi(self.depth as i32);
        tracing::info!(step, position, increment, error = %reason, "Newton failed; cutting the step back");
        if self.depth >= self.max_cutbacks || 0.5 * increment < self.floor {
            return Err(StepError::NotConverged {
                step,
                reached: position,
                load_factor,
                cutbacks: self.done.cutbacks - 1,
                reason: reason + &self.tiny_increment_hint(increment),
                residuals: residuals.to_vec(),
            });
        }
        self.cut();
        Ok(())
    }

    /// Why an increment far below the scale may not converge: the strain of an increment
    /// 1e-8 of the load is resolved to about machine epsilon over it (1e-8 relative in a
    /// 1 % strain), above the residual tolerance. The V1c column converges with 10⁶ load
    /// steps and stalls at a relative residual of 1e-5 with 10⁸.
    fn tiny_increment_hint(&self, increment: f64) -> String {
        let scale = self.scale.value();
        if increment >= TINY_INCREMENT * scale {
            return String::new();
        }
        let of = match self.scale {
            StepScale::LoadFactor => "the full load",
            StepScale::Time(_) => "the time step",
        };
        format!(
            "; the last increment tried was {:.1e} of {of}: with increments that small, round-off in \
             the strain increment can hold the residual above the tolerance, so use fewer, larger \
             steps (or a looser residual_tolerance)",
            increment / scale
        )
    }

    /// The report of step `step`, which reached `load_factor` and `time` with `reactions`,
    /// started at `start`.
    pub(crate) fn into_report(
        self,
        step: usize,
        load_factor: f64,
        time: f64,
        reactions: Vec<[f64; 3]>,
        dofs_per_node: usize,
        start: Instant,
    ) -> StepReport {
        let done = self.done;
        if done.linear_iterations > 0 {
            tracing::info!(
                step,
                newton_iterations = done.iterations,
                krylov_iterations = done.linear_iterations,
                setup_s = done.linear_setup.as_secs_f64(),
                direct_fallbacks = done.direct_fallbacks,
                "iterative linear solves"
            );
        }
        StepReport {
            step,
            load_factor,
            time,
            substeps: done.substeps,
            cutbacks: done.cutbacks,
            iterations: done.iterations,
            linear_iterations: done.linear_iterations,
            linear_setup: done.linear_setup,
            direct_fallbacks: done.direct_fallbacks,
            residuals: done.residuals,
            hardest_residuals: done.hardest_residuals,
            hardest_abandoned: done.hardest_abandoned,
            active_nodes: done.active_nodes,
            dofs: done.active_nodes * dofs_per_node,
            reactions,
            wall_time: start.elapsed(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn converged(iterations: usize) -> NewtonReport {
        NewtonReport { residuals: vec![1.0; iterations + 1], increments: vec![1.0; iterations], ..Default::default() }
    }

    /// Drive the control over a step from 0 to 1 whose attempts succeed when `holds(size)`:
    /// the sizes tried, in order, and the outcome.
    fn drive(holds: impl Fn(f64) -> bool, max_cutbacks: usize) -> (Vec<f64>, Result<StepReport, StepError>) {
        drive_with(CutBack::new(0.0, 1.0, StepScale::LoadFactor, max_cutbacks), holds)
    }

    /// `drive` with the control `control`.
    fn drive_with(mut control: CutBack, holds: impl Fn(f64) -> bool) -> (Vec<f64>, Result<StepReport, StepError>) {
        let (mut position, mut tried) = (0.0, Vec::new());
        while let Some(size) = control.next(position) {
            tried.push(size);
            let to = (position + size).min(1.0);
            if holds(size) {
                position = to;
                control.converged(converged(3), 10);
            } else if let Err(e) = control.failed(
                1,
                position,
                to,
                "too big".into(),
                &NewtonReport { residuals: vec![1.0, 2.0], ..Default::default() },
            ) {
                return (tried, Err(e));
            }
        }
        (tried, Ok(control.into_report(1, position, position, vec![], 2, Instant::now())))
    }

    /// A step that holds at once is one sub-step.
    #[test]
    fn a_step_that_converges_is_one_substep() {
        let (tried, report) = drive(|_| true, 8);
        assert_eq!(tried, vec![1.0]);
        let report = report.unwrap();
        assert_eq!((report.substeps, report.cutbacks, report.iterations, report.dofs), (1, 0, 3, 20));
    }

    /// Sizes above ¼ fail: the step halves twice, then after two converged quarters the
    /// sub-step doubles back to ½, which fails, and the last quarter is taken at ¼.
    #[test]
    fn failures_halve_and_two_successes_double() {
        let (tried, report) = drive(|size| size <= 0.25, 8);
        assert_eq!(tried, vec![1.0, 0.5, 0.25, 0.25, 0.5, 0.25, 0.25]);
        let report = report.unwrap();
        assert_eq!((report.substeps, report.cutbacks, report.iterations), (4, 3, 12));
        assert_eq!(report.load_factor, 1.0);
    }

    /// With a floor of 0.2, the attempt at ¼ is the last: its half would be below the floor,
    /// so the step stops after two halvings of the eight allowed.
    #[test]
    fn a_floor_stops_the_halving_early() {
        let (tried, report) = drive_with(CutBack::new(0.0, 1.0, StepScale::LoadFactor, 8).with_floor(0.2), |_| false);
        assert_eq!(tried, vec![1.0, 0.5, 0.25]);
        assert!(matches!(report, Err(StepError::NotConverged { cutbacks: 2, .. })), "{report:?}");
    }

    /// An attempt that fails at the smallest size stops the step with its residuals and
    /// the cut-backs made before it; nothing is reported converged.
    #[test]
    fn failing_at_the_smallest_size_stops_the_step() {
        let (tried, report) = drive(|_| false, 2);
        assert_eq!(tried, vec![1.0, 0.5, 0.25]);
        match report {
            Err(StepError::NotConverged { step: 1, load_factor, cutbacks: 2, residuals, .. }) => {
                assert_eq!(load_factor, 0.25);
                assert_eq!(residuals, vec![1.0, 2.0]);
            }
            other => panic!("{other:?}"),
        }
    }

    /// A step that fails at an increment below 1e-7 of the load says that round-off may
    /// be the cause and what to do; one that fails at a normal size does not.
    #[test]
    fn a_failure_at_a_tiny_increment_names_round_off() {
        let fail = |target: f64| {
            let mut control = CutBack::new(0.0, target, StepScale::LoadFactor, 1);
            let report = NewtonReport { residuals: vec![1.0, 1e-5], ..Default::default() };
            control.failed(1, 0.0, target, "no convergence".into(), &report).unwrap();
            match control.failed(1, 0.0, target / 2.0, "no convergence".into(), &report) {
                Err(StepError::NotConverged { reason, .. }) => reason,
                other => panic!("{other:?}"),
            }
        };
        let tiny = fail(1e-8);
        assert!(tiny.starts_with("no convergence; the last increment tried was 5.0e-9 of the full load"), "{tiny}");
        assert!(tiny.contains("fewer, larger steps"), "{tiny}");
        assert_eq!(fail(0.1), "no convergence");
    }

    /// The target is reached within round-off of the scale, without a sliver sub-step.
    #[test]
    fn the_target_is_reached_within_round_off() {
        let control = CutBack::new(0.0, 1.0, StepScale::LoadFactor, 8);
        assert_eq!(control.next(1.0 - 1e-13), None);
        assert_eq!(control.next(1.0 - 1e-11), Some(1.0));
        let time = CutBack::new(0.0, 1e-3, StepScale::Time(1e-3), 8);
        assert_eq!(time.next(1e-3 - 1e-16), None);
        // 0.1 + 0.2 is 0.30000000000000004: the attempt ends on the target itself.
        let sum = CutBack::new(0.1, 0.3, StepScale::LoadFactor, 8);
        assert_ne!(0.1 + 0.2, 0.3);
        assert_eq!(sum.next_end(0.1), Some(0.3));
        assert_eq!(sum.next_end(0.3), None);
    }
}
