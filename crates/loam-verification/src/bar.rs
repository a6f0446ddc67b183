//! V2: the axially vibrating bar (`docs/verification.md` §V2). A bar of length L fixed at
//! x = 0 and free at x = L, one cell thick with rollers so that it is one-dimensional,
//! ν = 0, starting unstressed with the velocity of its first mode, v₀ sin(β₁x). Its exact
//! motion is that mode: β₁ = π/(2L), ω₁ = β₁c, c = √(E/ρ), period T = 4L/c, centre-of-mass
//! velocity (2v₀/π) cos(ω₁t), energy ρv₀²L/4 per unit thickness. The time integrators
//! change the period in known ways (the trapezoidal rule stretches it by
//! ω₁Δt / (2 arctan(ω₁Δt/2)); lumped linear elements carry the discrete frequency of
//! Hughes 2000, §9.1), so the measured period is compared with the period the scheme
//! should produce. The norms: period from the zero crossings of v_cm, the largest v_cm
//! error relative to its amplitude, the energy drift over the run.

use crate::bound::Bound;
use crate::dynamics::{period_from_crossings, zero_crossings, DynamicRecord};
use loam_constitutive::{ConstitutiveLaw, Elastic};
use loam_grid::{BasisKind, FeMesh, Grid};
use loam_model::{Kinematics, Model, PlaneConstraint};
use loam_points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

/// The bounds `cargo xtask verify` checks on the bar (`docs/verification.md` §V2).
pub mod bounds {
    use super::Bound;

    /// Implicit MPM (trapezoidal, lumped mass): |period / trapezoidal period − 1|; what is
    /// left is the spatial error of 25 cells, ~5e-4.
    pub const IMPLICIT_PERIOD_ERROR: Bound =
        Bound::upper(5e-3, "docs/verification.md §V2: the period sits on the trapezoidal curve within 0.5 %");
    /// Implicit MPM: energy drift over 3 periods, checked at [`ENERGY_DRIFT_TIME_STEP`]:
    /// the trapezoidal rule conserves energy on the grid, the point–grid transfer loses
    /// a little.
    pub const IMPLICIT_ENERGY_DRIFT: Bound =
        Bound::upper(1e-2, "docs/verification.md §V2: energy drift <= 1 % over 3 periods at dt = 0.5, lumped mass");
    /// The time step at which [`IMPLICIT_ENERGY_DRIFT`] is checked.
    pub const ENERGY_DRIFT_TIME_STEP: f64 = 0.5;
    /// UL-FEM (trapezoidal, lumped mass): |period / discrete trapezoidal period − 1|, the
    /// implicit MPM's bound applied to the FEM reference.
    pub const FEM_PERIOD_ERROR: Bound =
        Bound::upper(5e-3, "docs/verification.md §V2: as the implicit MPM, against the lumped FEM's discrete period");
    /// Explicit MUSL at 0.9 of the critical step runs to the end (1 = yes).
    pub const EXPLICIT_STABLE: Bound = Bound::lower(1.0, "docs/verification.md §V2: stable below the critical step");
    /// Explicit MUSL at 0.9 of the critical step: |period / T − 1|.
    pub const EXPLICIT_PERIOD_ERROR: Bound =
        Bound::upper(1e-2, "docs/verification.md §V2: period within 1 % of T = 4L/c");
    /// Explicit MUSL at twice the critical step is stopped as unstable (1 = yes).
    pub const EXPLICIT_BLOW_UP_DETECTED: Bound =
        Bound::lower(1.0, "docs/verification.md §V2: a step above the limit is detected, never silent");
}

/// V2: the axially vibrating bar. Fixed at x = 0, free at x = L, ν = 0, initial velocity
/// v₀ sin(β₁ x) along x; one cell thick with rollers, so 1D.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct VibratingBar {
    pub length: f64,
    pub young: f64,
    pub density: f64,
    pub amplitude: f64,
    pub cell_size: f64,
}

impl VibratingBar {
    /// Reference parameters: L = 25, E = 100, ρ = 1, v₀ = 0.1, h = 1 (T = 10).
    pub const REFERENCE: Self = Self { length: 25.0, young: 100.0, density: 1.0, amplitude: 0.1, cell_size: 1.0 };

    /// Empty cells beyond the free end in [`VibratingBar::model`] and
    /// [`VibratingBar::fem_model`]: room for the bar to stretch.
    pub const SPARE_CELLS: usize = 4;

