//! The materials part of a scene: each material's density and constitutive law, every
//! parameter checked against what is valid and refused at its own key.

use super::locate::Seg;
use super::{
    CamClayInitialSpec, CamClayShearSpec, ConeFitSpec, CriticalStateSpec, LawSpec, LoadedScene, SceneError,
    SofteningSpec,
};
use loam_constitutive::{
    CamClayInitial, CamClayShear, ConeFit, ConstitutiveError, ConstitutiveLaw, DruckerPrager, Elastic, ModifiedCamClay,
    MohrCoulomb, VonMises,
};
use std::sync::Arc;

impl LoadedScene {
    /// The laws of the scene's materials, in order: at least one material, each with a
    /// positive density and a name of its own.
    pub(super) fn materials(&self) -> Result<Vec<Arc<dyn ConstitutiveLaw>>, SceneError> {
        let materials = &self.scene.materials;
        if materials.is_empty() {
            return Err(self.error(&[Seg::Key("materials")], "no materials: define at least one, e.g. Material(name: \"soil\", density: 2000.0, law: Elastic(young: 1e5, poisson: 0.3))"));
        }
        let mut laws: Vec<Arc<dyn ConstitutiveLaw>> = Vec::new();
        for (i, m) in materials.iter().enumerate() {
            let at = |key| [Seg::Key("materials"), Seg::Index(i), Seg::Key(key)];
            if !(m.density.is_finite() && m.density > 0.0) {
                return Err(self.error(
                    &at("density"),
                    format!("material \"{}\": density is {}; it must be a positive number", m.name, m.density),
                ));
            }
            if materials[..i].iter().any(|o| o.name == m.name) {
                return Err(self
                    .error(&at("name"), format!("material name \"{}\" is used twice; names must be unique", m.name)));
            }
            let base = [Seg::Key("materials"), Seg::Index(i), Seg::Key("law")];
            let error = |path: &[Seg], message: String| self.error(path, message);
            laws.push(LawChecks { error: &error, base: &base, label: format!("material \"{}\"", m.name) }.law(&m.law)?);
        }
        Ok(laws)
    }
}

/// The checks of a law (a scene material's, or an element test's), each refusal placed at
/// the parameter's key under `base` by `error` and named by `label`.
pub(super) struct LawChecks<'a> {
    pub error: &'a dyn Fn(&[Seg], String) -> SceneError,
    pub base: &'a [Seg<'a>],
    pub label: String,
}

