//! Newton's second try (docs/theory.md §6): a load step whose whole corrections fail is
//! started again from the same increment with the line search before it is cut back.

use loam::constitutive::{ConstitutiveLaw, Elastic, MohrCoulomb};
use loam::implicit::{AntiLocking, QuasiStatic, QuasiStaticSettings, StepReport};
use loam_verification::footing_model;
use std::sync::Arc;

/// The V3 strip footing on associated Mohr–Coulomb soil (φ = ψ = 30°) pushed 0.1 b in
/// `steps` load steps, with `retry_backtracks` for Newton's second try: each step's report.
fn pushed_footing(steps: usize, retry_backtracks: usize) -> Vec<StepReport> {
    let law: Arc<dyn ConstitutiveLaw> =
        Arc::new(MohrCoulomb::from_degrees(Elastic::new(1e5, 0.3).unwrap(), 10.0, 30.0, 30.0).unwrap());
    let model = footing_model(law, 2, 10, 5, 0.1, AntiLocking::BBar);
    let mut settings = QuasiStaticSettings { load_steps: steps, ..Default::default() };
    settings.newton.retry_backtracks = retry_backtracks;
    let mut qs = QuasiStatic::new(model, settings);
    let mut reports = Vec::new();
    while !qs.is_finished() {
        reports.push(qs.step().expect("the step converges"));
    }
    reports
}

/// Pushed 0.1 b in two steps, the first step fails with whole corrections (20 of them,
/// the iteration limit): without the second try it is cut back, with it the step is taken
/// whole, its report counting the abandoned corrections with the second try's.
#[test]
fn a_step_whole_corrections_cannot_take_is_taken_by_the_second_try_without_a_cut_back() {
    let without = pushed_footing(2, 0);
    assert_eq!(without[0].cutbacks, 1, "whole corrections alone need a cut-back here");
    let with = pushed_footing(2, 4);
    assert_eq!(with.iter().map(|r| r.cutbacks).sum::<usize>(), 0);
    let first = &with[0];
    let second_try = first.hardest_residuals.len() - 1;
    assert_eq!(first.hardest_abandoned, 20, "the first try ran to the iteration limit");
    assert_eq!(first.iterations, 20 + second_try, "the abandoned try's corrections are counted");
    assert_eq!(first.most_iterations(), first.iterations);
    // Steps whole corrections take are untouched by the retry, bit for bit.
    let (a, b) = (pushed_footing(8, 0), pushed_footing(8, 4));
    assert!(a.iter().zip(&b).all(|(a, b)| a.iterations == b.iterations && a.reactions == b.reactions));
}
