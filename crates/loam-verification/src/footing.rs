//! V3: a rigid rough strip footing pressed into weightless soil (`docs/verification.md`
//! V3). Prandtl's mechanism gives the limit pressure in closed form: q_u = (2 + π) c_u for
//! undrained (von Mises / Tresca) soil and q_u = c N_c for associated Mohr–Coulomb, with
//! N_q = e^{π tan φ} tan²(45° + φ/2) and N_c = (N_q − 1) cot φ. The run reads q_u at a
//! settlement of 0.1 B, before geometric hardening dominates.

use crate::bound::Bound;
use loam_constitutive::ConstitutiveLaw;
use loam_grid::{BasisKind, Grid};
use loam_model::{AntiLocking, Kinematics, Load, Model, PlaneConstraint, TimeFunction};
use loam_points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

/// The bounds `cargo xtask verify` checks on the footings (`docs/verification.md` §V3).
pub mod bounds {
    use super::Bound;

    /// |q_u / q_ref − 1| with the assumed strain on the finest mesh of the full sweep, for
    /// every law (the ν = 0.49 locking case among them).
    pub const Q_U: Bound = Bound::upper(0.05, "docs/verification.md §V3: |q_u/q_ref - 1| <= 5 % on the finest mesh");
    /// The largest fall of a load–settlement curve from one step to the next, over q_ref:
    /// a perfectly plastic solid's pressure never falls; Newton's 1e-9 relative residual
    /// leaves ~1e-9 q_ref of wobble, three decades below the bound, while a real fall (an
    /// unloading, a lost equilibrium) moves q by percent.
    pub const LARGEST_DROP: Bound =
        Bound::upper(1e-6, "docs/verification.md §V3: the curve is monotone to the plateau");
    /// The circular footing (axisymmetric, Tresca), rough and smooth, at 16 cells per R,
    /// against Eason & Shield's 6.05 c and Shield's 5.69 c.
    pub const CIRCULAR_Q_U: Bound = Bound::upper(
        0.05,
        "docs/verification.md §V3: circular footing within 5 % of 6.05 c (rough) and 5.69 c (smooth) at 16 cells per R",
    );
    /// Runs that stopped before 0.1 B: such a run has no q_u and hides the rest of its
    /// curve from the monotonicity check.
    pub const RUNS_STOPPED: Bound = Bound::upper(0.0, "docs/verification.md §V3: every run reaches 0.1 B");
    /// The strip footing in finite strain with F-bar, its peak pressure at 8 cells per b
    /// against (2 + π) c_u.
    pub const FINITE_STRAIN_Q: Bound = Bound::upper(
        0.05,
        "docs/verification.md §V3: finite strain with F-bar, peak within 5 % of (2 + pi) c_u at 8 cells per b",
    );
    /// Under load control (a pressure on the footing width ramped until Newton fails),
    /// |collapse pressure / q_ref − 1| on the finest mesh of the full sweep.
    pub const LOAD_CONTROLLED_COLLAPSE: Bound = Bound::upper(
        0.05,
        "docs/verification.md §V3: under load control, collapse within 5 % of (2 + pi) c_u on the finest mesh (16 cells per b in the full sweep)",
    );
    /// Under arc-length control, |peak pressure / q_ref − 1| on the finest mesh of the
    /// full sweep.
    pub const ARC_LENGTH_PEAK: Bound = Bound::upper(
        0.02,
        "docs/verification.md §V3: under arc-length control, the peak within 2 % of (2 + pi) c_u at 16 cells per b (the full sweep)",
    );
    /// Under arc-length control, the steps that failed to converge at their smallest
    /// cut-back: none, the curve is followed past the peak to the last step.
    pub const ARC_LENGTH_STOPPED: Bound =
        Bound::upper(0.0, "docs/verification.md §V3: the arc-length run takes all its steps");
    /// Newton corrections per step until the relative residual is first ≤ 1e-9, in the
    /// hardest sub-step; reported as a verdict on the finest mesh, not enforced (the
    /// count grows with the mesh, see the docs).
    pub const NEWTON_CORRECTIONS: Bound =
        Bound::upper(8.0, "docs/verification.md §V3: the issue's <= 8 Newton iterations per step to 1e-9");
}

