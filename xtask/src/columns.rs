//! V1 self-weight columns (docs/verification.md §V1): each case (V1a, V1a with small-strain
//! kinematics, V1b in 3D, V1c in large deformation) on a mesh sequence with every basis and
//! the updated Lagrangian FEM reference, the surcharged columns (V1a+q, V1c+q: a dead
//! pressure of half the column's weight on its top face) with GIMP, the observed rate of e_σ, the Newton residuals of
//! V1c and its load-step sensitivity. Writes the first sections of the report and
//! `convergence.svg`.

use crate::report::{Report, Row};
use anyhow::Result;
use loam::format::output::plot::{Plot, Series};
use loam::grid::BasisKind;
use loam::implicit::{Kinematics, QuasiStatic, QuasiStaticSettings};
use loam::model::Model;
use loam_verification::column::bounds::{GIMP_E_SIGMA_64, GIMP_RATE, V1C_NEWTON_ITERATIONS};
use loam_verification::{column_errors, column_fem_model, column_model, Column, ColumnErrors};
use std::fmt::Write as _;
use std::time::Instant;

/// Load steps of the large-deformation columns. Updated-Lagrangian MPM accumulates F
/// step by step, so the result carries a load-step (path) error besides the spatial one;
/// 160 steps puts it below the spatial error of the finest mesh (the report's load-step
/// table shows 160 and 320 steps agreeing within a few percent).
const LARGE_DEFORMATION_STEPS: usize = 160;

/// Every case runs with these, in this order (V1a-small skips the linear basis; the
/// axisymmetric column runs for the 2D cases).
const METHODS: [Method; 5] = [
    Method::Mpm(BasisKind::Gimp),
    Method::Axisymmetric,
    Method::Mpm(BasisKind::QuadraticBSpline),
    Method::Mpm(BasisKind::Linear),
    Method::Fem,
];

const GIMP: Method = Method::Mpm(BasisKind::Gimp);

/// What the report says of the UL-FEM reference under its table.
const FEM_NOTE: &str = " Updated Lagrangian FEM reference: one bilinear (trilinear) element per cell, 2×2(×2) Gauss points as the points, the mesh moving with the body. Its e_σ is dominated by sampling a piecewise-constant element stress at the Gauss points, ρg·h/(2√3) per point, so it falls at rate 1; its displacement is second order.";

/// One run of a column on one mesh.
struct ColumnRun {
    cells: usize,
    e_sigma: f64,
    e_top: f64,
    max_iterations: usize,
    wall_s: f64,
    last_residuals: Vec<f64>,
}

#[derive(Clone, Copy)]
struct Case {
    id: &'static str,
    title: &'static str,
    column: Column,
    dim: usize,
    kinematics: Kinematics,
    load_steps: usize,
    width: fn(&Column, usize) -> f64,
    reference: fn(&Column, f64) -> f64,
    reference_name: &'static str,
    /// Bounds apply (GIMP only): rate over the finest three meshes and e_σ at 64 cells.
    bounded: bool,
}

impl Case {
    /// A 2D square-celled column in finite strain against the Hencky closed form.
    fn hencky(id: &'static str, title: &'static str, column: Column, load_steps: usize, bounded: bool) -> Self {
        Case {
            id,
            title,
            column,
            dim: 2,
            kinematics: Kinematics::FiniteStrain,
            load_steps,
            width: |c, cells| c.height / cells as f64,
            reference: |c, y| c.hencky_displacement(y),
            reference_name: "Hencky (Lambert W)",
            bounded,
        }
    }

    /// The case's errors against its closed form at the points of a finished run.
    fn errors<const D: usize>(&self, model: &Model<D>) -> ColumnErrors {
        column_errors(model.points(), &self.column, 1, |y| (self.reference)(&self.column, y))
    }
}

/// The surcharge of the surcharged columns, as a fraction of the column's weight ρ₀gH₀.
const SURCHARGE_RATIO: f64 = 0.5;

