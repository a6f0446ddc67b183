//! What a run is made of: the background (grid and basis, or the body-fitted mesh of the
//! FEM reference), the points and their materials, the kinematics, the constraints on
//! grid planes and the loads. The implicit and explicit analyses both take a [`Model`];
//! quantities that do not depend on the integrator (constrained dofs, stored energy,
//! external work of dead loads) live here once.
//!
//! A model keeps its invariants: every point's material exists, every constraint lies on
//! a plane of the grid, point forces match the points. Its fields are private, checked by
//! the constructors, and the analyses change the points' evolving state only through
//! [`PointsMut`], which cannot add points or reassign their materials.

mod axisymmetry;
mod body_constraints;
mod constraint;
mod energy;
mod geostatic;
mod loads;
mod options;
mod population;
mod rigid;
mod rigid_bodies;
mod water;

pub use constraint::{BodyConstraint, FrictionalPlane, InclinedRoller, PlaneConstraint};
pub use energy::ExternalWork;
pub use loads::{Load, LoadKind, LoadLevel, TimeFunction};
pub use options::{AnalysisKind, ModelOption, Unaccepted};
pub use population::PointChange;
pub use rigid::{FreeBody, RigidMode};
pub use rigid_bodies::{RigidBody, MAX_RIGID_BODY_ID};
pub use water::{PhreaticLevel, Water};

use loam_constitutive::{ConstitutiveLaw, MaterialState};
use loam_grid::{ActiveNodes, Background, BasisKind, Connectivity, FeMesh, Grid, NodeField, NodeLayout};
use loam_points::{PointStore, PointsError};
pub use loam_points::{PointsMut, StateFields};
use nalgebra::SVector;
use std::sync::Arc;

/// Kinematics of the step update (docs/theory.md §2 and §3): one pipeline, two strain
/// measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kinematics {
    /// Linearised strain increments sym(∇Δu) on the start-of-step configuration; stress
    /// from the law at ε^e. Points still move (updated Lagrangian).
    SmallStrain,
    /// Multiplicative finite strain: logarithmic elastic strain, Kirchhoff stress, spatial
    /// tangent with the geometric (initial-stress) term of the seed paper's eq. (7).
    FiniteStrain,
}

/// Treatment of volumetric locking (near-incompressible elastic or plastic flow).
/// B-bar and assumed strain are small strain, F-bar finite strain; all three need the
/// linear basis or the FEM mesh, where all points of a cell share its nodes so that the
/// cell averages add no couplings.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum AntiLocking {
    /// The plain formulation: every point's own strain (full integration).
    #[default]
    None,
    /// B-bar (Hughes 1980): each point's dilatation is replaced by the volume average over
    /// the points of its cell (its element in the FEM reference), the deviatoric strain
    /// kept. Enough for incompressible (von Mises, Tresca) flow; dilatant (frictional,
    /// associated) flow still locks, because it ties the cell's dilatation to each point's
    /// own shear.
    BBar,
    /// Assumed strain: every component of a point's strain is the volume average over its
    /// cell (one-point quadrature, which leaves dilatant flow one constraint per cell),
    /// plus `stabilization` (0 < β ≤ 1) times the point's own deviatoric deviation from that
    /// average, which holds the cell's hourglass modes with β² of their stiffness
    /// (docs/theory.md §13; β = 1 is B-bar). A variational strain operator: residual and
    /// tangent stay consistent.
    AssumedStrain { stabilization: f64 },
    /// F-bar (de Souza Neto et al. 1996), finite strain: each point's increment of
    /// deformation ΔF is scaled to the volume change ΔJ̄ of its cell, the volume-weighted
    /// average of its points' det ΔF (ΔF̄ = (ΔJ̄ / ΔJ)^{1/3} ΔF; the in-plane part with the
    /// exponent ½ in plane strain), its isochoric part kept. Not variational: the tangent is
    /// not symmetric (docs/theory.md §13).
    FBar,
}

impl AntiLocking {
    /// The weight β of each point's own deviatoric strain beside its cell's average, or
    /// `None` without cell averaging.
    pub fn deviatoric_weight(&self) -> Option<f64> {
        match *self {
            AntiLocking::None | AntiLocking::FBar => None,
            AntiLocking::BBar => Some(1.0),
            AntiLocking::AssumedStrain { stabilization } => Some(stabilization),
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            AntiLocking::None => "none",
            AntiLocking::BBar => "B-bar",
            AntiLocking::AssumedStrain { .. } => "assumed strain",
            AntiLocking::FBar => "F-bar",
        }
    }
}

