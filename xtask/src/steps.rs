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
//! - V4c slope run-out (large deformation, collapse under gravity): implicit trapezoidal
//!   Newmark at several Δt and explicit MUSL at several CFL safety factors, the final
//!   profile's error against an implicit run at a small Δt, against the wall time.
//!
//! Writes `steps.md`, `steps.csv` and SVG plots into the output folder.

use crate::dynamics::{bar_explicit, bar_fem_implicit, bar_implicit, explicit, run_analysis, DynRun};
use crate::slope::{self, Runout};
use anyhow::{Context, Result};
use loam::analysis::Analysis;
use loam::explicit::{Explicit, ExplicitSettings, TimeStep};
use loam::format::output::plot::{Plot, Series};
use loam::format::output::{CsvCell, CsvWriter};
use loam::grid::BasisKind;
use loam::implicit::{Dynamic, DynamicSettings, Kinematics, QuasiStatic, QuasiStaticSettings};
use loam::model::Model;
use loam::points::PointStore;
use loam_verification::{column_errors, column_fem_model, column_model, Column, VibratingBar};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// The study's output: the markdown of `steps.md`, `steps.csv`, and the folder.
struct Study<'a> {
    md: String,
    csv: CsvWriter,
    out: &'a Path,
}

impl Study<'_> {
    /// One row of `steps.csv`: the problem and scheme, Δt (V2) or load steps or damping
    /// (V1c), the steps taken, the error and a second one (V2: v_cm), the wall time and
    /// how the run ended.
    fn csv_row(
        &mut self,
        id: [&str; 2],
        dt_or_steps: CsvCell,
        steps: usize,
        errors: [CsvCell; 2],
        wall_s: f64,
        outcome: &str,
    ) -> Result<()> {
        let [problem, scheme] = id;
        let [error, second_error] = errors;
        self.csv.row_mixed(&[
            CsvCell::Text(problem),
            CsvCell::Text(scheme),
            dt_or_steps,
            CsvCell::Int(steps as i64),
            error,
            second_error,
            CsvCell::Float(wall_s),
            CsvCell::Text(outcome),
        ])?;
        Ok(())
    }
}

pub fn run(quick: bool, out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let csv = CsvWriter::create(
        out.join("steps.csv"),
        &["problem", "scheme", "dt_or_steps", "steps", "error", "second_error", "wall_s", "outcome"],
    )?;
    let mut study = Study { md: String::new(), csv, out };
    writeln!(study.md, "# Implicit vs explicit step sizes\n\nMode: {}. Wall time: the steps alone, on this machine, one run each (noisy; compare ratios, not absolute values).\n", if quick { "quick" } else { "full" })?;
    bar_study(quick, &mut study)?;
    column_study(quick, &mut study)?;
    runout_study(quick, &mut study)?;
    std::fs::write(out.join("steps.md"), &study.md)?;
    println!("{}", study.md);
    eprintln!("steps: wrote {}/steps.md, steps.csv and SVG plots", out.display());
    Ok(())
}

/// One V2 run.
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

impl Point {
    /// A run of `scheme` at Δt = `dt`, its errors against the exact T and v_cm. Its energy
    /// growth: the leapfrog energy's where given (explicit), else W + ½Σm|v|² (implicit).
    fn new(scheme: &'static str, dt: f64, run: &DynRun, leapfrog_growth: Option<f64>, outcome: String) -> Self {
        let bar = VibratingBar::REFERENCE;
        let e = bar.errors(&run.record);
        Point {
            scheme,
            dt,
            steps: run.steps,
            period_error: (e.period / bar.period() - 1.0).abs(),
            vcm_error: e.vcm_error,
            energy_growth: leapfrog_growth.unwrap_or(e.energy_growth),
            wall_s: run.wall_s,
            outcome,
        }
    }

    fn stable(&self) -> bool {
        self.outcome == "ran to the end"
    }
}

