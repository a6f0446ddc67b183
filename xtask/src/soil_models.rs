//! Soil models (docs/verification.md, Soil models): Modified Cam clay's element tests
//! against the closed-form undrained path and an independent drained reference
//! (`loam_verification::cam_clay`), and its compression lines.

use crate::report::{Report, Row};
use anyhow::Result;
use loam::constitutive::{CamClayInitial, CamClayShear, ElementPath, ElementTest, Held, ModifiedCamClay};
use loam_verification::cam_clay::bounds::{COMPRESSION_LINES, DRAINED_PATH, UNDRAINED_FAILURE};
use loam_verification::cam_clay::{largest_q_difference, q_at, CamClayParameters};
use nalgebra::Matrix3;
use std::fmt::Write as _;

/// A soft clay: λ = 0.2, κ = 0.04, e₀ = 1.5, M = 1, ν = 0.25, from p′₀ = 100.
const CLAY: CamClayParameters = CamClayParameters { lambda: 0.2, kappa: 0.04, void_ratio: 1.5, m: 1.0, poisson: 0.25 };
const P0: f64 = 100.0;

fn law(ocr: f64) -> Result<ModifiedCamClay> {
    let c = CLAY;
    let (shear, initial) = (CamClayShear::Poisson(c.poisson), CamClayInitial::OverConsolidation(ocr));
    Ok(ModifiedCamClay::new(c.lambda, c.kappa, c.void_ratio, c.m, shear, initial)?)
}

/// `steps` equal steps of `path` to `strain`, the (ε_a, q) after each, and the point.
fn drive(
    law: &ModifiedCamClay,
    path: ElementPath,
    strain: f64,
    steps: usize,
) -> Result<(Vec<(f64, f64)>, ElementTest<'_>)> {
    let start = Matrix3::identity() * -P0;
    let mut t = ElementTest::new(law, start)?;
    let mut out = Vec::with_capacity(steps);
    let held = path.held(strain / steps as f64, &start);
    for _ in 0..steps {
        t.step(held)?;
        out.push((-t.strain()[(2, 2)], t.p_q().1));
    }
    Ok((out, t))
}

pub fn verify(_quick: bool, report: &mut Report) -> Result<()> {
    writeln!(report.md, "## Soil models: Modified Cam clay element tests\n\nλ = {}, κ = {}, e₀ = {}, M = {}, ν = {} (G follows p), from p′₀ = {P0} (`loam_constitutive::ElementTest`). Undrained triaxial to 30 % axial strain in 600 steps against the closed-form critical state; drained triaxial (normally consolidated) to 20 % against a stress-controlled RK4 integration of the continuum rates (20 000 steps), the largest |q/q_ref − 1| along the path; isotropic compression and unloading against λ and κ.\n", CLAY.lambda, CLAY.kappa, CLAY.void_ratio, CLAY.m, CLAY.poisson)?;
    report.mark_table("soil")?;
    writeln!(report.md, "| test | steps | loam | reference | relative difference |\n|---|---:|---:|---:|---:|")?;
    for ocr in [1.0, 1.5] {
        let law = law(ocr)?;
        let (_, t) = drive(&law, ElementPath::TriaxialUndrained, 0.3, 600)?;
        let pf = CLAY.undrained_failure(P0, ocr * P0);
        let (p, q) = t.p_q();
        let rel = (p / pf - 1.0).abs().max((q / (CLAY.m * pf) - 1.0).abs());
        writeln!(
            report.md,
            "| undrained, OCR {ocr}: p′, q at 30 % | 600 | {p:.4}, {q:.4} | {pf:.4}, {:.4} | {rel:.1e} |",
            CLAY.m * pf
        )?;
        report.rows.push(Row::checked(
            format!("Cam clay undrained OCR {ocr}"),
            "critical_state_difference",
            rel,
            UNDRAINED_FAILURE,
        ));
    }
    let reference = CLAY.drained_triaxial(P0, 149.0, 20_000);
    let law = law(1.0)?;
    for steps in [2_000, 8_000] {
        let (path, _) = drive(&law, ElementPath::TriaxialDrained, 0.2, steps)?;
        let worst = largest_q_difference(&path, &reference);
        let (ea, q) = path[path.len() - 1];
        let q_ref = q_at(&reference, ea).unwrap_or(f64::NAN);
        writeln!(
            report.md,
            "| drained, NC: q at {:.0} % (largest difference along the path) | {steps} | {q:.4} | {q_ref:.4} | {worst:.1e} |",
            100.0 * ea
        )?;
        let case = format!("Cam clay drained NC, {steps} steps");
        // The implicit return's error is first order in the step: the bound is on the finer.
        report.rows.push(match steps {
            8_000 => Row::checked(case, "largest_q_difference", worst, DRAINED_PATH),
            _ => Row::info(case, "largest_q_difference", worst),
        });
    }
    compression_lines(report)?;
    writeln!(report.md)?;
    Ok(())
}

