//! V3 strip footing (VERIFICATION.md V3): q_u against Prandtl's (2 + π) c_u for von Mises
//! and c N_c for associated Mohr–Coulomb, with the mesh sequence, plain, with B-bar and
//! with the assumed strain (β = 0.1). The 5 % bound is checked for every law with the
//! assumed strain at 8 cells per b (full sweep).

use crate::{Report, Row};
use anyhow::Result;
use loam::constitutive::{ConstitutiveLaw, Elastic, MohrCoulomb, VonMises};
use loam::implicit::{AntiLocking, QuasiStatic, QuasiStaticSettings};
use loam::verification::{footing_model, prandtl_nc};
use std::fmt::Write as _;
use std::sync::Arc;
use std::time::Instant;

/// Cohesion (c_u for von Mises: σ_y = √3 c_u in plane strain), E, ν of every footing run.
const C: f64 = 10.0;
const YOUNG: f64 = 1e5;
const POISSON: f64 = 0.3;
/// Settlement (in b) and load steps: 0.001 b per step. The limit load is reached between
/// 0.005 b (undrained) and ~0.03 b (φ = 30°); small steps keep the first plastic steps from
/// overshooting it.
const SETTLEMENT: f64 = 0.04;
const LOAD_STEPS: usize = 40;
/// The assumed strain's stabilization β (the usual hourglass weight, docs/theory.md §13).
const STABILIZATION: f64 = 0.1;

/// One footing run: the peak and final footing pressure over c, and what Newton needed.
struct FootingRun {
    peak: f64,
    last: f64,
    max_iterations: usize,
    /// The most corrections the hardest sub-step of any step needed until its relative
    /// residual was first ≤ 1e-9 (the bound; convergence also waits for the
    /// relative correction, which can cost one more).
    to_tolerance: usize,
    cutbacks: usize,
    wall_s: f64,
    failure: Option<String>,
    /// The step whose hardest sub-step took the most Newton iterations, and that
    /// sub-step's relative residuals.
    worst: usize,
    residuals: Vec<f64>,
}

fn run(law: &Arc<dyn ConstitutiveLaw>, cells: usize, anti_locking: AntiLocking) -> FootingRun {
    let model = footing_model(law.clone(), cells, 10, 5, SETTLEMENT, anti_locking);
    // The extrapolated start (docs/theory.md §6) halves the Newton iterations here.
    let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps: LOAD_STEPS, extrapolate: true, ..Default::default() });
    let tolerance = qs.settings().newton.residual_tolerance;
    let t = Instant::now();
    let mut out = FootingRun { peak: f64::NAN, last: f64::NAN, max_iterations: 0, to_tolerance: 0, cutbacks: 0, wall_s: 0.0, failure: None, worst: 0, residuals: Vec::new() };
    while !qs.is_finished() {
        match qs.step() {
            Ok(r) => {
                out.last = -r.reactions[0][1] / C;
                out.peak = out.peak.max(out.last);
                out.cutbacks += r.cutbacks;
                let to_tolerance = r.hardest_residuals.iter().position(|&x| x <= tolerance).unwrap_or(r.hardest_residuals.len());
                out.to_tolerance = out.to_tolerance.max(to_tolerance);
                if r.most_iterations() > out.max_iterations {
                    out.max_iterations = r.most_iterations();
                    out.worst = r.step;
                    out.residuals = r.hardest_residuals;
                }
            }
            Err(e) => {
                out.failure = Some(e.to_string());
                break;
            }
        }
    }
    out.wall_s = t.elapsed().as_secs_f64();
    out
}

