//! Shared set-up for the explicit MPM tests. The verification scenes (V1a, V2, V5) and their
//! reference numbers come from `loam-verification`, the one source every consumer uses;
//! what is left here is explicit-only: the free block, the grids these tests need and the
//! state checks (finite, unchanged).

use loam_constitutive::Elastic;
use loam_explicit::{Explicit, ExplicitSettings, Kinematics, Model};
use loam_grid::{BasisKind, Grid};
use loam_points::{PointStore, Shape};
use loam_verification::{column_model_with_spare_cells, disks_model_with, Column, DiskOutline, VibratingBar};
use nalgebra::Vector2;
use std::sync::Arc;

/// The V2 bar of the verification crate (L = 25, E = 100, ρ = 1, v₀ = 0.1, h = 1).
pub const BAR: VibratingBar = VibratingBar::REFERENCE;

/// The V1a column of the verification crate (E = 1e6, ρ = 80, g = 10, H = 50).
pub const COLUMN: Column = Column::V1A;

/// Empty cells beyond the bar's free end and above the column. The blow-up tests run until
/// a point leaves the grid, so the grid's extent is part of what they check: two cells, as
/// these tests were calibrated with (the verification crate's own models keep 4 and 1).
const SPARE_CELLS: usize = 2;

/// A 2 × 1.5 block (cells of 0.5, 2×2 points per cell) in a 12 × 6 grid moving at `v`.
pub fn moving_block(basis: BasisKind, v: Vector2<f64>) -> Model<2> {
    let grid = Grid::new(Vector2::zeros(), Vector2::repeat(0.5), [24, 12]).unwrap();
    let mut points = PointStore::new();
    let block = Shape::Box { min: Vector2::new(1.0, 2.5), max: Vector2::new(3.0, 4.0) };
    points.fill(&grid, &block, 2, 1000.0, 0).unwrap();
    let law = Arc::new(Elastic::new(1e5, 0.3).unwrap());
    let mut m = Model::new(grid, basis, Kinematics::FiniteStrain, points, vec![law], vec![], Vector2::zeros()).unwrap();
    m.velocities_mut().iter_mut().for_each(|x| *x = v);
    m
}

/// V2: bar [0, L] × [0, 1] (h = 1, 2×2 points per cell) in a 27 × 1 grid; x fixed at
/// x = 0, rollers (y fixed) on the bottom and top node planes, so the motion is 1D;
/// v(x, 0) = v₀ sin(β₁ x), no stress, ν = 0, finite strain.
pub fn vibrating_bar(basis: BasisKind) -> Model<2> {
    BAR.model_with_spare_cells(SPARE_CELLS, 2, basis, Kinematics::FiniteStrain)
}

/// V1a column: one cell wide, `cells` cells high, 2×2 points per cell, rollers on both
/// sides and the base, gravity −g (applied at once), ν = 0; the grid has two spare cells
/// above.
pub fn self_weight_column(cells: usize, basis: BasisKind, kinematics: Kinematics) -> Model<2> {
    let h = COLUMN.height / cells as f64;
    column_model_with_spare_cells::<2>(&COLUMN, h, cells, SPARE_CELLS, 2, basis, kinematics)
}

/// The V1 error norm e_σ of the V1a column (`loam_verification::column_stress_error`).
pub fn column_stress_error(points: &PointStore<2>) -> f64 {
    loam_verification::column_stress_error(points, &COLUMN, 1)
}

pub use loam_verification::{inscribed_polygon as disk, polygon_area_ratio};

/// V5 (Sulsky et al. 1994) with the disks drawn as inscribed `sides`-gons, 2×2 points per
/// cell, finite strain.
pub fn colliding_disks(sides: usize, basis: BasisKind) -> Model<2> {
    disks_model_with(DiskOutline::Polygon { sides }, basis, Kinematics::FiniteStrain)
}

/// Kinetic plus stored elastic energy.
pub fn total_energy(m: &Model<2>) -> f64 {
    m.points().kinetic_energy() + m.stored_energy()
}

pub use loam_explicit::LeapfrogEnergy;

/// Run to the end, calling `each` after every step.
pub fn run_to_end(ex: &mut Explicit<2>, mut each: impl FnMut(&loam_explicit::ExplicitStepReport, &Model<2>)) {
    ex.run(|r, m| {
        each(r, m);
        Ok::<_, std::convert::Infallible>(())
    })
    .unwrap();
}

pub fn settings(duration: f64) -> ExplicitSettings {
    ExplicitSettings::new(duration)
}

/// Every committed point field is finite.
pub fn assert_finite(m: &Model<2>) {
    let p = &m.points();
    let v2 = |v: &[Vector2<f64>]| v.iter().all(|x| x.iter().all(|c| c.is_finite()));
    let m3 = |v: &[nalgebra::Matrix3<f64>]| v.iter().all(|x| x.iter().all(|c| c.is_finite()));
    assert!(v2(p.position()) && v2(p.velocity()) && v2(p.half_length()), "non-finite position, velocity or domain");
    assert!(m3(p.stress()) && m3(p.elastic_strain()) && m3(p.deformation_gradient()), "non-finite stress or strain");
    assert!(p.volume().iter().chain(p.history_values()).all(|c| c.is_finite()), "non-finite volume or history");
    assert!(p.volume().iter().all(|&v| v > 0.0), "non-positive volume");
}

/// The committed point state of `a` and `b` is bitwise the same.
pub fn assert_same_state(a: &Model<2>, b: &Model<2>) {
    let (p, q) = (&a.points(), &b.points());
    assert!(p.position() == q.position(), "positions differ");
    assert!(p.velocity() == q.velocity(), "velocities differ");
    assert!(p.stress() == q.stress(), "stresses differ");
    assert!(p.elastic_strain() == q.elastic_strain(), "elastic strains differ");
    assert!(p.deformation_gradient() == q.deformation_gradient(), "deformation gradients differ");
    assert!(p.volume() == q.volume(), "volumes differ");
    assert!(p.half_length() == q.half_length(), "domains differ");
    assert!(p.history_values() == q.history_values(), "histories differ");
}
