//! Points that come and go: a model's points removed (an excavation, material that left
//! the problem) or added (a construction stage) between steps, and the points of a saved
//! state put back whatever their number. Every per-point quantity the model keeps beside
//! its store — the carriers of the loads' vertices, the point forces — follows the points
//! by their stable ids ([`loam_points::PointId`]).

use crate::{check_materials, Kinematics, Model, ModelError, ModelState};
use loam_constitutive::ConstitutiveLaw;
use loam_points::{PointId, PointStore, Shape};
use nalgebra::{Matrix3, SVector};
use std::collections::HashMap;
use std::sync::Arc;

/// A model's points start unstrained: refused, naming the first, if one carries a stress or
/// a deformation.
pub(crate) fn check_unstrained<const D: usize>(points: &PointStore<D>) -> Result<(), ModelError> {
    let strained =
        |p: &usize| points.stress()[*p] != Matrix3::zeros() || points.deformation_gradient()[*p] != Matrix3::identity();
    match (0..points.len()).find(strained) {
        Some(p) => Err(ModelError::Prestrained(p)),
        None => Ok(()),
    }
}

/// Put every point's material state at its unstrained start: b^e = I (finite strain) or
/// ε^e = 0 (small strain), and its law's initial history (the longest of the laws' lengths
/// for every point).
pub(crate) fn start_unstrained<const D: usize>(
    points: &mut PointStore<D>,
    kinematics: Kinematics,
    materials: &[Arc<dyn ConstitutiveLaw>],
) {
    points.reset_elastic_strain(match kinematics {
        Kinematics::FiniteStrain => Matrix3::identity(),
        Kinematics::SmallStrain => Matrix3::zeros(),
    });
    let stride = materials.iter().map(|m| m.history_len()).max().unwrap_or(0);
    let material = points.material().to_vec();
    let unstressed = Matrix3::zeros();
    points.init_history(stride, |p, h| materials[material[p] as usize].init_history(h, &unstressed));
}

/// A change of a model's points between steps.
#[derive(Debug, Clone)]
pub enum PointChange<const D: usize> {
    /// Remove the points whose current place lies in the region ([`Model::remove_points_in`]).
    RemoveIn(Shape<D>),
    /// Remove the points with these ids ([`Model::remove_points_by_id`]).
    RemoveIds(Vec<PointId>),
    /// Add these points ([`Model::append_points`]).
    Append(Box<PointStore<D>>),
}

impl<const D: usize> Model<D> {
    /// Make `change` to the points; returns how many points it removed or added.
    pub fn change_points(&mut self, change: PointChange<D>) -> Result<usize, ModelError> {
        match change {
            PointChange::RemoveIn(region) => self.remove_points_in(&region),
            PointChange::RemoveIds(ids) => self.remove_points_by_id(&ids),
            PointChange::Append(points) => {
                let n = points.len();
                self.append_points(*points).map(|_| n)
            }
        }
    }

    /// Remove the points whose current place lies in `region` (an excavation); returns how
    /// many. Refused, and nothing changed, as [`Model::remove_points_by_id`] refuses.
    pub fn remove_points_in(&mut self, region: &Shape<D>) -> Result<usize, ModelError> {
        let marked: Vec<bool> = self.points.position().iter().map(|x| region.contains(x)).collect();
        self.remove_marked(&marked)
    }

    /// Remove the points with ids `ids` (ids of no point are ignored); returns how many.
    /// Refused, and nothing changed, on a body-fitted mesh (whose points are its Gauss
    /// points), when no point would be left, or when a removed point carries a load's
    /// vertex.
    pub fn remove_points_by_id(&mut self, ids: &[PointId]) -> Result<usize, ModelError> {
        let ids: std::collections::HashSet<PointId> = ids.iter().copied().collect();
        let marked: Vec<bool> = self.points.id().iter().map(|id| ids.contains(id)).collect();
        self.remove_marked(&marked)
    }

    fn remove_marked(&mut self, marked: &[bool]) -> Result<usize, ModelError> {
        let fail = |what: String| Err(ModelError::Removal(what));
        let removed = marked.iter().filter(|&&m| m).count();
        if removed == 0 {
            return Ok(0);
        }
        if self.background.moves_with_body() {
            return fail("the points of the updated Lagrangian FEM reference are its Gauss points".into());
        }
        if removed == marked.len() {
            return fail(format!("all {removed} points would go; a model keeps at least one"));
        }
        let kept = |p: usize| !marked[p];
        for (k, load) in self.loads.iter().enumerate() {
            if let Some(v) = load.dropped_carrier(|p| kept(p).then_some(p)) {
                let p = load.carriers()[v] as usize;
                return fail(format!(
                    "point {} (id {}) carries vertex {v} of load {k}; a load's surface must stay on the material",
                    p,
                    self.points.id()[p]
                ));
            }
        }
        let renumbering = self.points.retain(kept);
        for load in &mut self.loads {
            load.renumber_carriers(|p| renumbering.new_index(p));
        }
        if !self.point_forces.is_empty() {
            let mut p = 0;
            self.point_forces.retain(|_| {
                p += 1;
                kept(p - 1)
            });
        }
        tracing::info!(removed, left = self.points.len(), "points removed");
        Ok(removed)
    }

