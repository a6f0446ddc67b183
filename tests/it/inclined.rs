//! A roller on an inclined plane, held in a local frame at the nodes: a body resting under
//! gravity in a trough between a 30° inclined roller and a vertical roller wall.

use loam::run::run_scene;
use loam::scene::LoadedScene;
use std::path::Path;

/// The trough: the incline through (1, 0.75) rising at 30° to the right (normal
/// (−sin 30°, cos 30°) into the block), the wall the grid plane x = 1 above y = 1 (so
/// that no node is held by both), an elastic block filling the corner up to y = 4,
/// 1000 kg/m³ under g = 10 (SI), in one load step.
const TROUGH: &str = r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: [0.5, 0.5], cells: [12, 10]),
    basis: Gimp,
    kinematics: SmallStrain,
    materials: [(name: "block", density: 1000.0, law: Elastic(young: 1e6, poisson: 0.3))],
    bodies: [(material: "block", shape: Polygon(vertices: [(1.0, 0.75), (4.0, 2.4820508075688772), (4.0, 4.0), (1.0, 4.0)]))],
    gravity: [0.0, -10.0],
    constraints: [Roller(axis: X, at: 1.0, within: Some((min: [1.0, 1.0], max: [1.0, 5.0])))],
    inclined_rollers: [(point: [1.0, 0.75], normal: [-0.5, 0.8660254037844386])],
    analysis: QuasiStatic(load_steps: 1),
    solver: (residual_tolerance: 1e-13),
    output: (vtu_every: 0, final_csv: true),
)"#;

/// The weight of the points in `points_final.csv` of a run in `dir` (g = 10).
fn weight(dir: &Path) -> f64 {
    let text = std::fs::read_to_string(dir.join("points_final.csv")).unwrap();
    let mass_column = text.lines().next().unwrap().split(',').position(|c| c == "mass").unwrap();
    let masses = text.lines().skip(1).map(|l| l.split(',').nth(mass_column).unwrap().parse::<f64>().unwrap());
    masses.sum::<f64>() * 10.0
}

/// The last row of a CSV file by column name.
fn last_row(path: &Path) -> Vec<(String, f64)> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    let last: Vec<f64> = lines.last().unwrap().split(',').map(|v| v.parse().unwrap()).collect();
    header.into_iter().zip(last).collect()
}

/// Equilibrium of the block: the incline's reaction is normal to it and, with the wall's
/// (horizontal), sums to the weight, to 1e-10 of the weight (the residual tolerance is
/// 1e-13: the reactions are f_int − f_ext at the held dofs, whose sum over the body is
/// minus the external force exactly, up to the free dofs' residual). So the incline
/// carries W / cos 30° and the wall W tan 30°, the statics of a frictionless trough.
#[test]
fn a_block_in_a_trough_rests_on_the_incline_and_the_wall() {
    let dir = tempfile::tempdir().unwrap();
    let scene = LoadedScene::parse(Path::new("trough.ron"), TROUGH.into()).unwrap();
    run_scene(&scene, dir.path(), &mut |_| {}).unwrap();
    let weight = weight(dir.path());
    let log = last_row(&dir.path().join("run_log.csv"));
    let get = |name: &str| log.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no {name}")).1;
    let (wall, incline) = (get("constraint0_reaction_x"), [get("incline0_reaction_x"), get("incline0_reaction_y")]);
    let n = [-0.5, 0.8660254037844386];
    let along = incline[0] * n[1] - incline[1] * n[0];
    assert!(along.abs() <= 1e-10 * weight, "the incline's reaction {incline:?} has {along} along the plane");
    assert!((wall + incline[0]).abs() <= 1e-10 * weight, "horizontal: wall {wall} + incline {}", incline[0]);
    assert!((incline[1] - weight).abs() <= 1e-10 * weight, "vertical: {} against the weight {weight}", incline[1]);
    let normal_force = (incline[0].powi(2) + incline[1].powi(2)).sqrt();
    assert!((normal_force * 30f64.to_radians().cos() / weight - 1.0).abs() < 1e-10);
    assert!((wall / (weight * 30f64.to_radians().tan()) - 1.0).abs() < 1e-10, "wall {wall}");
}

