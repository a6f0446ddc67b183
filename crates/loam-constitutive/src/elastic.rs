//! Linear isotropic elasticity, σ = λ tr(ε) I + 2μ ε. Driven by small strain it is linear
//! elasticity; driven by logarithmic strain through
//! [`finite_strain_update`](crate::finite_strain_update) it is Hencky elasticity
//! (de Souza Neto et al. 2008, §14.2).

use nalgebra::Matrix3;

use crate::tensor::{isotropic, Tensor4};
use crate::{check_finite, ConstitutiveError, ConstitutiveLaw, MaterialState, StressUpdate};

/// Linear isotropic elasticity with Young's modulus and Poisson's ratio.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Elastic {
    pub young: f64,
    pub poisson: f64,
}

impl Elastic {
    /// Validates `E > 0` and `-1 < ν < 0.5` (strict: ν = 0.5 makes λ infinite).
    pub fn new(young: f64, poisson: f64) -> Result<Self, ConstitutiveError> {
        if !(young.is_finite() && young > 0.0) {
            return Err(ConstitutiveError::InvalidParameter { name: "young", value: young });
        }
        if !(poisson.is_finite() && poisson > -1.0 && poisson < 0.5) {
            return Err(ConstitutiveError::InvalidParameter { name: "poisson", value: poisson });
        }
        Ok(Self { young, poisson })
    }

    /// Lamé constants `(λ, μ)`.
    #[inline]
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.young, self.poisson);
        let mu = e / (2.0 * (1.0 + nu));
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        (lambda, mu)
    }

    /// The constant elasticity tensor `λ I⊗I + 2μ I^s`.
    pub fn stiffness(&self) -> Tensor4 {
        let (lambda, mu) = self.lame();
        isotropic(lambda, mu)
    }

    /// The strain of a given stress, inverting Hooke's law:
    /// ε = (1+ν)/E σ − ν/E tr(σ) I.
    pub fn strain(&self, stress: &Matrix3<f64>) -> Matrix3<f64> {
        (stress * (1.0 + self.poisson) - Matrix3::identity() * (self.poisson * stress.trace())) / self.young
    }

    /// P-wave (constrained) modulus λ + 2μ.
    #[inline]
    pub fn p_wave_modulus(&self) -> f64 {
        let (lambda, mu) = self.lame();
        lambda + 2.0 * mu
    }

    /// Stress for a given (symmetric) strain.
    #[inline]
    pub fn stress(&self, eps: &Matrix3<f64>) -> Matrix3<f64> {
        let (lambda, mu) = self.lame();
        Matrix3::identity() * (lambda * eps.trace()) + eps * (2.0 * mu)
    }
}

impl ConstitutiveLaw for Elastic {
    fn elasticity(&self, _state: &MaterialState) -> Option<Elastic> {
        Some(*self)
    }

