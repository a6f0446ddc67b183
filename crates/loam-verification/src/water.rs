//! The water columns (`docs/verification.md` §V7): the V1 column under static groundwater
//! with a level at height h_w (half-way up, or above the top: submerged). Hydrostatics
//! gives p_w = γ_w max(0, h_w − y) at a point's current height y; the total vertical
//! stress is the weight above plus the water standing on the top,
//! σ_v(Y) = −γ_w max(0, h_w − H) − ρ g (H − Y) at initial height Y, for any deformation
//! (the cross-section does not change); the effective one is σ′_v = σ_v + p_w (the laws
//! see it; tension positive). The errors are V1's e_σ, scaled by the largest total
//! stress.

use crate::column::Column;

/// The bounds `cargo xtask verify` checks on the water cases (`docs/verification.md` §V7);
/// the columns' stresses take V1's.
pub mod bounds {
    use crate::Bound;

    /// The points' pore pressures against hydrostatics at their places, relative to the
    /// largest: the same formula evaluated twice, so round-off.
    pub const PORE_PRESSURE: Bound =
        Bound::upper(1e-12, "docs/verification.md §V7: pore pressure exact at points to 1e-12");
}
use loam_grid::BasisKind;
use loam_model::{Kinematics, Model, PhreaticLevel, Water};
use loam_points::PointStore;

/// A column of saturated soil under a level water table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaterColumn {
    /// The soil: height, stiffness, saturated density, gravity (no surcharge).
    pub column: Column,
    /// The water table's height.
    pub level: f64,
    /// γ_w.
    pub unit_weight: f64,
}

impl WaterColumn {
    /// H = 10, E = 5e3, ρ_sat = 2, g = 10 (γ_sat = 20, so γ_sat H / E = 0.04 as in V1a),
    /// γ_w = 10, the level half-way up.
    pub const HALF: WaterColumn = WaterColumn {
        column: Column { height: 10.0, young: 5e3, density: 2.0, gravity: 10.0, surcharge: 0.0 },
        level: 5.0,
        unit_weight: 10.0,
    };
    /// The same column submerged under 2 of water.
    pub const SUBMERGED: WaterColumn = WaterColumn { level: 12.0, ..WaterColumn::HALF };

    /// p_w at height `y`.
    pub fn pore_pressure(&self, y: f64) -> f64 {
        self.unit_weight * (self.level - y).max(0.0)
    }

    /// The total vertical stress at initial height `y`.
    pub fn total_stress(&self, y: f64) -> f64 {
        let c = &self.column;
        -self.unit_weight * (self.level - c.height).max(0.0) - c.density * c.gravity * (c.height - y)
    }

    /// The column on `cells` cells over its height (one wide, square cells, spare cells up
    /// to the level), 2×2 points per cell, GIMP, rollers on the sides and the base, with its
    /// water (whose force on the points also carries the water standing on the top); small
    /// strain is geometrically linear (the points keep their places).
    pub fn model(&self, cells: usize, kinematics: Kinematics) -> Model<2> {
        let c = &self.column;
        let h = c.height / cells as f64;
        let spare = ((self.level.max(c.height) - c.height) / h).ceil() as usize + 1;
        let mut model = crate::column_model_with_spare_cells::<2>(c, h, cells, spare, 2, BasisKind::Gimp, kinematics);
        if kinematics == Kinematics::SmallStrain {
            model = model.with_geometrically_linear().expect("small strain");
        }
        let water =
            Water::new(self.unit_weight, PhreaticLevel::Horizontal(self.level), model.gravity()).expect("valid water");
        model.with_water(water).expect("valid water column")
    }

    /// Errors of a finished run: e_σ of the effective and of the total vertical stress,
    /// each Σ |σ − σ_ref| V⁰ / (Σ V⁰ · max |σ_v|), and the largest |p_w − γ_w (h_w − y)|
    /// over γ_w h_w, with `pore` the points' pore pressures and y their current heights (their
    /// initial ones when `geometrically_linear`).
    pub fn errors(&self, points: &PointStore<2>, pore: &[f64], geometrically_linear: bool) -> WaterColumnErrors {
        let scale = -self.total_stress(0.0);
        let (mut eff, mut tot, mut vol, mut pw) = (0.0, 0.0, 0.0, 0.0f64);
        for (p, &pore_p) in pore.iter().enumerate() {
            let y0 = points.position0()[p][1];
            let y = if geometrically_linear { y0 } else { points.position()[p][1] };
            let s = points.stress()[p][(1, 1)];
            eff += (s - (self.total_stress(y0) + self.pore_pressure(y))).abs() * points.volume0()[p];
            tot += (s - pore_p - self.total_stress(y0)).abs() * points.volume0()[p];
            vol += points.volume0()[p];
            pw = pw.max((pore_p - self.pore_pressure(y)).abs() / self.pore_pressure(0.0));
        }
        WaterColumnErrors { effective: eff / (vol * scale), total: tot / (vol * scale), pore_pressure: pw }
    }
}

/// A water column run against hydrostatics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WaterColumnErrors {
    pub effective: f64,
    pub total: f64,
    pub pore_pressure: f64,
}
