//! V4 slopes: strength reduction against gravity increase and Taylor's chart.

use loam::analysis::{SearchSoFar, StrengthReduction, StrengthReductionError, StrengthTrial, TrialStart};
use loam::constitutive::{ConstitutiveLaw, Elastic, VonMises};
use loam::implicit::{AntiLocking, QuasiStatic, QuasiStaticSettings};
use loam::model::ModelState;
use loam_verification::{slope_model, SlopeGeometry};
use std::sync::Arc;

fn clay() -> Arc<dyn ConstitutiveLaw> {
    Arc::new(VonMises::new(Elastic::new(1e5, 0.3).unwrap(), 3f64.sqrt() * 10.0, 0.0).unwrap())
}

/// For φ = 0 the collapse load is proportional to c_u, so dividing c_u by F at γH/c_u = 4
/// (strength reduction) and raising γ at full c_u (gravity increase) must find the same
/// stability number, 4F = γ_c H/c_u: two procedures, one answer, within the bracket
/// (4 × 0.005) and the gravity step's resolution (0.1 / 2⁸), whether the trials start from
/// the last state that held or from zero. Both must lie within the 10 % of
/// Taylor's 5.5 (coarse mesh, 5 cells per H: measured 5.46).
#[test]
fn strength_reduction_and_gravity_increase_agree_for_undrained_clay() {
    let g = SlopeGeometry::UNDRAINED;
    // Gravity increase to γH/c_u = 8 in steps of 0.1, halved up to 8 times (no limit
    // resolution: the search as fine as the tolerance below assumes, 0.1 / 256).
    let model = slope_model(&g, clay(), 0.8, 10.0, 5, AntiLocking::BBar);
    let settings = QuasiStaticSettings { load_steps: 80, limit_resolution: 0.0, ..Default::default() };
    let mut qs = QuasiStatic::new(model, settings);
    while !qs.is_finished() {
        if qs.step().is_err() {
            break;
        }
    }
    let n_gravity = 8.0 * qs.load_factor();
    assert!(qs.load_factor() < 1.0, "the slope carried γH/c_u = 8");
    assert!((n_gravity / 5.5 - 1.0).abs() <= 0.10, "γH/c_u at collapse {n_gravity}");

    let model = slope_model(&g, clay(), 0.4, 10.0, 5, AntiLocking::BBar);
    for start in [TrialStart::LastHeld, TrialStart::Zero] {
        let srf = StrengthReduction {
            trial: QuasiStaticSettings { load_steps: 10, max_cutbacks: 4, ..Default::default() },
            bracket: (1.0, 2.0),
            tolerance: 0.005,
            start,
        };
        let fos = srf.factor_of_safety(&model, |_, _| {}).unwrap();
        assert!(fos.failed - fos.stable <= 0.005, "{start:?}: bracket {} – {}", fos.stable, fos.failed);
        let n_srf = 4.0 * fos.value();
        assert!(
            (n_srf - n_gravity).abs() <= 4.0 * 0.005 + 0.1 / 256.0,
            "{start:?}: strength reduction {n_srf}, gravity increase {n_gravity}"
        );
    }
}

/// A bracket that does not bracket is reported, naming the end that is wrong, whichever
/// way the trials start.
#[test]
fn a_bracket_that_does_not_bracket_is_reported() {
    let model = slope_model(&SlopeGeometry::UNDRAINED, clay(), 0.4, 10.0, 5, AntiLocking::BBar);
    for start in [TrialStart::LastHeld, TrialStart::Zero] {
        let srf = |bracket| StrengthReduction {
            trial: QuasiStaticSettings { load_steps: 5, max_cutbacks: 2, ..Default::default() },
            bracket,
            tolerance: 0.05,
            start,
        };
        assert!(matches!(
            srf((1.0, 1.2)).factor_of_safety(&model, |_, _| {}),
            Err(StrengthReductionError::HoldsAtUpper(f)) if f == 1.2
        ));
        assert!(matches!(
            srf((1.6, 2.0)).factor_of_safety(&model, |_, _| {}),
            Err(StrengthReductionError::FailsAtLower(f)) if f == 1.6
        ));
        assert!(matches!(
            srf((2.0, 1.0)).factor_of_safety(&model, |_, _| {}),
            Err(StrengthReductionError::InvalidSettings(_))
        ));
    }
}

