//! Transfers between points and nodes over one step's connectivity.
//!
//! Point → node is a *scatter* through the points' bands (`loam_grid::BandScatter`): the
//! points of bands two apart write disjoint nodes, so the even bands run in parallel, then
//! the odd ones, each band's points in ascending index. No two tasks write one value and
//! every node sums in one fixed order — bitwise identical results on any number of threads
//! (docs/theory.md §7). Node → point is an interpolation Σ_I N_I(x_p) u_I, independent per
//! point.

use loam_grid::Connectivity;
use nalgebra::SVector;

/// Fill a nodal field of `width` values per active node, `out`: zero it, then
/// `contrib(point, slot, node_values)` adds each point's contribution to each node of its
/// support (`slot` the node's place in the point's support), in the bands' fixed order.
pub fn scatter_nodal<const D: usize, F>(conn: &Connectivity<D>, width: usize, out: &mut [f64], contrib: F)
where
    F: Fn(usize, usize, &mut [f64]) + Sync,
{
    conn.bands().scatter(width, out, |p, window| {
        for (slot, &node) in conn.support_nodes(p).iter().enumerate() {
            contrib(p, slot, window.node(node as usize));
        }
    });
}

/// Add Σ_I N_I(x_p) u_I to `out`, term by term in support order, for the nodal field `field`
/// (D values per active node).
#[inline]
pub fn interpolate_add<const D: usize>(conn: &Connectivity<D>, p: usize, field: &[f64], out: &mut SVector<f64, D>) {
    for (&node, &n) in conn.support_nodes(p).iter().zip(conn.support_values(p)) {
        for i in 0..D {
            out[i] += n * field[node as usize * D + i];
        }
    }
}

/// Σ_I N_I u_I and Σ_I N_I w_I at point `p` of two nodal fields in one pass over its
/// support (the grid update's velocity and acceleration).
#[inline]
pub fn interpolate_pair<const D: usize>(
    conn: &Connectivity<D>,
    p: usize,
    u: &[f64],
    w: &[f64],
) -> (SVector<f64, D>, SVector<f64, D>) {
    let (mut up, mut wp) = (SVector::zeros(), SVector::zeros());
    for (&node, &n) in conn.support_nodes(p).iter().zip(conn.support_values(p)) {
        let k = node as usize * D;
        for i in 0..D {
            up[i] += n * u[k + i];
            wp[i] += n * w[k + i];
        }
    }
    (up, wp)
}

/// Σ_I N_I(x_p) u_I at point `p` of the nodal field `field` (D values per active node).
#[inline]
pub fn interpolate<const D: usize>(conn: &Connectivity<D>, p: usize, field: &[f64]) -> SVector<f64, D> {
    let mut out = SVector::zeros();
    interpolate_add(conn, p, field, &mut out);
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use loam_grid::{BasisKind, Grid};
    use nalgebra::Vector2;

    /// The linear basis reproduces a linear nodal field at any point, and the scatter of the
    /// basis values over the points is each node's share of them (partition of unity:
    /// the shares sum to the number of points).
    #[test]
    fn interpolation_reproduces_linear_fields_and_scatters_partition_unity() {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(0.5, 1.0), [4, 3]).unwrap();
        let positions = [Vector2::new(0.3, 0.4), Vector2::new(1.1, 2.7), Vector2::new(1.9, 1.0)];
        let mut conn = Connectivity::new(BasisKind::Linear);
        conn.compute(&grid, &positions, &[Vector2::zeros(); 3]).unwrap();
        let u = |x: Vector2<f64>| Vector2::new(1.0 + 2.0 * x[0] - x[1], 0.5 * x[1]);
        let field: Vec<f64> = conn
            .active_nodes()
            .active_to_grid
            .iter()
            .flat_map(|&g| u(grid.node_position(g as usize)).iter().copied().collect::<Vec<_>>())
            .collect();
        for (p, x) in positions.iter().enumerate() {
            assert!((interpolate(&conn, p, &field) - u(*x)).norm() < 1e-14);
        }
        let mut shares = vec![0.0; conn.active_nodes().len()];
        scatter_nodal(&conn, 1, &mut shares, |p, slot, out| out[0] += conn.support_values(p)[slot]);
        assert!((shares.iter().sum::<f64>() - 3.0).abs() < 1e-14);
    }
}
