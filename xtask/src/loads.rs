//! The checks of the loads on surfaces: the V3 footing under load control (a pressure
//! ramped on the footing width until Newton fails, against Prandtl), and V6, the
//! thick-walled cylinder under internal pressure (docs/verification.md §V6) — the radial
//! displacements at the bore and the outer radius against Lamé on three meshes (small
//! strain, dead pressure), Newton under a follower pressure of a tenth of E in finite
//! strain, with the residual sequence of its hardest load step, and the cylinder posed
//! axisymmetrically, against Lamé and its limit pressure.

use crate::columns::observed_rate;
use crate::report::{Report, Row};
use crate::soil::{self, COHESION, POISSON, YOUNG};
use anyhow::Result;
use loam::constitutive::{ConstitutiveLaw, Elastic, VonMises};
use loam::implicit::{AntiLocking, ArcLengthSettings, Kinematics, LoadControl, QuasiStatic, QuasiStaticSettings};
use loam::model::Model;
use loam_verification::cavity::{bounds::CAVITY_LIMIT, SphericalCavity};
use loam_verification::cylinder::bore_radius;
use loam_verification::cylinder::bounds::{
    FOLLOWER_NEWTON_ITERATIONS, RADIAL_DISPLACEMENT, RING_LAME, RING_LAME_ORDER, RING_LIMIT,
};
use loam_verification::footing::bounds::{ARC_LENGTH_PEAK, ARC_LENGTH_STOPPED, LOAD_CONTROLLED_COLLAPSE};
use loam_verification::sphere::bounds::{SPHERE_LAME, SPHERE_LIMIT};
use loam_verification::{footing_load_model, prandtl_nc, Cylinder, ThickSphere};
use std::fmt::Write as _;
use std::sync::Arc;
use std::time::Instant;

/// Load steps of the follower-pressure run.
const FOLLOWER_STEPS: usize = 20;
/// Ghost penalty of the follower-pressure run: the bore sweeps through the grid and leaves
/// nearly empty cells behind its loaded face (docs/theory.md §15, §17).
const FOLLOWER_GHOST: f64 = 0.1;

/// Run `model` in `load_steps` quasi-static steps: the finished model, the most Newton
/// corrections of a step and the residuals of that step.
fn solve(model: Model<2>, load_steps: usize) -> Result<(Model<2>, usize, Vec<f64>)> {
    let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps, ..Default::default() });
    let (mut most, mut hardest) = (0, Vec::new());
    while !qs.is_finished() {
        let r = qs.step()?;
        if r.iterations > most {
            (most, hardest) = (r.iterations, r.residuals);
        }
    }
    Ok((qs.into_model(), most, hardest))
}

/// Load steps of the load-controlled footing, and its full pressure over Prandtl's.
const FOOTING_STEPS: usize = 100;
const FOOTING_OVERLOAD: f64 = 1.25;

/// The V3 strip load at `cells` cells per b: von Mises soil, assumed strain, the pressure
/// `FOOTING_OVERLOAD` (2 + π) c_u at full load.
fn strip_load_model(cells: usize) -> Result<Model<2>> {
    let law = soil::undrained(Elastic::new(YOUNG, POISSON)?, COHESION)?;
    let assumed = AntiLocking::AssumedStrain { stabilization: 0.1 };
    Ok(footing_load_model(law, cells, 10, 5, FOOTING_OVERLOAD * prandtl_nc(0.0) * COHESION, assumed))
}