/// V2: the implicit schemes at multiples of Δt_c, explicit at fractions of it; the table,
/// the findings and the two plots.
fn bar_study(quick: bool, study: &mut Study) -> Result<()> {
    let dt_c = VibratingBar::REFERENCE.critical_time_step();
    let mut points = implicit_points(quick, dt_c);
    points.extend(explicit_points(quick, dt_c));
    writeln!(study.md, "## V2 vibrating bar\n\nL = 25, E = 100, ρ = 1, h = 1, 2×2 points per cell, linear basis (UL-FEM: one element per cell, 2×2 Gauss points), t_end = 3T = 30, Δt_c = h/c = {dt_c}. Period error against the exact T = 10 (so the implicit figures include the trapezoidal elongation); v_cm error = max |v_cm − exact| / (2v₀/π). Energy growth: implicit W + ½Σm|v|², explicit the leapfrog energy.\n")?;
    writeln!(study.md, "| scheme | Δt | Δt/Δt_c | steps | period error | v_cm error | max energy growth | wall [s] | outcome |\n|---|---:|---:|---:|---:|---:|---:|---:|---|")?;
    for p in &points {
        writeln!(
            study.md,
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
        let errors = [CsvCell::Float(p.period_error), CsvCell::Float(p.vcm_error)];
        study.csv_row(["V2", p.scheme], CsvCell::Float(p.dt), p.steps, errors, p.wall_s, &p.outcome)?;
    }
    bar_findings(&mut study.md, &points, dt_c)?;
    bar_plot(&points, "V2: period error against time step", "Δt", |p| p.dt)
        .write(&study.out.join("bar_error_vs_dt.svg"))?;
    bar_plot(&points, "V2: period error against wall time", "wall time of the steps [s]", |p| p.wall_s)
        .write(&study.out.join("bar_error_vs_wall.svg"))?;
    writeln!(study.md, "\n![error vs dt](bar_error_vs_dt.svg) ![error vs wall](bar_error_vs_wall.svg)\n")?;
    Ok(())
}

/// Implicit MPM, then the UL-FEM reference, at multiples of Δt_c.
fn implicit_points(quick: bool, dt_c: f64) -> Vec<Point> {
    let multiples: &[f64] =
        if quick { &[1.0, 5.0, 10.0, 50.0, 100.0] } else { &[1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0] };
    let linear: fn(f64) -> DynRun = |dt| bar_implicit(dt, BasisKind::Linear);
    let schemes = [("implicit", linear), ("UL-FEM implicit", bar_fem_implicit)];
    let mut points = Vec::new();
    for (scheme, run_at) in schemes {
        for &k in multiples {
            let dt = k * dt_c;
            eprintln!("steps: V2 {scheme} dt = {dt}");
            let run = run_at(dt);
            let outcome = run.failure.clone().unwrap_or_else(|| "ran to the end".into());
            points.push(Point::new(scheme, dt, &run, None, outcome));
        }
    }
    points
}

/// Explicit MUSL at fractions of Δt_c, up to and past the limit.
fn explicit_points(quick: bool, dt_c: f64) -> Vec<Point> {
    let fractions: &[f64] =
        if quick { &[0.25, 0.5, 0.9, 1.5, 2.0] } else { &[0.1, 0.25, 0.5, 0.75, 0.9, 1.0, 1.2, 1.5, 1.7, 1.8, 2.0] };
    let mut points = Vec::new();
    for &f in fractions {
        let dt = f * dt_c;
        eprintln!("steps: V2 explicit dt = {dt}");
        let (run, leapfrog_growth) =
            bar_explicit(TimeStep::Fixed { dt, allow_above_critical: true }, BasisKind::Linear);
        // Stable: reached the end without growth of the leapfrog energy beyond 1 % (a
        // slowly growing instability may not reach NaN within 3 periods; the energy read at
        // one time level swings by ±ωΔt/2 without being unstable).
        let outcome = match &run.failure {
            Some(f) => format!("blow-up detected after {} steps: {f}", run.steps),
            None if leapfrog_growth > 0.01 => format!("energy grew by {:.1} % (unstable)", 100.0 * leapfrog_growth),
            None => "ran to the end".into(),
        };
        points.push(Point::new("explicit", dt, &run, Some(leapfrog_growth), outcome));
    }
    points
}

/// The largest step of `scheme` with a period error under 1 %.
fn largest_within_1pct<'a>(points: &'a [Point], scheme: &str) -> Option<&'a Point> {
    points.iter().filter(|p| p.scheme == scheme && p.period_error < 0.01).max_by(|a, b| a.dt.total_cmp(&b.dt))
}

