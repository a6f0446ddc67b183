//! Running a scene end to end with its outputs: a VTU frame per output step collected in a
//! PVD file, a run log (one CSV row per step, flushed as it goes), `history.csv` (time,
//! energies, momentum) and `points_final.csv` after the last step. A run that fails mid-way
//! keeps every file written so far; the error says which step failed and why. Asked to,
//! a run writes a checkpoint between steps (`restart`), from which [`resume_scene`] goes on
//! as if it had never stopped.

use crate::monitor::MonitorColumns;
use crate::point_fields::{default_fields, write_frame, write_points_csv};
use crate::restart::{self, CheckpointEvery, CheckpointWritten, Checkpoints, OutputsState, Phase, RunTotals};
use loam_analysis::{
    Analysis, AnalysisError, Collapse, FactorOfSafety, Progress, SearchSoFar, StrengthReduction,
    StrengthReductionError, StrengthTrial, TrialStart,
};
use loam_format::checkpoint::{Checkpoint, CheckpointError, CheckpointHeader};
use loam_format::output::{CsvCell, CsvWriter, OutputError, PvdWriter};
use loam_format::output_dir::{clear_output_dir, prepare_output_dir, remove_temp_files, OutputDirError};
use loam_format::run_plots::plot_run;
use loam_implicit::{Peak, QuasiStatic};
use loam_model::{ExternalWork, LoadLevel, Model, ModelError, PointChange};
use loam_scene::FieldSpec;
use loam_scene::{
    AnalysisSpec, CollapseSpec, Excavation, LoadedScene, OutputSpec, SceneError, StrengthReductionSpec, TrialStartSpec,
};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Why a run stopped.
#[derive(Debug, thiserror::Error)]
pub enum RunFailure {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Analysis(#[from] AnalysisError),
    #[error("output: {0}")]
    Output(#[from] OutputError),
    #[error(transparent)]
    OutputDir(#[from] OutputDirError),
    #[error("strength reduction: {0}")]
    StrengthReduction(#[from] StrengthReductionError),
    #[error(transparent)]
    Checkpoint(#[from] CheckpointError),
    #[error("excavation {stage} after step {step}: {source}")]
    Excavation { stage: usize, step: usize, source: ModelError },
}

/// What a finished run did.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub analysis: &'static str,
    pub steps: usize,
    pub points: usize,
    pub newton_iterations: usize,
    pub max_iterations_per_step: usize,
    pub cutbacks: usize,
    pub wall_time: Duration,
    pub solver: String,
    pub output_dir: PathBuf,
    /// The bracketed factor of safety, when the scene asked for strength reduction.
    pub factor_of_safety: Option<FactorOfSafety>,
    /// The collapse a load-controlled quasi-static run ended with: the load factor it
    /// carried at most.
    pub collapse: Option<Collapse>,
    /// Under arc-length control, the most load the model carried and the step that
    /// carried it.
    pub peak: Option<Peak>,
    /// The load factor at the end (quasi-static), or 1.
    pub load_factor: f64,
    /// The plots drawn from the run's CSV files, or why they could not be (a run is not
    /// failed for its plots).
    pub plots: Result<Vec<PathBuf>, String>,
}

/// What a run is asked beyond its scene (`loam run`'s flags).
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Stop after this many steps, as if the run ended there: its last frame, history row
    /// and `points_final.csv` are at that step.
    pub max_steps: Option<usize>,
    /// Remove another run's outputs from the output folder, once the scene has been
    /// checked (only the files loam writes; `output_dir`).
    pub overwrite: bool,
    /// Write a checkpoint this often (none: never).
    pub checkpoint_every: Option<CheckpointEvery>,
}

/// What a run reports as it goes, to show progress.
#[derive(Debug, Clone, Copy)]
pub enum RunEvent<'a> {
    /// A strength-reduction trial finished (they come before the run's steps).
    Trial(&'a StrengthTrial),
    /// A step finished; `end` is the run's end time (quasi-static: load factor 1), `done`
    /// how far the run is, in [0, 1] (`Analysis::fraction_done`).
    Step { report: &'a Progress, end: f64, done: f64 },
    /// A checkpoint was written.
    Checkpoint(CheckpointWritten),
    /// A resumed run starts after `step` steps and `trials` strength-reduction trials.
    Resumed { step: usize, trials: usize },
    /// Excavation stage `stage` removed `removed` points after step `step`.
    Excavated { stage: usize, step: usize, removed: usize },
}

/// Run a scene, writing its outputs into `out_dir`; `progress` is told of each
/// strength-reduction trial and each step as they finish.
pub fn run_scene(
    scene: &LoadedScene,
    out_dir: &Path,
    progress: &mut dyn FnMut(RunEvent),
) -> Result<RunSummary, RunFailure> {
    run_scene_with(scene, out_dir, &RunOptions::default(), progress)
}

/// [`run_scene`] with `options`. Nothing in `out_dir` is touched before the scene has been
/// checked; once the folder is prepared, the run's plots are drawn at its end whether it
/// finished or not (a failed run's curves show where it went wrong).
pub fn run_scene_with(
    scene: &LoadedScene,
    out_dir: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(RunEvent),
) -> Result<RunSummary, RunFailure> {
    match scene.scene.dimension {
        3 => run_dim::<3>(scene, out_dir, options, progress),
        _ => run_dim::<2>(scene, out_dir, options, progress),
    }
}

/// The columns of `history.csv` before the momentum's.
const HISTORY_COLUMNS: [&str; 5] = ["time", "kinetic_energy", "strain_energy", "external_work", "total_energy"];

/// `history.csv`: one row per recorded step with time, energies and momentum. The external
/// work is accumulated every step, whether or not a row is written.
struct History<const D: usize> {
    writer: CsvWriter,
    work: ExternalWork<D>,
}

impl<const D: usize> History<D> {
    fn header() -> Vec<&'static str> {
        let mut header = HISTORY_COLUMNS.to_vec();
        header.extend(["momentum_x", "momentum_y", "momentum_z"].iter().take(D));
        header
    }

    /// A new history of the model at `level`, or, given `saved` (bytes of the file and
    /// work done), the one a checkpoint left.
    fn open(path: &Path, model: &Model<D>, level: LoadLevel, saved: Option<(u64, f64)>) -> Result<Self, OutputError> {
        let writer = CsvWriter::open(path, &Self::header(), saved.map(|(bytes, _)| bytes))?;
        let work = match saved {
            Some((_, work)) => ExternalWork::resumed(model, level, work),
            None => ExternalWork::new(model, level),
        };
        Ok(Self { writer, work })
    }

    fn advance(&mut self, model: &Model<D>, level: LoadLevel) {
        self.work.advance(model, level);
    }

    /// Total energy is kinetic + strain − external work: constant for a conservative
    /// system, falling where the scheme or the material dissipates.
    fn row(&mut self, model: &Model<D>, time: f64) -> Result<(), OutputError> {
        let kinetic = model.points().kinetic_energy();
        let strain = model.stored_energy();
        let work = self.work.work();
        let mut cells = vec![
            CsvCell::Float(time),
            CsvCell::Float(kinetic),
            CsvCell::Float(strain),
            CsvCell::Float(work),
            CsvCell::Float(kinetic + strain - work),
        ];
        cells.extend(model.points().momentum().iter().map(|&m| CsvCell::Float(m)));
        // A row is never written with an overflowed energy or momentum: the run stops.
        if let Some(k) = cells[1..].iter().position(|c| matches!(c, CsvCell::Float(v) if !v.is_finite())) {
            let what = HISTORY_COLUMNS.get(k + 1).unwrap_or(&"momentum");
            return Err(OutputError::Unstable { what: what.to_string(), time });
        }
        self.writer.row_mixed(&cells)
    }
}

fn run_dim<const D: usize>(
    scene: &LoadedScene,
    out_dir: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(RunEvent),
) -> Result<RunSummary, RunFailure> {
    let start = Instant::now();
    let analysis: Analysis<D> = scene.build::<D>()?;
    if options.overwrite {
        clear_output_dir(out_dir)?;
    }
    prepare_output_dir(out_dir, &scene.path)?;
    with_plots(out_dir, run_prepared(scene, analysis, out_dir, options, progress, start, None))
}

/// The run's `result` with the plots of its folder, drawn whether it finished or not.
fn with_plots(out_dir: &Path, result: Result<RunSummary, RunFailure>) -> Result<RunSummary, RunFailure> {
    let plots = plot_run(out_dir).map_err(|e| e.to_string());
    Ok(RunSummary { plots, ..result? })
}

/// Go on with the run whose `checkpoint` is in `out_dir`, of the scene `scene` (the
/// checkpoint's [`restart::checkpoint_scene`]): its outputs are cut back to where the
/// checkpoint left them and continued, so that they end as those of a run that never
/// stopped. A checkpoint of another scene text, loam, analysis or dimension is refused
/// before anything in the folder changes.
pub fn resume_scene(
    scene: &LoadedScene,
    checkpoint: Checkpoint,
    out_dir: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(RunEvent),
) -> Result<RunSummary, RunFailure> {
    match scene.scene.dimension {
        3 => resume_dim::<3>(scene, checkpoint, out_dir, options, progress),
        _ => resume_dim::<2>(scene, checkpoint, out_dir, options, progress),
    }
}

fn resume_dim<const D: usize>(
    scene: &LoadedScene,
    checkpoint: Checkpoint,
    out_dir: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(RunEvent),
) -> Result<RunSummary, RunFailure> {
    let start = Instant::now();
    let path = out_dir.join(restart::CHECKPOINT_FILE);
    let saved = checkpoint.header.analysis.clone();
    checkpoint.verify(&path, &CheckpointHeader::new(&scene.source, &saved, D as u32))?;
    let analysis: Analysis<D> = scene.build::<D>()?;
    checkpoint.verify(&path, &CheckpointHeader::new(&scene.source, analysis.name(), D as u32))?;
    remove_temp_files(out_dir)?;
    with_plots(out_dir, run_prepared(scene, analysis, out_dir, options, progress, start, Some(&checkpoint)))
}

/// The run into a prepared folder: strength reduction if asked, then the steps with their
/// outputs and checkpoints; from `resume`'s state if given.
fn run_prepared<const D: usize>(
    scene: &LoadedScene,
    mut analysis: Analysis<D>,
    out_dir: &Path,
    options: &RunOptions,
    progress: &mut dyn FnMut(RunEvent),
    start: Instant,
    resume: Option<&Checkpoint>,
) -> Result<RunSummary, RunFailure> {
    let header = CheckpointHeader::new(&scene.source, analysis.name(), D as u32);
    let mut saver = Checkpoints::new(options.checkpoint_every, out_dir, header, &scene.path);
    let (searching, stepping) = match resume.map(|c| restart::phase(c).map(|p| (c, p))).transpose()? {
        Some((c, Phase::Search)) => (Some(c), None),
        Some((c, Phase::Steps)) => (None, Some(c)),
        None => (None, None),
    };
    // The monitors are found on the model as the scene builds it, a resumed run's too.
    let monitors = MonitorColumns::new(scene.monitors(analysis.model())?);
    let search = SearchContext { out_dir, searching, stepping, saver: &mut saver };
    let factor_of_safety = strength_reduction_first(scene, &mut analysis, search, progress)?;
    let (mut outputs, mut totals) = match stepping {
        Some(c) => {
            restart::resume_analysis(c, &mut analysis)?;
            progress(RunEvent::Resumed { step: analysis.steps_done(), trials: 0 });
            (Outputs::resume(&scene.scene.output, &analysis, out_dir, c, monitors)?, restart::saved_totals(c)?)
        }
        None => (Outputs::create(&scene.scene.output, &analysis, out_dir, monitors)?, RunTotals::default()),
    };
    let steps = Stepping { scene, options, factor_of_safety: factor_of_safety.as_ref() };
    let collapse = steps.run(&mut analysis, &mut outputs, &mut totals, &mut saver, progress)?;
    outputs.finish(analysis.model(), analysis.load_level())?;
    Ok(RunSummary {
        analysis: analysis.name(),
        steps: analysis.steps_done(),
        points: analysis.model().points().len(),
        newton_iterations: totals.iterations,
        max_iterations_per_step: totals.max_iterations,
        cutbacks: totals.cutbacks,
        wall_time: start.elapsed(),
        solver: analysis.solver(),
        output_dir: out_dir.to_owned(),
        factor_of_safety,
        collapse,
        peak: analysis.peak(),
        load_factor: analysis.load_factor(),
        plots: Ok(Vec::new()),
    })
}

/// What the steps of a run need beside the analysis and its outputs.
struct Stepping<'a> {
    scene: &'a LoadedScene,
    options: &'a RunOptions,
    factor_of_safety: Option<&'a FactorOfSafety>,
}

impl Stepping<'_> {
    /// Step to the end (or to `max_steps`), recording each step, excavating and writing
    /// checkpoints when due. A load-controlled quasi-static step that cannot go on ends the
    /// run with its collapse, its state written as the last frame, unless the scene asks for
    /// the error (`at_collapse: Error`).
    fn run<const D: usize>(
        &self,
        analysis: &mut Analysis<D>,
        outputs: &mut Outputs<D>,
        totals: &mut RunTotals,
        saver: &mut Checkpoints,
        progress: &mut dyn FnMut(RunEvent),
    ) -> Result<Option<Collapse>, RunFailure> {
        let (end_time, excavations) = (analysis.end_time(), self.scene.excavations::<D>()?);
        let max_steps = self.options.max_steps;
        let stop = |a: &Analysis<D>| a.is_finished() || max_steps.is_some_and(|m| a.steps_done() >= m);
        while !stop(analysis) {
            let r = match analysis.step() {
                Ok(r) => r,
                Err(e) => {
                    let collapse = analysis.collapse(&e).filter(|_| self.reports_collapse());
                    let Some(collapse) = collapse else { return Err(e.into()) };
                    outputs.collapsed(analysis, collapse.step)?;
                    return Ok(Some(collapse));
                }
            };
            excavate(analysis, &excavations, r.step, progress)?;
            totals.add(&r);
            outputs.record(&r, analysis.model(), stop(analysis))?;
            progress(RunEvent::Step { report: &r, end: end_time, done: analysis.fraction_done() });
            if saver.due_after_step(r.step) && !analysis.is_finished() {
                let mut c = saver.start();
                restart::save_steps(&mut c, analysis, &outputs.state(), *totals, self.factor_of_safety);
                progress(RunEvent::Checkpoint(saver.write(&c, r.step, 0)?));
            }
        }
        Ok(None)
    }

    /// Whether the scene takes a collapse as the run's result: the default, but not where
    /// it asks for the error. The run from zero at a factor of safety found by lowering the
    /// strength of a state that held may itself stop short of the full load (near collapse
    /// the state depends on the path, docs/theory.md §14): that is reported, not an error.
    fn reports_collapse(&self) -> bool {
        !matches!(self.scene.scene.analysis, AnalysisSpec::QuasiStatic { at_collapse: CollapseSpec::Error, .. })
    }
}

/// The excavation stages due after step `step`, in the scene's order: their points are
/// removed before the step's outputs and checkpoint, which show the excavated ground.
fn excavate<const D: usize>(
    analysis: &mut Analysis<D>,
    stages: &[Excavation<D>],
    step: usize,
    progress: &mut dyn FnMut(RunEvent),
) -> Result<(), RunFailure> {
    for (stage, e) in stages.iter().enumerate().filter(|(_, e)| e.after_step == step) {
        let removed = analysis
            .change_points(PointChange::RemoveIn(e.region.clone()))
            .map_err(|source| RunFailure::Excavation { stage, step, source })?;
        progress(RunEvent::Excavated { stage, step, removed });
    }
    Ok(())
}

/// Where a strength-reduction search writes and saves, and the checkpoint it goes on from:
/// one saved during the search, or one saved in the run after it (with its result).
struct SearchContext<'a> {
    out_dir: &'a Path,
    searching: Option<&'a Checkpoint>,
    stepping: Option<&'a Checkpoint>,
    saver: &'a mut Checkpoints,
}

