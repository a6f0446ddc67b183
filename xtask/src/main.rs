//! `cargo xtask verify [--quick] [--update-docs]`: run the verification problems against
//! their closed-form references, report error and wall time, write `target/verify/
//! {report.md, summary.csv, *.svg}` (and the marked tables of docs/verification.md), and
//! exit non-zero when a bound fails.
//! `cargo xtask steps [--quick]`: the implicit-vs-explicit step-size study (`steps.rs`).
//! `cargo xtask bench`: run the criterion benchmarks.

mod columns;
mod contact;
mod dynamics;
mod footing;
mod granular;
mod hard_cases;
mod loads;
mod report;
mod scale;
mod slope;
mod soil;
mod soil_models;
mod steps;
mod tangents;
mod water;

use anyhow::{bail, Context, Result};
use clap::{Parser, Subcommand};
use report::Report;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(Parser)]
#[command(name = "xtask")]
struct Cli {
    #[command(subcommand)]
    command: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Run the verification problems and check their bounds.
    Verify {
        /// CI-sized subset (coarser meshes; same bounds).
        #[arg(long)]
        quick: bool,
        /// Output folder.
        #[arg(long, default_value = "target/verify")]
        out: PathBuf,
        /// Run these sections only (comma separated): columns, dynamics, footing, slope,
        /// hard_cases, loads, water, granular, soil, contact.
        #[arg(long, value_delimiter = ',')]
        only: Vec<String>,
        /// Write the result tables of docs/verification.md marked for this mode from the
        /// report (`docs_tables.rs`).
        #[arg(long)]
        update_docs: bool,
        /// Run the sections, and the strip footing's runs, side by side (CI: the cores stay
        /// busy between runs). The results are the same; the wall times then include the
        /// neighbours' load, so tables for the docs are written without it.
        #[arg(long, conflicts_with = "update_docs")]
        side_by_side: bool,
    },
    /// Implicit vs explicit: error against time step and against wall time (V2, V1c).
    Steps {
        /// Fewer time steps and a coarser column.
        #[arg(long)]
        quick: bool,
        /// Output folder.
        #[arg(long, default_value = "target/steps")]
        out: PathBuf,
    },
    /// The cost of one step of an elastic block at several sizes (`scale.rs`).
    Scale {
        /// Cells a side, comma separated; each size runs in its own process.
        #[arg(long, value_delimiter = ',', default_value = "16,24,32")]
        cells: Vec<usize>,
        /// auto, direct or iterative (as a scene's `linear`), or a method: lu, cholesky, cg,
        /// bicgstab.
        #[arg(long, default_value = "auto")]
        solver: String,
        /// 2 or 3.
        #[arg(long, default_value_t = 3)]
        dim: usize,
        /// The lower half this many times softer (1: uniform).
        #[arg(long, default_value_t = 1.0)]
        contrast: f64,
        /// Instead of the block: examples/slope_3d.ron at cells of this size in m (the
        /// example's own: 2), under gravity at a fixed strength, every load step timed.
        #[arg(long)]
        slope: Option<f64>,
        /// The slope's strength divided by this (c and tan φ).
        #[arg(long, default_value_t = 1.6)]
        factor: f64,
        /// Stop the slope after this many of its load steps (default: all of them).
        #[arg(long)]
        steps: Option<usize>,
    },
    /// Export the systems the iterative solver meets, for other preconditioners
    /// (`tangents.rs`).
    Tangents {
        /// Output folder.
        #[arg(long, default_value = "target/tangents")]
        out: PathBuf,
    },
    /// Run the criterion benchmarks (`cargo bench`), passing any extra arguments on.
    Bench {
        #[arg(trailing_var_arg = true)]
        args: Vec<String>,
    },
}

fn main() -> Result<()> {
    match Cli::parse().command {
        Cmd::Verify { quick, out, only, update_docs, side_by_side } => {
            verify(quick, &out, &only, update_docs, side_by_side)
        }
        Cmd::Steps { quick, out } => steps::run(quick, &out),
        Cmd::Scale { slope: Some(h), factor, steps, solver, .. } => scale::run_slope(h, factor, &solver, steps),
        Cmd::Scale { cells, solver, dim, contrast, .. } => scale::run(dim, &cells, &solver, contrast),
        Cmd::Tangents { out } => tangents::run(&out),
        Cmd::Bench { args } => {
            // The criterion benchmarks, unless the arguments pick their own: the package's
            // `explicit_block` is a profiler's driver that needs a size.
            let picked = args.iter().any(|a| a == "--bench");
            let criterion: &[&str] =
                if picked { &[] } else { &["--bench", "column", "--bench", "explicit", "--bench", "laws"] };
            let status = std::process::Command::new(env!("CARGO"))
                .args(["bench", "--package", "loam-bench"])
                .args(criterion)
                .args(&args)
                .status()
                .context("running cargo bench")?;
            if !status.success() {
                bail!("cargo bench failed");
            }
            Ok(())
        }
    }
}

/// Run every section of the report, write `report.md`, `summary.csv` and the plots, and
/// fail when a bound fails (after writing, so that the report shows which).
fn verify(quick: bool, out: &Path, only: &[String], update_docs: bool, side_by_side: bool) -> Result<()> {
    type Section = fn(bool, &mut Report) -> Result<()>;
    let sections: [(&str, Section); 10] = [
        ("columns", columns::verify),
        ("dynamics", dynamics::verify),
        ("footing", footing::verify),
        ("slope", slope::verify),
        ("hard_cases", hard_cases::verify),
        ("loads", loads::verify),
        ("water", water::verify),
        ("granular", granular::verify),
        ("soil", soil_models::verify),
        ("contact", contact::verify),
    ];
    if let Some(unknown) = only.iter().find(|o| !sections.iter().any(|(name, _)| name == o)) {
        let names: Vec<&str> = sections.iter().map(|(name, _)| *name).collect();
        bail!("no verify section {unknown:?}: the sections are {}", names.join(", "));
    }
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let selected: Vec<Section> =
        sections.iter().filter(|(name, _)| only.is_empty() || only.iter().any(|o| o == name)).map(|s| s.1).collect();
    let run = |section: &Section| -> Result<Report> {
        let mut part = Report::part(out, side_by_side);
        section(quick, &mut part)?;
        Ok(part)
    };
    // Side by side, the sections share the cores: a run's serial stretches (a factorisation,
    // a small problem's assembly) leave a core to the others. Every result is the same with
    // any number of threads; only the wall times include the neighbours' load.
    let parts: Vec<Result<Report>> = report::runs(side_by_side, &selected, run);
    let mut report = Report::new(out)?;
    for part in parts {
        report.append(part?);
    }
    let failed = report.bounds_table()?;
    writeln!(report.md, "\nThe linear (standard MPM) basis carries no bound: it is known not to converge on this problem (cell-crossing error), and the tables above show its stagnation.")?;
    std::fs::write(out.join("report.md"), &report.md)?;
    eprintln!("verify: wrote {}/report.md, summary.csv, convergence.svg", out.display());
    if update_docs {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/verification.md");
        let docs = std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?;
        let (text, ids) = xtask::docs_tables::update(&docs, &report.md, quick)?;
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
        eprintln!("verify: wrote tables {} of docs/verification.md", ids.join(", "));
    }
    if !failed.is_empty() {
        bail!("{} bound(s) failed:\n  {}", failed.len(), failed.join("\n  "));
    }
    eprintln!("verify: all bounds pass");
    Ok(())
}
