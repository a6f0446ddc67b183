//! J2 (von Mises) plasticity with linear isotropic hardening or softening and a residual
//! floor: radial return with the closed-form multiplier and the consistent tangent of
//! de Souza Neto, Perić & Owen (2008), Box 7.3/7.4 and eq. 7.120.
//!
//! Yield function Φ = q − σ_y(ε̄p) with q = √(3 J₂) = √(3/2) ‖s‖ and the piecewise-linear
//! yield stress σ_y(ε̄p) = max(σ_y0 + H ε̄p, σ_res). The floor only matters for H < 0
//! (softening): the residual value is in [0, σ_y0], so for H ≥ 0 it is never reached.

use nalgebra::Matrix3;

use crate::tensor::{flatten, identity_dyad, sym_identity, Tensor4};
use crate::{
    check_finite, check_update_inputs, ConstitutiveError, ConstitutiveLaw, Elastic, MaterialState, StrengthReducible,
    StressUpdate,
};

/// Which branch of the return mapping an update took (see [`VonMises::update_with_region`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VonMisesRegion {
    /// Trial state inside the yield surface: returned unchanged.
    Elastic,
    /// Plastic return on the sloped branch σ_y = σ_y0 + H ε̄p (H may be 0 or negative).
    Plastic,
    /// Plastic return ending on the residual floor σ_y = σ_res (H < 0 only).
    Residual,
}

/// Elastic–plastic J2 law. History slot 0: accumulated equivalent plastic strain ε̄p
/// (Δε̄p = √(2/3) ‖Δε^p‖, which equals the plastic multiplier Δγ of the radial return).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VonMises {
    pub elastic: Elastic,
    /// Initial yield stress σ_y0 in the √(3 J₂) = σ_y convention.
    pub yield_stress: f64,
    /// Linear hardening modulus H = dσ_y/dε̄p (negative: softening). Must exceed −3G.
    pub hardening: f64,
    /// Floor below which softening cannot take σ_y (default 0).
    pub residual_yield_stress: f64,
}

/// f_trial ≤ YIELD_TOL · σ_y(ε̄p_n) counts as elastic: a state committed on the surface and
/// re-evaluated with a zero increment is not pushed through a round-off plastic step.
const YIELD_TOL: f64 = 1e-12;

impl VonMises {
    /// Validates σ_y > 0 (finite) and −3G < H < ∞ (H ≤ −3G makes the return mapping
    /// ill-posed: Φ(Δγ) would no longer decrease with Δγ). Residual yield stress is 0.
    pub fn new(elastic: Elastic, yield_stress: f64, hardening: f64) -> Result<Self, ConstitutiveError> {
        // Re-validate the elastic constants: the fields are public.
        let elastic = Elastic::new(elastic.young, elastic.poisson)?;
        if !(yield_stress.is_finite() && yield_stress > 0.0) {
            return Err(ConstitutiveError::InvalidParameter { name: "yield_stress", value: yield_stress });
        }
        let (_, mu) = elastic.lame();
        if !(hardening.is_finite() && hardening > -3.0 * mu) {
            return Err(ConstitutiveError::InvalidParameter { name: "hardening", value: hardening });
        }
        Ok(Self { elastic, yield_stress, hardening, residual_yield_stress: 0.0 })
    }

    /// Sets the residual yield stress, which must lie in [0, σ_y0].
    pub fn with_residual_yield_stress(mut self, residual: f64) -> Result<Self, ConstitutiveError> {
        if !(residual.is_finite() && residual >= 0.0 && residual <= self.yield_stress) {
            return Err(ConstitutiveError::InvalidParameter { name: "residual_yield_stress", value: residual });
        }
        self.residual_yield_stress = residual;
        Ok(self)
    }

    /// σ_y(ε̄p) = max(σ_y0 + H ε̄p, σ_res).
    pub fn current_yield_stress(&self, eqps: f64) -> f64 {
        (self.yield_stress + self.hardening * eqps).max(self.residual_yield_stress)
    }

