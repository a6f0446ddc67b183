//! Stage "update points" of a Newton iteration (docs/theory.md §1): every point's trial
//! state — ΔF, stress, elastic strain, history, volume, tangent and spatial gradients —
//! recomputed from its *committed* state and the current increment Δu, so iterations never
//! compound. The law is driven by the shared point kernel ([`loam_kernels::update_point`]);
//! what is implicit here is the strain operator (B-bar and assumed strain, docs/theory.md
//! §13) and the tangent the assembly needs.

use crate::cell_average::{CellAverage, CellGroups, GroupSums};
use loam_constitutive::{ConstitutiveError, Tensor4};
use loam_grid::Connectivity;
use loam_kernels::{embed, update_point, Committed};
use loam_model::{Kinematics, Model};
use nalgebra::{Matrix3, SMatrix, SVector};
use rayon::prelude::*;

/// A material point whose update failed inside a Newton iteration.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("material point {point}: {source}")]
pub struct PointUpdateError {
    pub point: usize,
    pub source: ConstitutiveError,
}

/// Trial state of every point for the current Newton iterate. Reused across iterations and
/// steps; the committed state in the model only changes when a step converges.
#[derive(Debug, Default)]
pub(crate) struct TrialState<const D: usize> {
    pub delta_f: Vec<Matrix3<f64>>,
    pub stress: Vec<Matrix3<f64>>,
    pub elastic_strain: Vec<Matrix3<f64>>,
    pub history: Vec<f64>,
    pub volume: Vec<f64>,
    /// v_p times the in-plane part of the tangent, (i·D + j, k·D + l) = v a_ijkl.
    pub tangent: Vec<SMatrix<f64, 9, 9>>,
    /// Spatial gradients ∂N/∂x (strain gradients c_a with cell averages), `stride` per point.
    pub grad_x: Vec<SVector<f64, D>>,
    /// Cell averages only: v (I : D) and v (D : I) as 3×3, the volumetric contractions of
    /// the point's tangent that the averaged dilatation couples through (v I : D : I is
    /// the trace of the first). F-bar: the first is unused and the second is its coupling
    /// Q = (v/m) (a : I_m + σ) ([`crate::fbar`]).
    pub volumetric: Vec<(Matrix3<f64>, Matrix3<f64>)>,
    /// Axisymmetry only: 1 / r, r the point's radius in the trial configuration, so that
    /// N_a / r is the hoop strain of a unit radial increment at node a (docs/theory.md
    /// §20); the tangent's θθ row and column are then its index 4 (D = 2).
    pub inv_radius: Vec<f64>,
    /// F-bar only (empty otherwise): each point's own det ΔF, and the averaged dilatation
    /// operator b̄ of its support slots over its cell in the trial configuration, `stride`
    /// per point ([`crate::fbar`]).
    pub jacobian: Vec<f64>,
    pub average_x: Vec<SVector<f64, D>>,
    /// F-bar only: each cell's volume change ΔJ̄, by [`CellGroups`] index.
    pub cell_jacobian: Vec<f64>,
    /// The scratch of the cell averages (B-bar's once a step, F-bar's every iterate).
    pub group_sums: GroupSums<D>,
}

impl<const D: usize> TrialState<D> {
    /// Size every buffer to `n_points` points of `stride` support slots, and F-bar's too
    /// when `fbar`.
    pub fn resize(&mut self, n_points: usize, stride: usize, history_stride: usize, fbar: bool) {
        self.delta_f.resize(n_points, Matrix3::identity());
        self.stress.resize(n_points, Matrix3::zeros());
        self.elastic_strain.resize(n_points, Matrix3::zeros());
        // At least one slot per point so that every point gets its own chunk.
        self.history.resize(n_points * history_stride.max(1), 0.0);
        self.volume.resize(n_points, 0.0);
        self.tangent.resize(n_points, SMatrix::zeros());
        self.grad_x.resize(n_points * stride, SVector::zeros());
        self.volumetric.resize(n_points, (Matrix3::zeros(), Matrix3::zeros()));
        self.inv_radius.resize(n_points, 0.0);
        let (m, k) = if fbar { (n_points, n_points * stride) } else { (0, 0) };
        self.jacobian.resize(m, 1.0);
        self.average_x.resize(k, SVector::zeros());
    }
}

