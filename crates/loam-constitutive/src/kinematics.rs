//! Kinematic drivers that turn a displacement increment into a trial elastic strain, call
//! a [`ConstitutiveLaw`], and return stress and tangent in the form the assembly needs.
//!
//! - Small strain (docs/theory.md §3): `ε_tr = ε^e_n + sym(∇Δu)`.
//! - Finite strain (docs/theory.md §2): logarithmic elastic strain from `b^e_tr = ΔF b^e_n ΔFᵀ`,
//!   spatial tangent of de Souza Neto, Perić & Owen (2008), eq. 14.103.

use nalgebra::Matrix3;

use crate::tensor::{b_operator, idx, log_derivative_spectral, spectral, Spectral, Tensor4};
use crate::{check_finite, ConstitutiveError, ConstitutiveLaw, StressUpdate};

fn check_history(law: &dyn ConstitutiveLaw, h_n: &[f64], h_out: &[f64]) -> Result<(), ConstitutiveError> {
    let expected = law.history_len();
    for got in [h_n.len(), h_out.len()] {
        if got != expected {
            return Err(ConstitutiveError::HistoryLength { expected, got });
        }
    }
    Ok(())
}

/// Small-strain kinematics (docs/theory.md §3): `eps_trial = eps_e_n + sym(grad_du)` where
/// `grad_du` is the 3×3 displacement-increment gradient; returns the law's update.
pub fn small_strain_update(
    law: &dyn ConstitutiveLaw,
    grad_du: &Matrix3<f64>,
    eps_e_n: &Matrix3<f64>,
    h_n: &[f64],
    h_out: &mut [f64],
) -> Result<StressUpdate, ConstitutiveError> {
    law.update(&small_strain_trial(law, grad_du, eps_e_n, h_n, h_out)?, h_n, h_out)
}

/// [`small_strain_update`] without the modulus: the stress and elastic strain.
pub fn small_strain_stress(
    law: &dyn ConstitutiveLaw,
    grad_du: &Matrix3<f64>,
    eps_e_n: &Matrix3<f64>,
    h_n: &[f64],
    h_out: &mut [f64],
) -> Result<(Matrix3<f64>, Matrix3<f64>), ConstitutiveError> {
    law.update_stress(&small_strain_trial(law, grad_du, eps_e_n, h_n, h_out)?, h_n, h_out)
}

/// `eps_trial = eps_e_n + sym(grad_du)`, its inputs checked.
fn small_strain_trial(
    law: &dyn ConstitutiveLaw,
    grad_du: &Matrix3<f64>,
    eps_e_n: &Matrix3<f64>,
    h_n: &[f64],
    h_out: &[f64],
) -> Result<Matrix3<f64>, ConstitutiveError> {
    check_finite(grad_du, "displacement-increment gradient")?;
    check_finite(eps_e_n, "elastic strain")?;
    check_history(law, h_n, h_out)?;
    Ok(eps_e_n + (grad_du + grad_du.transpose()) * 0.5)
}

/// Result of [`finite_strain_update`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiniteStrainUpdate {
    /// σ = τ / J.
    pub cauchy: Matrix3<f64>,
    /// Kirchhoff stress τ.
    pub kirchhoff: Matrix3<f64>,
    /// Updated elastic left Cauchy–Green tensor b^e = exp(2 ε^e).
    pub be: Matrix3<f64>,
    /// a_ijkl = (1/(2J)) D_ijmn L_mnpq B_pqkl − σ_il δ_jk (docs/theory.md §2). With g the
    /// velocity-gradient-like perturbation (δΔF = g ΔF), `J a : g = δτ − τ gᵀ`, the exact
    /// linearisation of the internal force per reference volume.
    pub spatial_tangent: Tensor4,
}

/// Finite-strain update (docs/theory.md §2): `b_tr = ΔF b^e_n ΔFᵀ`, `ε_tr = ½ ln b_tr` (spectral),
/// `law.update(ε_tr)` → τ, ε^e, D; `σ = τ / j_total`; `b^e = exp(2 ε^e)`; spatial tangent a
/// (de Souza Neto et al. 2008, eq. 14.103).
///
/// `j_total` = det(F_{n+1}), the total Jacobian, given by the caller since plastic flow
/// may change volume. Errors for non-finite input, `det ΔF ≤ 0`, `j_total ≤ 0`, and a
/// non-positive-definite `b^e_n` (detected through `b_tr`).
pub fn finite_strain_update(
    law: &dyn ConstitutiveLaw,
    delta_f: &Matrix3<f64>,
    be_n: &Matrix3<f64>,
    j_total: f64,
    h_n: &[f64],
    h_out: &mut [f64],
) -> Result<FiniteStrainUpdate, ConstitutiveError> {
    let trial = FiniteStrainTrial::new(law, delta_f, be_n, j_total, h_n, h_out)?;
    let up = law.update(&trial.eps_tr, h_n, h_out)?;
    let FiniteStrainStress { cauchy, kirchhoff, be } = trial.stress(&up.stress, &up.elastic_strain)?;
    let l = log_derivative_spectral(&trial.spec);
    let bop = b_operator(&trial.b_tr);
    let mut a = up.tangent * (l * bop) * (0.5 / j_total);
    // Geometric term −σ_il δ_jk: nonzero only where j = k.
    for i in 0..3 {
        for j in 0..3 {
            for ll in 0..3 {
                a[(idx(i, j), idx(j, ll))] -= cauchy[(i, ll)];
            }
        }
    }
    Ok(FiniteStrainUpdate { cauchy, kirchhoff, be, spatial_tangent: a })
}

