//! Cross-crate checks of the implicit MPM: the assembled tangent is the derivative of the
//! residual, results do not depend on the thread count, and the V1 column matches its
//! closed form.

use loam::grid::BasisKind;
use loam::implicit::{Kinematics, QuasiStatic, QuasiStaticSettings};
use loam_verification::{column_errors, column_model, Column};

fn run_column(cells: usize, steps: usize, basis: BasisKind, kin: Kinematics) -> QuasiStatic<2> {
    let c = Column::V1C;
    let m = column_model::<2>(&c, c.height / cells as f64, cells, 2, basis, kin);
    let mut qs = QuasiStatic::new(m, QuasiStaticSettings { load_steps: steps, ..Default::default() });
    while !qs.is_finished() {
        let r = qs.step().unwrap();
        // V1c bound (issue): at most 6 Newton iterations per load step to 1e-9.
        assert!(r.iterations <= 6, "step {} took {} iterations", r.step, r.iterations);
        assert!(r.final_residual() <= 1e-9);
    }
    qs
}

/// GIMP on V1c, 32 cells, 160 load steps: e_σ from `cargo xtask verify` is 1.1e-3; the
/// bound here (1.5e-3) is the measured value plus margin for platform rounding, and far
/// below the linear basis (9e-2), so it detects a broken basis or tangent.
#[test]
fn gimp_column_matches_the_closed_form() {
    let c = Column::V1C;
    let qs = run_column(32, 160, BasisKind::Gimp, Kinematics::FiniteStrain);
    let e = column_errors(qs.model().points(), &c, 1, |y| c.hencky_displacement(y));
    assert!(e.stress < 1.5e-3, "e_sigma = {}", e.stress);
    // Top displacement within 0.2 % of the Lambert-W solution (measured 3.4e-4).
    assert!(e.top_displacement < 2e-3, "e_u = {}", e.top_displacement);
}

/// Small strain in one load step is linear elasticity: top displacement ρgH²/(2E)
/// (V1a, −1.0 m) to the discretisation error (measured 1.8e-4 at 32 cells).
#[test]
fn small_strain_column_is_linear_elastic() {
    let c = Column::V1A;
    let m = column_model::<2>(&c, c.height / 32.0, 32, 2, BasisKind::Gimp, Kinematics::SmallStrain);
    let mut qs = QuasiStatic::new(m, QuasiStaticSettings { load_steps: 1, ..Default::default() });
    qs.step().unwrap();
    let e = column_errors(qs.model().points(), &c, 1, |y| c.small_strain_displacement(y));
    assert!(e.top_displacement < 1e-3, "e_u = {}", e.top_displacement);
    // Equilibrium at points: linear-in-Y stress is reproduced to the first-order GIMP
    // point-stress error h/(4H) · ½ (measured 7.8e-3 = 1/128 at 32 cells).
    assert!(e.stress < 1e-2, "e_sigma = {}", e.stress);
}

/// Quadratic B-splines on the small-strain column (V1a, one load step) are second order:
/// e_σ against the linear-elastic closed form falls by 4 per halving of h (measured
/// 7.35e-4 and 1.84e-4 at 16 and 32 cells, ratio 4.00, where GIMP's point stresses are
/// first order: 1.56e-2 and 7.8e-3). The bounds allow rate 1.9 and 10 % on the value.
#[test]
fn bspline_small_strain_column_is_second_order() {
    let c = Column::V1A;
    let e = |cells: usize| {
        let m = column_model::<2>(
            &c,
            c.height / cells as f64,
            cells,
            2,
            BasisKind::QuadraticBSpline,
            Kinematics::SmallStrain,
        );
        let mut qs = QuasiStatic::new(m, QuasiStaticSettings { load_steps: 1, ..Default::default() });
        qs.step().unwrap();
        column_errors(qs.model().points(), &c, 1, |y| c.small_strain_displacement(y))
    };
    let (e16, e32) = (e(16), e(32));
    let rate = (e16.stress / e32.stress).log2();
    assert!(rate > 1.9, "rate {rate} ({} → {})", e16.stress, e32.stress);
    assert!(e32.stress < 2.0e-4, "e_sigma = {}", e32.stress);
    assert!(e32.top_displacement < 2.0e-4, "e_u = {}", e32.top_displacement);
}

/// The same scene gives bitwise the same numbers with 1 and 2 threads: the transfers scatter
/// in the bands' fixed order, assembly gathers in a fixed order and the point loops are
/// independent.
#[test]
fn one_or_many_threads_give_identical_results() {
    let run = |threads| {
        rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
            let qs = run_column(16, 10, BasisKind::Gimp, Kinematics::FiniteStrain);
            let p = &qs.model().points();
            (p.position().to_vec(), p.stress().to_vec())
        })
    };
    let (x1, s1) = run(1);
    let (x2, s2) = run(2);
    assert!(x1 == x2 && s1 == s2, "results differ between 1 and 2 threads");
}

/// The linear basis stagnates (cell crossing); shown, not hidden: e_σ stays above 1e-2 at
/// 32 cells where GIMP reaches 1e-3.
#[test]
fn linear_basis_stagnates_on_the_column() {
    let c = Column::V1C;
    let qs = run_column(32, 40, BasisKind::Linear, Kinematics::FiniteStrain);
    let e = column_errors(qs.model().points(), &c, 1, |y| c.hencky_displacement(y));
    assert!(e.stress > 1e-2, "e_sigma = {}", e.stress);
}

