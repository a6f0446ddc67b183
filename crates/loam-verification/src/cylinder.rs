//! V6: the thick-walled cylinder under internal pressure (`docs/verification.md` §V6), a
//! quarter of it in plane strain with rollers on the two symmetry planes. Lamé's solution
//! (small strain, linear elasticity): u_r(r) = A r + B / r with
//! A = (1 + ν)(1 − 2ν) p a² / (E (b² − a²)), B = (1 + ν) p a² b² / (E (b² − a²)).
//! The run is measured by the radial displacements at the inner and outer radius of the
//! least-squares fit of A r + B / r to every point's radial displacement (the points do not
//! sit on the radii), and by the largest point-wise error of u_r against Lamé's.
//!
//! The same cylinder is also posed axisymmetrically ([`Cylinder::ring`], docs/theory.md
//! §20): the ring a < r < b between smooth planes, whose grid fits it exactly, elastic
//! against Lamé and perfectly plastic (von Mises) against its limit pressure
//! p_lim = 2 c_u ln(b/a) (Hill 1950, plane strain along the axis: at collapse the plastic
//! flow is incompressible and ε_z = 0, so σ_z is the mean of σ_r and σ_θ and the von
//! Mises cylinder yields at σ_θ − σ_r = 2 c_u, c_u = σ_y / √3).

use crate::bound::Bound;
use loam_constitutive::{ConstitutiveLaw, Elastic};
use loam_grid::{BasisKind, Grid};
use loam_model::{AntiLocking, Kinematics, Load, Model, PlaneConstraint, TimeFunction};
use loam_points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

/// The bounds `cargo xtask verify` checks on the cylinder (`docs/verification.md` §V6).
pub mod bounds {
    use super::Bound;

    /// Inner and outer radial displacement at the finest of three meshes, small strain.
    pub const RADIAL_DISPLACEMENT: Bound =
        Bound::upper(0.01, "docs/verification.md §V6: u_r(a), u_r(b) within 1 % at the finest mesh");
    /// Newton corrections per load step under the follower pressure in finite strain.
    pub const FOLLOWER_NEWTON_ITERATIONS: Bound =
        Bound::upper(6.0, "docs/verification.md §V6: <= 6 Newton iterations per load step, follower pressure");
    /// The axisymmetric ring's largest point-wise error against Lamé at the finest mesh.
    pub const RING_LAME: Bound =
        Bound::upper(1e-3, "docs/verification.md §V6: axisymmetric ring within 0.1 % of Lamé at the finest mesh");
    /// The observed order of the ring's point-wise error (the bilinear basis: h²).
    pub const RING_LAME_ORDER: Bound =
        Bound::lower(1.8, "docs/verification.md §V6: axisymmetric ring converges as h^2 to Lamé");
    /// The axisymmetric ring's collapse pressure against 2 c_u ln(b/a) at the finest mesh.
    pub const RING_LIMIT: Bound =
        Bound::upper(0.005, "docs/verification.md §V6: axisymmetric collapse pressure within 0.5 % of 2 c_u ln(b/a)");
}

/// A thick-walled cylinder: inner and outer radius, elastic constants, internal pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    pub inner: f64,
    pub outer: f64,
    pub young: f64,
    pub poisson: f64,
    pub pressure: f64,
}

impl Cylinder {
    /// a = 1, b = 2, E = 1000, ν = 0.3, p = 1 (p/E = 1e-3: small strain).
    pub const REFERENCE: Cylinder = Cylinder { inner: 1.0, outer: 2.0, young: 1000.0, poisson: 0.3, pressure: 1.0 };

    /// Lamé's radial displacement at radius `r` (plane strain).
    pub fn radial_displacement(&self, r: f64) -> f64 {
        let (a, b, nu) = (self.inner, self.outer, self.poisson);
        let k = (1.0 + nu) * self.pressure * a * a / (self.young * (b * b - a * a));
        k * ((1.0 - 2.0 * nu) * r + b * b / r)
    }