/// The V3 footing under load control: for each mesh the load factor at which Newton
/// failed after its cut-backs, as a pressure over (2 + π) c_u.
fn load_control(quick: bool, report: &mut Report) -> Result<()> {
    let meshes: &[usize] = if quick { &[4, 8] } else { &[4, 8, 16] };
    let q_ref = prandtl_nc(0.0) * COHESION;
    writeln!(report.md, "## V3 footing under load control

The V3 soil (von Mises, c_u = {COHESION}, E = {YOUNG:e}, ν = {POISSON}, assumed strain β = 0.1, small strain, geometrically linear, half model 10 b × 5 b, 2×2 points per cell) under a uniform pressure on 0 ≤ x ≤ b (a flexible smooth footing, a dead pressure on surface vertices), ramped to {FOOTING_OVERLOAD} (2 + π) c_u in {FOOTING_STEPS} load steps, each halved when Newton fails until the increment would be below {} of the load (the default limit resolution). Collapse: the last converged pressure. Reference (2 + π) c_u = {q_ref:.3}; the displacement-controlled V3 figures (q at 0.1 B) are in the V3 section above.\n", QuasiStaticSettings::default().limit_resolution)?;
    writeln!(
        report.md,
        "| cells per b | collapse pressure | / (2 + π) c_u − 1 | steps | wall [s] |\n|---:|---:|---:|---:|---:|"
    )?;
    let mut finest = None;
    for &cells in meshes {
        eprintln!("verify: V3 under load control, {cells} cells per b");
        let t = Instant::now();
        let model = strip_load_model(cells)?;
        let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps: FOOTING_STEPS, ..Default::default() });
        while !qs.is_finished() && qs.step().is_ok() {}
        let collapse = qs.load_factor() * FOOTING_OVERLOAD * q_ref;
        let error = collapse / q_ref - 1.0;
        writeln!(
            report.md,
            "| {cells} | {collapse:.3} | {error:+.4} | {} | {:.2} |",
            qs.steps_done(),
            t.elapsed().as_secs_f64()
        )?;
        finest = Some((cells, error, qs.is_finished()));
    }
    let (cells, error, finished) = finest.expect("at least one mesh");
    writeln!(report.md)?;
    let name = format!("V3 load control {cells} cells per b");
    report.rows.push(Row::checked(&name, "|collapse/q_ref - 1|", error.abs(), LOAD_CONTROLLED_COLLAPSE));
    report.rows.push(Row::info(&name, "ran to full load (1 = yes: no collapse found)", f64::from(u8::from(finished))));
    Ok(())
}

/// Steps of the arc-length footing (the first, load-controlled, of 1 / `ARC_FIRST`).
const ARC_STEPS: usize = 60;
const ARC_FIRST: usize = 10;