    /// Add `points`, unstrained and each of an existing material, after the model's (a
    /// construction stage): they get new ids, the start of every law's history and no
    /// point force; returns the index of the first. Refused on a body-fitted mesh.
    pub fn append_points(&mut self, mut points: PointStore<D>) -> Result<usize, ModelError> {
        let fail = |what: String| Err(ModelError::Append(what));
        if self.background.moves_with_body() {
            return fail("the points of the updated Lagrangian FEM reference are its Gauss points".into());
        }
        points.check()?;
        check_unstrained(&points)?;
        check_materials(&points, &self.materials)?;
        start_unstrained(&mut points, self.kinematics, &self.materials);
        if self.axisymmetric() {
            if let Some(p) = (0..points.len()).find(|&p| points.position()[p][0] <= 0.0) {
                return fail(format!(
                    "point {p} lies at radius {} ≤ 0; the points lie at x > 0",
                    points.position()[p][0]
                ));
            }
            points.revolve();
        }
        let first = self.points.append(&points)?;
        if !self.point_forces.is_empty() {
            self.point_forces.resize(self.points.len(), SVector::zeros());
        }
        Ok(first)
    }

    /// Put the model in `state`, saved from a model of the same scene (whose points may
    /// since have been removed or added): refused, and nothing changed, unless its points
    /// are valid, each of an existing material, with the laws' history layout, as many
    /// vertices per load, each load's carriers among them, and a mesh of as many nodes
    /// (none on a grid). The loads' carriers and the point forces follow the points by id.
    pub fn restore(&mut self, state: ModelState<D>) -> Result<(), ModelError> {
        let ModelState { points, load_vertices, mesh_nodes } = state;
        let fail = |what: String| Err(ModelError::Restore(what));
        points.check()?;
        check_materials(&points, &self.materials)?;
        let stride = self.points.history_stride();
        if points.history_stride() != stride {
            return fail(format!("the material history is not {stride} values per point"));
        }
        let saved: Vec<usize> = load_vertices.iter().map(Vec::len).collect();
        let model: Vec<usize> = self.loads.iter().map(|l| l.positions().len()).collect();
        if saved != model {
            return fail(format!("vertices per load {saved:?} saved, {model:?} in the model"));
        }
        let nodes = self.background.mesh().map(|m| m.num_nodes());
        if mesh_nodes.as_ref().map(Vec::len) != nodes {
            return fail(format!("mesh nodes {:?} saved, {nodes:?} in the model", mesh_nodes.as_ref().map(Vec::len)));
        }
        // This model's point p is the saved point with its id.
        let saved_index: HashMap<PointId, usize> = points.id().iter().enumerate().map(|(p, &id)| (id, p)).collect();
        let own_ids = self.points.id().to_vec();
        let new_index = |p: usize| saved_index.get(&own_ids[p]).copied();
        if let Some(k) = self.loads.iter().position(|l| l.dropped_carrier(new_index).is_some()) {
            return fail(format!("a point carrying a vertex of load {k} is not among the saved points"));
        }
        if let Some(x) = &mesh_nodes {
            self.background.set_mesh_positions(x);
        }
        for (load, x) in self.loads.iter_mut().zip(&load_vertices) {
            load.renumber_carriers(new_index);
            load.set_positions(x);
        }
        if !self.point_forces.is_empty() {
            let own_index: HashMap<PointId, usize> = own_ids.iter().enumerate().map(|(p, &id)| (id, p)).collect();
            let force = |id: &PointId| own_index.get(id).map_or(SVector::zeros(), |&p| self.point_forces[p]);
            self.point_forces = points.id().iter().map(force).collect();
        }
        self.points = points;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Load, TimeFunction};
    use loam_constitutive::{Elastic, VonMises};
    use loam_grid::{BasisKind, Grid};
    use nalgebra::Vector2;

