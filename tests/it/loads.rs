//! Loads on the material's surface and at points (docs/theory.md §17), and static water
//! (§18), against closed forms: a uniform stress under a surcharge alone, the exact
//! equilibrium of a point load with its support reaction, the response to a surcharge
//! applied suddenly (an oscillation about the static settlement) or ramped over the first
//! period (none), a submerged slope that is the dry one with the buoyant weight, and a
//! geostatic stress under water in equilibrium.

use loam::grid::BasisKind;
use loam::implicit::{Dynamic, DynamicSettings, Kinematics, QuasiStatic, QuasiStaticSettings};
use loam::model::{Load, Model, TimeFunction};
use loam::points::Shape;
use loam_verification::{column_model, Column};
use nalgebra::Vector2;

/// A weightless column (V1a's size and stiffness) for the surcharge alone.
const WEIGHTLESS: Column = Column { height: 50.0, young: 1e6, density: 80.0, gravity: 0.0, surcharge: 4e4 };

fn run_quasi_static(model: Model<2>, load_steps: usize) -> Model<2> {
    let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps, ..Default::default() });
    while !qs.is_finished() {
        qs.step().unwrap();
    }
    qs.into_model()
}

/// Under a surcharge alone every point carries σ_yy = −q exactly: the load is consistent
/// with the internal force wherever the points integrate the basis gradients exactly, so
/// the uniform state is the discrete solution (tolerance 1e-9 relative: round-off of a
/// 16-cell solve). GIMP integrates over the point domains, so it holds in any number of
/// steps, also in finite strain, where q/E = 4 % moves the points by up to 0.6 cells;
/// the B-spline's point quadrature is exact only at the points' initial places (its
/// kinks lie on sub-cell faces), so it gets one load step.
#[test]
fn a_surcharge_alone_gives_a_uniform_stress() {
    let cases = [
        (BasisKind::Gimp, Kinematics::SmallStrain, 4),
        (BasisKind::Gimp, Kinematics::FiniteStrain, 4),
        (BasisKind::QuadraticBSpline, Kinematics::SmallStrain, 1),
        (BasisKind::Linear, Kinematics::SmallStrain, 1),
    ];
    for (basis, kinematics, steps) in cases {
        let model = column_model::<2>(&WEIGHTLESS, 50.0 / 16.0, 16, 2, basis, kinematics);
        let model = run_quasi_static(model, steps);
        let worst =
            model.points().stress().iter().map(|s| (s[(1, 1)] + WEIGHTLESS.surcharge).abs()).fold(0.0, f64::max);
        assert!(worst <= 1e-9 * WEIGHTLESS.surcharge, "{basis:?} {kinematics:?}: |σ_yy + q| up to {worst:e}");
    }
}

/// A point load on top of the column is carried to the base: the base constraint's
/// reaction balances it to round-off (the residual's equilibrium, 1e-9 relative).
#[test]
fn a_point_load_is_balanced_by_the_base_reaction() {
    let column = Column { surcharge: 0.0, ..WEIGHTLESS };
    let width = 50.0 / 16.0;
    let model = column_model::<2>(&column, width, 16, 2, BasisKind::Gimp, Kinematics::FiniteStrain);
    let force = Vector2::new(0.0, -2e4);
    let load = Load::force(Vector2::new(0.5 * width, 50.0), force, TimeFunction::Constant).unwrap();
    let mut qs = QuasiStatic::new(model.with_loads(vec![load]).unwrap(), QuasiStaticSettings::default());
    let mut last = None;
    while !qs.is_finished() {
        last = Some(qs.step().unwrap());
    }
    // Constraints of the column: rollers x = 0, x = w, then y = 0 (column_model's order).
    let base = last.unwrap().reactions[2];
    println!("base reaction {base:?}");
    // The reaction Σ (f_int − f_ext) over the base nodes is the force the support puts on
    // the column: minus the load.
    assert!((base[1] + force[1]).abs() <= 1e-9 * force.norm(), "base reaction {base:?} against the load {force}");
}