/// What each component does in a step of a given increment.
type StepOf<'a> = dyn Fn(f64) -> [Held; 6] + 'a;

/// Isotropic and oedometric compression along the virgin line, then unloading:
/// Δe/Δln p′ = −λ, −κ. The oedometer starts normally consolidated at the stress ratio
/// η_K0 that oedometric flow keeps (ε̇_s/ε̇_v = ⅔ with G following p:
/// η² + 3Λη − M² = 0, Λ = 1 − κ/λ), so its virgin line is exact from the first step.
fn compression_lines(report: &mut Report) -> Result<()> {
    let iso = |d: f64| {
        [Held::Strain(d), Held::Strain(d), Held::Strain(d), Held::Strain(0.0), Held::Strain(0.0), Held::Strain(0.0)]
    };
    let big_lambda = 1.0 - CLAY.kappa / CLAY.lambda;
    let eta = (-3.0 * big_lambda + (9.0 * big_lambda * big_lambda + 4.0 * CLAY.m * CLAY.m).sqrt()) / 2.0;
    let k0 = Matrix3::from_diagonal(&nalgebra::Vector3::new(
        -P0 + eta * P0 / 3.0,
        -P0 + eta * P0 / 3.0,
        -P0 - 2.0 * eta * P0 / 3.0,
    ));
    let oedometer = |d: f64| ElementPath::Oedometer.held(d, &k0);
    let paths: [(&str, Matrix3<f64>, &StepOf<'_>); 2] =
        [("isotropic", Matrix3::identity() * -P0, &iso), ("oedometric", k0, &oedometer)];
    let law = law(1.0)?;
    for (path, start, held) in paths {
        let mut t = ElementTest::new(&law, start)?;
        let e = |t: &ElementTest| CLAY.void_ratio + (1.0 + CLAY.void_ratio) * t.strain().trace();
        let mut points = vec![(e(&t), t.p_q().0)];
        // Isotropic strain increments are per axis (ε_v = 3d); the oedometer's is ε_v itself.
        let (load, unload) = if path == "isotropic" { (-1e-3, 5e-4) } else { (3e-3, -1.5e-3) };
        for (d, n) in [(load, 50), (unload, 20)] {
            for _ in 0..n {
                t.step(held(d))?;
            }
            points.push((e(&t), t.p_q().0));
        }
        let lines = [("virgin line", CLAY.lambda, 50), ("unloading line", CLAY.kappa, 20)];
        for (w, (line, slope, steps)) in points.windows(2).zip(lines) {
            let got = -(w[1].0 - w[0].0) / (w[1].1 / w[0].1).ln();
            let rel = (got / slope - 1.0).abs();
            writeln!(report.md, "| {path} {line}: −Δe/Δln p′ | {steps} | {got:.12} | {slope} | {rel:.1e} |")?;
            report.rows.push(Row::checked(
                format!("Cam clay {path} {line}"),
                "slope_difference",
                rel,
                COMPRESSION_LINES,
            ));
        }
    }
    Ok(())
}