/// The V3 footing under arc-length control: for each mesh the peak of the curve against
/// Prandtl, and how far the curve went on past it (the strip centre's settlement at the
/// last step over its settlement when the load first came within 1 % of the peak).
fn arc_length(quick: bool, report: &mut Report) -> Result<()> {
    let meshes: &[usize] = if quick { &[4, 8] } else { &[4, 8, 16] };
    let q_ref = prandtl_nc(0.0) * COHESION;
    let arc = ArcLengthSettings { steps: ARC_STEPS, ..Default::default() };
    writeln!(report.md, "## V3 footing under arc-length control

The load-controlled footing above (full pressure {FOOTING_OVERLOAD} (2 + π) c_u), under arc-length control (docs/theory.md §21): a first load step of 1/{ARC_FIRST} of the load, then {ARC_STEPS} steps in all, each aiming at {} Newton corrections and at most {} times the first step's length. Peak: the largest pressure of the curve. Past the peak: the strip centre's settlement at the last step over its settlement at the first step within 1 % of the peak.\n", arc.iterations, arc.max_growth)?;
    report.mark_table("V3-arc")?;
    writeln!(
        report.md,
        "| cells per b | peak pressure | / (2 + π) c_u − 1 | peak step | settlement at the end / near the peak | steps | Newton iterations | wall [s] |\n|---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    let mut finest = None;
    for &cells in meshes {
        eprintln!("verify: V3 under arc-length control, {cells} cells per b");
        let t = Instant::now();
        let model = strip_load_model(cells)?;
        let centre = model.points().nearest_at_start(&[0.0, 5.0].into()).expect("the model has points");
        let settings =
            QuasiStaticSettings { load_steps: ARC_FIRST, control: LoadControl::ArcLength(arc), ..Default::default() };
        let mut qs = QuasiStatic::new(model, settings);
        let settlement = |m: &Model<2>| m.points().position0()[centre][1] - m.points().position()[centre][1];
        let (mut curve, mut iterations, mut failed) = (Vec::new(), 0, 0);
        while !qs.is_finished() {
            match qs.step() {
                Ok(r) => iterations += r.iterations,
                Err(_) => {
                    failed = 1;
                    break;
                }
            }
            curve.push((qs.load_factor(), settlement(qs.model())));
        }
        let peak = qs.peak().expect("an arc-length run has a peak");
        let near_peak = curve.iter().find(|(l, _)| *l >= 0.99 * peak.load_factor).map_or(f64::NAN, |c| c.1);
        let end = curve.last().map_or(f64::NAN, |c| c.1);
        let pressure = peak.load_factor * FOOTING_OVERLOAD * q_ref;
        let error = pressure / q_ref - 1.0;
        writeln!(
            report.md,
            "| {cells} | {pressure:.3} | {error:+.4} | {} | {:.2} | {} | {iterations} | {:.2} |",
            peak.step,
            end / near_peak,
            qs.steps_done(),
            t.elapsed().as_secs_f64()
        )?;
        finest = Some((cells, error, failed));
    }
    let (cells, error, failed) = finest.expect("at least one mesh");
    writeln!(report.md)?;
    let name = format!("V3 arc length {cells} cells per b");
    report.rows.push(Row::checked(&name, "|peak/q_ref - 1|", error.abs(), ARC_LENGTH_PEAK));
    report.rows.push(Row::checked(&name, "steps that failed", f64::from(failed), ARC_LENGTH_STOPPED));
    Ok(())
}

/// The load sections of the report: the load-controlled and arc-length footings and V6.
pub(crate) fn verify(quick: bool, report: &mut Report) -> Result<()> {
    load_control(quick, report)?;
    arc_length(quick, report)?;
    cylinder(quick, report)
}

/// V6 with a dead pressure in small strain against Lamé, then the follower run.
fn cylinder(quick: bool, report: &mut Report) -> Result<()> {
    let meshes: &[usize] = if quick { &[10, 20, 40] } else { &[10, 20, 40, 80] };
    let c = Cylinder::REFERENCE;
    writeln!(report.md, "## V6 thick-walled cylinder: Lamé, small strain\n\nQuarter model, a = {}, b = {}, E = {}, ν = {}, p = {} on the bore (a dead pressure on surface vertices), GIMP, 2×2 points per cell, cells across b. u_r(a), u_r(b) from the least-squares fit of A r + B/r to every point's radial displacement; point-wise: the largest |u_r − Lamé| / Lamé(a).\n", c.inner, c.outer, c.young, c.poisson, c.pressure)?;
    writeln!(
        report.md,
        "| cells | points | u_r(a) error | u_r(b) error | point-wise | wall [s] |\n|---:|---:|---:|---:|---:|---:|"
    )?;
    let mut finest = None;
    for &cells in meshes {
        eprintln!("verify: V6 cylinder, {cells} cells");
        let t = Instant::now();
        let (model, _, _) = solve(c.model(cells, Kinematics::SmallStrain, false), 1)?;
        let e = c.measure(model.points());
        let n = model.points().len();
        writeln!(
            report.md,
            "| {cells} | {n} | {:.3e} | {:.3e} | {:.3e} | {:.3} |",
            e.inner,
            e.outer,
            e.pointwise,
            t.elapsed().as_secs_f64()
        )?;
        finest = Some((cells, e));
    }
    let (cells, e) = finest.expect("at least one mesh");
    let name = format!("V6 Lamé {cells} cells");
    report.rows.push(Row::checked(&name, "u_r(a)_error", e.inner, RADIAL_DISPLACEMENT));
    report.rows.push(Row::checked(&name, "u_r(b)_error", e.outer, RADIAL_DISPLACEMENT));
    follower(quick, report)
}

/// The follower-pressure run: p = E/10 in finite strain, the most Newton corrections of a
/// load step and that step's residuals.
fn follower(quick: bool, report: &mut Report) -> Result<()> {
    let cells = if quick { 20 } else { 40 };
    let c = Cylinder { pressure: 0.1 * Cylinder::REFERENCE.young, ..Cylinder::REFERENCE };
    eprintln!("verify: V6 follower pressure, {cells} cells");
    let t = Instant::now();
    let model = c.model(cells, Kinematics::FiniteStrain, true).with_ghost_penalty(FOLLOWER_GHOST)?;
    let (model, most, residuals) = solve(model, FOLLOWER_STEPS)?;
    let bore = bore_radius(&model);
    let sequence = residuals.iter().map(|r| format!("{r:.2e}")).collect::<Vec<_>>().join(" → ");
    writeln!(report.md, "\n## V6 follower pressure, finite strain\n\np = E/10 on the bore, following the surface (load stiffness in the tangent, LU), Hencky elasticity, {cells} cells, {FOLLOWER_STEPS} load steps, ghost penalty γ = {FOLLOWER_GHOST}. The bore's mean radius grows from {:.3} to {bore:.4}. Most Newton corrections in a load step: **{most}**; that step's relative residuals: {sequence}. Wall {:.2} s.\n", c.inner, t.elapsed().as_secs_f64())?;
    let name = format!("V6 follower {cells} cells");
    report.rows.push(Row::checked(&name, "max_newton_iterations_per_step", most as f64, FOLLOWER_NEWTON_ITERATIONS));
    report.rows.push(Row::info(&name, "bore_mean_radius", bore));
    ring(quick, report)
}

/// Load steps and full pressure over the limit of the axisymmetric ring's collapse run.
const RING_STEPS: usize = 30;
const RING_OVERLOAD: f64 = 1.1;

/// V6 posed axisymmetrically: the ring against Lamé on three meshes, then its collapse
/// pressure (von Mises, B-bar) against 2 c_u ln(b/a).
fn ring(quick: bool, report: &mut Report) -> Result<()> {
    let meshes: &[usize] = if quick { &[8, 16, 32] } else { &[8, 16, 32, 64] };
    let c = Cylinder::REFERENCE;
    writeln!(report.md, "## V6 axisymmetric ring\n\nThe same cylinder as an axisymmetric ring between smooth planes (x the radius), cells across b − a, two high, linear basis, B-bar, 2×2 points per cell, small strain, geometrically linear. Lamé: E = {}, ν = {}, p = {}; point-wise: the largest |u_r − Lamé| / Lamé(a); rate: least-squares slope of ln error against ln h. Collapse: von Mises, c_u = {COHESION}, E = {YOUNG:e}, ν = {POISSON}, the pressure ramped to {RING_OVERLOAD} × 2 c_u ln(b/a) in {RING_STEPS} load steps (each halved up to 8 times), the last converged pressure.\n", c.young, c.poisson, c.pressure)?;
    report.mark_table("V6-ring")?;
    writeln!(report.md, "| cells across b − a | points | Lamé point-wise | collapse / 2 c_u ln(b/a) − 1 | wall [s] |\n|---:|---:|---:|---:|---:|")?;
    let (mut runs, mut limit) = (Vec::new(), 0.0);
    let law = soil::undrained(Elastic::new(YOUNG, POISSON)?, COHESION)?;
    for &cells in meshes {
        eprintln!("verify: V6 axisymmetric ring, {cells} cells");
        let t = Instant::now();
        let elastic = Arc::new(Elastic::new(c.young, c.poisson)?);
        let (model, _, _) = solve(c.ring(cells, elastic), 1)?;
        let error = c.ring_error(model.points());
        let p_lim = c.limit_pressure(COHESION);
        let plastic = Cylinder { pressure: RING_OVERLOAD * p_lim, ..c };
        let settings = QuasiStaticSettings { load_steps: RING_STEPS, ..Default::default() };
        let mut qs = QuasiStatic::new(plastic.ring(cells, law.clone()), settings);
        while !qs.is_finished() && qs.step().is_ok() {}
        limit = qs.load_factor() * RING_OVERLOAD - 1.0;
        let n = model.points().len();
        writeln!(report.md, "| {cells} | {n} | {error:.3e} | {limit:+.2e} | {:.2} |", t.elapsed().as_secs_f64())?;
        runs.push((cells, error));
    }
    writeln!(report.md)?;
    let (cells, error) = *runs.last().expect("at least one mesh");
    let name = format!("V6 axisymmetric ring {cells} cells");
    report.rows.push(Row::checked(&name, "lame_pointwise_error", error, RING_LAME));
    report.rows.push(Row::checked(&name, "lame_rate", observed_rate(&runs), RING_LAME_ORDER));
    report.rows.push(Row::checked(&name, "|collapse/p_lim - 1|", limit.abs(), RING_LIMIT));
    sphere(quick, report)
}

/// Ghost penalty of the thick sphere's collapse runs: its curved faces cut the cells.
const SPHERE_GHOST: f64 = 0.1;

/// V6's thick sphere, axisymmetric: Lamé on three meshes, then the collapse pressure
/// (von Mises, B-bar, ghost penalty) against 2 σ_y ln(b/a).
fn sphere(quick: bool, report: &mut Report) -> Result<()> {
    let meshes: &[usize] = &[16, 32, 64];
    let s = ThickSphere::REFERENCE;
    writeln!(report.md, "## V6 thick sphere, axisymmetric\n\na = {}, b = {}, a quarter of the meridian plane, its arcs polygons of 64 sides, linear basis, B-bar, 2×2 points per cell, small strain, geometrically linear, cells across b − a. Lamé: E = {}, ν = {}, p = {}; u_ρ(a), u_ρ(b) from the least-squares fit of A ρ + B/ρ² to the points' radial displacements. Collapse: von Mises, c_u = {COHESION} (σ_y = √3 c_u), E = {YOUNG:e}, ν = {POISSON}, ghost penalty γ = {SPHERE_GHOST}, the pressure ramped to {RING_OVERLOAD} × 2 σ_y ln(b/a) in {RING_STEPS} load steps, the last converged pressure.\n", s.inner, s.outer, s.young, s.poisson, s.pressure)?;
    report.mark_table("V6-sphere")?;
    writeln!(report.md, "| cells across b − a | points | u_ρ(a) error | u_ρ(b) error | collapse / 2 σ_y ln(b/a) − 1 | wall [s] |\n|---:|---:|---:|---:|---:|---:|")?;
    let law = soil::undrained(Elastic::new(YOUNG, POISSON)?, COHESION)?;
    let p_lim = s.limit_pressure(3f64.sqrt() * COHESION);
    let (mut errors, mut limit) = ((0.0, 0.0), None);
    for &cells in meshes {
        eprintln!("verify: V6 thick sphere, {cells} cells");
        let t = Instant::now();
        let elastic = Arc::new(Elastic::new(s.young, s.poisson)?);
        let (model, _, _) = solve(s.model(cells, elastic, None), 1)?;
        errors = s.measure(model.points());
        // The collapse run on the finer meshes only (the full sweep's finest too).
        let collapse = (cells == 32 || (cells == 64 && !quick)).then(|| {
            let plastic = ThickSphere { pressure: RING_OVERLOAD * p_lim, ..s };
            let settings = QuasiStaticSettings { load_steps: RING_STEPS, ..Default::default() };
            let mut qs = QuasiStatic::new(plastic.model(cells, law.clone(), Some(SPHERE_GHOST)), settings);
            while !qs.is_finished() && qs.step().is_ok() {}
            qs.load_factor() * RING_OVERLOAD - 1.0
        });
        let shown = collapse.map_or("—".to_string(), |c| format!("{c:+.2e}"));
        let n = model.points().len();
        writeln!(
            report.md,
            "| {cells} | {n} | {:.3e} | {:.3e} | {shown} | {:.2} |",
            errors.0,
            errors.1,
            t.elapsed().as_secs_f64()
        )?;
        limit = collapse.map(|c| (cells, c)).or(limit);
    }
    writeln!(report.md)?;
    let name = format!("V6 thick sphere {} cells", meshes[meshes.len() - 1]);
    report.rows.push(Row::checked(&name, "u_rho(a)_error", errors.0, SPHERE_LAME));
    report.rows.push(Row::checked(&name, "u_rho(b)_error", errors.1, SPHERE_LAME));
    let (cells, c) = limit.expect("a collapse run");
    report.rows.push(Row::checked(
        format!("V6 thick sphere collapse {cells} cells"),
        "|collapse/p_lim - 1|",
        c.abs(),
        SPHERE_LIMIT,
    ));
    cavity(quick, report)
}

/// Load steps of the cavity expansion, its full pressure over the infinite soil's limit,
/// and its ghost penalty (the bore sweeps through the grid).
const CAVITY_STEPS: usize = 40;
const CAVITY_OVERLOAD: f64 = 1.05;
const CAVITY_GHOST: f64 = 0.1;
/// Newton's relative residual tolerance for the cavity: near-incompressible Hencky
/// elasticity (ν = 0.49) leaves a round-off floor of about 1e-9 of the first step's load
/// (measured at 8 cells: 1 → 4.6e-2 → 6.2e-7 → 1.2e-9, then no lower), which the default
/// 1e-9 does not always clear.
const CAVITY_RESIDUAL_TOLERANCE: f64 = 1e-8;

/// V6's spherical cavity expanded from a small radius: the follower pressure on the bore
/// ramped to `CAVITY_OVERLOAD` × (4/3) c (1 + ln(G/c)) until the run stops; the most it
/// carried against that limit and against the outer face's peak, how far the bore grew,
/// and the pressure along the way against the closed form at the bore's radius. The bound
/// is checked at 8 cells per a₀ (the full sweep); the 4-cell rows are info.
fn cavity(quick: bool, report: &mut Report) -> Result<()> {
    let meshes: &[usize] = if quick { &[4] } else { &[4, 8] };
    let s = SphericalCavity::REFERENCE;
    let (p_lim, (p_peak, a_peak)) = (s.limit_pressure(), s.peak());
    let full = CAVITY_OVERLOAD * p_lim;
    writeln!(report.md, "## V6 spherical cavity, large deformation\n\na₀ = {}, b = {}, Tresca (von Mises σ_y = 2c), c = {}, G = {} (G/c = {}), ν = {}; points on rings half a cell apart, linear basis, F-bar in finite strain, ghost penalty γ = {CAVITY_GHOST}, a follower pressure on the bore ramped to {CAVITY_OVERLOAD} × (4/3) c (1 + ln(G/c)) = {full:.3} in {CAVITY_STEPS} load steps; the most carried. The outer face at b puts the closed form's peak at {p_peak:.4} (a = {a_peak:.3} a₀), {:+.2} % of the infinite soil's limit {p_lim:.4}. Curve: the largest |p − p(a)| / p_lim over the converged steps, a the bore's mean radius.\n", s.inner, s.outer, s.cohesion, s.shear_modulus, s.shear_modulus / s.cohesion, s.poisson, 100.0 * (p_peak / p_lim - 1.0))?;
    report.mark_table("V6-cavity")?;
    writeln!(report.md, "| cells per a₀ | points | carried / limit − 1 | carried / peak − 1 | a / a₀ | curve | wall [s] |\n|---:|---:|---:|---:|---:|---:|---:|")?;
    let law: Arc<dyn ConstitutiveLaw> =
        Arc::new(VonMises::new(Elastic::new(s.young(), s.poisson)?, 2.0 * s.cohesion, 0.0)?);
    for &cells in meshes {
        eprintln!("verify: V6 spherical cavity, {cells} cells per a0");
        let t = Instant::now();
        let model = s.model(cells, law.clone(), full, Some(CAVITY_GHOST), Kinematics::FiniteStrain);
        let n = model.points().len();
        let mut settings = QuasiStaticSettings { load_steps: CAVITY_STEPS, ..Default::default() };
        settings.newton.residual_tolerance = CAVITY_RESIDUAL_TOLERANCE;
        let mut qs = QuasiStatic::new(model, settings);
        let mut curve: f64 = 0.0;
        while !qs.is_finished() && qs.step().is_ok() {
            let (p, a) = (qs.load_factor() * full, bore_radius(qs.model()));
            curve = curve.max((p - s.pressure_at(a)).abs() / p_lim);
        }
        let carried = qs.load_factor() * full;
        let a = bore_radius(qs.model()) / s.inner;
        let (to_limit, to_peak) = (carried / p_lim - 1.0, carried / p_peak - 1.0);
        let wall = t.elapsed().as_secs_f64();
        writeln!(report.md, "| {cells} | {n} | {to_limit:+.2e} | {to_peak:+.2e} | {a:.3} | {curve:.2e} | {wall:.2} |")?;
        let name = format!("V6 spherical cavity {cells} cells");
        if cells == 8 {
            report.rows.push(Row::checked(&name, "|carried/limit - 1|", to_limit.abs(), CAVITY_LIMIT));
        } else {
            report.rows.push(Row::info(&name, "carried/limit - 1", to_limit));
        }
        report.rows.push(Row::info(&name, "bore radius / a0", a));
        report.rows.push(Row::info(&name, "curve error", curve));
    }
    writeln!(report.md)?;
    Ok(())
}
