//! Closed-form references of the verification problems (`../shared/VERIFICATION.md`,
//! `docs/verification.md`) and the error norms measured against them. Shared by the tests,
//! `cargo xtask verify`, the benches and the examples, so every consumer measures the same
//! thing the same way.

use crate::points::PointStore;

/// Principal branch W₀ of the Lambert W function for x ≥ 0 (w e^w = x), by Halley's
/// iteration from a log-based start; converged to rounding.
pub fn lambert_w0(x: f64) -> f64 {
    assert!(x >= 0.0 && x.is_finite(), "lambert_w0 is implemented for finite x >= 0, got {x}");
    if x == 0.0 {
        return 0.0;
    }
    let mut w = if x < 1.0 {
        x / (1.0 + x)
    } else {
        (1.0 + x).ln() * (1.0 - (1.0 + (1.0 + x).ln()).ln() / (2.0 + (1.0 + x).ln()))
    };
    for _ in 0..50 {
        let ew = w.exp();
        let f = w * ew - x;
        let wp1 = w + 1.0;
        let step = f / (ew * wp1 - (w + 2.0) * f / (2.0 * wp1));
        w -= step;
        if step.abs() <= 1e-16 * w.abs().max(1e-300) {
            break;
        }
    }
    w
}

/// The self-weight column of V1: height `h0`, Young's modulus, density, gravity (ν = 0,
/// rollers on the sides so that the cross-section does not change).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Column {
    pub height: f64,
    pub young: f64,
    pub density: f64,
    pub gravity: f64,
}

impl Column {
    /// V1a: small deformation, E = 1e6, ρ = 80, g = 10, H = 50.
    pub const V1A: Column = Column { height: 50.0, young: 1e6, density: 80.0, gravity: 10.0 };
    /// V1b: large deformation, 3D, E = 1e3, ρ = 50, g = 9.81, H = 0.8.
    pub const V1B: Column = Column { height: 0.8, young: 1e3, density: 50.0, gravity: 9.81 };
    /// V1c: large deformation, 2D, E = 1e5, ρ = 2000, g = 10, H = 10.
    pub const V1C: Column = Column { height: 10.0, young: 1e5, density: 2000.0, gravity: 10.0 };

    /// ρ₀ g H₀: the stress scale of the error norm.
    pub fn stress_scale(&self) -> f64 {
        self.density * self.gravity * self.height
    }

    /// Vertical Cauchy stress at the point of initial height `y0`, for any law and any
    /// deformation: the weight above per unit (unchanged) area.
    pub fn stress_yy(&self, y0: f64) -> f64 {
        -self.density * self.gravity * (self.height - y0)
    }

    /// Stretch of Hencky elasticity at initial height `y0`: λ = W(s)/s, s = ρ₀g(H₀ − Y)/E.
    pub fn hencky_stretch(&self, y0: f64) -> f64 {
        let s = self.density * self.gravity * (self.height - y0) / self.young;
        if s <= 0.0 {
            1.0
        } else {
            lambert_w0(s) / s
        }
    }

    /// Vertical displacement of the material at initial height `y0`, Hencky elasticity:
    /// u(Y) = ∫₀^Y (λ(Y') − 1) dY', by 64-point Gauss–Legendre on 16 panels (the integrand
    /// is smooth; converged to ~1e-15 relative).
    pub fn hencky_displacement(&self, y0: f64) -> f64 {
        gauss_legendre(|y| self.hencky_stretch(y) - 1.0, 0.0, y0, 16)
    }

    /// Vertical displacement of linear small-strain elasticity (M = E for ν = 0):
    /// u(Y) = −(ρ₀g/E)(H₀Y − Y²/2).
    pub fn small_strain_displacement(&self, y0: f64) -> f64 {
        -(self.density * self.gravity / self.young) * (self.height * y0 - 0.5 * y0 * y0)
    }
}

/// ∫_a^b f by `panels` panels of 8-point Gauss–Legendre.
fn gauss_legendre(f: impl Fn(f64) -> f64, a: f64, b: f64, panels: usize) -> f64 {
    // 8-point nodes and weights (Abramowitz & Stegun 25.4.30).
    const X: [f64; 4] =
        [0.183_434_642_495_649_8, 0.525_532_409_916_329, 0.796_666_477_413_626_7, 0.960_289_856_497_536_3];
    const W: [f64; 4] =
        [0.362_683_783_378_362, 0.313_706_645_877_887_3, 0.222_381_034_453_374_5, 0.101_228_536_290_376_3];
    let h = (b - a) / panels as f64;
    let mut sum = 0.0;
    for k in 0..panels {
        let c = a + (k as f64 + 0.5) * h;
        for i in 0..4 {
            sum += W[i] * (f(c - 0.5 * h * X[i]) + f(c + 0.5 * h * X[i]));
        }
    }
    sum * 0.5 * h
}

