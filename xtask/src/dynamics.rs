//! Dynamic verification (docs/verification.md §V2, §V5 and the column under suddenly applied
//! gravity) and the drivers shared with `cargo xtask steps`: run an implicit or explicit
//! analysis to its end, sampling the histories after every step and timing the steps
//! alone (sampling costs the same per step for both schemes, so it is left out).

use crate::report::{Report, Row};
use anyhow::Result;
use loam::analysis::Analysis;
use loam::explicit::{Explicit, ExplicitSettings, LeapfrogEnergy, TimeStep};
use loam::format::output::plot::{Plot, Series};
use loam::grid::BasisKind;
use loam::implicit::{Dynamic, DynamicSettings, Kinematics};
use loam::model::Model;
use loam_verification::bar::bounds as bar_bounds;
use loam_verification::column::bounds::{SUDDEN_GRAVITY_AMPLIFICATION, SUDDEN_GRAVITY_E_SIGMA};
use loam_verification::disks::bounds as disk_bounds;
use loam_verification::{
    column_errors, column_model, disks_model, BarErrors, Bound, Column, ColumnErrors, DynamicRecord, VibratingBar,
};
use std::fmt::Write as _;
use std::time::{Duration, Instant};

/// A finished (or stopped) dynamic run.
pub struct DynRun {
    pub record: DynamicRecord,
    pub steps: usize,
    /// Wall time of the steps alone.
    pub wall_s: f64,
    pub max_iterations: usize,
    /// Why the run stopped early, if it did (e.g. explicit blow-up).
    pub failure: Option<String>,
}

/// Run an analysis to its end, or until it reports a failure (e.g. an explicit blow-up);
/// `sample` is called after every step.
pub fn run_analysis<const D: usize>(mut a: Analysis<D>, mut sample: impl FnMut(f64, &Model<D>)) -> (DynRun, Model<D>) {
    let mut record = DynamicRecord::default();
    record.push(0.0, a.model());
    let (mut wall, mut steps, mut max_it, mut failure) = (Duration::ZERO, 0, 0, None);
    while !a.is_finished() {
        let t = Instant::now();
        match a.step() {
            Ok(r) => {
                wall += t.elapsed();
                steps += 1;
                max_it = max_it.max(r.iterations);
                record.push(r.time, a.model());
                sample(r.time, a.model());
            }
            Err(e) => {
                failure = Some(e.to_string());
                break;
            }
        }
    }
    let run = DynRun { record, steps, wall_s: wall.as_secs_f64(), max_iterations: max_it, failure };
    (run, a.into_model())
}

/// An implicit dynamic analysis of `model`.
pub fn implicit<const D: usize>(model: Model<D>, settings: DynamicSettings) -> Analysis<D> {
    Analysis::Dynamic(Dynamic::new(model, settings).expect("valid dynamic settings"))
}

/// An explicit analysis of `model`.
pub fn explicit<const D: usize>(model: Model<D>, settings: ExplicitSettings) -> Analysis<D> {
    Analysis::Explicit(Explicit::new(model, settings).expect("valid explicit settings"))
}

fn bar_model(basis: BasisKind) -> Model<2> {
    VibratingBar::REFERENCE.model(2, basis, Kinematics::FiniteStrain)
}

/// V2 on the given discretisation of the bar, trapezoidal with lumped mass at Δt = `dt`.
fn bar_trapezoidal(model: Model<2>, dt: f64) -> DynRun {
    let settings = DynamicSettings::trapezoidal(dt, 3.0 * VibratingBar::REFERENCE.period());
    run_analysis(implicit(model, settings), |_, _| {}).0
}

/// V2 implicit at Δt = `dt` (trapezoidal, lumped mass).
pub fn bar_implicit(dt: f64, basis: BasisKind) -> DynRun {
    bar_trapezoidal(bar_model(basis), dt)
}

/// V2 with the updated Lagrangian FEM reference at Δt = `dt` (trapezoidal, lumped mass).
pub fn bar_fem_implicit(dt: f64) -> DynRun {
    bar_trapezoidal(VibratingBar::REFERENCE.fem_model(2, Kinematics::FiniteStrain), dt)
}

/// V2 explicit (MUSL, pure FLIP) with the given time step rule, and the largest growth of
/// its leapfrog energy (`LeapfrogEnergy`) relative to the start.
pub fn bar_explicit(time_step: TimeStep, basis: BasisKind) -> (DynRun, f64) {
    let bar = VibratingBar::REFERENCE;
    let settings = ExplicitSettings { time_step, flip: 1.0, ..ExplicitSettings::new(3.0 * bar.period()) };
    let model = bar_model(basis);
    let mut leapfrog = LeapfrogEnergy::new(settings.scheme, &model);
    let e0 = leapfrog.advance(&model);
    let mut growth = 0.0f64;
    let run = run_analysis(explicit(model, settings), |_, m| growth = growth.max((leapfrog.advance(m) - e0) / e0)).0;
    (run, growth)
}