/// A scene that asks for strength reduction first brackets its factor of safety (or takes
/// the one a checkpoint saved); the run then goes on at the largest factor that held, so
/// the outputs show the state just before failure.
fn strength_reduction_first<const D: usize>(
    scene: &LoadedScene,
    analysis: &mut Analysis<D>,
    search: SearchContext,
    progress: &mut dyn FnMut(RunEvent),
) -> Result<Option<FactorOfSafety>, RunFailure> {
    let (AnalysisSpec::QuasiStatic { strength_reduction: Some(spec), .. }, Analysis::QuasiStatic(qs)) =
        (&scene.scene.analysis, &*analysis)
    else {
        return Ok(None);
    };
    let saved = search.stepping.map(restart::saved_search_result).transpose()?.flatten();
    let fos = match saved {
        Some(fos) => fos,
        None => factor_of_safety(qs, spec, search, progress)?,
    };
    *analysis = analysis.with_strength_reduced(fos.stable)?;
    Ok(Some(fos))
}

/// The files a run writes as it goes: the run log, the VTU frames and their PVD, the
/// energy history, and `points_final.csv` at the end.
struct Outputs<'a, const D: usize> {
    spec: &'a OutputSpec,
    fields: Vec<FieldSpec>,
    out_dir: &'a Path,
    log: RunLog,
    pvd: Option<PvdWriter>,
    history: Option<History<D>>,
}

