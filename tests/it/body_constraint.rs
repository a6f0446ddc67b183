//! Constraints on bodies: the nodes a body's points reach, held or displaced, found again
//! at every step so that they follow the body through the grid.

use crate::support::{column, run, table};
use loam::scene::LoadedScene;
use std::path::Path;

/// Confined compression by a platen (SI units), in the linear theory (geometrically
/// linear, two load steps): an elastic soil column 2 m wide and 4 m high (E = 10 MPa,
/// ν = 0.3, no weight) between rollers at x = 0 and x = 2 on a fixed
/// base, a 1 m platen body above it pushed down δ = 1 cm by a body constraint. With the
/// linear basis the platen's points reach the node rows y = 4 and 5, so the soil's top
/// row moves δ and the soil takes the uniform strain ε_yy = −δ/4: σ_yy = M ε_yy and
/// σ_xx = λ ε_yy (M = λ + 2μ, the constrained modulus). A linear displacement field is
/// the discrete solution exactly (interior nodes' forces cancel for points placed
/// symmetrically in their cells), so the stresses hold to round-off: 1e-9 relative
/// covers the Newton tolerance of 1e-12. The platen's reaction is the force the soil's
/// top row takes, width × σ_yy (f_int − f_ext on its nodes), the base's the opposite.
#[test]
fn a_platen_pushed_by_a_body_constraint_compresses_the_soil_uniformly() {
    let delta = 0.01;
    let dir = run(&format!(
        r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: [1.0, 1.0], cells: [2, 7]),
    basis: Linear,
    kinematics: SmallStrain,
    geometrically_linear: true,
    materials: [(name: "soil", density: 1000.0, law: Elastic(young: 1e7, poisson: 0.3))],
    bodies: [
        (material: "soil", shape: Box(min: [0.0, 0.0], max: [2.0, 4.0])),
        (name: "platen", material: "soil", shape: Box(min: [0.0, 4.0], max: [2.0, 5.0])),
    ],
    gravity: [0.0, 0.0],
    constraints: [Roller(axis: X, at: 0.0), Roller(axis: X, at: 2.0), Fixed(axis: Y, at: 0.0)],
    body_constraints: [Displacement(body: "platen", displacement: [None, Some(-{delta})])],
    analysis: QuasiStatic(load_steps: 2),
    solver: (residual_tolerance: 1e-12),
    output: (vtu_every: 0, final_csv: true),
)"#
    ));
    let (young, nu) = (1e7, 0.3);
    let lambda = young * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    let modulus = lambda + young / (1.0 + nu);
    let strain = -delta / 4.0;
    let (header, rows) = table(&dir.path().join("points_final.csv"));
    let (y0, sxx, syy) = (column(&header, "y0"), column(&header, "sxx"), column(&header, "syy"));
    let soil: Vec<_> = rows.iter().filter(|r| r[y0] < 4.0).collect();
    assert_eq!(soil.len(), 32);
    for r in &soil {
        assert!((r[syy] / (modulus * strain) - 1.0).abs() < 1e-9, "σ_yy {} against {}", r[syy], modulus * strain);
        assert!((r[sxx] / (lambda * strain) - 1.0).abs() < 1e-9, "σ_xx {} against {}", r[sxx], lambda * strain);
    }
    let (y, platen_stress) = (column(&header, "y"), rows.iter().filter(|r| r[y0] > 4.0));
    for r in platen_stress {
        assert!((r[y] - (r[y0] - delta)).abs() < 1e-12, "a platen point moves δ: {} from {}", r[y], r[y0]);
        assert!(r[syy].abs() < 1e-9 * modulus * delta, "the platen moves rigidly: σ_yy {}", r[syy]);
    }
    let (header, log) = table(&dir.path().join("run_log.csv"));
    let last = log.last().unwrap();
    let force = 2.0 * modulus * strain;
    let platen = last[column(&header, "body_constraint0_reaction_y")];
    assert!((platen / force - 1.0).abs() < 1e-9, "platen reaction {platen} against {force}");
    assert_eq!(last[column(&header, "body_constraint0_displacement_y")], -delta);
    let base = last[column(&header, "constraint2_reaction_y")];
    assert!((base / -force - 1.0).abs() < 1e-9, "base reaction {base} against {}", -force);
}

