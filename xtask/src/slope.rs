//! V4 slopes (docs/verification.md §V4): the undrained 45° slope by gravity increase against
//! Taylor's stability number, and the Griffiths & Lane (1999) frictional slope by strength
//! reduction against their factor of safety 1.4.

use crate::report::{Report, Row};
use crate::soil::{self, COHESION, POISSON, YOUNG};
use anyhow::Result;
use loam::analysis::Analysis;
use loam::analysis::{FactorOfSafety, StrengthReduction, TrialStart};
use loam::constitutive::{ConeFit, ConstitutiveLaw, DruckerPrager, Elastic, MohrCoulomb};
use loam::explicit::{Explicit, ExplicitSettings, TimeStep};
use loam::grid::BasisKind;
use loam::implicit::{AntiLocking, Dynamic, DynamicSettings, Kinematics, QuasiStatic, QuasiStaticSettings};
use loam::model::Model;
use loam_verification::slope::bounds::{
    DRUCKER_PRAGER_FOS, GRIFFITHS_LANE, RUNOUT_PROFILES, SEARCH_PATHS, TAYLOR as TAYLOR_BOUND,
};
use loam_verification::slope::{GRIFFITHS_LANE_FACTOR_OF_SAFETY as GL_FOS, TAYLOR_STABILITY as TAYLOR};
use loam_verification::{slope_model, slope_model_with, SlopeGeometry};
use std::fmt::Write as _;
use std::sync::Arc;
use std::time::Instant;

/// The soil's cohesion as the undrained strength c_u (E/c_u = 10⁴; the collapse load does
/// not depend on E).
const C_U: f64 = COHESION;
/// γH/c_u reached at load factor 1, and the load steps to get there: 0.1 per step, refined
/// by up to 8 halvings where Newton fails, so collapse is located to 0.1/256.
const N_MAX: f64 = 8.0;
const GRAVITY_STEPS: usize = 80;

struct Collapse {
    n: f64,
    /// The whole load was carried: `n` is only a lower bound.
    carried: bool,
    max_iterations: usize,
    crest_settlement: f64,
    stop: String,
    wall_s: f64,
}

/// Gravity increase on the undrained slope: γH/c_u at the last load the slope carried.
fn undrained(cells: usize, anti_locking: AntiLocking) -> Result<Collapse> {
    let g = SlopeGeometry::UNDRAINED;
    let law = soil::undrained(Elastic::new(YOUNG, POISSON)?, C_U)?;
    let gamma = N_MAX * C_U / g.height;
    let model = slope_model(&g, law, gamma / 10.0, 10.0, cells, anti_locking);
    // Halved up to 8 times, as docs/verification.md §V4 says: no limit resolution, so
    // that γH/c_u is resolved to 0.1 / 256.
    let settings = QuasiStaticSettings { load_steps: GRAVITY_STEPS, limit_resolution: 0.0, ..Default::default() };
    let mut qs = QuasiStatic::new(model, settings);
    let t = Instant::now();
    let (mut max_iterations, mut stop, mut carried) =
        (0, "carried the whole load (no collapse up to γH/c_u = 8)".to_string(), true);
    while !qs.is_finished() {
        match qs.step() {
            Ok(r) => max_iterations = max_iterations.max(r.most_iterations()),
            Err(e) => {
                stop = e.to_string();
                carried = false;
                break;
            }
        }
    }
    Ok(Collapse {
        n: qs.load_factor() * N_MAX,
        carried,
        max_iterations,
        crest_settlement: crest_settlement(qs.model(), &g),
        stop,
        wall_s: t.elapsed().as_secs_f64(),
    })
}

/// Settlement of the crest edge: the point nearest the top of the slope face.
fn crest_settlement(model: &Model<2>, g: &SlopeGeometry) -> f64 {
    let p = model.points();
    let (cx, cy) = ((g.toe + g.run) * g.height, (g.depth + 1.0) * g.height);
    let distance = |a: usize| (p.position0()[a][0] - cx).hypot(p.position0()[a][1] - cy);
    let k = (0..p.len()).min_by(|&a, &b| distance(a).total_cmp(&distance(b))).unwrap_or(0);
    p.position0()[k][1] - p.position()[k][1]
}

