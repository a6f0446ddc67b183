//! F-bar in finite strain (de Souza Neto, Perić, Dutko & Owen 1996; for MPM, Coombs,
//! Charlton, Cortis & Augarde 2018; docs/theory.md §13): each point's law is driven by
//! ΔF̄ = (ΔJ̄ / ΔJ)^{1/m} ΔF, where ΔJ̄ = Σ_q v_q,n ΔJ_q / Σ_q v_q,n is the volume change of
//! its cell (its averaging group) and m = 3, or m = 2 on the in-plane part in plane strain
//! (F_zz stays 1). The cell keeps its volume, Σ_q ΔJ̄ v_q,n = Σ_q ΔJ_q v_q,n, but a point's
//! own dilatation no longer constrains the flow, so isochoric plasticity does not lock.
//!
//! The internal force stays f_a = Σ_p v_p σ̄_p ∂N_a/∂x (the spatial gradients of the
//! actual ΔF, v_p = det ΔF̄ v_p,n), so the residual is unchanged. Its derivative along δu,
//! with l = ∇_x δu and δ ln ΔJ̄ = tr l̄ = Σ_b δu_b · b̄_b, b̄_b the volume average of the
//! dilatation operator ∂N_b/∂x (+ N_b / r e_r in axisymmetry) over the cell in the trial
//! configuration, is the plain tangent plus
//!
//! K_ab,ik += v (∂N_a/∂x)_j Q_ij (b̄_b − ∂N_b/∂x − N_b / r e_r)_k,
//! Q = (1/m) (a : I_m + σ̄),
//!
//! a the spatial tangent of the plain case (with its geometric term), since δτ̄ =
//! c : (l + (1/m)(tr l̄ − tr l) I_m) and c / J̄ = a + σ̄_il δ_jk. The test side carries no
//! average, so the tangent is not symmetric.

use crate::cell_average::{average_dilatation_operators, CellGroups, PointOperators};
use crate::points::{
    finite_strain_point, for_each_slot, hoop_increment, increment_gradient, increment_of, HoopIncrement, PointInputs,
    PointUpdateError, TrialState,
};
use loam_constitutive::{ConstitutiveError, Tensor4};
use nalgebra::{Matrix3, SMatrix, SVector};
use rayon::prelude::*;

/// Update every point's trial state with F-bar: each point's ΔF and ΔJ, then the law
/// driven by ΔF̄ over the cell's ΔJ̄, then the cells' averaged dilatation operators b̄ in
/// the trial configuration for the tangent.
pub(crate) fn update_points<const D: usize>(
    inputs: PointInputs<'_, D>,
    groups: &CellGroups,
    trial: &mut TrialState<D>,
) -> Result<(), PointUpdateError> {
    increments(inputs, trial);
    cell_volume_changes(inputs, groups, trial);
    // Taken out for the update, which reads every point's ΔJ and its cell's ΔJ̄ while
    // writing its own slots.
    let jacobian = std::mem::take(&mut trial.jacobian);
    let cell_jacobian = std::mem::take(&mut trial.cell_jacobian);
    let result = for_each_slot(inputs, trial, |p, slot| {
        let j_bar = cell_jacobian[groups.group_of(p)];
        // A point whose own ΔF folds over is inverted whatever its cell does (ΔF̄ would
        // hide it: a negative ratio's cube root flips ΔF̄ back to a positive determinant),
        // and so is one whose cell folds over as a whole.
        let inverted = if jacobian[p] <= 0.0 { Some(jacobian[p]) } else { (j_bar <= 0.0).then_some(j_bar) };
        if let Some(j) = inverted {
            return Err(PointUpdateError { point: p, source: ConstitutiveError::NonPositiveJacobian { j } });
        }
        let ratio = j_bar / jacobian[p];
        let (g, hoop) = split_increment(inputs, p, slot.delta_f);
        let grads = inputs.conn.support_gradients(p);
        finite_strain_point(inputs.model, p, &g, hoop, Some(ratio), grads, slot)
            .map_err(|source| PointUpdateError { point: p, source })
    });
    trial.jacobian = jacobian;
    trial.cell_jacobian = cell_jacobian;
    result?;
    averaged_dilatation_operators(inputs, groups, trial);
    Ok(())
}

/// Every point's own ΔF = I + g (with the hoop stretch in axisymmetry) into the trial's
/// ΔF slot, and det ΔF into its Jacobian.
fn increments<const D: usize>(inputs: PointInputs<'_, D>, trial: &mut TrialState<D>) {
    let PointInputs { model, conn, du, .. } = inputs;
    (trial.delta_f.par_iter_mut(), trial.jacobian.par_iter_mut()).into_par_iter().enumerate().for_each(
        |(p, (delta_f, jacobian))| {
            let g = increment_of(conn.support_nodes(p), conn.support_gradients(p), du);
            let hoop = model.axisymmetric().then(|| hoop_increment(model, conn, p, du));
            *delta_f = Matrix3::identity() + increment_gradient(&g, hoop);
            *jacobian = delta_f.determinant();
        },
    );
}