/// Load steps of V1c+q: it compresses further than V1c (s up to 3 against 2), and at 128
/// cells its e_σ is 7.75e-5 with 160 steps, 7.10e-5 with 320 and 7.17e-5 with 640 — 320
/// put the path error below the spatial error of the finest mesh (docs/verification.md §V1).
const SURCHARGED_LARGE_DEFORMATION_STEPS: usize = 320;

/// The column cases of the report, in its order.
fn cases() -> [Case; 6] {
    [
        Case::hencky("V1a", "small deformation, 2D, Hencky", Column::V1A, 10, true),
        Case {
            kinematics: Kinematics::SmallStrain,
            reference: |c, y| c.small_strain_displacement(y),
            reference_name: "linear elasticity",
            ..Case::hencky(
                "V1a-small",
                "small deformation, 2D, small-strain kinematics in one load step",
                Column::V1A,
                1,
                false,
            )
        },
        Case {
            dim: 3,
            width: |_, _| 0.4,
            ..Case::hencky(
                "V1b",
                "large deformation, 3D (0.4 x 0.4 base), Hencky",
                Column::V1B,
                LARGE_DEFORMATION_STEPS,
                false,
            )
        },
        Case::hencky("V1c", "large deformation, 2D, Hencky", Column::V1C, LARGE_DEFORMATION_STEPS, true),
        Case {
            reference_name: "Hencky (Lambert W) with the surcharge",
            ..Case::hencky(
                "V1a+q",
                "small deformation, 2D, Hencky, surcharge q = ρ₀gH₀/2 on the top face (a dead pressure on surface vertices)",
                Column::V1A.surcharged(SURCHARGE_RATIO),
                10,
                true,
            )
        },
        Case {
            reference_name: "Hencky (Lambert W) with the surcharge",
            ..Case::hencky(
                "V1c+q",
                "large deformation, 2D, Hencky, surcharge q = ρ₀gH₀/2 on the top face (a dead pressure on surface vertices)",
                Column::V1C.surcharged(SURCHARGE_RATIO),
                SURCHARGED_LARGE_DEFORMATION_STEPS,
                true,
            )
        },
    ]
}

/// How the column is discretised: MPM with a basis, or the updated Lagrangian FEM
/// reference (one element per cell, 2×2(×2) Gauss points).
#[derive(Clone, Copy, PartialEq)]
enum Method {
    Mpm(BasisKind),
    /// GIMP on the column read as a cylinder of radius one cell (docs/theory.md §20), in a
    /// smooth tube: with ν = 0 the same closed form.
    Axisymmetric,
    Fem,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::Mpm(basis) => basis_name(basis),
            Method::Axisymmetric => "GIMP axisymmetric",
            Method::Fem => "UL-FEM",
        }
    }

    fn column<const D: usize>(self, case: &Case, width: f64, cells: usize) -> Model<D> {
        match self {
            Method::Mpm(basis) => column_model::<D>(&case.column, width, cells, 2, basis, case.kinematics),
            Method::Axisymmetric => column_model::<D>(&case.column, width, cells, 2, BasisKind::Gimp, case.kinematics)
                .with_axisymmetry()
                .expect("a 2D column on the axis"),
            Method::Fem => column_fem_model::<D>(&case.column, width, cells, 2, case.kinematics),
        }
    }
}

/// How the reports name a basis.
pub(crate) fn basis_name(basis: BasisKind) -> &'static str {
    match basis {
        BasisKind::Gimp => "GIMP",
        BasisKind::Linear => "linear",
        BasisKind::QuadraticBSpline => "B-spline",
    }
}

fn run_column(case: &Case, method: Method, cells: usize) -> Result<ColumnRun> {
    let width = (case.width)(&case.column, cells);
    let t = Instant::now();
    let (errors, max_iterations, last_residuals) = match case.dim {
        3 => solve::<3>(case, method.column::<3>(case, width, cells))?,
        _ => solve::<2>(case, method.column::<2>(case, width, cells))?,
    };
    Ok(ColumnRun {
        cells,
        e_sigma: errors.stress,
        e_top: errors.top_displacement,
        max_iterations,
        wall_s: t.elapsed().as_secs_f64(),
        last_residuals,
    })
}

