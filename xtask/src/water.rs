//! V7, static groundwater (docs/verification.md §V7): the column with a water table
//! half-way up in large deformation against hydrostatics (V1's e_σ and bounds, for the
//! effective and the total stress, and the pore pressures), the submerged column in small
//! strain, and a c–φ slope under water, whose factor of safety must be that of the dry
//! slope with the buoyant unit weight.

use crate::columns::observed_rate;
use crate::report::{Report, Row};
use crate::soil::{POISSON, YOUNG};
use anyhow::Result;
use loam::analysis::{StrengthReduction, TrialStart};
use loam::constitutive::{ConstitutiveLaw, Elastic, MohrCoulomb};
use loam::implicit::{AntiLocking, Kinematics, QuasiStatic, QuasiStaticSettings};
use loam::model::{Model, PhreaticLevel, Water};
use loam_verification::column::bounds::{GIMP_E_SIGMA_64, GIMP_RATE};
use loam_verification::slope::bounds::SUBMERGED_SLOPE;
use loam_verification::{slope_model, SlopeGeometry, WaterColumn, WaterColumnErrors};
use std::fmt::Write as _;
use std::sync::Arc;
use std::time::Instant;

/// Load steps of the half-submerged column: enough that the path error of updated
/// Lagrangian MPM stays below the spatial error at 128 cells (docs/verification.md §V7: at
/// 128 cells e_σ is 3.61e-4 with 10 steps, 1.83e-4 with 40, 1.68e-4 with 160).
const HALF_STEPS: usize = 40;

/// Run `model` in `load_steps` steps and measure it against `column`.
fn run_column(column: &WaterColumn, model: Model<2>, load_steps: usize) -> Result<WaterColumnErrors> {
    let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps, ..Default::default() });
    while !qs.is_finished() {
        qs.step()?;
    }
    let m = qs.model();
    let pore: Vec<f64> = (0..m.points().len()).map(|p| m.pore_pressure(p, 1.0)).collect();
    Ok(column.errors(m.points(), &pore, m.geometrically_linear()))
}

/// One column on the mesh sequence: its table, and (when `bounded`) V1's bounds on the
/// effective and total stress, and the pore pressures exact.
fn column_section(
    report: &mut Report,
    meshes: &[usize],
    case: (&str, &WaterColumn, Kinematics, usize),
    bounded: bool,
) -> Result<()> {
    let (name, column, kinematics, steps) = case;
    writeln!(
        report.md,
        "| cells | e_σ effective | e_σ total | pore pressure | wall [s] |\n|---:|---:|---:|---:|---:|"
    )?;
    let (mut runs, mut worst_pore) = (Vec::new(), 0.0f64);
    for &cells in meshes {
        eprintln!("verify: {name}, {cells} cells");
        let t = Instant::now();
        let e = run_column(column, column.model(cells, kinematics), steps)?;
        writeln!(
            report.md,
            "| {cells} | {:.3e} | {:.3e} | {:.1e} | {:.3} |",
            e.effective,
            e.total,
            e.pore_pressure,
            t.elapsed().as_secs_f64()
        )?;
        runs.push((cells, e));
        worst_pore = worst_pore.max(e.pore_pressure);
    }
    let last3 = &runs[runs.len().saturating_sub(3)..];
    let rate =
        |f: fn(&WaterColumnErrors) -> f64| observed_rate(&last3.iter().map(|(c, e)| (*c, f(e))).collect::<Vec<_>>());
    let (rate_eff, rate_tot) = (rate(|e| e.effective), rate(|e| e.total));
    writeln!(
        report.md,
        "\nObserved rate over the finest three meshes: effective {rate_eff:.2}, total {rate_tot:.2}.\n"
    )?;
    let at64 = runs.iter().find(|(c, _)| *c == 64).map(|(_, e)| *e);
    let bound = |b| bounded.then_some(b);
    report.rows.push(Row::new(name, "rate_e_sigma_effective", rate_eff, bound(GIMP_RATE)));
    report.rows.push(Row::new(name, "rate_e_sigma_total", rate_tot, bound(GIMP_RATE)));
    if let Some(e) = at64 {
        report.rows.push(Row::new(name, "e_sigma_effective_64", e.effective, bound(GIMP_E_SIGMA_64)));
        report.rows.push(Row::new(name, "e_sigma_total_64", e.total, bound(GIMP_E_SIGMA_64)));
    }
    report.rows.push(Row::new(
        name,
        "pore_pressure_error",
        worst_pore,
        bound(loam_verification::water::bounds::PORE_PRESSURE),
    ));
    Ok(())
}

