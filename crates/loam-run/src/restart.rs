//! What a checkpoint holds of a run, and how a run is put back from one (the file format
//! is `checkpoint`'s).
//!
//! A run is saved between steps, never inside one: a cut-back lives and dies within its
//! step, so the state between steps is the whole state. It is every field of every point
//! (bit for bit), the places of the loads' vertices and of a body-fitted mesh's nodes, the
//! analysis's counters (step, time or load factor, the linear solver resolved at the first
//! step, the extrapolation increment, the nodal fields of nodes that persist), the
//! strength-reduction trials done or the factor they bracketed, and the outputs' counters
//! (bytes of each CSV file, the frames listed, the external work accumulated). Everything
//! else is rebuilt from the scene, as it was built at the start, so the resumed run takes
//! the steps the interrupted one would have taken with the same numbers.

use loam_analysis::{Analysis, AnalysisState, FactorOfSafety, SearchSoFar, StrengthTrial};
use loam_explicit::ExplicitState;
use loam_format::checkpoint::{Checkpoint, CheckpointError, CheckpointHeader, Section};
use loam_implicit::{ArcLengthState, DynamicState, Peak, QuasiStatic, QuasiStaticState};
use loam_model::{Model, ModelState};
use loam_points::{Column, PointStore};
use loam_solve::LinearSolverKind;
use nalgebra::{SMatrix, SVector};
use std::path::{Path, PathBuf};
use std::str::FromStr;
use std::time::{Duration, Instant};

pub use loam_format::checkpoint::CHECKPOINT_FILE;

/// How often a run writes its checkpoint (`loam run --checkpoint-every`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CheckpointEvery {
    /// After every this many steps (and after every strength-reduction trial).
    Steps(usize),
    /// After the first step (or trial) that ends this long after the last checkpoint.
    Wall(Duration),
}

impl FromStr for CheckpointEvery {
    type Err = String;

    /// A step count (`50`) or a wall-time interval with its unit (`90s`, `10m`, `2h`).
    fn from_str(text: &str) -> Result<Self, String> {
        let t = text.trim();
        let invalid = || format!("{text:?}: give a number of steps (50) or a wall time with s, m or h (10m)");
        if let Ok(n) = t.parse::<usize>() {
            return if n > 0 { Ok(Self::Steps(n)) } else { Err(invalid()) };
        }
        let (number, scale) = match t.char_indices().last() {
            Some((k, 's')) => (&t[..k], 1.0),
            Some((k, 'm')) => (&t[..k], 60.0),
            Some((k, 'h')) => (&t[..k], 3600.0),
            _ => return Err(invalid()),
        };
        match number.trim().parse::<f64>() {
            Ok(v) if v.is_finite() && v > 0.0 && v * scale < 1e9 => Ok(Self::Wall(Duration::from_secs_f64(v * scale))),
            _ => Err(invalid()),
        }
    }
}

impl std::fmt::Display for CheckpointEvery {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Steps(n) => write!(f, "{n}"),
            Self::Wall(t) => write!(f, "{}s", t.as_secs_f64()),
        }
    }
}

/// A checkpoint written: where it stands and what it cost.
#[derive(Debug, Clone, Copy)]
pub struct CheckpointWritten {
    /// Steps done (0 while a strength-reduction search runs).
    pub step: usize,
    /// Strength-reduction trials done.
    pub trials: usize,
    pub bytes: u64,
    pub wall_time: Duration,
}

/// When and where a run writes its checkpoints.
pub(crate) struct Checkpoints {
    every: Option<CheckpointEvery>,
    path: PathBuf,
    header: CheckpointHeader,
    scene: PathBuf,
    last: Instant,
}

impl Checkpoints {
    pub fn new(every: Option<CheckpointEvery>, dir: &Path, header: CheckpointHeader, scene: &Path) -> Self {
        let scene = std::fs::canonicalize(scene).unwrap_or_else(|_| scene.to_owned());
        Self { every, path: dir.join(CHECKPOINT_FILE), header, scene, last: Instant::now() }
    }