/// The V2 findings: the explicit stability limit, the largest steps within 1 % and the
/// wall time each scheme needs for it.
fn bar_findings(md: &mut String, points: &[Point], dt_c: f64) -> Result<()> {
    let explicit = || points.iter().filter(|p| p.scheme == "explicit");
    let largest_explicit = explicit().filter(|p| p.stable()).map(|p| p.dt).fold(f64::NAN, f64::max);
    let first_unstable = explicit().filter(|p| !p.stable()).map(|p| p.dt).fold(f64::NAN, f64::min);
    let implicit_1pct = largest_within_1pct(points, "implicit");
    let fem_1pct = largest_within_1pct(points, "UL-FEM implicit");
    let explicit_1pct =
        explicit().filter(|p| p.stable() && p.period_error < 0.01).min_by(|a, b| a.wall_s.total_cmp(&b.wall_s));
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
    Ok(())
}

/// Period error of the stable runs against `x` (Δt or wall time), one series per scheme.
fn bar_plot(points: &[Point], title: &str, x_label: &str, x: fn(&Point) -> f64) -> Plot {
    let series = |scheme: &str| -> Vec<(f64, f64)> {
        points
            .iter()
            .filter(|p| p.scheme == scheme && p.stable() && p.period_error.is_finite() && p.period_error > 0.0)
            .map(|p| (x(p), p.period_error))
            .collect()
    };
    let mut plot = Plot { log_x: true, log_y: true, ..Plot::new(title, x_label, "|T/T_exact − 1|") };
    plot.series.push(Series::new("implicit trapezoidal", series("implicit")));
    plot.series.push(Series::new("UL-FEM trapezoidal", series("UL-FEM implicit")).dashed());
    plot.series.push(Series::new("explicit MUSL (stable runs)", series("explicit")).dashed());
    plot
}

/// Cells of the V1c column in the study.
fn column_cells(quick: bool) -> usize {
    if quick {
        16
    } else {
        32
    }
}

/// e_σ of the V1c column (V1 norm) at these points.
fn column_e_sigma(points: &PointStore<2>) -> f64 {
    let col = Column::V1C;
    column_errors(points, &col, 1, |y| col.hencky_displacement(y)).stress
}

/// V1c: implicit MPM and UL-FEM at several load steps, explicit MUSL with two dampings;
/// the table, the wall-time comparison and the plot.
fn column_study(quick: bool, study: &mut Study) -> Result<()> {
    let col = Column::V1C;
    let cells = column_cells(quick);
    let h = col.height / cells as f64;
    let model = || column_model::<2>(&col, h, cells, 2, BasisKind::Gimp, Kinematics::FiniteStrain);
    let fem_model = || column_fem_model::<2>(&col, h, cells, 2, Kinematics::FiniteStrain);
    writeln!(study.md, "## V1c column, quasi-static (large deformation)\n\n{cells} cells, GIMP, 2×2 points per cell, Hencky. Implicit: equal load steps, Newton to 1e-9. UL-FEM: the same implicit analysis on one bilinear element per cell with 2×2 Gauss points, the mesh moving with the body. Explicit: MUSL, Cfl 0.5, gravity applied at once, local damping α, run until the kinetic energy has decayed; e_σ (V1 norm) sampled along the run against the wall time of the steps so far.\n")?;
    writeln!(study.md, "| scheme | load steps / damping | steps | e_σ | wall [s] |\n|---|---:|---:|---:|---:|")?;
    let implicit_pts = column_implicit(study, "implicit", &model, &[1, 2, 5, 10, 20, 40, 80, 160])?;
    let fem_pts = column_implicit(study, "UL-FEM implicit", &fem_model, &[1, 5, 20, 80])?;
    let c = (col.young / col.density).sqrt();
    let t1 = 4.0 * col.height / c;
    let duration = if quick { 6.0 * t1 } else { 12.0 * t1 };
    let explicit_runs = [0.3, 0.6]
        .into_iter()
        .map(|damping| column_explicit(study, &model, damping, duration))
        .collect::<Result<Vec<_>>>()?;
    column_findings(&mut study.md, &implicit_pts, &explicit_runs)?;
    let mut plot = Plot {
        log_x: true,
        log_y: true,
        ..Plot::new("V1c column: stress error against wall time", "wall time of the steps [s]", "e_σ")
    };
    plot.series.push(Series::new("implicit (load steps 1…160)", implicit_pts.iter().map(|p| (p.0, p.1)).collect()));
    plot.series.push(Series::new("UL-FEM implicit (load steps 1…80)", fem_pts.iter().map(|p| (p.0, p.1)).collect()));
    for r in &explicit_runs {
        let curve = r.curve.iter().copied().filter(|p| p.0 > 0.0).collect();
        plot.series.push(Series::new(format!("explicit MUSL, damping {}", r.damping), curve).dashed());
    }
    plot.write(&study.out.join("column_error_vs_wall.svg"))?;
    writeln!(study.md, "![column](column_error_vs_wall.svg)\n")?;
    Ok(())
}