impl<'a, const D: usize> Outputs<'a, D> {
    /// Create the files and write the state before the first step (frame 0, the first
    /// history row).
    fn create(
        spec: &'a OutputSpec,
        analysis: &Analysis<D>,
        out_dir: &'a Path,
        monitors: MonitorColumns,
    ) -> Result<Self, OutputError> {
        let model = analysis.model();
        let log = RunLog::open(&out_dir.join("run_log.csv"), model, monitors, None)?;
        let fields = spec.fields.clone().unwrap_or_else(|| default_fields(model));
        let mut pvd = if spec.vtu_every > 0 { Some(PvdWriter::create(out_dir.join("points.pvd"))?) } else { None };
        if let Some(pvd) = pvd.as_mut() {
            let level = analysis.load_level();
            write_frame(model, &fields, spec.vtu_format.into(), level.body_factor(), pvd, 0, 0.0)?;
        }
        let mut history = None;
        if spec.history_every > 0 {
            let mut h = History::open(&out_dir.join("history.csv"), model, analysis.load_level(), None)?;
            h.row(model, analysis.time())?;
            history = Some(h);
        }
        Ok(Self { spec, fields, out_dir, log, pvd, history })
    }

    /// Go on writing where checkpoint `c` left the files.
    fn resume(
        spec: &'a OutputSpec,
        analysis: &Analysis<D>,
        out_dir: &'a Path,
        c: &Checkpoint,
        monitors: MonitorColumns,
    ) -> Result<Self, RunFailure> {
        let model = analysis.model();
        let saved = restart::saved_outputs(c, spec.history_every > 0, spec.vtu_every > 0)?;
        let log = RunLog::open(&out_dir.join("run_log.csv"), model, monitors, Some(saved.run_log_bytes))?;
        let fields = spec.fields.clone().unwrap_or_else(|| default_fields(model));
        let pvd = saved.frames.map(|frames| PvdWriter::resume(out_dir.join("points.pvd"), frames)).transpose()?;
        let level = analysis.load_level();
        let history = (saved.history)
            .map(|saved| History::open(&out_dir.join("history.csv"), model, level, Some(saved)))
            .transpose()?;
        Ok(Self { spec, fields, out_dir, log, pvd, history })
    }