/// Errors of a column run against the closed form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColumnErrors {
    /// e_σ = Σ |σ_yy,p − σ_yy(Y_p)| V⁰_p / (Σ V⁰_p · ρ₀gH₀) (AMPLE; Wyser et al. 2020).
    pub stress: f64,
    /// |u_num − u_ref| / |u_ref| at the highest point.
    pub top_displacement: f64,
    /// Numerical displacement of the highest point.
    pub top_displacement_value: f64,
}

/// Measure a finished column run. `vertical` is the axis of gravity; `reference_u` the
/// closed-form displacement at an initial height.
pub fn column_errors<const D: usize>(
    points: &PointStore<D>,
    column: &Column,
    vertical: usize,
    reference_u: impl Fn(f64) -> f64,
) -> ColumnErrors {
    let mut num = 0.0;
    let mut vol = 0.0;
    let mut top = 0;
    for p in 0..points.len() {
        let y0 = points.position0[p][vertical];
        let s = points.stress[p][(vertical, vertical)];
        num += (s - column.stress_yy(y0)).abs() * points.volume0[p];
        vol += points.volume0[p];
        if y0 > points.position0[top][vertical] {
            top = p;
        }
    }
    let y0 = points.position0[top][vertical];
    let u = points.position[top][vertical] - y0;
    let u_ref = reference_u(y0);
    ColumnErrors {
        stress: num / (vol * column.stress_scale()),
        top_displacement: (u - u_ref).abs() / u_ref.abs(),
        top_displacement_value: u,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lambert_w_satisfies_its_definition() {
        for &x in &[1e-12, 1e-3, 0.04, 0.392, 1.0, 2.0, 10.0, 1e3] {
            let w = lambert_w0(x);
            assert!((w * w.exp() - x).abs() <= 1e-14 * x.max(1.0), "x={x} w={w}");
        }
        // W(1) = Ω, the omega constant.
        assert!((lambert_w0(1.0) - 0.567_143_290_409_783_8).abs() < 1e-15);
    }

    /// The top displacements of VERIFICATION.md's table, computed independently there.
    #[test]
    fn column_reference_displacements_match_the_published_table() {
        let cases = [(Column::V1A, -0.962009), (Column::V1B, -0.115671), (Column::V1C, -3.919632)];
        for (c, u) in cases {
            let got = c.hencky_displacement(c.height);
            // the table gives 6 decimals
            assert!((got - u).abs() < 5e-7, "{c:?}: {got} vs {u}");
        }
        assert!((Column::V1A.small_strain_displacement(50.0) + 1.0).abs() < 1e-12);
    }

    /// Prandtl's N_c against VERIFICATION.md V3, which gives it to three decimals as
    /// bearing-capacity tables do: 8.345, 14.835, 30.140 at φ = 10°, 20°, 30°. Small φ
    /// approaches 2 + π, the φ = 0 value, without a jump.
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

/// What the MPM and FEM columns share: grid, body's upper corner, constraints, gravity, law.
struct ColumnParts<const D: usize> {
    grid: crate::grid::Grid<D>,
    max: nalgebra::SVector<f64, D>,
    constraints: Vec<crate::implicit::PlaneConstraint>,
    gravity: nalgebra::SVector<f64, D>,
    law: std::sync::Arc<dyn crate::constitutive::ConstitutiveLaw>,
}

/// The V1 column's shared parts (see [`column_model`]).
fn column_parts<const D: usize>(column: &Column, width: f64, cells_high: usize) -> ColumnParts<D> {
    use crate::constitutive::Elastic;
    use crate::grid::Grid;
    use crate::implicit::PlaneConstraint;
    use nalgebra::SVector;
    assert!(D >= 2);
    let h = column.height / cells_high as f64;
    let cell = SVector::<f64, D>::from_fn(|a, _| if a == 1 { h } else { width });
    let mut cells = [1usize; D];
    cells[1] = cells_high + 1;
    let grid = Grid::new(SVector::zeros(), cell, cells).expect("valid column grid");
    let max = SVector::<f64, D>::from_fn(|a, _| if a == 1 { column.height } else { width });
    let mut constraints = Vec::new();
    for a in 0..D {
        let mut fixed = [false; 3];
        fixed[a] = true;
        constraints.push(PlaneConstraint::new(a, 0, fixed));
        if a != 1 {
            constraints.push(PlaneConstraint::new(a, 1, fixed));
        }
    }
    let mut gravity = SVector::<f64, D>::zeros();
    gravity[1] = -column.gravity;
    let law = Elastic::new(column.young, 0.0).expect("valid elastic constants");
    ColumnParts { grid, max, constraints, gravity, law: std::sync::Arc::new(law) }
}

/// The V1 column as a model: one cell wide (`width`; the cell is `width` across in every
/// horizontal axis), `cells_high` cells over the column height plus one empty cell above,
/// `points_per_cell`^D points per cell, rollers on the sides and the base, ν = 0 elastic,
/// gravity along −y (axis 1) in 2D and 3D.
pub fn column_model<const D: usize>(
    column: &Column,
    width: f64,
    cells_high: usize,
    points_per_cell: usize,
    basis: crate::grid::BasisKind,
    kinematics: crate::implicit::Kinematics,
) -> crate::implicit::Model<D> {
    use crate::implicit::Model;
    use crate::points::Shape;
    let ColumnParts { grid, max, constraints, gravity, law } = column_parts::<D>(column, width, cells_high);
    let mut points = PointStore::new();
    points
        .fill(&grid, &Shape::Box { min: nalgebra::SVector::zeros(), max }, points_per_cell, column.density, 0)
        .expect("column fits the grid");
    Model::new(grid, basis, kinematics, points, vec![law], constraints, gravity).expect("valid column model")
}

/// The V1 column as an updated Lagrangian FEM model: the same grid planes, constraints,
/// law and loads as [`column_model`], the body meshed by one element per grid cell with
/// `gauss_order`^D Gauss points each.
pub fn column_fem_model<const D: usize>(
    column: &Column,
    width: f64,
    cells_high: usize,
    gauss_order: usize,
    kinematics: crate::implicit::Kinematics,
) -> crate::implicit::Model<D> {
    use crate::grid::FeMesh;
    use crate::implicit::Model;
    let ColumnParts { grid, max, constraints, gravity, law } = column_parts::<D>(column, width, cells_high);
    let elements = std::array::from_fn(|a| if a == 1 { cells_high } else { 1 });
    let mesh = FeMesh::block(nalgebra::SVector::zeros(), max, elements, gauss_order).expect("valid column mesh");
    Model::updated_lagrangian_fem(grid, kinematics, mesh, &[column.density], &[0], vec![law], constraints, gravity)
        .expect("valid column FEM model")
}

/// V2: the axially vibrating bar (VERIFICATION.md V2). Fixed at x = 0, free at x = L,
/// ν = 0, initial velocity v₀ sin(β₁ x) along x; one cell thick with rollers, so 1D.
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

    /// Grid, constraints and law of the bar (see [`VibratingBar::model`]).
    fn parts(
        &self,
    ) -> (
        crate::grid::Grid<2>,
        Vec<crate::implicit::PlaneConstraint>,
        std::sync::Arc<dyn crate::constitutive::ConstitutiveLaw>,
    ) {
        use crate::constitutive::Elastic;
        use crate::grid::Grid;
        use crate::implicit::PlaneConstraint;
        use nalgebra::Vector2;
        let h = self.cell_size;
        let cells_long = (self.length / h).round() as usize + 4;
        let grid = Grid::new(Vector2::zeros(), Vector2::new(h, h), [cells_long, 1]).expect("valid bar grid");
        let constraints = vec![
            PlaneConstraint::new(0, 0, [true, false, false]),
            PlaneConstraint::new(1, 0, [false, true, false]),
            PlaneConstraint::new(1, 1, [false, true, false]),
        ];
        let law = Elastic::new(self.young, 0.0).expect("valid elastic constants");
        (grid, constraints, std::sync::Arc::new(law))
    }

    /// The initial velocity v₀ sin(β₁ x) along x at `x`.
    fn initial_velocity(&self, x: &nalgebra::Vector2<f64>) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::new(self.amplitude * (self.wavenumber() * x[0]).sin(), 0.0)
    }

    /// The bar as a 2D model: grid from x = 0 over L plus 4 empty cells, one cell high;
    /// x fixed at x = 0, y fixed on both y planes; `points_per_cell`² points per cell with
    /// the initial velocity v₀ sin(β₁ x).
    pub fn model(
        &self,
        points_per_cell: usize,
        basis: crate::grid::BasisKind,
        kinematics: crate::implicit::Kinematics,
    ) -> crate::implicit::Model<2> {
        use crate::implicit::Model;
        use crate::points::Shape;
        use nalgebra::Vector2;
        let (grid, constraints, law) = self.parts();
        let mut points = PointStore::new();
        let shape = Shape::Box { min: Vector2::zeros(), max: Vector2::new(self.length, self.cell_size) };
        points.fill(&grid, &shape, points_per_cell, self.density, 0).expect("bar fits the grid");
        for (v, x) in points.velocity.iter_mut().zip(&points.position) {
            *v = self.initial_velocity(x);
        }
        Model::new(grid, basis, kinematics, points, vec![law], constraints, Vector2::zeros()).expect("valid bar model")
    }

    /// The bar as an updated Lagrangian FEM model: one element per grid cell along the bar,
    /// `gauss_order`² Gauss points each, the same constraints and initial velocity (at the
    /// Gauss points; the dynamic analysis maps it to the nodes once).
    pub fn fem_model(&self, gauss_order: usize, kinematics: crate::implicit::Kinematics) -> crate::implicit::Model<2> {
        use crate::grid::FeMesh;
        use crate::implicit::Model;
        use nalgebra::Vector2;
        let (grid, constraints, law) = self.parts();
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
        let velocities: Vec<_> = model.points().position.iter().map(|x| self.initial_velocity(x)).collect();
        model.velocities_mut().copy_from_slice(&velocities);
        model
    }
}

