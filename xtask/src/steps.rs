//! `cargo xtask steps`: implicit vs explicit step sizes (the seed paper's comparison).
//!
//! - V2 vibrating bar: implicit trapezoidal from the explicit critical step Δt_c = h/c up
//!   to 200 Δt_c; explicit MUSL at fractions of Δt_c up to and past the limit, blow-up
//!   detected. Period error (against the exact T) and v_cm error against Δt and against
//!   the wall time of the steps.
//! - V1c column (quasi-static, large deformation): implicit load stepping against explicit
//!   MUSL with local damping run to a steady state, e_σ against wall time.
//! - Both problems also with the updated Lagrangian FEM reference (the seed paper's
//!   comparison), through the same implicit analyses.
//!
//! Writes `steps.md`, `steps.csv` and SVG plots into the output folder.

use crate::dynamics::{bar_explicit, bar_fem_implicit, bar_implicit, explicit, run_analysis, DynRun};
use crate::svg::{Plot, Series};
use anyhow::{Context, Result};
use loam::explicit::{ExplicitSettings, TimeStep};
use loam::grid::BasisKind;
use loam::implicit::{Kinematics, QuasiStatic, QuasiStaticSettings};
use loam::io::output::{CsvCell, CsvWriter};
use loam_verification::{column_errors, column_fem_model, column_model, Column, VibratingBar};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

struct Point {
    scheme: &'static str,
    dt: f64,
    steps: usize,
    period_error: f64,
    vcm_error: f64,
    energy_growth: f64,
    wall_s: f64,
    outcome: String,
}

