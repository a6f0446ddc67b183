//! The explicit benchmark's elastic block (`benches/explicit.rs`: 2 points per cell and axis,
//! E = 1e7, ν = 0.3, ρ = 2000, g = 10, MUSL, FLIP, CFL 0.5, finite strain; units SI) run
//! for a given number of steps after a first one, printing point-steps per second and the
//! step's split by stage: a short run for a profiler where criterion's repetitions get in
//! the way. On a shared machine whose timings wander, the instruction count of
//! `valgrind --tool=cachegrind` is a measure that does not: the difference between two
//! step counts, divided by the steps and points, is the instructions per point-step
//! (docs/benchmarks.md, Explicit speed).
//!
//! ```text
//! cargo bench -p loam-bench --bench explicit_block -- DIM CELLS STEPS [gimp|bspline]
//! cargo bench -p loam-bench --bench explicit_block -- 2 256 20
//! RAYON_NUM_THREADS=1 valgrind --tool=cachegrind --cache-sim=no \
//!     $(cargo bench -p loam-bench --bench explicit_block --no-run --message-format=json \
//!       | jq -r 'select(.executable != null) | .executable') 2 128 6
//! ```
//!
//! A bench target rather than an example so that `cargo test` does not build it.

use loam::explicit::{Explicit, ExplicitSettings, StepPhases};
use loam::grid::BasisKind;
use loam::implicit::Kinematics;
use loam_verification::elastic_block;
use std::process::ExitCode;
use std::time::Instant;

/// Run the block of `cells` per side on `basis` for `steps` steps after a first one and
/// print the rate and the split.
fn run<const D: usize>(cells: usize, basis: BasisKind, steps: usize) -> Result<(), String> {
    let model =
        elastic_block::<D>(cells, Kinematics::FiniteStrain, true).with_basis(basis).map_err(|e| e.to_string())?;
    // Pure FLIP, as the bench (benches/explicit.rs) runs it.
    let settings = ExplicitSettings { flip: 1.0, ..ExplicitSettings::new(1e3) };
    let mut explicit = Explicit::new(model, settings).map_err(|e| e.to_string())?;
    explicit.step().map_err(|e| e.to_string())?;
    let mut total = StepPhases::default();
    let start = Instant::now();
    for _ in 0..steps {
        total = total.add(&explicit.step().map_err(|e| e.to_string())?.phases);
    }
    let per_step = start.elapsed().as_secs_f64() / steps.max(1) as f64;
    let points = explicit.model().points().len();
    let split: Vec<String> = total
        .named()
        .iter()
        .map(|(stage, d)| format!("{stage} {:.1} ms", 1e3 * d.as_secs_f64() / steps.max(1) as f64))
        .collect();
    println!(
        "{D}D, {cells} cells per side, {basis:?}, {points} points, {} threads: {:.2} M point-steps/s, {:.1} ms a step ({})",
        rayon::current_num_threads(),
        points as f64 / per_step / 1e6,
        1e3 * per_step,
        split.join(", ")
    );
    Ok(())
}

fn main() -> ExitCode {
    // `cargo bench` appends `--bench` to a harness-less target's arguments.
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    let usage = "usage: explicit_block DIM(2|3) CELLS STEPS [gimp|bspline]";
    let number = |i: usize| args.get(i).and_then(|s| s.parse::<usize>().ok());
    let basis = match args.get(3).map(String::as_str) {
        None | Some("gimp") => Some(BasisKind::Gimp),
        Some("bspline") => Some(BasisKind::QuadraticBSpline),
        Some(_) => None,
    };
    if args.is_empty() {
        // `cargo bench` runs every bench target without arguments: nothing to run here.
        eprintln!("{usage}");
        return ExitCode::SUCCESS;
    }
    let result = match (number(0), number(1), number(2), basis) {
        (Some(2), Some(cells), Some(steps), Some(basis)) if cells > 0 => run::<2>(cells, basis, steps),
        (Some(3), Some(cells), Some(steps), Some(basis)) if cells > 0 => run::<3>(cells, basis, steps),
        _ => Err(usage.to_string()),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("{e}");
            ExitCode::FAILURE
        }
    }
}