    /// Where the files stand, for a checkpoint.
    fn state(&self) -> OutputsState {
        OutputsState {
            run_log_bytes: self.log.writer.bytes(),
            history: self.history.as_ref().map(|h| (h.writer.bytes(), h.work.work())),
            frames: self.pvd.as_ref().map(|p| p.entries().to_vec()),
        }
    }

    /// After step `r`: its log row, and a history row and a frame when due (always after the
    /// `last` step).
    fn record(&mut self, r: &Progress, model: &Model<D>, last: bool) -> Result<(), OutputError> {
        self.log.row(r, model)?;
        if let Some(h) = self.history.as_mut() {
            h.advance(model, r.level);
            if r.step.is_multiple_of(self.spec.history_every) || last {
                h.row(model, r.time)?;
            }
        }
        if let Some(pvd) = self.pvd.as_mut() {
            if r.step.is_multiple_of(self.spec.vtu_every) || last {
                let format = self.spec.vtu_format.into();
                write_frame(model, &self.fields, format, r.level.body_factor(), pvd, r.step, r.time)?;
            }
        }
        Ok(())
    }

    /// The state a run ends in after step `step` could not be completed (a collapse): the
    /// last history row and frame, as after a last step.
    fn collapsed(&mut self, analysis: &Analysis<D>, step: usize) -> Result<(), OutputError> {
        let (model, level) = (analysis.model(), analysis.load_level());
        if let Some(h) = self.history.as_mut() {
            h.advance(model, level);
            h.row(model, analysis.time())?;
        }
        if let Some(pvd) = self.pvd.as_mut() {
            let format = self.spec.vtu_format.into();
            write_frame(model, &self.fields, format, level.body_factor(), pvd, step, analysis.time())?;
        }
        Ok(())
    }

