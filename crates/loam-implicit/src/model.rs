//! What a run is made of: the grid and basis, the points and their materials, the
//! kinematics, the constraints on grid planes and the loads.

use loam_constitutive::ConstitutiveLaw;
use loam_grid::{BasisKind, Grid};
use loam_points::PointStore;
use nalgebra::{Matrix3, SVector};
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

/// A constraint on the nodes of a grid plane: the listed displacement components are held
/// at zero. A roller fixes the component normal to the plane; a fixed plane all of them.
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneConstraint {
    /// Axis normal to the plane.
    pub axis: usize,
    /// Index of the node plane along `axis`.
    pub plane: usize,
    /// Which displacement components are fixed (first D entries used).
    pub fixed: [bool; 3],
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
    #[error("gravity component {axis} is {value}; it must be finite")]
    Gravity { axis: usize, value: f64 },
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
        Ok(Self { grid, basis, kinematics, points, materials, constraints, gravity, point_forces: Vec::new() })
    }

    /// Whether every material in use has a symmetric algorithmic tangent (so Cholesky
    /// applies) — the hyperelastic finite-strain tangent is symmetric as a whole.
    pub fn symmetric_tangent(&self) -> bool {
        self.materials.iter().all(|m| m.symmetric_tangent())
    }
}