/// The top settlement of the weightless column under a surcharge with time function
/// `time` at its highest point (initial height Y), over 2.25 periods of its first mode
/// (T = 4H/c), implicit trapezoidal rule with 100 steps per period: (time, settlement /
/// the point's static settlement qY/E) after every step.
fn settlement_history(time: TimeFunction, cells: usize) -> Vec<(f64, f64)> {
    let column = Column { surcharge: 0.0, ..WEIGHTLESS };
    let width = 50.0 / cells as f64;
    let model = column_model::<2>(&column, width, cells, 2, BasisKind::Gimp, Kinematics::SmallStrain);
    let top = Shape::Box { min: Vector2::zeros(), max: Vector2::new(width, 50.0) }
        .boundary(width / 2.0)
        .unwrap()
        .select(|c| c[1] > 49.99);
    let n = top.vertices.len();
    let load = Load::pressure(top, vec![WEIGHTLESS.surcharge; n], false, time).unwrap();
    let settings = DynamicSettings::trapezoidal(PERIOD / 100.0, 2.25 * PERIOD);
    let mut dynamic = Dynamic::new(model.with_loads(vec![load]).unwrap(), settings).unwrap();
    let pts = dynamic.model().points();
    let top_point = (0..pts.len()).max_by(|&a, &b| pts.position0()[a][1].total_cmp(&pts.position0()[b][1])).unwrap();
    let static_settlement = WEIGHTLESS.surcharge * pts.position0()[top_point][1] / column.young;
    let mut history = Vec::new();
    while !dynamic.is_finished() {
        let r = dynamic.step().unwrap();
        let p = dynamic.model().points();
        history.push((r.time, (p.position0()[top_point][1] - p.position()[top_point][1]) / static_settlement));
    }
    history
}

/// First-mode period of the weightless column, 4H/c.
const PERIOD: f64 = 4.0 * 50.0 / 111.803_398_874_989_5; // c = √(1e6 / 80)

/// A suddenly applied surcharge: in the continuum the top settles along a triangle wave
/// between 0 and twice the static settlement (the dynamic amplification of a step load);
/// every mode oscillates about its static part. Checked: the first peak and the trough
/// after it straddle the static settlement, their midpoint within 2 % of it, and the peak
/// lies in (1.8, 2] (the sharp wave front disperses on the grid: 1.89 at 16 cells, 1.91
/// at 32, approaching 2). A load ramped over a rise time t_r leaves an amplitude
/// |sin(π t_r/T_k)| / (π t_r/T_k) of its static part vibrating in a mode of period T_k;
/// the bar's modes have periods T/(2k − 1), so a ramp over T leaves almost none (the
/// discrete first period is 2 % shorter than 4H/c at 16 cells, which leaves about 2 %):
/// over the period after the ramp the settlement stays within 5 % of the static one (the
/// bound of the column under sudden gravity, docs/verification.md §V1), against ±90 % for
/// the sudden load.
#[test]
fn a_sudden_surcharge_oscillates_about_the_static_settlement_and_a_ramped_one_does_not() {
    let sudden = settlement_history(TimeFunction::Constant, 16);
    let first_half: Vec<f64> = sudden.iter().filter(|(t, _)| *t <= 0.75 * PERIOD).map(|p| p.1).collect();
    let second_half: Vec<f64> =
        sudden.iter().filter(|(t, _)| *t > 0.75 * PERIOD && *t <= 1.25 * PERIOD).map(|p| p.1).collect();
    let peak = first_half.iter().copied().fold(0.0, f64::max);
    let trough = second_half.iter().copied().fold(f64::INFINITY, f64::min);
    let finer = settlement_history(TimeFunction::Constant, 32);
    let finer_peak = finer.iter().filter(|(t, _)| *t <= 0.75 * PERIOD).map(|p| p.1).fold(0.0, f64::max);
    println!(
        "sudden: peak {peak:.4}, trough {trough:.4}, midpoint {:.4}; peak at 32 cells {finer_peak:.4}",
        0.5 * (peak + trough)
    );
    assert!((0.5 * (peak + trough) - 1.0).abs() <= 0.02, "peak {peak}, trough {trough}");
    assert!(peak > 1.8 && finer_peak <= 2.0 && finer_peak > peak, "peaks {peak} (16 cells), {finer_peak} (32)");
    let ramped = settlement_history(TimeFunction::Ramp { duration: PERIOD }, 16);
    let after: Vec<f64> = ramped.iter().filter(|(t, _)| *t >= PERIOD).map(|p| p.1).collect();
    let (lo, hi) = after.iter().fold((f64::INFINITY, 0.0f64), |(lo, hi), &u| (lo.min(u), hi.max(u)));
    println!("ramped over T: settlement over the period after the ramp in [{lo:.4}, {hi:.4}]");
    assert!(lo >= 0.95 && hi <= 1.05, "after the ramp: [{lo}, {hi}]");
}

