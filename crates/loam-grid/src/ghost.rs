//! Ghost-penalty faces of the background grid: the stabilisation of nearly empty cells
//! (Burman 2010; in the MPM, Coombs 2023, IJNME 124). A node whose support holds only a
//! sliver of material gets a vanishing stiffness and the tangent's condition number
//! grows without bound as the sliver shrinks. The face ghost penalty adds, on every face
//! between two supported cells of which at least one is cut (partly filled),
//!
//!   G(u, v) = h ∫_F [[∂_n u]] · [[∂_n v]] dF,
//!
//! the jump of the normal derivative across the face of the grid's bilinear (trilinear)
//! interpolant of the nodal values. For the tent and GIMP the nodal values reproduce
//! linear fields, so G vanishes on them: it is weakly consistent. (Not for quadratic
//! B-splines, whose nodal values next to a grid face are control values off the nodes;
//! `Model::with_ghost_penalty` refuses that basis.) It ties a nearly empty
//! node to its neighbours through the stiffness of the cells next to it. The caller scales
//! it by γ times a modulus (`Model::with_ghost_penalty`).

use crate::index::cell_corner;
use crate::GaussLegendre;
use crate::Grid;

/// One ghost face: the nodes of its two cells (grid indices, ascending) and the scalar
/// penalty matrix over them, row-major (applied to each displacement component alike).
#[derive(Debug, Clone, PartialEq)]
pub struct GhostFace {
    /// The two cells (numbered with axis 0 fastest) sharing the face.
    pub cells: [usize; 2],
    pub nodes: Vec<u32>,
    pub matrix: Vec<f64>,
}

/// A cell is cut when the material volume in it is below this fraction of the cell; an
/// empty cell whose nodes are all active (reached by point domains) counts as cut too.
/// The fill counts each point's volume in the cell of its centre, so once points crowd
/// unevenly under large deformation some interior faces are penalised as well; the
/// penalty is weakly consistent, so that costs accuracy at the level of its γ, not
/// correctness.
pub const CUT_FILL: f64 = 0.95;

/// The ghost faces of `grid`: faces between two cells whose nodes are all active (so
/// every dof of the penalty exists) and of which at least one is cut. `cell_fill[c]` is
/// the material volume in cell c over the cell volume (cells numbered with axis 0
/// fastest, like nodes).
pub fn ghost_faces<const D: usize>(
    grid: &Grid<D>,
    cell_fill: &[f64],
    is_active: impl Fn(usize) -> bool,
) -> Vec<GhostFace> {
    let cells = grid.cells();
    assert_eq!(cell_fill.len(), grid.num_cells(), "one fill fraction per cell");
    let supported = |ijk: [usize; D]| cell_nodes(grid, ijk).all(|n| is_active(n as usize));
    let mut faces = Vec::new();
    for c in 0..grid.num_cells() {
        let lower = grid.cell_ijk(c);
        for axis in 0..D {
            if lower[axis] + 1 >= cells[axis] {
                continue;
            }
            let mut upper = lower;
            upper[axis] += 1;
            let (fl, fu) = (cell_fill[c], cell_fill[grid.cell_index(upper)]);
            if (fl <= 0.0 && fu <= 0.0) || (fl >= CUT_FILL && fu >= CUT_FILL) || !supported(lower) || !supported(upper)
            {
                continue;
            }
            faces.push(face_matrix(grid, lower, axis));
        }
    }
    faces
}

/// The 2^D corner nodes of the cell at `ijk`.
fn cell_nodes<const D: usize>(grid: &Grid<D>, ijk: [usize; D]) -> impl Iterator<Item = u32> + '_ {
    (0..1usize << D).map(move |k| grid.node_index(cell_corner(ijk, k)) as u32)
}