    /// Whether a checkpoint is due after step `step`.
    pub fn due_after_step(&self, step: usize) -> bool {
        match self.every {
            None => false,
            Some(CheckpointEvery::Steps(n)) => step.is_multiple_of(n),
            Some(CheckpointEvery::Wall(t)) => self.last.elapsed() >= t,
        }
    }

    /// Whether a checkpoint is due after a strength-reduction trial: after every one when
    /// checkpoints go by steps (a trial is many steps), else when the interval is up.
    pub fn due_after_trial(&self) -> bool {
        match self.every {
            None => false,
            Some(CheckpointEvery::Steps(_)) => true,
            Some(CheckpointEvery::Wall(t)) => self.last.elapsed() >= t,
        }
    }

    /// A checkpoint of this run, its header and the run's own sections filled.
    pub fn start(&self) -> Checkpoint {
        let mut c = Checkpoint::new(self.header.clone());
        c.put("run.scene", Section::Text(self.scene.display().to_string()));
        let every = self.every.map_or(String::new(), |e| e.to_string());
        c.put("run.checkpoint_every", Section::Text(every));
        c
    }

    /// Write `checkpoint` (atomically, over the last one).
    pub fn write(
        &mut self,
        checkpoint: &Checkpoint,
        step: usize,
        trials: usize,
    ) -> Result<CheckpointWritten, loam_format::output::OutputError> {
        let start = Instant::now();
        let bytes = checkpoint.write(&self.path)?;
        self.last = Instant::now();
        Ok(CheckpointWritten { step, trials, bytes, wall_time: start.elapsed() })
    }
}

/// The scene file a checkpoint's run was started from.
pub fn checkpoint_scene(checkpoint: &Checkpoint) -> Result<PathBuf, CheckpointError> {
    checkpoint.text("run.scene").map(PathBuf::from)
}

/// The interval a checkpoint's run wrote its checkpoints at (`None`: not saved by a run
/// that asked for them).
pub fn checkpoint_interval(checkpoint: &Checkpoint) -> Result<Option<CheckpointEvery>, CheckpointError> {
    let text = checkpoint.text("run.checkpoint_every")?;
    if text.is_empty() {
        return Ok(None);
    }
    text.parse().map(Some).map_err(|e| shape_error("run.checkpoint_every", e))
}

fn shape_error(section: &str, what: String) -> CheckpointError {
    CheckpointError::Section { section: section.to_string(), what }
}

/// Where the run stands: searching for the factor of safety, or stepping.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Phase {
    Search,
    Steps,
}

pub(crate) fn phase(checkpoint: &Checkpoint) -> Result<Phase, CheckpointError> {
    match checkpoint.text("run.phase")? {
        "search" => Ok(Phase::Search),
        "steps" => Ok(Phase::Steps),
        other => Err(shape_error("run.phase", format!("`{other}` is neither `search` nor `steps`"))),
    }
}

/// The run's totals over its steps so far (the summary's).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct RunTotals {
    pub iterations: usize,
    pub max_iterations: usize,
    pub cutbacks: usize,
}

impl RunTotals {
    /// Count step `r` in.
    pub fn add(&mut self, r: &loam_analysis::Progress) {
        self.iterations += r.iterations;
        self.max_iterations = self.max_iterations.max(r.iterations);
        self.cutbacks += r.cutbacks;
    }
}

/// The outputs' counters a resumed run starts from.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct OutputsState {
    pub run_log_bytes: u64,
    /// `history.csv`'s bytes and the external work accumulated, if it is written.
    pub history: Option<(u64, f64)>,
    /// The frames listed in the PVD collection (time, file), if frames are written.
    pub frames: Option<Vec<(f64, String)>>,
}