/// The column loaded implicitly in each number of load steps; returns (wall, e_σ, load
/// steps) of the runs that converged.
fn column_implicit(
    study: &mut Study,
    scheme: &str,
    model: &dyn Fn() -> Model<2>,
    load_steps: &[usize],
) -> Result<Vec<(f64, f64, usize)>> {
    let mut pts = Vec::new();
    for &steps in load_steps {
        eprintln!("steps: V1c {scheme}, {steps} load steps");
        let mut qs = QuasiStatic::new(model(), QuasiStaticSettings { load_steps: steps, ..Default::default() });
        let t = Instant::now();
        let mut failed = None;
        while !qs.is_finished() {
            if let Err(e) = qs.step() {
                failed = Some(e.to_string());
                break;
            }
        }
        let wall = t.elapsed().as_secs_f64();
        let e = column_e_sigma(qs.model().points());
        match failed {
            None => {
                writeln!(study.md, "| {scheme} | {steps} | {steps} | {e:.3e} | {wall:.4} |")?;
                let errors = [CsvCell::Float(e), CsvCell::Text("")];
                study.csv_row(["V1c", scheme], CsvCell::Int(steps as i64), steps, errors, wall, "ok")?;
                pts.push((wall, e, steps));
            }
            Some(f) => writeln!(study.md, "| {scheme} | {steps} | – | failed: {f} | {wall:.4} |")?,
        }
    }
    Ok(pts)
}

/// An explicit run of the column with local damping: e_σ sampled along it against the
/// wall time of the steps so far.
struct ExplicitColumn {
    damping: f64,
    curve: Vec<(f64, f64)>,
    e_final: f64,
    /// Wall time at which the run first came within 5 % of its final error; `None` when
    /// the run stopped early.
    reach: Option<f64>,
}

/// The column under gravity applied at once, explicit MUSL with `damping`, to `duration`.
fn column_explicit(
    study: &mut Study,
    model: &dyn Fn() -> Model<2>,
    damping: f64,
    duration: f64,
) -> Result<ExplicitColumn> {
    eprintln!("steps: V1c explicit, damping {damping}");
    // Pure FLIP, as docs/verification.md's step comparison was measured.
    let settings = ExplicitSettings { damping, flip: 1.0, ..ExplicitSettings::new(duration) };
    let mut curve = Vec::new();
    let mut wall = 0.0;
    let mut last_wall = Instant::now();
    let mut k = 0usize;
    let (run, last) = run_analysis(explicit(model(), settings), |_, m| {
        wall += last_wall.elapsed().as_secs_f64();
        k += 1;
        if k.is_multiple_of(20) {
            curve.push((wall, column_e_sigma(m.points())));
        }
        last_wall = Instant::now();
    });
    let e_final = column_e_sigma(last.points());
    let outcome = run.failure.clone().unwrap_or_else(|| "ok".into());
    writeln!(study.md, "| explicit | α = {damping} | {} | {e_final:.3e} | {:.4} |", run.steps, run.wall_s)?;
    let errors = [CsvCell::Float(e_final), CsvCell::Text("")];
    let scheme = format!("explicit damping {damping}");
    study.csv_row(["V1c", &scheme], CsvCell::Float(damping), run.steps, errors, run.wall_s, &outcome)?;
    let reach = if run.failure.is_none() {
        Some(curve.iter().find(|(_, e)| *e <= 1.05 * e_final).map(|p| p.0).unwrap_or(run.wall_s))
    } else {
        writeln!(study.md, "\nexplicit α = {damping} stopped: {outcome}\n")?;
        None
    };
    Ok(ExplicitColumn { damping, curve, e_final, reach })
}