/// The V4 sections: V4a, V4b and the V4c run-out.
pub fn verify(quick: bool, report: &mut Report) -> Result<()> {
    let meshes: &[usize] = if quick { &[5, 10] } else { &[5, 10, 20] };
    undrained_section(meshes, report)?;
    griffiths_lane_section(meshes, report)?;
    runout(quick, report)
}

/// V4a: B-bar on every mesh, plain on the second; the bound on the finest B-bar run.
fn undrained_section(meshes: &[usize], report: &mut Report) -> Result<()> {
    writeln!(report.md, "## V4a undrained slope: gravity increase\n\n45° slope, H = 10, on a foundation layer H deep (Taylor's depth factor 2), 2 H of ground before the toe and behind the crest; base fixed, sides on rollers; von Mises with c_u = {C_U} (σ_y = √3 c_u), E = {YOUNG:e}, ν = {POISSON}; linear basis, 2×2 points per cell, small strain, B-bar. Gravity grows by γH/c_u = 0.1 per load step (up to 8 halvings of a step that fails); collapse is the last load the slope carried. Reference: Taylor's 1/N_s ≈ {TAYLOR} (N_s ≈ 0.18 for 45°, deep foundation). Bound: within 10 % on the finest mesh.\n")?;
    writeln!(report.md, "| cells per H | treatment | γH/c_u at collapse | /5.5 − 1 | crest settlement before collapse [m] | max Newton its per sub-step | wall [s] |\n|---:|---|---:|---:|---:|---:|---:|")?;
    let mut finest = f64::NAN;
    let mut stops = Vec::new();
    for &cells in meshes {
        eprintln!("verify: V4a undrained slope, B-bar, {cells} cells per H");
        let r = undrained(cells, AntiLocking::BBar)?;
        anyhow::ensure!(
            !r.carried,
            "V4a: the B-bar slope at {cells} cells per H carried γH/c_u = {N_MAX} without collapsing"
        );
        finest = collapse_row(&mut report.md, cells, "B-bar", &r)?;
        stops.push(format!("- {cells} cells per H: {}", r.stop));
        report.rows.push(Row::info(format!("V4a undrained slope {cells}/H"), "gammaH_over_cu_at_collapse", r.n));
    }
    let cells = meshes[1];
    eprintln!("verify: V4a undrained slope, plain, {cells} cells per H");
    let plain = undrained(cells, AntiLocking::None)?;
    collapse_row(&mut report.md, cells, "plain", &plain)?;
    stops.push(format!("- {cells} cells per H, plain: {}", plain.stop));
    writeln!(report.md, "\nWhy each run stopped (the collapse criterion is a load step that Newton cannot carry after all its cut-backs; at the limit load the tangent of a perfectly plastic body turns singular, which the Cholesky factorisation reports):\n\n{}\n", stops.join("\n"))?;
    let quantity = "abs_gammaH_over_cu_over_5.5_minus_1";
    report.rows.push(Row::checked("V4a undrained slope (finest)", quantity, finest.abs(), TAYLOR_BOUND));
    Ok(())
}

/// A V4a row; returns γH/c_u at collapse over Taylor's − 1. A run that carried the whole
/// load shows it as a lower bound ("> ").
fn collapse_row(md: &mut String, cells: usize, treatment: &str, r: &Collapse) -> Result<f64> {
    let at_least = if r.carried { "> " } else { "" };
    let rel = r.n / TAYLOR - 1.0;
    writeln!(
        md,
        "| {cells} | {treatment} | {at_least}{:.3} | {at_least}{rel:+.3} | {:.4} | {} | {:.2} |",
        r.n, r.crest_settlement, r.max_iterations, r.wall_s
    )?;
    Ok(rel)
}