/// The checkpoint of a strength-reduction search after `trials`, with `csv_bytes` of
/// `strength_reduction.csv` written and, in a search from the last state that held, that
/// state (`held`).
pub(crate) fn save_search<const D: usize>(
    c: &mut Checkpoint,
    trials: &[StrengthTrial],
    held: Option<&QuasiStatic<D>>,
    csv_bytes: u64,
) {
    c.put("run.phase", Section::Text("search".into()));
    put_trials(c, trials);
    c.put("search.csv_bytes", Section::U64(vec![csv_bytes]));
    if let Some(qs) = held {
        put_model(c, qs.model());
        put_analysis(c, &AnalysisState::QuasiStatic(qs.state()));
    }
}

/// The trials a search checkpoint holds, with the held state where it saved one (for
/// `model`, built from the same scene), and the bytes of `strength_reduction.csv` they
/// wrote.
pub(crate) fn saved_search<const D: usize>(
    c: &Checkpoint,
    model: &Model<D>,
) -> Result<(SearchSoFar<D>, u64), CheckpointError> {
    let held = match c.u64s("analysis.step") {
        Err(CheckpointError::Missing(_)) => None,
        _ => match take_analysis(c, "quasi-static")? {
            AnalysisState::QuasiStatic(state) => Some((state, take_model(c, model)?)),
            _ => unreachable!("a quasi-static state is read as one"),
        },
    };
    Ok((SearchSoFar { trials: take_trials(c)?, held }, one_u64(c, "search.csv_bytes")?))
}

/// The checkpoint of a run between steps.
pub(crate) fn save_steps<const D: usize>(
    c: &mut Checkpoint,
    analysis: &Analysis<D>,
    outputs: &OutputsState,
    totals: RunTotals,
    search: Option<&FactorOfSafety>,
) {
    c.put("run.phase", Section::Text("steps".into()));
    c.put(
        "run.totals",
        Section::U64(vec![totals.iterations as u64, totals.max_iterations as u64, totals.cutbacks as u64]),
    );
    if let Some(fos) = search {
        put_trials(c, &fos.trials);
        c.put("search.result", Section::F64(vec![fos.stable, fos.failed]));
    }
    put_model(c, analysis.model());
    put_analysis(c, &analysis.state());
    c.put("outputs.run_log_bytes", Section::U64(vec![outputs.run_log_bytes]));
    if let Some((bytes, work)) = outputs.history {
        c.put("outputs.history_bytes", Section::U64(vec![bytes]));
        c.put("outputs.history_work", Section::F64(vec![work]));
    }
    if let Some(frames) = &outputs.frames {
        c.put("outputs.frame_times", Section::F64(frames.iter().map(|f| f.0).collect()));
        let names: Vec<&str> = frames.iter().map(|f| f.1.as_str()).collect();
        c.put("outputs.frame_files", Section::Text(names.join("\n")));
    }
}

/// The factor of safety a stepping checkpoint's search bracketed, if it had one.
pub(crate) fn saved_search_result(c: &Checkpoint) -> Result<Option<FactorOfSafety>, CheckpointError> {
    let r = match c.f64s("search.result") {
        Err(CheckpointError::Missing(_)) => return Ok(None),
        r => r?,
    };
    let [stable, failed] = r[..] else {
        return Err(shape_error("search.result", format!("{} values where 2 belong", r.len())));
    };
    Ok(Some(FactorOfSafety { stable, failed, trials: take_trials(c)? }))
}

pub(crate) fn saved_totals(c: &Checkpoint) -> Result<RunTotals, CheckpointError> {
    match c.u64s("run.totals")? {
        &[iterations, max_iterations, cutbacks] => Ok(RunTotals {
            iterations: iterations as usize,
            max_iterations: max_iterations as usize,
            cutbacks: cutbacks as usize,
        }),
        v => Err(shape_error("run.totals", format!("{} values where 3 belong", v.len()))),
    }
}

