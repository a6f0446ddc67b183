//! Drucker–Prager plasticity: a smooth cone fitted to Mohr–Coulomb, with non-associated
//! flow and the linear softening of c, φ, ψ that [`MohrCoulomb`](crate::MohrCoulomb) has
//! (docs/theory.md §16; de Souza Neto, Perić & Owen 2008, §8.3.3 and Box 8.6).
//!
//! # Yield function and potential
//! Tension positive, p = tr σ / 3, J₂ = ½ s : s:
//!
//! ```text
//! f = √J₂ + η p − ξ c,   g = √J₂ + η̄ p
//! ```
//!
//! with η, ξ from φ and η̄ from ψ by the chosen [`ConeFit`]:
//!
//! | fit | η | ξ | η̄ |
//! |---|---|---|---|
//! | `PlaneStrain` | √3 sin φ √(3 + sin²ψ) / (3 + sin φ sin ψ) | η cot φ | √3 sin ψ / √(3 + sin²ψ) |
//! | `Compression` | 6 sin φ / (√3 (3 − sin φ)) | 6 cos φ / (√3 (3 − sin φ)) | 6 sin ψ / (√3 (3 − sin ψ)) |
//! | `Extension` | 6 sin φ / (√3 (3 + sin φ)) | 6 cos φ / (√3 (3 + sin φ)) | 6 sin ψ / (√3 (3 + sin ψ)) |
//!
//! `Compression` and `Extension` pass through Mohr–Coulomb's triaxial-compression and
//! -extension meridians. `PlaneStrain` gives Mohr–Coulomb's collapse stresses in plane
//! strain with the same dilation (the out-of-plane plastic strain rate zero, ε̇ᵖ_v / γ̇ᵖ =
//! sin ψ); for ψ = φ it is the cone inscribed in the Mohr–Coulomb pyramid, for ψ = 0 it is
//! η = sin φ, ξ = cos φ (the derivation is in docs/theory.md §16). In every fit ξ/η = cot φ:
//! the apex is Mohr–Coulomb's, σ = c cot φ I.
//!
//! # Return
//! The cone: s = s_tr (1 − GΔγ/√J₂_tr), p = p_tr − K η̄ Δγ, and Δγ solves
//! r(Δγ) = √J₂_tr − GΔγ + η (p_tr − K η̄ Δγ) − ξ c = 0, with η, ξ, η̄, c at
//! κ = κ_n + Δγ/√3 (κ̇ = √(2/3) ‖ė^p‖, the measure Mohr–Coulomb softens with): in one step
//! without softening, by Newton on the scalar r with it. Where the cone return would take
//! √J₂ below zero (√J₂_tr < GΔγ) the stress returns to the apex, with
//! κ = κ_n + √(2/3) ‖dev ε_tr‖ (the deviatoric trial strain is all plastic there). φ = 0 is
//! a von Mises cylinder of √J₂ = ξ c and has no apex. Softening is solved on the softening
//! branch and redone on the residual one when κ ends beyond κ_res, as in Mohr–Coulomb.
//!
//! # Tangent
//! On the cone, with N̂ = s_tr/‖s_tr‖, j = √J₂_tr, A = −1/r′(Δγ) and
//! η̄* = η̄ + Δγ η̄′(κ)/√3:
//!
//! ```text
//! D = 2G (1 − GΔγ/j) I_d + 2G² (Δγ/j − A) N̂⊗N̂ − √2 G K A (η N̂⊗I + η̄* I⊗N̂) + K (1 − K η η̄* A) I⊗I
//! ```
//!
//! (de Souza Neto et al. 2008, §8.3.3, extended here to κ-dependent η, ξ, η̄, c). At the apex
//! σ depends on ε_tr only through κ: D = I ⊗ (d(c cot φ)/dκ √(2/3) ŵ), ŵ the unit
//! deviatoric trial strain — zero without softening.
//!
//! History slots: `[0]` κ, `[1]` the accumulated volumetric plastic strain (informative).

use nalgebra::Matrix3;

use crate::frictional::{frictional_inputs, Branch, FrictionalStrength};
use crate::tensor::{flatten, identity_dyad, sym_identity, Tensor4};
use crate::{
    check_finite, ConstitutiveError, ConstitutiveLaw, Elastic, MaterialState, Softening, StrengthReducible,
    StressUpdate, SQRT_2_3,
};

