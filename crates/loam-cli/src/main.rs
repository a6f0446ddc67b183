//! The `loam` command-line program: run or check a scene file.

use anyhow::Context;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use loam_analysis::StrengthTrial;
use loam_format::checkpoint::Checkpoint;
use loam_run::{
    checkpoint_interval, checkpoint_scene, resume_scene, run_scene_with, CheckpointEvery, CheckpointWritten, Progress,
    RunEvent, RunOptions, RunSummary, CHECKPOINT_FILE,
};
use loam_scene::{LoadedScene, SceneSummary};
use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use tracing_subscriber::filter::LevelFilter;

#[derive(Parser)]
#[command(name = "loam", version, about = "Implicit material point method for geotechnics")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write its outputs (VTU/PVD frames, run_log.csv, history.csv,
    /// points_final.csv).
    Run {
        /// Scene file (RON), see docs/scene-format.md.
        scene: PathBuf,
        /// Output folder [default: out/SCENE, SCENE the scene file's name without extension].
        #[arg(long)]
        out: Option<PathBuf>,
        /// Remove the outputs of another run from the output folder first (only the files
        /// loam writes); without it such a folder is refused. A re-run of the same scene
        /// replaces its own outputs either way.
        #[arg(long)]
        overwrite: bool,
        #[command(flatten)]
        flags: RunFlags,
    },
    /// Go on with an interrupted run from the checkpoint in its output folder: its outputs
    /// end as those of a run that never stopped.
    Resume {
        /// The run's output folder (holding checkpoint.loam).
        dir: PathBuf,
        /// The scene file, where it is no longer where the run read it (it must be the same
        /// text).
        #[arg(long)]
        scene: Option<PathBuf>,
        #[command(flatten)]
        flags: RunFlags,
    },
    /// Draw the plots of a run from the CSV files in its output folder (loam run draws
    /// them at its end too): run_log.svg, load_displacement.svg, energies.svg,
    /// strength_reduction.svg.
    Plot {
        /// The run's output folder.
        dir: PathBuf,
    },
    /// Drive one point of a law along a laboratory path (triaxial, oedometer, simple shear)
    /// and write element.csv (p′, q, strains, stresses, history) with element_strain.svg
    /// and element_pq.svg; see docs/scene-format.md, "Element tests".
    Element {
        /// Element-test file (RON).
        test: PathBuf,
        /// Output folder [default: out/TEST, TEST the file's name without extension].
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Validate a scene completely (down to points and constraints) without running it.
    Check {
        /// Scene file (RON).
        scene: PathBuf,
        /// As for `run`.
        #[arg(long, value_parser = parse_size)]
        max_memory: Option<u64>,
    },
}

/// The flags `loam run` and `loam resume` share.
#[derive(clap::Args, Clone)]
struct RunFlags {
    /// No progress bar, and only errors in the log.
    #[arg(long, short)]
    quiet: bool,
    /// More of the solver's log on stderr: warnings are shown by default; -v adds the
    /// linear solver chosen and each cut-back with its cause, -vv every Newton iteration.
    #[arg(long, short, action = clap::ArgAction::Count, conflicts_with = "quiet")]
    verbose: u8,
    /// The most memory the run may take (e.g. 32G, 500M, 2TiB); a scene estimated above it
    /// is refused before its points are made [default: this machine's memory].
    #[arg(long, value_parser = parse_size)]
    max_memory: Option<u64>,
    /// Stop after this many steps in all, as if the run ended there (a look at the first
    /// steps of a long run).
    #[arg(long)]
    steps: Option<usize>,
    /// Write a checkpoint (checkpoint.loam in the output folder, replaced each time) every
    /// N steps, or at a wall-time interval (90s, 10m, 2h); `loam resume` goes on from it. A
    /// strength-reduction search is saved after each trial [resume's default: as the
    /// interrupted run did].
    #[arg(long, value_name = "N|TIME")]
    checkpoint_every: Option<CheckpointEvery>,
    /// Worker threads of the run; the results are bitwise the same for any number
    /// [default: one per core, or RAYON_NUM_THREADS].
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..))]
    threads: Option<u16>,
}

/// One log line on its way to stderr: written whole, with the progress bar cleared
/// while it is written and drawn again under it.
struct LogLine {
    bar: ProgressBar,
    text: Vec<u8>,
}

