//! Scene files: the RON schema of a run (`docs/scene-format.md`), its parsing and its
//! validation. Every error names the file, the line and column, and what would be valid;
//! a scene is checked completely — down to points outside the grid and constraints that
//! hold no node — before the first step runs.
//!
//! The schema's enums (`BasisSpec`, `KinematicsSpec`, `AntiLockingSpec`, `LinearSpec`,
//! `MassSpec`, `SchemeSpec`, `TimeStepSpec`) mirror domain enums instead of deserialising
//! them because the file format is a public contract that must not change when a Rust API
//! is renamed, and the lower crates must not know a file format; `convert` holds the one
//! `From` impl of each.

mod convert;
mod locate;
mod schema;

pub use locate::SceneError;
pub use schema::*;

use crate::analysis::{Analysis, AnalysisError};
use loam_constitutive::{ConstitutiveLaw, Elastic, MohrCoulomb, VonMises};
use loam_explicit::{Explicit, ExplicitError, ExplicitSettings, TimeStep};
use loam_grid::{FeMesh, Grid, MeshError};
use loam_implicit::{Dynamic, DynamicSettings, Model, PlaneConstraint, QuasiStatic, QuasiStaticSettings, StepError};
use loam_points::{PointStore, Shape};
use loam_solve::NewtonSettings;
use locate::{locate, Seg};
use nalgebra::{SVector, Vector2};
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A parsed scene with its source, so that later errors can point into the file.
#[derive(Debug, Clone)]
pub struct LoadedScene {
    pub path: PathBuf,
    pub source: String,
    pub scene: Scene,
}