    /// Bar wave speed c = √(E/ρ).
    pub fn wave_speed(&self) -> f64 {
        (self.young / self.density).sqrt()
    }

    /// β₁ = π / (2L).
    pub fn wavenumber(&self) -> f64 {
        std::f64::consts::PI / (2.0 * self.length)
    }

    /// ω₁ = β₁ c.
    pub fn omega(&self) -> f64 {
        self.wavenumber() * self.wave_speed()
    }

    /// T = 4L / c.
    pub fn period(&self) -> f64 {
        4.0 * self.length / self.wave_speed()
    }

    /// Centre-of-mass velocity (2v₀/π) cos(ω₁ t).
    pub fn centre_of_mass_velocity(&self, t: f64) -> f64 {
        2.0 * self.amplitude / std::f64::consts::PI * (self.omega() * t).cos()
    }

    /// Total energy per unit thickness ρ v₀² L / 4 (times the cell thickness h).
    pub fn energy(&self) -> f64 {
        self.density * self.amplitude.powi(2) * self.length / 4.0 * self.cell_size
    }

    /// The trapezoidal rule's period elongation ωΔt / (2 arctan(ωΔt/2)).
    pub fn trapezoidal_period_factor(&self, dt: f64) -> f64 {
        let w = self.omega() * dt;
        w / (2.0 * (w / 2.0).atan())
    }

    /// Period of the first mode of the lumped-mass linear-element bar (the FEM reference)
    /// under the trapezoidal rule: ω_h = (2c/h) sin(β₁h/2) (Hughes 2000, §9.1), the mode
    /// shape being sampled exactly at the nodes, stretched by ω_hΔt / (2 arctan(ω_hΔt/2)).
    pub fn lumped_fem_period(&self, dt: f64) -> f64 {
        let h = self.cell_size;
        let omega_h = 2.0 * self.wave_speed() / h * (self.wavenumber() * h / 2.0).sin();
        let w = omega_h * dt;
        2.0 * std::f64::consts::PI / omega_h * w / (2.0 * (w / 2.0).atan())
    }

    /// Explicit critical step h / c.
    pub fn critical_time_step(&self) -> f64 {
        self.cell_size / self.wave_speed()
    }

    /// Grid (the bar and `spare_cells` beyond its free end, one cell high), constraints
    /// and law of the bar.
    fn parts(&self, spare_cells: usize) -> (Grid<2>, Vec<PlaneConstraint>, Arc<dyn ConstitutiveLaw>) {
        let h = self.cell_size;
        let cells_long = (self.length / h).round() as usize + spare_cells;
        let grid = Grid::new(Vector2::zeros(), Vector2::new(h, h), [cells_long, 1]).expect("valid bar grid");
        let constraints = vec![
            PlaneConstraint::new(0, 0, [true, false, false]),
            PlaneConstraint::new(1, 0, [false, true, false]),
            PlaneConstraint::new(1, 1, [false, true, false]),
        ];
        let law = Elastic::new(self.young, 0.0).expect("valid elastic constants");
        (grid, constraints, Arc::new(law))
    }

    /// The initial velocity v₀ sin(β₁ x) along x at `x`.
    fn initial_velocity(&self, x: &Vector2<f64>) -> Vector2<f64> {
        Vector2::new(self.amplitude * (self.wavenumber() * x[0]).sin(), 0.0)
    }

    /// The bar as a 2D model: grid from x = 0 over L plus [`VibratingBar::SPARE_CELLS`]
    /// empty cells, one cell high; x fixed at x = 0, y fixed on both y planes;
    /// `points_per_cell`² points per cell with the initial velocity v₀ sin(β₁ x).
    pub fn model(&self, points_per_cell: usize, basis: BasisKind, kinematics: Kinematics) -> Model<2> {
        self.model_with_spare_cells(Self::SPARE_CELLS, points_per_cell, basis, kinematics)
    }