/// Errors in assembling a model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    #[error("the model has no material points")]
    NoPoints,
    #[error("material points: {0}")]
    Points(#[from] PointsError),
    #[error("point {0} starts with a stress or a deformation; a model starts unstrained (give a geostatic initial stress with Model::geostatic_stress)")]
    Prestrained(usize),
    #[error("constraint {index}: its {what} must be finite")]
    ConstraintValue { index: usize, what: &'static str },
    #[error("point {point} uses material {material}, but only {count} materials are defined")]
    MissingMaterial { point: usize, material: u32, count: usize },
    #[error("constraint {index} is on axis {axis}, but a {dimension}D model has axes 0..{dimension}")]
    ConstraintAxis { index: usize, axis: usize, dimension: usize },
    #[error("constraint {index} is on plane {plane} of axis {axis}, but that axis has planes 0..={max}")]
    ConstraintPlane { index: usize, axis: usize, plane: usize, max: usize },
    #[error("mesh block {block} has no density or material ({densities} densities, {materials} materials given)")]
    MeshBlock { block: usize, densities: usize, materials: usize },
    #[error("mesh block {block} has density {value}; it must be a positive number")]
    Density { block: usize, value: f64 },
    #[error("{0}")]
    AntiLocking(String),
    #[error("geostatic initial stress: {0}")]
    Geostatic(String),
    #[error("gravity component {axis} is {value}; it must be finite")]
    Gravity { axis: usize, value: f64 },
    #[error("point forces: {0}")]
    PointForces(String),
    #[error("load {index}: {what}")]
    Load { index: usize, what: String },
    #[error("water: {0}")]
    Water(String),
    #[error("materials: {0}")]
    Materials(String),
    #[error("ghost penalty: {0}")]
    GhostPenalty(String),
    #[error("geometrically linear analysis: {0}")]
    GeometricallyLinear(String),
    #[error("the saved state does not fit this model: {0}")]
    Restore(String),
    #[error("body constraint {index}: {what}")]
    BodyConstraint { index: usize, what: String },
    #[error("inclined roller: {0}")]
    InclinedRoller(String),
    #[error("body contact: {0}")]
    BodyContact(String),
    #[error("rigid body {index}: {what}")]
    RigidBody { index: usize, what: String },
    #[error("frictional plane {index}: {what}")]
    FrictionalPlane { index: usize, what: String },
    #[error("removing points: {0}")]
    Removal(String),
    #[error("adding points: {0}")]
    Append(String),
    #[error("basis: {0}")]
    Basis(String),
    #[error("axisymmetry: {0}")]
    Axisymmetry(String),
}

/// What an analysis changes in a model as it advances: the points' state, the places of
/// the loads' vertices and the nodes of a body-fitted mesh. With the analysis's own
/// counters it is all a checkpoint needs to go on (everything else is rebuilt from the
/// scene).
#[derive(Debug, Clone)]
pub struct ModelState<const D: usize> {
    pub points: PointStore<D>,
    /// Per load, its vertices' current places.
    pub load_vertices: Vec<Vec<SVector<f64, D>>>,
    /// The nodes of the body-fitted mesh (FEM reference); `None` on a grid.
    pub mesh_nodes: Option<Vec<SVector<f64, D>>>,
}

/// A complete MPM model. Build it, then hand it to an analysis.
#[derive(Debug, Clone)]
pub struct Model<const D: usize> {
    background: Background<D>,
    kinematics: Kinematics,
    points: PointStore<D>,
    materials: Vec<Arc<dyn ConstitutiveLaw>>,
    constraints: Vec<PlaneConstraint>,
    /// Rollers on inclined planes, held in a local frame at the nodes.
    inclined: Vec<InclinedRoller<D>>,
    /// Rigid planes with Coulomb friction that the material may leave.
    frictional: Vec<FrictionalPlane<D>>,
    /// Bodies in frictional contact with each other, each moving with its own nodal
    /// velocities (the Coulomb coefficient between them), or bonded where they meet.
    body_contact: Option<f64>,
    /// Bodies moved as rigid wholes at a prescribed velocity.
    rigid_bodies: Vec<RigidBody<D>>,
    /// Constraints on the nodes bodies' points reach.
    body_constraints: Vec<BodyConstraint>,
    /// Body force per unit mass at full load.
    gravity: SVector<f64, D>,
    /// Force on each point at full load (empty: none).
    point_forces: Vec<SVector<f64, D>>,
    /// Forces at points, tractions and pressures on surfaces.
    loads: Vec<Load<D>>,
    /// Static groundwater: the points' pore pressures.
    water: Option<Water>,
    anti_locking: AntiLocking,
    /// Gravity acts in full from the start (the points carry a geostatic initial stress).
    gravity_preloaded: bool,
    ghost_penalty: Option<f64>,
    geometrically_linear: bool,
    axisymmetric: bool,
}

impl<const D: usize> Model<D> {
    /// Check the model and put every point's material state at its unstrained start:
    /// b^e = I (finite strain) or ε^e = 0 (small strain), and the law's initial history.
    pub fn new(
        grid: Grid<D>,
        basis: BasisKind,
        kinematics: Kinematics,
        points: PointStore<D>,
        materials: Vec<Arc<dyn ConstitutiveLaw>>,
        constraints: Vec<PlaneConstraint>,
        gravity: SVector<f64, D>,
    ) -> Result<Self, ModelError> {
        Self::on(Background::on_grid(grid, basis), kinematics, points, materials, constraints, gravity)
    }

    /// The model on any background: every index checked before it is used.
    fn on(
        background: Background<D>,
        kinematics: Kinematics,
        mut points: PointStore<D>,
        materials: Vec<Arc<dyn ConstitutiveLaw>>,
        constraints: Vec<PlaneConstraint>,
        gravity: SVector<f64, D>,
    ) -> Result<Self, ModelError> {
        if points.is_empty() {
            return Err(ModelError::NoPoints);
        }
        points.check()?;
        population::check_unstrained(&points)?;
        check_materials(&points, &materials)?;
        check_constraints(background.grid(), &constraints)?;
        if let Some(axis) = (0..D).find(|&a| !gravity[a].is_finite()) {
            return Err(ModelError::Gravity { axis, value: gravity[axis] });
        }
        population::start_unstrained(&mut points, kinematics, &materials);
        Ok(Self {
            background,
            kinematics,
            points,
            materials,
            constraints,
            inclined: Vec::new(),
            frictional: Vec::new(),
            body_contact: None,
            rigid_bodies: Vec::new(),
            body_constraints: Vec::new(),
            gravity,
            point_forces: Vec::new(),
            loads: Vec::new(),
            water: None,
            anti_locking: AntiLocking::None,
            gravity_preloaded: false,
            ghost_penalty: None,
            geometrically_linear: false,
            axisymmetric: false,
        })
    }

    /// The updated Lagrangian FEM reference on the same grid planes, laws and loads: the
    /// points are the Gauss points of `mesh` (volume det J · w, mass ρ of their element's
    /// block times that volume, material of the block), the nodes are the mesh's, and the
    /// mesh moves with the body and is never reset. `density[b]` and `material[b]` belong
    /// to block b. Constraints on grid planes hold the mesh nodes that start on them; the
    /// grid serves only to place those planes.
    #[allow(clippy::too_many_arguments)]
    pub fn updated_lagrangian_fem(
        grid: Grid<D>,
        kinematics: Kinematics,
        mesh: FeMesh<D>,
        density: &[f64],
        material: &[u32],
        materials: Vec<Arc<dyn ConstitutiveLaw>>,
        constraints: Vec<PlaneConstraint>,
        gravity: SVector<f64, D>,
    ) -> Result<Self, ModelError> {
        let per = mesh.gauss_per_element();
        let mut points = PointStore::new();
        for (p, (x, volume)) in mesh.gauss_points().into_iter().enumerate() {
            let b = mesh.element_block(p / per);
            let (Some(&rho), Some(&m)) = (density.get(b), material.get(b)) else {
                return Err(ModelError::MeshBlock { block: b, densities: density.len(), materials: material.len() });
            };
            if !(rho.is_finite() && rho > 0.0) {
                return Err(ModelError::Density { block: b, value: rho });
            }
            points.push(x, volume, rho, SVector::zeros(), m);
            points.assign_body(p..p + 1, b as u32);
        }
        Self::on(Background::body_fitted(grid, mesh), kinematics, points, materials, constraints, gravity)
    }

    /// The same model with other laws for its materials (one per material, each with the
    /// history length of the one it replaces), the points' state kept: strength
    /// reduction's reduced strengths.
    pub fn with_materials(&self, materials: Vec<Arc<dyn ConstitutiveLaw>>) -> Result<Self, ModelError> {
        let mut model = self.clone();
        model.set_materials(materials)?;
        Ok(model)
    }

    /// [`Model::with_materials`] in place: a strength-reduction search that lowers the
    /// strength of the state it holds. Refused (and nothing changed) unless there is one
    /// law per material, each with the history length of the one it replaces.
    pub fn set_materials(&mut self, materials: Vec<Arc<dyn ConstitutiveLaw>>) -> Result<(), ModelError> {
        if materials.len() != self.materials.len() {
            return Err(ModelError::Materials(format!(
                "{} laws given for {} materials",
                materials.len(),
                self.materials.len()
            )));
        }
        if let Some(m) = (0..materials.len()).find(|&m| materials[m].history_len() != self.materials[m].history_len()) {
            return Err(ModelError::Materials(format!(
                "material {m}: the new law keeps {} history values, the old one {}",
                materials[m].history_len(),
                self.materials[m].history_len()
            )));
        }
        self.materials = materials;
        Ok(())
    }

    /// Dead forces on the points at full load, one per point, following the load factor.
    pub fn with_point_forces(mut self, forces: Vec<SVector<f64, D>>) -> Result<Self, ModelError> {
        if forces.len() != self.points.len() {
            return Err(ModelError::PointForces(format!(
                "{} forces given for {} points; give one per point",
                forces.len(),
                self.points.len()
            )));
        }
        if let Some(p) = forces.iter().position(|f| !f.iter().all(|c| c.is_finite())) {
            return Err(ModelError::PointForces(format!("the force on point {p} is not finite")));
        }
        self.point_forces = forces;
        Ok(self)
    }

    /// Forces at points and loads on surfaces (docs/theory.md §17). The background-grid MPM
    /// only (the FEM reference has no surface loads yet); a follower pressure needs finite
    /// strain; every vertex must lie in the grid.
    pub fn with_loads(mut self, loads: Vec<Load<D>>) -> Result<Self, ModelError> {
        let grid = self.background.grid().clone();
        let grid = &grid;
        for (index, load) in loads.iter().enumerate() {
            let error = |what: String| Err(ModelError::Load { index, what });
            if self.background.moves_with_body() {
                return error(
                    "the updated Lagrangian FEM reference takes no loads but gravity yet; use the MPM".into(),
                );
            }
            if !self.rigid_bodies.is_empty() {
                return error("loads beside rigid bodies are not supported yet (their nodal forces belong to no body's field); gravity and initial velocities are".into());
            }
            if self.body_contact.is_some() {
                return error("loads on bodies in contact are not supported yet (their nodal forces belong to no body's field); gravity and initial velocities are".into());
            }
            if load.is_follower() && self.geometrically_linear {
                return error("a follower pressure turns with the deformed surface, which a geometrically linear model does not have; leave geometrically_linear out or use a dead pressure".into());
            }
            let (lo, hi, h) = (grid.origin(), grid.extent_max(), grid.cell_size());
            let inside = |x: &SVector<f64, D>| (0..D).all(|a| x[a] >= lo[a] && x[a] <= hi[a] + 1e-9 * h[a]);
            if let Some(x) = load.positions().iter().find(|x| !inside(x)) {
                return error(format!(
                    "vertex {:?} lies outside the grid {:?} to {:?}",
                    x.as_slice(),
                    grid.origin().as_slice(),
                    grid.extent_max().as_slice()
                ));
            }
        }
        self.loads = loads;
        let positions = self.points.position0();
        for load in &mut self.loads {
            load.attach(grid, positions);
            load.revolve(self.axisymmetric);
        }
        self.update_load_vertices();
        Ok(self)
    }

    /// Rollers on inclined planes (docs/theory.md §5): the nodes on or beyond each plane
    /// held along its normal in a local frame. On a grid (a body-fitted mesh's nodes move).
    pub fn with_inclined_rollers(mut self, rollers: Vec<InclinedRoller<D>>) -> Result<Self, ModelError> {
        if !rollers.is_empty() && self.background.moves_with_body() {
            return Err(ModelError::InclinedRoller(
                "the updated Lagrangian FEM reference's nodes move with the body; hold it on grid planes".into(),
            ));
        }
        self.inclined = rollers;
        Ok(self)
    }

    /// The rollers on inclined planes.
    pub fn inclined_rollers(&self) -> &[InclinedRoller<D>] {
        &self.inclined
    }

    /// The active nodes roller `k` holds.
    pub fn inclined_roller_nodes(&self, active: &ActiveNodes, k: usize) -> Vec<usize> {
        self.plane_nodes(active, &self.inclined[k])
    }

    /// The active nodes on `plane` or beyond it (those a roller there holds, those a
    /// frictional plane there meets).
    pub fn plane_nodes(&self, active: &ActiveNodes, plane: &InclinedRoller<D>) -> Vec<usize> {
        (0..active.len()).filter(|&a| self.roller_holds(plane, active.active_to_grid[a] as usize)).collect()
    }

    /// Rigid planes with Coulomb friction (docs/theory.md §5), which the material may
    /// leave; on a grid, each holding some of its nodes.
    pub fn with_frictional_planes(mut self, planes: Vec<FrictionalPlane<D>>) -> Result<Self, ModelError> {
        for (index, plane) in planes.iter().enumerate() {
            let what = if self.background.moves_with_body() {
                "the updated Lagrangian FEM reference's nodes move with the body; hold it on grid planes"
            } else if self.nodes_beyond(plane.plane()).is_empty() {
                "no node of the grid lies on the plane or beyond it (on the side away from the material)"
            } else {
                continue;
            };
            return Err(ModelError::FrictionalPlane { index, what: what.into() });
        }
        self.frictional = planes;
        Ok(self)
    }

    /// The rigid planes with Coulomb friction.
    pub fn frictional_planes(&self) -> &[FrictionalPlane<D>] {
        &self.frictional
    }

    /// Bodies (the points' body ids) in contact with Coulomb friction `friction` between
    /// every two of them (docs/theory.md §10): each body moves with its own velocity field
    /// at the grid nodes, and where two meet they may slide and separate instead of moving
    /// as one. Explicit analyses; refused with loads (the loads' nodal forces belong to no
    /// body's field yet).
    pub fn with_body_contact(mut self, friction: f64) -> Result<Self, ModelError> {
        if !(friction.is_finite() && friction >= 0.0) {
            return Err(ModelError::BodyContact(format!(
                "the friction coefficient must be finite and ≥ 0, not {friction}"
            )));
        }
        if !self.loads.is_empty() {
            return Err(ModelError::BodyContact("loads on bodies in contact are not supported yet".into()));
        }
        if !self.body_constraints.is_empty() {
            return Err(ModelError::BodyContact(
                "a body constraint would hold every body's field at its nodes, which contact does not support yet; hold the material with grid-plane constraints or frictional planes".into(),
            ));
        }
        self.body_contact = Some(friction);
        Ok(self)
    }

    /// The Coulomb coefficient between bodies in contact, if they are.
    pub fn body_contact(&self) -> Option<f64> {
        self.body_contact
    }

    /// The background nodes on `plane` or beyond it (those an inclined roller there holds),
    /// in increasing order.
    pub fn nodes_beyond(&self, plane: &InclinedRoller<D>) -> Vec<usize> {
        (0..self.grid().num_nodes()).filter(|&node| self.roller_holds(plane, node)).collect()
    }

    /// Whether `roller` holds background node `node`: on its plane or beyond it, to within
    /// 1e-9 of a cell.
    pub(crate) fn roller_holds(&self, roller: &InclinedRoller<D>, node: usize) -> bool {
        let tolerance = 1e-9 * self.grid().cell_size().min();
        roller.holds(&self.background.node_reference_position(node), tolerance)
    }

    /// Static groundwater (docs/theory.md §18): every point below the phreatic level gets
    /// its pore pressure, the laws see the effective stress, and the balance takes the
    /// water's force −∇p_w on the points (the buoyancy), which also accounts for the water
    /// on submerged surfaces. Implicit analyses (`Explicit` refuses it). Before a geostatic
    /// stress, which then takes the effective (buoyant) weight.
    pub fn with_water(mut self, water: Water) -> Result<Self, ModelError> {
        if water.vertical() >= D {
            return Err(ModelError::Water("the water's vertical axis is not an axis of the model".into()));
        }
        self.water = Some(water);
        Ok(self)
    }

    /// The groundwater, if any.
    pub fn water(&self) -> Option<&Water> {
        self.water.as_ref()
    }

    /// The pore pressure of point `p` at its place in the configuration the mechanics is
    /// written on, with gravity's factor `body_factor` (in full when the geostatic stress
    /// preloaded it); zero without water.
    #[inline]
    pub fn pore_pressure(&self, p: usize, body_factor: f64) -> f64 {
        let factor = if self.gravity_preloaded { 1.0 } else { body_factor };
        self.water.as_ref().map_or(0.0, |w| factor * w.pore_pressure(&self.configuration()[p]))
    }

    /// The water's force per unit volume on point `p`, −∇p_w on the submerged part of its
    /// domain at its place in the configuration the mechanics is written on, with gravity's
    /// factor `body_factor` (in full once a geostatic stress preloaded it); zero without
    /// water.
    #[inline]
    pub fn water_force(&self, p: usize, body_factor: f64) -> SVector<f64, D> {
        let factor = if self.gravity_preloaded { 1.0 } else { body_factor };
        self.water.as_ref().map_or(SVector::zeros(), |w| {
            let half = self.points.half_length()[p][w.vertical()];
            w.force_density(&self.configuration()[p], half) * factor
        })
    }

    /// Stabilise nearly empty cells by the face ghost penalty with factor γ > 0 (docs/theory.md
    /// §15; 0.01–1 is the useful range). The background-grid MPM with the Linear or Gimp
    /// basis only: a body-fitted FEM mesh has no cut cells, and B-spline nodal values are
    /// not point values next to the grid faces. Implicit analyses only (`Explicit` refuses
    /// it: it has no tangent to stabilise).
    pub fn with_ghost_penalty(mut self, gamma: f64) -> Result<Self, ModelError> {
        if !(gamma.is_finite() && gamma > 0.0) {
            return Err(ModelError::GhostPenalty(format!("the factor is {gamma}; it must be a positive number")));
        }
        if self.background.moves_with_body() {
            return Err(ModelError::GhostPenalty("a body-fitted FEM mesh has no cut cells to stabilise".into()));
        }
        if self.background.basis() == BasisKind::QuadraticBSpline {
            return Err(ModelError::GhostPenalty(
                "the penalty acts on the grid's bilinear interpolant of the nodal values, which are control values off the nodes for QuadraticBSpline next to a grid face; use Linear or Gimp".into(),
            ));
        }
        self.ghost_penalty = Some(gamma);
        self.still_axisymmetric(ModelError::GhostPenalty)
    }

    /// The same model on the grid's `basis` instead (the points' GIMP domains kept, used by
    /// Gimp only). A body-fitted FEM mesh has no other basis, and the ghost penalty none
    /// but Linear and Gimp.
    pub fn with_basis(mut self, basis: BasisKind) -> Result<Self, ModelError> {
        if self.background.moves_with_body() {
            return Err(ModelError::Basis("a body-fitted FEM mesh has its element functions, no other basis".into()));
        }
        if self.ghost_penalty.is_some() && basis == BasisKind::QuadraticBSpline {
            return Err(ModelError::Basis("the ghost penalty needs Linear or Gimp".into()));
        }
        self.background = Background::on_grid(self.background.grid().clone(), basis);
        Ok(self)
    }

    /// Write equilibrium on the initial configuration: the connectivity, the point volumes
    /// and GIMP domains (and FEM mesh nodes) stay those of the start, and the positions
    /// only accumulate the displacement for output, so the grid and the points
    /// act as a fixed finite-element mesh with point quadrature. The small-deformation
    /// setting of limit analysis (bearing capacity, strength reduction; PLAXIS's default,
    /// without "updated mesh"): moving points under small-strain stresses adds a geometric
    /// effect the linearised theory does not have (docs/theory.md §3). Small strain only;
    /// implicit analyses only (`Explicit` moves its points by their velocities).
    pub fn with_geometrically_linear(mut self) -> Result<Self, ModelError> {
        if self.kinematics != Kinematics::SmallStrain {
            return Err(ModelError::GeometricallyLinear(
                "finite strain follows the deformed configuration; use kinematics SmallStrain".into(),
            ));
        }
        if let Some(k) = self.loads.iter().position(|l| l.is_follower()) {
            return Err(ModelError::GeometricallyLinear(format!(
                "load {k} is a follower pressure, which turns with the deformed surface; use a dead pressure"
            )));
        }
        self.geometrically_linear = true;
        Ok(self)
    }

    /// Use the given anti-locking treatment; B-bar and assumed strain need small strain,
    /// F-bar finite strain, all three the linear basis (or the FEM mesh), assumed strain a
    /// stabilization in (0, 1].
    pub fn with_anti_locking(mut self, anti_locking: AntiLocking) -> Result<Self, ModelError> {
        if let AntiLocking::AssumedStrain { stabilization } = anti_locking {
            if !(stabilization > 0.0 && stabilization <= 1.0) {
                return Err(ModelError::AntiLocking(format!(
                    "assumed-strain stabilization is {stabilization}; valid is 0 < β ≤ 1 (0 leaves hourglass modes free, 1 is B-bar; 0.1 is usual)"
                )));
            }
        }
        if anti_locking != AntiLocking::None {
            let name = anti_locking.name();
            let finite = anti_locking == AntiLocking::FBar;
            if finite && self.kinematics != Kinematics::FiniteStrain {
                return Err(ModelError::AntiLocking(format!(
                    "{name} is a finite-strain treatment; use kinematics FiniteStrain, or BBar in small strain"
                )));
            }
            if !finite && self.kinematics != Kinematics::SmallStrain {
                return Err(ModelError::AntiLocking(format!(
                    "{name} is a small-strain treatment; use kinematics SmallStrain, or FBar in finite strain"
                )));
            }
            if !self.background.groups_share_nodes() {
                return Err(ModelError::AntiLocking(format!(
                    "{name} averages over the points of a cell, which share their nodes only with the Linear basis"
                )));
            }
        }
        self.anti_locking = anti_locking;
        self.still_axisymmetric(ModelError::AntiLocking)
    }

    pub fn background(&self) -> &Background<D> {
        &self.background
    }

    /// The grid (for the FEM reference, the grid its constraint planes lie on).
    pub fn grid(&self) -> &Grid<D> {
        self.background.grid()
    }

    pub fn basis(&self) -> BasisKind {
        self.background.basis()
    }

    pub fn kinematics(&self) -> Kinematics {
        self.kinematics
    }

    pub fn points(&self) -> &PointStore<D> {
        &self.points
    }

    /// The points' evolving state, for the analyses that advance it.
    pub fn points_mut(&mut self) -> PointsMut<'_, D> {
        self.points.view_mut()
    }

    /// Move the background's nodes by the converged increment `du` (D values per node of
    /// `active`) where they move with the body (the mesh of the FEM reference); a grid,
    /// reset every step, stays.
    pub fn displace_background(&mut self, active: &ActiveNodes, du: &[f64]) {
        self.background.displace(active, du);
    }

    /// Exchange the points' state fields (position, velocity, deformation gradient, volume,
    /// GIMP half-lengths, stress, elastic strain and, where the laws keep one, history)
    /// with `fields`, each holding one value per point (the history in the laws' layout).
    /// O(1), and the model's invariants hold: a field of another length is a bug of the
    /// analysis, and panics.
    pub fn swap_state(&mut self, fields: &mut StateFields<D>) {
        self.points.swap_state(fields);
    }

    /// The points' velocities, to set an initial condition.
    pub fn velocities_mut(&mut self) -> &mut [SVector<f64, D>] {
        self.points.velocity_mut()
    }

    pub fn materials(&self) -> &[Arc<dyn ConstitutiveLaw>] {
        &self.materials
    }

    /// The law of point `p`'s material.
    #[inline]
    pub fn law(&self, p: usize) -> &dyn ConstitutiveLaw {
        &*self.materials[self.points.material()[p] as usize]
    }

    /// Point `p`'s committed material state, which its law's stiffness may depend on
    /// ([`ConstitutiveLaw::constant_stiffness`]), with the stress the law works with: the
    /// Kirchhoff stress τ = J σ in finite strain, σ in small strain.
    pub fn material_state(&self, p: usize) -> MaterialState<'_> {
        let pts = &self.points;
        let stress = match self.kinematics {
            Kinematics::FiniteStrain => pts.stress()[p] * pts.deformation_gradient()[p].determinant(),
            Kinematics::SmallStrain => pts.stress()[p],
        };
        let history = self.law(p).own_history(pts.history(p));
        MaterialState { stress, elastic_strain: &pts.elastic_strain()[p], history }
    }

    /// Per material, its P-wave modulus where the law's stiffness is constant (`None`: it
    /// follows the state, [`Model::p_wave_modulus`] per point).
    pub fn constant_p_wave_moduli(&self) -> Vec<Option<f64>> {
        (self.materials.iter())
            .map(|m| m.constant_stiffness().then(|| m.p_wave_modulus(&MaterialState::at_rest(&[]))))
            .collect()
    }

    /// The P-wave modulus of point `p` in its committed state, from `constant` (the
    /// model's [`Model::constant_p_wave_moduli`]) where its material's is constant.
    #[inline]
    pub fn p_wave_modulus(&self, constant: &[Option<f64>], p: usize) -> f64 {
        match constant[self.points.material()[p] as usize] {
            Some(m) => m,
            None => self.law(p).p_wave_modulus(&self.material_state(p)),
        }
    }

    pub fn constraints(&self) -> &[PlaneConstraint] {
        &self.constraints
    }

    /// The loads beside gravity and the per-point forces.
    pub fn loads(&self) -> &[Load<D>] {
        &self.loads
    }

    /// The factor on load `k` at `level`: the load factor, or its time function at the time.
    pub fn load_scale(&self, k: usize, level: LoadLevel) -> f64 {
        level.factor(self.loads[k].time_function())
    }

    /// Put every load vertex where its carrier point now puts it (the analyses, after a
    /// committed step).
    pub fn update_load_vertices(&mut self) {
        for load in &mut self.loads {
            load.follow(self.points.position(), self.points.deformation_gradient());
        }
    }

    /// Whether only forces follow the load factor of a quasi-static analysis — gravity
    /// (unless a geostatic stress preloaded it), point forces or loads, and no prescribed
    /// displacement — so that a step that cannot reach equilibrium is a collapse: the load
    /// factor reached is the most the model carries.
    pub fn load_controlled(&self) -> bool {
        let weight = !self.gravity_preloaded && self.gravity.iter().any(|&g| g != 0.0);
        let forces = self.point_forces.iter().any(|f| f.iter().any(|&v| v != 0.0));
        let displaced =
            self.constraints.iter().any(|c| c.is_displaced()) || self.body_constraints.iter().any(|c| c.is_displaced());
        (weight || forces || !self.loads.is_empty()) && !displaced
    }

    /// Body force per unit mass at full load.
    pub fn gravity(&self) -> &SVector<f64, D> {
        &self.gravity
    }

    pub fn anti_locking(&self) -> AntiLocking {
        self.anti_locking
    }

    /// Gravity acts in full from the start (the points carry a geostatic initial stress,
    /// [`Model::geostatic_stress`]); only point forces and prescribed displacements follow
    /// the load factor.
    pub fn gravity_preloaded(&self) -> bool {
        self.gravity_preloaded
    }

    /// Ghost-penalty factor γ (implicit MPM): the faces of cut cells are penalised by γ
    /// times the largest P-wave modulus (`loam_grid::ghost_faces`); `None` adds nothing.
    pub fn ghost_penalty(&self) -> Option<f64> {
        self.ghost_penalty
    }

    /// Small strain on the initial configuration ([`Model::with_geometrically_linear`]):
    /// the mechanics keeps the points' initial places and volumes
    /// ([`Model::configuration`]).
    pub fn geometrically_linear(&self) -> bool {
        self.geometrically_linear
    }

    /// The volume-averaging group of every point for B-bar: its grid cell (the face rule
    /// of the basis: a cell owns [x_i, x_{i+1})), or its element in the FEM reference.
    pub fn averaging_group(&self, p: usize) -> usize {
        self.background.averaging_group(p, &self.configuration()[p])
    }

    /// The point positions the mechanics is written on: the current ones, or the initial
    /// ones of a geometrically linear model (whose current positions only carry the
    /// displacement for output).
    pub fn configuration(&self) -> &[SVector<f64, D>] {
        if self.geometrically_linear {
            self.points.position0()
        } else {
            self.points.position()
        }
    }

    /// Whether background node `node` is held by constraint `c`.
    fn node_on_plane(&self, node: usize, c: &PlaneConstraint) -> bool {
        self.background.node_on_plane(node, c.axis, c.plane, c.within.as_ref())
    }

    /// The prescribed displacement increments of a step from load factor `from` to `to`
    /// on the constrained dofs of every motion field of `layout` (zero elsewhere), into
    /// `out` (sized like `constrained`): the planes', then the bodies'.
    pub fn prescribed_increment(
        &self,
        layout: &NodeLayout,
        conn: &Connectivity<D>,
        from: f64,
        to: f64,
        out: &mut [f64],
    ) {
        out.iter_mut().for_each(|v| *v = 0.0);
        let active = conn.active_nodes();
        for c in self.constraints.iter().filter(|c| c.is_displaced()) {
            let nodes = self.constraint_nodes(active, c);
            body_constraints::put_increment::<D>(layout, &nodes, (&c.fixed, &c.displacement), to - from, out);
        }
        self.put_body_increments(layout, conn, (from, to), out);
    }

    /// The nodes (active indices) each constraint holds.
    pub fn constraint_nodes(&self, active: &ActiveNodes, c: &PlaneConstraint) -> Vec<usize> {
        (0..active.len()).filter(|&a| self.node_on_plane(active.active_to_grid[a] as usize, c)).collect()
    }

    /// Whether the tangent is symmetric: every material in use has a symmetric algorithmic
    /// tangent (the hyperelastic finite-strain tangent is symmetric as a whole) and no
    /// F-bar, whose averaged volume change enters the stress but not the test function.
    pub fn symmetric_tangent(&self) -> bool {
        self.anti_locking != AntiLocking::FBar && self.materials.iter().all(|m| m.symmetric_tangent())
    }

    /// Whether some material softens, so that the tangent can turn indefinite.
    pub fn can_soften(&self) -> bool {
        self.materials.iter().any(|m| m.can_soften())
    }

    /// Mark the constrained dofs of the active nodes in `layout`: a constraint holds its
    /// components of every motion field at the nodes of its plane.
    /// (In axisymmetry the nodes on the axis are held radially too.)
    pub fn constrained_dofs(&self, layout: &NodeLayout, active: &ActiveNodes, out: &mut Vec<bool>) {
        out.clear();
        out.resize(layout.num_dofs(active.len()), false);
        let axis = self.axisymmetric.then(axisymmetry::axis_roller);
        for (a, &g) in active.active_to_grid.iter().enumerate() {
            for c in self.constraints.iter().chain(&axis) {
                if self.node_on_plane(g as usize, c) {
                    for k in motion_fields(layout) {
                        for i in 0..D {
                            out[layout.dof(a, k, i)] |= c.fixed[i];
                        }
                    }
                }
            }
        }
    }

    /// The first constraint (by index) that holds no active node: no material point has
    /// support on its plane, so it would silently constrain nothing.
    pub fn constraint_without_nodes(&self, active: &ActiveNodes) -> Option<(usize, &PlaneConstraint)> {
        self.constraints
            .iter()
            .enumerate()
            .find(|(_, c)| !active.active_to_grid.iter().any(|&g| self.node_on_plane(g as usize, c)))
    }

    /// Dead load on point `p` at full load: gravity on its mass plus its point force.
    #[inline]
    pub fn point_load(&self, p: usize) -> SVector<f64, D> {
        self.point_load_at(p, 1.0)
    }

    /// Dead load on point `p` at load factor `lambda`: gravity scaled with it (in full when
    /// preloaded by a geostatic stress) plus the scaled point force.
    #[inline]
    pub fn point_load_at(&self, p: usize, lambda: f64) -> SVector<f64, D> {
        let g = if self.gravity_preloaded { 1.0 } else { lambda };
        let f = self.gravity * (g * self.points.mass()[p]);
        match self.point_forces.get(p) {
            Some(fp) => f + fp * lambda,
            None => f,
        }
    }
}

