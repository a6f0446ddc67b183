//! The solver part of a scene: Newton's tolerances and iteration limit, the linear solver
//! and the quasi-static extrapolation, shared by the implicit analyses.

use super::locate::Seg;
use super::{LoadedScene, SceneError};
use loam_solve::{LinearSolverChoice, NewtonSettings};

/// The checked solver settings.
pub(super) struct Solver {
    pub newton: NewtonSettings,
    pub linear_solver: LinearSolverChoice,
    pub extrapolate: bool,
}

/// The most Newton iterations an attempt may take: beyond this a run that cannot converge
/// would look hung.
const MAX_NEWTON_ITERATIONS: usize = 1000;

/// The most backtracks of the line search along one correction: 2⁻²⁰ of it is round-off.
const MAX_BACKTRACKS: usize = 20;

impl LoadedScene {
    /// Both tolerances in (0, 1), at least one iteration.
    pub(super) fn solver(&self) -> Result<Solver, SceneError> {
        let sv = &self.scene.solver;
        let at = |key| [Seg::Key("solver"), Seg::Key(key)];
        if !(sv.residual_tolerance > 0.0 && sv.residual_tolerance < 1.0) {
            return Err(self.error(
                &at("residual_tolerance"),
                format!("residual_tolerance is {}; it must lie in (0, 1)", sv.residual_tolerance),
            ));
        }
        if !(sv.increment_tolerance > 0.0 && sv.increment_tolerance < 1.0) {
            return Err(self.error(
                &at("increment_tolerance"),
                format!("increment_tolerance is {}; it must lie in (0, 1)", sv.increment_tolerance),
            ));
        }
        if sv.max_iterations == 0 || sv.max_iterations > MAX_NEWTON_ITERATIONS {
            return Err(self.error(
                &at("max_iterations"),
                format!(
                    "max_iterations is {}; it must be 1 to {MAX_NEWTON_ITERATIONS} (Newton converges in a few \
                     iterations or not at all; a failed attempt is cut back)",
                    sv.max_iterations
                ),
            ));
        }
        for (key, value) in [("max_backtracks", sv.max_backtracks), ("retry_backtracks", sv.retry_backtracks)] {
            if value > MAX_BACKTRACKS {
                return Err(self.error(
                    &at(key),
                    format!(
                        "{key} is {value}; it must be 0 to {MAX_BACKTRACKS} (each backtrack at least halves the \
                         step along the correction, so {MAX_BACKTRACKS} reach below 1e-6 of it)"
                    ),
                ));
            }
        }
        let newton = NewtonSettings {
            residual_tolerance: sv.residual_tolerance,
            increment_tolerance: sv.increment_tolerance,
            max_iterations: sv.max_iterations,
            max_backtracks: sv.max_backtracks,
            retry_backtracks: sv.retry_backtracks,
            ..NewtonSettings::default()
        };
        Ok(Solver {
            newton,
            linear_solver: sv.linear.map_or(LinearSolverChoice::Auto, Into::into),
            extrapolate: sv.extrapolate,
        })
    }
}
