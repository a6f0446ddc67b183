//! Point kinematics of a step (docs/theory.md §2, §3): from a displacement-increment
//! gradient to the increment of deformation, the stress and tangent of the point's law,
//! and, once the step is committed, the new deformation gradient and GIMP domain.

use loam_constitutive::{
    finite_strain_stress, finite_strain_update, small_strain_stress, small_strain_update, ConstitutiveError,
    ConstitutiveLaw, Tensor4,
};
use loam_model::Kinematics;
use loam_points::{stretched_half_length, PointStore};
use nalgebra::{Matrix3, SMatrix, SVector};

/// Embed an in-plane D×D tensor in 3×3, zero out of plane (plane strain: the
/// displacement gradient has no out-of-plane part).
#[inline]
pub fn embed<const D: usize>(g: &SMatrix<f64, D, D>) -> Matrix3<f64> {
    let mut m = Matrix3::zeros();
    m.fixed_view_mut::<D, D>(0, 0).copy_from(g);
    m
}

/// A point's committed state, which an update starts from.
#[derive(Debug, Clone, Copy)]
pub struct Committed<'a> {
    /// The deformation gradient F.
    pub f: &'a Matrix3<f64>,
    /// b^e (finite strain) or ε^e (small strain).
    pub elastic_strain: &'a Matrix3<f64>,
    /// The law's history.
    pub history: &'a [f64],
}

impl<'a> Committed<'a> {
    /// The committed state of point `p` of `points`.
    #[inline]
    pub fn of<const D: usize>(points: &'a PointStore<D>, p: usize) -> Self {
        Self {
            f: &points.deformation_gradient()[p],
            elastic_strain: &points.elastic_strain()[p],
            history: points.history(p),
        }
    }
}

/// A point's trial state from its committed one and an increment, lent where the law wrote
/// it (the 9×9 tangent is 648 bytes: read, not copied).
#[derive(Debug, Clone, Copy)]
pub struct PointUpdate<'a> {
    /// ΔF = I + ∇Δu.
    pub delta_f: &'a Matrix3<f64>,
    /// Cauchy stress σ.
    pub stress: &'a Matrix3<f64>,
    /// b^e (finite strain) or ε^e (small strain).
    pub elastic_strain: &'a Matrix3<f64>,
    /// The spatial tangent a (finite strain, docs/theory.md §2) or the algorithmic
    /// modulus D (small strain).
    pub tangent: &'a Tensor4,
}