/// V4b: the factor of safety on every mesh, searched from the last state that held and
/// from zero side by side; the bound on the finest, and the two searches' agreement on all.
fn griffiths_lane_section(meshes: &[usize], report: &mut Report) -> Result<()> {
    writeln!(report.md, "## V4b Griffiths & Lane slope: strength reduction\n\n2:1 slope (26.57°), H = 10, foundation layer H deep, 1.2 H before the toe, 2 H behind the crest; Mohr–Coulomb c = 10, φ = 20°, ψ = 0 (non-associated: sparse LU), and the Drucker–Prager cone fitted to it in plane strain (η = sin φ, ξ = cos φ at ψ = 0), γ = 20 (c/(γH) = 0.05), E = {YOUNG:e}, ν = {POISSON}; linear basis, B-bar. Gravity in 10 load steps (up to 4 halvings) at F = 1; then, from the last state that held (the default), c and tan φ divided by a factor raised towards 2 in 10 strength steps, each halved down to half the tolerance; or from zero, each trial applying gravity anew at its factor, F bisected. Tolerance 0.005. Reference: F ≈ {GL_FOS} (Griffiths & Lane 1999; Bishop's method gives 1.38). Bound: within 5 % on the finest mesh, the two searches within the tolerance of each other, and Drucker–Prager within 2 % of Mohr–Coulomb on the finest mesh.\n")?;
    report.mark_table("V4b")?;
    writeln!(report.md, "| cells per H | law | trials start | F (bracket) | /1.4 − 1 | trials | Newton its | largest displacement at the last stable trial [m] | wall [s] |\n|---:|---|---|---:|---:|---:|---:|---:|---:|")?;
    let (mut finest, mut dp) = (f64::NAN, f64::NAN);
    let runs = [
        (SlopeLaw::MohrCoulomb, TrialStart::LastHeld, "last held"),
        (SlopeLaw::MohrCoulomb, TrialStart::Zero, "zero"),
        (SlopeLaw::DruckerPrager, TrialStart::LastHeld, "last held"),
    ];
    for &cells in meshes {
        let mut factors = Vec::new();
        for (law, start, name) in runs {
            let law_name = law.name();
            eprintln!("verify: V4b Griffiths & Lane slope, {law_name}, {cells} cells per H, trials from {name}");
            let (fos, wall) = griffiths_lane(cells, law, start)?;
            let last_stable = fos
                .trials
                .iter()
                .filter(|t| t.stable)
                .max_by(|a, b| a.factor.total_cmp(&b.factor))
                .map_or(f64::NAN, |t| t.max_displacement);
            let iterations: usize = fos.trials.iter().map(|t| t.iterations).sum();
            let rel = fos.value() / GL_FOS - 1.0;
            writeln!(
                report.md,
                "| {cells} | {law_name} | {name} | {:.3} ({:.4}–{:.4}) | {rel:+.3} | {} | {iterations} | {last_stable:.3} | {wall:.1} |",
                fos.value(),
                fos.stable,
                fos.failed,
                fos.trials.len()
            )?;
            let case = match law {
                SlopeLaw::MohrCoulomb => format!("V4b Griffiths-Lane slope {cells}/H, from {name}"),
                SlopeLaw::DruckerPrager => format!("V4b Griffiths-Lane slope {cells}/H, Drucker-Prager, from {name}"),
            };
            report.rows.push(Row::info(case.clone(), "factor_of_safety", fos.value()));
            report.rows.push(Row::info(case.clone(), "newton_iterations", iterations as f64));
            report.rows.push(Row::info(case, "wall_s", wall));
            if (law, start) == (SlopeLaw::MohrCoulomb, TrialStart::LastHeld) {
                finest = rel;
            }
            factors.push(fos.value());
        }
        let apart = (factors[0] - factors[1]).abs() / GRIFFITHS_LANE_TOLERANCE;
        let case = format!("V4b Griffiths-Lane slope {cells}/H");
        report.rows.push(Row::checked(&case, "|F_last_held - F_zero|/tolerance", apart, SEARCH_PATHS));
        dp = factors[2] / factors[0] - 1.0;
        report.rows.push(Row::info(&case, "F_Drucker-Prager/F_Mohr-Coulomb - 1", dp));
    }
    writeln!(report.md)?;
    let quantity = "abs_fos_over_1.4_minus_1";
    report.rows.push(Row::checked("V4b Griffiths-Lane slope (finest)", quantity, finest.abs(), GRIFFITHS_LANE));
    let quantity = "|F_Drucker-Prager/F_Mohr-Coulomb - 1|";
    report.rows.push(Row::checked("V4b Griffiths-Lane slope (finest)", quantity, dp.abs(), DRUCKER_PRAGER_FOS));
    Ok(())
}

/// The soil law of a V4b search: c = 10, φ = 20°, ψ = 0 as Mohr–Coulomb, or as the
/// Drucker–Prager cone fitted to it in plane strain.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum SlopeLaw {
    MohrCoulomb,
    DruckerPrager,
}

