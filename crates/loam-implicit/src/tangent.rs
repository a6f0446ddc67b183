//! The tangent of a step (docs/theory.md §1, §13): K_IJ = Σ_p v_p (∂N_I/∂x)_j a_ijkl
//! (∂N_J/∂x)_l, with the cross and volumetric terms of the cell averages or F-bar, the inertial
//! c M of dynamics and the ghost penalty G, assembled node block by node block in a fixed
//! order (deterministic).

use crate::cell_average::CellAverage;
use crate::fbar::add_tangent_terms as add_fbar_terms;
use crate::ghost::add_ghost_tangent;
use crate::inertia::Inertia;
use crate::points::{TrialState, HOOP};
use loam_grid::{Connectivity, GhostFace};
use loam_solve::{BlockPattern, Couplings, SystemMatrix};

/// Point–node connectivity seen as the coupling structure of assembly: points are the
/// elements.
pub(crate) struct PointCouplings<'a, const D: usize>(pub &'a Connectivity<D>);

impl<const D: usize> Couplings for PointCouplings<'_, D> {
    fn num_nodes(&self) -> usize {
        self.0.active_nodes().len()
    }
    fn elements_of(&self, node: usize) -> &[(u32, u32)] {
        self.0.node_points().of(node)
    }
    fn nodes_of(&self, element: usize) -> &[u32] {
        self.0.support_nodes(element)
    }
}

/// What the assembly reads besides the trial state.
pub(crate) struct TangentInputs<'a, const D: usize> {
    pub conn: &'a Connectivity<D>,
    pub pattern: &'a BlockPattern,
    pub average: Option<CellAverage<'a, D>>,
    pub ghost: &'a [GhostFace],
    pub constrained: &'a [bool],
    pub mass: &'a [f64],
    /// Finite strain with water: the water's force per unit volume, whose force on the
    /// current volume changes with it (empty otherwise).
    pub water_force: &'a [nalgebra::SVector<f64, D>],
    /// Whether the model is axisymmetric: the hoop strain's terms join each block.
    pub axisymmetric: bool,
    /// Whether the points are updated with F-bar ([`crate::fbar`]), whose averaged volume
    /// change couples each point's stress to its cell's nodes.
    pub fbar: bool,
}

/// Assemble the tangent at the trial state into `matrix` (on the pattern, in its layout).
pub(crate) fn assemble<const D: usize>(
    inputs: &TangentInputs<'_, D>,
    trial: &TrialState<D>,
    inertia: Option<&Inertia>,
    matrix: &mut SystemMatrix,
) {
    // Compiled once for each, so that a plane model's blocks carry no hoop test.
    if inputs.axisymmetric {
        assemble_blocks::<D, true>(inputs, trial, inertia, matrix);
    } else {
        assemble_blocks::<D, false>(inputs, trial, inertia, matrix);
    }
    add_ghost_tangent::<D>(inputs.ghost, inputs.pattern, inputs.constrained, matrix);
}