/// Result of [`finite_strain_stress`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FiniteStrainStress {
    /// σ = τ / J.
    pub cauchy: Matrix3<f64>,
    /// Kirchhoff stress τ.
    pub kirchhoff: Matrix3<f64>,
    /// Updated elastic left Cauchy–Green tensor b^e = exp(2 ε^e).
    pub be: Matrix3<f64>,
}

/// [`finite_strain_update`] without the spatial tangent, for an analysis that has no use
/// for it (explicit MPM): the same stress and b^e to the last bit, at a fraction of the
/// cost (the tangent's two 9 × 9 products and the derivative of the logarithm).
// Inline (with the trial's constructor, its stress and `spectral`): the explicit step calls
// it per point from another crate, and inlined, its 200-byte results are built in place
// instead of copied through three calls (measured: CHANGELOG.md, Explicit speed).
#[inline]
pub fn finite_strain_stress(
    law: &dyn ConstitutiveLaw,
    delta_f: &Matrix3<f64>,
    be_n: &Matrix3<f64>,
    j_total: f64,
    h_n: &[f64],
    h_out: &mut [f64],
) -> Result<FiniteStrainStress, ConstitutiveError> {
    let trial = FiniteStrainTrial::new(law, delta_f, be_n, j_total, h_n, h_out)?;
    let (tau, eps_e) = law.update_stress(&trial.eps_tr, h_n, h_out)?;
    trial.stress(&tau, &eps_e)
}

/// The trial state of a finite-strain update, the law's input.
struct FiniteStrainTrial {
    b_tr: Matrix3<f64>,
    spec: Spectral,
    eps_tr: Matrix3<f64>,
    j_total: f64,
}

impl FiniteStrainTrial {
    #[inline]
    fn new(
        law: &dyn ConstitutiveLaw,
        delta_f: &Matrix3<f64>,
        be_n: &Matrix3<f64>,
        j_total: f64,
        h_n: &[f64],
        h_out: &[f64],
    ) -> Result<Self, ConstitutiveError> {
        check_finite(delta_f, "deformation-gradient increment")?;
        check_finite(be_n, "elastic left Cauchy-Green tensor")?;
        if !j_total.is_finite() {
            return Err(ConstitutiveError::NonFinite { what: "total Jacobian" });
        }
        if j_total <= 0.0 {
            return Err(ConstitutiveError::NonPositiveJacobian { j: j_total });
        }
        // An inverted increment still gives an SPD b_tr, so it must be caught here
        // (inputs are finite, so det_df is not NaN).
        let det_df = delta_f.determinant();
        if det_df <= 0.0 {
            return Err(ConstitutiveError::NonPositiveJacobian { j: det_df });
        }
        check_history(law, h_n, h_out)?;
        let b_tr = delta_f * be_n * delta_f.transpose();
        let b_tr = (b_tr + b_tr.transpose()) * 0.5;
        let spec = spectral(&b_tr)?;
        let min = spec.min_value();
        if min <= 0.0 {
            return Err(ConstitutiveError::NotPositiveDefinite { min_eigenvalue: min });
        }
        let eps_tr = spec.map(|l| 0.5 * l.ln());
        Ok(Self { b_tr, spec, eps_tr, j_total })
    }

    /// σ = τ / J and b^e from the law's Kirchhoff stress `tau` and elastic strain `eps_e`.
    #[inline]
    fn stress(&self, tau: &Matrix3<f64>, eps_e: &Matrix3<f64>) -> Result<FiniteStrainStress, ConstitutiveError> {
        check_finite(tau, "stress returned by the law")?;
        check_finite(eps_e, "elastic strain returned by the law")?;
        let be = elastic_b(eps_e, &self.eps_tr, &self.b_tr, &self.spec)?;
        // One division instead of nine (a point's update is a chain of dependent divisions,
        // logarithms and roots; each one on it costs the explicit step).
        Ok(FiniteStrainStress { cauchy: tau * (1.0 / self.j_total), kirchhoff: *tau, be })
    }
}

/// `b^e = exp(2 ε^e)`, avoiding a second eigen-decomposition in the common cases: an
/// elastic step (ε^e is ε_tr, so b^e is b_tr) and an isotropic return (ε^e coaxial with
/// b_tr, so the trial eigenvectors diagonalise it).
#[inline]
fn elastic_b(
    eps_e: &Matrix3<f64>,
    eps_tr: &Matrix3<f64>,
    b_tr: &Matrix3<f64>,
    spec: &Spectral,
) -> Result<Matrix3<f64>, ConstitutiveError> {
    if eps_e == eps_tr {
        return Ok(*b_tr);
    }
    let n = &spec.vectors;
    let m = n.transpose() * eps_e * n;
    let off = m[(0, 1)].abs().max(m[(0, 2)].abs()).max(m[(1, 2)].abs());
    let scale = m.diagonal().amax().max(1e-300);
    let be = if off <= 1e-14 * scale {
        let d = Matrix3::from_diagonal(&m.diagonal().map(|e| (2.0 * e).exp()));
        n * d * n.transpose()
    } else {
        spectral(eps_e)?.map(|e| (2.0 * e).exp())
    };
    check_finite(&be, "updated elastic left Cauchy-Green tensor")?;
    Ok(be)
}