impl SlopeLaw {
    fn name(self) -> &'static str {
        match self {
            SlopeLaw::MohrCoulomb => "Mohr–Coulomb",
            SlopeLaw::DruckerPrager => "Drucker–Prager",
        }
    }

    fn law(self) -> Result<Arc<dyn ConstitutiveLaw>> {
        let elastic = Elastic::new(YOUNG, POISSON)?;
        Ok(match self {
            SlopeLaw::MohrCoulomb => Arc::new(MohrCoulomb::from_degrees(elastic, 10.0, 20.0, 0.0)?),
            SlopeLaw::DruckerPrager => {
                Arc::new(DruckerPrager::from_degrees(elastic, 10.0, 20.0, 0.0, ConeFit::PlaneStrain)?)
            }
        })
    }
}

/// The strength-reduction search's tolerance on F in V4b.
const GRIFFITHS_LANE_TOLERANCE: f64 = 0.005;

/// Strength reduction on the Griffiths & Lane slope with `law`, F bracketed in [1, 2] to
/// 0.005 with trials from `start`, and its wall time.
fn griffiths_lane(cells: usize, law: SlopeLaw, start: TrialStart) -> Result<(FactorOfSafety, f64)> {
    let g = SlopeGeometry::GRIFFITHS_LANE;
    let law = law.law()?;
    let model = slope_model(&g, law, 2.0, 10.0, cells, AntiLocking::BBar);
    let srf = StrengthReduction {
        trial: QuasiStaticSettings { load_steps: 10, max_cutbacks: 4, ..Default::default() },
        bracket: (1.0, 2.0),
        tolerance: GRIFFITHS_LANE_TOLERANCE,
        start,
    };
    let t = Instant::now();
    let fos = srf.factor_of_safety(&model, |_, _| {})?;
    Ok((fos, t.elapsed().as_secs_f64()))
}

/// The surface after run-out: the highest point in each column of cells.
fn profile(model: &Model<2>) -> Vec<f64> {
    let h = model.grid().cell_size()[0];
    let nx = model.grid().cells()[0];
    let mut top = vec![0.0f64; nx];
    for x in model.points().position() {
        let i = ((x[0] / h).max(0.0) as usize).min(nx - 1);
        top[i] = top[i].max(x[1]);
    }
    top
}

/// The largest rise of the ground in front of the toe above its initial level (the heave
/// of a base failure).
fn heave(profile: &[f64], h: f64, g: &SlopeGeometry) -> f64 {
    let toe = (g.toe * g.height / h) as usize;
    profile[..toe].iter().fold(f64::NEG_INFINITY, |m, &y| m.max(y)) - g.depth * g.height
}

/// V4c's slope: γH/c_u = 8 (well past collapse), a softer E, released under full gravity.
const N_RUNOUT: f64 = 8.0;
const YOUNG_RUNOUT: f64 = 1e4;
pub(crate) const DURATION: f64 = 4.0;

/// A run-out to `DURATION`: its steps, the range of its time steps, its Newton iterations
/// and cut-backs in all, its wall time and the final profile.
pub(crate) struct Runout {
    pub(crate) steps: usize,
    pub(crate) dt: (f64, f64),
    pub(crate) iterations: usize,
    pub(crate) cutbacks: usize,
    pub(crate) wall_s: f64,
    pub(crate) profile: Vec<f64>,
}

/// The V4c slope at `cells` cells per H (GIMP, finite strain), as a fresh model per call,
/// and its cell size.
pub(crate) fn runout_model(cells: usize) -> Result<(impl Fn() -> Model<2>, f64)> {
    let g = SlopeGeometry::UNDRAINED;
    let law = soil::undrained(Elastic::new(YOUNG_RUNOUT, POISSON)?, C_U)?;
    let gamma = N_RUNOUT * C_U / g.height;
    let model =
        move || slope_model_with(&g, law.clone(), gamma / 10.0, 10.0, cells, BasisKind::Gimp, Kinematics::FiniteStrain);
    Ok((model, g.height / cells as f64))
}