/// The outputs' counters of a stepping checkpoint; which outputs exist is the scene's.
pub(crate) fn saved_outputs(c: &Checkpoint, history: bool, frames: bool) -> Result<OutputsState, CheckpointError> {
    let run_log_bytes = one_u64(c, "outputs.run_log_bytes")?;
    let history = if history {
        let bytes = one_u64(c, "outputs.history_bytes")?;
        Some((bytes, one_f64(c, "outputs.history_work")?))
    } else {
        None
    };
    let frames = if frames {
        let times = c.f64s("outputs.frame_times")?;
        let text = c.text("outputs.frame_files")?;
        let files: Vec<&str> = if text.is_empty() { Vec::new() } else { text.split('\n').collect() };
        if files.len() != times.len() {
            let what = format!("{} frame files for {} times", files.len(), times.len());
            return Err(shape_error("outputs.frame_files", what));
        }
        Some(times.iter().zip(files).map(|(&t, f)| (t, f.to_string())).collect())
    } else {
        None
    };
    Ok(OutputsState { run_log_bytes, history, frames })
}

/// Put `analysis` (built from the checkpoint's scene) in the checkpoint's state.
pub(crate) fn resume_analysis<const D: usize>(
    c: &Checkpoint,
    analysis: &mut Analysis<D>,
) -> Result<(), CheckpointError> {
    let model = take_model(c, analysis.model())?;
    let state = take_analysis(c, analysis.name())?;
    analysis.resume(state, model).map_err(|e| CheckpointError::State(e.to_string()))
}

/// The one value of a section of numbers.
fn one<T: Copy>(values: &[T], section: &str) -> Result<T, CheckpointError> {
    match values {
        &[v] => Ok(v),
        v => Err(shape_error(section, format!("{} values where 1 belongs", v.len()))),
    }
}

fn one_u64(c: &Checkpoint, section: &str) -> Result<u64, CheckpointError> {
    one(c.u64s(section)?, section)
}

fn one_f64(c: &Checkpoint, section: &str) -> Result<f64, CheckpointError> {
    one(c.f64s(section)?, section)
}

const TRIAL_COLUMNS: usize = 7;

fn put_trials(c: &mut Checkpoint, trials: &[StrengthTrial]) {
    let rows = trials.iter().flat_map(|t| {
        [
            t.factor,
            t.stable as u8 as f64,
            t.load_factor,
            t.iterations as f64,
            t.cutbacks as f64,
            t.max_displacement,
            t.wall_time.as_secs_f64(),
        ]
    });
    c.put("search.trials", Section::F64(rows.collect()));
}

fn take_trials(c: &Checkpoint) -> Result<Vec<StrengthTrial>, CheckpointError> {
    let v = c.f64s("search.trials")?;
    if !v.len().is_multiple_of(TRIAL_COLUMNS) {
        return Err(shape_error("search.trials", format!("{} values, not rows of {TRIAL_COLUMNS}", v.len())));
    }
    Ok(v.chunks(TRIAL_COLUMNS)
        .map(|r| StrengthTrial {
            factor: r[0],
            stable: r[1] != 0.0,
            load_factor: r[2],
            iterations: r[3] as usize,
            cutbacks: r[4] as usize,
            max_displacement: r[5],
            wall_time: Duration::try_from_secs_f64(r[6]).unwrap_or_default(),
        })
        .collect())
}

/// The values of `v`, component by component (nalgebra's column-major order).
fn flat<const R: usize, const C: usize>(v: &[SMatrix<f64, R, C>]) -> Section {
    Section::F64(v.iter().flat_map(|m| m.iter().copied()).collect())
}

/// `out` (one entry per point already) from the section `name`, refused unless it holds
/// exactly as many values.
fn unflat<const R: usize, const C: usize>(
    c: &Checkpoint,
    name: &str,
    out: &mut [SMatrix<f64, R, C>],
) -> Result<(), CheckpointError> {
    let v = c.f64s(name)?;
    if v.len() != out.len() * R * C {
        return Err(shape_error(name, format!("{} values where this run has {}", v.len(), out.len() * R * C)));
    }
    for (m, chunk) in out.iter_mut().zip(v.chunks_exact(R * C)) {
        m.copy_from_slice(chunk);
    }
    Ok(())
}

