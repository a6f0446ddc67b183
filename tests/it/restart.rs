//! Restart through the library: a run stopped after some steps with a checkpoint, then
//! resumed from it, ends in the same state as a run that never stopped — every value of
//! `points_final.csv` bit for bit, and the same Newton iterations. The cases are the
//! state the SIGKILL tests of the `loam` program (crates/loam-cli/tests/restart.rs) do not
//! reach: a body-fitted mesh whose nodes move, loads whose vertices follow the surface, a
//! dead load, two bodies in explicit FLIP, a rigid body on a time table, Cam clay from a
//! geostatic start, and 3D.

use loam::format::checkpoint::Checkpoint;
use loam::run::{resume_scene, run_scene_with, CheckpointEvery, RunOptions, CHECKPOINT_FILE};
use loam::scene::LoadedScene;
use std::path::Path;

/// `examples/name` with each (from, to) replaced once.
pub(crate) fn scene(name: &str, edits: &[(&str, &str)]) -> LoadedScene {
    let path = Path::new("examples").join(name);
    let mut text = std::fs::read_to_string(&path).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{name} no longer has {from:?}");
        text = text.replacen(from, to, 1);
    }
    LoadedScene::parse(&path, text).unwrap()
}

/// Run `scene` whole, and stopped after `stop` steps and resumed: the same final points,
/// and the same monitors and rigid bodies' displacements and forces in `run_log.csv`.
fn resumed_run_matches(scene: &LoadedScene, stop: usize) -> tempfile::TempDir {
    let (whole, cut) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let a = run_scene_with(scene, whole.path(), &RunOptions::default(), &mut |_| {}).unwrap();
    let options = RunOptions {
        max_steps: Some(stop),
        checkpoint_every: Some(CheckpointEvery::Steps(stop)),
        ..Default::default()
    };
    run_scene_with(scene, cut.path(), &options, &mut |_| {}).unwrap();
    let checkpoint = Checkpoint::load(&cut.path().join(CHECKPOINT_FILE)).unwrap();
    let b = resume_scene(scene, checkpoint, cut.path(), &RunOptions::default(), &mut |_| {}).unwrap();
    assert_eq!((a.steps, a.newton_iterations), (b.steps, b.newton_iterations), "{}", scene.path.display());
    let points = |dir: &Path| std::fs::read(dir.join("points_final.csv")).unwrap();
    assert!(points(whole.path()) == points(cut.path()), "{}: the final points differ", scene.path.display());
    let monitors = |dir: &Path| {
        let log = std::fs::read_to_string(dir.join("run_log.csv")).unwrap();
        let header: Vec<&str> = log.lines().next().unwrap().split(',').collect();
        let kept = |name: &str| name.starts_with("monitor_") || name.starts_with("rigid");
        let keep: Vec<usize> = (0..header.len()).filter(|&k| kept(header[k])).collect();
        let rows: Vec<Vec<String>> = (log.lines())
            .map(|l| l.split(',').enumerate().filter(|(k, _)| keep.contains(k)).map(|(_, c)| c.to_string()).collect())
            .collect();
        rows
    };
    let differ = "the monitors or rigid bodies' columns differ";
    assert_eq!(monitors(whole.path()), monitors(cut.path()), "{}: {differ}", scene.path.display());
    whole
}

/// The FEM reference: the mesh's nodes move with the body and are saved with it.
#[test]
fn a_moving_mesh_resumes() {
    resumed_run_matches(&scene("column_fem.ron", &[]), 4);
}

/// A follower pressure: its vertices ride on the points and are saved with them.
#[test]
fn follower_loads_resume() {
    let coarse = [("cell_size: [0.125, 0.125], cells: [44, 44]", "cell_size: [0.25, 0.25], cells: [22, 22]")];
    resumed_run_matches(&scene("cavity_pressure.ron", &coarse), 11);
}

/// A dead pressure, ramped to 40 kPa (below the footing's collapse at 51.4 kPa).
#[test]
fn dead_loads_resume() {
    let below_collapse = [("load_steps: 100", "load_steps: 30"), ("Uniform(64.26990816987241)", "Uniform(40.0)")];
    resumed_run_matches(&scene("footing_load_control.ron", &below_collapse), 13);
}