/// A load step too large for the iteration limit is cut back and recovered: the whole V1c
/// load in one step with at most 3 Newton iterations fails, is halved until it converges,
/// and the result is the same equilibrium (e_σ as with many steps, within the bound).
#[test]
fn a_failed_step_is_cut_back_and_recovers() {
    let c = Column::V1C;
    let m = column_model::<2>(&c, c.height / 16.0, 16, 2, BasisKind::Gimp, Kinematics::FiniteStrain);
    let mut settings = QuasiStaticSettings { load_steps: 1, ..Default::default() };
    settings.newton.max_iterations = 3;
    let mut qs = QuasiStatic::new(m, settings);
    let r = qs.step().unwrap();
    assert!(r.cutbacks >= 1 && r.substeps >= 2, "{r:?}");
    assert_eq!(r.load_factor, 1.0);
    // The hardest sub-step is reported with its own history: at least one correction,
    // within the limit of 3, at least the mean over the sub-steps, and converged
    // (relative residual ≤ 1e-9).
    let most = r.most_iterations();
    assert!((1..=3).contains(&most) && most * r.substeps >= r.iterations, "{r:?}");
    assert!(*r.hardest_residuals.last().unwrap() <= 1e-9, "{r:?}");
    let e = column_errors(qs.model().points(), &c, 1, |y| c.hencky_displacement(y));
    // 16 cells: e_σ 3.7e-3 in the verify sweep; the path differs, so allow 2x.
    assert!(e.stress < 8e-3, "e_sigma = {}", e.stress);
}

/// When even the smallest allowed sub-step fails, the run stops with an error naming the
/// step and load factor — it never commits an unconverged state.
#[test]
fn an_unrecoverable_step_is_reported_not_accepted() {
    let c = Column::V1C;
    let m = column_model::<2>(&c, c.height / 8.0, 8, 2, BasisKind::Gimp, Kinematics::FiniteStrain);
    let mut settings = QuasiStaticSettings { load_steps: 1, max_cutbacks: 1, ..Default::default() };
    settings.newton.max_iterations = 1;
    let mut qs = QuasiStatic::new(m, settings);
    let before = qs.model().points().position().to_vec();
    let err = qs.step().unwrap_err();
    assert!(matches!(err, loam::implicit::StepError::NotConverged { step: 1, .. }), "{err}");
    assert!(err.to_string().contains("did not converge"));
    assert_eq!(qs.model().points().position(), before, "no unconverged state may be committed");
    assert_eq!(qs.load_factor(), 0.0);
}

/// Hard case: a 10⁶ stiffness contrast across one cell face (V1a column, upper half 10⁶
/// times softer, small strain, one load step). Newton still converges to 1e-9 in two
/// iterations (the tangent's condition number grows by the contrast, far from double
/// precision's limit), the stress is the weight above to the same first-order point error
/// as the uniform column (GIMP: e_σ = 1/(4n) = 7.8e-3 at 32 cells; bound 1e-2 as there),
/// and the top settlement matches the layered closed form to 0.1 % (measured 7.3e-4).
#[test]
fn a_million_fold_stiffness_contrast_converges() {
    use loam_verification::LayeredColumn;
    let layered = LayeredColumn { column: Column::V1A, contrast: 1e6 };
    let mut qs = QuasiStatic::new(
        layered.model(32, BasisKind::Gimp),
        QuasiStaticSettings { load_steps: 1, ..Default::default() },
    );
    let r = qs.step().unwrap();
    assert!(
        r.iterations <= 2 && r.final_residual() <= 1e-9,
        "{} iterations, residual {}",
        r.iterations,
        r.final_residual()
    );
    let e = column_errors(qs.model().points(), &layered.column, 1, |y| layered.displacement(y));
    assert!(e.stress < 1e-2, "e_sigma = {}", e.stress);
    assert!(e.top_displacement < 1e-3, "e_u = {} (u = {})", e.top_displacement, e.top_displacement_value);
}

/// A geometrically linear elastic run is linear in the load: ten load steps give the
/// displacements and stresses of one step (to round-off, 1e-10 relative), with every
/// point's volume as it started. The updated run moves its points and differs (by about
/// the strain, ~1e-3 relative here), which shows the test can tell the two apart.
#[test]
fn geometrically_linear_run_is_linear_in_the_load() {
    let c = Column::V1A;
    let run = |steps: usize, linear: bool| {
        let mut m = column_model::<2>(&c, c.height / 16.0, 16, 2, BasisKind::Gimp, Kinematics::SmallStrain);
        if linear {
            m = m.with_geometrically_linear().unwrap();
        }
        let mut qs = QuasiStatic::new(m, QuasiStaticSettings { load_steps: steps, ..Default::default() });
        while !qs.is_finished() {
            qs.step().unwrap();
        }
        qs.into_model()
    };
    let difference = |a: &loam::implicit::Model<2>, b: &loam::implicit::Model<2>| {
        let (pa, pb) = (&a.points(), &b.points());
        let (mut du, mut u, mut ds, mut s) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for p in 0..pa.len() {
            let (ua, ub) = (pa.position()[p] - pa.position0()[p], pb.position()[p] - pb.position0()[p]);
            du = du.max((ua - ub).norm());
            u = u.max(ua.norm());
            ds = ds.max((pa.stress()[p] - pb.stress()[p]).norm());
            s = s.max(pa.stress()[p].norm());
        }
        (du / u, ds / s)
    };
    let (one, ten) = (run(1, true), run(10, true));
    let (eu, es) = difference(&one, &ten);
    assert!(eu < 1e-10 && es < 1e-10, "displacement {eu:e}, stress {es:e}");
    assert!(ten.points().volume().iter().zip(ten.points().volume0()).all(|(v, v0)| v == v0));
    let (eu, _) = difference(&run(1, false), &run(10, false));
    assert!(eu > 1e-6, "the updated run should differ from one step: {eu:e}");
}