/// How much less wall time implicit needs to reach the error the best explicit run
/// settles to.
fn column_findings(
    md: &mut String,
    implicit_pts: &[(f64, f64, usize)],
    explicit_runs: &[ExplicitColumn],
) -> Result<()> {
    // The explicit run that settles lowest; the first on a tie.
    let mut best: Option<(f64, f64, f64)> = None; // (final e, wall to reach it, damping)
    for r in explicit_runs {
        if let Some(reach) = r.reach {
            if best.is_none_or(|b| r.e_final < b.0) {
                best = Some((r.e_final, reach, r.damping));
            }
        }
    }
    let Some((e_x, w_x, damping)) = best else { return Ok(()) };
    match implicit_pts.iter().filter(|p| p.1 <= e_x).min_by(|a, b| a.0.total_cmp(&b.0)) {
        Some(&(w_i, e_i, steps)) => writeln!(md, "\nExplicit (α = {damping}) settles to e_σ = {e_x:.3e} after {w_x:.3} s of steps; implicit reaches e_σ = {e_i:.3e} ≤ that with {steps} load steps in {w_i:.4} s: **{:.0}× less wall time**.\n", w_x / w_i)?,
        None => writeln!(md, "\nNo implicit run reached the explicit error {e_x:.3e}.\n")?,
    }
    Ok(())
}

/// One V4c run of the study: the scheme, its Δt or CFL safety, and the run.
struct RunoutPoint {
    scheme: &'static str,
    setting: f64,
    run: Runout,
    /// Max over the columns of cells of |profile − reference profile|, in cells.
    error: f64,
}