/// A body driven by a constraint on all its points goes wherever it is sent, through as
/// many cells as it takes: a 1 m block of GIMP points moved (2.3, −1.7) m in five load
/// steps ends with every point moved exactly that far and unstressed (a rigid
/// translation), where a plane constraint could only hold the nodes it started on. The
/// constraint's box is the block's first place, which its points leave after the first
/// steps: it picks the points once, by where they started.
#[test]
fn a_body_constraint_follows_its_body_through_the_grid() {
    let dir = run(r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: [0.5, 0.5], cells: [12, 12]),
    basis: Gimp,
    kinematics: FiniteStrain,
    materials: [(name: "steel", density: 7800.0, law: Elastic(young: 2e11, poisson: 0.3))],
    bodies: [(name: "block", material: "steel", shape: Box(min: [1.0, 3.5], max: [2.0, 4.5]))],
    gravity: [0.0, 0.0],
    body_constraints: [Displacement(body: "block", displacement: [Some(2.3), Some(-1.7)],
                                    within: Some((min: [1.0, 3.5], max: [2.0, 4.5])))],
    analysis: QuasiStatic(load_steps: 5),
    output: (vtu_every: 0, final_csv: true),
)"#);
    let (header, rows) = table(&dir.path().join("points_final.csv"));
    let [x0, y0, x, y, sxx, syy, sxy] = ["x0", "y0", "x", "y", "sxx", "syy", "sxy"].map(|c| column(&header, c));
    assert_eq!(rows.len(), 16);
    for r in &rows {
        assert!((r[x] - r[x0] - 2.3).abs() < 1e-12 && (r[y] - r[y0] + 1.7).abs() < 1e-12, "{r:?}");
        assert!([sxx, syy, sxy].iter().all(|&c| r[c].abs() < 1e-3), "a rigid translation leaves no stress: {r:?}");
    }
}

/// A body constraint that names no body, a duplicate body name, and an explicit
/// analysis given a displaced body constraint are refused, with a message that says why (their
/// places in the file are pinned in loam-scene's tests/scene_messages.rs).
#[test]
fn body_constraints_are_refused_where_they_cannot_hold() {
    let scene = |bodies: &str, analysis: &str| {
        format!(
            r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: [1.0, 1.0], cells: [4, 4]),
    materials: [(name: "soil", density: 1000.0, law: Elastic(young: 1e7, poisson: 0.3))],
    bodies: [{bodies}],
    gravity: [0.0, -10.0],
    constraints: [Fixed(axis: Y, at: 0.0)],
    body_constraints: [Fixed(body: "wall")],
    analysis: {analysis},
)"#
        )
    };
    let error = |text: String| match LoadedScene::parse(Path::new("s.ron"), text).and_then(|s| s.build::<2>()) {
        Ok(_) => panic!("accepted"),
        Err(e) => e.to_string(),
    };
    let one = r#"(name: "soil", material: "soil", shape: Box(min: [0.0, 0.0], max: [2.0, 2.0]))"#;
    let message = error(scene(one, "QuasiStatic(load_steps: 1)"));
    assert!(
        message.contains("body constraint 0 names body \"wall\", but no body is called that")
            && message.contains("[\"soil\"]"),
        "{message}"
    );
    let two = format!("{one}, {}", one.replace("0.0, 0.0], max: [2.0", "2.0, 0.0], max: [4.0"));
    let message = error(scene(&two, "QuasiStatic(load_steps: 1)"));
    assert!(message.contains("body 1 is called \"soil\", as body 0 is"), "{message}");
    let wall = one.replace("\"soil\", material", "\"wall\", material");
    let pushed = scene(&wall, "Explicit(duration: 0.1)")
        .replace("Fixed(body: \"wall\")", "Displacement(body: \"wall\", displacement: [None, Some(-0.1)])");
    let message = error(pushed);
    assert!(message.contains("body constraint 0 prescribes a non-zero displacement"), "{message}");
}