/// One point's slots in the trial state.
pub(crate) struct TrialSlot<'a, const D: usize> {
    pub delta_f: &'a mut Matrix3<f64>,
    stress: &'a mut Matrix3<f64>,
    elastic_strain: &'a mut Matrix3<f64>,
    volume: &'a mut f64,
    tangent: &'a mut SMatrix<f64, 9, 9>,
    grad_x: &'a mut [SVector<f64, D>],
    volumetric: &'a mut (Matrix3<f64>, Matrix3<f64>),
    history: &'a mut [f64],
    inv_radius: &'a mut f64,
}

/// What every point's update reads: the model's committed state, the step's connectivity,
/// its cell averages (B-bar, assumed strain) or averaging groups (F-bar) and the increment.
#[derive(Clone, Copy)]
pub(crate) struct PointInputs<'a, const D: usize> {
    pub model: &'a Model<D>,
    pub conn: &'a Connectivity<D>,
    pub average: Option<CellAverage<'a, D>>,
    pub fbar: Option<&'a CellGroups>,
    pub du: &'a [f64],
}

/// The index of the θθ row and column of a 2D point's tangent in axisymmetry
/// ([`TrialState::tangent`]).
pub(crate) const HOOP: usize = 4;

/// Update every point's trial state for the increment `inputs.du`; the first failing point
/// (lowest index) is reported.
pub(crate) fn update_points<const D: usize>(
    inputs: PointInputs<'_, D>,
    trial: &mut TrialState<D>,
) -> Result<(), PointUpdateError> {
    match inputs.fbar {
        Some(groups) => crate::fbar::update_points(inputs, groups, trial),
        None => for_each_slot(inputs, trial, |p, slot| update_trial_point(inputs, p, slot)),
    }
}

/// Run `update` on every point's slots of the trial state in parallel; the first failing
/// point (lowest index) is reported.
pub(crate) fn for_each_slot<const D: usize>(
    inputs: PointInputs<'_, D>,
    trial: &mut TrialState<D>,
    update: impl Fn(usize, TrialSlot<'_, D>) -> Result<(), PointUpdateError> + Sync,
) -> Result<(), PointUpdateError> {
    let stride = inputs.conn.stride();
    let hs = inputs.model.points().history_stride();
    let t = trial;
    let first_error = (
        t.delta_f.par_iter_mut(),
        t.stress.par_iter_mut(),
        t.elastic_strain.par_iter_mut(),
        t.volume.par_iter_mut(),
        t.tangent.par_iter_mut(),
        t.grad_x.par_chunks_mut(stride),
    )
        .into_par_iter()
        .zip((t.history.par_chunks_mut(hs.max(1)), t.volumetric.par_iter_mut(), t.inv_radius.par_iter_mut()))
        .enumerate()
        .filter_map(
            |(p, ((delta_f, stress, elastic_strain, volume, tangent, grad_x), (history, volumetric, inv_radius)))| {
                let slot = TrialSlot {
                    delta_f,
                    stress,
                    elastic_strain,
                    volume,
                    tangent,
                    grad_x,
                    volumetric,
                    history: &mut history[..hs],
                    inv_radius,
                };
                update(p, slot).err()
            },
        )
        .min_by_key(|e| e.point);
    first_error.map_or(Ok(()), Err)
}

/// Point `p`'s trial state: its increment gradient Σ_a Δu_a ⊗ c_a over its strain
/// gradients, the law driven in finite or small strain, and the tangent and gradients the
/// assembly needs.
fn update_trial_point<const D: usize>(
    inputs: PointInputs<'_, D>,
    p: usize,
    slot: TrialSlot<'_, D>,
) -> Result<(), PointUpdateError> {
    let PointInputs { model, conn, average, du, .. } = inputs;
    let nodes = conn.support_nodes(p);
    let grads = conn.support_gradients(p);
    let first = p * conn.stride();
    // With cell averaging (small strain only, Model::with_anti_locking) the strain
    // gradients c_a go to grad_x now, and the increment gradient is Σ Δu_a ⊗ c_a.
    let strain_grads: &[SVector<f64, D>] = match average {
        Some(avg) => {
            for (a, c) in slot.grad_x[..nodes.len()].iter_mut().enumerate() {
                *c = avg.strain_gradient(first + a, &grads[a]);
            }
            &slot.grad_x[..nodes.len()]
        }
        None => grads,
    };
    let g = increment_of(nodes, strain_grads, du);
    let hoop = model.axisymmetric().then(|| hoop_increment(model, conn, p, du));
    let failed = |source| PointUpdateError { point: p, source };
    match model.kinematics() {
        Kinematics::FiniteStrain => finite_strain_point(model, p, &g, hoop, None, grads, slot).map_err(failed),
        Kinematics::SmallStrain => {
            let theta_bar = average.map(|avg| averaged_dilatation(&avg, nodes, first, du));
            small_strain_point(model, p, &g, hoop, theta_bar, grads, slot).map_err(failed)
        }
    }
}

/// The in-plane increment gradient Σ_a Δu_a ⊗ c_a over the support `nodes` and their
/// gradients `grads`.
#[inline]
pub(crate) fn increment_of<const D: usize>(nodes: &[u32], grads: &[SVector<f64, D>], du: &[f64]) -> SMatrix<f64, D, D> {
    let mut g = SMatrix::<f64, D, D>::zeros();
    for (a, &node) in nodes.iter().enumerate() {
        let u = SVector::<f64, D>::from_fn(|i, _| du[node as usize * D + i]);
        g += u * grads[a].transpose();
    }
    g
}

/// A point's hoop increment in axisymmetry (docs/theory.md §20): the strain Δu_r / r with
/// Δu_r = Σ_a N_a Δu_a,r, and the radius r it is on.
#[derive(Debug, Clone, Copy)]
pub(crate) struct HoopIncrement {
    pub strain: f64,
    pub radius: f64,
}

pub(crate) fn hoop_increment<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
    p: usize,
    du: &[f64],
) -> HoopIncrement {
    let radius = model.configuration()[p][0];
    let nodes = conn.support_nodes(p).iter();
    let u_r: f64 = nodes.zip(conn.support_values(p)).map(|(&node, &n)| n * du[node as usize * D]).sum();
    HoopIncrement { strain: u_r / radius, radius }
}

