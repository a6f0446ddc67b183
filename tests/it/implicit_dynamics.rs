//! Implicit Newmark dynamics against the closed form of the vibrating bar (docs/verification.md §V2).

use loam::grid::BasisKind;
use loam::implicit::{Dynamic, DynamicSettings, Kinematics};
use loam_verification::{centre_of_mass_velocity, period_from_crossings, zero_crossings, VibratingBar};

struct BarRun {
    period: f64,
    vcm_error: f64,
    energy_drift: f64,
    max_iterations: usize,
}

fn run_bar(dt: f64, settings: impl Fn(DynamicSettings) -> DynamicSettings, basis: BasisKind) -> BarRun {
    let bar = VibratingBar::REFERENCE;
    let model = bar.model(2, basis, Kinematics::FiniteStrain);
    let t_end = 3.0 * bar.period();
    let mut dynamic = Dynamic::new(model, settings(DynamicSettings::trapezoidal(dt, t_end))).unwrap();
    let energy = |m: &loam::implicit::Model<2>| m.points().kinetic_energy() + m.stored_energy();
    let e0 = energy(dynamic.model());
    let (mut times, mut vcm) = (vec![0.0], vec![centre_of_mass_velocity(dynamic.model().points(), 0)]);
    let (mut vcm_error, mut max_iterations) = (0.0f64, 0);
    while !dynamic.is_finished() {
        let r = dynamic.step().unwrap();
        max_iterations = max_iterations.max(r.iterations);
        let v = centre_of_mass_velocity(dynamic.model().points(), 0);
        times.push(r.time);
        vcm.push(v);
        vcm_error = vcm_error
            .max((v - bar.centre_of_mass_velocity(r.time)).abs() / (2.0 * bar.amplitude / std::f64::consts::PI));
    }
    let e1 = energy(dynamic.model());
    BarRun {
        period: period_from_crossings(&zero_crossings(&times, &vcm)).unwrap(),
        vcm_error,
        energy_drift: (e1 - e0).abs() / e0,
        max_iterations,
    }
}

/// The measured period sits on the trapezoidal rule's curve ωΔt / (2 arctan(ωΔt/2)) within
/// 0.5 % (the bound; the rest is the spatial error of 25 cells, ~0.1 %).
#[test]
fn vibrating_bar_period_follows_the_trapezoidal_factor() {
    let bar = VibratingBar::REFERENCE;
    for dt in [0.1, 0.5, 1.0] {
        let run = run_bar(dt, |s| s, BasisKind::Linear);
        let expected = bar.period() * bar.trapezoidal_period_factor(dt);
        let err = run.period / expected - 1.0;
        println!("dt {dt}: period {:.5} (expected {expected:.5}, rel {err:+.2e}), v_cm error {:.2e}, energy drift {:.2e}, ≤{} Newton its", run.period, run.vcm_error, run.energy_drift, run.max_iterations);
        assert!(err.abs() <= 5e-3, "dt {dt}: period {} vs {expected}", run.period);
    }
}

/// Energy over 3 periods at Δt = 0.5 with lumped mass drifts ≤ 1 % (docs/verification.md §V2): the
/// trapezoidal rule conserves energy on the grid; what is lost is the point–grid transfer.
#[test]
fn vibrating_bar_conserves_energy() {
    let run = run_bar(0.5, |s| s, BasisKind::Linear);
    println!("energy drift {:.3e}", run.energy_drift);
    assert!(run.energy_drift <= 0.01, "drift {}", run.energy_drift);
}

/// Bossak's α_B = −0.1 damps: the energy after 3 periods is below the trapezoidal one.
#[test]
fn bossak_dissipates() {
    let plain = run_bar(1.0, |s| s, BasisKind::Linear);
    let bossak = run_bar(1.0, |s| s.bossak(-0.1), BasisKind::Linear);
    println!("drift trapezoidal {:.3e}, Bossak {:.3e}", plain.energy_drift, bossak.energy_drift);
    assert!(bossak.energy_drift > plain.energy_drift);
}

/// Consistent mass raises the discrete frequency, lumped mass lowers it (the classic
/// bracketing of FE mass matrices), and both stay within 0.5 % of the trapezoidal curve.
#[test]
fn consistent_mass_shortens_the_period() {
    use loam::implicit::MassMatrix;
    let bar = VibratingBar::REFERENCE;
    let dt = 0.1;
    let expected = bar.period() * bar.trapezoidal_period_factor(dt);
    let lumped = run_bar(dt, |s| s, BasisKind::Linear);
    let consistent = run_bar(dt, |s| DynamicSettings { mass: MassMatrix::Consistent, ..s }, BasisKind::Linear);
    println!("period lumped {:.5}, consistent {:.5}, expected {expected:.5}", lumped.period, consistent.period);
    assert!(consistent.period < lumped.period);
    assert!((consistent.period / expected - 1.0).abs() <= 5e-3);
}

/// Bad settings are refused before any step, naming the setting.
#[test]
fn invalid_settings_are_refused() {
    let bar = VibratingBar::REFERENCE;
    let model = bar.model(2, BasisKind::Linear, Kinematics::FiniteStrain);
    let err =
        Dynamic::new(model, DynamicSettings { gamma: 0.3, ..DynamicSettings::trapezoidal(0.1, 1.0) }).err().unwrap();
    assert!(err.to_string().contains("gamma"), "{err}");
}
