//! A failed factorisation traced to the grid (docs/theory.md §15): nodes that the points'
//! domains reach only by a sliver get a stiffness as small as the sliver, so the tangent's
//! pivots at them are lost to round-off or turned negative by the stress. The ghost
//! penalty is the remedy; the error says so where the model has none.

use loam_grid::Connectivity;
use loam_model::Model;
use loam_solve::LinearSolveError;
use nalgebra::SVector;

/// A node whose support is below this share of the best-supported node's is a sliver.
const SLIVER: f64 = 1e-3;

/// `error`, with the slivers named where the model has no ghost penalty and the grid has
/// free nodes that are slivers (`constrained` per dof); unchanged otherwise (and for
/// failures that are not about the tangent's pivots).
pub(crate) fn traced<const D: usize>(
    error: LinearSolveError,
    model: &Model<D>,
    conn: &Connectivity<D>,
    constrained: &[bool],
) -> LinearSolveError {
    let about_pivots = matches!(
        error,
        LinearSolveError::NotPositiveDefinite(_) | LinearSolveError::Singular(_) | LinearSolveError::NonFinite
    );
    if !about_pivots || model.ghost_penalty().is_some() || model.background().moves_with_body() {
        return error;
    }
    let Some((count, least, at)) = slivers(model, conn, constrained) else { return error };
    let cause = format!(
        "{count} free node(s) are reached only by slivers of the points' domains (the thinnest with {least:.1e} \
         of the best-reached node's material, at {:?}), which give them as little stiffness: add \
         `ghost_penalty: Some(0.1)` (docs/theory.md §15)",
        at.as_slice()
    );
    LinearSolveError::Traced { source: Box::new(error), cause }
}

/// The active nodes with a free dof whose support Σ_p N_I(x_p) A_p (A_p the point's
/// volume, or its meridian area in axisymmetry, where a ring's volume grows with the
/// radius) is below `SLIVER` of the largest: how many, the least share, and where that
/// node is.
fn slivers<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
    constrained: &[bool],
) -> Option<(usize, f64, SVector<f64, D>)> {
    let active = conn.active_nodes();
    let mut support = vec![0.0; active.len()];
    let (pts, axisymmetric) = (model.points(), model.axisymmetric());
    for (p, (&v, x)) in pts.volume().iter().zip(model.configuration()).enumerate() {
        let a = if axisymmetric { v / (std::f64::consts::TAU * x[0]) } else { v };
        for (&node, &n) in conn.support_nodes(p).iter().zip(conn.support_values(p)) {
            support[node as usize] += n * a;
        }
    }
    let most = support.iter().copied().fold(0.0, f64::max);
    let share = |s: f64| s / most;
    let free = |i: usize| constrained[i * D..(i + 1) * D].iter().any(|&c| !c);
    let thin: Vec<usize> = (0..support.len()).filter(|&i| share(support[i]) < SLIVER && free(i)).collect();
    let &least = thin.iter().min_by(|&&i, &&j| support[i].total_cmp(&support[j]))?;
    let at = model.grid().node_position(active.active_to_grid[least] as usize);
    Some((thin.len(), share(support[least]), at))
}
