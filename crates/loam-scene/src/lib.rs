//! Scene files: the RON schema of a run (`docs/scene-format.md`), its parsing and its
//! validation. Every error names the file, the line and column, and what would be valid;
//! a scene is checked completely — down to points outside the grid and constraints that
//! hold no node — before the first step runs.
//!
//! The loader is in parts, one file each, called in this order by [`LoadedScene::build`]
//! (the order decides which of several mistakes is reported):
//! - `schema`: the types the text deserialises into (syntax, unknown keys, missing fields
//!   and wrong types are refused by `LoadedScene::parse`);
//! - `locate`: the line and column of a value, for [`SceneError`];
//! - `grid`: the dimension and the background grid;
//! - `materials`: each material's density and constitutive law;
//! - `memory`: the memory the scene will take, refused above the limit before any point
//!   is made;
//! - `bodies`: the material points (or the FEM reference's mesh) and initial velocities;
//! - `constraints`: gravity, the plane constraints and prescribed displacements, the
//!   rollers on inclined planes;
//! - `loads`: forces at points, tractions and pressures on the bodies' boundaries;
//! - `water`: the phreatic level and the water's unit weight;
//! - `solver`: Newton's tolerances and the linear solver;
//! - `model`: the model assembled from the parts above, with its options (anti-locking,
//!   geometric linearity, ghost penalty, initial stress);
//! - `analysis`: the analysis and its settings, and the checks that need the whole model;
//! - `excavation`: the stages that remove a region's points after a step.
//!
//! The output settings need no check (every count and flag is valid); the runner reads
//! them from the schema.
//!
//! The schema's enums (`BasisSpec`, `KinematicsSpec`, `AntiLockingSpec`, `LinearSpec`,
//! `MassSpec`, `SchemeSpec`, `TimeStepSpec`) mirror domain enums instead of deserialising
//! them because the file format is a public contract that must not change when a Rust API
//! is renamed, and the lower crates must not know a file format; `convert` holds the one
//! `From` impl of each.

mod analysis;
mod bodies;
mod constraints;
mod convert;
mod element;
mod excavation;
mod grid;
mod loads;
mod locate;
mod materials;
mod memory;
mod model;
mod monitor;
mod schema;
mod solver;
mod water;

pub use element::{ElementPathSpec, ElementRun, ElementTestSpec, LoadedElementTest};
pub use excavation::Excavation;
pub use locate::SceneError;
pub use memory::{default_memory_limit, MemoryEstimate};
pub use monitor::Monitor;
pub use schema::*;

use loam_analysis::Analysis;
use loam_model::ModelError;
use locate::{locate, Seg};
use nalgebra::SVector;
use std::io::Read;
use std::path::{Path, PathBuf};

/// The largest scene file read, in bytes: the longest example is a few kB.
pub const MAX_SCENE_BYTES: u64 = 16 << 20;

/// The parser's message, or what it means where the parser's words mislead: a value where
/// a field name belongs (`Fixed(-0.001)`) is reported by RON as an invalid identifier.
fn parse_message(code: &ron::Error) -> String {
    match code {
        ron::Error::SuggestRawIdentifier(found) | ron::Error::InvalidIdentifier(found) => format!(
            "expected a field name here, found {found:?}: every field is named, as in \
             Fixed(axis: Y, at: 0.0) or Elastic(young: 1e5, poisson: 0.3) (docs/scene-format.md)"
        ),
        other => other.to_string(),
    }
}