/// How a Drucker–Prager cone is fitted to Mohr–Coulomb (the table in the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ConeFit {
    /// Mohr–Coulomb's collapse stresses in plane strain. For associated flow it is the
    /// cone inscribed in the pyramid, never stronger in 3D; for ψ < φ it is wider (at
    /// ψ = 0, η = sin φ) and can be stronger than Mohr–Coulomb near its edges in 3D.
    PlaneStrain,
    /// Through the triaxial-compression meridian (circumscribes the pyramid).
    Compression,
    /// Through the triaxial-extension meridian.
    Extension,
}

/// Where a Drucker–Prager update ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DruckerPragerRegion {
    Elastic,
    /// On the cone.
    Cone,
    /// At the apex σ = c cot φ I.
    Apex,
}

/// Drucker–Prager with a cone fitted to Mohr–Coulomb and optional linear softening (see
/// the module documentation). History: κ, accumulated volumetric plastic strain.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DruckerPrager {
    elastic: Elastic,
    strength: FrictionalStrength,
    fit: ConeFit,
}

/// The cone at some κ on a branch: η, ξ, η̄, c, and their κ-derivatives.
#[derive(Debug, Clone, Copy)]
struct Cone {
    eta: f64,
    xi: f64,
    etabar: f64,
    c: f64,
    deta: f64,
    dxi: f64,
    detabar: f64,
    dc: f64,
}

impl Cone {
    /// ξ c and its κ-derivative.
    fn strength(&self) -> (f64, f64) {
        (self.xi * self.c, self.dxi * self.c + self.xi * self.dc)
    }
}

/// Elastic trial states with f ≤ ELASTIC_TOL·scale are returned unchanged.
const ELASTIC_TOL: f64 = 1e-12;
/// Newton tolerance of the scalar return (relative to the stress scale).
const NEWTON_TOL: f64 = 1e-13;
const MAX_ITERATIONS: usize = 50;

/// √3.
const SQRT3: f64 = 1.732_050_807_568_877_2;

impl ConeFit {
    /// (η, ξ, η̄) at φ, ψ and the derivatives (∂η/∂φ, ∂η/∂ψ, ∂ξ/∂φ, ∂ξ/∂ψ, ∂η̄/∂ψ).
    fn coefficients(self, phi: f64, psi: f64) -> ([f64; 3], [f64; 5]) {
        let (sf, cf, sp, cp) = (phi.sin(), phi.cos(), psi.sin(), psi.cos());
        match self {
            ConeFit::PlaneStrain => {
                let root = (3.0 + sp * sp).sqrt();
                let den = 3.0 + sf * sp;
                let (eta, xi) = (SQRT3 * sf * root / den, SQRT3 * cf * root / den);
                let etabar = SQRT3 * sp / root;
                let d2 = den * den;
                let deta_dphi = 3.0 * SQRT3 * cf * root / d2;
                let dxi_dphi = -SQRT3 * root * (3.0 * sf + sp) / d2;
                let common = 3.0 * SQRT3 * cp * (sp - sf) / (root * d2);
                let detabar = 3.0 * SQRT3 * cp / (root * root * root);
                ([eta, xi, etabar], [deta_dphi, sf * common, dxi_dphi, cf * common, detabar])
            }
            ConeFit::Compression | ConeFit::Extension => {
                let s = if self == ConeFit::Compression { -1.0 } else { 1.0 };
                let k = 2.0 * SQRT3;
                let (df, dp) = (3.0 + s * sf, 3.0 + s * sp);
                let (eta, xi, etabar) = (k * sf / df, k * cf / df, k * sp / dp);
                let deta_dphi = 3.0 * k * cf / (df * df);
                let dxi_dphi = -k * (3.0 * sf + s) / (df * df);
                let detabar = 3.0 * k * cp / (dp * dp);
                ([eta, xi, etabar], [deta_dphi, 0.0, dxi_dphi, 0.0, detabar])
            }
        }
    }
}