/// The dynamic sections of the report: V2, V5 and the column under sudden gravity.
pub fn verify(quick: bool, report: &mut Report) -> Result<()> {
    bar_section(report)?;
    disks_section(report)?;
    sudden_gravity_section(quick, report)
}

/// An implicit scheme of the V2 table: how it runs, the period it should show and its
/// bounds.
struct ImplicitBar {
    /// The scheme in the table.
    label: &'static str,
    /// The scheme in the log and the bounds table ("{case} dt=…").
    case: &'static str,
    run: fn(f64) -> DynRun,
    /// The period the scheme should produce at Δt, and the mark of its table cell.
    reference: fn(&VibratingBar, f64) -> f64,
    mark: &'static str,
    period_quantity: &'static str,
    period_bound: Bound,
    /// Checked at `ENERGY_DRIFT_TIME_STEP` only.
    drift_bound: Option<Bound>,
}

/// Implicit MPM against the trapezoidal elongation of T, and the UL-FEM reference against
/// its lumped-mass discrete period.
const IMPLICIT_BARS: [ImplicitBar; 2] = [
    ImplicitBar {
        label: "implicit trapezoidal",
        case: "V2 implicit",
        run: |dt| bar_implicit(dt, BasisKind::Linear),
        reference: |bar, dt| bar.period() * bar.trapezoidal_period_factor(dt),
        mark: "",
        period_quantity: "period_error_vs_trapezoidal",
        period_bound: bar_bounds::IMPLICIT_PERIOD_ERROR,
        drift_bound: Some(bar_bounds::IMPLICIT_ENERGY_DRIFT),
    },
    ImplicitBar {
        label: "UL-FEM trapezoidal",
        case: "V2 UL-FEM",
        run: bar_fem_implicit,
        reference: |bar, dt| bar.lumped_fem_period(dt),
        mark: " ᶠ",
        period_quantity: "period_error_vs_discrete_trapezoidal",
        period_bound: bar_bounds::FEM_PERIOD_ERROR,
        drift_bound: None,
    },
];

/// One row of the V2 table: what it shows besides the run's own figures.
struct BarRow<'a> {
    scheme: &'a str,
    dt: String,
    /// The period the scheme should produce, and a mark after it.
    reference: f64,
    mark: &'a str,
    /// The most Newton iterations, or "–" for explicit runs.
    its: String,
}

impl BarRow<'_> {
    /// Write the row; returns the run's errors and its period error against `reference`.
    fn write(&self, md: &mut String, run: &DynRun) -> Result<(BarErrors, f64)> {
        let e = VibratingBar::REFERENCE.errors(&run.record);
        let err = e.period / self.reference - 1.0;
        writeln!(
            md,
            "| {} | {} | {} | {:.5} | {:.5}{} | {err:+.2e} | {:.2e} | {:.2e} | {} | {:.3} |",
            self.scheme,
            self.dt,
            run.steps,
            e.period,
            self.reference,
            self.mark,
            e.vcm_error,
            e.energy_drift,
            self.its,
            run.wall_s
        )?;
        Ok((e, err))
    }
}

/// V2: the implicit schemes at three steps, explicit at 0.9 Δt_c and above the limit.
fn bar_section(report: &mut Report) -> Result<()> {
    let bar = VibratingBar::REFERENCE;
    writeln!(report.md, "## V2 vibrating bar\n\nL = 25, E = 100, ρ = 1, v₀ = 0.1, h = 1, 2×2 points per cell, linear basis, Hencky (ν = 0), t_end = 3T = 30; explicit critical step h/c = {:.3}. Period from the zero crossings of v_cm; the implicit reference is T·ωΔt/(2 arctan(ωΔt/2)) (trapezoidal elongation), the explicit one T = 10. Wall time: the steps alone.\n", bar.critical_time_step())?;
    report.mark_table("V2")?;
    writeln!(report.md, "| scheme | Δt | steps | period | reference | period error | max v_cm error | energy drift | max Newton its | wall [s] |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    for scheme in &IMPLICIT_BARS {
        implicit_bar_rows(report, scheme)?;
    }
    explicit_bar_row(report)?;
    explicit_blow_up(report)
}

