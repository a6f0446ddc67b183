//! What a run is made of: the grid and basis, the points and their materials, the
//! kinematics, the constraints on grid planes and the loads. The implicit and explicit
//! analyses both take a [`Model`]; quantities that do not depend on the integrator
//! (constrained dofs, stored energy, external work of dead loads) live here once.

use loam_constitutive::tensor::sym_log;
use loam_constitutive::ConstitutiveLaw;
use loam_grid::{ActiveNodes, BasisKind, Connectivity, FeMesh, Grid};
use loam_points::PointStore;
use loam_solve::Couplings;
use nalgebra::{Matrix3, SVector};
use rayon::prelude::*;
use std::sync::Arc;

/// Kinematics of the step update (THEORY.md §2 and §3): one pipeline, two strain measures.
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
/// Both treatments are small strain, with the linear basis or the FEM mesh, where all
/// points of a cell share its nodes so that the cell averages add no couplings.
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
}

impl AntiLocking {
    /// The weight β of each point's own deviatoric strain beside its cell's average, or
    /// `None` without cell averaging.
    pub fn deviatoric_weight(&self) -> Option<f64> {
        match *self {
            AntiLocking::None => None,
            AntiLocking::BBar => Some(1.0),
            AntiLocking::AssumedStrain { stabilization } => Some(stabilization),
        }
    }

    pub fn name(&self) -> &'static str {
        match self {
            AntiLocking::None => "none",
            AntiLocking::BBar => "B-bar",
            AntiLocking::AssumedStrain { .. } => "assumed strain",
        }
    }
}

/// A constraint on the nodes of a grid plane: the listed displacement components are
/// prescribed — zero (a roller fixes the component normal to the plane, a fixed plane all
/// of them), or `displacement` at full load, applied in proportion to the load factor
/// (a footing pushed into the ground). `within` limits it to the nodes of the plane inside
/// a box (all axes; the plane's own axis is ignored).
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneConstraint {
    /// Axis normal to the plane.
    pub axis: usize,
    /// Index of the node plane along `axis`.
    pub plane: usize,
    /// Which displacement components are prescribed (first D entries used).
    pub fixed: [bool; 3],
    /// Prescribed displacement of the fixed components at full load (zero: held).
    pub displacement: [f64; 3],
    /// Only nodes with min ≤ x ≤ max (per axis, to within 1e-9 of a cell), if given.
    pub within: Option<([f64; 3], [f64; 3])>,
}

impl PlaneConstraint {
    /// Hold the `fixed` components of every node of the plane at zero.
    pub fn new(axis: usize, plane: usize, fixed: [bool; 3]) -> Self {
        Self { axis, plane, fixed, displacement: [0.0; 3], within: None }
    }

    /// Prescribe `displacement` (at full load) on the fixed components instead of zero.
    pub fn displaced(mut self, displacement: [f64; 3]) -> Self {
        self.displacement = displacement;
        self
    }

    /// Only the nodes of the plane inside the box [min, max].
    pub fn within(mut self, min: [f64; 3], max: [f64; 3]) -> Self {
        self.within = Some((min, max));
        self
    }

    /// Whether the constraint prescribes a non-zero displacement.
    pub fn is_displaced(&self) -> bool {
        self.displacement.iter().zip(&self.fixed).any(|(d, &f)| f && *d != 0.0)
    }
}

/// Errors in assembling a model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    #[error("the model has no material points")]
    NoPoints,
    #[error("point {point} uses material {material}, but only {count} materials are defined")]
    MissingMaterial { point: usize, material: u32, count: usize },
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
    #[error("strength reduction: {0}")]
    StrengthReduction(String),
    #[error("ghost penalty: {0}")]
    GhostPenalty(String),
    #[error("geometrically linear analysis: {0}")]
    GeometricallyLinear(String),
}