/// Centre-of-mass velocity along `axis`.
pub fn centre_of_mass_velocity<const D: usize>(points: &PointStore<D>, axis: usize) -> f64 {
    points.momentum()[axis] / points.total_mass()
}

/// Times where a sampled signal changes sign, by linear interpolation between samples.
pub fn zero_crossings(times: &[f64], values: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    for k in 1..times.len().min(values.len()) {
        let (a, b) = (values[k - 1], values[k]);
        if a == 0.0 && k == 1 {
            out.push(times[0]);
        }
        if (a < 0.0 && b >= 0.0) || (a > 0.0 && b <= 0.0) {
            if b == 0.0 {
                out.push(times[k]);
            } else {
                out.push(times[k - 1] + (times[k] - times[k - 1]) * a / (a - b));
            }
        }
    }
    out.dedup();
    out
}

/// Period of an oscillation from its zero crossings: twice the mean spacing from the first
/// crossing to the last. `None` with fewer than two crossings.
pub fn period_from_crossings(crossings: &[f64]) -> Option<f64> {
    if crossings.len() < 2 {
        return None;
    }
    let n = crossings.len() - 1;
    Some(2.0 * (crossings[n] - crossings[0]) / n as f64)
}

/// Time histories of a dynamic run, sampled after every step: centre-of-mass velocity,
/// kinetic and stored energy. Shared by the tests, `cargo xtask verify` and `steps`.
#[derive(Debug, Clone, Default)]
pub struct DynamicRecord {
    pub time: Vec<f64>,
    /// Centre-of-mass velocity along x.
    pub vcm_x: Vec<f64>,
    pub kinetic: Vec<f64>,
    pub stored: Vec<f64>,
}