/// Drive the point's law by the displacement-increment gradient `grad_du` (3×3, see
/// [`embed`]) from its committed state (the new history goes to `h_out`): finite strain
/// through b^e and the logarithmic strain with J = det ΔF det F, small strain through
/// ε^e + sym ∇Δu. The update is lent to `finish`, which keeps what its analysis needs.
#[inline]
pub fn update_point<R>(
    kinematics: Kinematics,
    law: &dyn ConstitutiveLaw,
    grad_du: &Matrix3<f64>,
    committed: Committed<'_>,
    h_out: &mut [f64],
    finish: impl FnOnce(PointUpdate<'_>) -> R,
) -> Result<R, ConstitutiveError> {
    let Committed { f, elastic_strain, history } = committed;
    let (history, h_out) = own_history(law, history, h_out);
    let delta_f = Matrix3::identity() + grad_du;
    Ok(match kinematics {
        Kinematics::FiniteStrain => {
            let j_total = delta_f.determinant() * f.determinant();
            let u = finite_strain_update(law, &delta_f, elastic_strain, j_total, history, h_out)?;
            finish(PointUpdate {
                delta_f: &delta_f,
                stress: &u.cauchy,
                elastic_strain: &u.be,
                tangent: &u.spatial_tangent,
            })
        }
        Kinematics::SmallStrain => {
            let u = small_strain_update(law, grad_du, elastic_strain, history, h_out)?;
            finish(PointUpdate {
                delta_f: &delta_f,
                stress: &u.stress,
                elastic_strain: &u.elastic_strain,
                tangent: &u.tangent,
            })
        }
    })
}

/// The law's own history slots of a point, committed and new
/// ([`ConstitutiveLaw::own_history`]). The slots beyond carry their committed values over,
/// so that a trial buffer holds no other point's leftovers.
#[inline]
fn own_history<'a, 'b>(
    law: &dyn ConstitutiveLaw,
    history: &'a [f64],
    h_out: &'b mut [f64],
) -> (&'a [f64], &'b mut [f64]) {
    let slots = history.len().min(h_out.len());
    if slots == 0 {
        // No law of the model keeps a history (the common elastic case): nothing to give.
        return (history, h_out);
    }
    let n = law.own_history(&history[..slots]).len();
    if n < slots {
        h_out[n..slots].copy_from_slice(&history[n..slots]);
    }
    (&history[..n], &mut h_out[..n])
}

/// A point's trial state without its tangent ([`update_point_stress`]).
#[derive(Debug, Clone, Copy)]
pub struct PointStress {
    /// ΔF = I + ∇Δu.
    pub delta_f: Matrix3<f64>,
    /// Cauchy stress σ.
    pub stress: Matrix3<f64>,
    /// b^e (finite strain) or ε^e (small strain).
    pub elastic_strain: Matrix3<f64>,
}

/// [`update_point`] for an analysis with no use for the tangent (explicit MPM): the same
/// stress, elastic strain and history, without the finite-strain tangent's cost.
#[inline]
pub fn update_point_stress(
    kinematics: Kinematics,
    law: &dyn ConstitutiveLaw,
    grad_du: &Matrix3<f64>,
    committed: Committed<'_>,
    h_out: &mut [f64],
) -> Result<PointStress, ConstitutiveError> {
    let Committed { f, elastic_strain, history } = committed;
    let (history, h_out) = own_history(law, history, h_out);
    let delta_f = Matrix3::identity() + grad_du;
    Ok(match kinematics {
        Kinematics::FiniteStrain => {
            let j_total = delta_f.determinant() * f.determinant();
            let u = finite_strain_stress(law, &delta_f, elastic_strain, j_total, history, h_out)?;
            PointStress { delta_f, stress: u.cauchy, elastic_strain: u.be }
        }
        Kinematics::SmallStrain => {
            let (stress, elastic_strain) = small_strain_stress(law, grad_du, elastic_strain, history, h_out)?;
            PointStress { delta_f, stress, elastic_strain }
        }
    })
}

/// Commit a point's increment of deformation: F ← ΔF F, and the GIMP half-lengths
/// stretched with the new F (iGIMP, docs/theory.md §4).
#[inline]
pub fn advance_deformation<const D: usize>(
    delta_f: &Matrix3<f64>,
    f: &mut Matrix3<f64>,
    half_length: &mut SVector<f64, D>,
    half_length0: &SVector<f64, D>,
) {
    *f = delta_f * *f;
    *half_length = stretched_half_length(half_length0, f);
}

#[cfg(test)]
mod tests {
    use super::*;
    use loam_constitutive::Elastic;
    use nalgebra::Matrix2;

    /// A uniaxial stretch λ in small strain gives σ_xx = (λ' + 2μ) ε with ε = λ − 1 and
    /// σ_yy = σ_zz = λ' ε; in finite strain the Kirchhoff stress of Hencky elasticity at
    /// ε = ln λ over J = λ.
    #[test]
    fn a_uniaxial_stretch_gives_the_closed_form_stress() {
        let law = Elastic::new(1000.0, 0.25).unwrap();
        let (lame, mu) = law.lame();
        let stretch = 1.01;
        let g = embed(&Matrix2::new(stretch - 1.0, 0.0, 0.0, 0.0));
        let (mut h, f) = ([0.0; 0], Matrix3::identity());
        let kept = |u: PointUpdate| (*u.stress, u.delta_f.determinant());
        let unstrained = Committed { f: &f, elastic_strain: &Matrix3::zeros(), history: &[] };
        let (small, _) = update_point(Kinematics::SmallStrain, &law, &g, unstrained, &mut h, kept).unwrap();
        let eps = stretch - 1.0;
        assert!((small[(0, 0)] - (lame + 2.0 * mu) * eps).abs() < 1e-10);
        assert!((small[(2, 2)] - lame * eps).abs() < 1e-10);
        let unstrained = Committed { f: &f, elastic_strain: &Matrix3::identity(), history: &[] };
        let (finite, det) = update_point(Kinematics::FiniteStrain, &law, &g, unstrained, &mut h, kept).unwrap();
        let e = f64::ln(stretch);
        assert!((finite[(0, 0)] - (lame + 2.0 * mu) * e / stretch).abs() < 1e-10);
        assert!((det - stretch).abs() < 1e-15);
        // Without the tangent: the same stress to the last bit, in either kinematics.
        for kinematics in [Kinematics::FiniteStrain, Kinematics::SmallStrain] {
            let b = if kinematics == Kinematics::FiniteStrain { Matrix3::identity() } else { Matrix3::zeros() };
            let c = Committed { f: &f, elastic_strain: &b, history: &[] };
            let full = update_point(kinematics, &law, &g, c, &mut h, |u| (*u.stress, *u.elastic_strain)).unwrap();
            let only = update_point_stress(kinematics, &law, &g, c, &mut h).unwrap();
            assert_eq!((only.stress, only.elastic_strain), full);
        }
    }
}