pub fn run(quick: bool, out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let bar = VibratingBar::REFERENCE;
    let dt_c = bar.critical_time_step();
    let mut md = String::new();
    let mut csv = CsvWriter::create(
        out.join("steps.csv"),
        &["problem", "scheme", "dt_or_steps", "steps", "error", "second_error", "wall_s", "outcome"],
    )?;
    writeln!(md, "# Implicit vs explicit step sizes\n\nMode: {}. Wall time: the steps alone, on this machine, one run each (noisy; compare ratios, not absolute values).\n", if quick { "quick" } else { "full" })?;

    // ---------------------------------------------------------------- V2
    let implicit_multiples: &[f64] =
        if quick { &[1.0, 5.0, 10.0, 50.0, 100.0] } else { &[1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0] };
    let explicit_fractions: &[f64] =
        if quick { &[0.25, 0.5, 0.9, 1.5, 2.0] } else { &[0.1, 0.25, 0.5, 0.75, 0.9, 1.0, 1.2, 1.5, 1.7, 1.8, 2.0] };
    let mut points = Vec::new();
    let implicit_runs: [(&str, &dyn Fn(f64) -> DynRun); 2] =
        [("implicit", &|dt| bar_implicit(dt, BasisKind::Linear)), ("UL-FEM implicit", &bar_fem_implicit)];
    for (scheme, run_at) in implicit_runs {
        for &k in implicit_multiples {
            let dt = k * dt_c;
            eprintln!("steps: V2 {scheme} dt = {dt}");
            let run = run_at(dt);
            let e = bar.errors(&run.record);
            points.push(Point {
                scheme,
                dt,
                steps: run.steps,
                period_error: (e.period / bar.period() - 1.0).abs(),
                vcm_error: e.vcm_error,
                energy_growth: e.energy_growth,
                wall_s: run.wall_s,
                outcome: run.failure.unwrap_or_else(|| "ran to the end".into()),
            });
        }
    }
    for &f in explicit_fractions {
        let dt = f * dt_c;
        eprintln!("steps: V2 explicit dt = {dt}");
        let (run, leapfrog_growth) =
            bar_explicit(TimeStep::Fixed { dt, allow_above_critical: true }, BasisKind::Linear);
        let e = bar.errors(&run.record);
        // Stable: reached the end without growth of the leapfrog energy beyond 1 % (a
        // slowly growing instability may not reach NaN within 3 periods; the energy read at
        // one time level swings by ±ωΔt/2 without being unstable).
        let outcome = match run.failure {
            Some(f) => format!("blow-up detected after {} steps: {f}", run.steps),
            None if leapfrog_growth > 0.01 => format!("energy grew by {:.1} % (unstable)", 100.0 * leapfrog_growth),
            None => "ran to the end".into(),
        };
        points.push(Point {
            scheme: "explicit",
            dt,
            steps: run.steps,
            period_error: (e.period / bar.period() - 1.0).abs(),
            vcm_error: e.vcm_error,
            energy_growth: leapfrog_growth,
            wall_s: run.wall_s,
            outcome,
        });
    }
    writeln!(md, "## V2 vibrating bar\n\nL = 25, E = 100, ρ = 1, h = 1, 2×2 points per cell, linear basis (UL-FEM: one element per cell, 2×2 Gauss points), t_end = 3T = 30, Δt_c = h/c = {dt_c}. Period error against the exact T = 10 (so the implicit figures include the trapezoidal elongation); v_cm error = max |v_cm − exact| / (2v₀/π). Energy growth: implicit W + ½Σm|v|², explicit the leapfrog energy.\n")?;
    writeln!(md, "| scheme | Δt | Δt/Δt_c | steps | period error | v_cm error | max energy growth | wall [s] | outcome |\n|---|---:|---:|---:|---:|---:|---:|---:|---|")?;
    for p in &points {
        writeln!(
            md,
            "| {} | {:.4} | {:.2} | {} | {:.2e} | {:.2e} | {:.2e} | {:.4} | {} |",
            p.scheme,
            p.dt,
            p.dt / dt_c,
            p.steps,
            p.period_error,
            p.vcm_error,
            p.energy_growth,
            p.wall_s,
            p.outcome
        )?;
        csv.row_mixed(&[
            CsvCell::Text("V2"),
            CsvCell::Text(p.scheme),
            CsvCell::Float(p.dt),
            CsvCell::Int(p.steps as i64),
            CsvCell::Float(p.period_error),
            CsvCell::Float(p.vcm_error),
            CsvCell::Float(p.wall_s),
            CsvCell::Text(&p.outcome),
        ])?;
    }
    let stable = |p: &&Point| p.outcome == "ran to the end";
    let largest_explicit =
        points.iter().filter(|p| p.scheme == "explicit").filter(stable).map(|p| p.dt).fold(f64::NAN, f64::max);
    let first_unstable =
        points.iter().filter(|p| p.scheme == "explicit" && !stable(p)).map(|p| p.dt).fold(f64::NAN, f64::min);
    let implicit_1pct =
        points.iter().filter(|p| p.scheme == "implicit" && p.period_error < 0.01).max_by(|a, b| a.dt.total_cmp(&b.dt));
    let fem_1pct = points
        .iter()
        .filter(|p| p.scheme == "UL-FEM implicit" && p.period_error < 0.01)
        .max_by(|a, b| a.dt.total_cmp(&b.dt));
    let explicit_1pct = points
        .iter()
        .filter(|p| p.scheme == "explicit" && stable(p) && p.period_error < 0.01)
        .min_by(|a, b| a.wall_s.total_cmp(&b.wall_s));
    writeln!(md, "\n- Largest stable explicit step: **{largest_explicit:.4}** ({:.2} Δt_c); the first unstable one tried: {first_unstable:.4} ({:.2} Δt_c).", largest_explicit / dt_c, first_unstable / dt_c)?;
    if let Some(p) = implicit_1pct {
        writeln!(
            md,
            "- Largest implicit step with period error < 1 %: **{:.4}** ({:.0} Δt_c), {} steps, {:.4} s.",
            p.dt,
            p.dt / dt_c,
            p.steps,
            p.wall_s
        )?;
    }
    if let Some(p) = fem_1pct {
        writeln!(md, "- UL-FEM reference (same Newmark, Newton and laws; one element per cell, 2×2 Gauss points): largest step with period error < 1 %: **{:.4}** ({:.0} Δt_c), {} steps, {:.4} s.", p.dt, p.dt / dt_c, p.steps, p.wall_s)?;
    }
    if let Some(p) = explicit_1pct {
        writeln!(
            md,
            "- Cheapest stable explicit run with period error < 1 %: Δt = {:.4}, {} steps, {:.4} s.",
            p.dt, p.steps, p.wall_s
        )?;
    }
    if let (Some(i), Some(e)) = (implicit_1pct, explicit_1pct) {
        writeln!(
            md,
            "- Wall time at 1 % period error: implicit {:.4} s, explicit {:.4} s (ratio explicit/implicit {:.2}).",
            i.wall_s,
            e.wall_s,
            e.wall_s / i.wall_s
        )?;
    }
    let series = |scheme: &str, x: fn(&Point) -> f64| -> Vec<(f64, f64)> {
        points
            .iter()
            .filter(|p| p.scheme == scheme && stable(p) && p.period_error.is_finite() && p.period_error > 0.0)
            .map(|p| (x(p), p.period_error))
            .collect()
    };
    let mut plot =
        Plot {
            log_x: true, log_y: true, ..Plot::new("V2: period error against time step", "Δt", "|T/T_exact − 1|")
        };
    plot.series.push(Series::new("implicit trapezoidal", series("implicit", |p| p.dt)));
    plot.series.push(Series::new("UL-FEM trapezoidal", series("UL-FEM implicit", |p| p.dt)).dashed());
    plot.series.push(Series::new("explicit MUSL (stable runs)", series("explicit", |p| p.dt)).dashed());
    plot.write(&out.join("bar_error_vs_dt.svg"))?;
    let mut plot = Plot {
        log_x: true,
        log_y: true,
        ..Plot::new("V2: period error against wall time", "wall time of the steps [s]", "|T/T_exact − 1|")
    };
    plot.series.push(Series::new("implicit trapezoidal", series("implicit", |p| p.wall_s)));
    plot.series.push(Series::new("UL-FEM trapezoidal", series("UL-FEM implicit", |p| p.wall_s)).dashed());
    plot.series.push(Series::new("explicit MUSL (stable runs)", series("explicit", |p| p.wall_s)).dashed());
    plot.write(&out.join("bar_error_vs_wall.svg"))?;
    writeln!(md, "\n![error vs dt](bar_error_vs_dt.svg) ![error vs wall](bar_error_vs_wall.svg)\n")?;

    // ---------------------------------------------------------------- V1c column
    let col = Column::V1C;
    let cells = if quick { 16 } else { 32 };
    let h = col.height / cells as f64;
    let model = || column_model::<2>(&col, h, cells, 2, BasisKind::Gimp, Kinematics::FiniteStrain);
    let reference = |y: f64| col.hencky_displacement(y);
    writeln!(md, "## V1c column, quasi-static (large deformation)\n\n{cells} cells, GIMP, 2×2 points per cell, Hencky. Implicit: equal load steps, Newton to 1e-9. UL-FEM: the same implicit analysis on one bilinear element per cell with 2×2 Gauss points, the mesh moving with the body. Explicit: MUSL, Cfl 0.5, gravity applied at once, local damping α, run until the kinetic energy has decayed; e_σ (V1 norm) sampled along the run against the wall time of the steps so far.\n")?;
    writeln!(md, "| scheme | load steps / damping | steps | e_σ | wall [s] |\n|---|---:|---:|---:|---:|")?;
    let mut implicit_pts = Vec::new();
    let mut fem_pts = Vec::new();
    let fem_model = || column_fem_model::<2>(&col, h, cells, 2, Kinematics::FiniteStrain);
    for (scheme, make, load_steps, pts) in [
        (
            "implicit",
            &model as &dyn Fn() -> loam::model::Model<2>,
            &[1usize, 2, 5, 10, 20, 40, 80, 160][..],
            &mut implicit_pts,
        ),
        ("UL-FEM implicit", &fem_model, &[1, 5, 20, 80][..], &mut fem_pts),
    ] {
        for &steps in load_steps {
            eprintln!("steps: V1c {scheme}, {steps} load steps");
            let mut qs = QuasiStatic::new(make(), QuasiStaticSettings { load_steps: steps, ..Default::default() });
            let t = Instant::now();
            let mut failed = None;
            while !qs.is_finished() {
                if let Err(e) = qs.step() {
                    failed = Some(e.to_string());
                    break;
                }
            }
            let wall = t.elapsed().as_secs_f64();
            let e = column_errors(qs.model().points(), &col, 1, reference).stress;
            match failed {
                None => {
                    writeln!(md, "| {scheme} | {steps} | {steps} | {e:.3e} | {wall:.4} |")?;
                    csv.row_mixed(&[
                        CsvCell::Text("V1c"),
                        CsvCell::Text(scheme),
                        CsvCell::Int(steps as i64),
                        CsvCell::Int(steps as i64),
                        CsvCell::Float(e),
                        CsvCell::Text(""),
                        CsvCell::Float(wall),
                        CsvCell::Text("ok"),
                    ])?;
                    pts.push((wall, e, steps));
                }
                Some(f) => writeln!(md, "| {scheme} | {steps} | – | failed: {f} | {wall:.4} |")?,
            }
        }
    }
    let c = (col.young / col.density).sqrt();
    let t1 = 4.0 * col.height / c;
    let duration = if quick { 6.0 * t1 } else { 12.0 * t1 };
    let mut explicit_curves = Vec::new();
    let mut explicit_best: Option<(f64, f64, f64)> = None; // (final e, wall to reach it, damping)
    for damping in [0.3, 0.6] {
        eprintln!("steps: V1c explicit, damping {damping}");
        let settings = ExplicitSettings { damping, ..ExplicitSettings::new(duration) };
        let mut curve = Vec::new();
        let mut wall = 0.0;
        let mut last_wall = Instant::now();
        let mut k = 0usize;
        let (run, last) = run_analysis(explicit(model(), settings), |_, m| {
            wall += last_wall.elapsed().as_secs_f64();
            k += 1;
            if k.is_multiple_of(20) {
                curve.push((wall, column_errors(m.points(), &col, 1, reference).stress));
            }
            last_wall = Instant::now();
        });
        let e_final = column_errors(last.points(), &col, 1, reference).stress;
        let outcome = run.failure.clone().unwrap_or_else(|| "ok".into());
        writeln!(md, "| explicit | α = {damping} | {} | {e_final:.3e} | {:.4} |", run.steps, run.wall_s)?;
        csv.row_mixed(&[
            CsvCell::Text("V1c"),
            CsvCell::Text(&format!("explicit damping {damping}")),
            CsvCell::Float(damping),
            CsvCell::Int(run.steps as i64),
            CsvCell::Float(e_final),
            CsvCell::Text(""),
            CsvCell::Float(run.wall_s),
            CsvCell::Text(&outcome),
        ])?;
        if run.failure.is_none() {
            // Wall time at which the run first came within 5 % of its final error.
            let reach = curve.iter().find(|(_, e)| *e <= 1.05 * e_final).map(|p| p.0).unwrap_or(run.wall_s);
            if explicit_best.is_none_or(|b| e_final < b.0) {
                explicit_best = Some((e_final, reach, damping));
            }
        } else {
            writeln!(md, "\nexplicit α = {damping} stopped: {outcome}\n")?;
        }
        explicit_curves.push((damping, curve));
    }
    if let Some((e_x, w_x, damping)) = explicit_best {
        match implicit_pts.iter().filter(|p| p.1 <= e_x).min_by(|a, b| a.0.total_cmp(&b.0)) {
            Some(&(w_i, e_i, steps)) => writeln!(md, "\nExplicit (α = {damping}) settles to e_σ = {e_x:.3e} after {w_x:.3} s of steps; implicit reaches e_σ = {e_i:.3e} ≤ that with {steps} load steps in {w_i:.4} s: **{:.0}× less wall time**.\n", w_x / w_i)?,
            None => writeln!(md, "\nNo implicit run reached the explicit error {e_x:.3e}.\n")?,
        }
    }
    let mut plot = Plot {
        log_x: true,
        log_y: true,
        ..Plot::new("V1c column: stress error against wall time", "wall time of the steps [s]", "e_σ")
    };
    plot.series.push(Series::new("implicit (load steps 1…160)", implicit_pts.iter().map(|p| (p.0, p.1)).collect()));
    plot.series.push(Series::new("UL-FEM implicit (load steps 1…80)", fem_pts.iter().map(|p| (p.0, p.1)).collect()));
    for (damping, curve) in &explicit_curves {
        plot.series.push(
            Series::new(
                format!("explicit MUSL, damping {damping}"),
                curve.iter().copied().filter(|p| p.0 > 0.0).collect(),
            )
            .dashed(),
        );
    }
    plot.write(&out.join("column_error_vs_wall.svg"))?;
    writeln!(md, "![column](column_error_vs_wall.svg)\n")?;
    std::fs::write(out.join("steps.md"), &md)?;
    println!("{md}");
    eprintln!("steps: wrote {}/steps.md, steps.csv and SVG plots", out.display());
    Ok(())
}