/// Load the column in the case's load steps: its errors, the most Newton iterations of a
/// step and the last step's residuals.
fn solve<const D: usize>(case: &Case, model: Model<D>) -> Result<(ColumnErrors, usize, Vec<f64>)> {
    let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps: case.load_steps, ..Default::default() });
    let mut max_its = 0;
    let mut last = Vec::new();
    while !qs.is_finished() {
        let r = qs.step()?;
        max_its = max_its.max(r.iterations);
        last = r.residuals;
    }
    Ok((case.errors(qs.model()), max_its, last))
}

/// Least-squares slope of ln e against ln h over (cells, e) pairs (h ∝ 1/cells).
pub(crate) fn observed_rate(runs: &[(usize, f64)]) -> f64 {
    let pts: Vec<(f64, f64)> = runs.iter().map(|&(cells, e)| ((1.0 / cells as f64).ln(), e.ln())).collect();
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx).powi(2)).sum();
    sxy / sxx
}

/// The column sections of the report and `convergence.svg`.
pub(crate) fn verify(quick: bool, report: &mut Report) -> Result<()> {
    writeln!(
        report.md,
        "Mode: {}. Columns of docs/verification.md §V1, 2x2(x2) points per cell, ν = 0, rollers on sides and base.",
        if quick { "quick (CI subset)" } else { "full" }
    )?;
    writeln!(report.md, "e_σ = Σ|σ_yy − σ_yy(Y)|V⁰ / (ΣV⁰ (q + ρ₀gH₀)), q the surcharge (zero but in V1a+q and V1c+q); e_u = relative error of the highest point's displacement; rate = least-squares slope of ln e_σ against ln h over the finest three meshes.\n")?;
    let mut plot = Plot {
        log_x: true,
        log_y: true,
        reference_slopes: vec![(-2.0, "rate 2".into()), (-1.5, "rate 1.5".into())],
        ..Plot::new("V1 self-weight column: stress error against mesh", "cells over the column height", "e_σ")
    };
    let mut residual_doc = String::new();
    let cases = cases();
    for case in &cases {
        for method in METHODS {
            if case.id == "V1a-small" && method == Method::Mpm(BasisKind::Linear) {
                continue;
            }
            if method == Method::Axisymmetric && case.dim != 2 {
                continue;
            }
            // The surcharged columns check the loads, which one basis does; the FEM
            // reference takes no surface loads yet.
            if case.column.surcharge != 0.0 && method != GIMP {
                continue;
            }
            let runs = case_section(quick, report, case, method)?;
            let finest = runs.last().unwrap();
            if case.id == "V1c" && method == GIMP {
                writeln!(
                    residual_doc,
                    "Newton residuals of the last load step of V1c (GIMP, {} cells): {}",
                    finest.cells,
                    finest.last_residuals.iter().map(|r| format!("{r:.2e}")).collect::<Vec<_>>().join(" → ")
                )?;
            }
            let name = format!("{} {}", case.id, method.name());
            let series = Series::new(name, runs.iter().map(|r| (r.cells as f64, r.e_sigma)).collect());
            plot.series.push(if method == GIMP { series } else { series.dashed() });
        }
    }
    writeln!(report.md, "## Newton convergence\n\n{residual_doc}")?;
    load_step_study(quick, report, cases.iter().find(|c| c.id == "V1c").expect("V1c case"))?;
    plot.write(&report.out.join("convergence.svg"))?;
    Ok(())
}