/// Static water changes nothing but the weight: the Griffiths & Lane slope (elastic here)
/// entirely under water with saturated unit weight 20 has the same displacements and
/// effective stresses as the dry slope with γ′ = 10, to round-off (the water's force is
/// the buoyancy γ_w upwards on every point, so the two systems are the same; 1e-9
/// relative covers the solver's round-off). With a Mohr–Coulomb law the factors of safety
/// agree as well (`cargo xtask verify`, V7).
#[test]
fn a_submerged_slope_is_the_dry_slope_with_the_buoyant_weight() {
    use loam::constitutive::{ConstitutiveLaw, Elastic};
    use loam::implicit::AntiLocking;
    use loam::model::{PhreaticLevel, Water};
    use loam_verification::{slope_model, SlopeGeometry};
    use std::sync::Arc;
    let g = SlopeGeometry::GRIFFITHS_LANE;
    let law: Arc<dyn ConstitutiveLaw> = Arc::new(Elastic::new(1e5, 0.3).unwrap());
    let dry = run_quasi_static(slope_model(&g, law.clone(), 1.0, 10.0, 5, AntiLocking::BBar), 1);
    let wet = slope_model(&g, law, 2.0, 10.0, 5, AntiLocking::BBar);
    let water = Water::new(10.0, PhreaticLevel::Horizontal(21.0), wet.gravity()).unwrap();
    let wet = run_quasi_static(wet.with_water(water).unwrap(), 1);
    let (pd, pw) = (dry.points(), wet.points());
    let scale = pd.stress().iter().map(|s| s.norm()).fold(0.0, f64::max);
    for p in 0..pd.len() {
        assert!((pd.stress()[p] - pw.stress()[p]).norm() <= 1e-9 * scale, "point {p}");
        assert!((pd.position()[p] - pw.position()[p]).norm() <= 1e-9 * 10.0, "point {p}");
        // The total stress carries the pore pressure on top: σ = σ′ − p_w I.
        let depth = 21.0 - pw.position()[p][1];
        assert!((wet.pore_pressure(p, 1.0) - 10.0 * depth).abs() <= 1e-9 * 210.0);
    }
}

/// A geostatic stress under a water table takes the effective weight: level ground 10
/// deep, the water table at 5.1 (inside the domains of the row of points at 5.25, which
/// are a fifth under water), K0 = 0.5. Per grid column a row of points weighs 10, 5 under
/// water; the lowest point (y = 0.25) carries 9 dry rows (90), the cut row (10 − 0.2 × 5 =
/// 9), 9 submerged rows (45) and half its own (2.5): σ′_v = −146.5. The first load step
/// finds the state in equilibrium, so nothing moves (1e-9 of a cell: Newton's tolerance
/// on a state already balanced).
#[test]
fn a_geostatic_stress_under_water_is_in_equilibrium() {
    use loam::constitutive::Elastic;
    use loam::grid::Grid;
    use loam::model::{PhreaticLevel, PlaneConstraint, Water};
    use loam::points::PointStore;
    use std::sync::Arc;
    let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [4, 11]).unwrap();
    let mut points = PointStore::new();
    points.fill(&grid, &Shape::Box { min: Vector2::zeros(), max: Vector2::new(4.0, 10.0) }, 2, 2.0, 0).unwrap();
    let law = Arc::new(Elastic::new(1e4, 0.3).unwrap());
    let constraints = vec![
        PlaneConstraint::new(0, 0, [true, false, false]),
        PlaneConstraint::new(0, 4, [true, false, false]),
        PlaneConstraint::new(1, 0, [true, true, false]),
    ];
    let gravity = Vector2::new(0.0, -10.0);
    let model =
        Model::new(grid, BasisKind::Gimp, Kinematics::SmallStrain, points, vec![law], constraints, gravity).unwrap();
    let mut model = model.with_water(Water::new(10.0, PhreaticLevel::Horizontal(5.1), &gravity).unwrap()).unwrap();
    model.geostatic_stress(0.5).unwrap();
    let before = model.points().position().to_vec();
    let bottom = model.points().stress().iter().map(|s| s[(1, 1)]).fold(0.0, f64::min);
    assert!((bottom + 146.5).abs() < 1e-9, "σ′_v at the lowest point {bottom}");
    let after = run_quasi_static(model, 1);
    let moved = after.points().position().iter().zip(&before).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
    assert!(moved < 1e-9, "moved {moved}");
}
