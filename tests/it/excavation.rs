//! Points that go mid-run: an excavation stage of a scene removes the points of a region
//! after a step, and the run goes on with the rest — equilibrium with the weight left,
//! the outputs of the points left, momentum of the body left.

use crate::restart::scene;
use loam::run::{run_scene, RunEvent};
use std::path::Path;

/// The columns of a CSV file by name, numbers parsed.
fn columns(path: &Path) -> Vec<(String, Vec<f64>)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|v| v.parse().unwrap()).collect()).collect();
    header.into_iter().enumerate().map(|(k, name)| (name, rows.iter().map(|r| r[k]).collect())).collect()
}

fn column<'a>(columns: &'a [(String, Vec<f64>)], name: &str) -> &'a [f64] {
    &columns.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no column {name}")).1
}

/// The V1c column (examples/column.ron), its points above y = 6 m removed halfway up the
/// load: the run goes on to full gravity, and then the base carries the weight of the
/// points left (Σ m g from points_final.csv, to the Newton tolerance 1e-9 of the residual:
/// 1e-7 relative), every output has their count, and no point left lies where the stage
/// cut (the column only settles after it).
#[test]
fn an_excavated_column_carries_the_weight_left() {
    let edits = [(
        "analysis: QuasiStatic(load_steps: 40),",
        "analysis: QuasiStatic(load_steps: 40),\n    excavation: [(after_step: 20, region: Box(min: [-1.0, 6.0], max: [2.0, 20.0]))],",
    )];
    let dir = tempfile::tempdir().unwrap();
    let mut removed = Vec::new();
    let summary = run_scene(&scene("column.ron", &edits), dir.path(), &mut |e| {
        if let RunEvent::Excavated { stage, step, removed: n } = e {
            removed.push((stage, step, n));
        }
    })
    .unwrap();
    assert_eq!(summary.steps, 40);
    // 128 points at 4 a cell over 32 cells; those above 6 m at half gravity are gone.
    assert_eq!(removed.len(), 1);
    let (stage, step, n) = removed[0];
    assert_eq!((stage, step), (0, 20));
    assert!(n > 0 && n < 128, "{n} removed");
    assert_eq!(summary.points, 128 - n);
    let points = columns(&dir.path().join("points_final.csv"));
    assert_eq!(column(&points, "mass").len(), 128 - n);
    let weight: f64 = column(&points, "mass").iter().sum::<f64>() * 10.0;
    let log = columns(&dir.path().join("run_log.csv"));
    let base = *column(&log, "constraint2_reaction_y").last().unwrap();
    assert!((base.abs() / weight - 1.0).abs() < 1e-7, "base reaction {base} for a weight {weight}");
    assert!(column(&points, "y").iter().all(|&y| y < 6.0), "the column only settles after the cut");
    let frame = std::fs::read(dir.path().join("points_00040.vtu")).unwrap();
    let count = format!("NumberOfPoints=\"{}\"", 128 - n);
    assert!(frame.windows(count.len()).any(|w| w == count.as_bytes()), "the last frame has the points left");
}

/// The colliding disks (V5) in explicit MUSL, the upper-right disk removed after step 20,
/// long before they meet: the lower-left one moves on alone, its momentum m (0.1, 0.1)
/// kept to round-off (an explicit step conserves momentum: the nodal internal forces sum
/// to zero), where both together had none.
#[test]
fn an_explicit_body_left_alone_keeps_its_momentum() {
    let edits = [
        ("duration: 3.0", "duration: 1.0"),
        ("output: (", "excavation: [(after_step: 20, region: Box(min: [0.5, 0.5], max: [1.0, 1.0]))],\n    output: ("),
    ];
    let dir = tempfile::tempdir().unwrap();
    run_scene(&scene("disks.ron", &edits), dir.path(), &mut |_| {}).unwrap();
    let points = columns(&dir.path().join("points_final.csv"));
    let mass: f64 = column(&points, "mass").iter().sum();
    assert!(column(&points, "x0").iter().all(|&x| x < 0.5), "only the lower-left disk is left");
    let history = columns(&dir.path().join("history.csv"));
    let (px, py) = (column(&history, "momentum_x"), column(&history, "momentum_y"));
    assert!(px[0].abs() < 1e-12 && py[0].abs() < 1e-12, "the two disks start with no momentum");
    for (x, y) in px.iter().zip(py).skip_while(|(x, _)| x.abs() < 1e-12) {
        assert!((x / (0.1 * mass) - 1.0).abs() < 1e-12 && (y / (0.1 * mass) - 1.0).abs() < 1e-12, "{x}, {y}");
    }
    assert!((px.last().unwrap() / (0.1 * mass) - 1.0).abs() < 1e-12);
}

