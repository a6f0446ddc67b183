//! `cargo xtask scale`: the cost of one quasi-static step of an elastic block under gravity
//! (GIMP, finite strain, 2 points per cell and axis, rollers on the sides, fixed base; 2D or
//! 3D; optionally with its lower half `--contrast` times softer) at several sizes, with each linear solver: time per Newton iteration, its phases, and the
//! peak memory of the process. Each size runs in a child process so that its peak memory
//! is its own.

use anyhow::{bail, Context, Result};
use loam::implicit::{IterationProfile, Kinematics, Model, QuasiStatic, QuasiStaticSettings};
use loam::scene::LinearSpec;
use loam::solve::LinearSolverChoice;
use loam_verification::layered_block;
use std::time::Instant;

/// Peak resident memory of this process so far (VmHWM), in bytes.
fn peak_memory() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// A profiled iteration's size and phases, in seconds.
fn phases(p: &IterationProfile) -> String {
    format!(
        "{} dofs | {} nnz | connect {:.2} s | points+residual {:.2} | assembly {:.2} | symbolic {:.2} | numeric {:.2} | solve {:.2} ({} Krylov)",
        p.dofs,
        p.nonzeros,
        p.connectivity.as_secs_f64(),
        p.points_and_residual.as_secs_f64(),
        p.assembly.as_secs_f64(),
        p.symbolic.as_secs_f64(),
        p.numeric.as_secs_f64(),
        p.solve.as_secs_f64(),
        p.krylov_iterations
    )
}

/// One size in this process: build, profile one iteration, run one load step; print one
/// line of figures.
pub fn run_one(dim: usize, n: usize, solver: LinearSolverChoice, contrast: f64) -> Result<()> {
    // A layer 10⁶ times softer crushes under its own weight in finite strain (J < 0): the
    // contrast runs are small strain, which asks the solver the same question.
    let kinematics = if contrast == 1.0 { Kinematics::FiniteStrain } else { Kinematics::SmallStrain };
    match dim {
        2 => run_model(n, layered_block::<2>(n, kinematics, true, contrast), solver),
        3 => run_model(n, layered_block::<3>(n, kinematics, true, contrast), solver),
        _ => bail!("--dim {dim}: expected 2 or 3"),
    }
}

fn run_model<const D: usize>(n: usize, model: Model<D>, solver: LinearSolverChoice) -> Result<()> {
    let t = Instant::now();
    let points = model.points().len();
    let build = t.elapsed().as_secs_f64();
    let mut qs =
        QuasiStatic::new(model, QuasiStaticSettings { load_steps: 1, linear_solver: solver, ..Default::default() });
    let p = qs.profile_iteration()?;
    let t = Instant::now();
    let report = qs.step()?;
    let step = t.elapsed().as_secs_f64();
    let mem = peak_memory().map_or(f64::NAN, |b| b as f64 / 1e9);
    println!(
        "{n}^{D} {} | {points} points | build {build:.2} s | {} | step {step:.2} s, {} Newton iterations ({} Krylov), {:.2} s per iteration, residuals {:?} | peak {mem:.2} GB",
        qs.linear_solver_description(),
        phases(&p),
        report.iterations,
        report.linear_iterations,
        step / report.iterations.max(1) as f64,
        report.residuals.iter().map(|r| format!("{r:.1e}")).collect::<Vec<_>>(),
    );
    Ok(())
}

/// `--solver`: a scene's `linear` (docs/scene-format.md) in lower case. `direct` in 3D
/// from 20 000 dofs takes GMRES on the symmetric part's factor for a non-symmetric
/// tangent; `lu` and `cholesky` factorise every correction.
fn linear_spec(name: &str) -> Result<LinearSpec> {
    Ok(match name {
        "auto" => LinearSpec::Auto,
        "direct" => LinearSpec::Direct,
        "iterative" => LinearSpec::Iterative,
        "lu" => LinearSpec::Lu,
        "cholesky" => LinearSpec::Cholesky,
        "cg" => LinearSpec::Cg,
        "bicgstab" => LinearSpec::BiCgStab,
        other => bail!("--solver {other}: expected auto, direct, iterative, lu, cholesky, cg or bicgstab"),
    })
}