impl DruckerPrager {
    /// Angles in degrees. Validates the elastic constants, c ≥ 0, 0 ≤ φ < 90°, 0 ≤ ψ ≤ φ,
    /// and c > 0 where φ = 0 (a cylinder of no size).
    pub fn from_degrees(
        elastic: Elastic,
        cohesion: f64,
        friction_deg: f64,
        dilation_deg: f64,
        fit: ConeFit,
    ) -> Result<Self, ConstitutiveError> {
        let strength = FrictionalStrength {
            cohesion,
            friction: friction_deg.to_radians(),
            dilation: dilation_deg.to_radians(),
            softening: None,
        };
        let law = Self { elastic, strength, fit };
        law.validate()?;
        Ok(law)
    }

    /// Linear softening to residual values (angles in degrees) at κ = κ_res > 0, as
    /// [`MohrCoulomb::with_softening`](crate::MohrCoulomb::with_softening).
    pub fn with_softening(
        mut self,
        cohesion_res: f64,
        friction_res_deg: f64,
        dilation_res_deg: f64,
        kappa_res: f64,
    ) -> Result<Self, ConstitutiveError> {
        self.strength.softening = Some(Softening {
            cohesion: cohesion_res,
            friction: friction_res_deg.to_radians(),
            dilation: dilation_res_deg.to_radians(),
            kappa: kappa_res,
        });
        self.validate()?;
        Ok(self)
    }

    fn validate(&self) -> Result<(), ConstitutiveError> {
        Elastic::new(self.elastic.young, self.elastic.poisson)?;
        self.strength.validate_peak()?;
        if self.strength.friction == 0.0 && self.strength.cohesion <= 0.0 {
            return Err(ConstitutiveError::InvalidParameter { name: "cohesion", value: self.strength.cohesion });
        }
        self.strength.validate_softening()
    }

    /// The elastic part.
    pub fn elastic(&self) -> Elastic {
        self.elastic
    }

    /// How the cone is fitted.
    pub fn fit(&self) -> ConeFit {
        self.fit
    }

    /// (c, φ, ψ) at accumulated plastic strain κ (angles in radians).
    pub fn strength(&self, kappa: f64) -> (f64, f64, f64) {
        self.strength.at(kappa)
    }

    /// (η, ξ, η̄) of the cone at accumulated plastic strain κ.
    pub fn cone(&self, kappa: f64) -> (f64, f64, f64) {
        let c = self.cone_on(kappa, self.strength.branch_at(kappa));
        (c.eta, c.xi, c.etabar)
    }

    fn cone_on(&self, kappa: f64, branch: Branch) -> Cone {
        let s = self.strength.on_branch(kappa, branch);
        let ([eta, xi, etabar], [de_f, de_p, dx_f, dx_p, db_p]) = self.fit.coefficients(s.phi, s.psi);
        Cone {
            eta,
            xi,
            etabar,
            c: s.c,
            deta: de_f * s.dphi + de_p * s.dpsi,
            dxi: dx_f * s.dphi + dx_p * s.dpsi,
            detabar: db_p * s.dpsi,
            dc: s.dc,
        }
    }

    /// f = √J₂ + η p − ξ c of `stress` at accumulated plastic strain κ.
    pub fn yield_function(&self, stress: &Matrix3<f64>, kappa: f64) -> f64 {
        let cone = self.cone_on(kappa, self.strength.branch_at(kappa));
        let p = stress.trace() / 3.0;
        let s = stress - Matrix3::identity() * p;
        (0.5 * s.norm_squared()).sqrt() + cone.eta * p - cone.xi * cone.c
    }

