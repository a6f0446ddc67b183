//! Small-cut stabilisation: the face ghost penalty on the translated block (docs/theory.md
//! §15, docs/verification.md §H).

use loam::grid::BasisKind;
use loam::implicit::{QuasiStatic, QuasiStaticSettings};
use loam_verification::{condition_number, translated_block};

/// Condition number of the block's tangent and the Newton iterations of its load step.
fn run(overlap: f64, ghost: Option<f64>) -> (f64, usize) {
    let mut qs = QuasiStatic::new(
        translated_block(overlap, BasisKind::Gimp, ghost),
        QuasiStaticSettings { load_steps: 1, ..Default::default() },
    );
    let (pattern, values, constrained) = qs.start_tangent().unwrap();
    let r = qs.step().unwrap();
    assert!(r.final_residual() <= 1e-9);
    (condition_number(&pattern, &values, &constrained), r.iterations)
}

/// Without the penalty the condition number of the GIMP tangent grows as overlap⁻²: the
/// far nodes' weights and gradients scale with the overlap of the point domains, so their
/// stiffness scales with its square (measured 4.23e5, 4.28e7, 4.30e9 at 1e-2, 1e-3, 1e-4:
/// ratio 100.0 per decade to 1 %). With γ = 0.1 it stays within 15 % of the well-cut
/// block's (measured 3.85e2 at 0.5, 4.29e2 at 1e-4 and 1e-6), and Newton converges in 2
/// iterations at every overlap.
#[test]
fn ghost_penalty_bounds_the_condition_number() {
    let (c2, _) = run(1e-2, None);
    let (c3, _) = run(1e-3, None);
    let (c4, _) = run(1e-4, None);
    for (coarse, fine) in [(c2, c3), (c3, c4)] {
        let ratio = fine / coarse;
        assert!((ratio / 100.0 - 1.0).abs() < 0.05, "condition ratio per decade {ratio}");
    }
    let (reference, _) = run(0.5, Some(0.1));
    for overlap in [1e-1, 1e-2, 1e-3, 1e-4, 1e-6] {
        let (c, its) = run(overlap, Some(0.1));
        assert!(c < 1.15 * reference, "overlap {overlap}: condition {c} against {reference}");
        assert!(its <= 2, "overlap {overlap}: {its} iterations");
    }
}

/// The penalised run gives bitwise the same numbers with 1 and 2 threads: the faces are
/// built, applied to the residual and added to the tangent in a fixed order.
#[test]
fn ghost_penalty_is_deterministic_across_threads() {
    let run = |threads| {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
            let mut qs = QuasiStatic::new(
                translated_block(1e-3, BasisKind::Gimp, Some(0.1)),
                QuasiStaticSettings { load_steps: 2, ..Default::default() },
            );
            while !qs.is_finished() {
                qs.step().unwrap();
            }
            let p = &qs.model().points();
            (p.position().to_vec(), p.stress().to_vec())
        })
    };
    assert!(run(1) == run(2), "results differ between 1 and 2 threads");
}

/// The penalty is refused where it would be inconsistent (B-spline nodal values are
/// control values next to the grid faces) and where there is no tangent (explicit).
#[test]
fn ghost_penalty_is_refused_where_it_does_not_apply() {
    let e = translated_block(0.1, BasisKind::QuadraticBSpline, None).with_ghost_penalty(0.1).unwrap_err();
    assert!(e.to_string().contains("QuadraticBSpline"), "{e}");
    let model = translated_block(0.1, BasisKind::Gimp, None);
    let e = model.clone().with_ghost_penalty(0.0).unwrap_err();
    assert!(e.to_string().contains("positive"), "{e}");
    let e = loam::explicit::Explicit::new(
        model.with_ghost_penalty(0.1).unwrap(),
        loam::explicit::ExplicitSettings::new(1.0),
    )
    .err()
    .expect("refused");
    assert!(e.to_string().contains("ghost penalty"), "{e}");
}