/// The text of a `kind` file (a scene, an element test), read up to [`MAX_SCENE_BYTES`]:
/// such a file describes its problem in a few lines, so a larger one is not one
/// (`/dev/zero` is refused, not read until memory runs out).
fn read_text(path: &Path, kind: &str) -> Result<String, SceneError> {
    let error = |message: String| SceneError { file: path.to_owned(), line: 0, column: 0, message };
    let unreadable = |e: std::io::Error| error(format!("cannot read the {kind} file: {e}"));
    let file = std::fs::File::open(path).map_err(unreadable)?;
    let mut bytes = Vec::new();
    file.take(MAX_SCENE_BYTES + 1).read_to_end(&mut bytes).map_err(unreadable)?;
    if bytes.len() as u64 > MAX_SCENE_BYTES {
        return Err(error(format!(
            "the file is larger than {} MiB; a {kind} is a short text that describes its problem: is this the {kind} file?",
            MAX_SCENE_BYTES >> 20
        )));
    }
    text_of(path, bytes)
}

/// RON text parsed as a `T`, a leading byte-order mark (which some Windows editors write)
/// skipped; the text kept for locating later errors.
fn parse_ron<T: serde::de::DeserializeOwned>(path: &Path, source: String) -> Result<(String, T), SceneError> {
    let source = match source.strip_prefix('\u{feff}') {
        Some(rest) => rest.to_string(),
        None => source,
    };
    let value = ron::from_str(&source).map_err(|e| SceneError {
        file: path.to_owned(),
        line: e.span.start.line,
        column: e.span.start.col,
        message: parse_message(&e.code),
    })?;
    Ok((source, value))
}

/// The text of a scene file, or an error at the first byte that is not UTF-8 (a binary
/// file, or text saved in another encoding).
fn text_of(path: &Path, bytes: Vec<u8>) -> Result<String, SceneError> {
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let line = 1 + valid.iter().filter(|&&b| b == b'\n').count();
        let start = valid.iter().rposition(|&b| b == b'\n').map_or(0, |i| i + 1);
        let column = 1 + String::from_utf8_lossy(&valid[start..]).chars().count();
        SceneError {
            file: path.to_owned(),
            line,
            column,
            message:
                "the file is not UTF-8 text (a binary file, or text saved in another encoding): save the scene as UTF-8"
                    .to_string(),
        }
    })
}

/// What a built scene holds ([`LoadedScene::check`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SceneSummary {
    /// Material points.
    pub points: usize,
    /// Displacement dofs of every grid node: an upper bound on the system's size.
    pub nodal_dofs: usize,
}

/// A parsed scene with its source, so that later errors can point into the file.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    pub path: PathBuf,
    pub source: String,
    pub scene: Scene,
    /// The most memory the run may take, in bytes: a scene estimated above it is refused
    /// before its points are made. `None`: this machine's memory.
    pub memory_limit: Option<u64>,
}