    /// After the last step: `points_final.csv`, if asked for.
    fn finish(&self, model: &Model<D>, level: LoadLevel) -> Result<(), OutputError> {
        if self.spec.final_csv {
            write_points_csv(model, &self.fields, level.body_factor(), &self.out_dir.join("points_final.csv"))?;
        }
        Ok(())
    }
}

/// `run_log.csv`: one row per step (load factor, Newton iterations, final residual, wall
/// time, ...). Every constraint adds its reaction per held component (implicit analyses;
/// NaN in explicit ones), a displaced one (a footing) its prescribed displacement before
/// it: the load–displacement curve; every inclined roller its reaction per component
/// (implicit and explicit); every body constraint, as a plane constraint does, its
/// displacement and reaction; every frictional plane its force on the material (implicit and
/// explicit).
/// Every load adds its resultant at the step's load factor or time, per component, and
/// every monitoring point its displacement and stress.
struct RunLog {
    writer: CsvWriter,
    /// The planes' held components, then the bodies'.
    planes: Vec<Held>,
    bodies: Vec<Held>,
    monitors: MonitorColumns,
}

/// One held component of a constraint, as `RunLog` writes it: its columns' prefix, its
/// constraint's index among the step's reactions, the component, and the prescribed
/// displacement at full load if displaced.
struct Held {
    prefix: String,
    reaction: usize,
    axis: usize,
    displacement: Option<f64>,
}

