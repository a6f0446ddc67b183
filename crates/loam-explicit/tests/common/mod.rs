//! Shared set-up for the explicit MPM tests: the verification scenes (VERIFICATION.md V1a,
//! V2, V5 and a free block), their measures (energy, the V1 stress error norm) and state
//! checks (finite, unchanged).

use loam_constitutive::{ConstitutiveLaw, Elastic};
use loam_explicit::{Explicit, ExplicitSettings, Kinematics, Model, PlaneConstraint};
use loam_grid::{BasisKind, Grid};
use loam_points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

pub fn elastic(young: f64, poisson: f64) -> Arc<dyn ConstitutiveLaw> {
    Arc::new(Elastic::new(young, poisson).unwrap())
}

/// A roller (normal component fixed) on node plane `plane` of `axis`.
pub fn roller(axis: usize, plane: usize) -> PlaneConstraint {
    let mut fixed = [false; 3];
    fixed[axis] = true;
    PlaneConstraint::new(axis, plane, fixed)
}

/// One elastic material filling `shapes` with `ppc`² points per cell, no constraints or
/// gravity; the caller adds what the scene needs.
#[allow(clippy::too_many_arguments)]
pub fn scene(
    cell: f64,
    cells: [usize; 2],
    shapes: &[Shape<2>],
    ppc: usize,
    density: f64,
    law: Arc<dyn ConstitutiveLaw>,
    basis: BasisKind,
    kinematics: Kinematics,
) -> Model<2> {
    scene_with(cell, cells, shapes, ppc, density, law, basis, kinematics, vec![], Vector2::zeros())
}

/// [`scene`] with constraints and gravity.
#[allow(clippy::too_many_arguments)]
pub fn scene_with(
    cell: f64,
    cells: [usize; 2],
    shapes: &[Shape<2>],
    ppc: usize,
    density: f64,
    law: Arc<dyn ConstitutiveLaw>,
    basis: BasisKind,
    kinematics: Kinematics,
    constraints: Vec<PlaneConstraint>,
    gravity: Vector2<f64>,
) -> Model<2> {
    let grid = Grid::new(Vector2::zeros(), Vector2::repeat(cell), cells).unwrap();
    let mut points = PointStore::new();
    for s in shapes {
        points.fill(&grid, s, ppc, density, 0).unwrap();
    }
    Model::new(grid, basis, kinematics, points, vec![law], constraints, gravity).unwrap()
}

pub fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Shape<2> {
    Shape::Box { min: Vector2::new(x0, y0), max: Vector2::new(x1, y1) }
}

/// A 2 × 1.5 block (cells of 0.5, 2×2 points per cell) in a 12 × 6 grid moving at `v`.
pub fn moving_block(basis: BasisKind, v: Vector2<f64>) -> Model<2> {
    let mut m = scene(
        0.5,
        [24, 12],
        &[rect(1.0, 2.5, 3.0, 4.0)],
        2,
        1000.0,
        elastic(1e5, 0.3),
        basis,
        Kinematics::FiniteStrain,
    );
    m.velocities_mut().iter_mut().for_each(|x| *x = v);
    m
}

/// VERIFICATION.md V2 reference parameters.
pub mod bar {
    pub const L: f64 = 25.0;
    pub const E: f64 = 100.0;
    pub const RHO: f64 = 1.0;
    pub const V0: f64 = 0.1;
    /// Wave speed √(E/ρ).
    pub fn c() -> f64 {
        (E / RHO).sqrt()
    }
    /// Period 4L/c = 10.
    pub fn period() -> f64 {
        4.0 * L / c()
    }
    pub fn beta() -> f64 {
        std::f64::consts::PI / (2.0 * L)
    }
    /// Centre-of-mass velocity (2 v₀/π) cos(ω₁ t).
    pub fn v_cm(t: f64) -> f64 {
        2.0 * V0 / std::f64::consts::PI * (beta() * c() * t).cos()
    }
}

/// V2: bar [0, L] × [0, 1] (h = 1, 2×2 points per cell) in a 27 × 1 grid; x fixed at
/// x = 0, rollers (y fixed) on the bottom and top node planes, so the motion is 1D;
/// v(x, 0) = v₀ sin(β₁ x), no stress, ν = 0.
pub fn vibrating_bar(basis: BasisKind) -> Model<2> {
    let mut m = scene_with(
        1.0,
        [27, 1],
        &[rect(0.0, 0.0, bar::L, 1.0)],
        2,
        bar::RHO,
        elastic(bar::E, 0.0),
        basis,
        Kinematics::FiniteStrain,
        vec![roller(0, 0), roller(1, 0), roller(1, 1)],
        Vector2::zeros(),
    );
    let x: Vec<f64> = m.points().position.iter().map(|x| x.x).collect();
    for (v, x) in m.velocities_mut().iter_mut().zip(x) {
        *v = Vector2::new(bar::V0 * (bar::beta() * x).sin(), 0.0);
    }
    m
}

