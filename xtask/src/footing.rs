//! V3 strip footing (docs/verification.md §V3): q_u, read at a settlement of 0.1 B, against
//! Prandtl's (2 + π) c_u for von Mises and c N_c for associated Mohr–Coulomb, with the mesh
//! sequence, plain, with B-bar and with the assumed strain (β = 0.1). The 5 % bound is
//! checked for every law with the assumed strain on the finest mesh (16 cells per b, full
//! sweep), and every curve's rise to its plateau is checked for drops. The load–settlement
//! curves go to `footing_curves.csv` and `footing_curves.svg`. Then the circular footing,
//! axisymmetric, rough and smooth, on Tresca soil.

use crate::report::{Report, Row};
use crate::soil::{self, COHESION, POISSON, YOUNG};
use anyhow::{Context, Result};
use loam::constitutive::{ConeFit, ConstitutiveLaw, DruckerPrager, Elastic, MohrCoulomb};
use loam::format::output::plot::{Plot, Series};
use loam::format::output::{CsvCell, CsvWriter};
use loam::implicit::{AntiLocking, QuasiStatic, QuasiStaticSettings, StepReport};
use loam_verification::footing::bounds::{
    CIRCULAR_Q_U, FINITE_STRAIN_Q, LARGEST_DROP, NEWTON_CORRECTIONS, Q_U, RUNS_STOPPED,
};
use loam_verification::{circular_footing_model, finite_strain_footing_model, footing_model, prandtl_nc};
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Settlement (in b) and load steps: 0.001 b per step to 0.2 b, the 0.1 B (B = 2b) at which
/// docs/verification.md §V3 reads q_u. The limit load is reached between 0.005 b (undrained) and
/// ~0.03 b (φ = 30°); small steps keep the first plastic steps from overshooting it.
const SETTLEMENT: f64 = 0.2;
const LOAD_STEPS: usize = 200;
/// The assumed strain's stabilization β (the usual hourglass weight, docs/theory.md §13).
const STABILIZATION: f64 = 0.1;
const ASSUMED: AntiLocking = AntiLocking::AssumedStrain { stabilization: STABILIZATION };

/// One footing run: the load–settlement curve and what Newton needed.
struct FootingRun {
    /// (settlement / b, q / c) after each converged load step, from (0, 0).
    curve: Vec<(f64, f64)>,
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

impl FootingRun {
    /// q_u / c: the footing pressure at the settlement of 0.1 B; NaN when the run stopped
    /// short of it.
    fn q_u(&self) -> f64 {
        if self.failure.is_some() {
            return f64::NAN;
        }
        self.curve.last().map_or(f64::NAN, |&(_, q)| q)
    }

    /// q / c at the load step nearest to `settlement` (in b): the curve holds step k at
    /// index k. NaN when the run stopped before it.
    fn q_at(&self, settlement: f64) -> f64 {
        let step = (settlement / SETTLEMENT * LOAD_STEPS as f64).round() as usize;
        self.curve.get(step).map_or(f64::NAN, |&(_, q)| q)
    }

    /// The largest fall of the curve from one step to the next (0 when it never falls).
    fn largest_drop(&self) -> f64 {
        self.curve.windows(2).map(|w| w[0].1 - w[1].1).fold(0.0, f64::max)
    }