pub fn verify(quick: bool, report: &mut Report) -> Result<()> {
    let fine_meshes: &[usize] = if quick { &[2, 4] } else { &[2, 4, 8] };
    let plain_meshes: &[usize] = &[2, 4];
    let assumed = AntiLocking::AssumedStrain { stabilization: STABILIZATION };
    let md = &mut report.md;
    writeln!(md, "## V3 strip footing\n\nRigid rough footing, half-width b = 1, pushed {SETTLEMENT} b in {LOAD_STEPS} load steps (extrapolated start) into weightless soil; half model 10 b × 5 b, linear basis, 2×2 points per cell, small strain, geometrically linear (points held at their places, Prandtl's small-deformation setting), E = {YOUNG:e}, ν = {POISSON} (and 0.49 for the locking case), c = {C}. q = footing reaction / b; q_u = the peak of the load–settlement curve; reference (2 + π) c_u (von Mises, c_u = σ_y/√3) and c N_c (Mohr–Coulomb, associated). Plain: every point's own strain (locks); B-bar: cell-averaged dilatation; assumed strain: the cell's average strain plus β = {STABILIZATION} times each point's deviatoric deviation (docs/theory.md §13). The bound |q_u/q_ref − 1| ≤ 5 % is checked for every law with the assumed strain at 8 cells per b (full sweep).\n")?;
    writeln!(md, "| law | treatment | cells per b | q_u/c | q(end)/c | reference | q_u/q_ref − 1 | max Newton its per sub-step | max corrections to 1e-9 | cut-backs | wall [s] |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    let elastic = Elastic::new(YOUNG, POISSON)?;
    let mut laws: Vec<(String, Arc<dyn ConstitutiveLaw>, f64)> =
        vec![("von Mises".into(), Arc::new(VonMises::new(elastic, 3f64.sqrt() * C, 0.0)?), prandtl_nc(0.0))];
    // Issue 5's locking case: nearly incompressible elasticity under the von Mises footing.
    let incompressible = Elastic::new(YOUNG, 0.49)?;
    laws.push(("von Mises, ν = 0.49".into(), Arc::new(VonMises::new(incompressible, 3f64.sqrt() * C, 0.0)?), prandtl_nc(0.0)));
    for phi in [0.0, 10.0, 20.0, 30.0] {
        laws.push((format!("Mohr–Coulomb φ = ψ = {phi}°"), Arc::new(MohrCoulomb::from_degrees(elastic, C, phi, phi)?), prandtl_nc(phi)));
    }
    let (mut residuals, mut verdicts) = (Vec::new(), Vec::new());
    for (name, law, nc) in &laws {
        for (anti_locking, meshes) in [(AntiLocking::None, plain_meshes), (AntiLocking::BBar, fine_meshes), (assumed, fine_meshes)] {
            let treatment = if anti_locking == AntiLocking::None { "plain" } else { anti_locking.name() };
            let mut finest = None;
            for &cells in meshes {
                eprintln!("verify: V3 {name}, {treatment}, {cells} cells per b");
                let r = run(law, cells, anti_locking);
                let ratio = r.peak / nc - 1.0;
                writeln!(md, "| {name} | {treatment} | {cells} | {:.3} | {:.3} | {nc:.3} | {ratio:+.3} | {} | {} | {} | {:.2} |", r.peak, r.last, r.max_iterations, r.to_tolerance, r.cutbacks, r.wall_s)?;
                if let Some(f) = &r.failure {
                    writeln!(md, "\n{name}, {treatment}, {cells} cells per b stopped: {f}\n")?;
                }
                report.rows.push(Row::info(format!("V3 {name} {treatment} {cells}/b"), "qu_over_q_ref_minus_1", ratio));
                report.rows.push(Row::info(format!("V3 {name} {treatment} {cells}/b"), "max_newton_corrections_to_1e-9", r.to_tolerance as f64));
                if anti_locking == assumed && cells == *meshes.last().unwrap() {
                    residuals.push(format!("- {name}, {treatment}, {cells} cells per b, step {}: {}", r.worst, r.residuals.iter().map(|x| format!("{x:.1e}")).collect::<Vec<_>>().join(" → ")));
                }
                finest = Some((cells, ratio, r.max_iterations, r.to_tolerance));
            }
            // Every law's bound, the anti-locking bound of issue 5 (ν = 0.49) among them, is
            // checked with the assumed strain where the full sweep reaches 8 cells per b.
            if let Some((cells, ratio, its, to_tolerance)) = finest.filter(|_| anti_locking == assumed) {
                if cells == 8 {
                    report.rows.push(Row::upper(format!("V3 {name}, assumed strain, 8/b"), "abs_qu_over_q_ref_minus_1", ratio.abs(), 0.05));
                }
                verdicts.push(format!(
                    "- {name}: {ratio:+.3} at {cells} cells per b — 5 % bound {}; ≤ 8 Newton iterations per step to 1e-9 {} ({to_tolerance} corrections to 1e-9, {its} to convergence)",
                    if ratio.abs() <= 0.05 { "met" } else { "NOT met" },
                    if to_tolerance <= 8 { "met" } else { "NOT met" }
                ));
            }
        }
    }
    writeln!(md, "\nWith the assumed strain on the finest mesh of this run:\n\n{}\n", verdicts.join("\n"))?;
    writeln!(md, "Relative residuals of the sub-step with the most Newton iterations, assumed strain, finest mesh:\n\n{}\n", residuals.join("\n"))?;
    Ok(())
}