/// The indices of `layout`'s motion fields (the ones constraints hold).
fn motion_fields(layout: &NodeLayout) -> impl Iterator<Item = usize> + '_ {
    (layout.fields().iter().enumerate()).filter(|(_, f)| matches!(f, NodeField::Motion { .. })).map(|(k, _)| k)
}

/// Every point's material must exist.
fn check_materials<const D: usize>(
    points: &PointStore<D>,
    materials: &[Arc<dyn ConstitutiveLaw>],
) -> Result<(), ModelError> {
    match points.material().iter().enumerate().find(|(_, &m)| m as usize >= materials.len()) {
        Some((point, &material)) => Err(ModelError::MissingMaterial { point, material, count: materials.len() }),
        None => Ok(()),
    }
}

/// Every constraint must lie on an axis of the model and a node plane of the grid, with
/// finite displacements and box.
fn check_constraints<const D: usize>(grid: &Grid<D>, constraints: &[PlaneConstraint]) -> Result<(), ModelError> {
    for (index, c) in constraints.iter().enumerate() {
        if !c.displacement.iter().all(|u| u.is_finite()) {
            return Err(ModelError::ConstraintValue { index, what: "displacement" });
        }
        // The box may be unbounded (±∞ on an axis it does not limit) but not NaN.
        if c.within.is_some_and(|(lo, hi)| lo.iter().chain(&hi).any(|x| x.is_nan())) {
            return Err(ModelError::ConstraintValue { index, what: "box (within)" });
        }
        if c.axis >= D {
            return Err(ModelError::ConstraintAxis { index, axis: c.axis, dimension: D });
        }
        let max = grid.cells()[c.axis];
        if c.plane > max {
            return Err(ModelError::ConstraintPlane { index, axis: c.axis, plane: c.plane, max });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests;