    /// Take in a converged load step; `tolerance` is Newton's residual tolerance.
    fn record(&mut self, r: StepReport, tolerance: f64) {
        self.curve.push((r.load_factor * SETTLEMENT, -r.reactions[0][1] / COHESION));
        self.cutbacks += r.cutbacks;
        let to_tolerance = r.hardest_abandoned
            + r.hardest_residuals.iter().position(|&x| x <= tolerance).unwrap_or(r.hardest_residuals.len());
        self.to_tolerance = self.to_tolerance.max(to_tolerance);
        if r.most_iterations() > self.max_iterations {
            self.max_iterations = r.most_iterations();
            self.worst = r.step;
            self.residuals = r.hardest_residuals;
        }
    }
}

fn run(law: &Arc<dyn ConstitutiveLaw>, cells: usize, anti_locking: AntiLocking) -> FootingRun {
    let model = footing_model(law.clone(), cells, 10, 5, SETTLEMENT, anti_locking);
    // The extrapolated start (docs/theory.md §6) halves the Newton iterations here.
    let mut qs = QuasiStatic::new(
        model,
        QuasiStaticSettings { load_steps: LOAD_STEPS, extrapolate: true, ..Default::default() },
    );
    let tolerance = qs.settings().newton.residual_tolerance;
    let t = Instant::now();
    let mut out = FootingRun {
        curve: vec![(0.0, 0.0)],
        max_iterations: 0,
        to_tolerance: 0,
        cutbacks: 0,
        wall_s: 0.0,
        failure: None,
        worst: 0,
        residuals: Vec::new(),
    };
    while !qs.is_finished() {
        match qs.step() {
            Ok(r) => out.record(r, tolerance),
            Err(e) => {
                out.failure = Some(e.to_string());
                break;
            }
        }
    }
    out.wall_s = t.elapsed().as_secs_f64();
    out
}

/// The observed order of convergence of q_u from three meshes each twice as fine as the
/// last: log₂ of the ratio of successive differences (NaN where it is undefined).
fn observed_order(coarse: f64, middle: f64, fine: f64) -> f64 {
    ((coarse - middle) / (middle - fine)).log2()
}

/// A law of the sweep: its name in the table, its legend label, and q_ref / c.
struct FootingLaw {
    name: String,
    label: String,
    law: Arc<dyn ConstitutiveLaw>,
    nc: f64,
}

/// Von Mises, von Mises with ν = 0.49, associated Mohr–Coulomb at φ = 0°…30° and
/// associated Drucker–Prager (plane-strain fit) at φ = 20°, 30°.
fn laws() -> Result<Vec<FootingLaw>> {
    let elastic = Elastic::new(YOUNG, POISSON)?;
    let law = |name: &str, label: &str, law, nc| FootingLaw { name: name.into(), label: label.into(), law, nc };
    let mut laws = vec![law("von Mises", "von Mises", soil::undrained(elastic, COHESION)?, prandtl_nc(0.0))];
    // Issue 5's locking case: nearly incompressible elasticity under the von Mises footing.
    let incompressible = Elastic::new(YOUNG, 0.49)?;
    laws.push(law("von Mises, ν = 0.49", "VM, ν = 0.49", soil::undrained(incompressible, COHESION)?, prandtl_nc(0.0)));
    for phi in [0.0, 10.0, 20.0, 30.0] {
        laws.push(law(
            &format!("Mohr–Coulomb φ = ψ = {phi}°"),
            &format!("MC φ = {phi}°"),
            Arc::new(MohrCoulomb::from_degrees(elastic, COHESION, phi, phi)?),
            prandtl_nc(phi),
        ));
    }
    // The smooth cone fitted to Mohr–Coulomb's plane-strain collapse: the same N_c.
    for phi in [20.0, 30.0] {
        laws.push(law(
            &format!("Drucker–Prager φ = ψ = {phi}°"),
            &format!("DP φ = {phi}°"),
            Arc::new(DruckerPrager::from_degrees(elastic, COHESION, phi, phi, ConeFit::PlaneStrain)?),
            prandtl_nc(phi),
        ));
    }
    Ok(laws)
}

/// The treatments in the table's order, each with its meshes (cells per b).
fn treatments(quick: bool) -> [(AntiLocking, &'static [usize]); 3] {
    let assumed_meshes: &[usize] = if quick { &[2, 4] } else { &[2, 4, 8, 16] };
    let bbar_meshes: &[usize] = if quick { &[2, 4] } else { &[2, 4, 8] };
    [(AntiLocking::None, &[2, 4]), (AntiLocking::BBar, bbar_meshes), (ASSUMED, assumed_meshes)]
}

/// How the report names a treatment.
fn treatment_name(anti_locking: AntiLocking) -> &'static str {
    if anti_locking == AntiLocking::None {
        "plain"
    } else {
        anti_locking.name()
    }
}

/// What the sweep gathers besides the table and the bounds: every curve, the plot of the
/// finest assumed-strain curves, and for each law the assumed strain's verdict and
/// hardest residuals.
struct Sweep {
    csv: CsvWriter,
    plot: Plot,
    verdicts: Vec<String>,
    residuals: Vec<String>,
}

impl Sweep {
    fn new(out: &Path) -> Result<Self> {
        let csv = CsvWriter::create(
            out.join("footing_curves.csv"),
            &["law", "treatment", "cells_per_b", "settlement_over_b", "q_over_c"],
        )?;
        let plot =
            Plot::new("V3 strip footing: load–settlement, assumed strain, finest mesh", "settlement / B", "q / q_ref");
        Ok(Self { csv, plot, verdicts: Vec::new(), residuals: Vec::new() })
    }