/// The 3×3 increment gradient of the in-plane `g`, with the hoop strain as its θθ (zz)
/// entry in axisymmetry.
#[inline]
pub(crate) fn increment_gradient<const D: usize>(g: &SMatrix<f64, D, D>, hoop: Option<HoopIncrement>) -> Matrix3<f64> {
    let mut g3 = embed(g);
    if let Some(h) = hoop {
        g3[(2, 2)] = h.strain;
    }
    g3
}

/// Finite strain (docs/theory.md §2): ΔF = I + g on the point's current volume, the
/// spatial gradients ∂N/∂x = ΔF⁻ᵀ ∂N/∂x_n of the step's start, the volume det ΔF v_n.
/// With F-bar's `volume_ratio` ΔJ̄ / ΔJ the law is driven by ΔF̄ instead, the volume is
/// det ΔF̄ v_n and the F-bar coupling Q is kept ([`crate::fbar`]); the spatial gradients
/// stay those of ΔF.
pub(crate) fn finite_strain_point<const D: usize>(
    model: &Model<D>,
    p: usize,
    g: &SMatrix<f64, D, D>,
    hoop: Option<HoopIncrement>,
    volume_ratio: Option<f64>,
    grads: &[SVector<f64, D>],
    slot: TrialSlot<'_, D>,
) -> Result<(), ConstitutiveError> {
    let pts = model.points();
    let TrialSlot { delta_f, stress, elastic_strain, volume, tangent, grad_x, history, inv_radius, volumetric } = slot;
    let mut g3 = increment_gradient(g, hoop);
    let plane = D == 2 && hoop.is_none();
    if let Some(ratio) = volume_ratio {
        g3 = crate::fbar::scaled_increment(&g3, ratio, plane);
    }
    let det_df = update_point(Kinematics::FiniteStrain, model.law(p), &g3, Committed::of(pts, p), history, |u| {
        let det_df = u.delta_f.determinant();
        (*delta_f, *stress, *elastic_strain) = (*u.delta_f, *u.stress, *u.elastic_strain);
        *volume = det_df * pts.volume()[p];
        *tangent = in_plane::<D>(u.tangent, *volume, hoop.is_some());
        if volume_ratio.is_some() {
            volumetric.1 = crate::fbar::coupling(u.tangent, u.stress, *volume, plane);
        }
        det_df
    })?;
    if let Some(h) = hoop {
        *inv_radius = 1.0 / (h.radius + h.strain * h.radius);
    }
    // det ΔF > 0 was checked by the update, so ΔF is invertible unless it is numerically
    // singular: an error, not a case to paper over.
    let inv = (SMatrix::<f64, D, D>::identity() + g)
        .try_inverse()
        .ok_or(ConstitutiveError::SingularIncrement { det: det_df })?;
    for (x, grad) in grad_x.iter_mut().zip(grads) {
        *x = inv.transpose() * grad;
    }
    Ok(())
}

