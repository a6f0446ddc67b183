//! The loads and constraints part of a scene: gravity, the plane constraints — rollers,
//! fixed planes and prescribed displacements, each on a plane of grid nodes, optionally
//! limited to a box — the rollers on inclined planes, and the constraints on named bodies.

use super::locate::Seg;
use super::{AnalysisSpec, Axis, BodyConstraintSpec, ConstraintSpec, LoadedScene, RegionSpec, SceneError};
use loam_grid::Grid;
use loam_model::{BodyConstraint, FrictionalPlane, InclinedRoller, Model, ModelError, PlaneConstraint, RigidBody};
use nalgebra::SVector;

impl LoadedScene {
    /// Body force per unit mass at full load.
    pub(super) fn gravity<const D: usize>(&self) -> Result<SVector<f64, D>, SceneError> {
        self.vector(&self.scene.gravity, &[Seg::Key("gravity")], "gravity")
    }

    /// The constraints in order; a prescribed displacement only where the analysis applies
    /// it (quasi-static).
    pub(super) fn constraints<const D: usize>(&self, grid: &Grid<D>) -> Result<Vec<PlaneConstraint>, SceneError> {
        let constraints = (self.scene.constraints.iter().enumerate())
            .map(|(i, c)| self.constraint(i, c, grid))
            .collect::<Result<Vec<_>, _>>()?;
        if let Some(index) = constraints.iter().position(|c| c.is_displaced()) {
            let analysis = match self.scene.analysis {
                AnalysisSpec::QuasiStatic { .. } => return Ok(constraints),
                AnalysisSpec::Explicit { .. } => "Explicit",
                AnalysisSpec::ImplicitDynamic { .. } => "ImplicitDynamic",
            };
            return Err(self.error(&[Seg::Key("constraints"), Seg::Index(index)], format!(
                "constraint {index} prescribes a displacement, which follows the load factor of a QuasiStatic analysis; the {analysis} analysis does not apply it"
            )));
        }
        Ok(constraints)
    }

    /// The rollers on inclined planes, each at its place in the file.
    pub(super) fn inclined_rollers<const D: usize>(&self) -> Result<Vec<InclinedRoller<D>>, SceneError> {
        (self.scene.inclined_rollers.iter().enumerate())
            .map(|(k, r)| {
                let at = |key| [Seg::Key("inclined_rollers"), Seg::Index(k), Seg::Key(key)];
                let point = self.vector(&r.point, &at("point"), "an inclined roller's point")?;
                let normal = self.vector(&r.normal, &at("normal"), "an inclined roller's normal")?;
                InclinedRoller::new(point, normal)
                    .map_err(|e| self.error(&at("normal"), format!("inclined roller {k}: {e}")))
            })
            .collect()
    }