    /// Write a run's curve to `footing_curves.csv`.
    fn curve(&mut self, law: &FootingLaw, treatment: &str, cells: usize, r: &FootingRun) -> Result<()> {
        for &(s, q) in &r.curve {
            self.csv.row_mixed(&[
                CsvCell::Text(&law.name),
                CsvCell::Text(treatment),
                CsvCell::Int(cells as i64),
                CsvCell::Float(s),
                CsvCell::Float(q),
            ])?;
        }
        Ok(())
    }

    /// The finest assumed-strain run of a law: its hardest residuals, and its curve on the plot.
    fn finest(&mut self, law: &FootingLaw, cells: usize, r: &FootingRun) {
        self.residuals.push(format!(
            "- {}, {}, {cells} cells per b, step {}: {}",
            law.name,
            treatment_name(ASSUMED),
            r.worst,
            r.residuals.iter().map(|x| format!("{x:.1e}")).collect::<Vec<_>>().join(" → ")
        ));
        self.plot.series.push(Series::new(
            format!("{}, {cells}/b", law.label),
            r.curve.iter().map(|&(s, q)| (s / 2.0, q / law.nc)).collect(),
        ));
    }

    /// Write the plot, and close the section with the verdicts and the residuals.
    fn finish(mut self, report: &mut Report) -> Result<()> {
        self.plot.series.push(Series::new("Prandtl", vec![(0.0, 1.0), (SETTLEMENT / 2.0, 1.0)]).dashed());
        self.plot.write(&report.out.join("footing_curves.svg"))?;
        let md = &mut report.md;
        writeln!(md, "\n![V3 load–settlement curves](footing_curves.svg)\n")?;
        writeln!(md, "\nWith the assumed strain on the finest mesh of this run:\n\n{}\n", self.verdicts.join("\n"))?;
        writeln!(
            md,
            "Relative residuals of the sub-step with the most Newton iterations, assumed strain, finest mesh:\n\n{}\n",
            self.residuals.join("\n")
        )?;
        Ok(())
    }
}

/// The V3 section: every law with every treatment on its meshes.
pub fn verify(quick: bool, report: &mut Report) -> Result<()> {
    let finest_assumed = treatments(quick)[2].1.last().unwrap();
    writeln!(report.md, "## V3 strip footing\n\nRigid rough footing, half-width b = 1 (B = 2b), pushed {SETTLEMENT} b = 0.1 B in {LOAD_STEPS} load steps (extrapolated start) into weightless soil; half model 10 b × 5 b, linear basis, 2×2 points per cell, small strain, geometrically linear (points held at their places, Prandtl's small-deformation setting), E = {YOUNG:e}, ν = {POISSON} (and 0.49 for the locking case), c = {COHESION}. q = footing reaction / b; q_u = q at the settlement of 0.1 B (docs/verification.md §V3), q(0.04 b) is shown beside it; reference (2 + π) c_u (von Mises, c_u = σ_y/√3) and c N_c (Mohr–Coulomb and Drucker–Prager fitted in plane strain, associated). Plain: every point's own strain (locks); B-bar: cell-averaged dilatation; assumed strain: the cell's average strain plus β = {STABILIZATION} times each point's deviatoric deviation (docs/theory.md §13). The bound |q_u/q_ref − 1| ≤ 5 % is checked for every law with the assumed strain on the finest mesh of the full sweep ({finest_assumed} cells per b); every curve is checked to rise to its plateau without a drop. Curves: footing_curves.csv, footing_curves.svg.\n")?;
    writeln!(report.md, "| law | treatment | cells per b | q(0.04 b)/c | q_u/c | reference | q_u/q_ref − 1 | largest drop / q_ref | max Newton its per sub-step | max corrections to 1e-9 | cut-backs | wall [s] |\n|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    let mut sweep = Sweep::new(&report.out)?;
    let laws = laws()?;
    // The circular footings first: the longest of them, left to the end, would run alone
    // there while the sweep's short runs share the cores.
    let (circular_runs, runs) = report.both(|| circular_runs(report), || sweep_runs(&laws, quick, report));
    let mut runs = runs.into_iter();
    for law in &laws {
        let (mut law_drop, mut stopped) = (0.0f64, 0usize);
        for (anti_locking, meshes) in treatments(quick) {
            let (drop, n_stopped) = treatment(quick, report, &mut sweep, law, (anti_locking, meshes), &mut runs)?;
            law_drop = law_drop.max(drop);
            stopped += n_stopped;
        }
        // Monotone to the plateau, and every run reaching 0.1 B (a run that stops short has
        // no q_u and hides the rest of its curve from the first check).
        let every = format!("V3 {}, every treatment and mesh", law.name);
        report.rows.push(Row::checked(&every, "largest_drop_over_q_ref", law_drop, LARGEST_DROP));
        report.rows.push(Row::checked(&every, "runs_stopped_before_0.1B", stopped as f64, RUNS_STOPPED));
    }
    sweep.finish(report)?;
    circular(report, circular_runs?)?;
    finite_strain(quick, report)
}

/// How far the finite-strain footing is pushed (in b) and in how many steps (extrapolated
/// start): its peak comes at about 0.006 b, and past it moving points make the load fall.
const FINITE_SETTLEMENT: f64 = 0.03;
const FINITE_STEPS: usize = 30;
/// The mesh whose F-bar peak is checked (cells per b; the full sweep's finest).
const FINITE_CHECKED_MESH: usize = 8;

/// The strip footing in finite strain (the points move): von Mises soil, linear basis,
/// plain and F-bar; the peak pressure against (2 + π) c_u, the bound on F-bar's at 8
/// cells per b.
fn finite_strain(quick: bool, report: &mut Report) -> Result<()> {
    let runs: &[(AntiLocking, usize)] = if quick {
        &[(AntiLocking::None, 4), (AntiLocking::FBar, 4)]
    } else {
        &[(AntiLocking::None, 4), (AntiLocking::FBar, 4), (AntiLocking::FBar, 8)]
    };
    let law = soil::undrained(Elastic::new(YOUNG, POISSON)?, COHESION)?;
    writeln!(report.md, "## V3 strip footing in finite strain\n\nThe V3 strip footing (von Mises, ν = {POISSON}) in finite strain: the points move, the linear basis, pushed {FINITE_SETTLEMENT} b in {FINITE_STEPS} steps (extrapolated start). Peak: the largest pressure, against (2 + π) c_u; end: the pressure where the run ended. Plain: every point's own deformation; F-bar: each point's scaled to its cell's volume change (docs/theory.md §13). Bound: F-bar's peak within 5 % at {FINITE_CHECKED_MESH} cells per b (full sweep).\n")?;
    report.mark_table("V3-finite")?;
    writeln!(report.md, "| treatment | cells per b | peak/q_ref − 1 | end/q_ref − 1 | settlement reached / b | Newton its | cut-backs | wall [s] |\n|---|---:|---:|---:|---:|---:|---:|---:|")?;
    for &(anti_locking, cells) in runs {
        let name = treatment_name(anti_locking);
        eprintln!("verify: V3 finite strain, {name}, {cells} cells per b");
        let t = Instant::now();
        let model = finite_strain_footing_model(law.clone(), cells, FINITE_SETTLEMENT, anti_locking);
        let settings = QuasiStaticSettings { load_steps: FINITE_STEPS, extrapolate: true, ..Default::default() };
        let mut qs = QuasiStatic::new(model, settings);
        let (mut peak, mut end, mut iterations, mut cutbacks) = (f64::NAN, f64::NAN, 0, 0);
        while !qs.is_finished() {
            let Ok(r) = qs.step() else { break };
            (iterations, cutbacks) = (iterations + r.iterations, cutbacks + r.cutbacks);
            end = -r.reactions[0][1] / (COHESION * prandtl_nc(0.0));
            peak = peak.max(end);
        }
        let reached = qs.load_factor() * FINITE_SETTLEMENT;
        let wall = t.elapsed().as_secs_f64();
        writeln!(
            report.md,
            "| {name} | {cells} | {:+.4} | {:+.4} | {reached:.4} | {iterations} | {cutbacks} | {wall:.2} |",
            peak - 1.0,
            end - 1.0
        )?;
        let case = format!("V3 finite strain {name} {cells} cells per b");
        if anti_locking == AntiLocking::FBar && cells == FINITE_CHECKED_MESH {
            report.rows.push(Row::checked(&case, "|peak/q_ref - 1|", (peak - 1.0).abs(), FINITE_STRAIN_Q));
        } else {
            report.rows.push(Row::info(&case, "peak/q_ref - 1", peak - 1.0));
        }
        report.rows.push(Row::info(&case, "settlement reached / b", reached));
    }
    writeln!(report.md)?;
    Ok(())
}

/// Load steps of the circular footing (its curve is flat soon after 0.01 R).
const CIRCULAR_STEPS: usize = 40;

/// The circular footing on Tresca soil (Mohr–Coulomb with φ = ψ = 0), axisymmetric,
/// rough and smooth, against Eason & Shield's 6.05 and Shield's 5.69: q at 0.2 R.
fn circular(report: &mut Report, runs: Vec<CircularRun>) -> Result<()> {
    writeln!(report.md, "## V3 circular footing, axisymmetric\n\nA rigid footing of radius R = 1 on the V3 soil as Tresca (Mohr–Coulomb, c = {COHESION}, φ = ψ = 0), 6 R wide and 5 R deep, linear basis, B-bar, 2×2 points per cell, small strain, geometrically linear, pushed {SETTLEMENT} R in {CIRCULAR_STEPS} steps (extrapolated start); rough: the footing's nodes held radially. q = footing force / π R² at 0.2 R; references N_c = 6.05 rough (Eason & Shield 1960), 5.69 smooth (Shield 1955).\n")?;
    report.mark_table("V3-circular")?;
    writeln!(
        report.md,
        "| footing | cells per R | q/c | / N_c − 1 | cut-backs | wall [s] |\n|---|---:|---:|---:|---:|---:|"
    )?;
    for (&(rough, nc, cells), (q, cutbacks, failure, wall)) in CIRCULAR_JOBS.iter().zip(runs) {
        let kind = if rough { "rough" } else { "smooth" };
        let error = if failure.is_some() { f64::NAN } else { q / nc - 1.0 };
        let shown = failure
            .as_deref()
            .map_or(format!("{q:.3} | {error:+.4}"), |f| format!("— | {}", f.split(':').next().unwrap_or(f)));
        writeln!(report.md, "| {kind} | {cells} | {shown} | {cutbacks} | {wall:.2} |")?;
        let name = format!("V3 circular {kind} {cells} cells per R");
        if cells == 16 {
            report.rows.push(Row::checked(&name, "|q/c/N_c - 1|", error.abs(), CIRCULAR_Q_U));
        } else {
            report.rows.push(Row::info(&name, "q/c/N_c - 1", error));
        }
    }
    writeln!(report.md)?;
    Ok(())
}

/// The circular footings: rough then smooth (with their N_c), each at 4, 8 and 16 cells per R.
const CIRCULAR_JOBS: [(bool, f64, usize); 6] =
    [(true, 6.05, 4), (true, 6.05, 8), (true, 6.05, 16), (false, 5.69, 4), (false, 5.69, 8), (false, 5.69, 16)];

/// q/c at the end, cut-backs, why it stopped (if it did), wall time.
type CircularRun = (f64, usize, Option<String>, f64);

/// Every circular footing of [`CIRCULAR_JOBS`], in order.
fn circular_runs(report: &Report) -> Result<Vec<CircularRun>> {
    let tresca: Arc<dyn ConstitutiveLaw> =
        Arc::new(MohrCoulomb::from_degrees(Elastic::new(YOUNG, POISSON)?, COHESION, 0.0, 0.0)?);
    Ok(report.runs(&CIRCULAR_JOBS, |&(rough, _, cells)| circular_run(&tresca, rough, cells)))
}

/// One circular footing.
fn circular_run(tresca: &Arc<dyn ConstitutiveLaw>, rough: bool, cells: usize) -> CircularRun {
    let kind = if rough { "rough" } else { "smooth" };
    eprintln!("verify: V3 circular footing, {kind}, {cells} cells per R");
    let t = Instant::now();
    let model = circular_footing_model(tresca.clone(), cells, SETTLEMENT, rough);
    let settings = QuasiStaticSettings { load_steps: CIRCULAR_STEPS, extrapolate: true, ..Default::default() };
    let mut qs = QuasiStatic::new(model, settings);
    let (mut q, mut cutbacks, mut failure) = (f64::NAN, 0, None);
    while !qs.is_finished() {
        match qs.step() {
            Ok(r) => {
                q = -r.reactions[0][1] / (std::f64::consts::PI * COHESION);
                cutbacks += r.cutbacks;
            }
            Err(e) => {
                failure = Some(format!("stopped at step {}: {e}", qs.steps_done() + 1));
                break;
            }
        }
    }
    (q, cutbacks, failure, t.elapsed().as_secs_f64())
}

/// Every run of the sweep, in the order of the table (law, treatment, mesh).
fn sweep_runs(laws: &[FootingLaw], quick: bool, report: &Report) -> Vec<FootingRun> {
    let jobs: Vec<(&FootingLaw, AntiLocking, usize)> = laws
        .iter()
        .flat_map(|law| {
            treatments(quick).into_iter().flat_map(move |(a, meshes)| meshes.iter().map(move |&cells| (law, a, cells)))
        })
        .collect();
    report.runs(&jobs, |&(law, anti_locking, cells)| {
        eprintln!("verify: V3 {}, {}, {cells} cells per b", law.name, treatment_name(anti_locking));
        run(&law.law, cells, anti_locking)
    })
}

/// One law with one treatment on its meshes, from their `runs` in order: the table rows,
/// the observed order of q_u and, for the assumed strain, the verdict. Returns the largest
/// drop / q_ref and the number of runs that stopped short.
fn treatment(
    quick: bool,
    report: &mut Report,
    sweep: &mut Sweep,
    law: &FootingLaw,
    (anti_locking, meshes): (AntiLocking, &[usize]),
    runs: &mut impl Iterator<Item = FootingRun>,
) -> Result<(f64, usize)> {
    let (mut drop, mut stopped, mut ratios, mut finest) = (0.0f64, 0, Vec::new(), None);
    for &cells in meshes {
        let r = runs.next().context("the sweep ran fewer footings than its table has rows")?;
        run_row(report, sweep, law, anti_locking, cells, &r)?;
        if anti_locking == ASSUMED && cells == *meshes.last().unwrap() {
            sweep.finest(law, cells, &r);
        }
        drop = drop.max(r.largest_drop() / law.nc);
        stopped += r.failure.is_some() as usize;
        ratios.push(r.q_u() / law.nc);
        finest = Some((cells, r));
    }
    // Defined where three meshes ran: the full sweep's B-bar and assumed strain.
    let order = match ratios[..] {
        [.., a, b, c] => Some(observed_order(a, b, c)),
        _ => None,
    };
    if let Some(order) = order {
        let case = format!("V3 {} {}", law.name, treatment_name(anti_locking));
        report.rows.push(Row::info(case, "observed_order_of_qu", order));
    }
    if let Some((cells, r)) = finest.filter(|_| anti_locking == ASSUMED) {
        verdict(quick, report, sweep, law, cells, &r, order);
    }
    Ok((drop, stopped))
}

/// One run's table row (and why it stopped, if it did), its curve and its rows of the
/// bounds table.
fn run_row(
    report: &mut Report,
    sweep: &mut Sweep,
    law: &FootingLaw,
    anti_locking: AntiLocking,
    cells: usize,
    r: &FootingRun,
) -> Result<()> {
    let (name, nc, treatment) = (&law.name, law.nc, treatment_name(anti_locking));
    let q_u = r.q_u();
    let ratio = q_u / nc - 1.0;
    let drop = r.largest_drop() / nc;
    writeln!(report.md, "| {name} | {treatment} | {cells} | {:.3} | {q_u:.3} | {nc:.3} | {ratio:+.4} | {drop:.1e} | {} | {} | {} | {:.2} |", r.q_at(0.04), r.max_iterations, r.to_tolerance, r.cutbacks, r.wall_s)?;
    if let Some(f) = &r.failure {
        writeln!(report.md, "\n{name}, {treatment}, {cells} cells per b stopped: {f}\n")?;
    }
    sweep.curve(law, treatment, cells, r)?;
    let case = format!("V3 {name} {treatment} {cells}/b");
    report.rows.push(Row::info(&case, "qu_over_q_ref_minus_1", ratio));
    report.rows.push(Row::info(&case, "max_newton_corrections_to_1e-9", r.to_tolerance as f64));
    Ok(())
}

/// The assumed strain's verdict on a law from its finest run. Every law's bound, the
/// anti-locking bound of the ν = 0.49 case among them, is checked there on the full sweep.
fn verdict(
    quick: bool,
    report: &mut Report,
    sweep: &mut Sweep,
    law: &FootingLaw,
    cells: usize,
    r: &FootingRun,
    order: Option<f64>,
) {
    let ratio = r.q_u() / law.nc - 1.0;
    if !quick {
        let case = format!("V3 {}, assumed strain, {cells}/b", law.name);
        report.rows.push(Row::checked(case, "abs_qu_over_q_ref_minus_1", ratio.abs(), Q_U));
    }
    let order = order.map_or(String::new(), |p| format!(" (observed order of q_u over the last three meshes: {p:.2})"));
    let met = |holds: bool| if holds { "met" } else { "NOT met" };
    sweep.verdicts.push(format!(
        "- {}: {ratio:+.4} at {cells} cells per b{order} — {:.0} % bound {}; ≤ {} Newton iterations per step to 1e-9 {} ({} corrections to 1e-9, {} to convergence)",
        law.name,
        100.0 * Q_U.value,
        met(Q_U.holds(ratio.abs())),
        NEWTON_CORRECTIONS.value,
        met(NEWTON_CORRECTIONS.holds(r.to_tolerance as f64)),
        r.to_tolerance,
        r.max_iterations
    ));
}
