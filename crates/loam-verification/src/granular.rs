//! V8, the collapse of a granular column onto a rough base (docs/verification.md §V8):
//! a column of cohesionless soil (Mohr–Coulomb, c = 0, φ = 20°, ψ = 0) of width L₀ and
//! height H₀ = a L₀, a = ½, standing against a smooth wall, released under gravity and
//! followed for 1.5 s, when the collapse is long over (its loose front still creeps);
//! explicit MPM only.
//!
//! What it is compared against:
//! - the deposit's height: for a ≲ 0.65–0.7 the top of the column is not reached by the
//!   collapse and the final height is H₀ (quasi-2D experiments: Lube, Huppert, Sparks &
//!   Freundt 2005, "Collapses of two-dimensional granular columns", Phys. Rev. E 72;
//!   Lajeunesse, Monnier & Homsy 2005, Phys. Fluids 17);
//! - its flank: a cohesionless slope steeper than φ cannot stand (the infinite slope's
//!   factor of safety tan φ / tan β), so a deposit at rest has a mean flank slope ≤ φ;
//! - its run-out: (L∞ − L₀) / L₀ ≈ 1.2 a in those experiments, for sands and beads whose
//!   friction angles (about 30°) are larger than φ here, so the figure is compared, not
//!   bounded: a lower φ runs further;
//! - rest: the CFL step back within 5 % of the wave speeds' step at the final densities
//!   (issue 19), with a FLIP fraction of 0.99 (pure FLIP keeps the point velocities that map
//!   to no nodal momentum, docs/theory.md §10); the end speed over the peak is reported.

use loam_constitutive::{ConstitutiveLaw, Elastic, MohrCoulomb};
use loam_grid::{BasisKind, Grid};
use loam_model::{Kinematics, Model, PlaneConstraint};
use loam_points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

/// The column and its soil (SI units: m, kg, s, Pa).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GranularColumn {
    /// L₀, the column's width.
    pub width: f64,
    /// H₀ = a L₀.
    pub height: f64,
    pub density: f64,
    pub young: f64,
    pub poisson: f64,
    /// φ in degrees (c = 0, ψ = 0).
    pub friction_deg: f64,
    pub gravity: f64,
    /// Grid width in units of L₀ (room for the run-out).
    pub domain_widths: f64,
}

impl GranularColumn {
    /// a = ½, L₀ = 0.2 m, sand-like ρ = 1800 kg/m³ with a soft E = 1 MPa (c_p = 27 m/s),
    /// φ = 20°, in a grid 3 L₀ wide.
    pub const V8: GranularColumn = GranularColumn {
        width: 0.2,
        height: 0.1,
        density: 1800.0,
        young: 1e6,
        poisson: 0.3,
        friction_deg: 20.0,
        gravity: 9.81,
        domain_widths: 3.0,
    };

    /// a = H₀ / L₀.
    pub fn aspect_ratio(&self) -> f64 {
        self.height / self.width
    }

    /// The experiments' run-out (L∞ − L₀) / L₀ = 1.2 a (Lube et al. 2005, a < 1.8).
    pub fn experimental_runout(&self) -> f64 {
        1.2 * self.aspect_ratio()
    }

    /// The model at `cells` cells across H₀: 2×2 points per cell, GIMP, finite strain;
    /// a smooth wall at x = 0 (x held), a rough base (x and y held), two spare cells above.
    pub fn model(&self, cells: usize) -> Model<2> {
        let h = self.height / cells as f64;
        let nx = (self.domain_widths * self.width / h).round() as usize;
        let grid = Grid::new(Vector2::zeros(), Vector2::repeat(h), [nx, cells + 2]).expect("valid V8 grid");
        let mut points = PointStore::new();
        let column = Shape::Box { min: Vector2::zeros(), max: Vector2::new(self.width, self.height) };
        points.fill(&grid, &column, 2, self.density, 0).expect("the column fits the grid");
        let elastic = Elastic::new(self.young, self.poisson).expect("valid elasticity");
        let law: Arc<dyn ConstitutiveLaw> =
            Arc::new(MohrCoulomb::from_degrees(elastic, 0.0, self.friction_deg, 0.0).expect("valid Mohr-Coulomb"));
        let constraints =
            vec![PlaneConstraint::new(0, 0, [true, false, false]), PlaneConstraint::new(1, 0, [true, true, false])];
        let gravity = Vector2::new(0.0, -self.gravity);
        Model::new(grid, BasisKind::Gimp, Kinematics::FiniteStrain, points, vec![law], constraints, gravity)
            .expect("valid V8 model")
    }
}

/// The bounds of V8.
pub mod bounds {
    use crate::Bound;
    /// |H∞ − H₀| in cells: the top of a column of a ≤ ½ is not reached by the collapse.
    pub const FINAL_HEIGHT: Bound =
        Bound::upper(1.0, "docs/verification.md §V8: H∞ = H₀ for a < 0.65 (Lube et al. 2005), within a cell");
    /// Mean flank slope over φ: a cohesionless slope at rest is no steeper than φ.
    pub const FLANK_SLOPE: Bound = Bound::upper(1.0, "docs/verification.md §V8: infinite slope, tan β ≤ tan φ at rest");
    /// |Δt_c(end) / (min_p h / c_p) − 1|: at rest the CFL step is the wave speeds' (issue 19).
    pub const CFL_AT_REST: Bound = Bound::upper(0.05, "issue 19: the CFL step within 5 % of its elastic value");
    /// The farthest point beyond the toe, in cells: the default settings leave no spray of
    /// points thrown clear of the deposit.
    pub const SPRAY: Bound = Bound::upper(2.0, "issue 34: no point beyond the deposit's toe by more than two cells");
    /// Steps to 1 s at 40 cells across H₀ (12 800 points) with the default settings: the
    /// step stays near the column's elastic one (h / c_p = 9.1e-5 s at CFL 0.5, 11 000
    /// steps) rather than falling with the loose front's density.
    pub const STEPS_AT_40_CELLS: Bound =
        Bound::upper(25_000.0, "issue 34: at most 25 000 steps to 1 s at 12 800 points, default settings");
}
