//! Geostatic (K0) initial stress: the weight of the material above each point, K0 times
//! it horizontally, carried by the matching elastic strain, and gravity acting in full
//! from the start.

use loam::constitutive::{ConstitutiveLaw, Elastic, MohrCoulomb};
use loam::grid::{BasisKind, Grid};
use loam::implicit::{QuasiStatic, QuasiStaticSettings};
use loam::model::{Kinematics, Model, ModelError, PlaneConstraint};
use loam::points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

const G: f64 = 10.0;

/// Two layers on a 2 m wide, 6 m deep grid of 0.5 m cells: 2 m of ρ = 1800 over 4 m of
/// ρ = 2100, 2×2 points per cell, rollers on the sides, fixed base.
fn layered(law: Arc<dyn ConstitutiveLaw>, kinematics: Kinematics) -> Model<2> {
    let grid = Grid::new(Vector2::zeros(), Vector2::new(0.5, 0.5), [4, 13]).unwrap();
    let mut points = PointStore::new();
    points.fill(&grid, &Shape::Box { min: Vector2::new(0.0, 4.0), max: Vector2::new(2.0, 6.0) }, 2, 1800.0, 0).unwrap();
    points.fill(&grid, &Shape::Box { min: Vector2::zeros(), max: Vector2::new(2.0, 4.0) }, 2, 2100.0, 0).unwrap();
    let constraints = vec![
        PlaneConstraint::new(0, 0, [true, false, false]),
        PlaneConstraint::new(0, 4, [true, false, false]),
        PlaneConstraint::new(1, 0, [true, true, false]),
    ];
    Model::new(grid, BasisKind::Linear, kinematics, points, vec![law], constraints, Vector2::new(0.0, -G)).unwrap()
}

/// σ_v(y) of the two layers, exact.
fn sigma_v(y: f64) -> f64 {
    if y >= 4.0 {
        -1800.0 * G * (6.0 - y)
    } else {
        -(1800.0 * G * 2.0 + 2100.0 * G * (4.0 - y))
    }
}

/// The points sit at sub-cell centres and the layer boundary on a row boundary, so the
/// column sum (half of a point's own row) reproduces the exact σ_v to rounding (1e-12);
/// σ_xx = σ_zz = K0 σ_v.
#[test]
fn layered_ground_gets_the_weight_above_each_point() {
    let mut model = layered(Arc::new(Elastic::new(1e5, 0.3).unwrap()), Kinematics::SmallStrain);
    model.geostatic_stress(0.6).unwrap();
    for p in 0..model.points().len() {
        let s = model.points().stress()[p];
        let exact = sigma_v(model.points().position()[p][1]);
        assert!((s[(1, 1)] / exact - 1.0).abs() < 1e-12, "point {p}: {} vs {exact}", s[(1, 1)]);
        assert!((s[(0, 0)] / (0.6 * exact) - 1.0).abs() < 1e-12 && (s[(2, 2)] / (0.6 * exact) - 1.0).abs() < 1e-12);
    }
}

/// The geostatic state is in equilibrium with full gravity: a load step moves the ground
/// by less than 1e-6 of the settlement that gravity loading from zero produces (the
/// sub-cell midpoint rule integrates the linear stress and the gravity load exactly), in
/// small and in finite strain, and the stress stays at K0 (here 0.6, not the elastic
/// ν/(1−ν) = 0.43 that gravity loading would give).
#[test]
fn geostatic_state_is_in_equilibrium() {
    for kinematics in [Kinematics::SmallStrain, Kinematics::FiniteStrain] {
        let law = Arc::new(Elastic::new(1e5, 0.3).unwrap());
        let settle = |mut model: Model<2>| {
            let mut qs = QuasiStatic::new(model.clone(), QuasiStaticSettings { load_steps: 1, ..Default::default() });
            qs.step().unwrap();
            model = qs.into_model();
            let u = (0..model.points().len())
                .map(|p| (model.points().position()[p] - model.points().position0()[p]).norm())
                .fold(0.0, f64::max);
            (u, model)
        };
        let (u_gravity, _) = settle(layered(law.clone(), kinematics));
        let mut model = layered(law, kinematics);
        model.geostatic_stress(0.6).unwrap();
        let (u_k0, after) = settle(model);
        println!("{kinematics:?}: gravity loading moves {u_gravity:.3e}, geostatic start {u_k0:.3e}");
        assert!(u_k0 < 1e-6 * u_gravity, "{u_k0} vs {u_gravity}");
        let p = 0;
        let s = after.points().stress()[p];
        assert!((s[(0, 0)] / s[(1, 1)] - 0.6).abs() < 1e-6, "K0 kept: {}", s[(0, 0)] / s[(1, 1)]);
    }
}