/// One implicit scheme at Δt = 0.1, 0.5 and 1.
fn implicit_bar_rows(report: &mut Report, scheme: &ImplicitBar) -> Result<()> {
    for dt in [0.1, 0.5, 1.0] {
        eprintln!("verify: {} dt = {dt}", scheme.case);
        let run = (scheme.run)(dt);
        let row = BarRow {
            scheme: scheme.label,
            dt: dt.to_string(),
            reference: (scheme.reference)(&VibratingBar::REFERENCE, dt),
            mark: scheme.mark,
            its: run.max_iterations.to_string(),
        };
        let (e, err) = row.write(&mut report.md, &run)?;
        let case = format!("{} dt={dt}", scheme.case);
        report.rows.push(Row::checked(&case, scheme.period_quantity, err.abs(), scheme.period_bound));
        let drift_bound = scheme.drift_bound.filter(|_| dt == bar_bounds::ENERGY_DRIFT_TIME_STEP);
        push_drift_and_wall(report, &case, &e, &run, drift_bound);
    }
    Ok(())
}

/// The energy drift (checked where `bound` is given) and the wall time of a V2 run.
fn push_drift_and_wall(report: &mut Report, case: &str, e: &BarErrors, run: &DynRun, bound: Option<Bound>) {
    report.rows.push(Row::new(case, "energy_drift", e.energy_drift, bound));
    report.rows.push(Row::info(case, "wall_time_s", run.wall_s));
}

/// Explicit MUSL at 0.9 of the critical step, against the exact period.
fn explicit_bar_row(report: &mut Report) -> Result<()> {
    eprintln!("verify: V2 explicit at 0.9 of the critical step");
    let (run, _) = bar_explicit(TimeStep::Cfl { safety: 0.9 }, BasisKind::Linear);
    let row = BarRow {
        scheme: "explicit MUSL",
        dt: "0.9 Δt_c".into(),
        reference: VibratingBar::REFERENCE.period(),
        mark: "",
        its: "–".into(),
    };
    let (e, err) = row.write(&mut report.md, &run)?;
    let case = "V2 explicit 0.9 dt_c";
    let stable = run.failure.is_none() as u8 as f64;
    report.rows.push(Row::checked(case, "stable (1 = ran to the end)", stable, bar_bounds::EXPLICIT_STABLE));
    report.rows.push(Row::checked(case, "period_error", err.abs(), bar_bounds::EXPLICIT_PERIOD_ERROR));
    push_drift_and_wall(report, case, &e, &run, None);
    Ok(())
}

/// Explicit above the limit, allowed on purpose: the blow-up must be detected.
fn explicit_blow_up(report: &mut Report) -> Result<()> {
    // MUSL with 2 points per cell is stable somewhat past h/c (its grid–point–grid transfer
    // filters the highest grid mode; about √3 h/c by a modal analysis), so 2 h/c is the
    // step that must be caught.
    let dt_over = 2.0 * VibratingBar::REFERENCE.critical_time_step();
    let (run, _) = bar_explicit(TimeStep::Fixed { dt: dt_over, allow_above_critical: true }, BasisKind::Linear);
    let detected = run.failure.is_some();
    let md = &mut report.md;
    writeln!(md, "\nᶠ UL-FEM reference: lumped-mass linear elements (one per cell, 2×2 Gauss points), whose first mode has ω_h = (2c/h) sin(β₁h/2), times the trapezoidal elongation at ω_hΔt.")?;
    writeln!(
        md,
        "\nExplicit above the limit (Δt = {dt_over:.3} = 2 Δt_c, allowed on purpose): {}\n",
        match &run.failure {
            Some(f) => format!("blow-up detected after {} steps: {f}", run.steps),
            None => "NOT detected — ran to the end".into(),
        }
    )?;
    let quantity = "blow-up detected (1 = yes)";
    report.rows.push(Row::checked(
        "V2 explicit 2 dt_c",
        quantity,
        detected as u8 as f64,
        bar_bounds::EXPLICIT_BLOW_UP_DETECTED,
    ));
    Ok(())
}

/// V5's implicit step, at which the bounds are checked; twice it is reported.
const DISKS_IMPLICIT_DT: f64 = 0.005;

