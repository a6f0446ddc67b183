//! Benchmarks of the explicit MPM (criterion; `cargo xtask bench`): point-steps per second
//! of the elastic block under gravity of issue 19 — 2D, 256 × 256 cells and 3D, 32³ cells,
//! 2 points per cell and axis (262 144 points each), E = 1e7, ν = 0.3, ρ = 2000, g = 10
//! (the block of the Taichi scripts in `scripts/peers/`; `scripts/bench_explicit.sh` runs
//! them side by side), MUSL, FLIP, CFL step 0.5, finite strain — with GIMP and with the
//! quadratic B-spline; and the 2D block at 128² and 512² cells (65 536 and 1 048 576
//! points), whose figures beside the 256² one show how the cost scales with the points.
//! Before each, one line gives the step's split by stage (`StepPhases`) and the memory per
//! point (growth of the resident set from before the model is built to after its first
//! steps; Linux). Criterion's throughput is in elements (points) per second of one step:
//! point-steps per second.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use loam::explicit::{Explicit, ExplicitSettings, StepPhases};
use loam::grid::BasisKind;
use loam::implicit::Kinematics;
use loam_verification::elastic_block;
use std::hint::black_box;
use std::time::Duration;

/// The resident set in bytes (0 where /proc is not there).
fn resident_bytes() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let kb = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok());
    kb.unwrap_or(0) * 1024
}

/// The block of `n` cells per side on `basis`, its explicit analysis to 1000 s (far more steps than a benchmark takes).
fn block<const D: usize>(n: usize, basis: BasisKind) -> Explicit<D> {
    let model = elastic_block::<D>(n, Kinematics::FiniteStrain, true).with_basis(basis).expect("a grid basis");
    Explicit::new(model, ExplicitSettings::new(1e3)).expect("valid settings")
}

/// One line: the stage split of `steps` steps and the memory per point.
fn profile<const D: usize>(name: &str, n: usize, basis: BasisKind) -> Explicit<D> {
    let before = resident_bytes();
    let mut ex = block::<D>(n, basis);
    ex.step().unwrap();
    let points = ex.model().points().len();
    let steps = 5;
    let mut total = StepPhases::default();
    let mut wall = Duration::ZERO;
    for _ in 0..steps {
        let r = ex.step().unwrap();
        wall += r.wall_time;
        total = total.add(&r.phases);
    }
    let per_step = wall.as_secs_f64() / steps as f64;
    let split: Vec<String> =
        total.named().iter().map(|(k, d)| format!("{k} {:.1} ms", 1e3 * d.as_secs_f64() / steps as f64)).collect();
    println!(
        "{name}: {points} points, {} threads, {:.2} M point-steps/s ({:.1} ms a step: {}), {:.0} B per point",
        rayon::current_num_threads(),
        points as f64 / per_step / 1e6,
        1e3 * per_step,
        split.join(", "),
        resident_bytes().saturating_sub(before) as f64 / points as f64
    );
    ex
}

fn bench_block<const D: usize>(c: &mut Criterion, name: &str, n: usize, basis: BasisKind) {
    let mut ex = profile::<D>(name, n, basis);
    let mut g = c.benchmark_group("explicit");
    g.throughput(Throughput::Elements(ex.model().points().len() as u64));
    g.sample_size(10);
    g.bench_function(name, |b| b.iter(|| black_box(ex.step().unwrap())));
    g.finish();
}

fn explicit(c: &mut Criterion) {
    // Cost linear in the points: 65 536 and 1 048 576 points beside the 262 144, smallest
    // first. Measured after the 262 144-point block had been dropped, the 65 536-point one
    // ran 5.9–6.2 M point-steps/s, against 6.8–7.2 M with glibc's mmap threshold held
    // (`MALLOC_MMAP_THRESHOLD_`: glibc raises it, up to 32 MiB, to a freed block's size, and
    // serves the later, smaller buffers from its heap) and 7 M in a process of its own; run
    // first it ran 6.8–7.1 M, and the 262 144-point block after it as fast as when first
    // (docs/verification.md, Explicit speed).
    bench_block::<2>(c, "block_2d_128_gimp", 128, BasisKind::Gimp);
    bench_block::<2>(c, "block_2d_256_gimp", 256, BasisKind::Gimp);
    bench_block::<2>(c, "block_2d_512_gimp", 512, BasisKind::Gimp);
    bench_block::<2>(c, "block_2d_256_bspline", 256, BasisKind::QuadraticBSpline);
    bench_block::<3>(c, "block_3d_32_gimp", 32, BasisKind::Gimp);
    bench_block::<3>(c, "block_3d_32_bspline", 32, BasisKind::QuadraticBSpline);
}

criterion_group!(benches, explicit);
criterion_main!(benches);