impl Held {
    /// The held components of a constraint: `fixed` and `displacement` its own,
    /// `displaced` whether it prescribes a displacement.
    fn of(prefix: String, reaction: usize, fixed: &[bool], displacement: &[f64; 3], displaced: bool) -> Vec<Held> {
        (fixed.iter().enumerate().filter(|(_, &f)| f))
            .map(|(axis, _)| Held {
                prefix: prefix.clone(),
                reaction,
                axis,
                displacement: displaced.then_some(displacement[axis]),
            })
            .collect()
    }
}

const AXES: [&str; 3] = ["x", "y", "z"];

impl RunLog {
    const COLUMNS: [&'static str; 14] = [
        "step",
        "time",
        "load_factor",
        "increment",
        "substeps",
        "cutbacks",
        "iterations",
        "krylov_iterations",
        "solver_setup_s",
        "direct_fallbacks",
        "final_residual",
        "active_nodes",
        "dofs",
        "wall_time_s",
    ];

    /// A new log of `model`, or the one a checkpoint left after `resume_at` bytes.
    fn open<const D: usize>(
        path: &Path,
        model: &Model<D>,
        monitors: MonitorColumns,
        resume_at: Option<u64>,
    ) -> Result<Self, OutputError> {
        let planes: Vec<Held> = (model.constraints().iter().enumerate())
            .flat_map(|(k, c)| Held::of(format!("constraint{k}"), k, &c.fixed[..D], &c.displacement, c.is_displaced()))
            .collect();
        let first_body = model.constraints().len() + model.inclined_rollers().len();
        let bodies: Vec<Held> = (model.body_constraints().iter().enumerate())
            .flat_map(|(k, c)| {
                Held::of(
                    format!("body_constraint{k}"),
                    first_body + k,
                    &c.fixed[..D],
                    &c.displacement,
                    c.is_displaced(),
                )
            })
            .collect();
        let mut header: Vec<String> = Self::COLUMNS.iter().map(|s| s.to_string()).collect();
        Self::held_columns(&mut header, &planes);
        for k in 0..model.inclined_rollers().len() {
            header.extend(AXES[..D].iter().map(|a| format!("incline{k}_reaction_{a}")));
        }
        Self::held_columns(&mut header, &bodies);
        for k in 0..model.frictional_planes().len() {
            header.extend(AXES[..D].iter().map(|a| format!("frictional_plane{k}_reaction_{a}")));
        }
        for k in 0..model.rigid_bodies().len() {
            header.extend(AXES[..D].iter().map(|a| format!("rigid{k}_displacement_{a}")));
            header.extend(AXES[..D].iter().map(|a| format!("rigid{k}_reaction_{a}")));
        }
        for k in 0..model.loads().len() {
            header.extend(AXES[..D].iter().map(|a| format!("load{k}_{a}")));
        }
        header.extend(monitors.header(D));
        let writer = CsvWriter::open(path, &header.iter().map(String::as_str).collect::<Vec<_>>(), resume_at)?;
        Ok(Self { writer, planes, bodies, monitors })
    }

