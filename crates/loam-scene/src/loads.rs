//! The loads part of a scene: forces at points, and tractions and pressures on the part of
//! a body's boundary inside a box, each with its time function. The surface is the body's
//! shape's boundary cut into facets as fine as the body's points (docs/theory.md §17).

use super::locate::Seg;
use super::{AnalysisSpec, LoadSpec, LoadedScene, PressureSpec, RegionSpec, SceneError, TimeFunctionSpec};
use loam_grid::Grid;
use loam_model::{Load, TimeFunction};
use loam_points::Surface;
use nalgebra::SVector;

impl LoadedScene {
    /// The scene's loads, in order.
    pub(super) fn loads<const D: usize>(&self, grid: &Grid<D>) -> Result<Vec<Load<D>>, SceneError> {
        (self.scene.loads.iter().enumerate()).map(|(k, spec)| self.load(k, spec, grid)).collect()
    }

    /// Load `k`.
    fn load<const D: usize>(&self, k: usize, spec: &LoadSpec, grid: &Grid<D>) -> Result<Load<D>, SceneError> {
        let at = |key| [Seg::Key("loads"), Seg::Index(k), Seg::Key(key)];
        let load = match spec {
            LoadSpec::PointLoad { at: x, force, time } => {
                let x = self.vector::<D>(x, &at("at"), "at")?;
                self.in_a_body(k, &x)?;
                let force = self.vector::<D>(force, &at("force"), "force")?;
                Load::force(x, force, self.time_function(k, time)?)
            }
            LoadSpec::Traction { body, within, traction, time } => {
                let surface = self.loaded_surface(k, *body, within.as_ref(), grid)?;
                let traction = self.vector::<D>(traction, &at("traction"), "traction")?;
                Load::traction(surface, traction, self.time_function(k, time)?)
            }
            LoadSpec::Pressure { body, within, pressure, follower, time } => {
                let surface = self.loaded_surface(k, *body, within.as_ref(), grid)?;
                let values = self.pressures(k, pressure, &surface)?;
                Load::pressure(surface, values, *follower, self.time_function(k, time)?)
            }
        };
        load.map_err(|e| self.error(&[Seg::Key("loads"), Seg::Index(k)], format!("load {k}: {e}")))
    }