/// The in-plane increment gradient and the hoop increment back from a point's ΔF.
fn split_increment<const D: usize>(
    inputs: PointInputs<'_, D>,
    p: usize,
    delta_f: &Matrix3<f64>,
) -> (SMatrix<f64, D, D>, Option<HoopIncrement>) {
    let g = SMatrix::<f64, D, D>::from_fn(|i, j| delta_f[(i, j)] - if i == j { 1.0 } else { 0.0 });
    let model = inputs.model;
    let hoop = model
        .axisymmetric()
        .then(|| HoopIncrement { strain: delta_f[(2, 2)] - 1.0, radius: model.configuration()[p][0] });
    (g, hoop)
}

/// ΔF̄ − I for the increment gradient `g3` (ΔF = I + g3) and the volume ratio ΔJ̄ / ΔJ:
/// the whole ΔF scaled by its cube root, or in plane strain the in-plane part by its
/// square root.
pub(crate) fn scaled_increment(g3: &Matrix3<f64>, ratio: f64, plane: bool) -> Matrix3<f64> {
    let mut delta_f = Matrix3::identity() + g3;
    if plane {
        let s = ratio.sqrt();
        delta_f.fixed_view_mut::<2, 2>(0, 0).scale_mut(s);
    } else {
        delta_f *= ratio.cbrt();
    }
    delta_f - Matrix3::identity()
}

/// F-bar's coupling Q = (v/m) (a : I_m + σ̄) of a point with spatial tangent `a` (full
/// 9×9, index 3i + j), Cauchy stress σ̄ and volume v (module docs).
pub(crate) fn coupling(a: &Tensor4, stress: &Matrix3<f64>, volume: f64, plane: bool) -> Matrix3<f64> {
    let m = if plane { 2 } else { 3 };
    let scale = volume / m as f64;
    Matrix3::from_fn(|i, j| scale * ((0..m).map(|k| a[(3 * i + j, 4 * k)]).sum::<f64>() + stress[(i, j)]))
}

/// Every cell's volume change ΔJ̄ = Σ_q v_q,n ΔJ_q / Σ_q v_q,n, once a cell.
fn cell_volume_changes<const D: usize>(inputs: PointInputs<'_, D>, groups: &CellGroups, trial: &mut TrialState<D>) {
    let volume_n = inputs.model.points().volume();
    let TrialState { jacobian, cell_jacobian, .. } = trial;
    cell_jacobian.resize(groups.len(), 1.0);
    cell_jacobian.par_iter_mut().enumerate().for_each(|(g, j_bar)| {
        let (mut vj, mut v) = (0.0, 0.0);
        for &q in groups.group(g) {
            vj += volume_n[q as usize] * jacobian[q as usize];
            v += volume_n[q as usize];
        }
        *j_bar = vj / v;
    });
}

/// b̄ of every point's support slot over its cell in the trial configuration: the actual
/// volumes v_q = ΔJ_q v_q,n, the spatial gradients and radii of the trial state.
fn averaged_dilatation_operators<const D: usize>(
    inputs: PointInputs<'_, D>,
    groups: &CellGroups,
    trial: &mut TrialState<D>,
) {
    let PointInputs { model, conn, .. } = inputs;
    let stride = conn.stride();
    let volume_n = model.points().volume();
    let TrialState { grad_x, jacobian, inv_radius, average_x, group_sums, .. } = trial;
    let operators = PointOperators {
        volume: |q: usize| volume_n[q] * jacobian[q],
        gradients: |q: usize| &grad_x[q * stride..][..conn.support_nodes(q).len()],
        inv_radius: |q: usize| inv_radius[q],
    };
    average_dilatation_operators(groups, conn, model.axisymmetric(), operators, group_sums, average_x);
}

/// F-bar's part of a point's block (a, b) of the tangent (module docs): the plain
/// gradient `ga` of the test side, db = b̄_b − ∂N_b/∂x − h_b e_r, the coupling Q and, in
/// axisymmetry, the hoop entry h_a of the test side's radial row.
#[inline]
pub(crate) fn add_tangent_terms<const D: usize>(
    q: &Matrix3<f64>,
    ga: &SVector<f64, D>,
    db: &SVector<f64, D>,
    hoop_a: Option<f64>,
    out: &mut [f64],
) {
    for i in 0..D {
        let row: f64 = (0..D).map(|j| ga[j] * q[(i, j)]).sum();
        for k in 0..D {
            out[i * D + k] += row * db[k];
        }
    }
    if let Some(ha) = hoop_a {
        for k in 0..D {
            out[k] += ha * q[(2, 2)] * db[k];
        }
    }
}