    /// The model with the frictional planes, each checked at its place in the file, the
    /// contact between bodies and the rigid bodies.
    pub(super) fn with_frictional_planes<const D: usize>(&self, model: Model<D>) -> Result<Model<D>, SceneError> {
        let key = |k| [Seg::Key("frictional_planes"), Seg::Index(k)];
        let planes = (self.scene.frictional_planes.iter().enumerate())
            .map(|(k, f)| {
                let at = |field| [Seg::Key("frictional_planes"), Seg::Index(k), Seg::Key(field)];
                let point = self.vector(&f.point, &at("point"), "a frictional plane's point")?;
                let normal = self.vector(&f.normal, &at("normal"), "a frictional plane's normal")?;
                let field = if f.friction.is_finite() && f.friction >= 0.0 { "normal" } else { "friction" };
                FrictionalPlane::new(point, normal, f.friction)
                    .map_err(|e| self.error(&at(field), format!("frictional plane {k}: {e}")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let model = model.with_frictional_planes(planes).map_err(|e| match e {
            ModelError::FrictionalPlane { index, .. } => self.error(&key(index), e.to_string()),
            _ => self.error(&[Seg::Key("frictional_planes")], e.to_string()),
        })?;
        match &self.scene.body_contact {
            Some(contact) => {
                // A bad coefficient is the friction's fault; loads or body constraints beside
                // contact are the key's.
                let valid = contact.friction.is_finite() && contact.friction >= 0.0;
                let at: &[Seg] =
                    if valid { &[Seg::Key("body_contact")] } else { &[Seg::Key("body_contact"), Seg::Key("friction")] };
                let model = model.with_body_contact(contact.friction).map_err(|e| self.error(at, e.to_string()))?;
                self.with_rigid_bodies(model)
            }
            None => self.with_rigid_bodies(model),
        }
    }

    /// The constraints on bodies, each body found by its name; a prescribed displacement
    /// is checked against the analysis by the model's table of options.
    pub(super) fn body_constraints<const D: usize>(&self) -> Result<Vec<BodyConstraint>, SceneError> {
        (self.scene.body_constraints.iter().enumerate()).map(|(k, c)| self.body_constraint::<D>(k, c)).collect()
    }

    /// Body constraint `k`.
    fn body_constraint<const D: usize>(&self, k: usize, c: &BodyConstraintSpec) -> Result<BodyConstraint, SceneError> {
        let (name, within) = match c {
            BodyConstraintSpec::Fixed { body, within } | BodyConstraintSpec::Displacement { body, within, .. } => {
                (body, within)
            }
        };
        let at = [Seg::Key("body_constraints"), Seg::Index(k), Seg::Key("body")];
        let body = self.body_named(name, &at, &format!("body constraint {k}"))?;
        let constraint = match c {
            BodyConstraintSpec::Fixed { .. } => BodyConstraint::new(body as u32, [true; 3]),
            BodyConstraintSpec::Displacement { displacement, .. } => {
                let (fixed, u) = self.prescribed::<D>(("body_constraints", k), displacement)?;
                BodyConstraint::new(body as u32, fixed).displaced(u)
            }
        };
        match within {
            None => Ok(constraint),
            Some(r) => {
                let (min, max) = self.region_box::<D>(("body_constraints", k), r, None)?;
                Ok(constraint.within(min, max))
            }
        }
    }

    /// The index of the body called `name`, or an error at `at` saying what `who` named.
    fn body_named(&self, name: &str, at: &[Seg], who: &str) -> Result<usize, SceneError> {
        let bodies = &self.scene.bodies;
        bodies.iter().position(|b| !name.is_empty() && b.name == name).ok_or_else(|| {
            let names: Vec<&str> = bodies.iter().map(|b| b.name.as_str()).filter(|n| !n.is_empty()).collect();
            self.error(at, format!(
                "{who} names body \"{name}\", but no body is called that; named bodies: {names:?} (name one with name: \"{name}\")"
            ))
        })
    }

    /// The model with the rigid bodies, each checked at its place in the file.
    fn with_rigid_bodies<const D: usize>(&self, model: Model<D>) -> Result<Model<D>, SceneError> {
        let rigid = (self.scene.rigid_bodies.iter().enumerate())
            .map(|(k, r)| {
                let at = |field| [Seg::Key("rigid_bodies"), Seg::Index(k), Seg::Key(field)];
                let body = self.body_named(&r.body, &at("body"), &format!("rigid body {k}"))?;
                let velocity = self.vector(&r.velocity, &at("velocity"), "a rigid body's velocity")?;
                let field = if r.friction.is_finite() && r.friction >= 0.0 { "velocity" } else { "friction" };
                let time = self.time_function_at(&at("time"), &format!("rigid body {k}"), &r.time)?;
                let rigid = RigidBody::new(body as u32, velocity, r.friction)
                    .map_err(|e| self.error(&at(field), format!("rigid body {k}: {e}")))?;
                Ok(rigid.in_time(time).expect("a checked time function"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let model = model.with_rigid_bodies(rigid).map_err(|e| match e {
            ModelError::RigidBody { index, .. } => {
                self.error(&[Seg::Key("rigid_bodies"), Seg::Index(index)], e.to_string())
            }
            _ => self.error(&[Seg::Key("rigid_bodies")], e.to_string()),
        })?;
        for (k, r) in model.rigid_bodies().iter().enumerate() {
            self.check_rigid_body_clear(&model, k, r)?;
        }
        Ok(model)
    }

    /// Rigid body `k` must start clear of the other bodies (no point of theirs inside its
    /// shape: contact needs them apart, and `may_overlap` would let them through), and its
    /// points, with their domains, must stay inside the grid over the run.
    fn check_rigid_body_clear<const D: usize>(
        &self,
        model: &Model<D>,
        k: usize,
        rigid: &RigidBody<D>,
    ) -> Result<(), SceneError> {
        let at = [Seg::Key("rigid_bodies"), Seg::Index(k), Seg::Key("body")];
        let b = rigid.body() as usize;
        let shape = self.shape::<D>(b, &self.scene.bodies[b])?;
        let pts = model.points();
        let show =
            |v: &SVector<f64, D>| format!("{:?}", v.iter().map(|c| (c * 1e6).round() / 1e6 + 0.0).collect::<Vec<_>>());
        let inside = (0..pts.len()).find(|&p| pts.body()[p] != rigid.body() && shape.contains(&pts.position()[p]));
        if let Some(p) = inside {
            let other = &self.scene.bodies[pts.body()[p] as usize];
            return Err(self.error(&at, format!(
                "rigid body {k} (body \"{}\") overlaps body \"{}\": its shape holds that body's point at {}; a rigid body must start clear of the material it meets (move one of them)",
                self.scene.bodies[b].name, other.name, show(&pts.position()[p])
            )));
        }
        let AnalysisSpec::Explicit { duration, .. } = self.scene.analysis else { return Ok(()) };
        let (lo, hi) = rigid.displacement_range(duration);
        let grid = model.grid();
        let (min, max) = (grid.origin(), grid.extent_max());
        // A domain that ends on the grid's edge is inside it (to round-off).
        let tol = 1e-9 * grid.cell_size().max();
        let leaves = (0..pts.len()).filter(|&p| pts.body()[p] == rigid.body()).find_map(|p| {
            let (x, l) = (pts.position()[p], pts.half_length()[p]);
            let out = |a: usize| x[a] - l[a] + lo[a] < min[a] - tol || x[a] + l[a] + hi[a] > max[a] + tol;
            (0..D).find(|&a| out(a)).map(|a| (p, a))
        });
        match leaves {
            Some((p, a)) => Err(self.error(&at, format!(
                "rigid body {k} (body \"{}\") leaves the grid during the run: its displacement over the {duration} s ranges from {} to {}, which takes its point at {} beyond the grid's {} to {} along axis {a}; enlarge the grid, or shorten the run or the motion",
                self.scene.bodies[b].name, show(&lo), show(&hi), show(&pts.position()[p]), min[a], max[a]
            ))),
            None => Ok(()),
        }
    }

    /// Constraint `i`, on a plane of grid nodes.
    fn constraint<const D: usize>(
        &self,
        i: usize,
        c: &ConstraintSpec,
        grid: &Grid<D>,
    ) -> Result<PlaneConstraint, SceneError> {
        let (axis, at, within) = match c {
            ConstraintSpec::Roller { axis, at, within }
            | ConstraintSpec::Fixed { axis, at, within }
            | ConstraintSpec::Displacement { axis, at, within, .. } => (*axis, *at, within),
        };
        let (a, plane) = self.node_plane(i, axis, at, grid)?;
        let constraint = match c {
            ConstraintSpec::Roller { .. } => {
                let mut fixed = [false; 3];
                fixed[a] = true;
                PlaneConstraint::new(a, plane, fixed)
            }
            ConstraintSpec::Fixed { .. } => PlaneConstraint::new(a, plane, [true; 3]),
            ConstraintSpec::Displacement { displacement, .. } => {
                let (fixed, u) = self.prescribed::<D>(("constraints", i), displacement)?;
                PlaneConstraint::new(a, plane, fixed).displaced(u)
            }
        };
        match within {
            None => Ok(constraint),
            Some(r) => self.within::<D>(i, r, constraint),
        }
    }

    /// The axis index of constraint `i` and the index of its node plane `axis = at`; the
    /// axis must exist in `D` dimensions and `at` must lie on a plane of grid nodes.
    fn node_plane<const D: usize>(
        &self,
        i: usize,
        axis: Axis,
        at: f64,
        grid: &Grid<D>,
    ) -> Result<(usize, usize), SceneError> {
        let here = [Seg::Key("constraints"), Seg::Index(i)];
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
        Ok((a, plane))
    }

    /// Which components constraint `i` prescribes, and their displacements at full load:
    /// `D` entries, `Some(u)` (finite) prescribed or `None` free, at least one `Some`.
    fn prescribed<const D: usize>(
        &self,
        (list, i): (&'static str, usize),
        displacement: &[Option<f64>],
    ) -> Result<([bool; 3], [f64; 3]), SceneError> {
        if displacement.len() != D
            || displacement.iter().flatten().any(|u| !u.is_finite())
            || displacement.iter().all(Option::is_none)
        {
            return Err(self.error(&[Seg::Key(list), Seg::Index(i), Seg::Key("displacement")], format!(
                "{} {i}: displacement needs {D} entries, Some(u) (finite) for a prescribed component or None for a free one, at least one Some; got {displacement:?}",
                label(list)
            )));
        }
        let mut fixed = [false; 3];
        let mut u = [0.0; 3];
        for (k, d) in displacement.iter().enumerate() {
            fixed[k] = d.is_some();
            u[k] = d.unwrap_or(0.0);
        }
        Ok((fixed, u))
    }

    /// `constraint` limited to the box `r`, whose bounds must be ordered on every axis but
    /// the plane's own.
    fn within<const D: usize>(
        &self,
        i: usize,
        r: &RegionSpec,
        constraint: PlaneConstraint,
    ) -> Result<PlaneConstraint, SceneError> {
        let (min, max) = self.region_box::<D>(("constraints", i), r, Some(constraint.axis))?;
        Ok(constraint.within(min, max))
    }

    /// The box `r` of entry `i` of the list `list` as bounds on three axes (unbounded on
    /// those beyond `D`); its bounds must be finite and ordered on every axis but `skip`.
    fn region_box<const D: usize>(
        &self,
        (list, i): (&'static str, usize),
        r: &RegionSpec,
        skip: Option<usize>,
    ) -> Result<([f64; 3], [f64; 3]), SceneError> {
        let at_w = |key| [Seg::Key(list), Seg::Index(i), Seg::Key("within"), Seg::Key(key)];
        let lo = self.vector::<D>(&r.min, &at_w("min"), "within.min")?;
        let hi = self.vector::<D>(&r.max, &at_w("max"), "within.max")?;
        if let Some(k) = (0..D).find(|&k| Some(k) != skip && lo[k] > hi[k]) {
            return Err(self.error(
                &at_w("min"),
                format!("{} {i}: within.min[{k}] = {} exceeds within.max[{k}] = {}", label(list), lo[k], hi[k]),
            ));
        }
        let mut min = [f64::NEG_INFINITY; 3];
        let mut max = [f64::INFINITY; 3];
        for k in 0..D {
            min[k] = lo[k];
            max[k] = hi[k];
        }
        Ok((min, max))
    }
}

/// How a message names an entry of the list `list`: "constraint", "body constraint".
fn label(list: &str) -> String {
    list.trim_end_matches('s').replace('_', " ")
}