    /// The quarter cylinder as a model: a grid of `cells` square cells across the outer
    /// radius and a quarter more as room to expand, 2×2 points per cell, the annulus a polygon of 256 sides per
    /// arc, rollers on x = 0 and y = 0, no gravity, and the pressure on the inner arc —
    /// dead, or following the surface (finite strain).
    pub fn model(&self, cells: usize, kinematics: Kinematics, follower: bool) -> Model<2> {
        let h = self.outer / cells as f64;
        let grid = Grid::new(Vector2::zeros(), Vector2::new(h, h), [cells + cells / 4 + 2, cells + cells / 4 + 2])
            .expect("valid grid");
        let arc = |r: f64, reverse: bool| -> Vec<Vector2<f64>> {
            let n = 256;
            let mut v: Vec<_> = (0..=n)
                .map(|k| {
                    let t = std::f64::consts::FRAC_PI_2 * k as f64 / n as f64;
                    Vector2::new(r * t.cos(), r * t.sin())
                })
                .collect();
            if reverse {
                v.reverse();
            }
            v
        };
        let mut outline = arc(self.outer, false);
        outline.extend(arc(self.inner, true));
        let shape = Shape::Polygon(outline);
        let mut points = PointStore::new();
        points.fill(&grid, &shape, 2, 1.0, 0).expect("the annulus fits the grid");
        let law = Elastic::new(self.young, self.poisson).expect("valid elastic constants");
        let rollers =
            vec![PlaneConstraint::new(0, 0, [true, false, false]), PlaneConstraint::new(1, 0, [false, true, false])];
        let model =
            Model::new(grid, BasisKind::Gimp, kinematics, points, vec![Arc::new(law)], rollers, Vector2::zeros())
                .expect("valid cylinder model");
        // The inner arc: facets inside the mid-radius, off the two straight symmetry edges.
        let bore = (shape.boundary(h / 2.0).expect("valid outline"))
            .select(|c| c.norm() < 0.5 * (self.inner + self.outer) && c.min() > 1e-9 * h);
        let n = bore.vertices.len();
        let load = Load::pressure(bore, vec![self.pressure; n], follower, TimeFunction::Constant).expect("valid load");
        model.with_loads(vec![load]).expect("the bore lies in the grid")
    }

    /// Fit u_r = A r + B / r to the points' radial displacements (least squares) and return
    /// the fitted (u_r(a), u_r(b)), with the largest point-wise |u_r − Lamé| / Lamé(a).
    pub fn measure(&self, points: &PointStore<2>) -> CylinderErrors {
        let radial = radial_displacements(points);
        let worst = radial.iter().map(|&(r, u)| (u - self.radial_displacement(r)).abs()).fold(0.0, f64::max);
        let [a_fit, b_fit] = least_squares(radial.iter().map(|&(r, u)| ([r, 1.0 / r], u)));
        let at = |r: f64| a_fit * r + b_fit / r;
        let rel = |r: f64| (at(r) - self.radial_displacement(r)).abs() / self.radial_displacement(r).abs();
        CylinderErrors {
            inner: rel(self.inner),
            outer: rel(self.outer),
            inner_value: at(self.inner),
            pointwise: worst / self.radial_displacement(self.inner).abs(),
        }
    }
}

impl Cylinder {
    /// The cylinder's limit pressure 2 c_u ln(b/a) for undrained strength `c_u` (module
    /// docs).
    pub fn limit_pressure(&self, c_u: f64) -> f64 {
        2.0 * c_u * (self.outer / self.inner).ln()
    }

    /// The cylinder as an axisymmetric ring of `law` (module docs): `cells` square cells
    /// across b − a, two high, the grid from the axis to a cell beyond b, 2×2 points per
    /// cell, the linear basis with B-bar (whose averaged dilatation keeps incompressible
    /// plastic flow from locking), small strain on the initial configuration, smooth
    /// planes top and bottom, and the dead pressure `self.pressure` on the bore.
    pub fn ring(&self, cells: usize, law: Arc<dyn ConstitutiveLaw>) -> Model<2> {
        let h = (self.outer - self.inner) / cells as f64;
        let across = (self.outer / h).round() as usize + 1;
        let grid = Grid::new(Vector2::zeros(), Vector2::new(h, h), [across, 2]).expect("valid grid");
        let shape = Shape::Box { min: Vector2::new(self.inner, 0.0), max: Vector2::new(self.outer, 2.0 * h) };
        let mut points = PointStore::new();
        points.fill(&grid, &shape, 2, 1.0, 0).expect("the ring fits the grid");
        let planes =
            vec![PlaneConstraint::new(1, 0, [false, true, false]), PlaneConstraint::new(1, 2, [false, true, false])];
        let model =
            Model::new(grid, BasisKind::Linear, Kinematics::SmallStrain, points, vec![law], planes, Vector2::zeros())
                .and_then(Model::with_axisymmetry)
                .and_then(Model::with_geometrically_linear)
                .and_then(|m| m.with_anti_locking(AntiLocking::BBar))
                .expect("valid ring model");
        let bore = (shape.boundary(h / 2.0).expect("valid outline")).select(|c| c[0] < self.inner + 0.25 * h);
        let n = bore.vertices.len();
        let load = Load::pressure(bore, vec![self.pressure; n], false, TimeFunction::Constant).expect("valid load");
        model.with_loads(vec![load]).expect("the bore lies in the grid")
    }

