//! Every refusal of the scene loader, word for word with its file:line:column, pinned in
//! one snapshot: a change to how a scene is checked (its order, its places, its wording)
//! shows here as a diff. Each case edits one example scene in one or two places; cases
//! that must be accepted print `ok`.

use loam_scene::{LoadedScene, SceneError};
use std::fmt::Write;
use std::path::Path;

const COLUMN: &str = include_str!("../../../examples/column.ron");
const COLUMN_FEM: &str = include_str!("../../../examples/column_fem.ron");
const BAR: &str = include_str!("../../../examples/vibrating_bar.ron");
const RUNOUT: &str = include_str!("../../../examples/slope_runout_explicit.ron");
const FOOTING: &str = include_str!("../../../examples/footing_von_mises.ron");
const RIGID: &str = include_str!("../../../examples/footing_rigid_explicit.ron");

/// A small 3D scene: a box of soil on a fixed base.
const CUBE: &str = r#"Scene(
    dimension: 3,
    grid: (origin: [0.0, 0.0, 0.0], cell_size: [1.0, 1.0, 1.0], cells: [2, 2, 3]),
    materials: [(name: "soil", density: 1.0, law: Elastic(young: 100.0, poisson: 0.2))],
    bodies: [(material: "soil", shape: Box(min: [0.0, 0.0, 0.0], max: [2.0, 2.0, 2.0]))],
    gravity: [0.0, 0.0, -10.0],
    constraints: [Fixed(axis: Z, at: 0.0)],
    analysis: QuasiStatic(load_steps: 1),
)"#;

/// `base` with each `(from, to)` applied once; `from` must occur.
fn edit(base: &str, edits: &[(&str, &str)]) -> String {
    let mut s = base.to_string();
    for (from, to) in edits {
        assert!(s.contains(from), "test setup: {from:?} not in the scene");
        s = s.replacen(from, to, 1);
    }
    s
}

fn outcome(dimension: usize, source: String) -> String {
    let build = |scene: LoadedScene| -> Result<(), SceneError> {
        match dimension {
            2 => scene.build::<2>().map(|_| ()),
            _ => scene.build::<3>().map(|_| ()),
        }
    };
    match LoadedScene::parse(Path::new("bad.ron"), source).and_then(build) {
        Ok(()) => "ok".into(),
        Err(e) => e.to_string(),
    }
}

const ELASTIC: &str = "law: Elastic(young: 1e5, poisson: 0.0)";
const COLUMN_BOX: &str = "shape: Box(min: [0.0, 0.0], max: [0.3125, 10.0])";
const QS: &str = "QuasiStatic(load_steps: 40)";
const Y0: &str = "Roller(axis: Y, at: 0.0),";
const PLANE: &str = "cells: [1, 33]),";

const CUBE_BOX: &str = "Box(min: [0.0, 0.0, 0.0], max: [2.0, 2.0, 2.0])";

fn mc(rest: &str) -> String {
    format!("law: MohrCoulomb(young: 1e5, poisson: 0.0, {rest})")
}

/// Mohr–Coulomb (c = 10, φ = 30°, ψ = 5°) softening to cohesion `c` (φ_r = 20°) at the
/// plastic strain `kappa`.
fn softening(c: &str, kappa: &str) -> String {
    mc(&format!(
        "cohesion: 10.0, friction: 30.0, dilation: 5.0, \
         softening: Some((cohesion: {c}, friction: 20.0, dilation: 0.0, plastic_strain: {kappa}))"
    ))
}

fn dp(rest: &str) -> String {
    format!("law: DruckerPrager(young: 1e5, poisson: 0.0, {rest})")
}

/// Modified Cam clay (λ = 0.2, κ = 0.04, e₀ = 1.5, M = 1) with `rest`.
fn cc(rest: &str) -> String {
    format!("law: ModifiedCamClay(lambda: 0.2, kappa: 0.04, void_ratio: 1.5, critical_state: Slope(1.0), {rest})")
}

fn vm(rest: &str) -> String {
    format!("law: VonMises(young: 1e5, poisson: 0.0, {rest})")
}

