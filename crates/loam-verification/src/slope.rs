//! V4: slope stability (`docs/verification.md` §V4), the seed paper's geotechnical
//! application. Two published references: Taylor's (1937) chart, whose stability number
//! for an undrained 45° slope on a deep foundation is N_s = c_u/(γH) ≈ 0.18 at collapse,
//! i.e. γH/c_u ≈ 5.5; and Griffiths & Lane (1999), whose first example (a 2:1 slope,
//! c/(γH) = 0.05, φ = 20°, ψ = 0) has a factor of safety of about 1.4 by strength
//! reduction. Past collapse the slope runs out in large deformation, where implicit and
//! explicit MPM are compared with each other.

use crate::bound::Bound;
use loam_constitutive::ConstitutiveLaw;
use loam_grid::{BasisKind, Grid};
use loam_model::{AntiLocking, Kinematics, Model, PlaneConstraint};
use loam_points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

/// Taylor (1937): γH/c_u at collapse of a 45° undrained slope on a deep foundation,
/// 1/N_s with N_s ≈ 0.18.
pub const TAYLOR_STABILITY: f64 = 5.5;
/// Griffiths & Lane (1999), example 1: the factor of safety by strength reduction
/// (Bishop's method gives 1.38).
pub const GRIFFITHS_LANE_FACTOR_OF_SAFETY: f64 = 1.4;

/// The bounds `cargo xtask verify` checks on the slopes (`docs/verification.md` §V4).
pub mod bounds {
    use super::Bound;

    /// V4a: |γH/c_u at collapse / [`super::TAYLOR_STABILITY`] − 1| on the finest mesh.
    pub const TAYLOR: Bound = Bound::upper(0.10, "docs/verification.md §V4: within 10 % of Taylor's 5.5, finest mesh");
    /// V7: the submerged slope's factor of safety over the dry slope's with γ′, same mesh.
    pub const SUBMERGED_SLOPE: Bound =
        Bound::upper(0.01, "docs/verification.md §V7: submerged F within 1 % of the dry slope's with gamma'");
    /// V4b: |F / [`super::GRIFFITHS_LANE_FACTOR_OF_SAFETY`] − 1| on the finest mesh.
    pub const GRIFFITHS_LANE: Bound =
        Bound::upper(0.05, "docs/verification.md §V4: within 5 % of Griffiths & Lane's 1.4, finest mesh");
    /// V4b: |F with the Drucker–Prager cone fitted in plane strain / F with Mohr–Coulomb − 1|
    /// on the finest mesh (the fit gives Mohr–Coulomb's collapse stresses in plane strain
    /// once the flow is steady).
    pub const DRUCKER_PRAGER_FOS: Bound = Bound::upper(
        0.02,
        "docs/verification.md §V4: F with Drucker–Prager (plane-strain fit) within 2 % of Mohr–Coulomb's, finest mesh",
    );
    /// V4b: |F from the last state that held − F from zero| over the search's tolerance,
    /// on every mesh: the continued search brackets the same factor.
    pub const SEARCH_PATHS: Bound = Bound::upper(
        1.0,
        "docs/verification.md §V4: F from the last state that held within the tolerance of F from zero",
    );
    /// V4c: the largest difference between the implicit and explicit run-out profiles,
    /// in cells.
    pub const RUNOUT_PROFILES: Bound =
        Bound::upper(2.0, "docs/verification.md §V4: implicit and explicit profiles within two cells");
}

/// The geometry of a V4 slope, in units of the slope height H: the foundation layer
/// `depth` deep, the toe `toe` from the left side, the face rising over a horizontal `run`
/// (1 for 45°, 2 for a 2:1 slope), the crest flat `crest` long.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlopeGeometry {
    pub height: f64,
    pub depth: f64,
    pub toe: f64,
    pub run: f64,
    pub crest: f64,
}

impl SlopeGeometry {
    /// The undrained 45° slope: a foundation layer H deep (Taylor's depth factor 2), 2 H of
    /// ground before the toe and behind the crest, room for the base failure of φ = 0.
    pub const UNDRAINED: Self = Self { height: 10.0, depth: 1.0, toe: 2.0, run: 1.0, crest: 2.0 };
    /// Griffiths & Lane (1999), their first example: a 2:1 slope on a foundation layer H
    /// deep (depth factor 2); 1.2 H before the toe and 2 H behind the crest.
    pub const GRIFFITHS_LANE: Self = Self { height: 10.0, depth: 1.0, toe: 1.2, run: 2.0, crest: 2.0 };

    /// The body's outline, counter-clockwise from the origin.
    pub fn outline(&self) -> Vec<Vector2<f64>> {
        let h = self.height;
        let width = (self.toe + self.run + self.crest) * h;
        let (toe_y, crest_y) = (self.depth * h, (self.depth + 1.0) * h);
        vec![
            Vector2::new(0.0, 0.0),
            Vector2::new(width, 0.0),
            Vector2::new(width, crest_y),
            Vector2::new((self.toe + self.run) * h, crest_y),
            Vector2::new(self.toe * h, toe_y),
            Vector2::new(0.0, toe_y),
        ]
    }
}

/// A V4 slope as a model: linear basis, 2×2 points per cell, `cells_per_h` cells over the
/// slope height, small strain, base fixed, sides on rollers, gravity −`gravity` along y
/// applied with the load factor (so a quasi-static run is a gravity-increase analysis),
/// one empty row of cells above the crest.
pub fn slope_model(
    geometry: &SlopeGeometry,
    law: Arc<dyn ConstitutiveLaw>,
    density: f64,
    gravity: f64,
    cells_per_h: usize,
    anti_locking: AntiLocking,
) -> Model<2> {
    slope_model_with(geometry, law, density, gravity, cells_per_h, BasisKind::Linear, Kinematics::SmallStrain)
        .with_anti_locking(anti_locking)
        .expect("valid slope model")
}

/// [`slope_model`] with any basis and kinematics and no anti-locking: the large-
/// deformation run-out (GIMP, finite strain).
pub fn slope_model_with(
    geometry: &SlopeGeometry,
    law: Arc<dyn ConstitutiveLaw>,
    density: f64,
    gravity: f64,
    cells_per_h: usize,
    basis: BasisKind,
    kinematics: Kinematics,
) -> Model<2> {
    let g = geometry;
    let h = g.height / cells_per_h as f64;
    let nx = ((g.toe + g.run + g.crest) * cells_per_h as f64).round() as usize;
    let ny = ((g.depth + 1.0) * cells_per_h as f64).round() as usize;
    let grid = Grid::new(Vector2::zeros(), Vector2::new(h, h), [nx, ny + 1]).expect("valid slope grid");
    let mut points = PointStore::new();
    points.fill(&grid, &Shape::Polygon(g.outline()), 2, density, 0).expect("slope fits the grid");
    let constraints = vec![
        PlaneConstraint::new(0, 0, [true, false, false]),
        PlaneConstraint::new(0, nx, [true, false, false]),
        PlaneConstraint::new(1, 0, [true, true, false]),
    ];
    Model::new(grid, basis, kinematics, points, vec![law], constraints, Vector2::new(0.0, -gravity))
        .expect("valid slope model")
}