/// A complete MPM model. Build it, then hand it to an analysis.
#[derive(Debug, Clone)]
pub struct Model<const D: usize> {
    pub grid: Grid<D>,
    pub basis: BasisKind,
    pub kinematics: Kinematics,
    pub points: PointStore<D>,
    pub materials: Vec<Arc<dyn ConstitutiveLaw>>,
    pub constraints: Vec<PlaneConstraint>,
    /// Body force per unit mass at full load.
    pub gravity: SVector<f64, D>,
    /// Force on each point at full load (empty: none).
    pub point_forces: Vec<SVector<f64, D>>,
    /// The body-fitted mesh of an updated Lagrangian FEM run, whose Gauss points are the
    /// points; `None` for the MPM (see [`Model::updated_lagrangian_fem`]).
    pub mesh: Option<FeMesh<D>>,
    /// Volumetric-locking treatment (set with [`Model::with_anti_locking`]).
    pub anti_locking: AntiLocking,
    /// Gravity acts in full from the start (the points carry a geostatic initial stress,
    /// [`Model::geostatic_stress`]); only point forces and prescribed displacements follow
    /// the load factor.
    pub gravity_preloaded: bool,
    /// Ghost-penalty factor γ (implicit MPM): the faces of cut cells are penalised by γ
    /// times the largest P-wave modulus (`loam_grid::ghost_faces`); `None` adds nothing.
    pub ghost_penalty: Option<f64>,
    /// Small strain on the initial configuration (set with
    /// [`Model::with_geometrically_linear`]): the mechanics keeps the points' initial
    /// places and volumes ([`Model::configuration`]).
    pub geometrically_linear: bool,
}