/// VERIFICATION.md V1a parameters.
pub mod column {
    pub const E: f64 = 1e6;
    pub const RHO: f64 = 80.0;
    pub const G: f64 = 10.0;
    pub const H: f64 = 50.0;
}

/// V1a-like column: one cell wide, `cells` cells high, 2×2 points per cell, rollers on
/// both sides and the base, gravity −g (applied at once), ν = 0; the grid has two spare
/// cells above.
pub fn self_weight_column(cells: usize, basis: BasisKind, kinematics: Kinematics) -> Model<2> {
    let h = column::H / cells as f64;
    scene_with(
        h,
        [1, cells + 2],
        &[rect(0.0, 0.0, h, column::H)],
        2,
        column::RHO,
        elastic(column::E, 0.0),
        basis,
        kinematics,
        vec![roller(0, 0), roller(0, 1), roller(1, 0)],
        Vector2::new(0.0, -column::G),
    )
}

/// VERIFICATION.md V1 error norm: e_σ = Σ|σ_yy,p − σ_yy(Y_p)| V⁰_p / (Σ V⁰_p ρ g H), with
/// σ_yy(Y) = −ρ g (H − Y) at the point's initial height Y.
pub fn column_stress_error(points: &PointStore<2>) -> f64 {
    let (mut num, mut vol) = (0.0, 0.0);
    for p in 0..points.len() {
        let exact = -column::RHO * column::G * (column::H - points.position0[p].y);
        num += (points.stress[p][(1, 1)] - exact).abs() * points.volume0[p];
        vol += points.volume0[p];
    }
    num / (vol * column::RHO * column::G * column::H)
}

/// A regular polygon of `sides` vertices inscribed in the circle (centre, r).
pub fn disk(centre: Vector2<f64>, r: f64, sides: usize) -> Shape<2> {
    Shape::Polygon(
        (0..sides)
            .map(|k| {
                let a = 2.0 * std::f64::consts::PI * k as f64 / sides as f64;
                centre + Vector2::new(a.cos(), a.sin()) * r
            })
            .collect(),
    )
}

/// Area of the regular `sides`-gon inscribed in a circle, relative to the circle.
pub fn polygon_area_ratio(sides: usize) -> f64 {
    let n = sides as f64;
    0.5 * n * (2.0 * std::f64::consts::PI / n).sin() / std::f64::consts::PI
}

/// V5 (Sulsky et al. 1994): unit square, 20 × 20 cells, two disks r = 0.2 at (0.2, 0.2)
/// and (0.8, 0.8) as `sides`-gons with 2×2 points per cell, E = 1000, ν = 0.3, ρ = 1000,
/// velocities ±(0.1, 0.1).
pub fn colliding_disks(sides: usize, basis: BasisKind) -> Model<2> {
    let shapes = [disk(Vector2::new(0.2, 0.2), 0.2, sides), disk(Vector2::new(0.8, 0.8), 0.2, sides)];
    let mut m = scene(0.05, [20, 20], &shapes, 2, 1000.0, elastic(1000.0, 0.3), basis, Kinematics::FiniteStrain);
    let x: Vec<f64> = m.points().position.iter().map(|x| x.x).collect();
    for (v, x) in m.velocities_mut().iter_mut().zip(x) {
        *v = Vector2::new(0.1, 0.1) * if x < 0.5 { 1.0 } else { -1.0 };
    }
    m
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
    let v2 = |v: &Vec<Vector2<f64>>| v.iter().all(|x| x.iter().all(|c| c.is_finite()));
    let m3 = |v: &Vec<nalgebra::Matrix3<f64>>| v.iter().all(|x| x.iter().all(|c| c.is_finite()));
    assert!(v2(&p.position) && v2(&p.velocity) && v2(&p.half_length), "non-finite position, velocity or domain");
    assert!(m3(&p.stress) && m3(&p.elastic_strain) && m3(&p.deformation_gradient), "non-finite stress or strain");
    assert!(p.volume.iter().chain(&p.history).all(|c| c.is_finite()), "non-finite volume or history");
    assert!(p.volume.iter().all(|&v| v > 0.0), "non-positive volume");
}

/// The committed point state of `a` and `b` is bitwise the same.
pub fn assert_same_state(a: &Model<2>, b: &Model<2>) {
    let (p, q) = (&a.points(), &b.points());
    assert!(p.position == q.position, "positions differ");
    assert!(p.velocity == q.velocity, "velocities differ");
    assert!(p.stress == q.stress, "stresses differ");
    assert!(p.elastic_strain == q.elastic_strain, "elastic strains differ");
    assert!(p.deformation_gradient == q.deformation_gradient, "deformation gradients differ");
    assert!(p.volume == q.volume, "volumes differ");
    assert!(p.half_length == q.half_length, "domains differ");
    assert!(p.history == q.history, "histories differ");
}