    /// Per held component, its prescribed displacement's column (if displaced) and its
    /// reaction's.
    fn held_columns(header: &mut Vec<String>, held: &[Held]) {
        for h in held {
            if h.displacement.is_some() {
                header.push(format!("{}_displacement_{}", h.prefix, AXES[h.axis]));
            }
            header.push(format!("{}_reaction_{}", h.prefix, AXES[h.axis]));
        }
    }

    fn row<const D: usize>(&mut self, r: &Progress, model: &Model<D>) -> Result<(), OutputError> {
        let mut cells = vec![
            CsvCell::Int(r.step as i64),
            CsvCell::Float(r.time),
            CsvCell::Float(r.load_factor),
            CsvCell::Float(r.increment),
            CsvCell::Int(r.substeps as i64),
            CsvCell::Int(r.cutbacks as i64),
            CsvCell::Int(r.iterations as i64),
            CsvCell::Int(r.linear_iterations as i64),
            CsvCell::Float(r.linear_setup.as_secs_f64()),
            CsvCell::Int(r.direct_fallbacks as i64),
            CsvCell::Float(r.final_residual),
            CsvCell::Int(r.active_nodes as i64),
            CsvCell::Int(r.dofs as i64),
            CsvCell::Float(r.wall_time.as_secs_f64()),
        ];
        Self::held_cells(&mut cells, &self.planes, r);
        let (planes, rollers) = (model.constraints().len(), model.inclined_rollers().len());
        let reaction = |k: usize| (0..D).map(move |i| CsvCell::Float(r.reactions.get(k).map_or(f64::NAN, |f| f[i])));
        (planes..planes + rollers).for_each(|k| cells.extend(reaction(k)));
        Self::held_cells(&mut cells, &self.bodies, r);
        let frictional = planes + rollers + model.body_constraints().len();
        (frictional..frictional + model.frictional_planes().len()).for_each(|k| cells.extend(reaction(k)));
        let first_rigid = frictional + model.frictional_planes().len();
        for (k, rigid) in model.rigid_bodies().iter().enumerate() {
            cells.extend(rigid.displacement(r.time).iter().map(|&u| CsvCell::Float(u)));
            cells.extend(reaction(first_rigid + k));
        }
        for (k, load) in model.loads().iter().enumerate() {
            cells.extend(load.resultant(model.load_scale(k, r.level)).iter().map(|&f| CsvCell::Float(f)));
        }
        cells.extend(self.monitors.cells(model));
        self.writer.row_mixed(&cells)
    }

    /// Per held component, its prescribed displacement at the step (if displaced) and its
    /// reaction (NaN where the analysis gives none).
    fn held_cells(cells: &mut Vec<CsvCell>, held: &[Held], r: &Progress) {
        for h in held {
            if let Some(u) = h.displacement {
                cells.push(CsvCell::Float(r.load_factor * u));
            }
            cells.push(CsvCell::Float(r.reactions.get(h.reaction).map_or(f64::NAN, |f| f[h.axis])));
        }
    }
}

