//! The updated Lagrangian FEM reference (docs/theory.md §12): the points are the Gauss points
//! of a body-fitted mesh that moves with the body. Checked against closed forms that are
//! exact for linear elements, independently of the MPM.

use loam::implicit::{Dynamic, DynamicSettings, Kinematics, QuasiStatic, QuasiStaticSettings};
use loam_verification::{column_errors, column_fem_model, Column, DynamicRecord, VibratingBar};

fn settle(model: loam::implicit::Model<2>, load_steps: usize) -> loam::implicit::Model<2> {
    let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps, ..Default::default() });
    while !qs.is_finished() {
        let r = qs.step().unwrap();
        assert!(r.iterations <= 8, "step {}: {} iterations", r.step, r.iterations);
    }
    qs.into_model()
}

/// Small strain, V1a: 1D linear elements with the consistent gravity load are nodally exact
/// (Tong 1969; Strang & Fix §1.2), so the top displacement is −ρgH²/(2E) = −1 to rounding,
/// and the element stress is exact at the element centre, so at the Gauss points ±h/(2√3)
/// the stress error is ρg h/(2√3) everywhere: e_σ = 1/(2√3 n) for n elements exactly.
#[test]
fn small_strain_column_is_nodally_exact() {
    let col = Column::V1A;
    for n in [4, 16] {
        let model = column_fem_model::<2>(&col, col.height / n as f64, n, 2, Kinematics::SmallStrain);
        let model = settle(model, 1);
        let e = column_errors(model.points(), &col, 1, |y| col.small_strain_displacement(y));
        let top_node = model.background().mesh().unwrap().positions().iter().map(|x| x[1]).fold(f64::MIN, f64::max);
        let expected_stress = 1.0 / (2.0 * 3f64.sqrt() * n as f64);
        println!(
            "n {n}: top node {top_node:.12} (exact {}), e_σ {:.6e} (expected {expected_stress:.6e})",
            col.height - 1.0,
            e.stress
        );
        // rounding of a linear solve on ~100 dofs with E = 1e6: 1e-9 of the 1 m displacement
        assert!((top_node - (col.height - 1.0)).abs() < 1e-9, "top node at {top_node}");
        assert!((e.stress / expected_stress - 1.0).abs() < 1e-8, "e_σ {}", e.stress);
    }
}

/// Finite strain, V1c (u_top = −3.92 m on 10 m): the FEM reference converges to the Hencky
/// closed form — the stress error stays at the Gauss-point sampling error 1/(2√3 n) of the
/// small-strain case (within 5 %: the stretch varies along the column), and the top
/// displacement error falls at least 3× per mesh halving (second order: 4×).
#[test]
fn finite_strain_column_converges_to_the_hencky_solution() {
    let col = Column::V1C;
    let mut previous = None;
    for n in [8, 16, 32] {
        let model = column_fem_model::<2>(&col, col.height / n as f64, n, 2, Kinematics::FiniteStrain);
        let model = settle(model, 10);
        let e = column_errors(model.points(), &col, 1, |y| col.hencky_displacement(y));
        let sampling = 1.0 / (2.0 * 3f64.sqrt() * n as f64);
        println!(
            "n {n}: e_σ {:.4e} (sampling {sampling:.4e}), top displacement error {:.3e}",
            e.stress, e.top_displacement
        );
        assert!(e.stress <= 1.05 * sampling, "e_σ {}", e.stress);
        if let Some(prev) = previous {
            assert!(e.top_displacement * 3.0 <= prev, "{} after {prev}", e.top_displacement);
        }
        previous = Some(e.top_displacement);
    }
}

/// V2 with the FEM reference: lumped-mass linear elements carry the first mode at the
/// discrete frequency ω_h = (2c/h) sin(β₁h/2) (Hughes 2000, §9.1), and the trapezoidal
/// rule stretches its period by ω_hΔt / (2 arctan(ω_hΔt/2)) (`lumped_fem_period`); the
/// measured period matches within 0.1 % (the crossing interpolation and the higher modes
/// excited by mapping the initial velocity to the nodes), and the energy drifts ≤ 1 % over
/// 3 periods (the bound for the MPM at Δt = 0.5).
#[test]
fn vibrating_bar_period_follows_the_discrete_frequency() {
    let bar = VibratingBar::REFERENCE;
    for dt in [0.1, 0.5, 1.0] {
        let model = bar.fem_model(2, Kinematics::FiniteStrain);
        let mut dynamic = Dynamic::new(model, DynamicSettings::trapezoidal(dt, 3.0 * bar.period())).unwrap();
        let mut record = DynamicRecord::default();
        record.push(0.0, dynamic.model());
        while !dynamic.is_finished() {
            let r = dynamic.step().unwrap();
            record.push(r.time, dynamic.model());
        }
        let errors = bar.errors(&record);
        let expected = bar.lumped_fem_period(dt);
        println!("dt {dt}: period {:.5} (expected {expected:.5}), drift {:.2e}", errors.period, errors.energy_drift);
        assert!((errors.period / expected - 1.0).abs() <= 1e-3, "dt {dt}: {} vs {expected}", errors.period);
        assert!(errors.energy_drift <= 0.01);
    }
}

/// Explicit MPM does not run FEM models, and says so instead of running a grid it ignores.
#[test]
fn explicit_analysis_refuses_a_fem_model() {
    use loam::explicit::{Explicit, ExplicitError, ExplicitSettings};
    let model = VibratingBar::REFERENCE.fem_model(2, Kinematics::FiniteStrain);
    let err = Explicit::new(model, ExplicitSettings::new(1.0)).err().unwrap();
    let ExplicitError::Unaccepted(refusal) = err else { panic!("{err}") };
    assert_eq!(refusal.option, loam::model::ModelOption::BodyFittedMesh);
    assert!(refusal.to_string().contains("explicit analysis runs MPM models only"), "{refusal}");
}