impl LawChecks<'_> {
    /// `key = value` must be `ok` and finite; otherwise the error says it must be `valid`.
    fn check(&self, key: &'static str, value: f64, ok: bool, valid: &str) -> Result<(), SceneError> {
        if ok && value.is_finite() {
            return Ok(());
        }
        Err(self.at(key, format!("{}: {key} = {value}; it must be {valid}", self.label)))
    }

    /// An error at the law's key `key`.
    fn at(&self, key: &'static str, message: String) -> SceneError {
        let mut path = self.base.to_vec();
        path.push(Seg::Key(key));
        (self.error)(&path, message)
    }

    /// Whatever the law still refuses (checked combinations) is reported at the law.
    fn refused(&self, e: ConstitutiveError) -> SceneError {
        (self.error)(self.base, format!("{}: {e}", self.label))
    }

    /// The law: its elastic part, checked first, then its strength.
    pub fn law(&self, law: &LawSpec) -> Result<Arc<dyn ConstitutiveLaw>, SceneError> {
        Ok(match *law {
            LawSpec::Elastic { young, poisson } => Arc::new(self.elastic(young, poisson)?),
            LawSpec::VonMises { young, poisson, yield_stress, hardening, residual_yield_stress } => {
                let elastic = self.elastic(young, poisson)?;
                Arc::new(self.von_mises(elastic, yield_stress, hardening, residual_yield_stress)?)
            }
            LawSpec::MohrCoulomb { young, poisson, cohesion, friction, dilation, tension_cutoff, softening } => {
                let elastic = self.elastic(young, poisson)?;
                Arc::new(self.mohr_coulomb(elastic, [cohesion, friction, dilation], tension_cutoff, softening)?)
            }
            LawSpec::DruckerPrager { young, poisson, cohesion, friction, dilation, fit, softening } => {
                let elastic = self.elastic(young, poisson)?;
                Arc::new(self.drucker_prager(elastic, [cohesion, friction, dilation], fit, softening)?)
            }
            LawSpec::ModifiedCamClay { lambda, kappa, void_ratio, critical_state, shear, initial, lode_dependent } => {
                let law = self.cam_clay([lambda, kappa, void_ratio], critical_state, shear, initial)?;
                Arc::new(match lode_dependent {
                    true => law.with_lode_dependence().map_err(|e| {
                        self.at(
                            "critical_state",
                            format!("{}: {e}; a Lode-dependent M is below 3 (φ′ < 90°)", self.label),
                        )
                    })?,
                    false => law,
                })
            }
        })
    }

    /// The elastic part of a law: Young's modulus and Poisson's ratio.
    fn elastic(&self, young: f64, poisson: f64) -> Result<Elastic, SceneError> {
        self.check("young", young, young > 0.0, "positive (Young's modulus)")?;
        self.check("poisson", poisson, poisson > -1.0 && poisson < 0.5, "in (-1, 0.5) (Poisson's ratio)")?;
        Elastic::new(young, poisson).map_err(|e| self.at("young", e.to_string()))
    }

    fn von_mises(
        &self,
        elastic: Elastic,
        yield_stress: f64,
        hardening: f64,
        residual_yield_stress: Option<f64>,
    ) -> Result<VonMises, SceneError> {
        self.check("yield_stress", yield_stress, yield_stress > 0.0, "positive")?;
        let (_, mu) = elastic.lame();
        self.check("hardening", hardening, hardening > -3.0 * mu, "above −3G (a hardening modulus; negative softens)")?;
        let mut law = VonMises::new(elastic, yield_stress, hardening).map_err(|e| self.refused(e))?;
        if let Some(r) = residual_yield_stress {
            self.check("residual_yield_stress", r, (0.0..=yield_stress).contains(&r), "between 0 and yield_stress")?;
            law = law.with_residual_yield_stress(r).map_err(|e| self.refused(e))?;
        }
        Ok(law)
    }

    /// The peak `[cohesion, friction, dilation]` (angles in degrees) of a frictional law.
    fn frictional(&self, [cohesion, friction, dilation]: [f64; 3]) -> Result<(), SceneError> {
        self.check("friction", friction, (0.0..90.0).contains(&friction), "in [0, 90) degrees (0 is Tresca)")?;
        let strong = cohesion >= 0.0 && (cohesion > 0.0 || friction > 0.0);
        self.check("cohesion", cohesion, strong, "≥ 0, and > 0 when friction = 0")?;
        let valid_dilation = "in [0, friction] degrees (= friction: associated flow)";
        self.check("dilation", dilation, (0.0..=friction).contains(&dilation), valid_dilation)
    }

    /// Mohr–Coulomb from its peak `[cohesion, friction, dilation]` (angles in degrees).
    fn mohr_coulomb(
        &self,
        elastic: Elastic,
        [cohesion, friction, dilation]: [f64; 3],
        tension_cutoff: Option<f64>,
        softening: Option<SofteningSpec>,
    ) -> Result<MohrCoulomb, SceneError> {
        self.frictional([cohesion, friction, dilation])?;
        let mut law = MohrCoulomb::from_degrees(elastic, cohesion, friction, dilation).map_err(|e| self.refused(e))?;
        if let Some(t) = tension_cutoff {
            let apex = if friction > 0.0 { cohesion / friction.to_radians().tan() } else { f64::INFINITY };
            self.check("tension_cutoff", t, t <= apex, "at most c cot φ (the apex of the cone)")?;
            law = law.with_tension_cutoff(t).map_err(|e| self.refused(e))?;
        }
        if let Some(sf) = softening {
            law = law
                .with_softening(sf.cohesion, sf.friction, sf.dilation, sf.plastic_strain)
                .map_err(|e| self.refused(e))?;
        }
        Ok(law)
    }

    /// Drucker–Prager from its peak `[cohesion, friction, dilation]` (angles in degrees).
    fn drucker_prager(
        &self,
        elastic: Elastic,
        [cohesion, friction, dilation]: [f64; 3],
        fit: ConeFitSpec,
        softening: Option<SofteningSpec>,
    ) -> Result<DruckerPrager, SceneError> {
        self.frictional([cohesion, friction, dilation])?;
        let fit = match fit {
            ConeFitSpec::PlaneStrain => ConeFit::PlaneStrain,
            ConeFitSpec::Compression => ConeFit::Compression,
            ConeFitSpec::Extension => ConeFit::Extension,
        };
        let mut law =
            DruckerPrager::from_degrees(elastic, cohesion, friction, dilation, fit).map_err(|e| self.refused(e))?;
        if let Some(sf) = softening {
            law = law
                .with_softening(sf.cohesion, sf.friction, sf.dilation, sf.plastic_strain)
                .map_err(|e| self.refused(e))?;
        }
        Ok(law)
    }

    /// Modified Cam clay from `[λ, κ, e₀]`, its critical state, shear and initial state.
    fn cam_clay(
        &self,
        [lambda, kappa, void_ratio]: [f64; 3],
        critical_state: CriticalStateSpec,
        shear: CamClayShearSpec,
        initial: CamClayInitialSpec,
    ) -> Result<ModifiedCamClay, SceneError> {
        self.check("kappa", kappa, kappa > 0.0, "positive (the unloading line's slope)")?;
        self.check("lambda", lambda, lambda > kappa, "above kappa (the virgin line is steeper than unloading)")?;
        self.check("void_ratio", void_ratio, void_ratio > 0.0, "positive")?;
        let m = match critical_state {
            CriticalStateSpec::Slope(m) => {
                self.check("critical_state", m, m > 0.0, "Slope(M) with M > 0, or Friction(φ′) in degrees")?;
                m
            }
            CriticalStateSpec::Friction(phi) => {
                let valid = "Friction(φ′) with 0 < φ′ < 90 degrees, or Slope(M)";
                self.check("critical_state", phi, phi > 0.0 && phi < 90.0, valid)?;
                ModifiedCamClay::slope_from_friction(phi)
            }
        };
        let shear = match shear {
            CamClayShearSpec::Modulus(g) => {
                self.check("shear", g, g > 0.0, "Modulus(G) with G > 0, or Poisson(ν)")?;
                CamClayShear::Modulus(g)
            }
            CamClayShearSpec::Poisson(nu) => {
                self.check("shear", nu, nu > -1.0 && nu < 0.5, "Poisson(ν) with ν in (-1, 0.5), or Modulus(G)")?;
                CamClayShear::Poisson(nu)
            }
        };
        let initial = match initial {
            CamClayInitialSpec::OverConsolidation(ocr) => {
                let valid = "OverConsolidation(OCR) with OCR ≥ 1 (1: normally consolidated), or Preconsolidation(p_c)";
                self.check("initial", ocr, ocr >= 1.0, valid)?;
                CamClayInitial::OverConsolidation(ocr)
            }
            CamClayInitialSpec::Preconsolidation(pc) => {
                self.check("initial", pc, pc > 0.0, "Preconsolidation(p_c) with p_c > 0, or OverConsolidation(OCR)")?;
                CamClayInitial::Preconsolidation(pc)
            }
        };
        ModifiedCamClay::new(lambda, kappa, void_ratio, m, shear, initial).map_err(|e| self.refused(e))
    }
}