/// Every size in a child process of its own.
pub fn run(dim: usize, cells: &[usize], solver: &str, contrast: f64) -> Result<()> {
    let choice = LinearSolverChoice::from(linear_spec(solver)?);
    if let [n] = cells {
        return run_one(dim, *n, choice, contrast);
    }
    let exe = std::env::current_exe().context("locating xtask")?;
    for n in cells {
        let status = std::process::Command::new(&exe)
            .args(["scale", "--dim", &dim.to_string(), "--solver", solver, "--contrast", &contrast.to_string()])
            .args(["--cells", &n.to_string()])
            .status()?;
        if !status.success() {
            bail!("scale: {n}^{dim} failed");
        }
    }
    Ok(())
}

/// `examples/slope_3d.ron` at cells of `cell_size` (the example's own is 2 m), its strength
/// divided by `factor` (c and tan φ), gravity in the example's load steps without the
/// strength-reduction search, the linear solver `solver`: one profiled Newton iteration, then
/// each load step's Newton effort and wall time (the first `steps` of them, or all), and the
/// peak memory. Issue 34's case: the 3D elastoplastic slope an engineer would refine.
pub fn run_slope(cell_size: f64, factor: f64, solver: &str, steps: Option<usize>) -> Result<()> {
    use loam::analysis::Analysis;
    use loam::scene::{AnalysisSpec, LoadedScene};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/slope_3d.ron");
    let mut loaded = LoadedScene::read(&path).map_err(|e| anyhow::anyhow!("{e}"))?;
    let scene = &mut loaded.scene;
    let extent: Vec<f64> = scene.grid.cell_size.iter().zip(&scene.grid.cells).map(|(h, n)| h * *n as f64).collect();
    let cells: Vec<usize> = extent.iter().map(|l| (l / cell_size).round() as usize).collect();
    if cells.iter().zip(&extent).any(|(&n, l)| n == 0 || (n as f64 * cell_size - l).abs() > 1e-9 * l) {
        bail!("--slope {cell_size}: the cell size must divide the grid's extent {extent:?}");
    }
    scene.grid.cell_size = vec![cell_size; 3];
    scene.grid.cells = cells;
    if let AnalysisSpec::QuasiStatic { strength_reduction, .. } = &mut scene.analysis {
        *strength_reduction = None;
    }
    scene.solver.linear = Some(linear_spec(solver)?);
    let t = Instant::now();
    let built = loaded.build::<3>().map_err(|e| anyhow::anyhow!("{e}"))?;
    // The laws' own strength reduction, as a search would apply it (c and tan φ / F).
    let Analysis::QuasiStatic(mut qs) = built.with_strength_reduced(factor)? else {
        bail!("examples/slope_3d.ron is no longer a quasi-static analysis");
    };
    println!(
        "slope_3d at {cell_size} m cells, c and tan φ / {factor}: {} points, built in {:.1} s",
        qs.model().points().len(),
        t.elapsed().as_secs_f64()
    );
    let p = qs.profile_iteration()?;
    println!(
        "one iteration ({}): {} | solver {:.2} GB",
        qs.linear_solver_description(),
        phases(&p),
        p.solver_bytes as f64 / 1e9
    );
    let start = Instant::now();
    let (mut iterations, mut cutbacks) = (0, 0);
    while !qs.is_finished() && qs.steps_done() < steps.unwrap_or(usize::MAX) {
        let before = qs.linear_solver_timings();
        let r = qs.step()?;
        let after = qs.linear_solver_timings();
        iterations += r.iterations;
        cutbacks += r.cutbacks;
        println!(
            "step {:>2}: λ {:.2} | {} corrections ({} in its hardest sub-step, {} of them abandoned), {} factorisations ({:.1} s), {} Krylov ({:.1} s), {} LU fallbacks | {} cut-backs | {:.1} s",
            r.step,
            r.load_factor,
            r.iterations,
            r.most_iterations(),
            r.hardest_abandoned,
            after.numeric_count - before.numeric_count,
            (after.numeric - before.numeric).as_secs_f64(),
            r.linear_iterations,
            (after.solve - before.solve).as_secs_f64(),
            r.direct_fallbacks,
            r.cutbacks,
            r.wall_time.as_secs_f64()
        );
    }
    let mem = peak_memory().map_or(f64::NAN, |b| b as f64 / 1e9);
    println!(
        "load: {iterations} corrections, {cutbacks} cut-backs, {:.1} s | peak {mem:.2} GB",
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