/// The points' blocks of [`assemble`], with the hoop terms when `AXISYMMETRIC`.
fn assemble_blocks<const D: usize, const AXISYMMETRIC: bool>(
    inputs: &TangentInputs<'_, D>,
    trial: &TrialState<D>,
    inertia: Option<&Inertia>,
    matrix: &mut SystemMatrix,
) {
    let conn = inputs.conn;
    let stride = conn.stride();
    let average = inputs.average;
    matrix.assemble(inputs.pattern, &PointCouplings(conn), inputs.constrained, |p, a, b, out| {
        if let Some(inertia) = inertia {
            let m = inertia.tangent_coefficient(conn, inputs.mass, p, a, b);
            for i in 0..D {
                out[i * D + i] += m;
            }
        }
        let ga = &trial.grad_x[p * stride + a];
        let gb = &trial.grad_x[p * stride + b];
        // In axisymmetry, the hoop entries N / r of the radial dofs' strain operators.
        let hoop = AXISYMMETRIC.then(|| {
            let (n, r_inv) = (conn.support_values(p), trial.inv_radius[p]);
            (n[a] * r_inv, n[b] * r_inv)
        });
        if let Some(avg) = average {
            let mut da = avg.average(p * stride + a) - ga;
            let mut db = avg.average(p * stride + b) - gb;
            if let Some((ha, hb)) = hoop {
                (da[0], db[0]) = (da[0] - ha, db[0] - hb);
            }
            add_averaged_terms::<D>(&trial.volumetric[p], (ga, gb), (&da, &db), hoop, out);
        }
        if inputs.fbar {
            let mut db = trial.average_x[p * stride + b] - gb;
            if let Some((_, hb)) = hoop {
                db[0] -= hb;
            }
            add_fbar_terms::<D>(&trial.volumetric[p].1, ga, &db, hoop.map(|h| h.0), out);
        }
        let t = &trial.tangent[p];
        for i in 0..D {
            for k in 0..D {
                let mut s = 0.0;
                for j in 0..D {
                    for l in 0..D {
                        s += ga[j] * t[(i * D + j, k * D + l)] * gb[l];
                    }
                }
                out[i * D + k] += s;
            }
        }
        if let Some((ha, hb)) = hoop {
            add_hoop_terms::<D>(t, ga, gb, ha, hb, out);
        }
        if let Some(bw) = inputs.water_force.get(p) {
            // −N_a b v with δv = v ∇·δu: K_ab,ik = −N_a b_i v ∂N_b/∂x_k; with F-bar the
            // volume follows the cell's, δv = v b̄_b · δu_b (b̄ with its hoop part).
            let na = conn.support_values(p)[a];
            let dilatation = if inputs.fbar { &trial.average_x[p * stride + b] } else { gb };
            for i in 0..D {
                for k in 0..D {
                    out[i * D + k] -= na * bw[i] * trial.volume[p] * dilatation[k];
                }
            }
            if let Some((_, hb)) = hoop.filter(|_| !inputs.fbar) {
                // The volume's hoop part: δv = v (∇·δu + δu_r / r).
                for i in 0..D {
                    out[i * D] -= na * bw[i] * trial.volume[p] * hb;
                }
            }
        }
    });
}

/// Axisymmetry (docs/theory.md §20): the strain operator of radial dof a,0 has the hoop
/// entry h_a = N_a / r beside e_0 ⊗ ∂N_a, so the block gains h_a a_θθkl ∂N_b,l on row 0,
/// ∂N_a,j a_ijθθ h_b on column 0 and h_a a_θθθθ h_b at (0, 0) (`t` holds v a with θθ at
/// index [`HOOP`]).
#[inline]
fn add_hoop_terms<const D: usize>(
    t: &nalgebra::SMatrix<f64, 9, 9>,
    ga: &nalgebra::SVector<f64, D>,
    gb: &nalgebra::SVector<f64, D>,
    ha: f64,
    hb: f64,
    out: &mut [f64],
) {
    for k in 0..D {
        out[k] += ha * (0..D).map(|l| t[(HOOP, k * D + l)] * gb[l]).sum::<f64>();
    }
    for i in 0..D {
        out[i * D] += hb * (0..D).map(|j| ga[j] * t[(i * D + j, HOOP)]).sum::<f64>();
    }
    out[0] += ha * t[(HOOP, HOOP)] * hb;
}

/// With E_a,i = e_i ⊗ c_a + ⅓ d_a,i I, d = b̄ − c (c the strain gradients `ga`, `gb`; in
/// axisymmetry d = b̄ − c − h e_r and E_a,0 has the hoop entry h_a, `hoop`): the cross and
/// volumetric terms of E_a,i : D : E_b,k beside the plain one, from the point's
/// volumetric contractions (v I : D, v D : I).
#[inline]
fn add_averaged_terms<const D: usize>(
    volumetric: &(nalgebra::Matrix3<f64>, nalgebra::Matrix3<f64>),
    (ga, gb): (&nalgebra::SVector<f64, D>, &nalgebra::SVector<f64, D>),
    (da, db): (&nalgebra::SVector<f64, D>, &nalgebra::SVector<f64, D>),
    hoop: Option<(f64, f64)>,
    out: &mut [f64],
) {
    let (id, di) = volumetric;
    let idi = id.trace();
    for i in 0..D {
        for k in 0..D {
            let mut s = idi * da[i] * db[k] / 9.0;
            for l in 0..D {
                s += da[i] * id[(k, l)] * gb[l] / 3.0;
                s += db[k] * ga[l] * di[(i, l)] / 3.0;
            }
            out[i * D + k] += s;
        }
    }
    if let Some((ha, hb)) = hoop {
        // (I : D)_θθ h_b on the radial column, h_a (D : I)_θθ on the radial row.
        for i in 0..D {
            out[i * D] += da[i] * id[(2, 2)] * hb / 3.0;
        }
        for k in 0..D {
            out[k] += db[k] * ha * di[(2, 2)] / 3.0;
        }
    }
}
