//! The loads and constraints part of a scene: gravity, and the plane constraints — rollers,
//! fixed planes and prescribed displacements, each on a plane of grid nodes, optionally
//! limited to a box.

use super::locate::Seg;
use super::{AnalysisSpec, Axis, ConstraintSpec, LoadedScene, RegionSpec, SceneError};
use loam_grid::Grid;
use loam_model::{InclinedRoller, PlaneConstraint};
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
                let (fixed, u) = self.prescribed::<D>(i, displacement)?;
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
        i: usize,
        displacement: &[Option<f64>],
    ) -> Result<([bool; 3], [f64; 3]), SceneError> {
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
        let at_w = |key| [Seg::Key("constraints"), Seg::Index(i), Seg::Key("within"), Seg::Key(key)];
        let lo = self.vector::<D>(&r.min, &at_w("min"), "within.min")?;
        let hi = self.vector::<D>(&r.max, &at_w("max"), "within.max")?;
        if let Some(k) = (0..D).find(|&k| k != constraint.axis && lo[k] > hi[k]) {
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
        Ok(constraint.within(min, max))
    }
}