/// A K0 below the active limit of a cohesionless Mohr–Coulomb soil (K_a = 1/3 at φ = 30°)
/// is outside the yield surface and is refused, naming the point; Jaky's 1 − sin φ = 0.5
/// is inside.
#[test]
fn k0_outside_the_yield_surface_is_refused() {
    let mc = || Arc::new(MohrCoulomb::from_degrees(Elastic::new(1e5, 0.3).unwrap(), 0.0, 30.0, 0.0).unwrap());
    let mut model = layered(mc(), Kinematics::SmallStrain);
    model.geostatic_stress(0.5).unwrap();
    let mut model = layered(mc(), Kinematics::SmallStrain);
    let e = model.geostatic_stress(0.2).unwrap_err();
    assert!(matches!(e, ModelError::Geostatic(_)) && e.to_string().contains("outside the yield surface"), "{e}");
}

/// A sloping surface (y_s = 4 + x/2 over 0 ≤ x ≤ 4, 1:2, on 0.5 m cells): each point gets
/// the weight of its own grid column above it, so σ_v follows the depth below the local
/// surface. Bound, from the fill rule: with 2×2 points per cell a sub-column's points sit
/// h/2 apart, the topmost within h/2 below the surface, so the points above a point (its
/// own row counted half) stand for its depth to within h/4; a cell column averages its two
/// sub-columns, whose surfaces differ by tan β · h/2, which adds tan β · h/4. Hence
/// |σ_v − ρg (y_s(x_p) − y_p)| ≤ ρg h (1 + tan β) / 4, and σ_h = K0 σ_v to rounding.
#[test]
fn sloping_ground_gets_the_weight_of_its_own_column() {
    let (h, rho, tan_beta, k0) = (0.5, 1900.0, 0.5, 0.55);
    let surface = |x: f64| 4.0 + tan_beta * x;
    let grid = Grid::new(Vector2::zeros(), Vector2::new(h, h), [8, 13]).unwrap();
    let mut points = PointStore::new();
    let slope = Shape::Polygon(vec![
        Vector2::zeros(),
        Vector2::new(4.0, 0.0),
        Vector2::new(4.0, surface(4.0)),
        Vector2::new(0.0, surface(0.0)),
    ]);
    points.fill(&grid, &slope, 2, rho, 0).unwrap();
    let constraints = vec![
        PlaneConstraint::new(0, 0, [true, false, false]),
        PlaneConstraint::new(0, 8, [true, false, false]),
        PlaneConstraint::new(1, 0, [true, true, false]),
    ];
    let law = Arc::new(Elastic::new(1e5, 0.3).unwrap());
    let mut model = Model::new(
        grid,
        BasisKind::Linear,
        Kinematics::SmallStrain,
        points,
        vec![law],
        constraints,
        Vector2::new(0.0, -G),
    )
    .unwrap();
    model.geostatic_stress(k0).unwrap();
    let bound = rho * G * h * (1.0 + tan_beta) / 4.0;
    let mut worst: f64 = 0.0;
    for p in 0..model.points().len() {
        let x = model.points().position()[p];
        let s = model.points().stress()[p];
        let continuum = -rho * G * (surface(x[0]) - x[1]);
        worst = worst.max((s[(1, 1)] - continuum).abs());
        assert!(
            (s[(1, 1)] - continuum).abs() <= bound,
            "point {p} at {x:?}: σ_v {} vs ρg depth {continuum}",
            s[(1, 1)]
        );
        assert!((s[(0, 0)] / (k0 * s[(1, 1)]) - 1.0).abs() < 1e-12 && s[(0, 1)] == 0.0);
    }
    println!("sloping K0: largest |σ_v − ρg depth| = {worst:.1} against the bound {bound:.1}");
}