    /// [`VibratingBar::model`] with `spare_cells` empty cells beyond the free end. Where a
    /// run is driven past its stability limit, the grid's end decides when a point leaves
    /// it, so a test of that moment fixes this number.
    pub fn model_with_spare_cells(
        &self,
        spare_cells: usize,
        points_per_cell: usize,
        basis: BasisKind,
        kinematics: Kinematics,
    ) -> Model<2> {
        let (grid, constraints, law) = self.parts(spare_cells);
        let mut points = PointStore::new();
        let shape = Shape::Box { min: Vector2::zeros(), max: Vector2::new(self.length, self.cell_size) };
        points.fill(&grid, &shape, points_per_cell, self.density, 0).expect("bar fits the grid");
        let view = points.view_mut();
        for (v, x) in view.velocity.iter_mut().zip(view.position.iter()) {
            *v = self.initial_velocity(x);
        }
        Model::new(grid, basis, kinematics, points, vec![law], constraints, Vector2::zeros()).expect("valid bar model")
    }

    /// The bar as an updated Lagrangian FEM model: one element per grid cell along the bar,
    /// `gauss_order`² Gauss points each, the same constraints and initial velocity (at the
    /// Gauss points; the dynamic analysis maps it to the nodes once).
    pub fn fem_model(&self, gauss_order: usize, kinematics: Kinematics) -> Model<2> {
        let (grid, constraints, law) = self.parts(Self::SPARE_CELLS);
        let elements = [(self.length / self.cell_size).round() as usize, 1];
        let mesh = FeMesh::block(Vector2::zeros(), Vector2::new(self.length, self.cell_size), elements, gauss_order)
            .expect("valid bar mesh");
        let mut model = Model::updated_lagrangian_fem(
            grid,
            kinematics,
            mesh,
            &[self.density],
            &[0],
            vec![law],
            constraints,
            Vector2::zeros(),
        )
        .expect("valid bar FEM model");
        let velocities: Vec<_> = model.points().position().iter().map(|x| self.initial_velocity(x)).collect();
        model.velocities_mut().copy_from_slice(&velocities);
        model
    }

    /// The V2 norms of a recorded run.
    pub fn errors(&self, record: &DynamicRecord) -> BarErrors {
        let scale = 2.0 * self.amplitude / std::f64::consts::PI;
        let vcm_error = record
            .time
            .iter()
            .zip(&record.vcm_x)
            .map(|(&t, &v)| (v - self.centre_of_mass_velocity(t)).abs() / scale)
            .fold(0.0, f64::max);
        let n = record.time.len();
        let e0 = record.energy(0);
        let energy_growth = (0..n).map(|k| (record.energy(k) - e0) / e0).fold(f64::NEG_INFINITY, f64::max);
        BarErrors {
            period: period_from_crossings(&zero_crossings(&record.time, &record.vcm_x)).unwrap_or(f64::NAN),
            vcm_error,
            energy_drift: (record.energy(n - 1) - e0).abs() / e0,
            energy_growth,
        }
    }
}

/// Errors of a vibrating-bar run (the V2 norms).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BarErrors {
    /// Period measured from the zero crossings of v_cm (NaN with fewer than two).
    pub period: f64,
    /// max over samples of |v_cm − v_cm,exact| / (2v₀/π).
    pub vcm_error: f64,
    /// |E(t_end) − E(0)| / E(0).
    pub energy_drift: f64,
    /// max over samples of (E(t) − E(0)) / E(0): positive when energy grew.
    pub energy_growth: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference bar's figures of `docs/verification.md` §V2: T = 10, h/c = 0.1, the
    /// energy ρv₀²L/4, and the trapezoidal periods its table gives to five decimals.
    #[test]
    fn the_reference_bar_has_the_documented_figures() {
        let bar = VibratingBar::REFERENCE;
        assert_eq!((bar.period(), bar.critical_time_step()), (10.0, 0.1));
        assert!((bar.energy() - 0.0625).abs() < 1e-15);
        for (dt, period) in [(0.1, 10.00329), (0.5, 10.08171), (1.0, 10.32075)] {
            let got = bar.period() * bar.trapezoidal_period_factor(dt);
            assert!((got - period).abs() < 5e-6, "dt = {dt}: {got}");
        }
    }

    /// The spare cells lengthen the grid only.
    #[test]
    fn spare_cells_change_the_grid_and_nothing_else() {
        let bar = VibratingBar::REFERENCE;
        let (a, b) = (
            bar.model(2, BasisKind::Linear, Kinematics::FiniteStrain),
            bar.model_with_spare_cells(2, 2, BasisKind::Linear, Kinematics::FiniteStrain),
        );
        assert_eq!((a.grid().cells(), b.grid().cells()), ([29, 1], [27, 1]));
        assert_eq!(a.points().position(), b.points().position());
        assert_eq!(a.points().velocity(), b.points().velocity());
    }
}