impl Write for LogLine {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        self.text.extend_from_slice(buf);
        Ok(buf.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

impl Drop for LogLine {
    fn drop(&mut self) {
        let text = std::mem::take(&mut self.text);
        // A log line that cannot be written is dropped: stderr is gone and the run's
        // outputs matter more.
        self.bar.suspend(|| {
            let _ = std::io::stderr().write_all(&text);
        });
    }
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_chain(&e));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes in one line, each cause once: an error whose message already
/// quotes its source (thiserror's `"output: {0}"` with `#[from]`) is not followed by the
/// source again, as anyhow's `{:#}` would ("X: X").
fn error_chain(e: &anyhow::Error) -> String {
    let mut text = String::new();
    let mut previous = String::new();
    for cause in e.chain() {
        let message = cause.to_string();
        if !previous.contains(&message) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&message);
        }
        previous = message;
    }
    text
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Check { scene, max_memory } => check(&scene, max_memory),
        Command::Plot { dir } => {
            for path in loam_format::plot_run(&dir).with_context(|| format!("plotting the run in {}", dir.display()))? {
                println!("{}", path.display());
            }
            Ok(())
        }
        Command::Element { test, out } => {
            let out = out.unwrap_or_else(|| default_out(&test));
            let loaded = loam_scene::LoadedElementTest::read(&test)?;
            let summary = loam_run::run_element(&loaded, &out)?;
            println!(
                "{}: {} steps, ending at p′ = {:.6e}, q = {:.6e}; outputs in {}",
                test.display(),
                summary.steps,
                summary.p,
                summary.q,
                out.display()
            );
            Ok(())
        }
        Command::Run { scene, out, overwrite, flags } => {
            let out = out.unwrap_or_else(|| default_out(&scene));
            run_command(&scene, &out, &flags, overwrite, None)
        }
        Command::Resume { dir, scene, mut flags } => {
            let path = dir.join(CHECKPOINT_FILE);
            let checkpoint =
                Checkpoint::load(&path).with_context(|| format!("resuming the run in {}", dir.display()))?;
            let scene = match scene {
                Some(scene) => scene,
                None => checkpoint_scene(&checkpoint)?,
            };
            if flags.checkpoint_every.is_none() {
                flags.checkpoint_every = checkpoint_interval(&checkpoint)?;
            }
            run_command(&scene, &dir, &flags, false, Some(checkpoint))
        }
    }
}

/// The default output folder of a file: out/ and its name without extension.
fn default_out(file: &Path) -> PathBuf {
    PathBuf::from("out").join(file.file_stem().map(|s| s.to_owned()).unwrap_or_default())
}

/// `loam check`: build the scene's analysis, every check included, and say what it holds.
fn check(scene: &Path, max_memory: Option<u64>) -> anyhow::Result<()> {
    let loaded = load(scene, max_memory)?;
    let SceneSummary { points, nodal_dofs: dofs } = loaded.check()?;
    println!(
        "{}: ok — {}D, {points} material points, {dofs} nodal dofs at most",
        scene.display(),
        loaded.scene.dimension
    );
    Ok(())
}

/// The scene file read with the memory limit given, its warnings on stderr, one per line.
fn load(scene: &Path, max_memory: Option<u64>) -> anyhow::Result<LoadedScene> {
    let loaded = LoadedScene { memory_limit: max_memory, ..LoadedScene::read(scene)? };
    for w in loaded.warnings() {
        eprintln!("warning: {w}");
    }
    Ok(loaded)
}

/// `loam run` (or `loam resume`, given the `checkpoint` to go on from): the scene run into
/// `out` under a progress bar, the solver's log above it.
fn run_command(
    scene: &Path,
    out: &Path,
    flags: &RunFlags,
    overwrite: bool,
    checkpoint: Option<Checkpoint>,
) -> anyhow::Result<()> {
    let RunFlags { quiet, verbose, max_memory, steps, checkpoint_every, threads } = flags.clone();
    if let Some(threads) = threads {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads.into())
            .build_global()
            .context("starting the worker threads")?;
    }
    let loaded = load(scene, max_memory)?;
    if let loam_scene::AnalysisSpec::QuasiStatic { strength_reduction: Some(srf), .. } = &loaded.scene.analysis {
        if !quiet {
            let (lo, hi, tol) = (srf.bracket.0, srf.bracket.1, srf.tolerance);
            let how = match srf.start {
                loam_scene::TrialStartSpec::LastHeld => {
                    format!("F raised from {lo} towards {hi} from the last state that held, to {tol}")
                }
                loam_scene::TrialStartSpec::Zero => {
                    format!("F bisected between {lo} and {hi}, each trial from zero load, to {tol}")
                }
            };
            println!(
                "strength reduction: {how}; one trial per row in {}",
                out.join("strength_reduction.csv").display()
            );
        }
    }
    let bar = if quiet { ProgressBar::hidden() } else { ProgressBar::new(1000) };
    bar.set_style(
        ProgressStyle::with_template("{spinner} [{elapsed_precise}] {bar:40} {msg}").expect("valid template"),
    );
    install_log(&bar, quiet, verbose);
    let mut trials = 0;
    let run_options = RunOptions { max_steps: steps, overwrite, checkpoint_every };
    let mut progress = |event: RunEvent| match event {
        RunEvent::Step { report, end, done } => show_progress(&bar, report, end, done),
        RunEvent::Trial(t) => {
            trials += 1;
            show_trial(&bar, trials, t, quiet);
        }
        RunEvent::Checkpoint(w) => show_line(&bar, &checkpoint_line(&w, out), quiet),
        RunEvent::Resumed { step, trials: done } => {
            trials = done;
            let at = if step > 0 { format!("after step {step}") } else { format!("after trial {done}") };
            show_line(&bar, &format!("resuming {} {at}", scene.display()), quiet);
        }
        RunEvent::Excavated { stage, step, removed } => {
            show_line(&bar, &format!("excavation {stage} after step {step}: {removed} points removed"), quiet)
        }
    };
    let result = match checkpoint {
        Some(c) => resume_scene(&loaded, c, out, &run_options, &mut progress),
        None => run_scene_with(&loaded, out, &run_options, &mut progress),
    };
    bar.finish_and_clear();
    let summary = result.with_context(|| format!("running {}", scene.display()))?;
    print_summary(scene, &summary);
    Ok(())
}