/// The penalty matrix of the face between the cell at `lower` and its neighbour along
/// `axis`: h_axis ∫_F [[∂N_i/∂x_axis]] [[∂N_j/∂x_axis]] dF by the tensor Gauss rule of
/// order 2 on the face (exact: the integrand is quadratic in each face coordinate).
fn face_matrix<const D: usize>(grid: &Grid<D>, lower: [usize; D], axis: usize) -> GhostFace {
    let h = grid.cell_size();
    let mut upper = lower;
    upper[axis] += 1;
    let mut nodes: Vec<u32> = cell_nodes(grid, lower).chain(cell_nodes(grid, upper)).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let n = nodes.len();
    // ∂N/∂x_axis of a node of `cell` at face point `xi` (local coordinates of that cell in
    // [0, 1]^D, with xi[axis] the face's own value): ±1/h Π_{b≠axis} φ_b.
    let derivative = |cell: [usize; D], xi: &[f64; D], node: [usize; D]| -> f64 {
        let mut d = 1.0;
        for b in 0..D {
            let far = node[b] == cell[b] + 1;
            if node[b] != cell[b] && !far {
                return 0.0;
            }
            if b == axis {
                d *= if far { 1.0 } else { -1.0 } / h[b];
            } else {
                d *= if far { xi[b] } else { 1.0 - xi[b] };
            }
        }
        d
    };
    let area: f64 = (0..D).filter(|&b| b != axis).map(|b| h[b]).product();
    // The 2-point rule mapped from [−1, 1] to the cell's [0, 1].
    let rule = GaussLegendre::new(2).expect("the 2-point rule");
    let gauss = [0, 1].map(|i| 0.5 + 0.5 * rule.point(i).0);
    let points = 1usize << (D - 1);
    let mut matrix = vec![0.0; n * n];
    let mut jump = vec![0.0; n];
    for q in 0..points {
        let mut xi = [0.0; D];
        let mut k = 0;
        for (b, x) in xi.iter_mut().enumerate() {
            if b != axis {
                *x = gauss[(q >> k) & 1];
                k += 1;
            }
        }
        let weight = area / points as f64;
        for (slot, &g) in nodes.iter().enumerate() {
            let node = grid.node_coords(g as usize);
            let mut below = xi;
            below[axis] = 1.0;
            let mut above = xi;
            above[axis] = 0.0;
            jump[slot] = derivative(upper, &above, node) - derivative(lower, &below, node);
        }
        for i in 0..n {
            for j in 0..n {
                matrix[i * n + j] += h[axis] * weight * jump[i] * jump[j];
            }
        }
    }
    GhostFace { cells: [grid.cell_index(lower), grid.cell_index(upper)], nodes, matrix }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};

    fn apply(face: &GhostFace, value: impl Fn(usize) -> f64) -> Vec<f64> {
        let n = face.nodes.len();
        (0..n).map(|i| (0..n).map(|j| face.matrix[i * n + j] * value(face.nodes[j] as usize)).sum()).collect()
    }

    /// The penalty vanishes on linear fields (weak consistency), is symmetric, and is
    /// positive on a field with a kink at the face: for u = |x − x_F| (slopes ∓1), the
    /// jump is 2 everywhere on the face, so u·G·u = h · 4 · |F|.
    #[test]
    fn penalty_vanishes_on_linear_fields_and_measures_kinks() {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(0.5, 0.25), [4, 4]).unwrap();
        let face = face_matrix(&grid, [1, 2], 0);
        assert_eq!(face.nodes.len(), 6);
        let n = face.nodes.len();
        for i in 0..n {
            for j in 0..n {
                assert!((face.matrix[i * n + j] - face.matrix[j * n + i]).abs() < 1e-15);
            }
        }
        let linear = |g: usize| {
            let x = grid.node_position(g);
            0.3 + 2.0 * x[0] - 1.5 * x[1]
        };
        assert!(apply(&face, linear).iter().all(|v| v.abs() < 1e-12));
        let x_face = 2.0 * 0.5;
        let kink = |g: usize| (grid.node_position(g)[0] - x_face).abs();
        let gu = apply(&face, kink);
        let energy: f64 = face.nodes.iter().zip(&gu).map(|(&g, v)| kink(g as usize) * v).sum();
        assert!((energy - 0.5 * 4.0 * 0.25).abs() < 1e-12, "{energy}");

        let grid = Grid::new(Vector3::zeros(), Vector3::new(1.0, 0.5, 2.0), [3, 3, 3]).unwrap();
        let face = face_matrix(&grid, [1, 0, 1], 2);
        assert_eq!(face.nodes.len(), 12);
        let linear = |g: usize| {
            let x = grid.node_position(g);
            1.0 - x[0] + 4.0 * x[1] + 0.5 * x[2]
        };
        assert!(apply(&face, linear).iter().all(|v| v.abs() < 1e-12));
    }

    /// Only faces next to a cut cell whose nodes are all active are penalised.
    #[test]
    fn faces_are_those_of_cut_supported_cells() {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [3, 1]).unwrap();
        // Full, full, sliver: one face (between cells 1 and 2).
        let faces = ghost_faces(&grid, &[1.0, 1.0, 0.01], |_| true);
        assert_eq!(faces.len(), 1);
        assert_eq!(faces[0].nodes, vec![1, 2, 3, 5, 6, 7]);
        assert_eq!(faces[0].cells, [1, 2]);
        // All full: none. The sliver's far nodes inactive: none.
        assert!(ghost_faces(&grid, &[1.0, 1.0, 1.0], |_| true).is_empty());
        assert!(ghost_faces(&grid, &[1.0, 1.0, 0.01], |n| n != 3 && n != 7).is_empty());
    }
}