/// V4c: the slope run-out by implicit trapezoidal Newmark at Δt from 0.01 to 0.1 s and by
/// explicit MUSL at CFL safety 0.25 to 0.9, each final profile against an implicit run at
/// Δt = 0.0025 s; the table, the finding at equal accuracy and the plot.
fn runout_study(quick: bool, study: &mut Study) -> Result<()> {
    let cells = if quick { 5 } else { 10 };
    let (model, h) = slope::runout_model(cells)?;
    let reference_dt = 0.0025;
    writeln!(study.md, "## V4c slope run-out (large deformation)\n\nThe verify report's V4c slope (γH/c_u = 8, released under full gravity, {} s), {cells} cells per H, GIMP, 2×2 points per cell, finite strain. Implicit: trapezoidal Newmark, lumped mass, fixed Δt. Explicit: MUSL, FLIP, CFL steps. Error: the largest difference of the final profile (highest point per column of cells) from that of an implicit run at Δt = {reference_dt} s, in cells; the two schemes' own limits differ by a few hundredths of a cell (verify's V4c row), so errors below that compare the schemes, not the steps. Wall time: the whole run, set-up included.\n", slope::DURATION)?;
    eprintln!("steps: V4c reference, implicit Δt = {reference_dt}");
    let implicit = |dt: f64| {
        let settings = DynamicSettings::trapezoidal(dt, slope::DURATION);
        slope::run_out(|| Ok(Analysis::Dynamic(Dynamic::new(model(), settings)?)))
    };
    let reference = implicit(reference_dt)?.profile;
    let error = |run: &Runout| run.profile.iter().zip(&reference).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / h;
    let mut points = Vec::new();
    for dt in [0.01, 0.02, 0.05, 0.1] {
        eprintln!("steps: V4c implicit Δt = {dt}");
        let run = implicit(dt)?;
        points.push(RunoutPoint { scheme: "implicit", setting: dt, error: error(&run), run });
    }
    for safety in [0.25, 0.5, 0.9] {
        eprintln!("steps: V4c explicit CFL safety {safety}");
        let settings = ExplicitSettings {
            time_step: TimeStep::Cfl { safety },
            flip: 1.0,
            ..ExplicitSettings::new(slope::DURATION)
        };
        let run = slope::run_out(|| Ok(Analysis::Explicit(Explicit::new(model(), settings)?)))?;
        points.push(RunoutPoint { scheme: "explicit", setting: safety, error: error(&run), run });
    }
    runout_table(study, &points)?;
    runout_findings(&mut study.md, &points)?;
    let mut plot = Plot {
        log_x: true,
        ..Plot::new("V4c run-out: profile error against wall time", "wall time [s]", "max profile error [cells]")
    };
    for scheme in ["implicit", "explicit"] {
        let curve = points.iter().filter(|p| p.scheme == scheme).map(|p| (p.run.wall_s, p.error)).collect();
        let series = Series::new(
            format!("{scheme} ({})", if scheme == "implicit" { "Δt 0.01…0.1 s" } else { "CFL 0.25…0.9" }),
            curve,
        );
        plot.series.push(if scheme == "explicit" { series.dashed() } else { series });
    }
    plot.write(&study.out.join("runout_error_vs_wall.svg"))?;
    writeln!(study.md, "![run-out](runout_error_vs_wall.svg)\n")?;
    Ok(())
}

/// The V4c table and its csv rows.
fn runout_table(study: &mut Study, points: &[RunoutPoint]) -> Result<()> {
    writeln!(study.md, "| scheme | Δt [s] or CFL safety | steps | Δt range [s] | Newton its | profile error [cells] | wall [s] |\n|---|---:|---:|---:|---:|---:|---:|")?;
    for p in points {
        let r = &p.run;
        let its = if p.scheme == "implicit" { r.iterations.to_string() } else { "–".into() };
        writeln!(
            study.md,
            "| {} | {} | {} | {:.2e}–{:.2e} | {its} | {:.3} | {:.2} |",
            p.scheme, p.setting, r.steps, r.dt.0, r.dt.1, p.error, r.wall_s
        )?;
        let errors = [CsvCell::Float(p.error), CsvCell::Text("")];
        study.csv_row(["V4c", p.scheme], CsvCell::Float(p.setting), r.steps, errors, r.wall_s, "ran to the end")?;
    }
    writeln!(study.md)?;
    Ok(())
}

/// At the explicit run's accuracy (CFL 0.5, the verify setting), the cheapest implicit run
/// at least as accurate, and the ratio of their wall times.
fn runout_findings(md: &mut String, points: &[RunoutPoint]) -> Result<()> {
    let Some(ex) = points.iter().find(|p| p.scheme == "explicit" && p.setting == 0.5) else { return Ok(()) };
    let im = points
        .iter()
        .filter(|p| p.scheme == "implicit" && p.error <= ex.error)
        .min_by(|a, b| a.run.wall_s.total_cmp(&b.run.wall_s));
    match im {
        Some(im) => writeln!(md, "- At the explicit run's accuracy (CFL 0.5: {:.3} cells, {} steps, {:.2} s), the cheapest implicit run as accurate is Δt = {} s: {:.3} cells, {} steps, {:.2} s — explicit/implicit wall time {:.2}.\n", ex.error, ex.run.steps, ex.run.wall_s, im.setting, im.error, im.run.steps, im.run.wall_s, ex.run.wall_s / im.run.wall_s)?,
        None => writeln!(md, "- No implicit run tried is as accurate as the explicit run at CFL 0.5 ({:.3} cells, {:.2} s).\n", ex.error, ex.run.wall_s)?,
    }
    Ok(())
}