impl LoadedScene {
    /// Read and parse a scene file (syntax, unknown keys, missing fields, wrong types).
    pub fn read(path: &Path) -> Result<Self, SceneError> {
        let source = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: path.to_owned(),
            line: 0,
            column: 0,
            message: format!("cannot read the scene file: {e}"),
        })?;
        Self::parse(path, source)
    }

    /// Parse scene text; `path` is only used in error messages.
    pub fn parse(path: &Path, source: String) -> Result<Self, SceneError> {
        let scene: Scene = ron::from_str(&source).map_err(|e| SceneError {
            file: path.to_owned(),
            line: e.span.start.line,
            column: e.span.start.col,
            message: e.code.to_string(),
        })?;
        Ok(Self { path: path.to_owned(), source, scene })
    }

    fn error(&self, path: &[Seg], message: impl Into<String>) -> SceneError {
        let (line, column) = locate(&self.source, path);
        SceneError { file: self.path.clone(), line, column, message: message.into() }
    }

    /// Build the model and analysis of a `D`-dimensional scene, checking everything that can
    /// be checked before the first step. `D` must equal the scene's `dimension`.
    pub fn build<const D: usize>(&self) -> Result<Analysis<D>, SceneError> {
        let s = &self.scene;
        if s.dimension != D {
            return Err(self.error(
                &[Seg::Key("dimension")],
                format!("dimension is {}; loam runs 2 (plane strain) or 3", s.dimension),
            ));
        }
        let vec_d = |v: &[f64], path: &[Seg], what: &str| -> Result<SVector<f64, D>, SceneError> {
            if v.len() != D {
                return Err(self.error(path, format!("{what} has {} components; a {D}D scene needs {D}", v.len())));
            }
            if let Some(x) = v.iter().find(|x| !x.is_finite()) {
                return Err(self.error(path, format!("{what} has the value {x}; every component must be finite")));
            }
            Ok(SVector::from_column_slice(v))
        };
        // Grid.
        let origin = vec_d(&s.grid.origin, &[Seg::Key("grid"), Seg::Key("origin")], "grid.origin")?;
        let cell = vec_d(&s.grid.cell_size, &[Seg::Key("grid"), Seg::Key("cell_size")], "grid.cell_size")?;
        if s.grid.cells.len() != D {
            return Err(self.error(
                &[Seg::Key("grid"), Seg::Key("cells")],
                format!("grid.cells has {} entries; a {D}D scene needs {D}", s.grid.cells.len()),
            ));
        }
        let mut cells = [0usize; D];
        cells.copy_from_slice(&s.grid.cells);
        let grid = Grid::new(origin, cell, cells).map_err(|e| {
            let key = match e {
                loam_grid::GridError::CellSize { .. } => "cell_size",
                loam_grid::GridError::CellCount { .. } | loam_grid::GridError::TooLarge { .. } => "cells",
                loam_grid::GridError::Origin { .. } => "origin",
            };
            self.error(&[Seg::Key("grid"), Seg::Key(key)], e.to_string())
        })?;
        // Materials.
        if s.materials.is_empty() {
            return Err(self.error(&[Seg::Key("materials")], "no materials: define at least one, e.g. Material(name: \"soil\", density: 2000.0, law: Elastic(young: 1e5, poisson: 0.3))"));
        }
        let mut laws: Vec<Arc<dyn ConstitutiveLaw>> = Vec::new();
        for (i, m) in s.materials.iter().enumerate() {
            let at = |key| [Seg::Key("materials"), Seg::Index(i), Seg::Key(key)];
            if !(m.density.is_finite() && m.density > 0.0) {
                return Err(self.error(
                    &at("density"),
                    format!("material \"{}\": density is {}; it must be a positive number", m.name, m.density),
                ));
            }
            if s.materials[..i].iter().any(|o| o.name == m.name) {
                return Err(self
                    .error(&at("name"), format!("material name \"{}\" is used twice; names must be unique", m.name)));
            }
            laws.push(self.law(i, m)?);
        }
        // Bodies.
        if s.bodies.is_empty() {
            return Err(self.error(
                &[Seg::Key("bodies")],
                "no bodies: add at least one Body(material: ..., shape: Box(min: [...], max: [...]))",
            ));
        }
        let fem = s.method == MethodSpec::UpdatedLagrangianFem;
        let mut points = PointStore::<D>::new();
        let mut mesh: Option<FeMesh<D>> = None;
        let (mut block_density, mut block_material) = (Vec::new(), Vec::new());
        for (i, b) in s.bodies.iter().enumerate() {
            let at = |key| [Seg::Key("bodies"), Seg::Index(i), Seg::Key(key)];
            let Some(mi) = s.materials.iter().position(|m| m.name == b.material) else {
                let names: Vec<&str> = s.materials.iter().map(|m| m.name.as_str()).collect();
                return Err(self.error(
                    &at("material"),
                    format!("body {i} uses material \"{}\", which is not defined; defined: {names:?}", b.material),
                ));
            };
            let shape = match &b.shape {
                ShapeSpec::Box { min, max } => Shape::Box {
                    min: vec_d(
                        min,
                        &[Seg::Key("bodies"), Seg::Index(i), Seg::Key("shape"), Seg::Key("min")],
                        "Box min",
                    )?,
                    max: vec_d(
                        max,
                        &[Seg::Key("bodies"), Seg::Index(i), Seg::Key("shape"), Seg::Key("max")],
                        "Box max",
                    )?,
                },
                ShapeSpec::Ball { centre, radius } => Shape::Ball {
                    centre: vec_d(
                        centre,
                        &[Seg::Key("bodies"), Seg::Index(i), Seg::Key("shape"), Seg::Key("centre")],
                        "Ball centre",
                    )?,
                    radius: *radius,
                },
                ShapeSpec::Polygon { vertices } => {
                    if D != 2 {
                        return Err(self.error(&at("shape"), "Polygon shapes are 2D only; use Box in 3D"));
                    }
                    Shape::Polygon(vertices.iter().map(|v| Vector2::new(v[0], v[1])).collect())
                }
            };
            if fem {
                let Shape::Box { min, max } = shape else {
                    return Err(self.error(
                        &at("shape"),
                        format!(
                            "body {i}: the updated Lagrangian FEM meshes Box bodies only; use a Box or method: Mpm"
                        ),
                    ));
                };
                let h = grid.cell_size();
                let elements = std::array::from_fn(|a| (((max[a] - min[a]) / h[a]).round() as usize).max(1));
                let block = FeMesh::block(min, max, elements, b.points_per_cell).map_err(|e| {
                    let key = if matches!(e, MeshError::GaussOrder(_)) { "points_per_cell" } else { "shape" };
                    self.error(
                        &at(key),
                        format!("body {i}: {e} (with method UpdatedLagrangianFem, points_per_cell is the Gauss order)"),
                    )
                })?;
                match &mut mesh {
                    None => mesh = Some(block),
                    Some(m) => {
                        m.append(block).map_err(|e| self.error(&at("points_per_cell"), format!("body {i}: {e}")))?
                    }
                }
                block_density.push(s.materials[mi].density);
                block_material.push(mi as u32);
                continue;
            }
            let added = points
                .fill(&grid, &shape, b.points_per_cell, s.materials[mi].density, mi as u32)
                .map_err(|e| self.error(&at("shape"), format!("body {i}: {e}")))?;
            if let Some(v) = &b.velocity {
                let first = points.len() - added;
                let field = self.velocity_field::<D>(v, i)?;
                for p in first..points.len() {
                    points.velocity[p] = field(&points.position[p]);
                }
            }
        }
        // Loads and constraints.
        let gravity = vec_d(&s.gravity, &[Seg::Key("gravity")], "gravity")?;
        let mut constraints = Vec::new();
        for (i, c) in s.constraints.iter().enumerate() {
            let here = [Seg::Key("constraints"), Seg::Index(i)];
            let (axis, at, within) = match c {
                ConstraintSpec::Roller { axis, at, within }
                | ConstraintSpec::Fixed { axis, at, within }
                | ConstraintSpec::Displacement { axis, at, within, .. } => (*axis, *at, within),
            };
            let a = axis.index();
            if a >= D {
                return Err(
                    self.error(&here, format!("constraint {i} is on axis {axis:?}, which a {D}D scene does not have"))
                );
            }
            let Some(plane) = grid.node_plane(a, at) else {
                let h = grid.cell_size()[a];
                let o = grid.origin()[a];
                return Err(self.error(&here, format!(
                    "constraint {i}: {axis:?} = {at} is not a plane of grid nodes; planes lie at {o} + k·{h} for k = 0..={}",
                    grid.cells()[a]
                )));
            };
            let mut constraint = match c {
                ConstraintSpec::Roller { .. } => {
                    let mut fixed = [false; 3];
                    fixed[a] = true;
                    PlaneConstraint::new(a, plane, fixed)
                }
                ConstraintSpec::Fixed { .. } => PlaneConstraint::new(a, plane, [true; 3]),
                ConstraintSpec::Displacement { displacement, .. } => {
                    if displacement.len() != D
                        || displacement.iter().flatten().any(|u| !u.is_finite())
                        || displacement.iter().all(Option::is_none)
                    {
                        return Err(self.error(&[Seg::Key("constraints"), Seg::Index(i), Seg::Key("displacement")], format!(
                            "constraint {i}: displacement needs {D} entries, Some(u) (finite) for a prescribed component or None for a free one, at least one Some; got {displacement:?}"
                        )));
                    }
                    let mut fixed = [false; 3];
                    let mut u = [0.0; 3];
                    for (k, d) in displacement.iter().enumerate() {
                        fixed[k] = d.is_some();
                        u[k] = d.unwrap_or(0.0);
                    }
                    PlaneConstraint::new(a, plane, fixed).displaced(u)
                }
            };
            if let Some(r) = within {
                let at_w = |key| [Seg::Key("constraints"), Seg::Index(i), Seg::Key("within"), Seg::Key(key)];
                let lo = vec_d(&r.min, &at_w("min"), "within.min")?;
                let hi = vec_d(&r.max, &at_w("max"), "within.max")?;
                if let Some(k) = (0..D).find(|&k| k != a && lo[k] > hi[k]) {
                    return Err(self.error(
                        &at_w("min"),
                        format!("constraint {i}: within.min[{k}] = {} exceeds within.max[{k}] = {}", lo[k], hi[k]),
                    ));
                }
                let mut min = [f64::NEG_INFINITY; 3];
                let mut max = [f64::INFINITY; 3];
                for k in 0..D {
                    min[k] = lo[k];
                    max[k] = hi[k];
                }
                constraint = constraint.within(min, max);
            }
            constraints.push(constraint);
        }
        if let Some(index) = constraints.iter().position(|c| c.is_displaced()) {
            if !matches!(s.analysis, AnalysisSpec::QuasiStatic { .. }) {
                return Err(self.error(&[Seg::Key("constraints"), Seg::Index(index)], format!(
                    "constraint {index} prescribes a displacement, which follows the load factor of a QuasiStatic analysis; the {} analysis does not apply it",
                    match s.analysis { AnalysisSpec::Explicit { .. } => "Explicit", _ => "ImplicitDynamic" }
                )));
            }
        }
        let sv = &s.solver;
        if !(sv.residual_tolerance > 0.0 && sv.residual_tolerance < 1.0) {
            return Err(self.error(
                &[Seg::Key("solver"), Seg::Key("residual_tolerance")],
                format!("residual_tolerance is {}; it must lie in (0, 1)", sv.residual_tolerance),
            ));
        }
        if !(sv.increment_tolerance > 0.0 && sv.increment_tolerance < 1.0) {
            return Err(self.error(
                &[Seg::Key("solver"), Seg::Key("increment_tolerance")],
                format!("increment_tolerance is {}; it must lie in (0, 1)", sv.increment_tolerance),
            ));
        }
        if sv.max_iterations == 0 {
            return Err(self.error(
                &[Seg::Key("solver"), Seg::Key("max_iterations")],
                "max_iterations is 0; it must be at least 1",
            ));
        }
        let newton = NewtonSettings {
            residual_tolerance: sv.residual_tolerance,
            increment_tolerance: sv.increment_tolerance,
            max_iterations: sv.max_iterations,
            ..NewtonSettings::default()
        };
        let linear_solver = sv.linear.map(Into::into);
        let basis = s.basis.into();
        let kinematics = s.kinematics.into();
        let model = match mesh {
            None => Model::new(grid, basis, kinematics, points, laws, constraints, gravity)
                .map_err(|e| self.error(&[Seg::Key("bodies")], e.to_string()))?,
            Some(mesh) => {
                let mut model = Model::updated_lagrangian_fem(
                    grid,
                    kinematics,
                    mesh,
                    &block_density,
                    &block_material,
                    laws,
                    constraints,
                    gravity,
                )
                .map_err(|e| self.error(&[Seg::Key("bodies")], e.to_string()))?;
                // Initial velocities at the Gauss points of each body's block.
                let mesh = model.mesh.as_ref().expect("FEM model has a mesh");
                let per = mesh.gauss_per_element();
                let blocks: Vec<usize> = (0..model.points.len()).map(|p| mesh.element_block(p / per)).collect();
                for (i, b) in s.bodies.iter().enumerate() {
                    if let Some(v) = &b.velocity {
                        let field = self.velocity_field::<D>(v, i)?;
                        let pts = &mut model.points;
                        for p in (0..pts.len()).filter(|&p| blocks[p] == i) {
                            pts.velocity[p] = field(&pts.position[p]);
                        }
                    }
                }
                model
            }
        };
        let model = model
            .with_anti_locking(s.anti_locking.into())
            .map_err(|e| self.error(&[Seg::Key("anti_locking")], e.to_string()))?;
        let model = match s.geometrically_linear {
            false => model,
            true => {
                if matches!(s.analysis, AnalysisSpec::Explicit { .. }) {
                    return Err(self.error(&[Seg::Key("geometrically_linear")], "explicit analysis moves its points by their velocities; set geometrically_linear: false or use an implicit analysis"));
                }
                model
                    .with_geometrically_linear()
                    .map_err(|e| self.error(&[Seg::Key("geometrically_linear")], e.to_string()))?
            }
        };
        let mut model = match s.ghost_penalty {
            None => model,
            Some(gamma) => {
                if matches!(s.analysis, AnalysisSpec::Explicit { .. }) {
                    return Err(self.error(&[Seg::Key("ghost_penalty")], "the ghost penalty stabilises the implicit tangent; an Explicit analysis has none (remove the key)"));
                }
                model.with_ghost_penalty(gamma).map_err(|e| self.error(&[Seg::Key("ghost_penalty")], e.to_string()))?
            }
        };
        if let InitialStressSpec::Geostatic { k0 } = s.initial_stress {
            model.geostatic_stress(k0).map_err(|e| self.error(&[Seg::Key("initial_stress")], e.to_string()))?;
        }
        let at_analysis = |key: &'static str| [Seg::Key("analysis"), Seg::Key(key)];
        let mut analysis = match s.analysis {
            AnalysisSpec::QuasiStatic { load_steps, max_cutbacks, strength_reduction } => {
                if load_steps == 0 {
                    return Err(self.error(&at_analysis("load_steps"), "load_steps is 0; it must be at least 1"));
                }
                if let Some(srf) = strength_reduction {
                    let at = |key: &'static str| [Seg::Key("analysis"), Seg::Key("strength_reduction"), Seg::Key(key)];
                    let (lo, hi) = srf.bracket;
                    if !(lo.is_finite() && lo > 0.0 && hi.is_finite() && hi > lo) {
                        return Err(self.error(
                            &at("bracket"),
                            format!(
                                "bracket is ({lo}, {hi}); it must be (F_holds, F_fails) with 0 < F_holds < F_fails"
                            ),
                        ));
                    }
                    if !(srf.tolerance.is_finite() && srf.tolerance > 0.0 && srf.tolerance < hi - lo) {
                        return Err(self.error(
                            &at("tolerance"),
                            format!(
                                "tolerance is {}; it must be positive and below the bracket's width {}",
                                srf.tolerance,
                                hi - lo
                            ),
                        ));
                    }
                    if !model.materials.iter().any(|law| law.with_strength_reduced(1.0).is_some()) {
                        return Err(self.error(&[Seg::Key("materials")], "strength reduction needs a material with a strength (VonMises or MohrCoulomb); every material here is elastic"));
                    }
                }
                Analysis::QuasiStatic(QuasiStatic::new(
                    model,
                    QuasiStaticSettings {
                        load_steps,
                        newton,
                        max_cutbacks,
                        linear_solver,
                        extrapolate: sv.extrapolate,
                    },
                ))
            }
            AnalysisSpec::ImplicitDynamic { time_step, duration, beta, gamma, bossak_alpha, mass, max_cutbacks } => {
                let settings = DynamicSettings {
                    time_step,
                    duration,
                    beta,
                    gamma,
                    bossak_alpha,
                    mass: mass.into(),
                    newton,
                    max_cutbacks,
                    linear_solver,
                };
                match Dynamic::new(model, settings) {
                    Ok(d) => Analysis::Dynamic(d),
                    Err(StepError::InvalidSettings { field, value, valid }) => {
                        return Err(self.error(&at_analysis(field), format!("{field} is {value}; valid: {valid}")))
                    }
                    Err(e) => return Err(self.error(&[Seg::Key("analysis")], e.to_string())),
                }
            }
            AnalysisSpec::Explicit { duration, ref time_step, scheme, flip, damping } => {
                let settings =
                    ExplicitSettings { scheme: scheme.into(), flip, time_step: time_step.into(), damping, duration };
                if fem {
                    return Err(self.error(&[Seg::Key("method")], "method UpdatedLagrangianFem runs with the implicit analyses (QuasiStatic, ImplicitDynamic) only; use method: Mpm for Explicit"));
                }
                match Explicit::new(model, settings) {
                    Ok(e) => Analysis::Explicit(e),
                    Err(ExplicitError::InvalidSettings { field, value, valid }) => {
                        let key = if field.starts_with("time_step") { "time_step" } else { field };
                        return Err(self.error(&at_analysis(key), format!("{field} is {value}; valid: {valid}")));
                    }
                    Err(e) => return Err(self.error(&[Seg::Key("analysis")], e.to_string())),
                }
            }
        };
        analysis.check().map_err(|e| match e {
            AnalysisError::Implicit(StepError::ConstraintTouchesNoNode { index, .. })
            | AnalysisError::Explicit(ExplicitError::ConstraintTouchesNoNode { index, .. }) => {
                self.error(&[Seg::Key("constraints"), Seg::Index(index)], format!("constraint {index}: {e}"))
            }
            AnalysisError::Implicit(StepError::PointOutsideGrid { ref source, .. })
            | AnalysisError::Explicit(ExplicitError::PointOutsideGrid { ref source, .. }) => self.error(
                &[Seg::Key("bodies")],
                format!("material point {} at {:?}: its basis reaches outside the grid ({}); enlarge the grid or move the body", source.point, source.position, source.source),
            ),
            other => self.error(&[], other.to_string()),
        })?;
        // A fixed explicit step above the critical one is refused here, before any output.
        if let Analysis::Explicit(e) = &analysis {
            if let TimeStep::Fixed { dt, allow_above_critical: false } = e.settings().time_step {
                let critical = e.critical_time_step();
                if dt > critical {
                    return Err(self.error(&at_analysis("time_step"), format!(
                        "the fixed time step {dt:e} is above the critical step {critical:e} (h / (c_p + |v|)): the explicit run would blow up; use Cfl(0.5), a step ≤ {critical:e}, or allow_above_critical: true"
                    )));
                }
            }
        }
        Ok(analysis)
    }

    /// The constitutive law of material `i`, each parameter checked against what is valid
    /// and refused at its own place in the file.
    fn law(&self, i: usize, m: &MaterialSpec) -> Result<Arc<dyn ConstitutiveLaw>, SceneError> {
        let at = |key: &'static str| [Seg::Key("materials"), Seg::Index(i), Seg::Key("law"), Seg::Key(key)];
        let check = |key: &'static str, value: f64, ok: bool, valid: &str| {
            if ok && value.is_finite() {
                Ok(())
            } else {
                Err(self.error(&at(key), format!("material \"{}\": {key} = {value}; it must be {valid}", m.name)))
            }
        };
        let (young, poisson) = match m.law {
            LawSpec::Elastic { young, poisson }
            | LawSpec::VonMises { young, poisson, .. }
            | LawSpec::MohrCoulomb { young, poisson, .. } => (young, poisson),
        };
        check("young", young, young > 0.0, "positive (Young's modulus)")?;
        check("poisson", poisson, poisson > -1.0 && poisson < 0.5, "in (-1, 0.5) (Poisson's ratio)")?;
        let elastic = Elastic::new(young, poisson).map_err(|e| self.error(&at("young"), e.to_string()))?;
        // Whatever the law still refuses (checked combinations) is reported at the law.
        let refused = |e: loam_constitutive::ConstitutiveError| {
            self.error(
                &[Seg::Key("materials"), Seg::Index(i), Seg::Key("law")],
                format!("material \"{}\": {e}", m.name),
            )
        };
        Ok(match m.law {
            LawSpec::Elastic { .. } => Arc::new(elastic),
            LawSpec::VonMises { yield_stress, hardening, residual_yield_stress, .. } => {
                check("yield_stress", yield_stress, yield_stress > 0.0, "positive")?;
                let (_, mu) = elastic.lame();
                check(
                    "hardening",
                    hardening,
                    hardening > -3.0 * mu,
                    "above −3G (a hardening modulus; negative softens)",
                )?;
                let mut law = VonMises::new(elastic, yield_stress, hardening).map_err(refused)?;
                if let Some(r) = residual_yield_stress {
                    check("residual_yield_stress", r, (0.0..=yield_stress).contains(&r), "between 0 and yield_stress")?;
                    law = law.with_residual_yield_stress(r).map_err(refused)?;
                }
                Arc::new(law)
            }
            LawSpec::MohrCoulomb { cohesion, friction, dilation, tension_cutoff, softening, .. } => {
                check("friction", friction, (0.0..90.0).contains(&friction), "in [0, 90) degrees (0 is Tresca)")?;
                check(
                    "cohesion",
                    cohesion,
                    cohesion >= 0.0 && (cohesion > 0.0 || friction > 0.0),
                    "≥ 0, and > 0 when friction = 0",
                )?;
                check(
                    "dilation",
                    dilation,
                    (0.0..=friction).contains(&dilation),
                    "in [0, friction] degrees (= friction: associated flow)",
                )?;
                let mut law = MohrCoulomb::from_degrees(elastic, cohesion, friction, dilation).map_err(refused)?;
                if let Some(t) = tension_cutoff {
                    let apex = if friction > 0.0 { cohesion / friction.to_radians().tan() } else { f64::INFINITY };
                    check("tension_cutoff", t, t <= apex, "at most c cot φ (the apex of the cone)")?;
                    law = law.with_tension_cutoff(t).map_err(refused)?;
                }
                if let Some(sf) = softening {
                    law = law
                        .with_softening(sf.cohesion, sf.friction, sf.dilation, sf.plastic_strain)
                        .map_err(refused)?;
                }
                Arc::new(law)
            }
        })
    }

    /// The initial velocity field of body `i`.
    fn velocity_field<const D: usize>(
        &self,
        v: &VelocitySpec,
        i: usize,
    ) -> Result<impl Fn(&SVector<f64, D>) -> SVector<f64, D>, SceneError> {
        let at = [Seg::Key("bodies"), Seg::Index(i), Seg::Key("velocity")];
        let vec_d = |v: &[f64]| -> Result<SVector<f64, D>, SceneError> {
            if v.len() != D || v.iter().any(|x| !x.is_finite()) {
                return Err(self.error(&at, format!("body {i}: the velocity needs {D} finite components, got {v:?}")));
            }
            Ok(SVector::from_column_slice(v))
        };
        Ok(match v {
            VelocitySpec::Uniform(u) => {
                let u = vec_d(u)?;
                (u, 0usize, 0.0, 0.0)
            }
            VelocitySpec::Sine { amplitude, axis, wavelength, origin } => {
                let a = vec_d(amplitude)?;
                if axis.index() >= D {
                    return Err(
                        self.error(&at, format!("body {i}: the velocity's axis {axis:?} does not exist in {D}D"))
                    );
                }
                if !(wavelength.is_finite() && *wavelength > 0.0) {
                    return Err(
                        self.error(&at, format!("body {i}: the wavelength is {wavelength}; it must be positive"))
                    );
                }
                (a, axis.index(), 2.0 * std::f64::consts::PI / wavelength, *origin)
            }
        })
        .map(|(a, axis, k, origin)| {
            move |x: &SVector<f64, D>| if k == 0.0 { a } else { a * (k * (x[axis] - origin)).sin() }
        })
    }
}