fn put_model<const D: usize>(c: &mut Checkpoint, model: &Model<D>) {
    for (name, column) in model.points().columns() {
        let section = match column {
            Column::Floats(v) => Section::F64(v),
            Column::Integers(v) => Section::U64(v),
        };
        c.put(&format!("points.{name}"), section);
    }
    let vertices: Vec<SVector<f64, D>> = model.loads().iter().flat_map(|l| l.positions().iter().copied()).collect();
    c.put("model.load_vertices", flat(&vertices));
    if let Some(mesh) = model.background().mesh() {
        c.put("model.mesh_nodes", flat(mesh.positions()));
    }
}

/// The model state of checkpoint `c` for `model` (built from the same scene): its points,
/// every field read by name and its length checked.
fn take_model<const D: usize>(c: &Checkpoint, model: &Model<D>) -> Result<ModelState<D>, CheckpointError> {
    let column = |name: &str| match c.f64s(&format!("points.{name}")) {
        Ok(v) => Some(Column::Floats(v.to_vec())),
        Err(_) => c.u64s(&format!("points.{name}")).ok().map(|v| Column::Integers(v.to_vec())),
    };
    let p = PointStore::from_columns(&column, model.points().history_stride())
        .map_err(|e| shape_error("points", e.to_string()))?;
    let mut vertices: Vec<SVector<f64, D>> = model.loads().iter().flat_map(|l| l.positions().iter().copied()).collect();
    unflat(c, "model.load_vertices", &mut vertices)?;
    let mut rest = &vertices[..];
    let load_vertices = (model.loads().iter())
        .map(|l| {
            let (this, after) = rest.split_at(l.positions().len());
            rest = after;
            this.to_vec()
        })
        .collect();
    let mesh_nodes = match model.background().mesh() {
        Some(mesh) => {
            let mut x = mesh.positions().to_vec();
            unflat(c, "model.mesh_nodes", &mut x)?;
            Some(x)
        }
        None => None,
    };
    Ok(ModelState { points: p, load_vertices, mesh_nodes })
}

/// The linear solvers by the names a checkpoint gives them (stable, whatever their
/// display names become).
const SOLVER_NAMES: [(LinearSolverKind, &str); 4] = [
    (LinearSolverKind::Cholesky, "cholesky"),
    (LinearSolverKind::Lu, "lu"),
    (LinearSolverKind::Cg, "cg"),
    (LinearSolverKind::BiCgStab, "bicgstab"),
];

fn put_solver(c: &mut Checkpoint, kind: Option<LinearSolverKind>) {
    let name = kind.and_then(|k| SOLVER_NAMES.iter().find(|(s, _)| *s == k)).map_or("", |(_, n)| n);
    c.put("analysis.linear_solver", Section::Text(name.to_string()));
}

fn take_solver(c: &Checkpoint) -> Result<Option<LinearSolverKind>, CheckpointError> {
    let name = c.text("analysis.linear_solver")?;
    if name.is_empty() {
        return Ok(None);
    }
    match SOLVER_NAMES.iter().find(|(_, n)| *n == name) {
        Some((kind, _)) => Ok(Some(*kind)),
        None => Err(shape_error("analysis.linear_solver", format!("`{name}` is not a linear solver"))),
    }
}

fn put_analysis(c: &mut Checkpoint, state: &AnalysisState) {
    let flag = |b: bool| Section::U64(vec![b as u64]);
    match state {
        AnalysisState::QuasiStatic(s) => {
            c.put("analysis.step", Section::U64(vec![s.step as u64]));
            c.put("analysis.time", Section::F64(vec![s.load_factor]));
            c.put("quasi_static.previous", Section::F64(s.previous.clone()));
            c.put("quasi_static.previous_increment", Section::F64(s.previous_increment.into_iter().collect()));
            let arc = s.arc_length.map(|a| vec![a.length, a.max_length, a.peak.load_factor, a.peak.step as f64]);
            c.put("quasi_static.arc_length", Section::F64(arc.unwrap_or_default()));
            put_solver(c, s.linear_solver);
        }
        AnalysisState::Dynamic(s) => {
            c.put("analysis.step", Section::U64(vec![s.step as u64]));
            c.put("analysis.time", Section::F64(vec![s.time]));
            c.put("dynamic.started", flag(s.started));
            c.put("dynamic.nodal_mass", Section::F64(s.nodal_mass.clone()));
            c.put("dynamic.nodal_velocity", Section::F64(s.nodal_velocity.clone()));
            c.put("dynamic.nodal_acceleration", Section::F64(s.nodal_acceleration.clone()));
            put_solver(c, s.linear_solver);
        }
        AnalysisState::Explicit(s) => {
            c.put("analysis.step", Section::U64(vec![s.steps as u64]));
            c.put("analysis.time", Section::F64(vec![s.time]));
        }
    }
}

