//! The load stiffness of follower pressures (docs/theory.md §17): a pressure on the current
//! facets changes with the increment, so the residual R = f_int − f_ext − f_p(Δu) has the
//! extra tangent −∂f_p/∂Δu, without which Newton would lose its quadratic rate.
//!
//! Vertex v's force is f_v = −s Σ_{e∋v} (p_v / D) a_e (s the load's factor, a_e the facet's
//! area vector). A vertex carried by point p sits at x_w = x_p + u_p + diag(ΔF_p F_p) R_w
//! with R_w = X_w − X_p, so ∂x_w,k/∂Δu_I,k = c_wI,k = N_I(x_p) + (Σ_l ∂N_I/∂x_l F_lk) R_w,k.
//! In 2D a_e = R (x_1 − x_0), R the rotation by −90°, so ∂a_e/∂x_1 = R = −∂a_e/∂x_0; in 3D
//! ∂a_e/∂x_k = ½ [x_{k+2} − x_{k+1}]_× (cyclic). The block coupling the force at node J
//! (weight ω_vJ of v) to the increment at node I is s (p_v / D) ω_vJ ∂a_e/∂x_w diag(c_wI).

use loam_grid::Connectivity;
use loam_kernels::{trial_vertices, LoadSupports};
use loam_model::{Load, LoadKind, LoadLevel, Model};
use loam_solve::{BlockPattern, SystemMatrix};
use nalgebra::{SMatrix, SVector};

/// The node couplings the follower loads add to the pattern: every node a vertex's force
/// reaches with every node that moves a vertex of its facets (lists are extended).
pub(crate) fn follower_couplings<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
    supports: &LoadSupports,
    couplings: &mut [Vec<u32>],
) {
    for (k, load) in model.loads().iter().enumerate().filter(|(_, l)| l.is_follower()) {
        for facet in &load.surface().facets {
            let moving: Vec<u32> = facet
                .iter()
                .flat_map(|&w| conn.support_nodes(load.carriers()[w as usize] as usize).iter().copied())
                .collect();
            for &v in facet {
                for &j in supports.support(k, v as usize).0 {
                    couplings[j as usize].extend_from_slice(&moving);
                    for &i in &moving {
                        couplings[i as usize].push(j);
                    }
                }
            }
        }
    }
}

/// What the load stiffness reads: the connectivity, the load vertices' supports, the
/// committed positions, the trial increment and increments of deformation.
pub(crate) struct FollowerInputs<'a, const D: usize> {
    pub model: &'a Model<D>,
    pub conn: &'a Connectivity<D>,
    pub supports: &'a LoadSupports,
    pub level: LoadLevel,
    pub du: &'a [f64],
    pub delta_f: &'a [nalgebra::Matrix3<f64>],
}

/// K += −∂f_p/∂Δu for every follower load, facet by facet in a fixed order.
pub(crate) fn add_follower_tangent<const D: usize>(
    inputs: &FollowerInputs<D>,
    pattern: &BlockPattern,
    constrained: &[bool],
    matrix: &mut SystemMatrix,
) {
    let FollowerInputs { model, conn, supports, level, du, delta_f } = *inputs;
    let points = model.points();
    for (k, load) in model.loads().iter().enumerate().filter(|(_, l)| l.is_follower()) {
        let LoadKind::Pressure { values: pressure, .. } = load.kind() else { continue };
        let scale = model.load_scale(k, level);
        let x = trial_vertices(conn, load, points, du, delta_f);
        for facet in &load.surface().facets {
            let corners = facet.map(|v| x[v as usize]);
            for (slot, &w) in facet.iter().enumerate() {
                let da = area_derivative(&corners, slot);
                let p = load.carriers()[w as usize] as usize;
                let carry = Carry { p, offset: *load.offset(w as usize), f: points.deformation_gradient()[p] };
                for &v in facet {
                    let coefficient = scale * pressure[v as usize] / D as f64;
                    let (nodes_j, weights) = supports.support(k, v as usize);
                    for (&j, &omega) in nodes_j.iter().zip(weights) {
                        add_moving_blocks(conn, &carry, &(da * (coefficient * omega)), j, pattern, constrained, matrix);
                    }
                }
            }
        }
    }
}

/// A vertex's carrier: point `p`, the offset X_v − X_p and the committed F_p.
struct Carry<const D: usize> {
    p: usize,
    offset: SVector<f64, D>,
    f: nalgebra::Matrix3<f64>,
}

/// Add `block` · diag(c_I) to the coupling of node `j` with every node I of the carrier's
/// support: x_v,k = x_p,k + u_p,k + (ΔF F)_kk R_k, so ∂x_v,k/∂Δu_I,k =
/// c_I,k = N_I(x_p) + (Σ_l ∂N_I/∂x_l F_lk) R_k, and nothing across components.
fn add_moving_blocks<const D: usize>(
    conn: &Connectivity<D>,
    carry: &Carry<D>,
    block: &SMatrix<f64, D, D>,
    j: u32,
    pattern: &BlockPattern,
    constrained: &[bool],
    matrix: &mut SystemMatrix,
) {
    let p = carry.p;
    let mut flat = [0.0; 9];
    let supports = conn.support_nodes(p).iter().zip(conn.support_values(p)).zip(conn.support_gradients(p));
    for ((&i, &n), g) in supports {
        for b in 0..D {
            let c = n + (0..D).map(|l| g[l] * carry.f[(l, b)]).sum::<f64>() * carry.offset[b];
            for a in 0..D {
                flat[a * D + b] = c * block[(a, b)];
            }
        }
        matrix.add_block(pattern, constrained, j as usize, i as usize, &flat[..D * D]);
    }
}

/// ∂a/∂x_slot of the facet with corners `x` (module docs).
fn area_derivative<const D: usize>(x: &[SVector<f64, D>; D], slot: usize) -> SMatrix<f64, D, D> {
    match D {
        2 => {
            let sign = if slot == 1 { 1.0 } else { -1.0 };
            SMatrix::from_fn(|i, j| sign * [[0.0, 1.0], [-1.0, 0.0]][i][j])
        }
        3 => {
            let e = (x[(slot + 2) % 3] - x[(slot + 1) % 3]) * 0.5;
            // [e]_× δ = e × δ
            let m = [[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]];
            SMatrix::from_fn(|i, j| m[i][j])
        }
        _ => unreachable!("loads exist in 2D and 3D"),
    }
}

/// Whether the model has a follower load (and so a load stiffness and its couplings).
pub(crate) fn has_follower<const D: usize>(loads: &[Load<D>]) -> bool {
    loads.iter().any(|l| l.is_follower())
}