/// The same trough in two load steps, with and without the extrapolated predictor: the
/// second step starts from the first's increment scaled, whole at the framed nodes (whose
/// increment is along the plane already), so the held normal component stays zero and
/// both runs end in the same state — every point where the other run puts it, to 1e-6 of
/// the largest displacement (the Newton tolerances; a predictor that moved the framed
/// nodes off the plane would leave them there, as Newton never corrects a held dof).
#[test]
fn the_extrapolated_predictor_keeps_the_roller() {
    let run = |extrapolate: bool| {
        let text = TROUGH.replace("QuasiStatic(load_steps: 1)", "QuasiStatic(load_steps: 2)").replace(
            "solver: (residual_tolerance: 1e-13)",
            &format!("solver: (residual_tolerance: 1e-13, extrapolate: {extrapolate})"),
        );
        let dir = tempfile::tempdir().unwrap();
        run_scene(&LoadedScene::parse(Path::new("trough.ron"), text).unwrap(), dir.path(), &mut |_| {}).unwrap();
        let text = std::fs::read_to_string(dir.path().join("points_final.csv")).unwrap();
        text.lines()
            .skip(1)
            .map(|l| l.split(',').take(4).map(|v| v.parse().unwrap()).collect())
            .collect::<Vec<Vec<f64>>>()
    };
    let (plain, extrapolated) = (run(false), run(true));
    let largest = plain.iter().map(|r| (r[2] - r[0]).hypot(r[3] - r[1])).fold(0.0, f64::max);
    let apart = plain.iter().zip(&extrapolated).map(|(a, b)| (a[2] - b[2]).hypot(a[3] - b[3])).fold(0.0, f64::max);
    assert!(largest > 0.0 && apart <= 1e-6 * largest, "{apart} apart for displacements up to {largest}");
}