    /// The stress update together with the branch it took.
    pub fn update_with_region(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<(StressUpdate, VonMisesRegion), ConstitutiveError> {
        let (r, region) = self.returned(eps_trial, h_n, h_out)?;
        let tangent = match &r.flow {
            None => self.elastic.stiffness(),
            Some(flow) => flow.tangent(),
        };
        Ok((StressUpdate { stress: r.stress, elastic_strain: r.elastic_strain, tangent }, region))
    }

    /// The stress, elastic strain and history of an update (radial return, de Souza Neto
    /// et al. 2008, Box 7.4), with what its consistent tangent needs where it flowed.
    fn returned(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<(Returned, VonMisesRegion), ConstitutiveError> {
        let eqps_n = check_inputs(eps_trial, h_n, h_out)?;
        let eps = (eps_trial + eps_trial.transpose()) * 0.5;
        let (lambda, mu) = self.elastic.lame();
        let bulk = lambda + 2.0 * mu / 3.0;
        let g = mu;

        let vol = eps.trace();
        let dev = eps - Matrix3::identity() * (vol / 3.0);
        let s_tr = dev * (2.0 * g);
        let s_norm = s_tr.norm();
        if !(s_norm.is_finite() && vol.is_finite()) {
            return Err(ConstitutiveError::NonFinite { what: "von Mises trial stress" });
        }
        let q_tr = (1.5f64).sqrt() * s_norm;
        let sy_n = self.current_yield_stress(eqps_n);
        let f_tr = q_tr - sy_n;

        if f_tr <= YIELD_TOL * sy_n.max(self.yield_stress) {
            h_out[0] = eqps_n;
            // Exactly the elastic law's update of the input (not of its symmetrised copy).
            let r = Returned { stress: self.elastic.stress(eps_trial), elastic_strain: *eps_trial, flow: None };
            return Ok((r, VonMisesRegion::Elastic));
        }

        let (dgamma, h_eff, region) = self.multiplier(q_tr, f_tr, g, eqps_n);
        // q_tr > 0 here: f_tr > 0 and σ_y ≥ 0.
        let n_hat = s_tr / s_norm;
        let factor = 1.0 - 3.0 * g * dgamma / q_tr;
        let s = s_tr * factor;
        let stress = s + Matrix3::identity() * (bulk * vol);
        // ε^e = ε_tr − Δγ √(3/2) N̂ (flow vector ∂Φ/∂σ = √(3/2) N̂).
        let elastic_strain = eps - n_hat * (dgamma * (1.5f64).sqrt());
        check_finite(&stress, "von Mises stress")?;
        h_out[0] = eqps_n + dgamma;
        let flow = Flow { g, bulk, factor, n_hat, dgamma, q_tr, h_eff };
        Ok((Returned { stress, elastic_strain, flow: Some(flow) }, region))
    }

    /// The plastic multiplier Δγ of a return from q_tr with the yield excess f_tr, the
    /// hardening modulus it ends on and its region: the closed form on the sloped branch
    /// (de Souza Neto et al. 2008, Box 7.4 with linear hardening),
    /// Φ(Δγ) = q_tr − 3GΔγ − (σ_y(ε̄p_n) + H Δγ) = 0, or on the residual floor.
    fn multiplier(&self, q_tr: f64, f_tr: f64, g: f64, eqps_n: f64) -> (f64, f64, VonMisesRegion) {
        let floor = self.residual_yield_stress;
        let h = self.hardening;
        let on_slope_at_n = h >= 0.0 || self.yield_stress + h * eqps_n > floor;
        let dgamma = f_tr / (3.0 * g + h);
        if !on_slope_at_n || (h < 0.0 && self.yield_stress + h * (eqps_n + dgamma) < floor) {
            // The return ends on the floor (σ_y constant = σ_res): redo with H = 0.
            // q_tr > σ_y(ε̄p_n) ≥ σ_res, so Δγ > 0; the sloped solution crossed the floor, so
            // ε̄p_n + Δγ lies beyond the kink and the floor branch is the consistent one
            // (Φ decreases monotonically in Δγ because H > −3G).
            return ((q_tr - floor) / (3.0 * g), 0.0, VonMisesRegion::Residual);
        }
        (dgamma, h, VonMisesRegion::Plastic)
    }
}

/// An update's stress and elastic strain, and its return where it flowed.
struct Returned {
    stress: Matrix3<f64>,
    elastic_strain: Matrix3<f64>,
    flow: Option<Flow>,
}

/// A radial return: shear and bulk moduli, the deviatoric scaling 1 − 3GΔγ/q_tr, the flow
/// direction N̂, the multiplier, the trial q and the hardening modulus it ended on.
struct Flow {
    g: f64,
    bulk: f64,
    factor: f64,
    n_hat: Matrix3<f64>,
    dgamma: f64,
    q_tr: f64,
    h_eff: f64,
}

impl Flow {
    /// The consistent tangent, de Souza Neto et al. 2008, eq. 7.120:
    /// D = 2G(1 − 3GΔγ/q_tr) I_d + 6G²(Δγ/q_tr − 1/(3G+H)) N̂⊗N̂ + K I⊗I.
    fn tangent(&self) -> Tensor4 {
        let Flow { g, bulk, factor, n_hat, dgamma, q_tr, h_eff } = *self;
        let i_dyad = identity_dyad();
        let i_dev = sym_identity() - i_dyad / 3.0;
        let nf = flatten(&n_hat);
        i_dev * (2.0 * g * factor)
            + nf * nf.transpose() * (6.0 * g * g * (dgamma / q_tr - 1.0 / (3.0 * g + h_eff)))
            + i_dyad * bulk
    }
}

/// The input checks: a finite trial strain and one history value, the equivalent plastic
/// strain ε̄p ≥ 0; returns it.
fn check_inputs(eps_trial: &Matrix3<f64>, h_n: &[f64], h_out: &[f64]) -> Result<f64, ConstitutiveError> {
    check_update_inputs(eps_trial, h_n, h_out, 1)?;
    let eqps_n = h_n[0];
    if !(eqps_n.is_finite() && eqps_n >= 0.0) {
        return Err(ConstitutiveError::NonFinite { what: "equivalent plastic strain history" });
    }
    Ok(eqps_n)
}

impl StrengthReducible for VonMises {
    /// σ_y, H and the residual σ_y over F: the undrained strength c_u = σ_y/√3 over F.
    fn with_strength_reduced(&self, factor: f64) -> Result<std::sync::Arc<dyn ConstitutiveLaw>, ConstitutiveError> {
        VonMises::new(self.elastic, self.yield_stress / factor, self.hardening / factor)
            .and_then(|law| law.with_residual_yield_stress(self.residual_yield_stress / factor))
            .map(|law| std::sync::Arc::new(law) as std::sync::Arc<dyn ConstitutiveLaw>)
    }
}

impl ConstitutiveLaw for VonMises {
    fn elasticity(&self, _state: &MaterialState) -> Option<Elastic> {
        Some(self.elastic)
    }

    /// Softening (H < 0) makes the algorithmic tangent negative in the flow direction.
    fn can_soften(&self) -> bool {
        self.hardening < 0.0
    }

    fn as_strength_reducible(&self) -> Option<&dyn StrengthReducible> {
        Some(self)
    }

    fn name(&self) -> &'static str {
        "von-mises"
    }

    fn history_len(&self) -> usize {
        1
    }

    fn history_names(&self) -> &'static [&'static str] {
        &["equivalent_plastic_strain"]
    }