    /// The stress update with the region it ended in.
    pub fn update_with_region(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<(StressUpdate, DruckerPragerRegion), ConstitutiveError> {
        let (r, region) = self.returned(eps_trial, h_n, h_out)?;
        let tangent = match &r.flow {
            None => self.elastic.stiffness(),
            Some(flow) => flow.tangent(),
        };
        if !tangent.iter().all(|v| v.is_finite()) {
            return Err(ConstitutiveError::NonFinite { what: "Drucker-Prager tangent" });
        }
        Ok((StressUpdate { stress: r.stress, elastic_strain: r.elastic_strain, tangent }, region))
    }

    /// The stress, elastic strain and history of an update, with what its tangent needs.
    fn returned(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<(Returned, DruckerPragerRegion), ConstitutiveError> {
        let (kappa_n, evp_n) = frictional_inputs(eps_trial, h_n, h_out, "Drucker-Prager history")?;
        let tr = self.trial(eps_trial, kappa_n)?;
        let cone_n = self.cone_on(kappa_n, self.strength.branch_at(kappa_n));
        let f_tr = tr.j + cone_n.eta * tr.p - cone_n.strength().0;
        if f_tr <= ELASTIC_TOL * tr.scale {
            h_out[0] = kappa_n;
            h_out[1] = evp_n;
            // Exactly the elastic law's update of the input (not of its symmetrised copy).
            let r = Returned { stress: self.elastic.stress(eps_trial), elastic_strain: *eps_trial, flow: None };
            return Ok((r, DruckerPragerRegion::Elastic));
        }
        let on_cone = self.strength.on_branches(kappa_n, |c: &ConeReturn| c.kappa, |b| self.cone_return(&tr, b))?;
        let (r, deps_v, kappa, region) = match on_cone {
            Some(c) if tr.j - tr.g * c.dgamma >= 0.0 => self.on_cone(&tr, &c),
            _ => self.at_apex(&tr)?,
        };
        check_finite(&r.stress, "Drucker-Prager stress")?;
        h_out[0] = kappa;
        h_out[1] = evp_n + deps_v;
        Ok((r, region))
    }

    /// The trial state: symmetrised strain, s_tr, p_tr, j = √J₂_tr, the moduli and scale.
    fn trial(&self, eps_trial: &Matrix3<f64>, kappa_n: f64) -> Result<Trial, ConstitutiveError> {
        let eps = (eps_trial + eps_trial.transpose()) * 0.5;
        let (lambda, g) = self.elastic.lame();
        let k = lambda + 2.0 * g / 3.0;
        let vol = eps.trace();
        let dev = eps - Matrix3::identity() * (vol / 3.0);
        let s = dev * (2.0 * g);
        let (j, p) = ((0.5 * s.norm_squared()).sqrt(), k * vol);
        if !(j.is_finite() && p.is_finite()) {
            return Err(ConstitutiveError::NonFinite { what: "Drucker-Prager trial stress" });
        }
        let scale = j.max(p.abs()).max(self.strength.cohesion).max(f64::MIN_POSITIVE);
        Ok(Trial { eps, dev, s, j, p, g, k, kappa_n, scale })
    }

    /// The return to the cone on `branch`: Δγ from r(Δγ) = 0 (one Newton step without
    /// softening, Newton otherwise), Δγ ≥ 0. `Ok(None)` where Newton meets a flat residual.
    fn cone_return(&self, tr: &Trial, branch: Branch) -> Result<Option<ConeReturn>, ConstitutiveError> {
        let mut dgamma = 0.0f64;
        let mut last = f64::NAN;
        for _ in 0..MAX_ITERATIONS {
            let kappa = tr.kappa_n + dgamma / SQRT3;
            let cone = self.cone_on(kappa, branch);
            let (xc, dxc) = cone.strength();
            let p = tr.p - tr.k * cone.etabar * dgamma;
            let r = tr.j - tr.g * dgamma + cone.eta * p - xc;
            let dr = -tr.g - tr.k * cone.eta * cone.etabar
                + (cone.deta * p - cone.eta * tr.k * cone.detabar * dgamma - dxc) / SQRT3;
            if !(r.is_finite() && dr.is_finite()) || dr >= 0.0 {
                return Ok(None);
            }
            last = r / tr.scale;
            if r.abs() <= NEWTON_TOL * tr.scale && dgamma > 0.0 {
                return Ok(Some(ConeReturn { dgamma, kappa, cone, slope: dr }));
            }
            dgamma = (dgamma - r / dr).max(0.0);
        }
        Err(ConstitutiveError::ReturnMappingFailed {
            law: "drucker-prager",
            iterations: MAX_ITERATIONS,
            residual: last,
        })
    }

    /// The state after a return to the cone.
    fn on_cone(&self, tr: &Trial, c: &ConeReturn) -> (Returned, f64, f64, DruckerPragerRegion) {
        let Cone { eta, etabar, detabar, .. } = c.cone;
        let factor = 1.0 - tr.g * c.dgamma / tr.j;
        let p = tr.p - tr.k * etabar * c.dgamma;
        let stress = tr.s * factor + Matrix3::identity() * p;
        // Δε^p = Δγ (N̂/√2 + η̄/3 I), N̂ = s_tr/‖s_tr‖ = s_tr/(√2 j).
        let n_hat = tr.s / (std::f64::consts::SQRT_2 * tr.j);
        let deps_p = n_hat * (c.dgamma / std::f64::consts::SQRT_2) + Matrix3::identity() * (c.dgamma * etabar / 3.0);
        let flow = Flow::Cone {
            g: tr.g,
            k: tr.k,
            factor,
            n_hat,
            dgamma: c.dgamma,
            j: tr.j,
            a: -1.0 / c.slope,
            eta,
            etabar_star: etabar + c.dgamma * detabar / SQRT3,
        };
        let r = Returned { stress, elastic_strain: tr.eps - deps_p, flow: Some(flow) };
        (r, c.dgamma * etabar, c.kappa, DruckerPragerRegion::Cone)
    }

    /// The return to the apex σ = c cot φ I, κ = κ_n + √(2/3) ‖dev ε_tr‖; an error where φ
    /// is zero there (no apex: not reached from a cone return that failed).
    fn at_apex(&self, tr: &Trial) -> Result<(Returned, f64, f64, DruckerPragerRegion), ConstitutiveError> {
        let nd = tr.dev.norm();
        // The zero subgradient of ‖dev ε_tr‖ for a (round-off) hydrostatic trial.
        let w_hat = if nd > 1e-14 * tr.eps.norm() { tr.dev / nd } else { Matrix3::zeros() };
        let kappa = tr.kappa_n + SQRT_2_3 * nd;
        let s = self.strength.on_branch(kappa, self.strength.branch_at(kappa));
        let (sf, cf) = (s.phi.sin(), s.phi.cos());
        if sf <= 0.0 {
            return Err(ConstitutiveError::ReturnMappingFailed {
                law: "drucker-prager",
                iterations: 0,
                residual: f64::NAN,
            });
        }
        let pa = s.c * cf / sf;
        // d(c cot φ)/dκ = c' cot φ − c φ'/sin²φ.
        let dpa = s.dc * cf / sf - s.c * s.dphi / (sf * sf);
        let stress = Matrix3::identity() * pa;
        let elastic_strain = Matrix3::identity() * (pa / (3.0 * tr.k));
        let deps_v = (tr.p - pa) / tr.k;
        let flow = Flow::Apex { slope: w_hat * (dpa * SQRT_2_3) };
        Ok((Returned { stress, elastic_strain, flow: Some(flow) }, deps_v, kappa, DruckerPragerRegion::Apex))
    }
}

/// The trial state of an update.
struct Trial {
    eps: Matrix3<f64>,
    dev: Matrix3<f64>,
    s: Matrix3<f64>,
    j: f64,
    p: f64,
    g: f64,
    k: f64,
    kappa_n: f64,
    scale: f64,
}

/// A converged return to the cone: Δγ, κ, the cone there and r′(Δγ).
#[derive(Debug, Clone, Copy)]
struct ConeReturn {
    dgamma: f64,
    kappa: f64,
    cone: Cone,
    slope: f64,
}

/// An update's stress and elastic strain, and its return where it flowed.
struct Returned {
    stress: Matrix3<f64>,
    elastic_strain: Matrix3<f64>,
    flow: Option<Flow>,
}

/// What the consistent tangent of a return needs (the module docs' formulas).
enum Flow {
    Cone {
        g: f64,
        k: f64,
        factor: f64,
        n_hat: Matrix3<f64>,
        dgamma: f64,
        j: f64,
        a: f64,
        eta: f64,
        etabar_star: f64,
    },
    /// ∂σ/∂ε_tr = I ⊗ `slope`.
    Apex {
        slope: Matrix3<f64>,
    },
}

impl Flow {
    fn tangent(&self) -> Tensor4 {
        match *self {
            Flow::Cone { g, k, factor, n_hat, dgamma, j, a, eta, etabar_star } => {
                let i_dyad = identity_dyad();
                let i_dev = sym_identity() - i_dyad / 3.0;
                let (nf, i) = (flatten(&n_hat), flatten(&Matrix3::identity()));
                let coupling = std::f64::consts::SQRT_2 * g * k * a;
                i_dev * (2.0 * g * factor) + nf * nf.transpose() * (2.0 * g * g * (dgamma / j - a))
                    - (nf * i.transpose() * eta + i * nf.transpose() * etabar_star) * coupling
                    + i_dyad * (k * (1.0 - k * eta * etabar_star * a))
            }
            Flow::Apex { slope } => flatten(&Matrix3::identity()) * flatten(&slope).transpose(),
        }
    }
}

impl StrengthReducible for DruckerPrager {
    /// c/F, φ_F = atan(tan φ / F), ψ_F = min(ψ, φ_F) and the residual values alike (as
    /// Mohr–Coulomb), the cone refitted to the reduced angles.
    fn with_strength_reduced(&self, factor: f64) -> Result<std::sync::Arc<dyn ConstitutiveLaw>, ConstitutiveError> {
        let law = Self { elastic: self.elastic, strength: self.strength.reduced(factor)?, fit: self.fit };
        law.validate().map(|()| std::sync::Arc::new(law) as std::sync::Arc<dyn ConstitutiveLaw>)
    }
}

impl ConstitutiveLaw for DruckerPrager {
    fn elasticity(&self, _state: &MaterialState) -> Option<Elastic> {
        Some(self.elastic)
    }

    fn as_strength_reducible(&self) -> Option<&dyn StrengthReducible> {
        Some(self)
    }

    fn name(&self) -> &'static str {
        "drucker-prager"
    }

    fn history_len(&self) -> usize {
        2
    }

    fn history_names(&self) -> &'static [&'static str] {
        &["plastic_shear_strain", "plastic_volumetric_strain"]
    }