/// V5: the colliding disks, explicit and implicit, with their energy histories.
fn disks_section(report: &mut Report) -> Result<()> {
    writeln!(report.md, "## V5 colliding disks\n\nSulsky et al. (1994): 20×20 cells, disks r = 0.2 filled at 2×2 points per cell (the sampled disks' kinetic energy is the reference E₀, exact disks 2.513), E = 1000, ν = 0.3, ρ = 1000, ±(0.1, 0.1), to t = 3. Energy = kinetic + stored (Hencky).\n")?;
    report.mark_table("V5")?;
    writeln!(
        report.md,
        "| scheme | steps | E₀ | E(3) | loss | max growth | wall [s] |\n|---|---:|---:|---:|---:|---:|---:|"
    )?;
    let (explicit, leapfrog_energy) = disks_explicit();
    let implicit = disks_implicit(DISKS_IMPLICIT_DT);
    let implicit_energy: Vec<f64> = (0..implicit.record.time.len()).map(|k| implicit.record.energy(k)).collect();
    disks_coarse_row(report)?;
    let runs = [
        ("explicit MUSL, Cfl 0.5 (leapfrog energy)", &explicit, leapfrog_energy),
        ("implicit trapezoidal, Δt = 0.005", &implicit, implicit_energy),
    ];
    let mut plot = Plot::new("V5 colliding disks: energy histories", "time", "energy");
    for (name, run, energy) in &runs {
        eprintln!("verify: V5 {name}");
        disks_row(report, name, run, energy)?;
        let r = &run.record;
        let kinetic = r.time.iter().copied().zip(r.kinetic.iter().copied()).collect();
        plot.series.push(Series::new(format!("{name}: kinetic"), kinetic).dashed());
        let total = r.time.iter().copied().zip(energy.iter().copied()).collect();
        plot.series.push(Series::new(format!("{name}: total"), total));
    }
    plot.write(&report.out.join("disks_energy.svg"))?;
    writeln!(report.md, "\n![V5 energies](disks_energy.svg)\n")?;
    Ok(())
}

/// V5 explicit (MUSL, pure FLIP, Cfl 0.5) and its energy history read as leapfrog conserves it.
fn disks_explicit() -> (DynRun, Vec<f64>) {
    // Explicit energy is read as leapfrog conserves it (loam::explicit::LeapfrogEnergy):
    // W + ½|v|² at one time level swings by ±ωΔt/2 in a leapfrog scheme without any real
    // gain or loss. The implicit trapezoidal rule has all quantities at one time level.
    let settings = ExplicitSettings { flip: 1.0, ..ExplicitSettings::new(3.0) };
    let disks = disks_model(Kinematics::FiniteStrain);
    let mut leapfrog = LeapfrogEnergy::new(settings.scheme, &disks);
    let mut energy = vec![leapfrog.advance(&disks)];
    let run = run_analysis(explicit(disks, settings), |_, m| energy.push(leapfrog.advance(m))).0;
    (run, energy)
}

/// V5 implicit (trapezoidal) at Δt = `dt`.
fn disks_implicit(dt: f64) -> DynRun {
    run_analysis(implicit(disks_model(Kinematics::FiniteStrain), DynamicSettings::trapezoidal(dt, 3.0)), |_, _| {}).0
}

/// The unbounded row: implicit at twice the checked step.
fn disks_coarse_row(report: &mut Report) -> Result<()> {
    // The implicit loss falls with Δt (6 % at 0.02, 5.1 % at 0.01, 4.1 % at 0.005 when this
    // was written): the point velocity is updated by the nodal accelerations while the
    // positions follow the projected grid motion, so internal vibrations are filtered a
    // little every step. The bound is checked at Δt = 0.005; Δt = 0.01 is reported.
    let dt = 2.0 * DISKS_IMPLICIT_DT;
    let coarse = disks_implicit(dt);
    let n = coarse.record.time.len();
    let (first, last) = (coarse.record.energy(0), coarse.record.energy(n - 1));
    let loss = (first - last) / first;
    writeln!(
        report.md,
        "| implicit trapezoidal, Δt = {dt} (not bounded) | {} | {first:.4} | {last:.4} | {loss:.2e} | – | {:.3} |",
        coarse.steps, coarse.wall_s
    )?;
    report.rows.push(Row::info(format!("V5 implicit dt={dt}"), "energy_loss_at_t3", loss));
    Ok(())
}