impl DynamicRecord {
    pub fn push<const D: usize>(&mut self, time: f64, model: &crate::model::Model<D>) {
        self.time.push(time);
        self.vcm_x.push(centre_of_mass_velocity(&model.points(), 0));
        self.kinetic.push(model.points().kinetic_energy());
        self.stored.push(model.stored_energy());
    }

    /// Kinetic + stored energy at sample k.
    pub fn energy(&self, k: usize) -> f64 {
        self.kinetic[k] + self.stored[k]
    }
}

/// Errors of a vibrating-bar run (VERIFICATION.md V2 norms).
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

impl VibratingBar {
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

/// V5: two elastic disks colliding (Sulsky, Chen & Schreyer 1994; VERIFICATION.md V5) on
/// the unit square, 20 × 20 cells, 2 × 2 points per cell, linear basis (the disks touch the
/// grid's faces, which GIMP domains would cross).
pub fn disks_model(kinematics: crate::implicit::Kinematics) -> crate::model::Model<2> {
    use crate::constitutive::Elastic;
    use crate::grid::{BasisKind, Grid};
    use crate::model::Model;
    use crate::points::Shape;
    use nalgebra::Vector2;
    use std::sync::Arc;
    let grid = Grid::new(Vector2::zeros(), Vector2::new(0.05, 0.05), [20, 20]).expect("valid disk grid");
    let mut points = PointStore::new();
    for (centre, v) in [(Vector2::new(0.2, 0.2), 0.1), (Vector2::new(0.8, 0.8), -0.1)] {
        let first = points.len();
        points.fill(&grid, &Shape::Ball { centre, radius: 0.2 }, 2, 1000.0, 0).expect("disk fits the grid");
        for p in first..points.len() {
            points.velocity[p] = Vector2::new(v, v);
        }
    }
    let law = Elastic::new(1000.0, 0.3).expect("valid elastic constants");
    Model::new(grid, BasisKind::Linear, kinematics, points, vec![Arc::new(law)], vec![], Vector2::zeros())
        .expect("valid disk model")
}

/// V3: a rigid rough strip footing on weightless soil (VERIFICATION.md V3), half model by
/// symmetry. Footing half-width `b` = 1, domain `width`·b wide and `depth`·b deep,
/// `cells_per_b` cells per b, 2×2 points per cell, linear basis, small strain and
/// geometrically linear (Prandtl's small-deformation setting: moving the points under
/// small-strain stresses makes the load fall after its peak and jump where points cross
/// a cell, docs/verification.md V3); rollers on
/// the symmetry plane x = 0 and the far side, the base fixed; the top nodes 0 ≤ x ≤ b pushed
/// down by `settlement` at full load and held horizontally (rough). The footing pressure
/// is −(reaction of constraint 0)_y / b.
pub fn footing_model(
    law: std::sync::Arc<dyn crate::constitutive::ConstitutiveLaw>,
    cells_per_b: usize,
    width: usize,
    depth: usize,
    settlement: f64,
    anti_locking: crate::model::AntiLocking,
) -> crate::model::Model<2> {
    use crate::grid::{BasisKind, Grid};
    use crate::model::{Kinematics, Model, PlaneConstraint};
    use crate::points::Shape;
    use nalgebra::Vector2;
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
    let constraints = vec![
        PlaneConstraint::new(1, ny, [true, true, false])
            .displaced([0.0, -settlement, 0.0])
            .within([0.0, top, 0.0], [b, top, 0.0]),
        PlaneConstraint::new(0, 0, [true, false, false]),
        PlaneConstraint::new(0, nx, [true, false, false]),
        PlaneConstraint::new(1, 0, [true, true, false]),
    ];
    Model::new(grid, BasisKind::Linear, Kinematics::SmallStrain, points, vec![law], constraints, Vector2::zeros())
        .and_then(|m| m.with_anti_locking(anti_locking))
        .and_then(|m| m.with_geometrically_linear())
        .expect("valid footing model")
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

/// The geometry of a V4 slope (VERIFICATION.md V4), in units of the slope height H: the
/// foundation layer `depth` deep, the toe `toe` from the left side, the face rising over a
/// horizontal `run` (1 for 45°, 2 for a 2:1 slope), the crest flat `crest` long.
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
    pub fn outline(&self) -> Vec<nalgebra::Vector2<f64>> {
        use nalgebra::Vector2;
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
    law: std::sync::Arc<dyn crate::constitutive::ConstitutiveLaw>,
    density: f64,
    gravity: f64,
    cells_per_h: usize,
    anti_locking: crate::model::AntiLocking,
) -> crate::model::Model<2> {
    use crate::grid::BasisKind;
    use crate::model::Kinematics;
    slope_model_with(geometry, law, density, gravity, cells_per_h, BasisKind::Linear, Kinematics::SmallStrain)
        .with_anti_locking(anti_locking)
        .expect("valid slope model")
}

/// [`slope_model`] with any basis and kinematics and no anti-locking: the large-
/// deformation run-out (GIMP, finite strain).
pub fn slope_model_with(
    geometry: &SlopeGeometry,
    law: std::sync::Arc<dyn crate::constitutive::ConstitutiveLaw>,
    density: f64,
    gravity: f64,
    cells_per_h: usize,
    basis: crate::grid::BasisKind,
    kinematics: crate::model::Kinematics,
) -> crate::model::Model<2> {
    use crate::grid::Grid;
    use crate::model::{Model, PlaneConstraint};
    use crate::points::Shape;
    use nalgebra::Vector2;
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

/// The V1 column in two layers, the upper half `contrast` times softer than the lower (a
/// hard case: a stiffness contrast across one cell face), small strain, ν = 0. The stress
/// is still the weight above, σ_yy = −ρg(H − Y); the displacement integrates σ/E layer by
/// layer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayeredColumn {
    pub column: Column,
    pub contrast: f64,
}

impl LayeredColumn {
    /// u(Y) = ∫₀^Y σ_yy/E(Y') dY', E = E₀ below H/2 and E₀/contrast above.
    pub fn displacement(&self, y0: f64) -> f64 {
        let c = &self.column;
        let half = 0.5 * c.height;
        let integral = |a: f64, b: f64| c.height * (b - a) - 0.5 * (b * b - a * a);
        let rg = c.density * c.gravity;
        let lower = -rg / c.young * integral(0.0, y0.min(half));
        let upper = if y0 > half { -rg * self.contrast / c.young * integral(half, y0) } else { 0.0 };
        lower + upper
    }

    /// One cell wide, `cells_high` (even) cells over the height, 2×2 points per cell, the
    /// layer interface on a cell face.
    pub fn model(&self, cells_high: usize, basis: crate::grid::BasisKind) -> crate::implicit::Model<2> {
        use crate::constitutive::Elastic;
        use crate::implicit::{Kinematics, Model};
        use crate::points::Shape;
        use nalgebra::Vector2;
        assert!(cells_high % 2 == 0, "the interface must lie on a cell face");
        let c = &self.column;
        let width = c.height / cells_high as f64;
        let ColumnParts { grid, max, constraints, gravity, law } = column_parts::<2>(c, width, cells_high);
        let soft = Elastic::new(c.young / self.contrast, 0.0).expect("valid soft layer");
        let mut points = PointStore::new();
        let half = 0.5 * c.height;
        points
            .fill(&grid, &Shape::Box { min: Vector2::zeros(), max: Vector2::new(max[0], half) }, 2, c.density, 0)
            .expect("lower layer fits");
        points
            .fill(&grid, &Shape::Box { min: Vector2::new(0.0, half), max }, 2, c.density, 1)
            .expect("upper layer fits");
        Model::new(
            grid,
            basis,
            Kinematics::SmallStrain,
            points,
            vec![law, std::sync::Arc::new(soft)],
            constraints,
            gravity,
        )
        .expect("valid layered column")
    }
}

/// A hard case: plane-strain compression of a softening von Mises specimen (1 × 2, quarter
/// model: rollers on the left and the base), the top pushed down by `shortening` with the
/// load factor. σ_y = 100 softening at H = −500 (E = 1e4, ν = 0.3) to 30; a 0.25 × 0.25
/// weaker corner (σ_y = 90) at the origin seeds the shear band. Linear basis, B-bar,
/// `cells_across` cells over the width; the grid reaches `margin` widths beyond the right
/// side, where the specimen bulges.
pub fn softening_specimen(cells_across: usize, margin: f64, shortening: f64) -> crate::model::Model<2> {
    use crate::constitutive::{ConstitutiveLaw, Elastic, VonMises};
    use crate::grid::{BasisKind, Grid};
    use crate::model::{AntiLocking, Kinematics, Model, PlaneConstraint};
    use crate::points::Shape;
    use nalgebra::Vector2;
    let n = cells_across;
    let h = 1.0 / n as f64;
    let extra = (margin * n as f64).ceil() as usize;
    let grid = Grid::new(Vector2::zeros(), Vector2::new(h, h), [n + extra, 2 * n + 1]).expect("valid specimen grid");
    let elastic = Elastic::new(1e4, 0.3).expect("valid elasticity");
    let law = |yield_stress: f64| -> std::sync::Arc<dyn ConstitutiveLaw> {
        std::sync::Arc::new(
            VonMises::new(elastic, yield_stress, -500.0)
                .and_then(|l| l.with_residual_yield_stress(0.3 * yield_stress))
                .expect("valid softening law"),
        )
    };
    let w = 0.25;
    let mut points = PointStore::new();
    let outline = [(w, 0.0), (1.0, 0.0), (1.0, 2.0), (0.0, 2.0), (0.0, w), (w, w)].map(|(x, y)| Vector2::new(x, y));
    points.fill(&grid, &Shape::Polygon(outline.to_vec()), 2, 1.0, 0).expect("specimen fits the grid");
    points
        .fill(&grid, &Shape::Box { min: Vector2::zeros(), max: Vector2::new(w, w) }, 2, 1.0, 1)
        .expect("weak corner fits");
    let constraints = vec![
        PlaneConstraint::new(1, 2 * n, [false, true, false]).displaced([0.0, -shortening, 0.0]),
        PlaneConstraint::new(1, 0, [false, true, false]),
        PlaneConstraint::new(0, 0, [true, false, false]),
    ];
    Model::new(
        grid,
        BasisKind::Linear,
        Kinematics::SmallStrain,
        points,
        vec![law(100.0), law(90.0)],
        constraints,
        Vector2::zeros(),
    )
    .and_then(|m| m.with_anti_locking(AntiLocking::BBar))
    .expect("valid specimen")
}

/// A hard case for small cuts: a 4 h × 4 h elastic block (E = 1e3, ν = 0.3, unit density)
/// on a fixed base under gravity 10, shifted along x so that its right face lies
/// `overlap` of a cell into the next cell (h = 1, 10 × 6 cells), small strain. With GIMP
/// the rightmost point domains reach that cell by `overlap` h, and its far nodes get
/// weights ~ overlap² and stiffness ~ overlap².
pub fn translated_block(
    overlap: f64,
    basis: crate::grid::BasisKind,
    ghost_penalty: Option<f64>,
) -> crate::model::Model<2> {
    use crate::constitutive::Elastic;
    use crate::grid::Grid;
    use crate::model::{Kinematics, Model, PlaneConstraint};
    use crate::points::Shape;
    use nalgebra::Vector2;
    let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [10, 6]).expect("valid grid");
    // Points at the sub-cell centres of the block's own cells, not of the grid's.
    let shift = 2.0 + overlap;
    let block_cells = Grid::new(Vector2::new(shift, 0.0), Vector2::new(1.0, 1.0), [4, 4]).expect("valid block cells");
    let mut points = PointStore::new();
    points
        .fill(
            &block_cells,
            &Shape::Box { min: Vector2::new(shift, 0.0), max: Vector2::new(shift + 4.0, 4.0) },
            2,
            1.0,
            0,
        )
        .expect("block fits");
    let law = std::sync::Arc::new(Elastic::new(1e3, 0.3).expect("valid elasticity"));
    let model = Model::new(
        grid,
        basis,
        Kinematics::SmallStrain,
        points,
        vec![law],
        vec![PlaneConstraint::new(1, 0, [true, true, false])],
        Vector2::new(0.0, -10.0),
    )
    .expect("valid block");
    match ghost_penalty {
        Some(gamma) => model.with_ghost_penalty(gamma).expect("valid ghost penalty"),
        None => model,
    }
}

/// The 2-norm condition number of a symmetric tangent restricted to its free dofs, by a
/// dense eigen-decomposition: for the small models of the hard-case studies only.
pub fn condition_number(pattern: &crate::solve::BlockPattern, values: &[f64], constrained: &[bool]) -> f64 {
    let n = pattern.num_dofs();
    let free: Vec<usize> = (0..n).filter(|&i| !constrained[i]).collect();
    let mut index = vec![usize::MAX; n];
    for (k, &i) in free.iter().enumerate() {
        index[i] = k;
    }
    let mut k = nalgebra::DMatrix::<f64>::zeros(free.len(), free.len());
    for c in 0..n {
        for idx in pattern.col_ptr()[c]..pattern.col_ptr()[c + 1] {
            let r = pattern.row_idx()[idx];
            if index[r] != usize::MAX && index[c] != usize::MAX {
                k[(index[r], index[c])] += values[idx];
            }
        }
    }
    let eigenvalues = k.symmetric_eigen().eigenvalues;
    eigenvalues.iter().fold(0.0f64, |m, v| m.max(v.abs()))
        / eigenvalues.iter().fold(f64::INFINITY, |m, v| m.min(v.abs()))
}
