//! Prescribed displacements on constrained dofs and the support reactions they produce.

use loam::constitutive::Elastic;
use loam::grid::{BasisKind, Grid};
use loam::implicit::{Dynamic, DynamicSettings, QuasiStatic, QuasiStaticSettings, StepError};
use loam::model::{Kinematics, Model, PlaneConstraint};
use loam::points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

/// A block W × H on a fixed base, rollers on both sides, its top pushed down by δ: a
/// uniform oedometric strain −δ/H, so σ_yy = −M δ/H with M = E(1−ν)/((1+ν)(1−2ν)), and the
/// top reaction is σ_yy · W per unit thickness. Linear fields are reproduced exactly by the
/// linear basis, so both hold to rounding (1e-9 relative) in one load step; the base
/// carries the opposite reaction. (Over several steps the updated-Lagrangian point volumes
/// shrink with the strain, and the reaction is σ_yy times the compressed top row's volume
/// over h: 0.19 % less at this δ after 4 steps.)
fn block(delta: f64, within: Option<([f64; 3], [f64; 3])>) -> Model<2> {
    let (w, h, cells) = (2.0, 4.0, 8);
    let grid = Grid::new(Vector2::zeros(), Vector2::new(0.5, 0.5), [4, cells + 1]).unwrap();
    let mut points = PointStore::new();
    points.fill(&grid, &Shape::Box { min: Vector2::zeros(), max: Vector2::new(w, h) }, 2, 1.0, 0).unwrap();
    let mut top = PlaneConstraint::new(1, cells, [false, true, false]).displaced([0.0, -delta, 0.0]);
    if let Some((lo, hi)) = within {
        top = top.within(lo, hi);
    }
    let constraints = vec![
        top,
        PlaneConstraint::new(1, 0, [true, true, false]),
        PlaneConstraint::new(0, 0, [true, false, false]),
        PlaneConstraint::new(0, 4, [true, false, false]),
    ];
    let law = Elastic::new(1000.0, 0.25).unwrap();
    Model::new(
        grid,
        BasisKind::Linear,
        Kinematics::SmallStrain,
        points,
        vec![Arc::new(law)],
        constraints,
        Vector2::zeros(),
    )
    .unwrap()
}

#[test]
fn pushed_block_carries_the_oedometric_stress() {
    let delta = 0.01;
    let mut qs = QuasiStatic::new(block(delta, None), QuasiStaticSettings { load_steps: 1, ..Default::default() });
    let mut last = None;
    while !qs.is_finished() {
        last = Some(qs.step().unwrap());
    }
    let r = last.unwrap();
    let (e, nu) = (1000.0, 0.25);
    let m = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let sigma = -m * delta / 4.0;
    for p in 0..qs.model().points().len() {
        let s = qs.model().points().stress()[p][(1, 1)];
        assert!((s / sigma - 1.0).abs() < 1e-9, "point {p}: σ_yy {s} vs {sigma}");
    }
    // Reaction = f_int on the top nodes = σ_yy W (negative: the soil resists compression).
    let top = r.reactions[0][1];
    let base = r.reactions[1][1];
    assert!((top / (sigma * 2.0) - 1.0).abs() < 1e-9, "top reaction {top} vs {}", sigma * 2.0);
    assert!((base + top).abs() < 1e-9 * top.abs(), "base {base} balances top {top}");
    assert_eq!(r.reactions[0][0], 0.0, "free component carries no reaction");
}

/// `within` limits the constraint to part of its plane: pushing only 0 ≤ x ≤ 1 of the
/// 2-wide top leaves the nodes beyond x = 1 free, so the right half of the top rises less
/// than δ (here it must move down less than the pushed part, and not be held).
#[test]
fn within_limits_the_constrained_nodes() {
    let delta = 0.01;
    let mut qs = QuasiStatic::new(
        block(delta, Some(([0.0, 4.0, 0.0], [1.0, 4.0, 0.0]))),
        QuasiStaticSettings { load_steps: 2, ..Default::default() },
    );
    while !qs.is_finished() {
        qs.step().unwrap();
    }
    let pts = &qs.model().points();
    let top_right = (0..pts.len())
        .filter(|&p| pts.position0()[p][0] > 1.5)
        .max_by(|&a, &b| pts.position0()[a][1].total_cmp(&pts.position0()[b][1]))
        .unwrap();
    let top_left = (0..pts.len())
        .filter(|&p| pts.position0()[p][0] < 0.5)
        .max_by(|&a, &b| pts.position0()[a][1].total_cmp(&pts.position0()[b][1]))
        .unwrap();
    let u_right = pts.position()[top_right][1] - pts.position0()[top_right][1];
    let u_left = pts.position()[top_left][1] - pts.position0()[top_left][1];
    assert!(u_left < u_right && u_right.abs() < 0.9 * u_left.abs(), "left {u_left}, right {u_right}");
}