    /// Whether `x` lies inside (or on) one of the bodies' shapes.
    pub(super) fn in_some_body<const D: usize>(&self, x: &SVector<f64, D>) -> Result<bool, SceneError> {
        for (i, b) in self.scene.bodies.iter().enumerate() {
            if self.shape::<D>(i, b)?.contains(x) {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// A point load must act on the material: `x` inside (or on) one of the bodies.
    fn in_a_body<const D: usize>(&self, k: usize, x: &SVector<f64, D>) -> Result<(), SceneError> {
        if self.in_some_body(x)? {
            return Ok(());
        }
        Err(self.error(&[Seg::Key("loads"), Seg::Index(k), Seg::Key("at")], format!(
            "load {k}: the point {:?} lies in no body; a point load acts on the material, so `at` must lie inside or on a body's shape",
            x.as_slice()
        )))
    }

    /// The boundary of body `body` inside the box `within` (all of it without one), facets
    /// as fine as the body's points.
    fn loaded_surface<const D: usize>(
        &self,
        k: usize,
        body: usize,
        within: Option<&RegionSpec>,
        grid: &Grid<D>,
    ) -> Result<Surface<D>, SceneError> {
        let here = [Seg::Key("loads"), Seg::Index(k)];
        let bodies = &self.scene.bodies;
        let Some(b) = bodies.get(body) else {
            return Err(
                self.error(&here, format!("load {k} is on body {body}, but the scene has bodies 0..{}", bodies.len()))
            );
        };
        let shape = self.shape::<D>(body, b)?;
        let spacing = grid.cell_size().min() / b.points_per_cell.max(1) as f64;
        let boundary = shape.boundary(spacing).map_err(|e| self.error(&here, format!("load {k}: {e}")))?;
        let Some(r) = within else {
            return Ok(boundary);
        };
        let at_w = |key| [Seg::Key("loads"), Seg::Index(k), Seg::Key("within"), Seg::Key(key)];
        let lo = self.vector::<D>(&r.min, &at_w("min"), "within.min")?;
        let hi = self.vector::<D>(&r.max, &at_w("max"), "within.max")?;
        if let Some(a) = (0..D).find(|&a| lo[a] > hi[a]) {
            return Err(self.error(
                &at_w("min"),
                format!("load {k}: within.min[{a}] = {} exceeds within.max[{a}] = {}", lo[a], hi[a]),
            ));
        }
        let tol = grid.cell_size() * 1e-9;
        let part = boundary.select(|c| (0..D).all(|a| c[a] >= lo[a] - tol[a] && c[a] <= hi[a] + tol[a]));
        if part.facets.is_empty() {
            return Err(self.error(&[Seg::Key("loads"), Seg::Index(k), Seg::Key("within")], format!(
                "load {k}: the box {:?} to {:?} holds no part of body {body}'s boundary; a box must contain the middle of the loaded boundary segments (e.g. a thin box around the loaded face)",
                lo.as_slice(), hi.as_slice()
            )));
        }
        Ok(part)
    }

    /// The pressure of load `k` at every vertex of `surface`.
    fn pressures<const D: usize>(
        &self,
        k: usize,
        spec: &PressureSpec,
        surface: &Surface<D>,
    ) -> Result<Vec<f64>, SceneError> {
        let at = |key| [Seg::Key("loads"), Seg::Index(k), Seg::Key("pressure"), Seg::Key(key)];
        let invalid = |what: &str| {
            self.error(
                &[Seg::Key("loads"), Seg::Index(k), Seg::Key("pressure")],
                format!("load {k}: {what} must be finite"),
            )
        };
        let xs = &surface.vertices;
        match spec {
            PressureSpec::Uniform(p) if p.is_finite() => Ok(vec![*p; xs.len()]),
            PressureSpec::Uniform(_) => Err(invalid("the pressure")),
            PressureSpec::Linear { value, at: x0, gradient } => {
                if !value.is_finite() {
                    return Err(invalid("the value"));
                }
                let x0 = self.vector::<D>(x0, &at("at"), "at")?;
                let g = self.vector::<D>(gradient, &at("gradient"), "gradient")?;
                Ok(xs.iter().map(|x| value + g.dot(&(x - x0))).collect())
            }
            PressureSpec::Hydrostatic { level, unit_weight } if level.is_finite() && unit_weight.is_finite() => {
                Ok(xs.iter().map(|x| unit_weight * (level - x[D - 1]).max(0.0)).collect())
            }
            PressureSpec::Hydrostatic { .. } => Err(invalid("the level and unit weight")),
        }
    }

    /// The time function of load `k`: only dynamic and explicit analyses have time; a
    /// quasi-static one applies every load with its load factor.
    fn time_function(&self, k: usize, spec: &TimeFunctionSpec) -> Result<TimeFunction, SceneError> {
        let here = [Seg::Key("loads"), Seg::Index(k), Seg::Key("time")];
        if !matches!(spec, TimeFunctionSpec::Constant)
            && matches!(self.scene.analysis, AnalysisSpec::QuasiStatic { .. })
        {
            return Err(self.error(&here, format!(
                "load {k} has a time function, but a QuasiStatic analysis applies every load with its load factor (0 to 1 over the load steps); remove `time`"
            )));
        }
        self.time_function_at(&here, &format!("load {k}"), spec)
    }

    /// The time function `spec` of `who`, checked, an error at `here`.
    pub(super) fn time_function_at(
        &self,
        here: &[Seg],
        who: &str,
        spec: &TimeFunctionSpec,
    ) -> Result<TimeFunction, SceneError> {
        let f = match spec {
            TimeFunctionSpec::Constant => return Ok(TimeFunction::Constant),
            TimeFunctionSpec::Ramp { duration } => TimeFunction::Ramp { duration: *duration },
            TimeFunctionSpec::Table(rows) => TimeFunction::Table(rows.clone()),
        };
        f.check().map_err(|e| self.error(here, format!("{who}: time function: {e}")))?;
        Ok(f)
    }
}