    fn plastic_strain(&self, h: &[f64]) -> f64 {
        h[0]
    }

    /// f within 1e-6 of the strength scale max(c, |σ|) of zero.
    fn is_yielding(&self, stress: &Matrix3<f64>, h: &[f64]) -> bool {
        let tol = 1e-6 * self.strength(h[0]).0.max(stress.norm());
        self.yield_function(stress, h[0]) >= -tol
    }

    /// Symmetric for associated flow (ψ = φ, so η̄ = η) without softening.
    fn symmetric_tangent(&self) -> bool {
        self.strength.dilation == self.strength.friction && !self.strength.softens()
    }

    fn can_soften(&self) -> bool {
        self.strength.softens()
    }

    fn update(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<StressUpdate, ConstitutiveError> {
        self.update_with_region(eps_trial, h_n, h_out).map(|(u, _)| u)
    }

    /// The stress and elastic strain without the consistent tangent (an explicit step has
    /// no use for it).
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
    use nalgebra::Vector3;

    fn el() -> Elastic {
        Elastic::new(1.0e4, 0.3).unwrap()
    }

    const FITS: [ConeFit; 3] = [ConeFit::PlaneStrain, ConeFit::Compression, ConeFit::Extension];

    /// The closed-form derivatives of η, ξ, η̄ against central differences (step 1e-6 rad:
    /// truncation ~1e-12, round-off ~1e-10, against a tolerance of 1e-8).
    #[test]
    fn cone_coefficient_derivatives_match_differences() {
        let h = 1e-6;
        for fit in FITS {
            for (phi, psi) in [(0.5, 0.2), (0.3, 0.3), (0.9, 0.0), (0.0, 0.0)] {
                let (_, d) = fit.coefficients(phi, psi);
                let at = |f: f64, p: f64| fit.coefficients(f, p).0;
                let (fp, fm, pp, pm) = (at(phi + h, psi), at(phi - h, psi), at(phi, psi + h), at(phi, psi - h));
                let fd = [
                    (fp[0] - fm[0]) / (2.0 * h),
                    (pp[0] - pm[0]) / (2.0 * h),
                    (fp[1] - fm[1]) / (2.0 * h),
                    (pp[1] - pm[1]) / (2.0 * h),
                    (pp[2] - pm[2]) / (2.0 * h),
                ];
                for (a, b) in d.iter().zip(fd) {
                    assert!((a - b).abs() <= 1e-8 * (1.0 + b.abs()), "{fit:?} φ {phi} ψ {psi}: {a} vs {b}");
                }
                // η̄ does not depend on φ.
                assert!(((fp[2] - fm[2]) / (2.0 * h)).abs() < 1e-9);
            }
        }
    }

    /// The compression and extension cones pass through Mohr–Coulomb's meridians: a stress
    /// on Mohr–Coulomb's triaxial compression (σ₁ = σ₂ > σ₃) or extension (σ₁ > σ₂ = σ₃)
    /// meridian is on the cone (f = 0 to round-off), and every cone's apex is c cot φ.
    #[test]
    fn compression_and_extension_cones_meet_mohr_coulomb_meridians() {
        let (c, phi) = (10.0f64, 30f64.to_radians());
        let (sf, cf) = (phi.sin(), phi.cos());
        for (fit, ext) in [(ConeFit::Compression, false), (ConeFit::Extension, true)] {
            let law = DruckerPrager::from_degrees(el(), c, 30.0, 10.0, fit).unwrap();
            for s1 in [-50.0, -10.0, 5.0] {
                // MC: (1 + sin φ) σ₁ − (1 − sin φ) σ₃ = 2c cos φ.
                let s3 = ((1.0 + sf) * s1 - 2.0 * c * cf) / (1.0 - sf);
                let sig = if ext { Vector3::new(s1, s3, s3) } else { Vector3::new(s1, s1, s3) };
                let f = law.yield_function(&Matrix3::from_diagonal(&sig), 0.0);
                assert!(f.abs() < 1e-12 * sig.amax(), "{fit:?}: f = {f}");
            }
            let apex = Matrix3::identity() * (c * cf / sf);
            assert!(law.yield_function(&apex, 0.0).abs() < 1e-12 * c);
        }
    }

    /// Plane strain, driven to steady plastic flow (a biaxial test: σ_xx held at −p₀ by a
    /// Newton iteration on ε_xx with the consistent tangent, ε_yy shortened, ε_zz = 0): the
    /// plane-strain cone's in-plane stresses reach Mohr–Coulomb's collapse condition
    /// (σ₁ − σ₃) + (σ₁ + σ₃) sin φ = 2c cos φ, whatever ψ (the fit's derivation,
    /// docs/theory.md §16), to 1e-7 of c after 20 % axial strain (the approach to steady
    /// flow decays exponentially with plastic strain).
    #[test]
    fn plane_strain_cone_collapses_at_mohr_coulomb_stresses() {
        let (c, p0) = (10.0, 40.0);
        for (phi, psi) in [(30.0f64, 30.0), (30.0, 0.0), (20.0, 8.0), (0.0, 0.0)] {
            let law = DruckerPrager::from_degrees(el(), c, phi, psi, ConeFit::PlaneStrain).unwrap();
            let (lambda, g) = el().lame();
            // Start at σ = −p₀ I (elastic strain), then compress along y.
            let e0 = -p0 / (3.0 * lambda + 2.0 * g);
            let mut ee = Matrix3::identity() * e0;
            let mut h = [0.0, 0.0];
            let mut stress = Matrix3::zeros();
            for _ in 0..400 {
                let mut dexx = 0.0;
                for _ in 0..20 {
                    let d = Matrix3::from_diagonal(&Vector3::new(dexx, -5e-4, 0.0));
                    let mut h_out = [0.0, 0.0];
                    let up = law.update(&(ee + d), &h, &mut h_out).unwrap();
                    let r = up.stress[(0, 0)] + p0;
                    if r.abs() < 1e-12 * p0 {
                        stress = up.stress;
                        ee = up.elastic_strain;
                        h = h_out;
                        break;
                    }
                    dexx -= r / up.tangent[(0, 0)];
                }
            }
            let (sf, cf) = (phi.to_radians().sin(), phi.to_radians().cos());
            let (s1, s3) = (stress[(0, 0)], stress[(1, 1)]);
            let mc = (s1 - s3) + (s1 + s3) * sf - 2.0 * c * cf;
            assert!(mc.abs() < 1e-7 * c, "φ {phi} ψ {psi}: MC residual {mc}, σ {stress}");
            assert!(stress[(2, 2)] <= s1 && stress[(2, 2)] >= s3, "σ_zz intermediate");
        }
    }

    #[test]
    fn elastic_trial_unchanged_and_bad_input_refused() {
        let law = DruckerPrager::from_degrees(el(), 10.0, 30.0, 0.0, ConeFit::PlaneStrain).unwrap();
        let eps = Matrix3::new(-2e-4, 1e-5, 0.0, 1e-5, -1e-4, 0.0, 0.0, 0.0, -1e-4);
        let (up, region) = law.update_with_region(&eps, &[0.0, 0.0], &mut [0.0, 0.0]).unwrap();
        assert_eq!(region, DruckerPragerRegion::Elastic);
        assert_eq!(up.stress, law.elastic.stress(&eps));
        assert_eq!(up.tangent, law.elastic.stiffness());
        assert!(matches!(law.update(&eps, &[0.0], &mut [0.0, 0.0]), Err(ConstitutiveError::HistoryLength { .. })));
        assert!(law.update(&eps, &[f64::NAN, 0.0], &mut [0.0, 0.0]).is_err());
        let name = |r: Result<DruckerPrager, ConstitutiveError>| match r {
            Err(ConstitutiveError::InvalidParameter { name, .. }) => name,
            other => panic!("{other:?}"),
        };
        let fit = ConeFit::PlaneStrain;
        assert_eq!(name(DruckerPrager::from_degrees(el(), -1.0, 30.0, 0.0, fit)), "cohesion");
        assert_eq!(name(DruckerPrager::from_degrees(el(), 0.0, 0.0, 0.0, fit)), "cohesion");
        assert_eq!(name(DruckerPrager::from_degrees(el(), 1.0, 90.0, 0.0, fit)), "friction");
        assert_eq!(name(DruckerPrager::from_degrees(el(), 1.0, 30.0, 31.0, fit)), "dilation");
        assert_eq!(name(law.with_softening(11.0, 30.0, 0.0, 0.1)), "residual cohesion");
        assert_eq!(name(law.with_softening(1.0, 30.0, 0.0, 0.0)), "kappa_res");
    }

    /// A trial stress far beyond the apex returns to c cot φ I with a zero tangent (no
    /// softening) and κ from the deviatoric trial strain.
    #[test]
    fn apex_return() {
        let law = DruckerPrager::from_degrees(el(), 10.0, 30.0, 10.0, ConeFit::Compression).unwrap();
        let eps = Matrix3::new(1e-2, 1e-4, 0.0, 1e-4, 1.2e-2, 0.0, 0.0, 0.0, 1.1e-2);
        let mut h = [0.0, 0.0];
        let (up, region) = law.update_with_region(&eps, &[0.0, 0.0], &mut h).unwrap();
        assert_eq!(region, DruckerPragerRegion::Apex);
        let apex = 10.0 / 30f64.to_radians().tan();
        assert!((up.stress - Matrix3::identity() * apex).norm() < 1e-12 * apex);
        assert_eq!(up.tangent.norm(), 0.0);
        let dev = eps - Matrix3::identity() * (eps.trace() / 3.0);
        assert!((h[0] - SQRT_2_3 * dev.norm()).abs() < 1e-15);
    }

    /// Reduction by F divides c and tan φ and refits the cone; ψ is capped at φ_F.
    #[test]
    fn strength_reduction_refits_the_cone() {
        let law = DruckerPrager::from_degrees(el(), 10.0, 30.0, 30.0, ConeFit::PlaneStrain).unwrap();
        let reduced = law.with_strength_reduced(2.0).unwrap();
        let phi_f = (30f64.to_radians().tan() / 2.0).atan();
        let expected =
            DruckerPrager::from_degrees(el(), 5.0, phi_f.to_degrees(), phi_f.to_degrees(), ConeFit::PlaneStrain)
                .unwrap();
        let s = Matrix3::from_diagonal(&Vector3::new(-3.0, -20.0, -9.0));
        let (f, g) = (
            reduced.update(&el().strain(&s), &[0.0, 0.0], &mut [0.0, 0.0]).unwrap(),
            expected.update(&el().strain(&s), &[0.0, 0.0], &mut [0.0, 0.0]).unwrap(),
        );
        assert!((f.stress - g.stress).norm() < 1e-12 * s.norm());
        assert!((expected.strength(0.0).0 - 5.0).abs() < 1e-15);
        assert!(law.with_strength_reduced(0.0).is_err());
    }
}
