//! Benchmarks of the explicit MPM (criterion; `cargo xtask bench`): point-steps per second
//! of the elastic block under gravity of issue 19 — 2D, 256 × 256 cells and 3D, 32³ cells,
//! 2 points per cell and axis (262 144 points each), E = 1e7, ν = 0.3, ρ = 2000, g = 10
//! (the block of the Taichi scripts in `scripts/peers/`; `scripts/bench_explicit.sh` runs
//! them side by side), MUSL, FLIP, CFL step 0.5, finite strain — with GIMP and with the
//! quadratic B-spline, each stepped on from rest as the peer's scripts do; and how the cost
//! scales with the points: the 2D GIMP block at 128², 256² and 512² cells (65 536, 262 144
//! and 1 048 576 points), each timed over one and the same step, taken when a P wave has
//! crossed a quarter of it (`SCALING_CROSSING`), so that the three are measured in the same
//! state of motion. The 2D GIMP block is also run as a cylinder (axisymmetric), beside the
//! plane one.
//! Before each, one line gives the step's split by stage (`StepPhases`) and the memory per
//! point (growth of the resident set from before the model is built to after its first
//! steps; Linux). Criterion's throughput is in elements (points) per second of one step:
//! point-steps per second.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use loam::explicit::{Explicit, ExplicitSettings, StepPhases};
use loam::grid::BasisKind;
use loam::implicit::Kinematics;
use loam::model::ModelState;
use loam_verification::elastic_block;
use std::hint::black_box;
use std::time::{Duration, Instant};

/// The resident set in bytes (0 where /proc is not there).
fn resident_bytes() -> u64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let kb = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok());
    kb.unwrap_or(0) * 1024
}

/// The block of `n` cells per side on `basis` (a cylinder when `axisymmetric`, 2D), its
/// explicit analysis to 1000 s (far more steps than a benchmark takes).
fn block<const D: usize>(n: usize, basis: BasisKind, axisymmetric: bool) -> Explicit<D> {
    let mut model = elastic_block::<D>(n, Kinematics::FiniteStrain, true).with_basis(basis).expect("a grid basis");
    if axisymmetric {
        model = model.with_axisymmetry().expect("a 2D block on the axis");
    }
    // Pure FLIP, as the figures in docs/benchmarks.md and the peer were measured.
    Explicit::new(model, ExplicitSettings { flip: 1.0, ..ExplicitSettings::new(1e3) }).expect("valid settings")
}

/// One line: the stage split of `steps` steps and the memory per point.
fn profile<const D: usize>(name: &str, n: usize, basis: BasisKind, axisymmetric: bool) -> Explicit<D> {
    let before = resident_bytes();
    let mut ex = block::<D>(n, basis, axisymmetric);
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

fn bench_block<const D: usize>(c: &mut Criterion, name: &str, n: usize, basis: BasisKind, axisymmetric: bool) {
    let mut ex = profile::<D>(name, n, basis, axisymmetric);
    let mut g = c.benchmark_group("explicit");
    g.throughput(Throughput::Elements(ex.model().points().len() as u64));
    g.sample_size(10);
    g.bench_function(name, |b| b.iter(|| black_box(ex.step().unwrap())));
    g.finish();
}

/// How far into its motion a scaling block is timed: after the time a P wave takes to cross
/// this share of the block (n/2 steps of the CFL step 0.5 at n cells), about where the 256²
/// block is measured in its own bench (some 150 steps from rest).
const SCALING_CROSSING: f64 = 0.25;

/// The 2D GIMP block of `n` cells per side stepped from rest to [`SCALING_CROSSING`] of a
/// P wave's crossing, then its next step timed again and again from that state, restored
/// before each (untimed). Stepped on instead, as criterion repeats the step as often as fits
/// its time, a block is measured further into its motion the fewer its points (about 600,
/// 150 and 40 steps at 128², 256², 512², against a crossing of 2n steps), where the points'
/// updates cost more: the blocks would not be compared like for like (CHANGELOG.md,
/// Explicit speed).
fn bench_scaling(c: &mut Criterion, name: &str, n: usize) {
    let mut ex = profile::<2>(name, n, BasisKind::Gimp, false);
    // h / c_p: the critical step less its velocity term, small against c_p under gravity.
    let crossing = n as f64 * ex.critical_time_step().unwrap();
    while ex.time() < SCALING_CROSSING * crossing {
        ex.step().unwrap();
    }
    let (state, points) = (ex.state(), ex.model().points().clone());
    let mut g = c.benchmark_group("explicit");
    g.throughput(Throughput::Elements(points.len() as u64));
    g.sample_size(10);
    g.bench_function(name, |b| {
        b.iter_custom(|iters| {
            let mut timed = Duration::ZERO;
            for _ in 0..iters {
                let saved = ModelState { points: points.clone(), load_vertices: Vec::new(), mesh_nodes: None };
                ex.resume(state, saved).unwrap();
                let start = Instant::now();
                black_box(ex.step().unwrap());
                timed += start.elapsed();
            }
            timed
        })
    });
    g.finish();
}

fn explicit(c: &mut Criterion) {
    bench_block::<2>(c, "block_2d_256_gimp", 256, BasisKind::Gimp, false);
    // The same block as a cylinder (docs/theory.md §20): the hoop terms' cost.
    bench_block::<2>(c, "block_2d_256_gimp_axisymmetric", 256, BasisKind::Gimp, true);
    bench_block::<2>(c, "block_2d_256_bspline", 256, BasisKind::QuadraticBSpline, false);
    bench_block::<3>(c, "block_3d_32_gimp", 32, BasisKind::Gimp, false);
    bench_block::<3>(c, "block_3d_32_bspline", 32, BasisKind::QuadraticBSpline, false);
    // Cost linear in the points. Stepped on from rest (before the scaling blocks were timed
    // from a restored state), the 65 536-point block also ran slower when built after a
    // larger one had been dropped (5.9–6.2 against 6.8–7.1 M point-steps/s first in its
    // process); restored before each timed step, it is not the slowest by habit here, after
    // the blocks above (CHANGELOG.md, Explicit speed).
    bench_scaling(c, "scaling_2d_128_gimp", 128);
    bench_scaling(c, "scaling_2d_256_gimp", 256);
    bench_scaling(c, "scaling_2d_512_gimp", 512);
}

criterion_group!(benches, explicit);
criterion_main!(benches);
