//! The linear solvers inside an analysis: multigrid-preconditioned CG against the sparse
//! direct solve on a 3D oedometric block (docs/theory.md §19).

use loam::implicit::{Kinematics, Model, QuasiStatic, QuasiStaticSettings};
use loam::solve::{LinearSolverChoice, LinearSolverKind};
use loam_verification::block::{BLOCK_DENSITY, BLOCK_GRAVITY, BLOCK_POISSON};
use loam_verification::elastic_block;
use nalgebra::Vector3;

/// The laterally confined block of `n` cells (roller base), in small strain.
fn oedometric_block(n: usize) -> Model<3> {
    elastic_block::<3>(n, Kinematics::SmallStrain, false)
}

/// One load step with `solver`: the kind taken, the Krylov iterations, and the points'
/// stresses.
fn run(n: usize, solver: LinearSolverChoice) -> (LinearSolverKind, usize, Vec<nalgebra::Matrix3<f64>>) {
    let settings = QuasiStaticSettings { load_steps: 1, linear_solver: solver, ..Default::default() };
    let mut qs = QuasiStatic::new(oedometric_block(n), settings);
    let report = qs.step().unwrap();
    (qs.linear_solver_kind(), report.linear_iterations, qs.model().points().stress().to_vec())
}

/// e_σ = ‖σ_h − σ‖ / ‖σ‖ over the points, σ_zz = −ρ g (H − z), σ_xx = σ_yy = ν/(1−ν) σ_zz.
fn stress_error(n: usize, stress: &[nalgebra::Matrix3<f64>]) -> f64 {
    let model = oedometric_block(n);
    let (mut num, mut den) = (0.0, 0.0);
    for (s, x) in stress.iter().zip(model.points().position()) {
        let szz = -BLOCK_DENSITY * BLOCK_GRAVITY * (n as f64 - x[2]);
        let sxx = BLOCK_POISSON / (1.0 - BLOCK_POISSON) * szz;
        let exact = nalgebra::Matrix3::from_diagonal(&Vector3::new(sxx, sxx, szz));
        num += (s - exact).norm_squared();
        den += exact.norm_squared();
    }
    (num / den).sqrt()
}

#[test]
fn multigrid_cg_gives_the_direct_solvers_oedometric_stresses() {
    let n = 8;
    let (direct_kind, direct_its, direct) = run(n, LinearSolverChoice::Direct);
    let (cg_kind, cg_its, cg) = run(n, LinearSolverChoice::Iterative);
    assert_eq!((direct_kind, cg_kind), (LinearSolverKind::Cholesky, LinearSolverKind::Cg));
    assert_eq!(direct_its, 0);
    assert!(cg_its > 0);
    let (e_direct, e_cg) = (stress_error(n, &direct), stress_error(n, &cg));
    // Both converge Newton to the relative residual 1e-9 of the same discrete problem:
    // their stresses may differ by the unsolved residual only, far below the spatial error.
    let scale = direct.iter().map(|s| s.norm()).fold(0.0, f64::max);
    let diff = direct.iter().zip(&cg).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
    assert!(diff < 1e-6 * scale, "stresses differ by {diff:e} (scale {scale:e})");
    assert!((e_direct - e_cg).abs() < 1e-6 * e_direct, "e_sigma {e_direct:e} (direct) and {e_cg:e} (CG)");
    // And they approach the closed form under refinement (its rate is the V1 column's
    // business, docs/verification.md §V1): the error at 8 cells is below that at 4.
    let e_coarse = stress_error(4, &run(4, LinearSolverChoice::Iterative).2);
    assert!(e_cg < e_coarse, "e_sigma {e_cg:e} at 8 cells, {e_coarse:e} at 4");
}

#[test]
fn the_automatic_choice_turns_to_multigrid_in_3d_above_its_size() {
    // 8 cells: 2 187 dofs, below the 5 000 of the automatic choice; 12 cells: 6 591.
    assert_eq!(run(8, LinearSolverChoice::Auto).0, LinearSolverKind::Cholesky);
    assert_eq!(run(12, LinearSolverChoice::Auto).0, LinearSolverKind::Cg);
}

#[test]
fn multigrid_cg_gives_the_same_numbers_on_one_and_two_threads() {
    // Every reduction has a fixed order, the coarsest LU runs on one thread: bitwise equal.
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| run(6, LinearSolverChoice::Iterative).2)
    };
    assert!(on(1) == on(2));
}

/// Near a plastic mechanism multigrid CG does not converge (docs/theory.md §19): on the von
/// Mises footing's second load step its residual grows. The correction is then solved by
/// sparse LU, and the run follows the direct solver's: the same Newton residuals, to the
/// forcing term's four digits, and the same reactions.
#[test]
fn a_failed_krylov_solve_falls_back_on_the_direct_solver() {
    let path = std::path::Path::new("examples/footing_von_mises.ron");
    let source = std::fs::read_to_string(path).unwrap();
    // Without Newton's second try: where whole corrections fail, the direct and the
    // Krylov runs abandon their first tries after different numbers of corrections, so
    // their counts would differ though both converge; cut back, they take the same path.
    let run = |linear: &str| {
        let text = source.replace("solver: (", &format!("solver: (linear: Some({linear}), retry_backtracks: 0, "));
        let scene = loam::scene::LoadedScene::parse(path, text).unwrap();
        let mut analysis = scene.build::<2>().unwrap();
        (0..4).map(|_| analysis.step().unwrap()).collect::<Vec<_>>()
    };
    let (direct, iterative) = (run("Direct"), run("Iterative"));
    for (d, i) in direct.iter().zip(&iterative) {
        assert_eq!(d.iterations, i.iterations, "Newton iterations of step {}", d.step);
        for (a, b) in d.reactions.iter().zip(&i.reactions) {
            for k in 0..2 {
                // Newton's tolerance 1e-9 bounds both residuals; the reactions are sums of them.
                assert!((a[k] - b[k]).abs() <= 1e-6 * a[k].abs().max(1.0), "step {}: {a:?} against {b:?}", d.step);
            }
        }
    }
    assert!(iterative.iter().any(|p| p.linear_iterations > 0));
    assert!(iterative.iter().any(|p| p.direct_fallbacks > 0), "the second step's solve falls back");
}