/// One case with one method on its mesh sequence: the section's table, its observed rate
/// and its rows of the bounds table; returns the runs.
fn case_section(quick: bool, report: &mut Report, case: &Case, method: Method) -> Result<Vec<ColumnRun>> {
    let mesh: &[usize] = match (case.dim, quick) {
        (3, true) => &[4, 8, 16, 32],
        (3, false) => &[4, 8, 16, 32, 64],
        (_, true) => &[8, 16, 32, 64],
        (_, false) => &[4, 8, 16, 32, 64, 128],
    };
    let name = format!("{} {}", case.id, method.name());
    eprintln!("verify: {name} on {mesh:?} cells");
    let runs: Vec<ColumnRun> = mesh.iter().map(|&n| run_column(case, method, n)).collect::<Result<_>>()?;
    let md = &mut report.md;
    let fem_note = if method == Method::Fem { FEM_NOTE } else { "" };
    writeln!(md, "## {name}: {}\n\nReference: {}.{fem_note}\n", case.title, case.reference_name)?;
    writeln!(md, "| cells | e_σ | e_u (top) | max Newton its/step | wall time [s] |\n|---:|---:|---:|---:|---:|")?;
    for r in &runs {
        writeln!(md, "| {} | {:.3e} | {:.3e} | {} | {:.4} |", r.cells, r.e_sigma, r.e_top, r.max_iterations, r.wall_s)?;
    }
    let last3: Vec<&ColumnRun> = runs.iter().rev().take(3).rev().collect();
    let rate = observed_rate(&last3.iter().map(|r| (r.cells, r.e_sigma)).collect::<Vec<_>>());
    writeln!(
        md,
        "\nObserved rate over {:?} cells: **{rate:.2}**\n",
        last3.iter().map(|r| r.cells).collect::<Vec<_>>()
    )?;
    push_rows(report, &name, case, method, &runs, rate);
    Ok(runs)
}

/// The bounds table's rows of one case and method: GIMP's rate and e_σ at 64 cells are
/// checked where the case is bounded, V1c's Newton iterations always.
fn push_rows(report: &mut Report, name: &str, case: &Case, method: Method, runs: &[ColumnRun], rate: f64) {
    // The axisymmetric column is held to the plane GIMP column's bounds.
    let gimp_bounded = case.bounded && (method == GIMP || method == Method::Axisymmetric);
    let rows = &mut report.rows;
    rows.push(Row::new(name, "rate_e_sigma", rate, gimp_bounded.then_some(GIMP_RATE)));
    if let Some(r64) = runs.iter().find(|r| r.cells == 64) {
        rows.push(Row::new(name, "e_sigma_64", r64.e_sigma, gimp_bounded.then_some(GIMP_E_SIGMA_64)));
        rows.push(Row::info(name, "e_u_64", r64.e_top));
    }
    let finest = runs.last().unwrap();
    if finest.cells != 64 {
        rows.push(Row::info(name, format!("e_sigma_{}", finest.cells), finest.e_sigma));
    }
    let max_its = runs.iter().map(|r| r.max_iterations).max().unwrap_or(0);
    let newton_bound = (case.id == "V1c").then_some(V1C_NEWTON_ITERATIONS);
    rows.push(Row::new(name, "max_newton_iterations_per_step", max_its as f64, newton_bound));
    rows.push(Row::info(name, "wall_time_total_s", runs.iter().map(|r| r.wall_s).sum()));
}

/// Load-step sensitivity of V1c (GIMP): the path error of updated-Lagrangian MPM.
fn load_step_study(quick: bool, report: &mut Report, v1c: &Case) -> Result<()> {
    let study_cells = if quick { 64 } else { 128 };
    writeln!(report.md, "\n## Load-step sensitivity (V1c, GIMP, {study_cells} cells)\n\n| load steps | e_σ | e_u (top) | wall time [s] |\n|---:|---:|---:|---:|")?;
    for steps in [10, 40, 160, 320] {
        let case = Case { load_steps: steps, ..*v1c };
        let r = run_column(&case, GIMP, study_cells)?;
        writeln!(report.md, "| {steps} | {:.3e} | {:.3e} | {:.4} |", r.e_sigma, r.e_top, r.wall_s)?;
        report.rows.push(Row::info(
            format!("V1c GIMP {study_cells} cells"),
            format!("e_sigma_{steps}_steps"),
            r.e_sigma,
        ));
    }
    writeln!(report.md)?;
    Ok(())
}