/// The lines a finished run ends with: a warning if its plots could not be drawn, the
/// factor of safety of a strength reduction, the collapse load of a load-controlled run
/// that reached it, the peak of an arc-length-controlled one, and what the run did.
fn print_summary(scene: &Path, summary: &RunSummary) {
    if let Err(e) = &summary.plots {
        eprintln!("warning: the plots of {} could not be drawn: {e}", summary.output_dir.display());
    }
    if let Some(fos) = &summary.factor_of_safety {
        println!(
            "factor of safety F = {:.4}: holds at {:.4}, fails at {:.4} ({} trials); the run below is at F = {:.4}",
            fos.value(),
            fos.stable,
            fos.failed,
            fos.trials.len(),
            fos.stable
        );
    }
    if let Some(p) = &summary.peak {
        println!(
            "peak: the model carried load factor λ = {:.6} at most (step {}); the arc-length control ended at λ = {:.6} (step {})",
            p.load_factor, p.step, summary.load_factor, summary.steps
        );
        if let Some(c) = &summary.collapse {
            println!("step {} could not go on ({})", c.step, c.reason);
        }
    } else if let Some(c) = &summary.collapse {
        println!(
            "collapse: the model carried load factor λ = {:.6} at most; step {} could not go on to {:.6} ({})",
            c.load_factor, c.step, c.attempted, c.reason
        );
    }
    println!(
        "{}: {} analysis, {} steps, {} points, {} Newton iterations (max {} per step), {} cut-backs, {}, {:.3} s; outputs in {}",
        scene.display(),
        summary.analysis,
        summary.steps,
        summary.points,
        summary.newton_iterations,
        summary.max_iterations_per_step,
        summary.cutbacks,
        summary.solver,
        summary.wall_time.as_secs_f64(),
        summary.output_dir.display()
    );
}

/// A size in bytes: a number with an optional unit K, M, G, T (powers of 1000, also KB ...)
/// or KiB, MiB, GiB, TiB (powers of 1024).
fn parse_size(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let split = t.find(|c: char| c.is_ascii_alphabetic()).unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let value: f64 = number
        .trim()
        .parse()
        .map_err(|_| format!("{text:?} is not a size: give a number and a unit, e.g. 32G or 500MiB"))?;
    let scale = match unit.to_ascii_uppercase().as_str() {
        "" | "B" => 1.0,
        "K" | "KB" => 1e3,
        "M" | "MB" => 1e6,
        "G" | "GB" => 1e9,
        "T" | "TB" => 1e12,
        "KIB" => 1024.0,
        "MIB" => 1024f64.powi(2),
        "GIB" => 1024f64.powi(3),
        "TIB" => 1024f64.powi(4),
        _ => return Err(format!("{unit:?} is not a unit: use K, M, G, T (powers of 1000) or KiB, MiB, GiB, TiB")),
    };
    let bytes = value * scale;
    if !(bytes.is_finite() && bytes >= 1.0 && bytes < u64::MAX as f64) {
        return Err(format!("{text:?}: the size must be at least one byte and finite"));
    }
    Ok(bytes as u64)
}