/// Dynamics does not apply displacements with a load factor; it refuses them by name.
#[test]
fn dynamics_refuses_a_prescribed_displacement() {
    let err = Dynamic::new(block(0.01, None), DynamicSettings::trapezoidal(0.1, 1.0)).err().unwrap();
    let StepError::Unaccepted(refusal) = &err else { panic!("{err}") };
    assert_eq!(refusal.option, loam::model::ModelOption::DisplacedConstraint { index: 0 });
    assert!(err.to_string().starts_with("constraint 0 prescribes a non-zero displacement"), "{err}");
}

/// B-bar on a nearly incompressible elastic block (ν = 0.49): the same oedometric push
/// gives the same exact stress (a uniform strain is unchanged by averaging), so B-bar
/// costs nothing where there is no locking; and it converges in one Newton correction
/// (linear problem, consistent tangent).
#[test]
fn bbar_leaves_a_uniform_strain_exact() {
    let delta = 0.01;
    let (e, nu) = (1000.0, 0.49);
    let grid = Grid::new(Vector2::zeros(), Vector2::new(0.5, 0.5), [4, 9]).unwrap();
    let mut points = PointStore::new();
    points.fill(&grid, &Shape::Box { min: Vector2::zeros(), max: Vector2::new(2.0, 4.0) }, 2, 1.0, 0).unwrap();
    let constraints = vec![
        PlaneConstraint::new(1, 8, [false, true, false]).displaced([0.0, -delta, 0.0]),
        PlaneConstraint::new(1, 0, [true, true, false]),
        PlaneConstraint::new(0, 0, [true, false, false]),
        PlaneConstraint::new(0, 4, [true, false, false]),
    ];
    let law = Elastic::new(e, nu).unwrap();
    let model = Model::new(
        grid,
        BasisKind::Linear,
        Kinematics::SmallStrain,
        points,
        vec![Arc::new(law)],
        constraints,
        Vector2::zeros(),
    )
    .unwrap()
    .with_anti_locking(loam::model::AntiLocking::BBar)
    .unwrap();
    let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps: 1, ..Default::default() });
    let r = qs.step().unwrap();
    let m = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let sigma = -m * delta / 4.0;
    for p in 0..qs.model().points().len() {
        let s = qs.model().points().stress()[p][(1, 1)];
        assert!((s / sigma - 1.0).abs() < 1e-9, "point {p}: σ_yy {s} vs {sigma}");
    }
    assert!(r.iterations <= 2, "{} iterations", r.iterations);
}

/// The extrapolated start (`QuasiStaticSettings::extrapolate`) changes where Newton starts,
/// not where it ends: on the oedometric block in 4 load steps both starts give the same
/// stresses (1e-9). The strain is uniform and the law linear, so from the second step on
/// the scaled previous increment is the exact one and the extrapolated start is in
/// equilibrium to rounding (1e-12 relative; uniform stress balances at every free node
/// whatever the point volumes), while a zero start puts the whole step on the top nodes
/// (relative residual of order one).
#[test]
fn extrapolated_start_converges_to_the_same_state() {
    let run = |extrapolate: bool| {
        let mut qs = QuasiStatic::new(
            block(0.01, None),
            QuasiStaticSettings { load_steps: 4, extrapolate, ..Default::default() },
        );
        let first: Vec<f64> = (0..4).map(|_| qs.step().unwrap().residuals[0]).collect();
        (first, qs.into_model())
    };
    let (zero_start, plain) = run(false);
    let (extrapolated, model) = run(true);
    for p in 0..model.points().len() {
        let (a, b) = (model.points().stress()[p][(1, 1)], plain.points().stress()[p][(1, 1)]);
        assert!((a / b - 1.0).abs() < 1e-9, "point {p}: {a} vs {b}");
    }
    println!("initial residuals: zero start {zero_start:?}, extrapolated {extrapolated:?}");
    for k in 1..4 {
        assert!(
            zero_start[k] > 0.1 && extrapolated[k] < 1e-12,
            "step {}: {} vs {}",
            k + 1,
            zero_start[k],
            extrapolated[k]
        );
    }
}