/// θ̄ = Σ_a Δu_a · b̄_a: the cell's averaged dilatation (Hughes 1980).
fn averaged_dilatation<const D: usize>(avg: &CellAverage<'_, D>, nodes: &[u32], first: usize, du: &[f64]) -> f64 {
    nodes
        .iter()
        .enumerate()
        .map(|(a, &node)| (0..D).map(|i| du[node as usize * D + i] * avg.average(first + a)[i]).sum::<f64>())
        .sum()
}

/// Small strain (docs/theory.md §3) on the start-of-step volume, with the cell's averaged
/// dilatation θ̄ in place of the point's own when given: ε̄ = ε + (θ̄ − θ)/3 I.
fn small_strain_point<const D: usize>(
    model: &Model<D>,
    p: usize,
    g: &SMatrix<f64, D, D>,
    hoop: Option<HoopIncrement>,
    theta_bar: Option<f64>,
    grads: &[SVector<f64, D>],
    slot: TrialSlot<'_, D>,
) -> Result<(), ConstitutiveError> {
    let pts = model.points();
    let mut g3 = increment_gradient(g, hoop);
    if let Some(theta_bar) = theta_bar {
        let theta = if hoop.is_some() { g3.trace() } else { g.trace() };
        g3 += Matrix3::identity() * ((theta_bar - theta) / 3.0);
    }
    let TrialSlot { delta_f, stress, elastic_strain, volume, tangent, grad_x, volumetric, history, inv_radius } = slot;
    if let Some(h) = hoop {
        *inv_radius = 1.0 / h.radius;
    }
    update_point(Kinematics::SmallStrain, model.law(p), &g3, Committed::of(pts, p), history, |u| {
        (*delta_f, *stress, *elastic_strain) = (*u.delta_f, *u.stress, *u.elastic_strain);
        *volume = pts.volume()[p];
        *tangent = in_plane::<D>(u.tangent, *volume, hoop.is_some());
        if theta_bar.is_some() {
            let (a, v) = (u.tangent, *volume);
            let id = Matrix3::from_fn(|k, l| v * (0..3).map(|m| a[(4 * m, 3 * k + l)]).sum::<f64>());
            let di = Matrix3::from_fn(|i, j| v * (0..3).map(|m| a[(3 * i + j, 4 * m)]).sum::<f64>());
            *volumetric = (id, di);
        }
    })?;
    if theta_bar.is_none() {
        grad_x[..grads.len()].copy_from_slice(grads);
    }
    Ok(())
}

/// In-plane block (i·D + j, k·D + l) of a full 9×9 tensor, scaled; unused entries zero.
/// With `hoop` (axisymmetry, D = 2) also the θθ row and column, a_θθkl and a_ijθθ, at
/// index 4.
#[inline]
fn in_plane<const D: usize>(a: &Tensor4, scale: f64, hoop: bool) -> SMatrix<f64, 9, 9> {
    if D == 3 {
        return a * scale;
    }
    let mut out = SMatrix::<f64, 9, 9>::zeros();
    if hoop {
        const THETA: usize = 8; // θθ of the full tensor: 3·2 + 2
        for i in 0..D {
            for j in 0..D {
                out[(HOOP, i * D + j)] = scale * a[(THETA, 3 * i + j)];
                out[(i * D + j, HOOP)] = scale * a[(3 * i + j, THETA)];
            }
        }
        out[(HOOP, HOOP)] = scale * a[(THETA, THETA)];
    }
    for i in 0..D {
        for j in 0..D {
            for k in 0..D {
                for l in 0..D {
                    out[(i * D + j, k * D + l)] = scale * a[(3 * i + j, 3 * k + l)];
                }
            }
        }
    }
    out
}
