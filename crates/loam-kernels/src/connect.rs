//! Stage 1 of every step: connect the points to the background.

use crate::ConnectError;
use loam_grid::{ActiveNodes, Connectivity, NodeLayout};
use loam_model::Model;

/// Connect the points of `model` at the configuration the mechanics is written on to its
/// background (basis values and gradients, active nodes, node → point adjacency, the
/// points' bands) and mark the constrained dofs of the active nodes in `layout`: the
/// planes' and the bodies'. `step` names the step in an error.
pub fn connect<const D: usize>(
    model: &Model<D>,
    layout: &NodeLayout,
    conn: &mut Connectivity<D>,
    constrained: &mut Vec<bool>,
    step: usize,
) -> Result<(), ConnectError> {
    model
        .background()
        .connect(conn, model.configuration(), model.points().half_length())
        .map_err(|e| ConnectError::locate(step, e))?;
    model.constrained_dofs(layout, conn.active_nodes(), constrained);
    model.mark_body_constrained_dofs(layout, conn, constrained);
    Ok(())
}

/// Every constraint and inclined roller must hold at least one of the `active` nodes: one
/// that holds none would silently constrain nothing.
pub fn check_constraints<const D: usize>(model: &Model<D>, active: &ActiveNodes) -> Result<(), ConnectError> {
    if let Some((index, c)) = model.constraint_without_nodes(active) {
        return Err(ConnectError::ConstraintTouchesNoNode { index, axis: c.axis, plane: c.plane });
    }
    match (0..model.inclined_rollers().len()).find(|&k| model.inclined_roller_nodes(active, k).is_empty()) {
        Some(index) => Err(ConnectError::InclinedRollerTouchesNoNode { index }),
        None => Ok(()),
    }
}

/// [`check_constraints`] on the active nodes of `conn`, and every body constraint must
/// hold at least one of them.
pub fn check_constraints_connected<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
) -> Result<(), ConnectError> {
    check_constraints(model, conn.active_nodes())?;
    match (0..model.body_constraints().len()).find(|&k| model.body_constraint_nodes(conn, k).is_empty()) {
        Some(index) => Err(ConnectError::BodyConstraintTouchesNoNode { index }),
        None => Ok(()),
    }
}