/// The solver's log on stderr above the progress bar: errors only when quiet, warnings by
/// default, -v information (solver choice, cut-backs), -vv debug (Newton iterations).
fn install_log(bar: &ProgressBar, quiet: bool, verbose: u8) {
    let level = match (quiet, verbose) {
        (true, _) => LevelFilter::ERROR,
        (false, 0) => LevelFilter::WARN,
        (false, 1) => LevelFilter::INFO,
        _ => LevelFilter::DEBUG,
    };
    let log_bar = bar.clone();
    tracing_subscriber::fmt()
        .with_max_level(level)
        .with_target(false)
        .with_ansi(std::io::stderr().is_terminal())
        .with_writer(move || LogLine { bar: log_bar.clone(), text: Vec::new() })
        .init();
}

/// A line above the progress bar, unless quiet.
fn show_line(bar: &ProgressBar, line: &str, quiet: bool) {
    if !quiet && bar.is_hidden() {
        // Not a terminal (a pipe, a log file): the bar draws nothing, so print the line.
        println!("{line}");
    } else if !quiet {
        bar.println(line);
    }
}

/// What a checkpoint written says: where the run stands, its size and the time it took.
fn checkpoint_line(w: &CheckpointWritten, out: &Path) -> String {
    let at = if w.step > 0 { format!("step {}", w.step) } else { format!("trial {}", w.trials) };
    let size = if w.bytes < 1_000_000 {
        format!("{:.1} kB", w.bytes as f64 / 1e3)
    } else {
        format!("{:.1} MB", w.bytes as f64 / 1e6)
    };
    format!(
        "checkpoint after {at}: {size} in {:.2} s ({})",
        w.wall_time.as_secs_f64(),
        out.join(CHECKPOINT_FILE).display()
    )
}

/// A finished strength-reduction trial, one line above the progress bar (unless quiet),
/// and the bar's message.
fn show_trial(bar: &ProgressBar, k: usize, t: &StrengthTrial, quiet: bool) {
    // A trial from the last state that held keeps the full load: it fails at load factor 1.
    let outcome = match (t.stable, t.load_factor < 1.0) {
        (true, _) => "holds".to_string(),
        (false, true) => format!("fails at load factor {:.3}", t.load_factor),
        (false, false) => "fails".to_string(),
    };
    let line = format!(
        "trial {k}: F = {:.4} {outcome} ({} Newton iterations, {} cut-backs, {:.1} s)",
        t.factor,
        t.iterations,
        t.cutbacks,
        t.wall_time.as_secs_f64()
    );
    show_line(bar, &line, quiet);
    bar.set_message(format!("strength reduction: {line}"));
}

/// The progress bar after step `r` of a run that ends at `end` and is a share `done` of
/// the way there.
fn show_progress(bar: &ProgressBar, r: &Progress, end: f64, done: f64) {
    bar.set_position((1000.0 * done) as u64);
    let newton = if r.final_residual.is_nan() {
        String::new()
    } else {
        format!(" its={} res={:.1e}", r.iterations, r.final_residual)
    };
    let cutbacks = if r.cutbacks > 0 { format!(" cut-backs={}", r.cutbacks) } else { String::new() };
    let krylov = if r.linear_iterations > 0 { format!(" krylov={}", r.linear_iterations) } else { String::new() };
    bar.set_message(format!(
        "step {} t={:.4e}/{:.4e} Δ={:.2e}{newton}{krylov}{cutbacks}",
        r.step, r.time, end, r.increment
    ));
}

#[cfg(test)]
mod tests {
    use super::{error_chain, parse_size};

    #[derive(Debug)]
    struct Quoting(std::io::Error);

    impl std::fmt::Display for Quoting {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(f, "output: {}", self.0)
        }
    }

    impl std::error::Error for Quoting {
        fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
            Some(&self.0)
        }
    }

    /// A cause its parent already quotes is printed once; a context and a cause that adds
    /// words are both printed.
    #[test]
    fn each_cause_is_printed_once() {
        let e = anyhow::Error::new(Quoting(std::io::Error::other("disk full"))).context("running scene.ron");
        assert_eq!(format!("{e:#}"), "running scene.ron: output: disk full: disk full");
        assert_eq!(error_chain(&e), "running scene.ron: output: disk full");
    }

    #[test]
    fn sizes_take_decimal_and_binary_units() {
        assert_eq!(parse_size("32G"), Ok(32_000_000_000));
        assert_eq!(parse_size("500 MiB"), Ok(500 << 20));
        assert_eq!(parse_size("1.5gb"), Ok(1_500_000_000));
        assert_eq!(parse_size("4096"), Ok(4096));
        assert!(parse_size("12 parsecs").unwrap_err().contains("not a unit"));
        assert!(parse_size("-1G").is_err() && parse_size("G").is_err());
    }
}
