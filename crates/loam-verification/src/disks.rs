//! V5: two elastic disks colliding (Sulsky, Chen & Schreyer 1994; `docs/verification.md`
//! V5). On the unit square, 20 × 20 cells, disks of radius 0.2 centred at (0.2, 0.2) and
//! (0.8, 0.8), E = 1000, ν = 0.3, ρ = 1000, moving towards each other at ±(0.1, 0.1). The
//! exact disks carry a kinetic energy of 2.513 per unit thickness and first touch near
//! t = 1.59. There is no closed form for the impact itself: the reference is physical,
//! the total energy may lose a few percent through the transfers and must never grow.

use crate::bound::Bound;
use loam_constitutive::Elastic;
use loam_grid::{BasisKind, Grid};
use loam_model::{Kinematics, Model};
use loam_points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

/// The bounds `cargo xtask verify` checks on the disks (`docs/verification.md` §V5), for
/// explicit MUSL (leapfrog energy) and implicit trapezoidal (Δt = 0.005) alike.
pub mod bounds {
    use super::Bound;

    /// The run reaches t = 3 (1 = yes).
    pub const RAN_TO_END: Bound = Bound::lower(1.0, "docs/verification.md §V5: both schemes run through the impact");
    /// (E(0) − E(3)) / E(0): the energy lost through the point–grid transfers and the impact.
    pub const ENERGY_LOSS: Bound = Bound::upper(0.05, "docs/verification.md §V5: may lose a few percent, bound 5 %");
    /// max (E(t) − E(0)) / E(0): "never grows", up to round-off and the Newton tolerance of
    /// the stored energy, both far below 1e-3.
    pub const ENERGY_GROWTH: Bound = Bound::upper(1e-3, "docs/verification.md §V5: total energy never grows");
}

/// Radius of both disks.
pub const RADIUS: f64 = 0.2;
/// Density, Young's modulus and Poisson's ratio of both disks.
pub const DENSITY: f64 = 1000.0;
pub const YOUNG: f64 = 1000.0;
pub const POISSON: f64 = 0.3;
/// Centre and velocity (both components) of each disk.
const DISKS: [(Vector2<f64>, f64); 2] = [(Vector2::new(0.2, 0.2), 0.1), (Vector2::new(0.8, 0.8), -0.1)];

/// How a disk's outline is drawn when it is filled with points.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DiskOutline {
    /// The exact circle.
    Circle,
    /// The regular polygon of `sides` vertices inscribed in the circle.
    Polygon { sides: usize },
}

/// V5 as a model: 2 × 2 points per cell, linear basis (the disks touch the grid's faces,
/// which GIMP domains would cross), the exact circles.
pub fn disks_model(kinematics: Kinematics) -> Model<2> {
    disks_model_with(DiskOutline::Circle, BasisKind::Linear, kinematics)
}

/// [`disks_model`] with any outline and basis: the explicit tests fill inscribed polygons
/// and run both bases.
pub fn disks_model_with(outline: DiskOutline, basis: BasisKind, kinematics: Kinematics) -> Model<2> {
    let grid = Grid::new(Vector2::zeros(), Vector2::new(0.05, 0.05), [20, 20]).expect("valid disk grid");
    let mut points = PointStore::new();
    for (centre, v) in DISKS {
        let shape = match outline {
            DiskOutline::Circle => Shape::Ball { centre, radius: RADIUS },
            DiskOutline::Polygon { sides } => inscribed_polygon(centre, RADIUS, sides),
        };
        let first = points.len();
        points.fill(&grid, &shape, 2, DENSITY, 0).expect("disk fits the grid");
        for p in first..points.len() {
            points.velocity_mut()[p] = Vector2::new(v, v);
        }
    }
    let law = Elastic::new(YOUNG, POISSON).expect("valid elastic constants");
    Model::new(grid, basis, kinematics, points, vec![Arc::new(law)], vec![], Vector2::zeros())
        .expect("valid disk model")
}

/// The regular polygon of `sides` vertices inscribed in the circle (`centre`, `radius`),
/// the first vertex on the +x axis.
pub fn inscribed_polygon(centre: Vector2<f64>, radius: f64, sides: usize) -> Shape<2> {
    Shape::Polygon(
        (0..sides)
            .map(|k| {
                let a = 2.0 * std::f64::consts::PI * k as f64 / sides as f64;
                centre + Vector2::new(a.cos(), a.sin()) * radius
            })
            .collect(),
    )
}

/// Area of the regular `sides`-gon inscribed in a circle, relative to the circle.
pub fn polygon_area_ratio(sides: usize) -> f64 {
    let n = sides as f64;
    0.5 * n * (2.0 * std::f64::consts::PI / n).sin() / std::f64::consts::PI
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square inscribed in a circle covers 2/π of it; many sides approach the circle.
    #[test]
    fn inscribed_polygons_cover_their_share_of_the_circle() {
        assert!((polygon_area_ratio(4) - 2.0 / std::f64::consts::PI).abs() < 1e-15);
        assert!((1.0 - polygon_area_ratio(1000)).abs() < 1e-5);
    }

    /// Each disk moves towards the other, every point of it at the disk's velocity.
    #[test]
    fn the_disks_approach_each_other() {
        let model = disks_model_with(DiskOutline::Polygon { sides: 64 }, BasisKind::Gimp, Kinematics::FiniteStrain);
        let p = model.points();
        for (x, v) in p.position().iter().zip(p.velocity()) {
            let sign = if x.x < 0.5 { 1.0 } else { -1.0 };
            assert_eq!(*v, Vector2::new(0.1, 0.1) * sign);
        }
        assert!(p.position().iter().any(|x| x.x < 0.5) && p.position().iter().any(|x| x.x > 0.5));
    }
}
