//! Every refusal of the scene loader, word for word with its file:line:column, pinned in
//! one snapshot: a change to how a scene is checked (its order, its places, its wording)
//! shows here as a diff. Each case edits one example scene in one or two places; cases
//! that must be accepted print `ok`.

use loam_scene::LoadedScene;
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

/// What `loam check` says of `source`.
fn outcome(source: String) -> String {
    match LoadedScene::parse(Path::new("bad.ron"), source).and_then(|scene| scene.check().map(|_| ())) {
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

fn cases() -> Vec<(&'static str, String)> {
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
    let mut v: Vec<(&'static str, String)> = vec![
        ("column", c(&[])),
        ("syntax", c(&[("cell_size: [0.3125, 0.3125]", "cell_size: [0.3125 0.3125]")])),
        ("unknown key", c(&[("basis: Gimp,", "basis: Gimp, bass: 1,")])),
        ("missing gravity", c(&[("    gravity: [0.0, -10.0],\n", "")])),
        ("dimension 3 in 2D", c(&[("dimension: 2", "dimension: 3")])),
        ("dimension 4", c(&[("dimension: 2", "dimension: 4")])),
        ("origin length", c(&[("origin: [0.0, 0.0]", "origin: [0.0]")])),
        ("origin NaN", c(&[("origin: [0.0, 0.0]", "origin: [0.0, NaN]")])),
        ("cell size negative", c(&[("cell_size: [0.3125, 0.3125]", "cell_size: [0.3125, -0.3125]")])),
        ("cell size length", c(&[("cell_size: [0.3125, 0.3125]", "cell_size: [0.3125, 0.3125, 1.0]")])),
        ("cells length", c(&[("cells: [1, 33]", "cells: [1]")])),
        ("cells zero", c(&[("cells: [1, 33]", "cells: [0, 33]")])),
        ("cells too many", c(&[("cells: [1, 33]", "cells: [100000000000, 100000000000]")])),
        ("no materials", c(&[(&soil("2000.0"), "")])),
        ("density zero", c(&[("density: 2000.0", "density: 0.0")])),
        ("density infinite", c(&[("density: 2000.0", "density: inf")])),
        ("material twice", c(&[(&soil("2000.0"), &format!("{}\n        {}", soil("2000.0"), soil("1.0")))])),
        ("young negative", c(&[("young: 1e5", "young: -1e5")])),
        ("young infinite", c(&[("young: 1e5", "young: inf")])),
        ("poisson one half", c(&[("poisson: 0.0", "poisson: 0.5")])),
        ("poisson minus one", c(&[("poisson: 0.0", "poisson: -1.0")])),
        ("von mises", c(&[(ELASTIC, &vm("yield_stress: 17.3"))])),
        ("von mises yield zero", c(&[(ELASTIC, &vm("yield_stress: 0.0"))])),
        ("von mises hardening", c(&[(ELASTIC, &vm("yield_stress: 17.3, hardening: -2e5"))])),
        ("von mises softening", c(&[(ELASTIC, &vm("yield_stress: 17.3, hardening: -10.0"))])),
        ("von mises residual", c(&[(ELASTIC, &vm("yield_stress: 17.3, residual_yield_stress: Some(5.0)"))])),
        ("von mises residual high", c(&[(ELASTIC, &vm("yield_stress: 17.3, residual_yield_stress: Some(20.0)"))])),
        ("von mises residual neg", c(&[(ELASTIC, &vm("yield_stress: 17.3, residual_yield_stress: Some(-1.0)"))])),
        ("mohr coulomb", c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 30.0, dilation: 5.0"))])),
        ("tresca", c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 0.0, dilation: 0.0"))])),
        ("drucker prager", c(&[(ELASTIC, &dp("cohesion: 10.0, friction: 30.0, dilation: 5.0"))])),
        ("drucker prager fit", c(&[(ELASTIC, &dp("cohesion: 10.0, friction: 30.0, dilation: 5.0, fit: Extension"))])),
        ("drucker prager fit typo", c(&[(ELASTIC, &dp("cohesion: 10.0, friction: 30.0, dilation: 5.0, fit: Triaxial"))])),
        ("drucker prager dilation", c(&[(ELASTIC, &dp("cohesion: 10.0, friction: 20.0, dilation: 25.0"))])),
        ("drucker prager no strength", c(&[(ELASTIC, &dp("cohesion: 0.0, friction: 0.0, dilation: 0.0"))])),
        ("drucker prager residual",
            c(&[(
                ELASTIC,
                &dp("cohesion: 10.0, friction: 30.0, dilation: 5.0, \
                     softening: Some((cohesion: 12.0, friction: 20.0, dilation: 0.0, plastic_strain: 0.1))"),
            )]),
        ),
        ("friction 90", c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 90.0, dilation: 0.0"))])),
        ("friction negative", c(&[(ELASTIC, &mc("cohesion: 10.0, friction: -1.0, dilation: 0.0"))])),
        ("no strength", c(&[(ELASTIC, &mc("cohesion: 0.0, friction: 0.0, dilation: 0.0"))])),
        ("cohesion negative", c(&[(ELASTIC, &mc("cohesion: -1.0, friction: 20.0, dilation: 0.0"))])),
        ("dilation above friction", c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 20.0, dilation: 25.0"))])),
        ("tension cutoff",
            c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 30.0, dilation: 0.0, tension_cutoff: Some(1.0)"))]),
        ),
        ("tension cutoff above apex",
            c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 30.0, dilation: 0.0, tension_cutoff: Some(100.0)"))]),
        ),
        ("tension cutoff negative",
            c(&[(ELASTIC, &mc("cohesion: 10.0, friction: 30.0, dilation: 0.0, tension_cutoff: Some(-1.0)"))]),
        ),
        ("softening", c(&[(ELASTIC, &softening("2.0", "0.1"))])),
        ("softening upwards", c(&[(ELASTIC, &softening("20.0", "0.1"))])),
        ("softening at zero strain", c(&[(ELASTIC, &softening("2.0", "0.0"))])),
        ("no bodies", c(&[(&format!("(material: \"soil\", {COLUMN_BOX}, points_per_cell: 2),"), "")])),
        ("unknown material", c(&[("(material: \"soil\"", "(material: \"clay\"")])),
        ("box min length", c(&[("min: [0.0, 0.0]", "min: [0.0]")])),
        ("box max infinite", c(&[("max: [0.3125, 10.0]", "max: [0.3125, inf]")])),
        ("ball", c(&[(COLUMN_BOX, "shape: Ball(centre: [0.15, 5.0], radius: 0.1)")])),
        ("ball centre length", c(&[(COLUMN_BOX, "shape: Ball(centre: [0.15], radius: 0.1)")])),
        ("ball radius negative", c(&[(COLUMN_BOX, "shape: Ball(centre: [0.15, 5.0], radius: -1.0)")])),
        ("polygon", c(&[(COLUMN_BOX, "shape: Polygon(vertices: [(0.0, 0.0), (0.3125, 0.0), (0.0, 10.0)])")])),
        ("polygon of two", c(&[(COLUMN_BOX, "shape: Polygon(vertices: [(0.0, 0.0), (0.3125, 0.0)])")])),
        ("points per cell zero", c(&[("points_per_cell: 2", "points_per_cell: 0")])),
        ("empty region", c(&[("min: [0.0, 0.0], max: [0.3125, 10.0]", "min: [0.0, 5.0], max: [0.3125, 5.01]")])),
        ("outside the grid", c(&[("max: [0.3125, 10.0]", "max: [0.3125, 12.0]")])),
        ("quadratic basis", c(&[("basis: Gimp", "basis: QuadraticBSpline")])),
        ("quadratic basis explicit", c(&[("basis: Gimp", "basis: QuadraticBSpline"), (QS, explicit)])),
        ("linear basis", c(&[("basis: Gimp", "basis: Linear")])),
        ("velocity", c(&[("points_per_cell: 2", "points_per_cell: 2, velocity: Some(Uniform([0.0, 1.0]))")])),
        ("velocity length", c(&[("points_per_cell: 2", "points_per_cell: 2, velocity: Some(Uniform([1.0]))")])),
        ("velocity infinite",
            c(&[("points_per_cell: 2", "points_per_cell: 2, velocity: Some(Uniform([0.0, inf]))")]),
        ),
        ("sine axis z",
            c(&[(
                "points_per_cell: 2",
                "points_per_cell: 2, velocity: Some(Sine(amplitude: [0.0, 1.0], axis: Z, wavelength: 4.0))",
            )]),
        ),
        ("sine wavelength zero",
            c(&[(
                "points_per_cell: 2",
                "points_per_cell: 2, velocity: Some(Sine(amplitude: [0.0, 1.0], axis: Y, wavelength: 0.0))",
            )]),
        ),
        ("gravity length", c(&[("gravity: [0.0, -10.0]", "gravity: [0.0, -10.0, 0.0]")])),
        ("gravity NaN", c(&[("gravity: [0.0, -10.0]", "gravity: [NaN, -10.0]")])),
        ("constraint axis z", c(&[(Y0, "Roller(axis: Z, at: 0.0),")])),
        ("constraint off the nodes", c(&[(Y0, "Roller(axis: Y, at: 0.1),")])),
        ("constraint beyond the grid", c(&[(Y0, "Fixed(axis: Y, at: -0.3125),")])),
        ("constraint on no active node", c(&[(Y0, "Roller(axis: Y, at: 10.3125),")])),
        ("explicit constraint on no active node", c(&[(Y0, "Roller(axis: Y, at: 10.3125),"), (QS, explicit)])),
        ("displacement", c(&[(Y0, &push("[None, Some(-0.1)]"))])),
        ("displacement all free", c(&[(Y0, &push("[None, None]"))])),
        ("displacement length", c(&[(Y0, &push("[Some(-0.1)]"))])),
        ("displacement infinite", c(&[(Y0, &push("[Some(inf), None]"))])),
        ("displacement in dynamics", c(&[(Y0, &push("[None, Some(-0.1)]")), (QS, dynamic)])),
        ("displacement in explicit", c(&[(Y0, &push("[None, Some(-0.1)]")), (QS, explicit)])),
        ("within", c(&[(Y0, &within("(min: [0.0, 0.0], max: [0.0, 5.0])"))])),
        ("within length", c(&[(Y0, &within("(min: [0.0], max: [0.0, 5.0])"))])),
        ("within max NaN", c(&[(Y0, &within("(min: [0.0, 0.0], max: [0.0, NaN])"))])),
        ("within upside down", c(&[(Y0, &within("(min: [0.0, 5.0], max: [0.0, 1.0])"))])),
        ("within across the plane", c(&[(Y0, &within("(min: [1.0, 0.0], max: [0.0, 5.0])"))])),
        ("body constraint", held(&["Fixed(body: \"col\", within: Some((min: [0.0, 0.0], max: [0.3125, 0.5])))"], QS)),
        ("body constraint on no body", held(&["Fixed(body: \"wall\")"], QS)),
        ("body constraint all free", held(&["Displacement(body: \"col\", displacement: [None, None])"], QS)),
        ("body constraint upside down", held(&["Fixed(body: \"col\", within: Some((min: [0.0, 5.0], max: [0.3125, 1.0])))"], QS)),
        ("body constraint outside its body", held(&["Fixed(body: \"col\", within: Some((min: [0.0, 10.5], max: [0.3125, 11.0])))"], QS)),
        ("body constraint in explicit", held(&["Fixed(body: \"col\")"], explicit)),
        ("displaced body constraint in explicit", held(&["Displacement(body: \"col\", displacement: [None, Some(-0.1)])"], explicit)),
        ("displaced body constraint in dynamics", held(&["Displacement(body: \"col\", displacement: [None, Some(-0.1)])"], dynamic)),
        ("monitor", c(&[(QS, &format!("{QS},\n    monitor: [(name: \"top\", at: [0.15, 9.9])]"))])),
        ("monitor name", c(&[(QS, &format!("{QS},\n    monitor: [(name: \"top point\", at: [0.15, 9.9])]"))])),
        ("monitor twice", c(&[(QS, &format!("{QS},\n    monitor: [(name: \"top\", at: [0.15, 9.9]), (name: \"top\", at: [0.15, 1.0])]"))])),
        ("monitor outside", c(&[(QS, &format!("{QS},\n    monitor: [(name: \"above\", at: [0.15, 10.2])]"))])),
        ("monitor length", c(&[(QS, &format!("{QS},\n    monitor: [(name: \"top\", at: [0.15])]"))])),
        ("body names twice", held(&["Fixed(body: \"col\")"], QS).replace(
            "    ],\n    gravity",
            "        (name: \"col\", material: \"soil\", shape: Box(min: [0.0, 10.0], max: [0.3125, 10.3])),\n    ],\n    gravity",
        )),
        ("residual tolerance zero", c(&[("residual_tolerance: 1e-9", "residual_tolerance: 0.0")])),
        ("residual tolerance one", c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1.0")])),
        ("increment tolerance",
            c(&[(
                "residual_tolerance: 1e-9",
                "residual_tolerance: 1e-9, \
             increment_tolerance: 2.0",
            )]),
        ),
        ("max iterations zero", c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, max_iterations: 0")])),
        ("too many backtracks", c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, max_backtracks: 50")])),
        ("too many retry backtracks", c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, retry_backtracks: 21")])),
        ("linear lu", c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, linear: Some(Lu)")])),
        ("solver unknown key", c(&[("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, linearr: None")])),
        ("bbar finite strain", c(&[(PLANE, &option("anti_locking: BBar,"))])),
        ("fbar small strain", c(&[(PLANE, &option("anti_locking: FBar,")), ("kinematics: FiniteStrain,", small)])),
        ("fbar gimp", c(&[(PLANE, &option("anti_locking: FBar,"))])),
        ("bbar gimp", c(&[(PLANE, &option("anti_locking: BBar,")), ("kinematics: FiniteStrain,", small)])),
        ("bbar",
            c(&[(PLANE, &option("anti_locking: BBar,")), ("kinematics: FiniteStrain,", small), ("Gimp", "Linear")]),
        ),
        ("assumed strain too strong",
            c(&[
                (PLANE, &option("anti_locking: AssumedStrain(stabilization: 1.5),")),
                ("kinematics: FiniteStrain,", small),
                ("Gimp", "Linear"),
            ]),
        ),
        ("geometrically linear finite strain", c(&[(PLANE, &option("geometrically_linear: true,"))])),
        ("geometrically linear",
            c(&[(PLANE, &option("geometrically_linear: true,")), ("kinematics: FiniteStrain,", small)]),
        ),
        ("geometrically linear explicit",
            c(&[(PLANE, &option("geometrically_linear: true,")), ("kinematics: FiniteStrain,", small), (QS, explicit)]),
        ),
        ("ghost penalty", c(&[(PLANE, &option("ghost_penalty: Some(0.1),"))])),
        ("ghost penalty negative", c(&[(PLANE, &option("ghost_penalty: Some(-1.0),"))])),
        ("ghost penalty explicit", c(&[(PLANE, &option("ghost_penalty: Some(0.1),")), (QS, explicit)])),
        ("fbar explicit",
            c(&[(PLANE, &option("anti_locking: FBar,")), ("Gimp", "Linear"), (QS, explicit)]),
        ),
        ("axisymmetric", c(&[(PLANE, &option("axisymmetric: true,"))])),
        ("axisymmetric 3D", edit(CUBE, &[("dimension: 3,", "dimension: 3,\n    axisymmetric: true,")])),
        ("axisymmetric off the axis",
            c(&[
                (PLANE, &option("axisymmetric: true,")),
                ("origin: [0.0, 0.0]", "origin: [-0.3125, 0.0]"),
                ("cells: [1, 33]", "cells: [2, 33]"),
            ]),
        ),
        ("axisymmetric radial gravity", c(&[(PLANE, &option("axisymmetric: true,")), ("gravity: [0.0, -10.0]", "gravity: [1.0, -10.0]")])),
        ("axisymmetric material at r < 0",
            c(&[(PLANE, &option("axisymmetric: true,")), (COLUMN_BOX, "shape: Box(min: [-0.3125, 0.0], max: [0.3125, 10.0])")]),
        ),
        ("axisymmetric follower pressure", c(&[(PLANE, &option("axisymmetric: true,")), (Y0, &load("Pressure(within: Some((min: [0.0, 9.9], max: [0.3125, 10.1])), pressure: Uniform(1.0), follower: true)"))])),
        ("axisymmetric assumed strain",
            c(&[
                (PLANE, &option("axisymmetric: true,\n    anti_locking: AssumedStrain(stabilization: 0.1),")),
                ("kinematics: FiniteStrain,", small),
                ("Gimp", "Linear"),
            ]),
        ),
        ("geostatic", c(&[(PLANE, &option("initial_stress: Geostatic(k0: 0.5),"))])),
        ("geostatic negative", c(&[(PLANE, &option("initial_stress: Geostatic(k0: -0.5),"))])),
        ("cam clay", c(&[(PLANE, &option("initial_stress: Geostatic(k0: 0.6),")), (ELASTIC, &cc("shear: Poisson(0.3)"))])),
        ("cam clay unstressed", c(&[(ELASTIC, &cc("shear: Poisson(0.3)"))])),
        ("cam clay lambda",
            c(&[(PLANE, &option("initial_stress: Geostatic(k0: 0.6),")), (ELASTIC, &cc("shear: Poisson(0.3)").replace("lambda: 0.2", "lambda: 0.04"))]),
        ),
        ("cam clay ocr",
            c(&[(PLANE, &option("initial_stress: Geostatic(k0: 0.6),")), (ELASTIC, &cc("shear: Modulus(1e3), initial: OverConsolidation(0.8)"))]),
        ),
        ("cam clay preconsolidation too low",
            c(&[(PLANE, &option("initial_stress: Geostatic(k0: 0.6),")), (ELASTIC, &cc("shear: Modulus(1e3), initial: Preconsolidation(1.0)"))]),
        ),
        ("cam clay strength reduction",
            c(&[
                (PLANE, &option("initial_stress: Geostatic(k0: 0.6),")),
                (ELASTIC, &cc("shear: Poisson(0.3)")),
                ("load_steps: 40", "load_steps: 40,\n        strength_reduction: Some(())"),
            ]),
        ),
        ("load steps zero", c(&[("load_steps: 40", "load_steps: 0")])),
        ("cutbacks zero", c(&[("load_steps: 40", "load_steps: 40, max_cutbacks: 0")])),
        ("limit resolution", c(&[("load_steps: 40", "load_steps: 40, limit_resolution: 1.0")])),
        ("strength reduction of elastic",
            c(&[("load_steps: 40", "load_steps: 40,\n        strength_reduction: Some(())")]),
        ),
        ("strength reduction",
            c(&[
                ("load_steps: 40", "load_steps: 40,\n        strength_reduction: Some(())"),
                (ELASTIC, &vm("yield_stress: 1e6")),
            ]),
        ),
        ("strength reduction bracket",
            c(&[("load_steps: 40", "load_steps: 40,\n        strength_reduction: Some((bracket: (2.0, 1.0)))")]),
        ),
        ("strength reduction bracket at zero",
            c(&[("load_steps: 40", "load_steps: 40,\n        strength_reduction: Some((bracket: (0.0, 1.0)))")]),
        ),
        ("strength reduction tolerance",
            c(&[(
                "load_steps: 40",
                "load_steps: 40,\n        strength_reduction: Some((bracket: (1.0, 1.5), tolerance: 0.6))",
            )]),
        ),
        ("arc length", c(&[("load_steps: 40", &arc("steps: 80"))])),
        ("arc length one step", c(&[("load_steps: 40", &arc("steps: 1"))])),
        ("arc length one load step", c(&[("load_steps: 40", "load_steps: 1, control: ArcLength(steps: 80)")])),
        ("arc length cholesky",
            c(&[("load_steps: 40", &arc("steps: 80")), ("residual_tolerance: 1e-9", "residual_tolerance: 1e-9, linear: Some(Cholesky)")]),
        ),
        ("arc length iterations", c(&[("load_steps: 40", &arc("steps: 80, iterations: 0"))])),
        ("arc length growth", c(&[("load_steps: 40", &arc("steps: 80, max_growth: 0.5"))])),
        ("arc length pushed only",
            c(&[("load_steps: 40", &arc("steps: 80")), (Y0, &push("[None, Some(-0.1)]")), ("gravity: [0.0, -10.0]", "gravity: [0.0, 0.0]")]),
        ),
        ("arc length no load", c(&[("load_steps: 40", &arc("steps: 80")), ("gravity: [0.0, -10.0]", "gravity: [0.0, 0.0]")])),
        ("arc length follower",
            c(&[("load_steps: 40", &arc("steps: 80")), (Y0, &load("Pressure(within: Some((min: [0.0, 9.9], max: [0.3125, 10.1])), pressure: Uniform(1.0), follower: true)"))]),
        ),
        ("arc length strength reduction",
            c(&[("load_steps: 40", &format!("{},\n        strength_reduction: Some(())", arc("steps: 80"))), (ELASTIC, &vm("yield_stress: 1e6"))]),
        ),
        ("dynamic", c(&[(QS, dynamic)])),
        ("dynamic consistent", c(&[(QS, "ImplicitDynamic(time_step: 0.1, duration: 1.0, mass: Consistent)")])),
        ("dynamic step zero", c(&[(QS, "ImplicitDynamic(time_step: 0.0, duration: 1.0)")])),
        ("dynamic duration negative", c(&[(QS, "ImplicitDynamic(time_step: 0.1, duration: -1.0)")])),
        ("dynamic gamma", c(&[(QS, "ImplicitDynamic(time_step: 0.1, duration: 1.0, gamma: 0.4)")])),
        ("dynamic beta", c(&[(QS, "ImplicitDynamic(time_step: 0.1, duration: 1.0, beta: 0.0)")])),
        ("dynamic bossak", c(&[(QS, "ImplicitDynamic(time_step: 0.1, duration: 1.0, bossak_alpha: 0.5)")])),
        ("explicit", c(&[(QS, explicit)])),
        ("explicit usl", c(&[(QS, "Explicit(duration: 1.0, scheme: Usl)")])),
        ("explicit usf", c(&[(QS, "Explicit(duration: 1.0, scheme: Usf, flip: 0.5)")])),
        ("explicit duration zero", c(&[(QS, "Explicit(duration: 0.0)")])),
        ("explicit damping", c(&[(QS, "Explicit(duration: 1.0, damping: 1.5)")])),
        ("explicit flip", c(&[(QS, "Explicit(duration: 1.0, flip: 2.0)")])),
        ("explicit cfl zero", c(&[(QS, "Explicit(duration: 1.0, time_step: Cfl(0.0))")])),
        ("explicit cfl above one", c(&[(QS, "Explicit(duration: 1.0, time_step: Cfl(1.5))")])),
        ("explicit fixed", c(&[(QS, "Explicit(duration: 1.0, time_step: Fixed(dt: 1e-4))")])),
        ("explicit fixed zero", c(&[(QS, "Explicit(duration: 1.0, time_step: Fixed(dt: 0.0))")])),
        ("explicit fixed above critical", c(&[(QS, "Explicit(duration: 1.0, time_step: Fixed(dt: 1.0))")])),
        ("explicit fixed above critical allowed",
            c(&[(QS, "Explicit(duration: 1.0, time_step: Fixed(dt: 1.0, allow_above_critical: true))")]),
        ),
    ];
    let f = |edits: &[(&str, &str)]| edit(COLUMN_FEM, edits);
    let block = |y0: &str, y1: &str, rest: &str| {
        format!("(material: \"soil\", shape: Box(min: [0.0, {y0}], max: [0.3125, {y1}]), points_per_cell: {rest}),")
    };
    let fem_velocity = |v: &str| format!("points_per_cell: 2, velocity: Some({v})");
    v.extend([
        ("fem", f(&[])),
        ("fem gauss order", f(&[("points_per_cell: 2", "points_per_cell: 4")])),
        ("fem polygon", f(&[(COLUMN_BOX, "shape: Polygon(vertices: [(0.0, 0.0), (0.3125, 0.0), (0.0, 10.0)])")])),
        ("fem ball", f(&[(COLUMN_BOX, "shape: Ball(centre: [0.15, 5.0], radius: 0.1)")])),
        ("fem box length", f(&[("max: [0.3125, 10.0]", "max: [0.3125]")])),
        ("fem box upside down", f(&[("max: [0.3125, 10.0]", "max: [0.3125, -10.0]")])),
        ("fem two orders",
            f(&[(
                &format!("(material: \"soil\", {COLUMN_BOX}, points_per_cell: 2),"),
                &format!("{}\n        {}", block("0.0", "5.0", "2"), block("5.0", "10.0", "3")),
            )]),
        ),
        ("fem two blocks",
            f(&[(
                &format!("(material: \"soil\", {COLUMN_BOX}, points_per_cell: 2),"),
                &format!(
                    "{}\n        {}",
                    block("0.0", "5.0", "2"),
                    block("5.0", "10.0", "2, velocity: Some(Uniform([0.0, 1.0]))")
                ),
            )]),
        ),
        ("fem velocity", f(&[("points_per_cell: 2", &fem_velocity("Uniform([0.0, 1.0])"))])),
        ("fem velocity length", f(&[("points_per_cell: 2", &fem_velocity("Uniform([1.0])"))])),
        ("fem velocity wavelength",
            f(&[("points_per_cell: 2", &fem_velocity("Sine(amplitude: [1.0, 0.0], axis: Y, wavelength: -1.0)"))]),
        ),
        ("fem unknown material", f(&[("(material: \"soil\"", "(material: \"clay\"")])),
        ("fem explicit", f(&[("QuasiStatic(load_steps: 10)", explicit)])),
        ("fem explicit damping", f(&[("QuasiStatic(load_steps: 10)", "Explicit(duration: 1.0, damping: 2.0)")])),
        ("fem dynamic", f(&[("QuasiStatic(load_steps: 10)", dynamic)])),
        ("fem constraint on no active node", f(&[(Y0, "Roller(axis: Y, at: 10.3125),")])),
        ("load surcharge", c(&[(Y0, &load("Pressure(within: Some((min: [0.0, 9.9], max: [0.3125, 10.1])), pressure: Uniform(1e4))"))])),
        ("load whole boundary", c(&[(Y0, &load("Traction(traction: [0.0, -1.0])"))])),
        ("load point", c(&[(Y0, &load("PointLoad(at: [0.15, 10.0], force: [0.0, -1e3])"))])),
        ("load point off the material", c(&[(Y0, &load("PointLoad(at: [0.15, 10.2], force: [0.0, -1e3])"))])),
        ("load box off the boundary", c(&[(Y0, &load("Pressure(within: Some((min: [0.05, 4.0], max: [0.25, 6.0])), pressure: Uniform(1e4))"))])),
        ("load box unordered", c(&[(Y0, &load("Pressure(within: Some((min: [0.0, 11.0], max: [0.3125, 9.0])), pressure: Uniform(1e4))"))])),
        ("load body missing", c(&[(Y0, &load("Traction(body: 2, traction: [0.0, -1.0])"))])),
        ("load traction length", c(&[(Y0, &load("Traction(traction: [-1.0])"))])),
        ("load pressure infinite", c(&[(Y0, &load("Pressure(pressure: Uniform(inf))"))])),
        ("load hydrostatic", c(&[(Y0, &load("Pressure(pressure: Hydrostatic(level: 8.0, unit_weight: 10.0))"))])),
        ("load linear gradient length", c(&[(Y0, &load("Pressure(pressure: Linear(value: 1.0, at: [0.0, 0.0], gradient: [1.0]))"))])),
        ("load time in quasi-static", c(&[(Y0, &load("Traction(traction: [0.0, -1.0], time: Ramp(duration: 1.0))"))])),
        ("load follower in small strain", c(&[("kinematics: FiniteStrain", "kinematics: SmallStrain"), (Y0, &load("Pressure(pressure: Uniform(1.0), follower: true)"))])),
        ("load follower geometrically linear",
            c(&[(PLANE, &option("geometrically_linear: true,")), ("kinematics: FiniteStrain,", small), (Y0, &load("Pressure(pressure: Uniform(1.0), follower: true)"))]),
        ),
        ("load follower", c(&[(Y0, &load("Pressure(pressure: Uniform(1.0), follower: true)"))])),
        ("load on the fem reference", f(&[(Y0, &load("Traction(traction: [0.0, -1.0])"))])),
        ("water", c(&[("kinematics: FiniteStrain", "kinematics: SmallStrain"), (PLANE, &option("water: Some((unit_weight: 10.0, level: Horizontal(5.0))),"))])),
        ("water polyline", c(&[(PLANE, &option("water: Some((unit_weight: 10.0, level: Polyline([(0.0, 4.0), (0.3125, 6.0)]))),"))])),
        ("water level above the grid", c(&[(PLANE, &option("water: Some((unit_weight: 10.0, level: Horizontal(20.0))),"))])),
        ("water unit weight", c(&[(PLANE, &option("water: Some((unit_weight: -1.0, level: Horizontal(5.0))),"))])),
        ("water polyline backwards", c(&[(PLANE, &option("water: Some((unit_weight: 10.0, level: Polyline([(1.0, 4.0), (0.0, 6.0)]))),"))])),
        ("vibrating bar", edit(BAR, &[])),
        ("bar sine axis", edit(BAR, &[("axis: X, wavelength", "axis: Z, wavelength")])),
        ("bar amplitude length", edit(BAR, &[("amplitude: [0.1, 0.0]", "amplitude: [0.1]")])),
        ("bar gamma", edit(BAR, &[("duration: 30.0", "duration: 30.0, gamma: 0.3")])),
        ("bar load table", edit(BAR, &[("analysis:", "loads: [PointLoad(at: [1.0, 0.5], force: [1.0, 0.0], time: Table([(0.0, 0.0), (2.0, 1.0)]))],\n    analysis:")])),
        ("bar load table not increasing", edit(BAR, &[("analysis:", "loads: [PointLoad(at: [1.0, 0.5], force: [1.0, 0.0], time: Table([(0.0, 0.0), (2.0, 1.0), (2.0, 0.0)]))],\n    analysis:")])),
        ("bar load ramp zero", edit(BAR, &[("analysis:", "loads: [PointLoad(at: [1.0, 0.5], force: [1.0, 0.0], time: Ramp(duration: 0.0))],\n    analysis:")])),
        ("runout", edit(RUNOUT, &[])),
        ("runout with water", edit(RUNOUT, &[("analysis:", "water: Some((unit_weight: 10.0, level: Horizontal(5.0))),\n    analysis:")])),
        ("runout fixed step", edit(RUNOUT, &[("Cfl(0.5)", "Fixed(dt: 0.5)")])),
        ("runout frictional base", edit(RUNOUT, &[("analysis:", "frictional_planes: [(point: [0.0, 0.0], normal: [0.0, 1.0], friction: 0.4)],\n    analysis:")])),
        ("runout friction negative", edit(RUNOUT, &[("analysis:", "frictional_planes: [(point: [0.0, 0.0], normal: [0.0, 1.0], friction: -0.4)],\n    analysis:")])),
        ("runout frictional normal zero", edit(RUNOUT, &[("analysis:", "frictional_planes: [(point: [0.0, 0.0], normal: [0.0, 0.0], friction: 0.4)],\n    analysis:")])),
        ("runout frictional plane below the grid", edit(RUNOUT, &[("analysis:", "frictional_planes: [(point: [0.0, -1.0], normal: [0.0, 1.0], friction: 0.4)],\n    analysis:")])),
        ("runout inclined roller", edit(RUNOUT, &[("analysis:", "inclined_rollers: [(point: [0.0, 0.0], normal: [-0.5, 0.8660254037844386])],\n    analysis:")])),
        ("runout body contact", edit(RUNOUT, &[("analysis:", "body_contact: Some((friction: 0.3)),\n    analysis:"), ("Cfl(0.5)", "Cfl(0.5), scheme: Usl")])),
        ("runout body contact, MUSL", edit(RUNOUT, &[("analysis:", "body_contact: Some((friction: 0.3)),\n    analysis:")])),
        ("runout body contact friction NaN", edit(RUNOUT, &[("analysis:", "body_contact: Some((friction: NaN)),\n    analysis:"), ("Cfl(0.5)", "Cfl(0.5), scheme: Usl")])),
        ("bar load body contact", edit(BAR, &[("analysis:", "loads: [PointLoad(at: [1.0, 0.5], force: [1.0, 0.0], time: Ramp(duration: 1.0))],\n    body_contact: Some((friction: 0.3)),\n    analysis:")])),
        ("column body contact, quasi-static", edit(COLUMN, &[("analysis:", "body_contact: Some((friction: 0.3)),\n    analysis:")])),
        ("rigid footing", edit(RIGID, &[])),
        ("rigid footing unknown body", edit(RIGID, &[("(body: \"footing\",", "(body: \"pile\",")])),
        ("rigid footing velocity of one", edit(RIGID, &[("velocity: [0.0, -0.1]", "velocity: [-0.1]")])),
        ("rigid footing velocity NaN", edit(RIGID, &[("velocity: [0.0, -0.1]", "velocity: [0.0, NaN]")])),
        ("rigid footing friction negative", edit(RIGID, &[("friction: 0.5", "friction: -0.5")])),
        ("rigid footing, MUSL", edit(RIGID, &[("scheme: Usl, ", "")])),
        ("rigid footing, quasi-static", edit(RIGID, &[("Explicit(duration: 10.0, time_step: Cfl(0.5), scheme: Usl, damping: 0.1)", "QuasiStatic(load_steps: 10)")])),
        ("rigid footing time table decreasing", edit(RIGID, &[("friction: 0.5)", "friction: 0.5, time: Table([(0.0, 0.0), (0.0, 1.0)]))")])),
        ("rigid footing twice", edit(RIGID, &[("friction: 0.5),", "friction: 0.5), (body: \"footing\", velocity: [0.0, 0.0]),")])),
        ("rigid footing and clay", edit(RIGID, &[("friction: 0.5),", "friction: 0.5), (body: \"clay\", velocity: [0.0, 0.0]),")])),
        ("rigid footing overlapping the clay", edit(RIGID, &[("min: [0.0, 3.0], max: [0.5, 3.3]", "min: [0.0, 2.8], max: [0.5, 3.3]")])),
        ("rigid footing overlapping the clay, may_overlap", edit(RIGID, &[("min: [0.0, 3.0], max: [0.5, 3.3]), points_per_cell: 2)", "min: [0.0, 2.8], max: [0.5, 3.3]), points_per_cell: 2, may_overlap: true)")])),
        ("rigid footing leaving the grid", edit(RIGID, &[("velocity: [0.0, -0.1]", "velocity: [0.0, -0.4]")])),
        ("rigid footing with a load", edit(RIGID, &[("rigid_bodies:", "loads: [PointLoad(at: [1.0, 3.0], force: [0.0, -1.0], time: Ramp(duration: 1.0))],\n    rigid_bodies:")])),
        ("column frictional plane below the grid", edit(COLUMN, &[("analysis:", "frictional_planes: [(point: [0.0, -5.0], normal: [0.0, 1.0], friction: 0.4)],\n    analysis:")])),
        ("runout polygon of two", edit(RUNOUT, &[("(50.0, 0.0), (50.0, 20.0), (30.0, 20.0), (20.0, 10.0), ", "")])),
        ("footing", edit(FOOTING, &[])),
        ("footing gimp", edit(FOOTING, &[("basis: Linear", "basis: Gimp")])),
        ("footing within length", edit(FOOTING, &[("max: [1.0, 5.0]", "max: [1.0]")])),
        ("footing displacement none", edit(FOOTING, &[("[Some(0.0), Some(-0.2)]", "[None, None]")])),
        ("cube", edit(CUBE, &[])),
        ("cube gravity length", edit(CUBE, &[("gravity: [0.0, 0.0, -10.0]", "gravity: [0.0, -10.0]")])),
        ("cube cells length", edit(CUBE, &[("cells: [2, 2, 3]", "cells: [2, 2]")])),
        ("cube polygon", edit(CUBE, &[(CUBE_BOX, "Polygon(vertices: [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])")])),
        ("cube water plane", edit(CUBE, &[("analysis:", "water: Some((unit_weight: 10.0, level: Plane(height: 1.0, slope: [0.1, 0.2, 0.0]))),\n    analysis:")])),
        ("cube water plane along gravity", edit(CUBE, &[("analysis:", "water: Some((unit_weight: 10.0, level: Plane(height: 1.0, slope: [0.1, 0.0, 0.5]))),\n    analysis:")])),
        ("cube water plane leaving the grid", edit(CUBE, &[("analysis:", "water: Some((unit_weight: 10.0, level: Plane(height: 2.5, slope: [0.5, 0.0, 0.0]))),\n    analysis:")])),
        ("cube water polyline", edit(CUBE, &[("analysis:", "water: Some((unit_weight: 10.0, level: Polyline([(0.0, 1.0), (2.0, 1.0)]))),\n    analysis:")])),
        ("cube ball", edit(CUBE, &[(CUBE_BOX, "Ball(centre: [1.0, 1.0, 1.0], radius: 0.9)")])),
        ("cube constraint at the top", edit(CUBE, &[("Fixed(axis: Z, at: 0.0)", "Fixed(axis: Z, at: 3.0)")])),
        ("cube within",
            edit(
                CUBE,
                &[(
                    "Fixed(axis: Z, at: 0.0)",
                    "Fixed(axis: Z, at: 0.0, \
             within: Some((min: [0.0, 0.0, 0.0], max: [1.0, 1.0, 0.0])))",
                )],
            ),
        ),
        ("cube sine",
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
    for (name, source) in cases() {
        writeln!(report, "{name}: {}", outcome(source)).unwrap();
    }
    insta::assert_snapshot!(report);
}
