//! The errors both integrators share: connecting the points to the background, and a run
//! stopped by its step observer.

use loam_grid::{ElementError, LocateError, PointBasisError};

/// Why the points could not be connected to the background at the start of a step, or
/// why a constraint holds nothing.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConnectError {
    #[error("step {step}: {source}; the point left the grid (enlarge the grid)")]
    PointOutsideGrid { step: usize, source: PointBasisError },
    #[error("step {step}: {source} (updated Lagrangian FEM: the mesh is too distorted to go on)")]
    Element { step: usize, source: ElementError },
    #[error("step {step}: vertex {vertex} of load {load}, at {position:?}, touches no node that a material point reaches: the load is not on the material (or left the grid)")]
    LoadOffMaterial { step: usize, load: usize, vertex: usize, position: Vec<f64> },
    #[error("constraint {index} (axis {axis}, node plane {plane}) touches no active node: no material point has support on that plane")]
    ConstraintTouchesNoNode { index: usize, axis: usize, plane: usize },
    #[error("inclined roller {index} holds no active node: no material point has support on or beyond its plane")]
    InclinedRollerTouchesNoNode { index: usize },
    #[error(
        "body constraint {index} holds no node: its body has no point (that started inside its box, if it has one)"
    )]
    BodyConstraintTouchesNoNode { index: usize },
}

impl ConnectError {
    /// The error of step `step` for a background that could not locate the points.
    pub fn locate(step: usize, error: LocateError) -> Self {
        match error {
            LocateError::OutsideGrid(source) => ConnectError::PointOutsideGrid { step, source },
            LocateError::Element(source) => ConnectError::Element { step, source },
        }
    }
}

/// A setting of an analysis outside its valid range: the field, its value and what would
/// be valid (the one shape of the quasi-static, dynamic, explicit and strength-reduction
/// settings' refusals).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("invalid setting `{field}` = {value}: valid is {valid}")]
pub struct InvalidSetting {
    pub field: &'static str,
    pub value: f64,
    pub valid: &'static str,
}

/// A run stopped by the analysis's step error `S` or by its step observer's error `E`
/// (an output that could not be written, say).
#[derive(Debug, thiserror::Error)]
pub enum RunError<S: std::error::Error + 'static, E: std::error::Error + 'static> {
    #[error(transparent)]
    Step(S),
    #[error(transparent)]
    Observer(E),
}