/// A bounded V5 row: the energy lost by t = 3 and its largest growth over the run.
fn disks_row(report: &mut Report, name: &str, run: &DynRun, energy: &[f64]) -> Result<()> {
    let n = energy.len();
    let e0 = energy[0];
    let loss = (e0 - energy[n - 1]) / e0;
    let growth = energy.iter().map(|e| (e - e0) / e0).fold(f64::NEG_INFINITY, f64::max);
    writeln!(
        report.md,
        "| {name} | {} | {e0:.4} | {:.4} | {loss:.2e} | {growth:.2e} | {:.3} |",
        run.steps,
        energy[n - 1],
        run.wall_s
    )?;
    if let Some(f) = &run.failure {
        writeln!(report.md, "\n{name} stopped: {f}\n")?;
    }
    let case = format!("V5 {name}");
    let ran = run.failure.is_none() as u8 as f64;
    report.rows.push(Row::checked(&case, "ran to t=3 (1 = yes)", ran, disk_bounds::RAN_TO_END));
    report.rows.push(Row::checked(&case, "energy_loss_at_t3", loss, disk_bounds::ENERGY_LOSS));
    report.rows.push(Row::checked(&case, "max_energy_growth", growth, disk_bounds::ENERGY_GROWTH));
    Ok(())
}

/// The V1a column under suddenly applied gravity, time-averaged and at its deepest.
struct SuddenGravity {
    run: DynRun,
    /// Errors of the time-averaged stress against the static closed form.
    errors: ColumnErrors,
    /// Mean and largest settlement of the top point over the static one.
    mean_ratio: f64,
    amplification: f64,
}

/// The column under sudden gravity: it oscillates about the static answer.
fn sudden_gravity(col: &Column, cells: usize, dt: f64, duration: f64) -> SuddenGravity {
    let model = column_model::<2>(col, col.height / cells as f64, cells, 2, BasisKind::Gimp, Kinematics::FiniteStrain);
    let top = (0..model.points().len())
        .max_by(|&a, &b| model.points().position0()[a][1].total_cmp(&model.points().position0()[b][1]))
        .unwrap();
    let mut mean_stress = vec![0.0; model.points().len()];
    let (mut n_samples, mut max_settlement, mut mean_top) = (0usize, 0.0f64, 0.0);
    let (run, mut last) = run_analysis(implicit(model, DynamicSettings::trapezoidal(dt, duration)), |_, m| {
        n_samples += 1;
        for (s, sig) in mean_stress.iter_mut().zip(m.points().stress()) {
            *s += sig[(1, 1)];
        }
        let u = m.points().position()[top][1] - m.points().position0()[top][1];
        max_settlement = max_settlement.max(-u);
        mean_top += u;
    });
    for (s, m) in last.points_mut().stress.iter_mut().zip(&mean_stress) {
        s[(1, 1)] = m / n_samples as f64;
    }
    mean_top /= n_samples as f64;
    let y_top = last.points().position0()[top][1];
    let errors = column_errors(last.points(), col, 1, |y| col.hencky_displacement(y));
    let static_top = -col.hencky_displacement(y_top);
    SuddenGravity { run, errors, mean_ratio: -mean_top / static_top, amplification: max_settlement / static_top }
}

/// The V1a column under suddenly applied gravity: its section and bounds.
fn sudden_gravity_section(quick: bool, report: &mut Report) -> Result<()> {
    let col = Column::V1A;
    let cells = if quick { 16 } else { 32 };
    let c = (col.young / col.density).sqrt();
    let period = 4.0 * col.height / c;
    let dt = period / 40.0;
    eprintln!("verify: V1a column under sudden gravity, {cells} cells");
    let SuddenGravity { run, errors, mean_ratio, amplification } = sudden_gravity(&col, cells, dt, 4.0 * period);
    let md = &mut report.md;
    writeln!(md, "## V1a column under suddenly applied gravity (implicit trapezoidal)\n\n{cells} cells, GIMP, Δt = T₁/40 = {dt:.4} s (T₁ = 4H/c = {period:.4} s), 4 periods, {} steps, {:.3} s. A load applied at once drives an undamped oscillation about the static state: the time-averaged stress is compared with the static closed form (V1 norm e_σ), the largest settlement of the top point with twice the static one (dynamic amplification factor 2 of a step load).\n", run.steps, run.wall_s)?;
    writeln!(md, "| e_σ of the time-averaged stress | mean top settlement / static | max top settlement / static |\n|---:|---:|---:|\n| {:.3e} | {mean_ratio:.4} | {amplification:.4} |\n", errors.stress)?;
    let case = "V1a sudden gravity";
    report.rows.push(Row::checked(case, "e_sigma_time_averaged", errors.stress, SUDDEN_GRAVITY_E_SIGMA));
    report.rows.push(Row::info(case, "mean_settlement_ratio", mean_ratio));
    let off = (amplification - 2.0).abs();
    report.rows.push(Row::checked(case, "|amplification - 2|", off, SUDDEN_GRAVITY_AMPLIFICATION));
    if let Some(f) = run.failure {
        anyhow::bail!("the column under sudden gravity stopped: {f}");
    }
    Ok(())
}
