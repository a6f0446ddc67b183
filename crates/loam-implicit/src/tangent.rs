//! The tangent of a step (docs/theory.md §1, §13): K_IJ = Σ_p v_p (∂N_I/∂x)_j a_ijkl
//! (∂N_J/∂x)_l, with the cross and volumetric terms of the cell averages, the inertial
//! c M of dynamics and the ghost penalty G, assembled node block by node block in a fixed
//! order (deterministic).

use crate::cell_average::CellAverage;
use crate::ghost::add_ghost_tangent;
use crate::inertia::Inertia;
use crate::points::TrialState;
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
}

/// Assemble the tangent at the trial state into `matrix` (on the pattern, in its layout).
pub(crate) fn assemble<const D: usize>(
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
        if let Some(avg) = average {
            let da = avg.average(p * stride + a) - ga;
            let db = avg.average(p * stride + b) - gb;
            add_averaged_terms::<D>(&trial.volumetric[p], ga, gb, &da, &db, out);
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
        if let Some(bw) = inputs.water_force.get(p) {
            // −N_a b v with δv = v ∇·δu: K_ab,ik = −N_a b_i v ∂N_b/∂x_k.
            let na = conn.support_values(p)[a];
            for i in 0..D {
                for k in 0..D {
                    out[i * D + k] -= na * bw[i] * trial.volume[p] * gb[k];
                }
            }
        }
    });
    add_ghost_tangent::<D>(inputs.ghost, inputs.pattern, inputs.constrained, matrix);
}

/// With E_a,i = e_i ⊗ c_a + ⅓ d_a,i I, d = b̄ − c (c the strain gradients `ga`, `gb`): the
/// cross and volumetric terms of E_a,i : D : E_b,k beside the plain one, from the point's
/// volumetric contractions (v I : D, v D : I).
#[inline]
fn add_averaged_terms<const D: usize>(
    volumetric: &(nalgebra::Matrix3<f64>, nalgebra::Matrix3<f64>),
    ga: &nalgebra::SVector<f64, D>,
    gb: &nalgebra::SVector<f64, D>,
    da: &nalgebra::SVector<f64, D>,
    db: &nalgebra::SVector<f64, D>,
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
}
