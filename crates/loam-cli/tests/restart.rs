//! Restart as a user meets it: `loam run --checkpoint-every` killed by SIGKILL at a random
//! step (or strength-reduction trial), then `loam resume`, ends with the outputs of a run
//! that was never stopped, byte for byte: `points_final.csv`, every frame and the PVD
//! collection, `history.csv`, and `run_log.csv` and `strength_reduction.csv` but for
//! their wall-time columns. One case per analysis: quasi-static (with the extrapolated
//! increment and a prescribed displacement), strength reduction, implicit dynamics and
//! explicit.
//!
//! The step is drawn from a seed printed with the case (`LOAM_RESTART_SEED` fixes it);
//! the kill lands wherever the run is when the test sees that step in the log — inside a
//! later step or in the middle of writing a checkpoint.

mod common;
use common::{env_or, Rng};

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn example(name: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples").join(name);
    std::fs::read_to_string(path).unwrap()
}

/// `text` with `from` replaced by `to` (which must be there: the test would otherwise run
/// another scene than it says).
fn edit(text: &str, from: &str, to: &str) -> String {
    assert!(text.contains(from), "the example no longer has {from:?}");
    text.replacen(from, to, 1)
}

fn loam(args: &[&std::ffi::OsStr]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_loam"));
    c.args(args).stdout(Stdio::null()).stderr(Stdio::piped());
    c
}

/// Lines in `path` so far (0 if it is not there yet).
fn lines(path: &Path) -> usize {
    std::fs::read(path).map_or(0, |b| b.iter().filter(|&&c| c == b'\n').count())
}

/// Where the killed run is watched: rows of this file past its header.
struct KillAt {
    file: &'static str,
    rows: usize,
}

/// Run `scene` with checkpoints every `every`, killing it once `at.file` holds `at.rows`
/// rows and a checkpoint exists; `false` if it finished first.
fn run_and_kill(scene: &Path, out: &Path, every: &str, at: &KillAt) -> bool {
    let args = ["run".as_ref(), scene.as_os_str(), "--out".as_ref(), out.as_os_str()];
    let mut child = loam(&args).args(["-q", "--checkpoint-every", every]).spawn().expect("the loam binary runs");
    let (watched, checkpoint) = (out.join(at.file), out.join("checkpoint.loam"));
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            assert!(status.success(), "the run to be killed failed on its own");
            return false;
        }
        if lines(&watched) > at.rows && checkpoint.exists() {
            child.kill().unwrap(); // SIGKILL
            child.wait().unwrap();
            return true;
        }
        assert!(start.elapsed() < Duration::from_secs(300), "the run to be killed hangs");
        std::thread::sleep(Duration::from_millis(1));
    }
}

/// The files of `dir` a run writes, by name, with the columns named in `wall` removed
/// from the CSV files (they hold wall times).
fn outputs(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let wall = ["solver_setup_s", "wall_time_s"];
    let mut files: Vec<(String, Vec<u8>)> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv" || e == "vtu" || e == "pvd"))
        .map(|p| {
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            let bytes = std::fs::read(&p).unwrap();
            let bytes = if name.ends_with(".csv") { without_columns(&bytes, &wall) } else { bytes };
            (name, bytes)
        })
        .collect();
    files.sort();
    files
}

fn without_columns(csv: &[u8], drop: &[&str]) -> Vec<u8> {
    let text = String::from_utf8_lossy(csv);
    let header: Vec<&str> = text.lines().next().unwrap_or("").split(',').collect();
    let keep: Vec<bool> = header.iter().map(|h| !drop.contains(h)).collect();
    let mut out = String::new();
    for line in text.lines() {
        let cells: Vec<&str> = line.split(',').zip(&keep).filter(|(_, &k)| k).map(|(c, _)| c).collect();
        out.push_str(&cells.join(","));
        out.push('\n');
    }
    out.into_bytes()
}