    /// A 4 × 2-cell block of 2 × 2 points per cell (32 points, 1000 kg/m³, 0.25 m² each)
    /// on a 6 × 4 grid of 1 m cells, materials elastic (0) and von Mises (1, one history
    /// value), the right half of von Mises.
    fn block() -> Model<2> {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [6, 4]).unwrap();
        let mut points = PointStore::new();
        for (x0, material) in [(0.0, 0), (2.0, 1)] {
            let shape = Shape::Box { min: Vector2::new(x0, 0.0), max: Vector2::new(x0 + 2.0, 2.0) };
            points.fill(&grid, &shape, 2, 1000.0, material).unwrap();
        }
        let elastic = Elastic::new(1e5, 0.3).unwrap();
        let laws: Vec<Arc<dyn ConstitutiveLaw>> =
            vec![Arc::new(elastic), Arc::new(VonMises::new(elastic, 10.0, 0.0).unwrap())];
        Model::new(grid, BasisKind::Linear, Kinematics::FiniteStrain, points, laws, vec![], Vector2::zeros()).unwrap()
    }

    /// The points of a region go, the others keep their ids, state and order; the mass is
    /// that of the points left (24 of 0.25 m² at 1000 kg/m³ = 6000 kg per metre).
    #[test]
    fn a_region_is_removed_and_the_rest_kept() {
        let mut model = block();
        let top_right = Shape::Box { min: Vector2::new(2.0, 1.0), max: Vector2::new(4.0, 2.0) };
        assert_eq!(model.remove_points_in(&top_right).unwrap(), 8);
        let pts = model.points();
        assert_eq!(pts.len(), 24);
        assert!((pts.total_mass() - 6000.0).abs() < 1e-9);
        assert!(pts.position().iter().all(|x| !top_right.contains(x)));
        assert!(pts.id().windows(2).all(|w| w[0] < w[1]));
        assert_eq!(pts.history_values().len(), 24);
        assert_eq!(model.remove_points_by_id(&[0, 1, 999]).unwrap(), 2);
        assert_eq!(&model.points().id()[..2], &[2, 3]);
    }

    /// Removing every point, a load's carrier or a Gauss point of the FEM reference is
    /// refused and changes nothing.
    #[test]
    fn removals_that_would_break_the_model_are_refused() {
        let mut model = block();
        let everything = Shape::Box { min: Vector2::zeros(), max: Vector2::new(6.0, 4.0) };
        assert!(matches!(model.remove_points_in(&everything), Err(ModelError::Removal(_))));
        let force = Load::force(Vector2::new(0.25, 0.25), Vector2::new(0.0, -1.0), TimeFunction::Constant).unwrap();
        let mut loaded = block().with_loads(vec![force]).unwrap();
        let corner = Shape::Box { min: Vector2::zeros(), max: Vector2::new(0.5, 0.5) };
        let e = loaded.remove_points_in(&corner).unwrap_err();
        assert!(e.to_string().contains("carries vertex 0 of load 0"), "{e}");
        assert_eq!(loaded.points().len(), 32);
        // The carrier follows its point when others go.
        let right = Shape::Box { min: Vector2::new(2.0, 0.0), max: Vector2::new(4.0, 2.0) };
        assert_eq!(loaded.remove_points_in(&right).unwrap(), 16);
        assert_eq!(loaded.points().position()[loaded.loads()[0].carriers()[0] as usize], Vector2::new(0.25, 0.25));
        assert_eq!(model.points().len(), 32);
    }

    /// Appended points take new ids, the unstrained state of the kinematics (b^e = I) and
    /// their law's initial history; points already strained are refused.
    #[test]
    fn appended_points_start_unstrained_with_new_ids() {
        let mut model = block();
        model.remove_points_by_id(&[31]).unwrap();
        let mut more = PointStore::new();
        let shape = Shape::Box { min: Vector2::new(0.0, 2.0), max: Vector2::new(1.0, 3.0) };
        more.fill(model.grid(), &shape, 2, 500.0, 1).unwrap();
        assert_eq!(model.append_points(more.clone()).unwrap(), 31);
        let pts = model.points();
        assert_eq!(pts.len(), 35);
        assert_eq!(&pts.id()[31..], &[32, 33, 34, 35]);
        assert!(pts.elastic_strain()[31..].iter().all(|b| *b == Matrix3::identity()));
        assert_eq!(pts.history(34), &[0.0]);
        more.stress_mut()[0] = Matrix3::identity();
        assert!(matches!(model.append_points(more), Err(ModelError::Prestrained(0))));
        let mut unknown = PointStore::new();
        unknown.fill(model.grid(), &shape, 1, 500.0, 7).unwrap();
        assert!(matches!(model.append_points(unknown), Err(ModelError::MissingMaterial { material: 7, .. })));
    }

    /// A state saved after a removal is put back into a model built anew (all points): its
    /// points, and the loads' carriers by id.
    #[test]
    fn a_state_after_a_removal_restores_into_a_new_model() {
        let force = Load::force(Vector2::new(3.75, 1.75), Vector2::new(0.0, -1.0), TimeFunction::Constant).unwrap();
        let mut run = block().with_loads(vec![force]).unwrap();
        let carrier_id = run.points().id()[run.loads()[0].carriers()[0] as usize];
        run.remove_points_in(&Shape::Box { min: Vector2::zeros(), max: Vector2::new(2.0, 2.0) }).unwrap();
        let saved = ModelState {
            points: run.points().clone(),
            load_vertices: run.loads().iter().map(|l| l.positions().to_vec()).collect(),
            mesh_nodes: None,
        };
        let mut fresh = block().with_loads(vec![run.loads()[0].clone()]).unwrap();
        fresh.restore(saved).unwrap();
        assert_eq!(fresh.points().columns(), run.points().columns());
        assert_eq!(fresh.points().id()[fresh.loads()[0].carriers()[0] as usize], carrier_id);
        assert_eq!(fresh.loads()[0].carriers(), run.loads()[0].carriers());
    }
}