/// Arc-length control: the length, its cap and the peak are saved, and the secant
/// predictor's last increment with them.
#[test]
fn arc_length_control_resumes() {
    resumed_run_matches(&scene("footing_arc_length.ron", &[("steps: 60", "steps: 20")]), 9);
}

/// Modified Cam clay from a geostatic start: p_c in the history and the exactly carried
/// initial elastic strain are saved and restored (15 steps to the footing's last load).
#[test]
fn cam_clay_resumes() {
    resumed_run_matches(&scene("footing_cam_clay.ron", &[("load_steps: 50", "load_steps: 50, max_cutbacks: 2")]), 6);
}

/// Explicit FLIP with two bodies, and the last step landing on the end time.
#[test]
fn explicit_flip_resumes() {
    resumed_run_matches(&scene("disks.ron", &[("duration: 3.0", "duration: 1.0")]), 17);
}

/// A rigid wall held by a time table, then moved: stopped inside the table's ramp (step
/// 1890 ends at t = 0.8063 s, the ramp is 0.8–0.81 s), its displacement is the table's
/// integral from the saved time, and the fields, the rigid body's among them, are rebuilt
/// on resume.
#[test]
fn a_rigid_body_resumes() {
    let edits = [("duration: 1.55", "duration: 0.9"), ("vtu_every: 500", "vtu_every: 0")];
    let whole = resumed_run_matches(&scene("retaining_wall_explicit.ron", &edits), 1890);
    let log = std::fs::read_to_string(whole.path().join("run_log.csv")).unwrap();
    let header: Vec<&str> = log.lines().next().unwrap().split(',').collect();
    assert!(header.contains(&"rigid0_reaction_x"), "{header:?}");
}

/// 3D: the slope between rough walls at full strength (Mohr–Coulomb history, B-bar), on
/// 4 m cells in four load steps.
#[test]
fn a_3d_run_resumes() {
    let steps = [
        ("cell_size: [2.0, 2.0, 2.0], cells: [26, 6, 11]", "cell_size: [4.0, 4.0, 4.0], cells: [13, 3, 6]"),
        (
        "load_steps: 10, max_cutbacks: 4,\n                          strength_reduction: Some((bracket: (1.0, 2.5), tolerance: 0.01))",
        "load_steps: 4, max_cutbacks: 4",
        ),
    ];
    resumed_run_matches(&scene("slope_3d.ron", &steps), 2);
}

/// Points removed mid-run: an excavation stage after step 10, the run stopped after step
/// 14 and resumed — the removal is in the checkpoint, not done again. A monitor on a point
/// it removes writes NaN from then on, the resumed run too (found on the model as built),
/// and one below it goes on.
#[test]
fn a_run_resumes_after_an_excavation() {
    let stage = [(
        "analysis: QuasiStatic(load_steps: 40),",
        "analysis: QuasiStatic(load_steps: 40),\n    excavation: [(after_step: 10, region: Box(min: [-1.0, 6.0], max: [2.0, 20.0]))],\n    \
         monitor: [(name: \"dug\", at: [0.15, 8.0]), (name: \"kept\", at: [0.15, 3.0])],",
    )];
    let whole = resumed_run_matches(&scene("column.ron", &stage), 14);
    let log = std::fs::read_to_string(whole.path().join("run_log.csv")).unwrap();
    let header: Vec<&str> = log.lines().next().unwrap().split(',').collect();
    let (dug, kept) =
        ["monitor_dug_uy", "monitor_kept_uy"].map(|c| header.iter().position(|h| *h == c).unwrap()).into();
    for (step, row) in log.lines().skip(1).enumerate().map(|(k, l)| (k + 1, l.split(',').collect::<Vec<_>>())) {
        assert_eq!(row[dug] == "NaN", step >= 10, "step {step}: {}", row[dug]);
        assert!(row[kept].parse::<f64>().unwrap().is_finite(), "step {step}");
    }
}