/// The case: `scene_text` run whole, then killed at a random row of the file the kill
/// watches (`files`, with the rows each reaches in the whole run) and resumed; the two
/// folders must hold the same outputs.
fn killed_run_resumes_to_the_same_outputs(name: &str, scene_text: &str, every: &str, files: &[&'static str]) {
    let now = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).unwrap();
    let seed = env_or("LOAM_RESTART_SEED", now.as_nanos() as u64);
    let mut rng = Rng(seed | 1);
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join(format!("{name}.ron"));
    std::fs::write(&scene, scene_text).unwrap();
    let (whole, cut) = (dir.path().join("whole"), dir.path().join("cut"));
    let o = loam(&["run".as_ref(), scene.as_os_str(), "--out".as_ref(), whole.as_os_str(), "-q".as_ref()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{name}: {}", String::from_utf8_lossy(&o.stderr));
    let file = files[rng.below(files.len())];
    let rows = lines(&whole.join(file)) - 1;
    // A row in the first 80 %, so that the kill lands before the end.
    let at = KillAt { file, rows: rng.below(rows * 4 / 5).max(1) };
    println!("{name}: seed {seed}, kill after {} rows of {file} (of {rows})", at.rows);
    assert!(run_and_kill(&scene, &cut, every, &at), "{name} (seed {seed}): the run ended before it was killed");
    let o = loam(&["resume".as_ref(), cut.as_os_str(), "-q".as_ref()]).output().unwrap();
    assert!(o.status.success(), "{name} (seed {seed}): resume failed: {}", String::from_utf8_lossy(&o.stderr));
    let (a, b) = (outputs(&whole), outputs(&cut));
    let names = |v: &[(String, Vec<u8>)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(names(&a), names(&b), "{name} (seed {seed}): other files");
    for ((file, x), (_, y)) in a.iter().zip(&b) {
        assert!(x == y, "{name} (seed {seed}): {file} differs after the resume");
    }
}

/// Quasi-static: the von Mises footing (plastic history, a prescribed displacement, the
/// extrapolated increment carried from step to step), shortened to 60 load steps.
#[test]
fn quasi_static_resumes_byte_identical() {
    let text = edit(&example("footing_von_mises.ron"), "load_steps: 200", "load_steps: 60");
    killed_run_resumes_to_the_same_outputs("footing", &text, "1", &["run_log.csv"]);
}

/// Strength reduction: the Griffiths & Lane slope on 2 m cells to a tolerance of 0.05 (8
/// trials, each from the last state that held, which the checkpoint saves), killed during
/// the search or during the run at the factor found.
#[test]
fn strength_reduction_resumes_byte_identical() {
    let text = example("slope_griffiths_lane.ron");
    let text = edit(&text, "cell_size: [1.0, 1.0], cells: [52, 21]", "cell_size: [2.0, 2.0], cells: [26, 11]");
    let text = edit(&text, "tolerance: 0.005", "tolerance: 0.05");
    killed_run_resumes_to_the_same_outputs("slope", &text, "1", &["strength_reduction.csv", "run_log.csv"]);
}

/// Implicit dynamics: the vibrating bar at a tenth of its time step (600 steps), with a
/// history row every step.
#[test]
fn implicit_dynamic_resumes_byte_identical() {
    let text = edit(&example("vibrating_bar.ron"), "time_step: 0.5", "time_step: 0.05");
    killed_run_resumes_to_the_same_outputs("bar", &text, "5", &["run_log.csv"]);
}

/// Explicit: the undrained slope's run-out over its first second (von Mises history, GIMP,
/// finite strain).
#[test]
fn explicit_resumes_byte_identical() {
    let text = edit(&example("slope_runout_explicit.ron"), "duration: 4.0", "duration: 1.0");
    killed_run_resumes_to_the_same_outputs("runout", &text, "1", &["run_log.csv"]);
}

/// A checkpoint is refused, and the folder left as it was, when the scene changed since,
/// when a byte of it changed, and when there is none; `--scene` finds a scene moved since.
#[test]
fn a_foreign_or_damaged_checkpoint_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("column.ron");
    std::fs::write(&scene, example("column.ron")).unwrap();
    let out = dir.path().join("out");
    let args = ["run".as_ref(), scene.as_os_str(), "--out".as_ref(), out.as_os_str(), "-q".as_ref()];
    let o = loam(&args).args(["--checkpoint-every", "5", "--steps", "12"]).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let resume = |extra: &[&str]| {
        let o = loam(&["resume".as_ref(), out.as_os_str(), "-q".as_ref()]).args(extra).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let log_before = std::fs::read(out.join("run_log.csv")).unwrap();
    std::fs::write(&scene, example("column.ron").replace("load_steps: 40", "load_steps: 41")).unwrap();
    let (ok, e) = resume(&[]);
    assert!(!ok && e.contains("another scene file"), "{e}");
    assert_eq!(std::fs::read(out.join("run_log.csv")).unwrap(), log_before, "a refused resume changed the log");
    std::fs::remove_file(&scene).unwrap();
    let (ok, e) = resume(&[]);
    assert!(!ok && e.contains("column.ron"), "{e}");
    let checkpoint = out.join("checkpoint.loam");
    let saved = std::fs::read(&checkpoint).unwrap();
    let mut bytes = saved.clone();
    bytes[saved.len() / 2] ^= 1;
    std::fs::write(&checkpoint, &bytes).unwrap();
    let (ok, e) = resume(&[]);
    assert!(!ok && e.contains("is damaged"), "{e}");
    std::fs::remove_file(&checkpoint).unwrap();
    let (ok, e) = resume(&[]);
    assert!(!ok && e.contains("cannot read the checkpoint"), "{e}");
    std::fs::write(&checkpoint, &saved).unwrap();
    let moved = dir.path().join("moved.ron");
    std::fs::write(&moved, example("column.ron")).unwrap();
    let (ok, e) = resume(&["--scene", moved.to_str().unwrap()]);
    assert!(ok, "{e}");
    assert_eq!(lines(&out.join("run_log.csv")), 41, "the resumed run did not reach its 40 steps");
}