    /// The largest point-wise |u_r − Lamé(r)| of an axisymmetric ring's points, relative to
    /// Lamé(a).
    pub fn ring_error(&self, points: &PointStore<2>) -> f64 {
        let worst = (points.position0().iter().zip(points.position()))
            .map(|(x0, x)| (x[0] - x0[0] - self.radial_displacement(x0[0])).abs())
            .fold(0.0, f64::max);
        worst / self.radial_displacement(self.inner).abs()
    }
}

/// The mean distance from the origin of the vertices of `model`'s first load (a bore
/// centred on the origin: the cylinder's, the cavity's).
pub fn bore_radius(model: &Model<2>) -> f64 {
    let x = model.loads()[0].positions();
    x.iter().map(|v| v.norm()).sum::<f64>() / x.len() as f64
}

/// Every point's (initial distance from the origin, displacement along it).
pub(crate) fn radial_displacements(points: &PointStore<2>) -> Vec<(f64, f64)> {
    (points.position0().iter().zip(points.position()))
        .map(|(x0, x)| {
            let r = x0.norm();
            (r, (x - x0).dot(&(x0 / r)))
        })
        .collect()
}

/// The coefficients [c₀, c₁] of c₀ φ₀ + c₁ φ₁ that fit the samples (φ, u) best in least
/// squares (the 2×2 normal equations).
pub(crate) fn least_squares(samples: impl Iterator<Item = ([f64; 2], f64)>) -> [f64; 2] {
    let (mut m, mut rhs) = ([[0.0; 2]; 2], [0.0; 2]);
    for (phi, u) in samples {
        for i in 0..2 {
            for j in 0..2 {
                m[i][j] += phi[i] * phi[j];
            }
            rhs[i] += phi[i] * u;
        }
    }
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    [(rhs[0] * m[1][1] - rhs[1] * m[0][1]) / det, (m[0][0] * rhs[1] - m[1][0] * rhs[0]) / det]
}

/// A cylinder run measured against Lamé.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CylinderErrors {
    /// |u_r(a) − Lamé| / Lamé at the inner radius, from the fit.
    pub inner: f64,
    /// The same at the outer radius.
    pub outer: f64,
    /// The fitted u_r(a).
    pub inner_value: f64,
    /// Largest point-wise |u_r − Lamé(r)| over the points, relative to Lamé(a).
    pub pointwise: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lamé's solution satisfies its boundary conditions: σ_r(a) = −p, σ_r(b) = 0, with
    /// σ_r = (λ + 2μ) u' + λ u / r in plane strain (derivative by central differences).
    #[test]
    fn lame_solution_meets_its_boundary_conditions() {
        let c = Cylinder::REFERENCE;
        let (e, nu) = (c.young, c.poisson);
        let (lambda, mu) = (e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)));
        let sigma_r = |r: f64| {
            let du = (c.radial_displacement(r + 1e-6) - c.radial_displacement(r - 1e-6)) / 2e-6;
            (lambda + 2.0 * mu) * du + lambda * c.radial_displacement(r) / r
        };
        assert!((sigma_r(c.inner) + c.pressure).abs() < 1e-6, "{}", sigma_r(c.inner));
        assert!(sigma_r(c.outer).abs() < 1e-6, "{}", sigma_r(c.outer));
    }
}