/// The columns of `strength_reduction.csv`.
const TRIAL_COLUMNS: [&str; 7] =
    ["factor", "stable", "load_factor", "iterations", "cutbacks", "max_displacement", "wall_time_s"];

/// Bracket the factor of safety of the quasi-static analysis's model, one row per trial in
/// `strength_reduction.csv` (flushed as it goes, so a long search shows its progress) and,
/// when due, a checkpoint after a trial; a search resumed from a checkpoint goes on after
/// its trials.
fn factor_of_safety<const D: usize>(
    qs: &QuasiStatic<D>,
    spec: &StrengthReductionSpec,
    search: SearchContext,
    progress: &mut dyn FnMut(RunEvent),
) -> Result<FactorOfSafety, RunFailure> {
    let path = search.out_dir.join("strength_reduction.csv");
    let (so_far, bytes) = match search.searching {
        Some(c) => restart::saved_search(c, qs.model()).map(|(so_far, bytes)| (so_far, Some(bytes)))?,
        None => (SearchSoFar::default(), None),
    };
    let mut csv = CsvWriter::open(&path, &TRIAL_COLUMNS, bytes)?;
    if !so_far.trials.is_empty() {
        progress(RunEvent::Resumed { step: 0, trials: so_far.trials.len() });
    }
    let start = match spec.start {
        TrialStartSpec::LastHeld => TrialStart::LastHeld,
        TrialStartSpec::Zero => TrialStart::Zero,
    };
    let srf =
        StrengthReduction { trial: qs.settings().clone(), bracket: spec.bracket, tolerance: spec.tolerance, start };
    let (saver, mut trials) = (search.saver, so_far.trials.clone());
    let mut written = Ok(());
    let fos = srf.factor_of_safety_after(qs.model(), so_far, |t, held| {
        progress(RunEvent::Trial(t));
        trials.push(t.clone());
        if written.is_ok() {
            written = record_trial(&mut csv, t, &trials, held, saver).map(|w| {
                if let Some(w) = w {
                    progress(RunEvent::Checkpoint(w));
                }
            });
        }
    });
    written?;
    Ok(fos?)
}

/// Trial `t`'s row, and a checkpoint after `trials` if one is due.
fn record_trial<const D: usize>(
    csv: &mut CsvWriter,
    t: &StrengthTrial,
    trials: &[StrengthTrial],
    held: Option<&QuasiStatic<D>>,
    saver: &mut Checkpoints,
) -> Result<Option<CheckpointWritten>, OutputError> {
    csv.row_mixed(&[
        CsvCell::Float(t.factor),
        CsvCell::Int(t.stable as i64),
        CsvCell::Float(t.load_factor),
        CsvCell::Int(t.iterations as i64),
        CsvCell::Int(t.cutbacks as i64),
        CsvCell::Float(t.max_displacement),
        CsvCell::Float(t.wall_time.as_secs_f64()),
    ])?;
    if !saver.due_after_trial() {
        return Ok(None);
    }
    let mut c = saver.start();
    restart::save_search(&mut c, trials, held, csv.bytes());
    saver.write(&c, 0, trials.len()).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point whose kinetic energy overflows stops the history with `Unstable` instead of
    /// an `inf` row; the header and the rows before stay.
    #[test]
    fn an_overflowed_energy_is_not_written() {
        let text = include_str!("../../../examples/column.ron");
        let scene = LoadedScene::parse(Path::new("column.ron"), text.to_string()).unwrap();
        let mut model = scene.build::<2>().unwrap().into_model();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("history.csv");
        let mut history = History::open(&path, &model, LoadLevel::Factor(0.0), None).unwrap();
        history.row(&model, 0.0).unwrap();
        model.velocities_mut()[3] = nalgebra::Vector2::new(0.0, 1e200);
        match history.row(&model, 0.5) {
            Err(OutputError::Unstable { what, time }) => assert_eq!((what.as_str(), time), ("kinetic_energy", 0.5)),
            other => panic!("{other:?}"),
        }
        assert_eq!(std::fs::read_to_string(&path).unwrap().lines().count(), 2);
    }
}