    fn plastic_strain(&self, h: &[f64]) -> f64 {
        h[0]
    }

    /// q = √(3/2 s:s) at σ_y(ε̄p) within 1e-6 σ_y.
    fn is_yielding(&self, stress: &Matrix3<f64>, h: &[f64]) -> bool {
        let s = stress - Matrix3::identity() * (stress.trace() / 3.0);
        let sy = self.current_yield_stress(h[0]);
        (1.5f64).sqrt() * s.norm() >= sy - 1e-6 * sy.max(self.yield_stress)
    }

    fn update(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<StressUpdate, ConstitutiveError> {
        self.update_with_region(eps_trial, h_n, h_out).map(|(u, _)| u)
    }

    /// [`VonMises::update_with_region`]'s stress and elastic strain without the consistent
    /// tangent (two 9 × 9 tensors built and summed), which an explicit step has no use for.
    fn update_stress(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<(Matrix3<f64>, Matrix3<f64>), ConstitutiveError> {
        let (r, _) = self.returned(eps_trial, h_n, h_out)?;
        Ok((r.stress, r.elastic_strain))
    }

    fn p_wave_modulus(&self, _state: &MaterialState) -> f64 {
        self.elastic.p_wave_modulus()
    }

    fn stored_energy(&self, elastic_strain: &Matrix3<f64>) -> f64 {
        self.elastic.stored_energy(elastic_strain)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::central_difference;

    fn law() -> VonMises {
        VonMises::new(Elastic::new(2.0e4, 0.3).unwrap(), 30.0, 0.0).unwrap()
    }

    /// Central differences of the stress along the six symmetric unit directions. The
    /// step is relative to the strain (1e-6 ‖ε‖): truncation ~(1e-6)² and round-off
    /// ~1e-16/1e-6 of the tangent, both far below the 1e-6 tolerance of the tangent checks (docs/theory.md §16).
    fn fd_tangent(law: &VonMises, eps: &Matrix3<f64>, h_n: &[f64]) -> Tensor4 {
        central_difference(|e| law.update(e, h_n, &mut [0.0]).unwrap().stress, eps, 1e-6 * eps.norm())
    }

    fn q_of(s: &Matrix3<f64>) -> f64 {
        let dev = s - Matrix3::identity() * (s.trace() / 3.0);
        (1.5f64).sqrt() * dev.norm()
    }

    #[test]
    fn rejects_bad_parameters() {
        let el = Elastic::new(2.0e4, 0.3).unwrap();
        let g = el.lame().1;
        assert!(VonMises::new(el, 0.0, 0.0).is_err());
        assert!(VonMises::new(el, -1.0, 0.0).is_err());
        assert!(VonMises::new(el, f64::NAN, 0.0).is_err());
        assert!(VonMises::new(el, 1.0, f64::INFINITY).is_err());
        assert!(VonMises::new(el, 1.0, -3.0 * g).is_err());
        assert!(VonMises::new(el, 1.0, -2.9 * g).is_ok());
        let l = VonMises::new(el, 1.0, -10.0).unwrap();
        assert!(l.with_residual_yield_stress(-0.1).is_err());
        assert!(l.with_residual_yield_stress(1.1).is_err());
        assert!(l.with_residual_yield_stress(0.4).is_ok());
        assert!(matches!(
            VonMises::new(el, 1.0, f64::NAN),
            Err(ConstitutiveError::InvalidParameter { name: "hardening", .. })
        ));
    }

    #[test]
    fn elastic_trial_unchanged() {
        let l = law();
        let eps = Matrix3::new(2e-4, 1e-4, 0.0, 1e-4, -1e-4, 5e-5, 0.0, 5e-5, 3e-4);
        let (up, region) = l.update_with_region(&eps, &[0.01], &mut [0.0]).unwrap();
        assert_eq!(region, VonMisesRegion::Elastic);
        // Exactly the elastic law's own arithmetic.
        assert_eq!(up.stress, l.elastic.stress(&eps));
        assert_eq!(up.tangent, l.elastic.stiffness());
        assert_eq!(up.elastic_strain, eps);
    }

    #[test]
    fn return_lands_on_surface_and_tangent_matches_fd() {
        let eps = Matrix3::new(3e-3, 1e-3, -5e-4, 1e-3, -1e-3, 7e-4, -5e-4, 7e-4, 5e-4);
        let el = Elastic::new(2.0e4, 0.3).unwrap();
        for (h, res, eqps_n, expect) in [
            (0.0, 0.0, 0.0, VonMisesRegion::Plastic),
            (500.0, 0.0, 0.02, VonMisesRegion::Plastic),
            (-800.0, 0.0, 0.0, VonMisesRegion::Plastic),
            // Softening that crosses the floor during the step: q_tr ≈ 64.3, the sloped
            // return would give Δγ = 34.3/(3G + H) ≈ 1.9e-3 > (30 − 25)/5000 = 1e-3.
            (-5000.0, 25.0, 0.0, VonMisesRegion::Residual),
            // The same softening, staying on the slope (Δγ ≈ 1.6e-3 < 5/2000).
            (-2000.0, 25.0, 0.0, VonMisesRegion::Plastic),
            // Already on the floor.
            (-2000.0, 25.0, 0.01, VonMisesRegion::Residual),
        ] {
            let l = VonMises::new(el, 30.0, h).unwrap().with_residual_yield_stress(res).unwrap();
            let mut h_out = [0.0];
            let (up, region) = l.update_with_region(&eps, &[eqps_n], &mut h_out).unwrap();
            assert_eq!(region, expect, "H {h}");
            // Consistency: q = σ_y(ε̄p_{n+1}) up to round-off (1e-12 relative, closed form).
            let sy = l.current_yield_stress(h_out[0]);
            assert!((q_of(&up.stress) - sy).abs() < 1e-12 * sy, "H {h}");
            // σ = C:ε^e.
            assert!((l.elastic.stress(&up.elastic_strain) - up.stress).norm() < 1e-12 * up.stress.norm());
            let fd = fd_tangent(&l, &eps, &[eqps_n]);
            let r = (up.tangent - fd).norm() / up.tangent.norm();
            // Brief: relative difference ≤ 1e-6.
            assert!(r < 1e-6, "H {h}: rel {r}");
            // Associated flow: symmetric tangent (round-off only).
            assert!((up.tangent - up.tangent.transpose()).norm() < 1e-12 * up.tangent.norm());
        }
    }

    #[test]
    fn stored_energy_delegates() {
        let l = law();
        let e = Matrix3::new(1e-3, 0.0, 2e-4, 0.0, -3e-4, 0.0, 2e-4, 0.0, 5e-4);
        assert_eq!(l.stored_energy(&e), l.elastic.stored_energy(&e));
        assert_eq!(l.p_wave_modulus(&MaterialState::at_rest(&[0.0])), l.elastic.p_wave_modulus());
    }

    #[test]
    fn bad_input_is_an_error() {
        let l = law();
        let mut e = Matrix3::zeros();
        assert!(matches!(l.update(&e, &[], &mut [0.0]), Err(ConstitutiveError::HistoryLength { .. })));
        assert!(l.update(&e, &[f64::NAN], &mut [0.0]).is_err());
        e[(1, 2)] = f64::NAN;
        assert!(l.update(&e, &[0.0], &mut [0.0]).is_err());
        // Finite but overflowing strain: an error, not an infinite stress.
        let huge = Matrix3::from_diagonal(&nalgebra::Vector3::new(1e305, -1e305, 0.0));
        assert!(l.update(&huge, &[0.0], &mut [0.0]).is_err());
    }
}
