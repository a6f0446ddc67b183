//! The ghost penalty of the implicit MPM (docs/theory.md §15): the faces of cut cells of
//! the committed configuration, scaled by γ and the stiffness of their cells, the
//! couplings they add to the pattern, and their force G Δu and tangent G.

use loam_grid::{ghost_faces, Connectivity, GhostFace, INACTIVE};
use loam_model::Model;
use loam_solve::{BlockPattern, SystemMatrix};

/// The ghost faces of the committed configuration: cell fill from the volumes of the
/// points whose centres lie in each cell, faces of cut cells whose nodes are all active,
/// renumbered to active nodes and scaled by γ times the largest P-wave modulus of the
/// points in the face's two cells (so a soft layer is not stiffened by a stiff one
/// elsewhere).
pub(crate) fn scaled_ghost_faces<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
    gamma: f64,
) -> Vec<GhostFace> {
    let grid = model.grid();
    let (mut fill, mut modulus) = (vec![0.0; grid.num_cells()], vec![0.0f64; grid.num_cells()]);
    let moduli = model.constant_p_wave_moduli();
    let pts = model.points();
    let axisymmetric = model.axisymmetric();
    for (p, (x, v)) in model.configuration().iter().zip(pts.volume()).enumerate() {
        let c = grid.cell_index(grid.cell_coords(x));
        if axisymmetric {
            fill[c] += v / (grid.cell_volume() * ring(model, c));
        } else {
            fill[c] += v / grid.cell_volume();
        }
        modulus[c] = modulus[c].max(model.p_wave_modulus(&moduli, p));
    }
    let to_active = &conn.active_nodes().grid_to_active;
    let mut faces = ghost_faces(grid, &fill, |g| to_active[g] != INACTIVE);
    for face in &mut faces {
        let mut m = modulus[face.cells[0]].max(modulus[face.cells[1]]);
        if axisymmetric {
            // The face is a ring through the midpoint of its cells' centres.
            m *= 0.5 * (ring(model, face.cells[0]) + ring(model, face.cells[1]));
        }
        face.nodes.iter_mut().for_each(|g| *g = to_active[*g as usize]);
        face.matrix.iter_mut().for_each(|v| *v *= gamma * m);
    }
    faces
}

/// 2π r_c of cell `c` (axisymmetry, docs/theory.md §20): a point's ring volume over its
/// cell's ring volume is its cell fill, and a face's penalty acts on its ring.
fn ring<const D: usize>(model: &Model<D>, c: usize) -> f64 {
    let grid = model.grid();
    let i = c % grid.cells()[0];
    std::f64::consts::TAU * (grid.origin()[0] + (i as f64 + 0.5) * grid.cell_size()[0])
}

/// The node couplings the ghost faces add to the sparsity pattern: every node of a face
/// with every other (lists are reused; `update_with` sorts and dedups them).
pub(crate) fn ghost_couplings(faces: &[GhostFace], active_nodes: usize, couplings: &mut Vec<Vec<u32>>) {
    couplings.iter_mut().for_each(Vec::clear);
    couplings.resize(active_nodes, Vec::new());
    for face in faces {
        for &a in &face.nodes {
            couplings[a as usize].extend_from_slice(&face.nodes);
        }
    }
}

/// r += G Δu for every ghost face, component by component, faces in a fixed order.
pub(crate) fn add_ghost_force<const D: usize>(ghost: &[GhostFace], du: &[f64], r: &mut [f64]) {
    for face in ghost {
        let n = face.nodes.len();
        for (a, &na) in face.nodes.iter().enumerate() {
            for (b, &nb) in face.nodes.iter().enumerate() {
                let g = face.matrix[a * n + b];
                for i in 0..D {
                    r[na as usize * D + i] += g * du[nb as usize * D + i];
                }
            }
        }
    }
}

/// K += G, the same scalar matrix on every displacement component, faces in a fixed order.
pub(crate) fn add_ghost_tangent<const D: usize>(
    ghost: &[GhostFace],
    pattern: &BlockPattern,
    constrained: &[bool],
    matrix: &mut SystemMatrix,
) {
    let mut block = [0.0; 9];
    for face in ghost {
        let n = face.nodes.len();
        for (a, &na) in face.nodes.iter().enumerate() {
            for (b, &nb) in face.nodes.iter().enumerate() {
                for i in 0..D {
                    block[i * D + i] = face.matrix[a * n + b];
                }
                matrix.add_block(pattern, constrained, na as usize, nb as usize, &block[..D * D]);
            }
        }
    }
}