/// The V7 section of the report.
pub(crate) fn verify(quick: bool, report: &mut Report) -> Result<()> {
    let meshes: &[usize] = if quick { &[8, 16, 32, 64] } else { &[8, 16, 32, 64, 128] };
    writeln!(report.md, "## V7 water: the half-submerged column, large deformation\n\nV1's column (H = 10, 2×2 points per cell, GIMP, rollers), ρ_sat = 2, g = 10, E = 5e3 (γ_sat H / E = 0.04, as V1a), Hencky in {HALF_STEPS} load steps; water table at H/2, γ_w = 10. Closed forms: σ_v = −γ_sat (H − Y) at initial height Y, p_w = γ_w (H/2 − y)⁺ at the current height, σ′_v = σ_v + p_w. e_σ as V1's, over the largest total stress; pore pressure: the largest |p_w − hydrostatic| / γ_w h_w.\n")?;
    column_section(
        report,
        meshes,
        ("V7 half-submerged column", &WaterColumn::HALF, Kinematics::FiniteStrain, HALF_STEPS),
        true,
    )?;
    writeln!(report.md, "## V7 water: the submerged column, small strain\n\nThe same column under 2 of water, small strain, geometrically linear, one load step (the first-order sampling error of V1a-small, docs/verification.md §V1, is expected; not bounded).\n")?;
    column_section(
        report,
        meshes,
        ("V7 submerged column", &WaterColumn::SUBMERGED, Kinematics::SmallStrain, 1),
        false,
    )?;
    submerged_slope(quick, report)
}

/// The Griffiths & Lane slope under water (level above the crest, γ_sat = 20) against the
/// dry slope with γ′ = 10: the same factor of safety.
fn submerged_slope(quick: bool, report: &mut Report) -> Result<()> {
    let cells = if quick { 5 } else { 10 };
    let g = SlopeGeometry::GRIFFITHS_LANE;
    let law: Arc<dyn ConstitutiveLaw> =
        Arc::new(MohrCoulomb::from_degrees(Elastic::new(YOUNG, POISSON)?, 10.0, 20.0, 0.0)?);
    let srf = StrengthReduction {
        trial: QuasiStaticSettings { load_steps: 10, max_cutbacks: 4, ..Default::default() },
        bracket: (1.0, 3.0),
        tolerance: 0.005,
        start: TrialStart::LastHeld,
    };
    eprintln!("verify: V7 submerged slope, {cells} cells per H");
    let t = Instant::now();
    let dry = srf.factor_of_safety(&slope_model(&g, law.clone(), 1.0, 10.0, cells, AntiLocking::BBar), |_, _| {})?;
    let wet = slope_model(&g, law, 2.0, 10.0, cells, AntiLocking::BBar);
    let level = (g.depth + 1.0) * g.height + 0.5 * g.height / cells as f64;
    let water = Water::new(10.0, PhreaticLevel::Horizontal(level), wet.gravity()).map_err(anyhow::Error::msg)?;
    let wet = wet.with_water(water)?;
    let wet = srf.factor_of_safety(&wet, |_, _| {})?;
    let rel = wet.value() / dry.value() - 1.0;
    writeln!(report.md, "## V7 water: the submerged slope\n\nThe Griffiths & Lane slope (V4b: c = 10, φ = 20°, ψ = 0), {cells} cells per H, B-bar, entirely under water (level {level} above the crest, ρ_sat = 2, γ_w = 10), against the same slope dry with γ′ = γ_sat − γ_w = 10. Strength reduction between 1 and 3 to 0.005, 10 load steps per trial. With static water the pore pressures change nothing but the weight: the factors must agree.\n\n| slope | F (bracket) |\n|---|---:|\n| dry, γ′ = 10 | {:.4} ({:.4}–{:.4}) |\n| submerged, γ_sat = 20 | {:.4} ({:.4}–{:.4}) |\n\nRelative difference {rel:+.2e}; wall {:.1} s.\n", dry.value(), dry.stable, dry.failed, wet.value(), wet.stable, wet.failed, t.elapsed().as_secs_f64())?;
    report.rows.push(Row::checked(
        format!("V7 submerged slope {cells}/H"),
        "|F_wet/F_dry - 1|",
        rel.abs(),
        SUBMERGED_SLOPE,
    ));
    Ok(())
}