impl LoadedScene {
    /// Read and parse a scene file (syntax, unknown keys, missing fields, wrong types). The
    /// read is bounded by [`MAX_SCENE_BYTES`]: a scene describes its bodies by shapes, so a
    /// larger file is not a scene (`/dev/zero` is refused, not read until memory runs out).
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        Self::parse(path, read_text(path, "scene")?)
    }

    /// Parse scene text; `path` is only used in error messages. A leading byte-order mark
    /// (which some Windows editors write) is skipped.
    pub fn parse(path: &Path, source: String) -> Result<Self, SceneError> {
        let (source, scene) = parse_ron(path, source)?;
        Ok(Self { path: path.to_owned(), source, scene, memory_limit: None })
    }

    /// What is valid but probably not meant, each at its place: a material no body uses,
    /// and a plastic material in an implicit analysis without anti-locking (its flow locks
    /// in the points' cells, and collapse loads come out too high). `loam check` and
    /// `loam run` print them before anything else.
    pub fn warnings(&self) -> Vec<SceneError> {
        let used = |name: &str| self.scene.bodies.iter().any(|b| b.material == name);
        let implicit = !matches!(self.scene.analysis, AnalysisSpec::Explicit { .. });
        let may_lock = implicit && self.scene.anti_locking == AntiLockingSpec::None;
        let mut warnings = Vec::new();
        for (i, m) in self.scene.materials.iter().enumerate() {
            if !used(&m.name) {
                let at = [Seg::Key("materials"), Seg::Index(i), Seg::Key("name")];
                warnings.push(
                    self.error(
                        &at,
                        format!("material \"{}\" is used by no body (a typo in a body's material?)", m.name),
                    ),
                );
            } else if may_lock && !matches!(m.law, LawSpec::Elastic { .. }) {
                let at = [Seg::Key("materials"), Seg::Index(i), Seg::Key("law")];
                let remedy = match self.scene.method {
                    MethodSpec::Mpm => {
                        "give basis: Linear with anti_locking: FBar (finite strain) or BBar (small strain)"
                    }
                    _ => "give anti_locking: FBar (finite strain) or BBar (small strain)",
                };
                warnings.push(self.error(&at, format!("material \"{}\" is plastic, and without anti-locking its plastic flow locks: collapse loads come out too high (docs/theory.md §13); {remedy}", m.name)));
            }
        }
        warnings
    }

    /// An error at `path` in the file.
    fn error(&self, path: &[Seg], message: impl Into<String>) -> SceneError {
        let (line, column) = locate(&self.source, path);
        SceneError { file: self.path.clone(), line, column, message: message.into() }
    }

    /// The `D` components of the vector `v` at `path` (`what` names it in the message),
    /// each finite.
    fn vector<const D: usize>(&self, v: &[f64], path: &[Seg], what: &str) -> Result<SVector<f64, D>, SceneError> {
        if v.len() != D {
            return Err(self.error(path, format!("{what} has {} components; a {D}D scene needs {D}", v.len())));
        }
        if let Some(x) = v.iter().find(|x| !x.is_finite()) {
            return Err(self.error(path, format!("{what} has the value {x}; every component must be finite")));
        }
        Ok(SVector::from_column_slice(v))
    }

    /// Build the scene in its own dimension, every check included (`loam check`), and count
    /// what it holds. Not generic, so that its callers do not each compile the analyses
    /// again for both dimensions.
    pub fn check(&self) -> Result<SceneSummary, SceneError> {
        fn summary<const D: usize>(analysis: Analysis<D>) -> SceneSummary {
            let model = analysis.model();
            SceneSummary { points: model.points().len(), nodal_dofs: model.background().num_nodes() * D }
        }
        match self.scene.dimension {
            3 => self.build::<3>().map(summary),
            _ => self.build::<2>().map(summary),
        }
    }

    /// Build the model and analysis of a `D`-dimensional scene, checking everything that can
    /// be checked before the first step. `D` must equal the scene's `dimension`.
    pub fn build<const D: usize>(&self) -> Result<Analysis<D>, SceneError> {
        self.check_dimension::<D>()?;
        let grid = self.grid::<D>()?;
        let laws = self.materials()?;
        self.check_memory(&grid)?;
        let bodies = self.bodies(&grid)?;
        let gravity = self.gravity::<D>()?;
        self.check_scales(&grid, &laws, &gravity)?;
        let constraints = self.constraints(&grid)?;
        let inclined = self.inclined_rollers::<D>()?;
        let held_bodies = self.body_constraints::<D>()?;
        let loads = self.loads(&grid)?;
        let solver = self.solver()?;
        let model = self.model(grid, bodies, laws, constraints, gravity)?;
        let model = model
            .with_inclined_rollers(inclined)
            .map_err(|e| self.error(&[Seg::Key("inclined_rollers")], e.to_string()))?
            .with_body_constraints(held_bodies)
            .map_err(|e| match e {
                ModelError::BodyConstraint { index, .. } => {
                    self.error(&[Seg::Key("body_constraints"), Seg::Index(index)], e.to_string())
                }
                _ => self.error(&[Seg::Key("body_constraints")], e.to_string()),
            })?;
        let model = self.with_initial_stress(self.with_loads(self.with_frictional_planes(model)?, loads)?)?;
        let mut analysis = self.analysis(model, solver)?;
        self.check_before_the_first_step(&mut analysis)?;
        self.excavations::<D>()?;
        self.monitors(analysis.model())?;
        Ok(analysis)
    }
}