impl<const D: usize> Model<D> {
    /// Check the model and put every point's material state at its unstrained start:
    /// b^e = I (finite strain) or ε^e = 0 (small strain), and the law's initial history.
    pub fn new(
        grid: Grid<D>,
        basis: BasisKind,
        kinematics: Kinematics,
        mut points: PointStore<D>,
        materials: Vec<Arc<dyn ConstitutiveLaw>>,
        constraints: Vec<PlaneConstraint>,
        gravity: SVector<f64, D>,
    ) -> Result<Self, ModelError> {
        if points.is_empty() {
            return Err(ModelError::NoPoints);
        }
        if let Some((p, &m)) = points.material.iter().enumerate().find(|(_, &m)| m as usize >= materials.len()) {
            return Err(ModelError::MissingMaterial { point: p, material: m, count: materials.len() });
        }
        for (index, c) in constraints.iter().enumerate() {
            let max = grid.cells()[c.axis];
            if c.plane > max {
                return Err(ModelError::ConstraintPlane { index, axis: c.axis, plane: c.plane, max });
            }
        }
        if let Some(axis) = (0..D).find(|&a| !gravity[a].is_finite()) {
            return Err(ModelError::Gravity { axis, value: gravity[axis] });
        }
        points.reset_elastic_strain(match kinematics {
            Kinematics::FiniteStrain => Matrix3::identity(),
            Kinematics::SmallStrain => Matrix3::zeros(),
        });
        let stride = materials.iter().map(|m| m.history_len()).max().unwrap_or(0);
        let material = points.material.clone();
        points.init_history(stride, |p, h| materials[material[p] as usize].init_history(h));
        Ok(Self {
            grid,
            basis,
            kinematics,
            points,
            materials,
            constraints,
            gravity,
            point_forces: Vec::new(),
            mesh: None,
            anti_locking: AntiLocking::None,
            gravity_preloaded: false,
            ghost_penalty: None,
            geometrically_linear: false,
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
        }
        // The element functions are the bilinear (trilinear) tensor products of the linear
        // basis: same support size, so the connectivity buffers have the right stride.
        let mut model = Self::new(grid, BasisKind::Linear, kinematics, points, materials, constraints, gravity)?;
        model.mesh = Some(mesh);
        Ok(model)
    }

    /// The same model with every material's strength divided by `factor` (c/F, tan φ/F,
    /// σ_y/F: `ConstitutiveLaw::with_strength_reduced`); elastic materials are kept. A
    /// model without any material that has a strength is refused.
    pub fn with_strength_reduced(&self, factor: f64) -> Result<Self, ModelError> {
        if !(factor.is_finite() && factor > 0.0) {
            return Err(ModelError::StrengthReduction(format!("the factor is {factor}; it must be a positive number")));
        }
        let mut reduced_any = false;
        let materials = self
            .materials
            .iter()
            .enumerate()
            .map(|(m, law)| match law.with_strength_reduced(factor) {
                None => Ok(law.clone()),
                Some(r) => {
                    reduced_any = true;
                    r.map_err(|e| ModelError::StrengthReduction(format!("material {m} at F = {factor}: {e}")))
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        if !reduced_any {
            return Err(ModelError::StrengthReduction("no material has a strength to reduce (all are elastic)".into()));
        }
        Ok(Self { materials, ..self.clone() })
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
        if self.mesh.is_some() {
            return Err(ModelError::GhostPenalty("a body-fitted FEM mesh has no cut cells to stabilise".into()));
        }
        if self.basis == BasisKind::QuadraticBSpline {
            return Err(ModelError::GhostPenalty(
                "the penalty acts on the grid's bilinear interpolant of the nodal values, which are control values off the nodes for QuadraticBSpline next to a grid face; use Linear or Gimp".into(),
            ));
        }
        self.ghost_penalty = Some(gamma);
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
        self.geometrically_linear = true;
        Ok(self)
    }

    /// Use the given anti-locking treatment; B-bar and assumed strain need small strain and
    /// the linear basis (or the FEM mesh), assumed strain a stabilization in (0, 1].
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
            if self.kinematics != Kinematics::SmallStrain {
                return Err(ModelError::AntiLocking(format!(
                    "{name} is a small-strain treatment; use kinematics SmallStrain"
                )));
            }
            if self.mesh.is_none() && self.basis != BasisKind::Linear {
                return Err(ModelError::AntiLocking(format!(
                    "{name} averages over the points of a cell, which share their nodes only with the Linear basis"
                )));
            }
        }
        self.anti_locking = anti_locking;
        Ok(self)
    }

    /// The volume-averaging group of every point for B-bar: its grid cell (the face rule
    /// of the basis: a cell owns [x_i, x_{i+1})), or its element in the FEM reference.
    pub fn averaging_cell(&self, p: usize) -> usize {
        if let Some(mesh) = &self.mesh {
            return p / mesh.gauss_per_element();
        }
        self.grid.cell_index(self.grid.cell_coords(&self.configuration()[p]))
    }

    /// The point positions the mechanics is written on: the current ones, or the initial
    /// ones of a geometrically linear model (whose current positions only carry the
    /// displacement for output).
    pub fn configuration(&self) -> &[SVector<f64, D>] {
        if self.geometrically_linear {
            &self.points.position0
        } else {
            &self.points.position
        }
    }

    /// Whether node `node` (grid node index in MPM, mesh node index in FEM) lies on the plane
    /// of constraint `c`: a grid node on that node plane, or a mesh node that started on it
    /// (within 1e-9 of a cell).
    fn node_on_plane(&self, node: usize, c: &PlaneConstraint) -> bool {
        let h = self.grid.cell_size();
        let (on_plane, x) = match &self.mesh {
            None => (self.grid.node_coords(node)[c.axis] == c.plane, self.grid.node_position(node)),
            Some(mesh) => {
                let x = mesh.reference_positions()[node];
                let plane = self.grid.origin()[c.axis] + c.plane as f64 * h[c.axis];
                ((x[c.axis] - plane).abs() <= 1e-9 * h[c.axis], x)
            }
        };
        on_plane
            && c.within.is_none_or(|(lo, hi)| {
                (0..D).all(|a| a == c.axis || (x[a] >= lo[a] - 1e-9 * h[a] && x[a] <= hi[a] + 1e-9 * h[a]))
            })
    }

    /// The prescribed displacement increments of a step from load factor `from` to `to`
    /// on the constrained dofs (zero elsewhere), into `out` (sized like `constrained`).
    pub fn prescribed_increment(&self, active: &ActiveNodes, from: f64, to: f64, out: &mut [f64]) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for c in self.constraints.iter().filter(|c| c.is_displaced()) {
            for (a, &g) in active.active_to_grid.iter().enumerate() {
                if self.node_on_plane(g as usize, c) {
                    for i in (0..D).filter(|&i| c.fixed[i]) {
                        out[a * D + i] = (to - from) * c.displacement[i];
                    }
                }
            }
        }
    }

    /// The nodes (active indices) each constraint holds.
    pub fn constraint_nodes(&self, active: &ActiveNodes, c: &PlaneConstraint) -> Vec<usize> {
        (0..active.len()).filter(|&a| self.node_on_plane(active.active_to_grid[a] as usize, c)).collect()
    }

    /// Whether every material in use has a symmetric algorithmic tangent (so Cholesky
    /// applies) — the hyperelastic finite-strain tangent is symmetric as a whole.
    pub fn symmetric_tangent(&self) -> bool {
        self.materials.iter().all(|m| m.symmetric_tangent())
    }

    /// Whether some material softens, so the tangent can turn indefinite and only LU
    /// factorises it.
    pub fn indefinite_tangent(&self) -> bool {
        self.materials.iter().any(|m| m.indefinite_tangent())
    }

    /// Mark the constrained dofs (`active node · D + component`) of the active nodes.
    pub fn constrained_dofs(&self, active: &ActiveNodes, out: &mut Vec<bool>) {
        out.clear();
        out.resize(active.len() * D, false);
        for (a, &g) in active.active_to_grid.iter().enumerate() {
            for c in &self.constraints {
                if self.node_on_plane(g as usize, c) {
                    for i in 0..D {
                        out[a * D + i] |= c.fixed[i];
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
        let f = self.gravity * (g * self.points.mass[p]);
        match self.point_forces.get(p) {
            Some(fp) => f + fp * lambda,
            None => f,
        }
    }

    /// Put the points in a geostatic initial stress: the vertical stress is the weight of
    /// the material above each point in its grid column, σ_v = −|g| Σ m / A (A the column's
    /// horizontal area; points at the same height count half), the horizontal ones K0 σ_v,
    /// with the elastic strain that carries it (small strain ε^e = C⁻¹σ, finite strain
    /// b^e = exp(2 C⁻¹σ)). Gravity then acts in full from the start
    /// (`gravity_preloaded`). K0 applies to level or layered ground; a slope is brought to
    /// equilibrium by gravity loading instead. Fails if gravity is not along one axis, a
    /// law has no isotropic elasticity, or the state lies outside a yield surface.
    pub fn geostatic_stress(&mut self, k0: f64) -> Result<(), ModelError> {
        if !(k0.is_finite() && k0 > 0.0) {
            return Err(ModelError::Geostatic(format!("K0 is {k0}; it must be a positive number")));
        }
        let vertical = (0..D).max_by(|&a, &b| self.gravity[a].abs().total_cmp(&self.gravity[b].abs())).unwrap_or(0);
        let g = self.gravity[vertical];
        if g == 0.0 || (0..D).any(|a| a != vertical && self.gravity[a] != 0.0) {
            return Err(ModelError::Geostatic("a geostatic stress needs gravity along one axis".into()));
        }
        // Down is the direction of gravity; "above" is against it.
        let up = -g.signum();
        let h = self.grid.cell_size();
        let area: f64 = (0..D).filter(|&a| a != vertical).map(|a| h[a]).product();
        let pts = &self.points;
        let n = pts.len();
        // The column of a point: its cell's coordinates across gravity (the vertical one
        // zeroed), so points sort by column, then from the top down.
        let column = |p: usize| {
            let mut ijk = self.grid.cell_coords(&pts.position[p]);
            ijk[vertical] = 0;
            ijk
        };
        let mut order: Vec<([usize; D], usize)> = (0..n).map(|p| (column(p), p)).collect();
        order.sort_by(|(ca, a), (cb, b)| {
            ca.cmp(cb).then((up * pts.position[*b][vertical]).total_cmp(&(up * pts.position[*a][vertical])))
        });
        let tol = 1e-9 * h[vertical];
        let mut sigma_v = vec![0.0; n];
        for col in order.chunk_by(|a, b| a.0 == b.0) {
            let mut above = 0.0;
            // The rows of the column: points at the same height, top down.
            for row in
                col.chunk_by(|&(_, a), &(_, b)| (pts.position[a][vertical] - pts.position[b][vertical]).abs() <= tol)
            {
                let row_mass: f64 = row.iter().map(|&(_, q)| pts.mass[q]).sum();
                for &(_, q) in row {
                    sigma_v[q] = -g.abs() * (above + 0.5 * row_mass) / area;
                }
                above += row_mass;
            }
        }
        let hs = pts.history_stride();
        let mut h_out = vec![0.0; hs];
        let mut strains = Vec::with_capacity(n);
        let mut stresses = Vec::with_capacity(n);
        for (p, &sv) in sigma_v.iter().enumerate() {
            let law = &self.materials[pts.material[p] as usize];
            let Some(elastic) = law.elasticity() else {
                return Err(ModelError::Geostatic(format!(
                    "material {} ({}) has no isotropic elasticity to carry an initial stress",
                    pts.material[p],
                    law.name()
                )));
            };
            let mut sigma = Matrix3::identity() * (k0 * sv);
            sigma[(vertical, vertical)] = sv;
            let eps = elastic.strain(&sigma);
            // Admissible: the law's own update from that elastic strain returns the stress.
            let upd = law
                .update(&eps, pts.history(p), &mut h_out)
                .map_err(|e| ModelError::Geostatic(format!("point {p}: {e}")))?;
            if (upd.stress - sigma).norm() > 1e-8 * sigma.norm().max(f64::MIN_POSITIVE) {
                return Err(ModelError::Geostatic(format!(
                    "point {p} at {:?}: the K0 = {k0} stress (σ_v = {:.4e}) lies outside the yield surface of material {} ({}); use a K0 inside it or gravity loading",
                    pts.position[p].as_slice(), sv, pts.material[p], law.name()
                )));
            }
            let be = match self.kinematics {
                Kinematics::SmallStrain => eps,
                Kinematics::FiniteStrain => loam_constitutive::tensor::sym_exp(&(eps * 2.0))
                    .map_err(|e| ModelError::Geostatic(format!("point {p}: {e}")))?,
            };
            strains.push(be);
            stresses.push(sigma);
        }
        self.points.elastic_strain = strains;
        self.points.stress = stresses;
        self.gravity_preloaded = true;
        Ok(())
    }

    /// Stored elastic energy Σ_p V⁰_p W(ε^e_p): with finite strain ε^e = ½ ln b^e and W
    /// per unit reference volume (Hencky); with small strain W(ε^e) on the initial volume.
    pub fn stored_energy(&self) -> f64 {
        let pts = &self.points;
        (0..pts.len())
            .into_par_iter()
            .map(|p| {
                let law = &self.materials[pts.material[p] as usize];
                let eps = match self.kinematics {
                    Kinematics::SmallStrain => pts.elastic_strain[p],
                    Kinematics::FiniteStrain => match sym_log(&pts.elastic_strain[p]) {
                        Ok(l) => l * 0.5,
                        Err(_) => return f64::NAN,
                    },
                };
                pts.volume0[p] * law.stored_energy(&eps)
            })
            .collect::<Vec<_>>()
            .iter()
            .sum()
    }
}

/// Internal force of a point at one support node, v σ ∂N_a, and with B-bar (b̄_a given)
/// also σ : (⅓ (b̄_a − ∂N_a) ⊗ e_i) I = v (tr σ / 3)(b̄_a − ∂N_a): the one kernel of the
/// implicit residual, the dynamic start and the explicit grid update.
#[inline]
pub fn internal_force<const D: usize>(
    volume: f64,
    stress: &Matrix3<f64>,
    grad: &SVector<f64, D>,
    bbar: Option<&SVector<f64, D>>,
) -> SVector<f64, D> {
    let mut f = SVector::<f64, D>::from_fn(|i, _| volume * (0..D).map(|j| stress[(i, j)] * grad[j]).sum::<f64>());
    if let Some(b) = bbar {
        f += (b - grad) * (volume * stress.trace() / 3.0);
    }
    f
}

/// Work of the dead loads (gravity, point forces) on the points' motion, accumulated
/// step by step with the trapezoidal rule in the load factor: exact for loads held
/// constant, and for loads ramped linearly with displacement increments of one step.
#[derive(Debug, Clone, Default)]
pub struct ExternalWork<const D: usize> {
    previous: Vec<SVector<f64, D>>,
    previous_factor: f64,
    work: f64,
}

impl<const D: usize> ExternalWork<D> {
    /// Start at the model's current positions and load factor.
    pub fn new(model: &Model<D>, load_factor: f64) -> Self {
        Self { previous: model.points.position.clone(), previous_factor: load_factor, work: 0.0 }
    }

    /// Add the work done since the last call; the load factor went linearly from the last
    /// one to `load_factor`. Returns the accumulated work.
    pub fn advance(&mut self, model: &Model<D>, load_factor: f64) -> f64 {
        let pts = &model.points;
        let dw: f64 = (0..pts.len())
            .map(|p| {
                let mean = (model.point_load_at(p, self.previous_factor) + model.point_load_at(p, load_factor)) * 0.5;
                mean.dot(&(pts.position[p] - self.previous[p]))
            })
            .sum();
        self.work += dw;
        self.previous.copy_from_slice(&pts.position);
        self.previous_factor = load_factor;
        self.work
    }

    pub fn work(&self) -> f64 {
        self.work
    }
}

/// Point–node connectivity seen as the coupling structure of assembly and gathers:
/// points are the elements.
pub struct PointCouplings<'a, const D: usize>(pub &'a Connectivity<D>);

impl<const D: usize> Couplings for PointCouplings<'_, D> {
    fn num_nodes(&self) -> usize {
        self.0.active_nodes().len()
    }
    fn elements_of(&self, node: usize) -> &[(u32, u32)] {
        self.0.node_points().of(node)
    }
    fn nodes_of(&self, element: usize) -> &[u32] {
        self.0.support_nodes(element)
    }
}