/// The arc-length state of a quasi-static checkpoint: length, longest length, peak load
/// factor and its step; none where the section is empty, or absent (a checkpoint written
/// before arc-length control).
fn take_arc_length(c: &Checkpoint) -> Result<Option<ArcLengthState>, CheckpointError> {
    let name = "quasi_static.arc_length";
    let values = match c.f64s(name) {
        Err(CheckpointError::Missing(_)) => return Ok(None),
        other => other?,
    };
    match *values {
        [] => Ok(None),
        [length, max_length, load_factor, step]
            if length.is_finite()
                && length > 0.0
                && max_length.is_finite()
                && max_length >= length
                && load_factor.is_finite()
                && step >= 1.0
                && step.fract() == 0.0 =>
        {
            Ok(Some(ArcLengthState { length, max_length, peak: Peak { step: step as usize, load_factor } }))
        }
        _ => Err(shape_error(
            name,
            format!("{values:?}: not (length > 0, longest ≥ length, peak load factor, peak step ≥ 1)"),
        )),
    }
}

/// The analysis state of checkpoint `c` for an analysis named `name`.
fn take_analysis(c: &Checkpoint, name: &str) -> Result<AnalysisState, CheckpointError> {
    let step = one_u64(c, "analysis.step")? as usize;
    let time = one_f64(c, "analysis.time")?;
    Ok(match name {
        "quasi-static" => {
            let increment = c.f64s("quasi_static.previous_increment")?;
            if increment.len() > 1 {
                return Err(shape_error("quasi_static.previous_increment", format!("{} values", increment.len())));
            }
            AnalysisState::QuasiStatic(QuasiStaticState {
                step,
                load_factor: time,
                previous: c.f64s("quasi_static.previous")?.to_vec(),
                previous_increment: increment.first().copied(),
                linear_solver: take_solver(c)?,
                arc_length: take_arc_length(c)?,
            })
        }
        "implicit dynamic" => AnalysisState::Dynamic(DynamicState {
            step,
            time,
            started: one_u64(c, "dynamic.started")? != 0,
            nodal_mass: c.f64s("dynamic.nodal_mass")?.to_vec(),
            nodal_velocity: c.f64s("dynamic.nodal_velocity")?.to_vec(),
            nodal_acceleration: c.f64s("dynamic.nodal_acceleration")?.to_vec(),
            linear_solver: take_solver(c)?,
        }),
        _ => AnalysisState::Explicit(ExplicitState { steps: step, time }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intervals_are_steps_or_wall_times() {
        assert_eq!("50".parse(), Ok(CheckpointEvery::Steps(50)));
        assert_eq!("90s".parse(), Ok(CheckpointEvery::Wall(Duration::from_secs(90))));
        assert_eq!(" 1.5 m".parse(), Ok(CheckpointEvery::Wall(Duration::from_secs(90))));
        assert_eq!("2h".parse(), Ok(CheckpointEvery::Wall(Duration::from_secs(7200))));
        for bad in ["0", "-3", "10 parsecs", "s", "0m", "nanh", "1e300h", ""] {
            let e = bad.parse::<CheckpointEvery>().unwrap_err();
            assert!(e.contains("number of steps"), "{bad}: {e}");
        }
        for every in [CheckpointEvery::Steps(7), CheckpointEvery::Wall(Duration::from_millis(1500))] {
            assert_eq!(every.to_string().parse(), Ok(every));
        }
    }
}
