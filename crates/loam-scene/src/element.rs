//! An element-test file (`loam element FILE`): one law, its initial stress and a
//! laboratory path, checked as a scene's materials are (docs/scene-format.md, "Element
//! tests"). The test itself is `loam_constitutive::ElementTest`.

use super::locate::{locate, Seg};
use super::materials::LawChecks;
use super::{parse_ron, read_text, LawSpec, SceneError};
use loam_constitutive::{ConstitutiveLaw, ElementPath, ElementTest};
use nalgebra::Matrix3;
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// An element test: a law, the normal components of its initial stress (σ_xx, σ_yy, σ_zz;
/// tension positive, z the axial direction) and the path.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, rename = "ElementTest")]
pub struct ElementTestSpec {
    #[serde(default)]
    pub title: String,
    pub law: LawSpec,
    pub initial_stress: Vec<f64>,
    pub path: ElementPathSpec,
}

/// A laboratory path to a total strain (compression positive: the axial strain shortens
/// along z; simple shear's is the engineering shear strain γ_xz) in `steps` equal steps.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
pub enum ElementPathSpec {
    /// Axial compression, the lateral stresses held.
    TriaxialDrained { axial_strain: f64, steps: usize },
    /// Axial compression at constant volume.
    TriaxialUndrained { axial_strain: f64, steps: usize },
    /// Axial compression without lateral strain.
    Oedometer { axial_strain: f64, steps: usize },
    /// Shear γ_xz under a constant σ_zz.
    SimpleShear { shear_strain: f64, steps: usize },
}

/// An element-test file as read: its path, text and contents.
#[derive(Debug, Clone)]
pub struct LoadedElementTest {
    pub path: PathBuf,
    pub source: String,
    pub spec: ElementTestSpec,
}

/// What an element test runs: the law, the initial stress, the path, each step's strain
/// increment and the number of steps.
#[derive(Debug, Clone)]
pub struct ElementRun {
    pub title: String,
    pub law: Arc<dyn ConstitutiveLaw>,
    pub initial_stress: Matrix3<f64>,
    pub path: ElementPath,
    pub increment: f64,
    pub steps: usize,
}

/// More steps than this is not an element test but a typo.
const MAX_STEPS: usize = 1_000_000;

impl LoadedElementTest {
    /// Read and parse an element-test file.
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        let (source, spec) = parse_ron(path, read_text(path, "element test")?)?;
        Ok(Self { path: path.to_owned(), source, spec })
    }

    fn error(&self, path: &[Seg], message: impl Into<String>) -> SceneError {
        let (line, column) = locate(&self.source, path);
        SceneError { file: self.path.clone(), line, column, message: message.into() }
    }

    /// The test checked: the law's parameters at their keys, a finite initial stress, a
    /// finite non-zero strain in 1 to 1 000 000 steps.
    pub fn build(&self) -> Result<ElementRun, SceneError> {
        let error = |path: &[Seg], message: String| self.error(path, message);
        let law = LawChecks { error: &error, base: &[Seg::Key("law")], label: "the law".into() }.law(&self.spec.law)?;
        let s = &self.spec.initial_stress;
        if s.len() != 3 {
            return Err(self.error(
                &[Seg::Key("initial_stress")],
                format!("initial_stress has {} components; it needs 3, [σ_xx, σ_yy, σ_zz]", s.len()),
            ));
        }
        if let Some(v) = s.iter().find(|v| !v.is_finite()) {
            return Err(self.error(
                &[Seg::Key("initial_stress")],
                format!("initial_stress has the value {v}; every component must be finite"),
            ));
        }
        let (path, strain, steps, key) = match self.spec.path {
            ElementPathSpec::TriaxialDrained { axial_strain, steps } => {
                (ElementPath::TriaxialDrained, axial_strain, steps, "axial_strain")
            }
            ElementPathSpec::TriaxialUndrained { axial_strain, steps } => {
                (ElementPath::TriaxialUndrained, axial_strain, steps, "axial_strain")
            }
            ElementPathSpec::Oedometer { axial_strain, steps } => {
                (ElementPath::Oedometer, axial_strain, steps, "axial_strain")
            }
            ElementPathSpec::SimpleShear { shear_strain, steps } => {
                (ElementPath::SimpleShear, shear_strain, steps, "shear_strain")
            }
        };
        if !(strain.is_finite() && strain != 0.0) {
            return Err(self.error(
                &[Seg::Key("path"), Seg::Key(key)],
                format!("{key} is {strain}; it must be a finite, non-zero strain (compression positive)"),
            ));
        }
        if !(1..=MAX_STEPS).contains(&steps) {
            return Err(self.error(
                &[Seg::Key("path"), Seg::Key("steps")],
                format!("steps is {steps}; it must be from 1 to {MAX_STEPS}"),
            ));
        }
        let initial_stress = Matrix3::from_diagonal(&nalgebra::Vector3::new(s[0], s[1], s[2]));
        if let Err(e) = ElementTest::new(law.as_ref(), initial_stress) {
            return Err(self.error(&[Seg::Key("initial_stress")], format!("the law cannot start here: {e}")));
        }
        let title = self.spec.title.clone();
        Ok(ElementRun { title, law, initial_stress, path, increment: strain / steps as f64, steps })
    }
}
