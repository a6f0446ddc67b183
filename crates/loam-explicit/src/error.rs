//! Why an explicit step or run stopped.

use loam_kernels::{ConnectError, InvalidSetting};

/// Errors of an explicit analysis. A step that fails leaves the model's committed state as
/// it was after the last successful step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExplicitError {
    #[error("explicit analysis: {0}")]
    InvalidSettings(InvalidSetting),
    #[error(
        "step {step}: the fixed time step {dt:e} exceeds the critical time step {critical:e} \
         (h / (c_p + |v_p|), docs/theory.md §10); use a CFL step (a scene's `time_step: \
         Cfl(0.5)`), a smaller fixed step, or `allow_above_critical: true` to run anyway (it \
         will blow up)"
    )]
    AboveCritical { step: usize, dt: f64, critical: f64 },
    /// The points could not be connected to the background, a point left the grid, or a
    /// constraint holds no node.
    #[error(transparent)]
    Connect(#[from] ConnectError),
    #[error(
        "step {step} (from t = {time:e}): material point {point} became unstable: {reason}; the \
         state of the last completed step is kept. Reduce the time step (a CFL step with a \
         smaller safety factor, e.g. a scene's `time_step: Cfl(0.25)`), or check the material \
         and the loads"
    )]
    Unstable { step: usize, time: f64, point: usize, reason: String },
    #[error(
        "step {step} (t = {time:e}): the time step {dt:e} is below {floor:e} (1e-9 of the \
         duration), so the run would not reach its end; point {point} sets it, with P-wave \
         speed {wave_speed:.4e} and speed {speed:.4e} (the velocity the grid carries it at). \
         Check the point's body velocity and its material's stiffness and density against \
         the grid and the duration"
    )]
    TimeStepCollapsed { step: usize, time: f64, dt: f64, floor: f64, point: usize, wave_speed: f64, speed: f64 },
    /// The model uses an option explicit analysis does not accept (`loam_model`'s table).
    #[error(transparent)]
    Unaccepted(#[from] loam_model::Unaccepted),
    #[error(
        "the model's bodies are in contact (body_contact or rigid_bodies), which needs scheme: Usl, not {0:?}: \
         the stress must come from the contact-corrected grid velocities that move the points \
         (a re-mapped or start-of-step field velocity does not carry the contact, docs/theory.md §10)"
    )]
    ContactScheme(crate::UpdateScheme),
    #[error("the analysis is already finished ({0} steps)")]
    Finished(usize),
}