/// In a dynamic analysis a held body stays where it is, exactly, and carries what rests
/// on it: an elastic column 2 m high (E = 1 MPa, 1000 kg/m³, g = 10, SI) loaded at once
/// by gravity while resting on a slab held by a body constraint oscillates on it; the
/// slab's points never move, the column's never pass into the slab, and the reaction on
/// the slab's nodes (which carry the slab's own weight too), averaged over two periods
/// of the column (T = 4L/c = 0.253 s, c = √(E/ρ)), is the weight of both: the
/// undamped oscillation about the static state averages out over whole periods; 1 %
/// allows for the time step's sampling and the period's numerical lengthening.
#[test]
fn a_held_body_carries_a_column_in_dynamics() {
    let dir = run(r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: [0.25, 0.25], cells: [4, 12]),
    basis: Gimp,
    kinematics: SmallStrain,
    materials: [(name: "soil", density: 1000.0, law: Elastic(young: 1e6, poisson: 0.0))],
    bodies: [
        (name: "slab", material: "soil", shape: Box(min: [0.0, 0.25], max: [1.0, 0.75])),
        (material: "soil", shape: Box(min: [0.0, 0.75], max: [1.0, 2.75])),
    ],
    gravity: [0.0, -10.0],
    constraints: [Roller(axis: X, at: 0.0), Roller(axis: X, at: 1.0)],
    body_constraints: [Fixed(body: "slab")],
    analysis: ImplicitDynamic(time_step: 0.002, duration: 0.506),
    output: (vtu_every: 0, final_csv: true),
)"#);
    let (header, rows) = table(&dir.path().join("points_final.csv"));
    let [y0, x, y, x0] = ["y0", "x", "y", "x0"].map(|c| column(&header, c));
    let weight: f64 = rows.iter().map(|r| r[column(&header, "mass")] * 10.0).sum();
    for r in &rows {
        if r[y0] < 0.75 {
            assert_eq!((r[x], r[y]), (r[x0], r[y0]), "a slab point moved");
        } else {
            assert!(r[y] > 0.75, "a column point passed into the slab: {r:?}");
        }
    }
    let (header, log) = table(&dir.path().join("run_log.csv"));
    let reaction = column(&header, "body_constraint0_reaction_y");
    let mean = log.iter().map(|r| r[reaction]).sum::<f64>() / log.len() as f64;
    assert!((mean / weight - 1.0).abs() < 0.01, "mean reaction {mean} against the weight {weight}");
}

/// In an explicit run a held body is a rigid obstacle: an elastic block sliding at 2 m/s
/// (SI) into a wall held by a body constraint bounces off it. The wall's points end
/// exactly where they started, no point of the block passes the wall's face, and the
/// momentum, +500 kg m/s at the start, is reversed (the wall's points at rest carry none);
/// held only at a far corner, the wall is pushed instead.
#[test]
fn a_held_wall_turns_a_block_back_in_explicit_dynamics() {
    let scene = |held: &str| {
        format!(
            r#"Scene(
    dimension: 2,
    grid: (origin: [0.0, 0.0], cell_size: [0.25, 0.25], cells: [10, 4]),
    basis: Gimp,
    kinematics: FiniteStrain,
    materials: [(name: "rubber", density: 1000.0, law: Elastic(young: 1e6, poisson: 0.3))],
    bodies: [
        (material: "rubber", shape: Box(min: [0.25, 0.0], max: [0.75, 0.5]), velocity: Some(Uniform([2.0, 0.0]))),
        (name: "wall", material: "rubber", shape: Box(min: [1.5, 0.0], max: [2.0, 1.0])),
    ],
    gravity: [0.0, 0.0],
    constraints: [Roller(axis: Y, at: 0.0)],
    body_constraints: [{held}],
    analysis: Explicit(duration: 0.6),
    output: (vtu_every: 0, final_csv: true, history_every: 1),
)"#
        )
    };
    let dir = run(&scene(r#"Fixed(body: "wall")"#));
    let (header, rows) = table(&dir.path().join("points_final.csv"));
    let [x0, y0, x, y] = ["x0", "y0", "x", "y"].map(|c| column(&header, c));
    for r in &rows {
        if r[x0] > 1.5 {
            assert_eq!((r[x], r[y]), (r[x0], r[y0]), "a wall point moved");
        } else {
            assert!(r[x] < 1.5, "a block point passed into the wall: {r:?}");
        }
    }
    let (header, history) = table(&dir.path().join("history.csv"));
    let momentum = column(&header, "momentum_x");
    assert_eq!(history[0][momentum], 500.0);
    assert!(history.last().unwrap()[momentum] < -100.0, "the block bounced: {:?}", history.last());
    let free = run(&scene(r#"Fixed(body: "wall", within: Some((min: [1.9, 0.9], max: [2.0, 1.0])))"#));
    let (_, rows) = table(&free.path().join("points_final.csv"));
    assert!(rows.iter().any(|r| r[x0] > 1.5 && r[x0] < 1.7 && r[x] > r[x0] + 1e-3), "a free wall is pushed");
}