/// V3: a rigid rough strip footing on weightless soil, half model by symmetry. Footing
/// half-width `b` = 1, domain `width`·b wide and `depth`·b deep, `cells_per_b` cells per
/// b, 2×2 points per cell, linear basis, small strain and geometrically linear (Prandtl's
/// small-deformation setting: moving the points under small-strain stresses makes the load
/// fall after its peak and jump where points cross a cell, docs/verification.md §V3);
/// rollers on the symmetry plane x = 0 and the far side, the base fixed; the top nodes
/// 0 ≤ x ≤ b pushed down by `settlement` at full load and held horizontally (rough). The
/// footing pressure is −(reaction of constraint 0)_y / b.
pub fn footing_model(
    law: Arc<dyn ConstitutiveLaw>,
    cells_per_b: usize,
    width: usize,
    depth: usize,
    settlement: f64,
    anti_locking: AntiLocking,
) -> Model<2> {
    let footing = pushed_footing(cells_per_b, depth, settlement, true);
    footing_soil(law, cells_per_b, width, depth, Some(footing), anti_locking)
}

/// The rigid footing 0 ≤ x ≤ 1 on the surface of soil `depth` deep at `cells` cells per
/// unit: its nodes pushed down `settlement` at full load and, when `rough`, held
/// horizontally (radially).
fn pushed_footing(cells: usize, depth: usize, settlement: f64, rough: bool) -> PlaneConstraint {
    let top = depth as f64;
    PlaneConstraint::new(1, depth * cells, [rough, true, false])
        .displaced([0.0, -settlement, 0.0])
        .within([0.0, top, 0.0], [1.0, top, 0.0])
}

/// V3's strip footing in finite strain (the points move, no geometric linearity):
/// the soil, supports and rough footing of [`footing_model`], 10 b wide and 5 b deep, with
/// `anti_locking` (F-bar or none).
pub fn finite_strain_footing_model(
    law: Arc<dyn ConstitutiveLaw>,
    cells_per_b: usize,
    settlement: f64,
    anti_locking: AntiLocking,
) -> Model<2> {
    let (width, depth) = (10, 5);
    let footing = pushed_footing(cells_per_b, depth, settlement, true);
    let soil = soil_model(law, cells_per_b, width, depth, Some(footing), Kinematics::FiniteStrain);
    soil.with_anti_locking(anti_locking).expect("valid footing model")
}

/// V3's soil under a rigid circular footing of radius R = b, axisymmetric (docs/theory.md
/// §20; x the radius): 6 R wide and 5 R deep, B-bar, the footing's nodes pushed down
/// `settlement` at full load and, when `rough`, held radially. Its reaction is the whole
/// footing's force.
pub fn circular_footing_model(
    law: Arc<dyn ConstitutiveLaw>,
    cells_per_r: usize,
    settlement: f64,
    rough: bool,
) -> Model<2> {
    let (width, depth) = (6, 5);
    let footing = pushed_footing(cells_per_r, depth, settlement, rough);
    footing_soil(law, cells_per_r, width, depth, Some(footing), AntiLocking::BBar)
        .with_axisymmetry()
        .expect("the footing's soil starts on the axis")
}

/// The soil of V3 on its grid and supports (rollers on x = 0 and the far side, the base
/// fixed), after `footing` when there is one: small strain, geometrically linear.
fn footing_soil(
    law: Arc<dyn ConstitutiveLaw>,
    cells_per_b: usize,
    width: usize,
    depth: usize,
    footing: Option<PlaneConstraint>,
    anti_locking: AntiLocking,
) -> Model<2> {
    soil_model(law, cells_per_b, width, depth, footing, Kinematics::SmallStrain)
        .with_anti_locking(anti_locking)
        .and_then(|m| m.with_geometrically_linear())
        .expect("valid footing model")
}

