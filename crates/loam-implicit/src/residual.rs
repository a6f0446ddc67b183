//! The residual of a step (docs/theory.md §1, §6): R = M x + f_int + G Δu − f_ext on the
//! free dofs, zero on the constrained ones, where f_int − f_ext is kept as the support
//! reaction; and the reference force that makes it relative.

use crate::cell_average::CellAverage;
use crate::ghost::add_ghost_force;
use crate::inertia::Inertia;
use crate::points::TrialState;
use loam_grid::{Connectivity, GhostFace};
use loam_kernels::{internal_force, scatter_internal_force};
use nalgebra::SVector;

/// What the residual reads besides the trial state.
pub(crate) struct ResidualInputs<'a, const D: usize> {
    pub conn: &'a Connectivity<D>,
    pub average: Option<CellAverage<'a, D>>,
    pub ghost: &'a [GhostFace],
    pub constrained: &'a [bool],
    pub f_ext: &'a [f64],
    pub mass: &'a [f64],
    /// Finite strain with water: the water's force per unit volume on each point, −∇p_w,
    /// which acts on the current volume; the external force holds it on the committed
    /// volume, so the residual takes its change (empty otherwise).
    pub water_force: &'a [SVector<f64, D>],
    pub committed_volume: &'a [f64],
    /// Whether the model is axisymmetric: the hoop stress's radial force joins f_int.
    pub axisymmetric: bool,
}

/// The residual at the increment `du` of the trial state `trial` into `r`, the support
/// reactions into `reaction`; returns the reference force norm. The reference is the
/// external (and inertial) force on free dofs plus the support reactions (= f_int) on
/// constrained ones: a free vibration has no external force, and must not be judged
/// against zero.
pub(crate) fn residual<const D: usize>(
    inputs: &ResidualInputs<'_, D>,
    trial: &TrialState<D>,
    inertia: Option<&mut Inertia>,
    du: &[f64],
    r: &mut [f64],
    reaction: &mut Vec<f64>,
) -> f64 {
    // Compiled once for each, so that a plane model's forces carry no hoop test.
    if inputs.axisymmetric {
        internal_forces::<D, true>(inputs, trial, r);
    } else {
        internal_forces::<D, false>(inputs, trial, r);
    }
    add_ghost_force::<D>(inputs.ghost, du, r);
    // In dynamics the internal and inertial forces join the reference, with the momentum
    // force as a floor (`Inertia::add_to_residual`).
    let mut reference = match inertia {
        Some(inertia) => inertia.add_to_residual(inputs.conn, inputs.mass, du, inputs.constrained, r),
        None => 0.0,
    };
    reaction.resize(r.len(), 0.0);
    for (((ri, &fe), &fixed), reaction) in
        r.iter_mut().zip(inputs.f_ext).zip(inputs.constrained).zip(reaction.iter_mut())
    {
        *reaction = 0.0;
        if fixed {
            reference += *ri * *ri;
            *reaction = *ri - fe;
            *ri = 0.0;
        } else {
            reference += fe * fe;
            *ri -= fe;
        }
    }
    reference.sqrt()
}

/// f_int less the change of the water's force into `r`, with the hoop force when
/// `AXISYMMETRIC`.
fn internal_forces<const D: usize, const AXISYMMETRIC: bool>(
    inputs: &ResidualInputs<'_, D>,
    trial: &TrialState<D>,
    r: &mut [f64],
) {
    let stride = inputs.conn.stride();
    let average = inputs.average;
    let (conn, water) = (inputs.conn, inputs.water_force);
    scatter_internal_force(conn, r, |p, a| {
        let k = p * stride + a;
        let hoop = AXISYMMETRIC.then(|| conn.support_values(p)[a] * trial.inv_radius[p]);
        let bbar = average.map(|c| c.average(k));
        let f = internal_force(trial.volume[p], &trial.stress[p], &trial.grad_x[k], bbar, hoop);
        let dv = trial.volume[p] - inputs.committed_volume[p];
        f - water_body_force(water, p, dv, conn.support_values(p)[a])
    });
}

/// The water's force on point `p` at the node of weight `n`: N v (−∇p_w), zero without
/// water.
#[inline]
pub(crate) fn water_body_force<const D: usize>(
    water: &[SVector<f64, D>],
    p: usize,
    volume: f64,
    n: f64,
) -> SVector<f64, D> {
    water.get(p).map_or(SVector::zeros(), |b| b * (n * volume))
}
