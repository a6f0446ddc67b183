//! The fields of a VTU frame read back with an independent XML parser (roxmltree): every
//! array a plastic run writes is there with one value (or one per component) per point,
//! the plastic strain agrees with `points_final.csv` and is positive where the soil
//! yielded, and a scene that names its fields gets those and no others. The frames are
//! written as ASCII here; the binary writer is checked against the ASCII values bit for bit
//! in `output::vtu`.

use loam_run::run_scene;
use loam_scene::LoadedScene;
use std::path::Path;

/// A small von Mises block squeezed by a prescribed displacement until it yields.
const BLOCK: &str = r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: [0.25, 0.25], cells: [4, 5]),
    basis: Gimp,
    kinematics: SmallStrain,
    materials: [(name: "clay", density: 1.0,
                 law: VonMises(young: 1e4, poisson: 0.3, yield_stress: 10.0))],
    bodies: [(material: "clay", shape: Box(min: [0.0, 0.0], max: [1.0, 1.0]))],
    gravity: [0.0, 0.0],
    constraints: [
        Roller(axis: Y, at: 0.0),
        Roller(axis: X, at: 0.0),
        Displacement(axis: Y, at: 1.0, displacement: [None, Some(-0.01)]),
    ],
    analysis: QuasiStatic(load_steps: 4),
    output: (vtu_every: 4, final_csv: true, vtu_format: Ascii),
)"#;

/// The PointData arrays of a frame: (name, components, values), and the point count.
fn point_data(path: &Path) -> (usize, Vec<(String, usize, Vec<f64>)>) {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text).unwrap();
    let piece = doc.descendants().find(|n| n.has_tag_name("Piece")).unwrap();
    let points: usize = piece.attribute("NumberOfPoints").unwrap().parse().unwrap();
    let data = piece.children().find(|n| n.has_tag_name("PointData")).unwrap();
    let arrays = data
        .children()
        .filter(|n| n.has_tag_name("DataArray"))
        .map(|a| {
            let components = a.attribute("NumberOfComponents").map_or(1, |c| c.parse().unwrap());
            let values = a.text().unwrap_or("").split_whitespace().map(|v| v.parse().unwrap()).collect();
            (a.attribute("Name").unwrap().to_string(), components, values)
        })
        .collect();
    (points, arrays)
}

fn run(source: &str, out: &Path) {
    let scene = LoadedScene::parse(Path::new("block.ron"), source.to_string()).unwrap();
    run_scene(&scene, out, &mut |_| {}).unwrap();
}

#[test]
fn a_plastic_frame_carries_its_state_fields() {
    let dir = tempfile::tempdir().unwrap();
    run(BLOCK, dir.path());
    let (points, arrays) = point_data(&dir.path().join("points_00004.vtu"));
    assert_eq!(points, 64);
    let names: Vec<&str> = arrays.iter().map(|a| a.0.as_str()).collect();
    for name in ["displacement", "stress", "p", "q", "plastic_strain", "yielding", "equivalent_plastic_strain"] {
        assert!(names.contains(&name), "{name} missing from {names:?}");
    }
    for (name, components, values) in &arrays {
        assert_eq!(values.len(), points * components, "{name}: {} values", values.len());
        assert!(values.iter().all(|v| v.is_finite()), "{name}");
    }
    let field = |n: &str| &arrays.iter().find(|a| a.0 == n).unwrap().2;
    // A 1 % squeeze of a block whose yield strain is 1e-3: every point yields.
    assert!(field("plastic_strain").iter().all(|&e| e > 0.0));
    assert!(field("yielding").iter().all(|&y| y == 1.0));
    assert_eq!(field("plastic_strain"), field("equivalent_plastic_strain"));
    // The same values as points_final.csv's column (written from the same state).
    let csv = std::fs::read_to_string(dir.path().join("points_final.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let k = header.iter().position(|h| *h == "plastic_strain").unwrap();
    let from_csv: Vec<f64> = csv.lines().skip(1).map(|l| l.split(',').nth(k).unwrap().parse().unwrap()).collect();
    for (a, b) in from_csv.iter().zip(field("plastic_strain")) {
        assert!((a - b).abs() <= 1e-12 * a.abs().max(1e-300), "{a} vs {b}");
    }
}

#[test]
fn a_scene_that_names_its_fields_gets_only_those() {
    let dir = tempfile::tempdir().unwrap();
    run(&BLOCK.replace("final_csv: true,", "final_csv: true, fields: Some([PlasticStrain, MeanStress]),"), dir.path());
    let (_, arrays) = point_data(&dir.path().join("points_00004.vtu"));
    let names: Vec<&str> = arrays.iter().map(|a| a.0.as_str()).collect();
    assert_eq!(names, ["plastic_strain", "p"]);
}

/// A scene of two materials, one without the other's history values (an elastic platen
/// on the von Mises block), writes its frames: the platen's points get 0 for the block's
/// equivalent plastic strain (an elastic body never yields), the block's points theirs.
#[test]
fn a_law_without_a_history_value_writes_zero_for_it() {
    let two = BLOCK
        .replace(
            "law: VonMises(young: 1e4, poisson: 0.3, yield_stress: 10.0))],",
            "law: VonMises(young: 1e4, poisson: 0.3, yield_stress: 10.0)),\n (name: \"platen\", density: 1.0, law: Elastic(young: 1e6, poisson: 0.3))],",
        )
        .replace(
            "bodies: [(material: \"clay\", shape: Box(min: [0.0, 0.0], max: [1.0, 1.0]))],",
            "bodies: [(material: \"clay\", shape: Box(min: [0.0, 0.0], max: [1.0, 0.75])), (material: \"platen\", shape: Box(min: [0.0, 0.75], max: [1.0, 1.0]))],",
        );
    assert_ne!(two, BLOCK);
    let dir = tempfile::tempdir().unwrap();
    run(&two, dir.path());
    let (points, arrays) = point_data(&dir.path().join("points_00004.vtu"));
    let field = |n: &str| &arrays.iter().find(|a| a.0 == n).unwrap().2;
    let (material, plastic) = (field("material"), field("equivalent_plastic_strain"));
    assert_eq!(plastic.len(), points);
    assert!(material.iter().zip(plastic).all(|(&m, &e)| if m == 1.0 { e == 0.0 } else { e > 0.0 }), "{plastic:?}");
}