/// V3's soil with the given kinematics, no anti-locking.
fn soil_model(
    law: Arc<dyn ConstitutiveLaw>,
    cells_per_b: usize,
    width: usize,
    depth: usize,
    footing: Option<PlaneConstraint>,
    kinematics: Kinematics,
) -> Model<2> {
    let b = 1.0;
    let h = b / cells_per_b as f64;
    let (nx, ny) = (width * cells_per_b, depth * cells_per_b);
    // One empty row of cells above the surface keeps the top node plane inside the grid.
    let grid = Grid::new(Vector2::zeros(), Vector2::new(h, h), [nx, ny + 1]).expect("valid footing grid");
    let mut points = PointStore::new();
    let top = depth as f64 * b;
    points
        .fill(&grid, &Shape::Box { min: Vector2::zeros(), max: Vector2::new(width as f64 * b, top) }, 2, 1.0, 0)
        .expect("soil fits the grid");
    let supports = [
        PlaneConstraint::new(0, 0, [true, false, false]),
        PlaneConstraint::new(0, nx, [true, false, false]),
        PlaneConstraint::new(1, 0, [true, true, false]),
    ];
    let constraints = footing.into_iter().chain(supports).collect();
    Model::new(grid, BasisKind::Linear, kinematics, points, vec![law], constraints, Vector2::zeros())
        .expect("valid footing model")
}

/// V3 under load control: the soil, grid and supports of [`footing_model`], and instead of
/// the pushed footing a uniform pressure `pressure` (at full load) on the surface
/// 0 ≤ x ≤ b — a flexible smooth footing, whose limit pressure on weightless undrained
/// soil is Prandtl's (2 + π) c_u as well. The analysis ramps it until Newton fails: the
/// collapse load.
pub fn footing_load_model(
    law: Arc<dyn ConstitutiveLaw>,
    cells_per_b: usize,
    width: usize,
    depth: usize,
    pressure: f64,
    anti_locking: AntiLocking,
) -> Model<2> {
    let b = 1.0;
    let model = footing_soil(law, cells_per_b, width, depth, None, anti_locking);
    let top = depth as f64 * b;
    let soil = Shape::Box { min: Vector2::zeros(), max: Vector2::new(width as f64 * b, top) };
    let strip = (soil.boundary(b / (2 * cells_per_b) as f64).expect("valid soil boundary"))
        .select(|c| c[1] > top - 1e-9 && c[0] < b);
    let n = strip.vertices.len();
    let load = Load::pressure(strip, vec![pressure; n], false, TimeFunction::Constant).expect("valid pressure");
    model.with_loads(vec![load]).expect("the strip lies in the grid")
}

/// Prandtl's bearing capacity factor N_c = (N_q − 1) cot φ with N_q = e^{π tan φ} tan²(45° + φ/2),
/// and 2 + π at φ = 0 (the limit).
pub fn prandtl_nc(friction_deg: f64) -> f64 {
    if friction_deg == 0.0 {
        return 2.0 + std::f64::consts::PI;
    }
    let phi = friction_deg.to_radians();
    let nq = (std::f64::consts::PI * phi.tan()).exp() * (std::f64::consts::FRAC_PI_4 + phi / 2.0).tan().powi(2);
    (nq - 1.0) / phi.tan()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Prandtl's N_c against the values bearing-capacity tables give to three decimals
    /// (quoted in `docs/verification.md` §V3): 8.345, 14.835, 30.140 at φ = 10°, 20°, 30°.
    /// Small φ approaches 2 + π, the φ = 0 value, without a jump.
    #[test]
    fn prandtl_nc_matches_the_tabulated_values() {
        for (phi, nc) in [(10.0, 8.345), (20.0, 14.835), (30.0, 30.140)] {
            // the table's last decimal
            let got = prandtl_nc(phi);
            assert!((got - nc).abs() < 5e-4, "φ = {phi}: {got}");
        }
        assert_eq!(prandtl_nc(0.0), 2.0 + std::f64::consts::PI);
        // Expanding e^{π tan φ} tan²(π/4 + φ/2) = 1 + (2 + π) φ + (π²/2 + 2π + 2) φ² + O(φ³)
        // gives N_c = 2 + π + (π²/2 + 2π + 2) φ + O(φ²). At φ = 1e-6 rad the O(φ²) term and
        // the round-off of (N_q − 1)/tan φ (≈ 1e-16/φ) are both below 1e-8.
        let pi = std::f64::consts::PI;
        let phi = 1e-6;
        let linear = 2.0 + pi + (pi * pi / 2.0 + 2.0 * pi + 2.0) * phi;
        let got = prandtl_nc(phi.to_degrees());
        assert!((got - linear).abs() < 1e-8, "{got} vs {linear}");
    }
}