/// A stage that could never happen, a region of the wrong dimension and excavation beside
/// strength reduction or arc-length control are refused at their place in the file.
#[test]
fn bad_excavation_stages_are_refused() {
    let at = |stage: &str| {
        let edits = [("analysis: QuasiStatic(load_steps: 40),", stage)];
        scene("column.ron", &edits).build::<2>().err().map(|e| e.to_string()).unwrap_or_default()
    };
    let e = at("analysis: QuasiStatic(load_steps: 40), excavation: [(after_step: 41, region: Box(min: [0.0, 0.0], max: [1.0, 1.0]))],");
    assert!(e.contains("after_step is 41") && e.contains("40 load steps"), "{e}");
    let e = at("analysis: QuasiStatic(load_steps: 40), excavation: [(after_step: 0, region: Box(min: [0.0, 0.0], max: [1.0, 1.0]))],");
    assert!(e.contains("after_step is 0"), "{e}");
    let e = at("analysis: QuasiStatic(load_steps: 40), excavation: [(after_step: 3, region: Box(min: [0.0, 0.0, 0.0], max: [1.0, 1.0, 1.0]))],");
    assert!(e.contains("3 components") && e.contains(":24:"), "{e}");
    let e = at("analysis: QuasiStatic(load_steps: 40, strength_reduction: Some((bracket: (1.0, 2.0), tolerance: 0.01))), excavation: [(after_step: 3, region: Box(min: [0.0, 0.0], max: [1.0, 1.0]))],");
    assert!(e.contains("strength reduction"), "{e}");
    let e = at("analysis: QuasiStatic(load_steps: 40, control: ArcLength(steps: 80)), excavation: [(after_step: 3, region: Box(min: [0.0, 0.0], max: [1.0, 1.0]))],");
    assert!(e.contains("arc-length control cannot be combined"), "{e}");
}

/// Outputs are written in id order whatever the order of the store: a model of points put
/// in reverse writes the points_final.csv, byte for byte, of the model in their first
/// order (geostatic stresses, so every row differs).
#[test]
fn outputs_are_in_id_order() {
    use loam::constitutive::Elastic;
    use loam::grid::{BasisKind, Grid};
    use loam::model::{Kinematics, Model};
    use loam::points::{PointStore, Shape};
    use loam::scene::FieldSpec;
    use nalgebra::Vector2;
    use std::sync::Arc;
    let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [3, 4]).unwrap();
    let mut points = PointStore::new();
    points.fill(&grid, &Shape::Box { min: Vector2::zeros(), max: Vector2::new(2.0, 3.0) }, 2, 1800.0, 0).unwrap();
    let build = |points: PointStore<2>| {
        let law = Arc::new(Elastic::new(1e5, 0.3).unwrap());
        let mut model = Model::new(
            grid.clone(),
            BasisKind::Gimp,
            Kinematics::SmallStrain,
            points,
            vec![law],
            vec![],
            Vector2::new(0.0, -10.0),
        )
        .unwrap();
        model.geostatic_stress(0.5).unwrap();
        model
    };
    let mut reversed = points.clone();
    reversed.reorder(&(0..points.len()).rev().collect::<Vec<_>>()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let fields = [FieldSpec::MeanStress, FieldSpec::Material];
    let write = |model: &Model<2>, name: &str| {
        let path = dir.path().join(name);
        loam::run::write_points_csv(model, &fields, 1.0, &path).unwrap();
        std::fs::read(path).unwrap()
    };
    let (a, b) = (write(&build(points), "a.csv"), write(&build(reversed), "b.csv"));
    assert!(a == b, "the reversed store wrote other rows");
}