/// A block on the frictionless 30° incline alone (the trough without its wall), in
/// implicit dynamics: it slides down the incline. The roller's reaction is normal to the
/// plane, and the internal forces sum to zero over the nodes, so the tangential momentum
/// balance of the whole block is Σ m a = W sin 30° exactly (the held dofs are the local
/// normal ones only, every mass-weighted transfer keeps momentum, and the trapezoidal rule
/// integrates a constant acceleration exactly): the centre of mass moves ½ g sin 30° t²
/// down the slope, to the Newton tolerance (bound 1e-6 of that distance; residual
/// tolerance 1e-10) — from rest, gravity sets on at once and the block rings normal to the
/// plane as it settles, which the tangential balance does not see. Normal to the plane the
/// roller holds: no point ends more than 1 cm below it, the compression of a cell (0.5 m)
/// at twice the static strain at the block's base, ρ g H cos 30° / E = 8.7e-3 (measured
/// 3 mm; with the nodal velocity and acceleration keeping their normal components at the
/// roller's nodes, 78 mm). The roller's force is normal to the plane at every step.
#[test]
fn a_block_slides_down_an_inclined_roller_in_implicit_dynamics() {
    let text = TROUGH
        .replace("QuasiStatic(load_steps: 1)", "ImplicitDynamic(time_step: 0.01, duration: 0.3)")
        .replace("constraints: [Roller(axis: X, at: 1.0, within: Some((min: [1.0, 1.0], max: [1.0, 5.0])))],", "")
        .replace("(1.0, 0.75), (4.0, 2.4820508075688772), (4.0, 4.0), (1.0, 4.0)", "(2.0, 1.3273502691896257), (4.0, 2.4820508075688772), (4.0, 3.4820508075688772), (2.0, 2.3273502691896257)")
        .replace("solver: (residual_tolerance: 1e-13)", "solver: (residual_tolerance: 1e-10)");
    let dir = tempfile::tempdir().unwrap();
    run_scene(&LoadedScene::parse(Path::new("incline.ron"), text).unwrap(), dir.path(), &mut |_| {}).unwrap();
    let text = std::fs::read_to_string(dir.path().join("points_final.csv")).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let column = |name: &str| header.iter().position(|c| *c == name).unwrap();
    let (x0, y0, x, y, m) = (column("x0"), column("y0"), column("x"), column("y"), column("mass"));
    let (cos, sin) = (3f64.sqrt() / 2.0, 0.5);
    let above = |px: f64, py: f64| -(px - 1.0) * sin + (py - 0.75) * cos;
    let (mut mass, mut moved, mut lowest) = (0.0, [0.0, 0.0], (f64::INFINITY, f64::INFINITY));
    for row in text.lines().skip(1) {
        let v: Vec<f64> = row.split(',').map(|v| v.parse().unwrap()).collect();
        mass += v[m];
        moved[0] += v[m] * (v[x] - v[x0]);
        moved[1] += v[m] * (v[y] - v[y0]);
        lowest = (lowest.0.min(above(v[x0], v[y0])), lowest.1.min(above(v[x], v[y])));
    }
    let down = -(moved[0] * cos + moved[1] * sin) / mass;
    let expected = 0.5 * 10.0 * sin * 0.3 * 0.3;
    println!("down the slope {down}, expected {expected}; lowest point above the plane {lowest:?}");
    assert!((down / expected - 1.0).abs() < 1e-6, "the centre of mass moved {down} down the slope, not {expected}");
    assert!(lowest.0 > 0.0 && lowest.1 > -0.01, "a point went {} below the roller", -lowest.1);
    // The roller's force is its held (normal) dofs' residual turned to the global frame:
    // normal to the plane to round-off, at every step.
    let log = std::fs::read_to_string(dir.path().join("run_log.csv")).unwrap();
    let header: Vec<&str> = log.lines().next().unwrap().split(',').collect();
    let (rx, ry) = (
        header.iter().position(|c| *c == "incline0_reaction_x").unwrap(),
        header.iter().position(|c| *c == "incline0_reaction_y").unwrap(),
    );
    let weight = mass * 10.0;
    for row in log.lines().skip(1) {
        let v: Vec<f64> = row.split(',').map(|v| v.parse().unwrap()).collect();
        let along = v[rx] * cos + v[ry] * sin;
        assert!(along.abs() <= 1e-9 * weight, "the roller's force has {along} along the plane");
    }
}

/// The trough in explicit dynamics with local damping: once the block has settled, the
/// incline's force on it is normal to the incline (the roller takes only the normal
/// component of a nodal velocity: the tangential part is round-off) and carries the
/// statics' W / cos 30°. The wall's reaction is not reported by explicit runs, so only the
/// incline's is checked; after 3 s of damping 0.7 (about 90 periods of the block's first
/// mode) the residual ringing is read from the run: the bound 1 % is the settling's, not
/// the roller's.
#[test]
fn an_explicit_run_rests_on_an_inclined_roller() {
    let dir = tempfile::tempdir().unwrap();
    let text = TROUGH.replace("QuasiStatic(load_steps: 1)", "Explicit(duration: 3.0, damping: 0.7)");
    let scene = LoadedScene::parse(Path::new("trough.ron"), text).unwrap();
    run_scene(&scene, dir.path(), &mut |_| {}).unwrap();
    let last = last_row(&dir.path().join("run_log.csv"));
    let get = |name: &str| last.iter().find(|(k, _)| k == name).unwrap().1;
    let (rx, ry) = (get("incline0_reaction_x"), get("incline0_reaction_y"));
    let weight = weight(dir.path());
    let (n, t) = ((-0.5f64, 3f64.sqrt() / 2.0), (3f64.sqrt() / 2.0, 0.5));
    let normal = rx * n.0 + ry * n.1;
    let tangential = rx * t.0 + ry * t.1;
    println!("normal {normal}, W / cos 30° {}, tangential {tangential}", weight / (3f64.sqrt() / 2.0));
    assert!(tangential.abs() <= 1e-9 * weight, "tangential {tangential}");
    assert!((normal / (weight / (3f64.sqrt() / 2.0)) - 1.0).abs() < 0.01, "normal {normal}");
}