    fn name(&self) -> &'static str {
        "elastic"
    }

    fn update(
        &self,
        eps_trial: &Matrix3<f64>,
        _h_n: &[f64],
        _h_out: &mut [f64],
    ) -> Result<StressUpdate, ConstitutiveError> {
        check_finite(eps_trial, "trial strain")?;
        Ok(StressUpdate { stress: self.stress(eps_trial), elastic_strain: *eps_trial, tangent: self.stiffness() })
    }

    fn update_stress(
        &self,
        eps_trial: &Matrix3<f64>,
        _h_n: &[f64],
        _h_out: &mut [f64],
    ) -> Result<(Matrix3<f64>, Matrix3<f64>), ConstitutiveError> {
        check_finite(eps_trial, "trial strain")?;
        Ok((self.stress(eps_trial), *eps_trial))
    }

    fn stored_energy(&self, eps: &Matrix3<f64>) -> f64 {
        let (lambda, mu) = self.lame();
        0.5 * lambda * eps.trace().powi(2) + mu * eps.component_mul(eps).sum()
    }

    fn p_wave_modulus(&self, _state: &MaterialState) -> f64 {
        Elastic::p_wave_modulus(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::{central_difference, idx, symmetric_unit_directions};

    #[test]
    fn rejects_bad_parameters() {
        assert!(Elastic::new(0.0, 0.3).is_err());
        assert!(Elastic::new(-1.0, 0.3).is_err());
        assert!(Elastic::new(f64::NAN, 0.3).is_err());
        assert!(Elastic::new(1.0, 0.5).is_err());
        assert!(Elastic::new(1.0, -1.0).is_err());
        assert!(Elastic::new(1.0, 0.49).is_ok());
        assert!(Elastic::new(1.0, -0.5).is_ok());
    }

    #[test]
    fn rejects_non_finite_strain() {
        let law = Elastic::new(1.0, 0.2).unwrap();
        let mut e = Matrix3::zeros();
        e[(0, 0)] = f64::INFINITY;
        assert!(matches!(law.update(&e, &[], &mut []), Err(ConstitutiveError::NonFinite { .. })));
    }

    #[test]
    fn uniaxial_strain_closed_form() {
        let law = Elastic::new(200.0, 0.25).unwrap();
        let (lambda, mu) = law.lame();
        // E = 200, ν = 0.25: μ = 80, λ = 80 (closed form).
        assert!((mu - 80.0).abs() < 1e-12 && (lambda - 80.0).abs() < 1e-12);
        let e = 1e-3;
        let mut eps = Matrix3::zeros();
        eps[(1, 1)] = e;
        let up = law.update(&eps, &[], &mut []).unwrap();
        // Exact arithmetic up to a couple of roundings.
        assert!((up.stress[(1, 1)] - (lambda + 2.0 * mu) * e).abs() < 1e-15);
        assert!((up.stress[(0, 0)] - lambda * e).abs() < 1e-15);
        assert!((up.stress[(2, 2)] - lambda * e).abs() < 1e-15);
        assert_eq!(up.stress[(0, 1)], 0.0);
        assert_eq!(up.elastic_strain, eps);
        assert!((up.tangent - isotropic(lambda, mu)).norm() < 1e-12);
        assert!((law.p_wave_modulus() - 240.0).abs() < 1e-12);
    }

    #[test]
    fn tangent_matches_finite_difference() {
        let law = Elastic::new(1.3e4, 0.31).unwrap();
        let eps0 = Matrix3::new(1e-3, 2e-4, -3e-4, 2e-4, -5e-4, 1e-4, -3e-4, 1e-4, 7e-4);
        let d = law.update(&eps0, &[], &mut []).unwrap().tangent;
        // Linear law: central differences are exact up to round-off (~1e-16 · |σ| / h).
        let fd = central_difference(|e| law.update(e, &[], &mut []).unwrap().stress, &eps0, 1e-6);
        let r = (d - fd).norm() / d.norm();
        assert!(r < 1e-6, "rel {r}");
        // Minor symmetry.
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        assert_eq!(d[(idx(i, j), idx(k, l))], d[(idx(j, i), idx(k, l))]);
                        assert_eq!(d[(idx(i, j), idx(k, l))], d[(idx(i, j), idx(l, k))]);
                    }
                }
            }
        }
    }

    /// σ = ∂W/∂ε: central differences of the stored energy recover the stress. W is
    /// quadratic, so the difference is exact up to round-off (~1e-16 |W| / h ≈ 1e-10 |σ|).
    #[test]
    fn stored_energy_is_the_stress_potential() {
        let law = Elastic::new(1.3e4, 0.31).unwrap();
        let eps = Matrix3::new(1e-3, 2e-4, -3e-4, 2e-4, -5e-4, 1e-4, -3e-4, 1e-4, 7e-4);
        let sigma = law.stress(&eps);
        let h = 1e-6;
        for (k, l, s) in symmetric_unit_directions() {
            let dw = (law.stored_energy(&(eps + s * h)) - law.stored_energy(&(eps - s * h))) / (2.0 * h);
            // dW along the symmetric direction s is σ : s = σ_kl (σ symmetric).
            assert!((dw - sigma[(k, l)]).abs() < 1e-6 * sigma.norm(), "({k},{l}): {dw} vs {}", sigma[(k, l)]);
        }
        assert_eq!(law.stored_energy(&Matrix3::zeros()), 0.0);
    }
}