/// Run an analysis of the run-out to its end; the wall time includes setting it up.
pub(crate) fn run_out(start: impl FnOnce() -> Result<Analysis<2>>) -> Result<Runout> {
    let t = Instant::now();
    let mut a = start()?;
    let mut out =
        Runout { steps: 0, dt: (f64::INFINITY, 0.0), iterations: 0, cutbacks: 0, wall_s: 0.0, profile: vec![] };
    while !a.is_finished() {
        let r = a.step()?;
        out.steps += 1;
        out.dt = (out.dt.0.min(r.increment), out.dt.1.max(r.increment));
        out.iterations += r.iterations;
        out.cutbacks += r.cutbacks;
    }
    out.wall_s = t.elapsed().as_secs_f64();
    out.profile = profile(a.model());
    Ok(out)
}

/// V4c: the undrained slope at γH/c_u = 8 (well past collapse) released under full gravity,
/// in large deformation, by implicit dynamics and by explicit MPM on the same mesh.
fn runout(quick: bool, report: &mut Report) -> Result<()> {
    let cells = if quick { 5 } else { 10 };
    let g = SlopeGeometry::UNDRAINED;
    let (model, h) = runout_model(cells)?;
    writeln!(report.md, "## V4c run-out of the undrained slope: implicit and explicit side by side\n\nThe V4a slope with γH/c_u = {N_RUNOUT} (collapse is at 5.4), E = {YOUNG_RUNOUT:e}, released under full gravity at t = 0 and followed for {DURATION} s (the kinetic energy has fallen by two orders by then); GIMP, finite strain (no anti-locking: B-bar is small-strain only), {cells} cells per H (h = {h}), 2×2 points per cell. Implicit: trapezoidal Newmark, lumped mass. Explicit: MUSL, pure FLIP, CFL safety 0.5. Profile = highest point per column of cells; crest height = the profile where the crest was (initially {}), heave = the largest rise of the ground in front of the toe (a base failure lifts it). Bound: the implicit and explicit final profiles agree within two cells.\n", (g.depth + 1.0) * g.height)?;
    writeln!(report.md, "| scheme | Δt [s] | steps | Newton its | cut-backs | wall [s] | crest height [m] | heave before the toe [m] | max profile difference from explicit [cells] |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    eprintln!("verify: V4c run-out, explicit, {cells} cells per H");
    // Pure FLIP: no numerical dissipation beside the trapezoidal rule's none (1 % PIC, the
    // default, moves the explicit profile by 0.3 of a cell at 5 cells per H).
    let settings =
        ExplicitSettings { time_step: TimeStep::Cfl { safety: 0.5 }, flip: 1.0, ..ExplicitSettings::new(DURATION) };
    let ex = run_out(|| Ok(Analysis::Explicit(Explicit::new(model(), settings)?)))?;
    let crest_i = ((g.toe + g.run) * g.height / h) as usize;
    let (dt_min, dt_max) = ex.dt;
    let (crest, heave_ex) = (ex.profile[crest_i], heave(&ex.profile, h, &g));
    writeln!(
        report.md,
        "| explicit | {dt_min:.2e}–{dt_max:.2e} | {} | – | – | {:.2} | {crest:.2} | {heave_ex:.2} | 0 |",
        ex.steps, ex.wall_s
    )?;
    report.rows.push(Row::info(format!("V4c run-out explicit {cells}/H"), "wall_time_s", ex.wall_s));
    let mut worst = 0.0f64;
    for dt in [0.02, 0.05] {
        eprintln!("verify: V4c run-out, implicit Δt = {dt}, {cells} cells per H");
        let settings = DynamicSettings::trapezoidal(dt, DURATION);
        let im = run_out(|| Ok(Analysis::Dynamic(Dynamic::new(model(), settings)?)))?;
        let diff = ex.profile.iter().zip(&im.profile).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / h;
        worst = worst.max(diff);
        let (crest, heave_im) = (im.profile[crest_i], heave(&im.profile, h, &g));
        writeln!(
            report.md,
            "| implicit | {dt} | {} | {} | {} | {:.2} | {crest:.2} | {heave_im:.2} | {diff:.3} |",
            im.steps, im.iterations, im.cutbacks, im.wall_s
        )?;
        report.rows.push(Row::info(format!("V4c run-out implicit dt={dt} {cells}/H"), "wall_time_s", im.wall_s));
    }
    writeln!(report.md)?;
    let case = format!("V4c run-out {cells}/H");
    report.rows.push(Row::checked(case, "max_profile_difference_cells", worst, RUNOUT_PROFILES));
    Ok(())
}