fn cases() -> Vec<(&'static str, usize, String)> {
    let c = |edits: &[(&str, &str)]| edit(COLUMN, edits);
    let soil = |density: &str| format!("(name: \"soil\", density: {density}, {ELASTIC}),");
    let push = |d: &str| format!("{Y0}\n        Displacement(axis: Y, at: 10.0, displacement: {d}),");
    let within = |w: &str| format!("{Y0}\n        Roller(axis: X, at: 0.0, within: Some({w})),");
    let option = |line: &str| format!("{PLANE}\n    {line}");
    let arc = |settings: &str| format!("load_steps: 40, control: ArcLength({settings})");
    // The loads key after the constraints (Y0 is the last constraint line).
    let load = |l: &str| format!("{Y0}\n    ],\n    loads: [\n        {l},");
    let small = "kinematics: SmallStrain,";
    let explicit = "Explicit(duration: 1.0)";
    let dynamic = "ImplicitDynamic(time_step: 0.1, duration: 1.0)";
    // The column named "col", with `constraints` on it and `analysis`.
    let held = |constraints: &[&str], analysis: &str| {
        let named = edit(COLUMN, &[("(material: \"soil\", shape", "(name: \"col\", material: \"soil\", shape")]);
        let at = format!("    body_constraints: [{}],\n    analysis: {analysis},", constraints.join(", "));
        edit(&named, &[("    analysis: QuasiStatic(load_steps: 40),", &at)])
    };
    let mut v: Vec<(&'static str, usize, String)> = vec![
        ("column", 2, c(&[])),
        ("syntax", 2, c(&[("cell_size: [0.3125, 0.3125]", "cell_size: [0.3125 0.3125]")])),
        ("unknown key", 2, c(&[("basis: Gimp,", "basis: Gimp, bass: 1,")])),
        ("missing gravity", 2, c(&[("    gravity: [0.0, -10.0],\n", "")])),
        ("dimension 3 in 2D", 2, c(&[("dimension: 2", "dimension: 3")])),
        ("dimension 4", 2, c(&[("dimension: 2", "dimension: 4")])),
        ("origin length", 2, c(&[("origin: [0.0, 0.0]", "origin: [0.0]")])),
        ("origin NaN", 2, c(&[("origin: [0.0, 0.0]", "origin: [0.0, NaN]")])),
        ("cell size negative", 2, c(&[("cell_size: [0.3125, 0.3125]", "cell_size: [0.3125, -0.3125]")])),
        ("cell size length", 2, c(&[("cell_size: [0.3125, 0.3125]", "cell_size: [0.3125, 0.3125, 1.0]")])),
        ("cells length", 2, c(&[("cells: [1, 33]", "cells: [1]")])),
        ("cells zero", 2, c(&[("cells: [1, 33]", "cells: [0, 33]")])),
        ("cells too many", 2, c(&[("cells: [1, 33]", "cells: [100000000000, 100000000000]")])),
        ("no materials", 2, c(&[(&soil("2000.0"), "")])),
        ("density zero", 2, c(&[("density: 2000.0", "density: 0.0")])),
        ("density infinite", 2, c(&[("density: 2000.0", "density: inf")])),
        ("material twice", 2, c(&[(&soil("2000.0"), &format!("{}\n        {}", soil("2000.0"), soil("1.0")))])),
        ("young negative", 2, c(&[("young: 1e5", "young: -1e5")])),
        ("young infinite", 2, c(&[("young: 1e5", "young: inf")])),
        ("poisson one half", 2, c(&[("poisson: 0.0", "poisson: 0.5")])),
        ("poisson minus one", 2, c(&[("poisson: 0.0", "poisson: -1.0")])),
        ("von mises", 2, c(&[(ELASTIC, &vm("yield_stress: 17.3"))])),
        ("von mises yield zero", 2, c(&[(ELASTIC, &vm("yield_stress: 0.0"))])),
        ("von mises hardening", 2, c(&[(ELASTIC, &vm("yield_stress: 17.3, hardening: -2e5"))])),
        ("von mises softening", 2, c(&[(ELASTIC, &vm("yield_stress: 17.3, hardening: -10.0"))])),
        ("von mises residual", 2, c(&[(ELASTIC, &vm("yield_stress: 17.3, residual_yield_stress: Some(5.0)"))])),
        ("von mises residual high", 2, c(&[(ELASTIC, &vm("yield_stress: 17.3, residual_yield_stress: Some(20.0)"))])),
        ("von mises residual neg", 2, c(&[(ELASTIC, &vm("yield_stress: 17.3, residual_yield_stress: Some(-1.0)"))])),
        ("mohr coulomb", 2, c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 30.0, dilation: 5.0"))])),
        ("tresca", 2, c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 0.0, dilation: 0.0"))])),
        ("drucker prager", 2, c(&[(ELASTIC, &dp("cohesion: 10.0, friction: 30.0, dilation: 5.0"))])),
        ("drucker prager fit", 2, c(&[(ELASTIC, &dp("cohesion: 10.0, friction: 30.0, dilation: 5.0, fit: Extension"))])),
        ("drucker prager fit typo", 2, c(&[(ELASTIC, &dp("cohesion: 10.0, friction: 30.0, dilation: 5.0, fit: Triaxial"))])),
        ("drucker prager dilation", 2, c(&[(ELASTIC, &dp("cohesion: 10.0, friction: 20.0, dilation: 25.0"))])),
        ("drucker prager no strength", 2, c(&[(ELASTIC, &dp("cohesion: 0.0, friction: 0.0, dilation: 0.0"))])),
        (
            "drucker prager residual",
            2,
            c(&[(
                ELASTIC,
                &dp("cohesion: 10.0, friction: 30.0, dilation: 5.0, \
                     softening: Some((cohesion: 12.0, friction: 20.0, dilation: 0.0, plastic_strain: 0.1))"),
            )]),
        ),
        ("friction 90", 2, c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 90.0, dilation: 0.0"))])),
        ("friction negative", 2, c(&[(ELASTIC, &mc("cohesion: 10.0, friction: -1.0, dilation: 0.0"))])),
        ("no strength", 2, c(&[(ELASTIC, &mc("cohesion: 0.0, friction: 0.0, dilation: 0.0"))])),
        ("cohesion negative", 2, c(&[(ELASTIC, &mc("cohesion: -1.0, friction: 20.0, dilation: 0.0"))])),
        ("dilation above friction", 2, c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 20.0, dilation: 25.0"))])),
        (
            "tension cutoff",
            2,
            c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 30.0, dilation: 0.0, tension_cutoff: Some(1.0)"))]),
        ),
        (
            "tension cutoff above apex",
            2,
            c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 30.0, dilation: 0.0, tension_cutoff: Some(100.0)"))]),
        ),
        (
            "tension cutoff negative",
            2,
            c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 30.0, dilation: 0.0, tension_cutoff: Some(-1.0)"))]),
        ),
        ("softening", 2, c(&[(ELASTIC, &softening("2.0", "0.1"))])),
        ("softening upwards", 2, c(&[(ELASTIC, &softening("20.0", "0.1"))])),
        ("softening at zero strain", 2, c(&[(ELASTIC, &softening("2.0", "0.0"))])),
        ("no bodies", 2, c(&[(&format!("(material: \"soil\", {COLUMN_BOX}, points_per_cell: 2),"), "")])),
        ("unknown material", 2, c(&[("(material: \"soil\"", "(material: \"clay\"")])),
        ("box min length", 2, c(&[("min: [0.0, 0.0]", "min: [0.0]")])),
        ("box max infinite", 2, c(&[("max: [0.3125, 10.0]", "max: [0.3125, inf]")])),
        ("ball", 2, c(&[(COLUMN_BOX, "shape: Ball(centre: [0.15, 5.0], radius: 0.1)")])),
        ("ball centre length", 2, c(&[(COLUMN_BOX, "shape: Ball(centre: [0.15], radius: 0.1)")])),
        ("ball radius negative", 2, c(&[(COLUMN_BOX, "shape: Ball(centre: [0.15, 5.0], radius: -1.0)")])),
        ("polygon", 2, c(&[(COLUMN_BOX, "shape: Polygon(vertices: [(0.0, 0.0), (0.3125, 0.0), (0.0, 10.0)])")])),
        ("polygon of two", 2, c(&[(COLUMN_BOX, "shape: Polygon(vertices: [(0.0, 0.0), (0.3125, 0.0)])")])),
        ("points per cell zero", 2, c(&[("points_per_cell: 2", "points_per_cell: 0")])),
        ("empty region", 2, c(&[("min: [0.0, 0.0], max: [0.3125, 10.0]", "min: [0.0, 5.0], max: [0.3125, 5.01]")])),
        ("outside the grid", 2, c(&[("max: [0.3125, 10.0]", "max: [0.3125, 12.0]")])),
        ("quadratic basis", 2, c(&[("basis: Gimp", "basis: QuadraticBSpline")])),
        ("quadratic basis explicit", 2, c(&[("basis: Gimp", "basis: QuadraticBSpline"), (QS, explicit)])),
        ("linear basis", 2, c(&[("basis: Gimp", "basis: Linear")])),
        ("velocity", 2, c(&[("points_per_cell: 2", "points_per_cell: 2, velocity: Some(Uniform([0.0, 1.0]))")])),
        ("velocity length", 2, c(&[("points_per_cell: 2", "points_per_cell: 2, velocity: Some(Uniform([1.0]))")])),
        (
            "velocity infinite",
            2,
            c(&[("points_per_cell: 2", "points_per_cell: 2, velocity: Some(Uniform([0.0, inf]))")]),
        ),
        (
            "sine axis z",
            2,
            c(&[(
                "points_per_cell: 2",
                "points_per_cell: 2, velocity: Some(Sine(amplitude: [0.0, 1.0], axis: Z, wavelength: 4.0))",
            )]),
        ),
        (
            "sine wavelength zero",
            2,
            c(&[(
                "points_per_cell: 2",
                "points_per_cell: 2, velocity: Some(Sine(amplitude: [0.0, 1.0], axis: Y, wavelength: 0.0))",
            )]),
        ),
        ("gravity length", 2, c(&[("gravity: [0.0, -10.0]", "gravity: [0.0, -10.0, 0.0]")])),
        ("gravity NaN", 2, c(&[("gravity: [0.0, -10.0]", "gravity: [NaN, -10.0]")])),
        ("constraint axis z", 2, c(&[(Y0, "Roller(axis: Z, at: 0.0),")])),
        ("constraint off the nodes", 2, c(&[(Y0, "Roller(axis: Y, at: 0.1),")])),
        ("constraint beyond the grid", 2, c(&[(Y0, "Fixed(axis: Y, at: -0.3125),")])),
        ("constraint on no active node", 2, c(&[(Y0, "Roller(axis: Y, at: 10.3125),")])),
        ("explicit constraint on no active node", 2, c(&[(Y0, "Roller(axis: Y, at: 10.3125),"), (QS, explicit)])),
        ("displacement", 2, c(&[(Y0, &push("[None, Some(-0.1)]"))])),
        ("displacement all free", 2, c(&[(Y0, &push("[None, None]"))])),
        ("displacement length", 2, c(&[(Y0, &push("[Some(-0.1)]"))])),
        ("displacement infinite", 2, c(&[(Y0, &push("[Some(inf), None]"))])),
        ("displacement in dynamics", 2, c(&[(Y0, &push("[None, Some(-0.1)]")), (QS, dynamic)])),
        ("displacement in explicit", 2, c(&[(Y0, &push("[None, Some(-0.1)]")), (QS, explicit)])),
        ("within", 2, c(&[(Y0, &within("(min: [0.0, 0.0], max: [0.0, 5.0])"))])),
        ("within length", 2, c(&[(Y0, &within("(min: [0.0], max: [0.0, 5.0])"))])),
        ("within max NaN", 2, c(&[(Y0, &within("(min: [0.0, 0.0], max: [0.0, NaN])"))])),
        ("within upside down", 2, c(&[(Y0, &within("(min: [0.0, 5.0], max: [0.0, 1.0])"))])),
        ("within across the plane", 2, c(&[(Y0, &within("(min: [1.0, 0.0], max: [0.0, 5.0])"))])),
        ("body constraint", 2, held(&["Fixed(body: \"col\", within: Some((min: [0.0, 0.0], max: [0.3125, 0.5])))"], QS)),
        ("body constraint on no body", 2, held(&["Fixed(body: \"wall\")"], QS)),
        ("body constraint all free", 2, held(&["Displacement(body: \"col\", displacement: [None, None])"], QS)),
        ("body constraint upside down", 2, held(&["Fixed(body: \"col\", within: Some((min: [0.0, 5.0], max: [0.3125, 1.0])))"], QS)),
        ("body constraint outside its body", 2, held(&["Fixed(body: \"col\", within: Some((min: [0.0, 10.5], max: [0.3125, 11.0])))"], QS)),
        ("body constraint in explicit", 2, held(&["Fixed(body: \"col\")"], explicit)),
        ("displaced body constraint in explicit", 2, held(&["Displacement(body: \"col\", displacement: [None, Some(-0.1)])"], explicit)),
        ("displaced body constraint in dynamics", 2, held(&["Displacement(body: \"col\", displacement: [None, Some(-0.1)])"], dynamic)),
        ("monitor", 2, c(&[(QS, &format!("{QS},\n    monitor: [(name: \"top\", at: [0.15, 9.9])]"))])),
        ("monitor name", 2, c(&[(QS, &format!("{QS},\n    monitor: [(name: \"top point\", at: [0.15, 9.9])]"))])),
        ("monitor twice", 2, c(&[(QS, &format!("{QS},\n    monitor: [(name: \"top\", at: [0.15, 9.9]), (name: \"top\", at: [0.15, 1.0])]"))])),
        ("monitor outside", 2, c(&[(QS, &format!("{QS},\n    monitor: [(name: \"above\", at: [0.15, 10.2])]"))])),
        ("monitor length", 2, c(&[(QS, &format!("{QS},\n    monitor: [(name: \"top\", at: [0.15])]"))])),
        ("body names twice", 2, held(&["Fixed(body: \"col\")"], QS).replace(
            "    ],\n    gravity",
            "        (name: \"col\", material: \"soil\", shape: Box(min: [0.0, 10.0], max: [0.3125, 10.3])),\n    ],\n    gravity",
        )),
        ("residual tolerance zero", 2, c(&[("residual_tolerance: 1e-9", "residual_tolerance: 0.0")])),
        ("residual tolerance one", 2, c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1.0")])),
        (
            "increment tolerance",
            2,
            c(&[(
                "residual_tolerance: 1e-9",
                "residual_tolerance: 1e-9, \
             increment_tolerance: 2.0",
            )]),
        ),
        ("max iterations zero", 2, c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, max_iterations: 0")])),
        ("too many backtracks", 2, c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, max_backtracks: 50")])),
        ("too many retry backtracks", 2, c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, retry_backtracks: 21")])),
        ("linear lu", 2, c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, linear: Some(Lu)")])),
        ("solver unknown key", 2, c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, linearr: None")])),
        ("bbar finite strain", 2, c(&[(PLANE, &option("anti_locking: BBar,"))])),
        ("fbar small strain", 2, c(&[(PLANE, &option("anti_locking: FBar,")), ("kinematics: FiniteStrain,", small)])),
        ("fbar gimp", 2, c(&[(PLANE, &option("anti_locking: FBar,"))])),
        ("bbar gimp", 2, c(&[(PLANE, &option("anti_locking: BBar,")), ("kinematics: FiniteStrain,", small)])),
        (
            "bbar",
            2,
            c(&[(PLANE, &option("anti_locking: BBar,")), ("kinematics: FiniteStrain,", small), ("Gimp", "Linear")]),
        ),
        (
            "assumed strain too strong",
            2,
            c(&[
                (PLANE, &option("anti_locking: AssumedStrain(stabilization: 1.5),")),
                ("kinematics: FiniteStrain,", small),
                ("Gimp", "Linear"),
            ]),
        ),
        ("geometrically linear finite strain", 2, c(&[(PLANE, &option("geometrically_linear: true,"))])),
        (
            "geometrically linear",
            2,
            c(&[(PLANE, &option("geometrically_linear: true,")), ("kinematics: FiniteStrain,", small)]),
        ),
        (
            "geometrically linear explicit",
            2,
            c(&[(PLANE, &option("geometrically_linear: true,")), ("kinematics: FiniteStrain,", small), (QS, explicit)]),
        ),
        ("ghost penalty", 2, c(&[(PLANE, &option("ghost_penalty: Some(0.1),"))])),
        ("ghost penalty negative", 2, c(&[(PLANE, &option("ghost_penalty: Some(-1.0),"))])),
        ("ghost penalty explicit", 2, c(&[(PLANE, &option("ghost_penalty: Some(0.1),")), (QS, explicit)])),
        (
            "fbar explicit",
            2,
            c(&[(PLANE, &option("anti_locking: FBar,")), ("Gimp", "Linear"), (QS, explicit)]),
        ),
        ("axisymmetric", 2, c(&[(PLANE, &option("axisymmetric: true,"))])),
        ("axisymmetric 3D", 3, edit(CUBE, &[("dimension: 3,", "dimension: 3,\n    axisymmetric: true,")])),
        (
            "axisymmetric off the axis",
            2,
            c(&[
                (PLANE, &option("axisymmetric: true,")),
                ("origin: [0.0, 0.0]", "origin: [-0.3125, 0.0]"),
                ("cells: [1, 33]", "cells: [2, 33]"),
            ]),
        ),
        ("axisymmetric radial gravity", 2, c(&[(PLANE, &option("axisymmetric: true,")), ("gravity: [0.0, -10.0]", "gravity: [1.0, -10.0]")])),
        (
            "axisymmetric material at r < 0",
            2,
            c(&[(PLANE, &option("axisymmetric: true,")), (COLUMN_BOX, "shape: Box(min: [-0.3125, 0.0], max: [0.3125, 10.0])")]),
        ),
        ("axisymmetric follower pressure", 2, c(&[(PLANE, &option("axisymmetric: true,")), (Y0, &load("Pressure(within: Some((min: [0.0, 9.9], max: [0.3125, 10.1])), pressure: Uniform(1.0), follower: true)"))])),
        (
            "axisymmetric assumed strain",
            2,
            c(&[
                (PLANE, &option("axisymmetric: true,\n    anti_locking: AssumedStrain(stabilization: 0.1),")),
                ("kinematics: FiniteStrain,", small),
                ("Gimp", "Linear"),
            ]),
        ),
        ("geostatic", 2, c(&[(PLANE, &option("initial_stress: Geostatic(k0: 0.5),"))])),
        ("geostatic negative", 2, c(&[(PLANE, &option("initial_stress: Geostatic(k0: -0.5),"))])),
        ("cam clay", 2, c(&[(PLANE, &option("initial_stress: Geostatic(k0: 0.6),")), (ELASTIC, &cc("shear: Poisson(0.3)"))])),
        ("cam clay unstressed", 2, c(&[(ELASTIC, &cc("shear: Poisson(0.3)"))])),
        (
            "cam clay lambda",
            2,
            c(&[(PLANE, &option("initial_stress: Geostatic(k0: 0.6),")), (ELASTIC, &cc("shear: Poisson(0.3)").replace("lambda: 0.2", "lambda: 0.04"))]),
        ),
        (
            "cam clay ocr",
            2,
            c(&[(PLANE, &option("initial_stress: Geostatic(k0: 0.6),")), (ELASTIC, &cc("shear: Modulus(1e3), initial: OverConsolidation(0.8)"))]),
        ),
        (
            "cam clay preconsolidation too low",
            2,
            c(&[(PLANE, &option("initial_stress: Geostatic(k0: 0.6),")), (ELASTIC, &cc("shear: Modulus(1e3), initial: Preconsolidation(1.0)"))]),
        ),
        (
            "cam clay strength reduction",
            2,
            c(&[
                (PLANE, &option("initial_stress: Geostatic(k0: 0.6),")),
                (ELASTIC, &cc("shear: Poisson(0.3)")),
                ("load_steps: 40", "load_steps: 40,\n        strength_reduction: Some(())"),
            ]),
        ),
        ("load steps zero", 2, c(&[("load_steps: 40", "load_steps: 0")])),
        ("cutbacks zero", 2, c(&[("load_steps: 40", "load_steps: 40, max_cutbacks: 0")])),
        ("limit resolution", 2, c(&[("load_steps: 40", "load_steps: 40, limit_resolution: 1.0")])),
        (
            "strength reduction of elastic",
            2,
            c(&[("load_steps: 40", "load_steps: 40,\n        strength_reduction: Some(())")]),
        ),
        (
            "strength reduction",
            2,
            c(&[
                ("load_steps: 40", "load_steps: 40,\n        strength_reduction: Some(())"),
                (ELASTIC, &vm("yield_stress: 1e6")),
            ]),
        ),
        (
            "strength reduction bracket",
            2,
            c(&[("load_steps: 40", "load_steps: 40,\n        strength_reduction: Some((bracket: (2.0, 1.0)))")]),
        ),
        (
            "strength reduction bracket at zero",
            2,
            c(&[("load_steps: 40", "load_steps: 40,\n        strength_reduction: Some((bracket: (0.0, 1.0)))")]),
        ),
        (
            "strength reduction tolerance",
            2,
            c(&[(
                "load_steps: 40",
                "load_steps: 40,\n        strength_reduction: Some((bracket: (1.0, 1.5), tolerance: 0.6))",
            )]),
        ),
        ("arc length", 2, c(&[("load_steps: 40", &arc("steps: 80"))])),
        ("arc length one step", 2, c(&[("load_steps: 40", &arc("steps: 1"))])),
        ("arc length one load step", 2, c(&[("load_steps: 40", "load_steps: 1, control: ArcLength(steps: 80)")])),
        (
            "arc length cholesky",
            2,
            c(&[("load_steps: 40", &arc("steps: 80")), ("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, linear: Some(Cholesky)")]),
        ),
        ("arc length iterations", 2, c(&[("load_steps: 40", &arc("steps: 80, iterations: 0"))])),
        ("arc length growth", 2, c(&[("load_steps: 40", &arc("steps: 80, max_growth: 0.5"))])),
        (
            "arc length pushed only",
            2,
            c(&[("load_steps: 40", &arc("steps: 80")), (Y0, &push("[None, Some(-0.1)]")), ("gravity: [0.0, -10.0]", "gravity: [0.0, 0.0]")]),
        ),
        ("arc length no load", 2, c(&[("load_steps: 40", &arc("steps: 80")), ("gravity: [0.0, -10.0]", "gravity: [0.0, 0.0]")])),
        (
            "arc length follower",
            2,
            c(&[("load_steps: 40", &arc("steps: 80")), (Y0, &load("Pressure(within: Some((min: [0.0, 9.9], max: [0.3125, 10.1])), pressure: Uniform(1.0), follower: true)"))]),
        ),
        (
            "arc length strength reduction",
            2,
            c(&[("load_steps: 40", &format!("{},\n        strength_reduction: Some(())", arc("steps: 80"))), (ELASTIC, &vm("yield_stress: 1e6"))]),
        ),
        ("dynamic", 2, c(&[(QS, dynamic)])),
        ("dynamic consistent", 2, c(&[(QS, "ImplicitDynamic(time_step: 0.1, duration: 1.0, mass: Consistent)")])),
        ("dynamic step zero", 2, c(&[(QS, "ImplicitDynamic(time_step: 0.0, duration: 1.0)")])),
        ("dynamic duration negative", 2, c(&[(QS, "ImplicitDynamic(time_step: 0.1, duration: -1.0)")])),
        ("dynamic gamma", 2, c(&[(QS, "ImplicitDynamic(time_step: 0.1, duration: 1.0, gamma: 0.4)")])),
        ("dynamic beta", 2, c(&[(QS, "ImplicitDynamic(time_step: 0.1, duration: 1.0, beta: 0.0)")])),
        ("dynamic bossak", 2, c(&[(QS, "ImplicitDynamic(time_step: 0.1, duration: 1.0, bossak_alpha: 0.5)")])),
        ("explicit", 2, c(&[(QS, explicit)])),
        ("explicit usl", 2, c(&[(QS, "Explicit(duration: 1.0, scheme: Usl)")])),
        ("explicit usf", 2, c(&[(QS, "Explicit(duration: 1.0, scheme: Usf, flip: 0.5)")])),
        ("explicit duration zero", 2, c(&[(QS, "Explicit(duration: 0.0)")])),
        ("explicit damping", 2, c(&[(QS, "Explicit(duration: 1.0, damping: 1.5)")])),
        ("explicit flip", 2, c(&[(QS, "Explicit(duration: 1.0, flip: 2.0)")])),
        ("explicit cfl zero", 2, c(&[(QS, "Explicit(duration: 1.0, time_step: Cfl(0.0))")])),
        ("explicit cfl above one", 2, c(&[(QS, "Explicit(duration: 1.0, time_step: Cfl(1.5))")])),
        ("explicit fixed", 2, c(&[(QS, "Explicit(duration: 1.0, time_step: Fixed(dt: 1e-4))")])),
        ("explicit fixed zero", 2, c(&[(QS, "Explicit(duration: 1.0, time_step: Fixed(dt: 0.0))")])),
        ("explicit fixed above critical", 2, c(&[(QS, "Explicit(duration: 1.0, time_step: Fixed(dt: 1.0))")])),
        (
            "explicit fixed above critical allowed",
            2,
            c(&[(QS, "Explicit(duration: 1.0, time_step: Fixed(dt: 1.0, allow_above_critical: true))")]),
        ),
    ];
    let f = |edits: &[(&str, &str)]| edit(COLUMN_FEM, edits);
    let block = |y0: &str, y1: &str, rest: &str| {
        format!("(material: \"soil\", shape: Box(min: [0.0, {y0}], max: [0.3125, {y1}]), points_per_cell: {rest}),")
    };
    let fem_velocity = |v: &str| format!("points_per_cell: 2, velocity: Some({v})");
    v.extend([
        ("fem", 2, f(&[])),
        ("fem gauss order", 2, f(&[("points_per_cell: 2", "points_per_cell: 4")])),
        ("fem polygon", 2, f(&[(COLUMN_BOX, "shape: Polygon(vertices: [(0.0, 0.0), (0.3125, 0.0), (0.0, 10.0)])")])),
        ("fem ball", 2, f(&[(COLUMN_BOX, "shape: Ball(centre: [0.15, 5.0], radius: 0.1)")])),
        ("fem box length", 2, f(&[("max: [0.3125, 10.0]", "max: [0.3125]")])),
        ("fem box upside down", 2, f(&[("max: [0.3125, 10.0]", "max: [0.3125, -10.0]")])),
        (
            "fem two orders",
            2,
            f(&[(
                &format!("(material: \"soil\", {COLUMN_BOX}, points_per_cell: 2),"),
                &format!("{}\n        {}", block("0.0", "5.0", "2"), block("5.0", "10.0", "3")),
            )]),
        ),
        (
            "fem two blocks",
            2,
            f(&[(
                &format!("(material: \"soil\", {COLUMN_BOX}, points_per_cell: 2),"),
                &format!(
                    "{}\n        {}",
                    block("0.0", "5.0", "2"),
                    block("5.0", "10.0", "2, velocity: Some(Uniform([0.0, 1.0]))")
                ),
            )]),
        ),
        ("fem velocity", 2, f(&[("points_per_cell: 2", &fem_velocity("Uniform([0.0, 1.0])"))])),
        ("fem velocity length", 2, f(&[("points_per_cell: 2", &fem_velocity("Uniform([1.0])"))])),
        (
            "fem velocity wavelength",
            2,
            f(&[("points_per_cell: 2", &fem_velocity("Sine(amplitude: [1.0, 0.0], axis: Y, wavelength: -1.0)"))]),
        ),
        ("fem unknown material", 2, f(&[("(material: \"soil\"", "(material: \"clay\"")])),
        ("fem explicit", 2, f(&[("QuasiStatic(load_steps: 10)", explicit)])),
        ("fem explicit damping", 2, f(&[("QuasiStatic(load_steps: 10)", "Explicit(duration: 1.0, damping: 2.0)")])),
        ("fem dynamic", 2, f(&[("QuasiStatic(load_steps: 10)", dynamic)])),
        ("fem constraint on no active node", 2, f(&[(Y0, "Roller(axis: Y, at: 10.3125),")])),
        ("load surcharge", 2, c(&[(Y0, &load("Pressure(within: Some((min: [0.0, 9.9], max: [0.3125, 10.1])), pressure: Uniform(1e4))"))])),
        ("load whole boundary", 2, c(&[(Y0, &load("Traction(traction: [0.0, -1.0])"))])),
        ("load point", 2, c(&[(Y0, &load("PointLoad(at: [0.15, 10.0], force: [0.0, -1e3])"))])),
        ("load point off the material", 2, c(&[(Y0, &load("PointLoad(at: [0.15, 10.2], force: [0.0, -1e3])"))])),
        ("load box off the boundary", 2, c(&[(Y0, &load("Pressure(within: Some((min: [0.05, 4.0], max: [0.25, 6.0])), pressure: Uniform(1e4))"))])),
        ("load box unordered", 2, c(&[(Y0, &load("Pressure(within: Some((min: [0.0, 11.0], max: [0.3125, 9.0])), pressure: Uniform(1e4))"))])),
        ("load body missing", 2, c(&[(Y0, &load("Traction(body: 2, traction: [0.0, -1.0])"))])),
        ("load traction length", 2, c(&[(Y0, &load("Traction(traction: [-1.0])"))])),
        ("load pressure infinite", 2, c(&[(Y0, &load("Pressure(pressure: Uniform(inf))"))])),
        ("load hydrostatic", 2, c(&[(Y0, &load("Pressure(pressure: Hydrostatic(level: 8.0, unit_weight: 10.0))"))])),
        ("load linear gradient length", 2, c(&[(Y0, &load("Pressure(pressure: Linear(value: 1.0, at: [0.0, 0.0], gradient: [1.0]))"))])),
        ("load time in quasi-static", 2, c(&[(Y0, &load("Traction(traction: [0.0, -1.0], time: Ramp(duration: 1.0))"))])),
        ("load follower in small strain", 2, c(&[("kinematics: FiniteStrain", "kinematics: SmallStrain"), (Y0, &load("Pressure(pressure: Uniform(1.0), follower: true)"))])),
        (
            "load follower geometrically linear",
            2,
            c(&[(PLANE, &option("geometrically_linear: true,")), ("kinematics: FiniteStrain,", small), (Y0, &load("Pressure(pressure: Uniform(1.0), follower: true)"))]),
        ),
        ("load follower", 2, c(&[(Y0, &load("Pressure(pressure: Uniform(1.0), follower: true)"))])),
        ("load on the fem reference", 2, f(&[(Y0, &load("Traction(traction: [0.0, -1.0])"))])),
        ("water", 2, c(&[("kinematics: FiniteStrain", "kinematics: SmallStrain"), (PLANE, &option("water: Some((unit_weight: 10.0, level: Horizontal(5.0))),"))])),
        ("water polyline", 2, c(&[(PLANE, &option("water: Some((unit_weight: 10.0, level: Polyline([(0.0, 4.0), (0.3125, 6.0)]))),"))])),
        ("water level above the grid", 2, c(&[(PLANE, &option("water: Some((unit_weight: 10.0, level: Horizontal(20.0))),"))])),
        ("water unit weight", 2, c(&[(PLANE, &option("water: Some((unit_weight: -1.0, level: Horizontal(5.0))),"))])),
        ("water polyline backwards", 2, c(&[(PLANE, &option("water: Some((unit_weight: 10.0, level: Polyline([(1.0, 4.0), (0.0, 6.0)]))),"))])),
        ("vibrating bar", 2, edit(BAR, &[])),
        ("bar sine axis", 2, edit(BAR, &[("axis: X, wavelength", "axis: Z, wavelength")])),
        ("bar amplitude length", 2, edit(BAR, &[("amplitude: [0.1, 0.0]", "amplitude: [0.1]")])),
        ("bar gamma", 2, edit(BAR, &[("duration: 30.0", "duration: 30.0, gamma: 0.3")])),
        ("bar load table", 2, edit(BAR, &[("analysis:", "loads: [PointLoad(at: [1.0, 0.5], force: [1.0, 0.0], time: Table([(0.0, 0.0), (2.0, 1.0)]))],\n    analysis:")])),
        ("bar load table not increasing", 2, edit(BAR, &[("analysis:", "loads: [PointLoad(at: [1.0, 0.5], force: [1.0, 0.0], time: Table([(0.0, 0.0), (2.0, 1.0), (2.0, 0.0)]))],\n    analysis:")])),
        ("bar load ramp zero", 2, edit(BAR, &[("analysis:", "loads: [PointLoad(at: [1.0, 0.5], force: [1.0, 0.0], time: Ramp(duration: 0.0))],\n    analysis:")])),
        ("runout", 2, edit(RUNOUT, &[])),
        ("runout with water", 2, edit(RUNOUT, &[("analysis:", "water: Some((unit_weight: 10.0, level: Horizontal(5.0))),\n    analysis:")])),
        ("runout fixed step", 2, edit(RUNOUT, &[("Cfl(0.5)", "Fixed(dt: 0.5)")])),
        ("runout frictional base", 2, edit(RUNOUT, &[("analysis:", "frictional_planes: [(point: [0.0, 0.0], normal: [0.0, 1.0], friction: 0.4)],\n    analysis:")])),
        ("runout friction negative", 2, edit(RUNOUT, &[("analysis:", "frictional_planes: [(point: [0.0, 0.0], normal: [0.0, 1.0], friction: -0.4)],\n    analysis:")])),
        ("runout frictional normal zero", 2, edit(RUNOUT, &[("analysis:", "frictional_planes: [(point: [0.0, 0.0], normal: [0.0, 0.0], friction: 0.4)],\n    analysis:")])),
        ("runout frictional plane below the grid", 2, edit(RUNOUT, &[("analysis:", "frictional_planes: [(point: [0.0, -1.0], normal: [0.0, 1.0], friction: 0.4)],\n    analysis:")])),
        ("runout inclined roller", 2, edit(RUNOUT, &[("analysis:", "inclined_rollers: [(point: [0.0, 0.0], normal: [-0.5, 0.8660254037844386])],\n    analysis:")])),
        ("runout body contact", 2, edit(RUNOUT, &[("analysis:", "body_contact: Some((friction: 0.3)),\n    analysis:"), ("Cfl(0.5)", "Cfl(0.5), scheme: Usl")])),
        ("runout body contact, MUSL", 2, edit(RUNOUT, &[("analysis:", "body_contact: Some((friction: 0.3)),\n    analysis:")])),
        ("runout body contact friction NaN", 2, edit(RUNOUT, &[("analysis:", "body_contact: Some((friction: NaN)),\n    analysis:"), ("Cfl(0.5)", "Cfl(0.5), scheme: Usl")])),
        ("bar load body contact", 2, edit(BAR, &[("analysis:", "loads: [PointLoad(at: [1.0, 0.5], force: [1.0, 0.0], time: Ramp(duration: 1.0))],\n    body_contact: Some((friction: 0.3)),\n    analysis:")])),
        ("column body contact, quasi-static", 2, edit(COLUMN, &[("analysis:", "body_contact: Some((friction: 0.3)),\n    analysis:")])),
        ("rigid footing", 2, edit(RIGID, &[])),
        ("rigid footing unknown body", 2, edit(RIGID, &[("(body: \"footing\",", "(body: \"pile\",")])),
        ("rigid footing velocity of one", 2, edit(RIGID, &[("velocity: [0.0, -0.1]", "velocity: [-0.1]")])),
        ("rigid footing velocity NaN", 2, edit(RIGID, &[("velocity: [0.0, -0.1]", "velocity: [0.0, NaN]")])),
        ("rigid footing friction negative", 2, edit(RIGID, &[("friction: 0.5", "friction: -0.5")])),
        ("rigid footing, MUSL", 2, edit(RIGID, &[("scheme: Usl, ", "")])),
        ("rigid footing, quasi-static", 2, edit(RIGID, &[("Explicit(duration: 10.0, time_step: Cfl(0.5), scheme: Usl, damping: 0.1)", "QuasiStatic(load_steps: 10)")])),
        ("rigid footing time table decreasing", 2, edit(RIGID, &[("friction: 0.5)", "friction: 0.5, time: Table([(0.0, 0.0), (0.0, 1.0)]))")])),
        ("rigid footing twice", 2, edit(RIGID, &[("friction: 0.5),", "friction: 0.5), (body: \"footing\", velocity: [0.0, 0.0]),")])),
        ("rigid footing and clay", 2, edit(RIGID, &[("friction: 0.5),", "friction: 0.5), (body: \"clay\", velocity: [0.0, 0.0]),")])),
        ("rigid footing overlapping the clay", 2, edit(RIGID, &[("min: [0.0, 3.0], max: [0.5, 3.3]", "min: [0.0, 2.8], max: [0.5, 3.3]")])),
        ("rigid footing overlapping the clay, may_overlap", 2, edit(RIGID, &[("min: [0.0, 3.0], max: [0.5, 3.3]), points_per_cell: 2)", "min: [0.0, 2.8], max: [0.5, 3.3]), points_per_cell: 2, may_overlap: true)")])),
        ("rigid footing leaving the grid", 2, edit(RIGID, &[("velocity: [0.0, -0.1]", "velocity: [0.0, -0.4]")])),
        ("rigid footing with a load", 2, edit(RIGID, &[("rigid_bodies:", "loads: [PointLoad(at: [1.0, 3.0], force: [0.0, -1.0], time: Ramp(duration: 1.0))],\n    rigid_bodies:")])),
        ("column frictional base, quasi-static", 2, edit(COLUMN, &[("analysis:", "frictional_planes: [(point: [0.0, 0.0], normal: [0.0, 1.0], friction: 0.4)],\n    analysis:")])),
        ("runout polygon of two", 2, edit(RUNOUT, &[("(50.0, 0.0), (50.0, 20.0), (30.0, 20.0), (20.0, 10.0), ", "")])),
        ("footing", 2, edit(FOOTING, &[])),
        ("footing gimp", 2, edit(FOOTING, &[("basis: Linear", "basis: Gimp")])),
        ("footing within length", 2, edit(FOOTING, &[("max: [1.0, 5.0]", "max: [1.0]")])),
        ("footing displacement none", 2, edit(FOOTING, &[("[Some(0.0), Some(-0.2)]", "[None, None]")])),
        ("cube", 3, edit(CUBE, &[])),
        ("cube in 2D", 2, edit(CUBE, &[])),
        ("cube gravity length", 3, edit(CUBE, &[("gravity: [0.0, 0.0, -10.0]", "gravity: [0.0, -10.0]")])),
        ("cube cells length", 3, edit(CUBE, &[("cells: [2, 2, 3]", "cells: [2, 2]")])),
        ("cube polygon", 3, edit(CUBE, &[(CUBE_BOX, "Polygon(vertices: [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])")])),
        ("cube water plane", 3, edit(CUBE, &[("analysis:", "water: Some((unit_weight: 10.0, level: Plane(height: 1.0, slope: [0.1, 0.2, 0.0]))),\n    analysis:")])),
        ("cube water plane along gravity", 3, edit(CUBE, &[("analysis:", "water: Some((unit_weight: 10.0, level: Plane(height: 1.0, slope: [0.1, 0.0, 0.5]))),\n    analysis:")])),
        ("cube water plane leaving the grid", 3, edit(CUBE, &[("analysis:", "water: Some((unit_weight: 10.0, level: Plane(height: 2.5, slope: [0.5, 0.0, 0.0]))),\n    analysis:")])),
        ("cube water polyline", 3, edit(CUBE, &[("analysis:", "water: Some((unit_weight: 10.0, level: Polyline([(0.0, 1.0), (2.0, 1.0)]))),\n    analysis:")])),
        ("cube ball", 3, edit(CUBE, &[(CUBE_BOX, "Ball(centre: [1.0, 1.0, 1.0], radius: 0.9)")])),
        ("cube constraint at the top", 3, edit(CUBE, &[("Fixed(axis: Z, at: 0.0)", "Fixed(axis: Z, at: 3.0)")])),
        (
            "cube within",
            3,
            edit(
                CUBE,
                &[(
                    "Fixed(axis: Z, at: 0.0)",
                    "Fixed(axis: Z, at: 0.0, \
             within: Some((min: [0.0, 0.0, 0.0], max: [1.0, 1.0, 0.0])))",
                )],
            ),
        ),
        (
            "cube sine",
            3,
            edit(
                CUBE,
                &[(
                    CUBE_BOX,
                    "Box(min: [0.0, 0.0, 0.0], max: [2.0, 2.0, 2.0]), \
                     velocity: Some(Sine(amplitude: [0.0, 0.0, 1.0], axis: Z, wavelength: 8.0, origin: 1.0))",
                )],
            ),
        ),
    ]);
    v
}

#[test]
fn every_refusal_word_for_word() {
    let mut report = String::new();
    for (name, dimension, source) in cases() {
        writeln!(report, "{name}: {}", outcome(dimension, source)).unwrap();
    }
    insta::assert_snapshot!(report);
}