/// A search from the last state that held, stopped after any of its trials and resumed
/// from the state that held then (what a checkpoint saves), tries the same factors and
/// brackets the same F as the search that never stopped, bit for bit.
#[test]
fn a_search_from_the_last_held_state_resumes_where_it_stopped() {
    let model = slope_model(&SlopeGeometry::UNDRAINED, clay(), 0.4, 10.0, 5, AntiLocking::BBar);
    let srf = StrengthReduction {
        trial: QuasiStaticSettings { load_steps: 4, max_cutbacks: 4, ..Default::default() },
        bracket: (1.0, 2.0),
        tolerance: 0.01,
        start: TrialStart::LastHeld,
    };
    let mut saved = Vec::new();
    let whole = srf
        .factor_of_safety(&model, |_, held| {
            let qs = held.expect("a search from the last held state hands it over");
            let points = ModelState { points: qs.model().points().clone(), load_vertices: vec![], mesh_nodes: None };
            saved.push((qs.state(), points));
        })
        .unwrap();
    assert!(whole.trials.iter().any(|t| t.cutbacks > 0), "the case cuts back, so the replay has halvings to redo");
    let key =
        |t: &StrengthTrial| (t.factor.to_bits(), t.stable, t.iterations, t.cutbacks, t.max_displacement.to_bits());
    for k in 1..whole.trials.len() {
        let so_far = SearchSoFar { trials: whole.trials[..k].to_vec(), held: Some(saved[k - 1].clone()) };
        let mut new = Vec::new();
        let resumed = srf.factor_of_safety_after(&model, so_far, |t, _| new.push(t.clone())).unwrap();
        assert_eq!((resumed.stable, resumed.failed), (whole.stable, whole.failed), "resumed after {k} trials");
        assert_eq!(new.iter().map(key).collect::<Vec<_>>(), whole.trials[k..].iter().map(key).collect::<Vec<_>>());
    }
    let refused = SearchSoFar { trials: whole.trials[..2].to_vec(), held: None };
    assert!(matches!(
        srf.factor_of_safety_after(&model, refused, |_, _| {}),
        Err(StrengthReductionError::Reduction(_))
    ));
}

/// The linear solver follows the tangent: Cholesky for a symmetric, non-softening law
/// (von Mises, H = 0; associated Mohr–Coulomb, whose returns to the plane, the edges and
/// the apex all have symmetric tangents); LU for non-associated Mohr–Coulomb
/// (non-symmetric) and for a softening von Mises (symmetric but indefinite past the peak,
/// where Cholesky stops at its first negative pivot). A solver asked for is used as asked.
#[test]
fn the_linear_solver_follows_symmetry_and_softening() {
    use loam::constitutive::MohrCoulomb;
    use loam::solve::{LinearSolverChoice, LinearSolverKind};
    let kind = |law: Arc<dyn ConstitutiveLaw>| {
        let model = slope_model(&SlopeGeometry::UNDRAINED, law, 0.4, 10.0, 5, AntiLocking::BBar);
        QuasiStatic::new(model, QuasiStaticSettings::default()).linear_solver_kind()
    };
    let elastic = Elastic::new(1e5, 0.3).unwrap();
    assert_eq!(kind(clay()), LinearSolverKind::Cholesky);
    assert_eq!(kind(Arc::new(MohrCoulomb::from_degrees(elastic, 10.0, 20.0, 0.0).unwrap())), LinearSolverKind::Lu);
    assert_eq!(kind(Arc::new(VonMises::new(elastic, 17.3, -100.0).unwrap())), LinearSolverKind::Lu);
    assert_eq!(
        kind(Arc::new(MohrCoulomb::from_degrees(elastic, 10.0, 20.0, 20.0).unwrap())),
        LinearSolverKind::Cholesky
    );
    let forced = slope_model(&SlopeGeometry::UNDRAINED, clay(), 0.4, 10.0, 5, AntiLocking::BBar);
    let settings =
        QuasiStaticSettings { linear_solver: LinearSolverChoice::Forced(LinearSolverKind::Lu), ..Default::default() };
    assert_eq!(QuasiStatic::new(forced, settings).linear_solver_kind(), LinearSolverKind::Lu);
}
