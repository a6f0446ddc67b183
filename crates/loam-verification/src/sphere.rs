//! The thick-walled sphere under internal pressure (`docs/verification.md` §V6), posed
//! axisymmetrically (docs/theory.md §20): a quarter of its meridian plane,
//! a < ρ = √(r² + z²) < b, x the radius and y the axis, the plane z = 0 a plane of
//! symmetry. Lamé's solution (small strain, linear elasticity; Timoshenko & Goodier §137):
//! u_ρ = p a³ [(1 − 2ν) ρ + (1 + ν) b³ / (2 ρ²)] / (E (b³ − a³)). Perfectly plastic, the
//! sphere collapses at p = 2 σ_y ln(b/a) (Hill 1950): in spherical symmetry σ_θ = σ_φ, so
//! von Mises and Tresca are one, σ_θ − σ_ρ = σ_y.

use crate::bound::Bound;
use crate::cylinder::{least_squares, radial_displacements};
use loam_constitutive::ConstitutiveLaw;
use loam_grid::{BasisKind, Grid};
use loam_model::{AntiLocking, Kinematics, Load, Model, PlaneConstraint, TimeFunction};
use loam_points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

/// The bounds `cargo xtask verify` checks on the sphere (`docs/verification.md` §V6).
pub mod bounds {
    use super::Bound;

    /// u_ρ(a) and u_ρ(b) of the fit at the finest of three meshes.
    pub const SPHERE_LAME: Bound =
        Bound::upper(0.01, "docs/verification.md §V6: thick sphere within 1 % of Lamé at the finest mesh");
    /// The collapse pressure against 2 σ_y ln(b/a), with the ghost penalty.
    pub const SPHERE_LIMIT: Bound =
        Bound::upper(0.01, "docs/verification.md §V6: thick sphere collapses within 1 % of 2 σ_y ln(b/a)");
}

/// A thick-walled sphere: inner and outer radius, elastic constants, internal pressure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThickSphere {
    pub inner: f64,
    pub outer: f64,
    pub young: f64,
    pub poisson: f64,
    pub pressure: f64,
}

impl ThickSphere {
    /// a = 1, b = 2, E = 1000, ν = 0.3, p = 1 (p/E = 1e-3: small strain).
    pub const REFERENCE: ThickSphere =
        ThickSphere { inner: 1.0, outer: 2.0, young: 1000.0, poisson: 0.3, pressure: 1.0 };

    /// Lamé's radial displacement at ρ.
    pub fn radial_displacement(&self, rho: f64) -> f64 {
        let (a, b, nu) = (self.inner, self.outer, self.poisson);
        let k = self.pressure * a.powi(3) / (self.young * (b.powi(3) - a.powi(3)));
        k * ((1.0 - 2.0 * nu) * rho + (1.0 + nu) * b.powi(3) / (2.0 * rho * rho))
    }

    /// The collapse pressure 2 σ_y ln(b/a).
    pub fn limit_pressure(&self, yield_stress: f64) -> f64 {
        2.0 * yield_stress * (self.outer / self.inner).ln()
    }

    /// The quarter meridian plane as an axisymmetric model of `law`: `cells` square cells
    /// across b − a, the grid from the axis to a cell beyond b, 2×2 points per cell in the
    /// annulus (its arcs polygons of 64 sides), the linear basis with B-bar, small strain
    /// on the initial configuration, a roller on z = 0, the optional ghost penalty `ghost`,
    /// and the dead pressure on the bore.
    pub fn model(&self, cells: usize, law: Arc<dyn ConstitutiveLaw>, ghost: Option<f64>) -> Model<2> {
        let h = (self.outer - self.inner) / cells as f64;
        let across = (self.outer / h).ceil() as usize + 1;
        let grid = Grid::new(Vector2::zeros(), Vector2::new(h, h), [across, across]).expect("valid grid");
        let arc = |r: f64| -> Vec<Vector2<f64>> {
            (0..=64)
                .map(|k| {
                    let t = std::f64::consts::FRAC_PI_2 * k as f64 / 64.0;
                    Vector2::new(r * t.cos(), r * t.sin())
                })
                .collect()
        };
        let mut outline = arc(self.outer);
        outline.extend(arc(self.inner).into_iter().rev());
        let shape = Shape::Polygon(outline);
        let mut points = PointStore::new();
        points.fill(&grid, &shape, 2, 1.0, 0).expect("the sphere fits the grid");
        let roller = vec![PlaneConstraint::new(1, 0, [false, true, false])];
        let mut model =
            Model::new(grid, BasisKind::Linear, Kinematics::SmallStrain, points, vec![law], roller, Vector2::zeros())
                .and_then(Model::with_axisymmetry)
                .and_then(Model::with_geometrically_linear)
                .and_then(|m| m.with_anti_locking(AntiLocking::BBar))
                .expect("valid sphere model");
        if let Some(gamma) = ghost {
            model = model.with_ghost_penalty(gamma).expect("a valid ghost penalty");
        }
        // The bore: facets inside the mid-radius, off the symmetry plane and the axis.
        let bore = (shape.boundary(h / 2.0).expect("valid outline"))
            .select(|c| c.norm() < 0.5 * (self.inner + self.outer) && c.min() > 1e-9 * h);
        let n = bore.vertices.len();
        let load = Load::pressure(bore, vec![self.pressure; n], false, TimeFunction::Constant).expect("valid load");
        model.with_loads(vec![load]).expect("the bore lies in the grid")
    }

    /// Fit u_ρ = A ρ + B / ρ² to the points' radial displacements (least squares) and
    /// return the relative errors of the fit at a and b against Lamé's.
    pub fn measure(&self, points: &PointStore<2>) -> (f64, f64) {
        let radial = radial_displacements(points);
        let [a_fit, b_fit] = least_squares(radial.iter().map(|&(rho, u)| ([rho, 1.0 / (rho * rho)], u)));
        let rel = |r: f64| {
            let exact = self.radial_displacement(r);
            (a_fit * r + b_fit / (r * r) - exact).abs() / exact.abs()
        };
        (rel(self.inner), rel(self.outer))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Lamé's solution meets its boundary conditions: σ_ρ(a) = −p, σ_ρ(b) = 0, with
    /// σ_ρ = (λ + 2μ) u' + 2λ u / ρ (derivative by central differences).
    #[test]
    fn lame_sphere_meets_its_boundary_conditions() {
        let s = ThickSphere::REFERENCE;
        let (e, nu) = (s.young, s.poisson);
        let (lambda, mu) = (e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)), e / (2.0 * (1.0 + nu)));
        let sigma = |r: f64| {
            let du = (s.radial_displacement(r + 1e-6) - s.radial_displacement(r - 1e-6)) / 2e-6;
            (lambda + 2.0 * mu) * du + 2.0 * lambda * s.radial_displacement(r) / r
        };
        assert!((sigma(s.inner) + s.pressure).abs() < 1e-6, "{}", sigma(s.inner));
        assert!(sigma(s.outer).abs() < 1e-6, "{}", sigma(s.outer));
    }
}
