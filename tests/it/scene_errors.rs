//! Bad scenes are refused before any step runs, with an error that names the file, the line
//! and column of the offending value, and what would be valid. One test per kind of
//! mistake; each mutates the valid example scene in one place.

use loam::scene::{LoadedScene, SceneError};
use std::path::Path;

const GOOD: &str = include_str!("../../examples/column.ron");

fn check(source: &str) -> Result<(), SceneError> {
    let scene = LoadedScene::parse(Path::new("bad.ron"), source.to_string())?;
    scene.build::<2>().map(|_| ())
}

/// Replace `from` (which must occur) by `to` in the good scene and expect an error at
/// `line` (1-based) whose message contains every string of `says`.
fn refused(from: &str, to: &str, line: usize, says: &[&str]) -> SceneError {
    assert!(GOOD.contains(from), "test setup: {from:?} not in the example");
    refused_source(&GOOD.replacen(from, to, 1), line, says)
}

/// Expect `source` to be refused at `line` (1-based) with a message containing every
/// string of `says`.
fn refused_source(source: &str, line: usize, says: &[&str]) -> SceneError {
    let e = check(source).expect_err("scene must be refused");
    assert_eq!(e.file, Path::new("bad.ron"));
    assert_eq!(e.line, line, "wrong line for {e}");
    assert!(e.column >= 1, "{e}");
    for s in says {
        assert!(e.to_string().contains(s), "{e} should say {s:?}");
    }
    e
}

/// The 1-based line of the example's first non-comment line that contains `pat`.
fn line_of(pat: &str) -> usize {
    GOOD.lines().position(|l| !l.trim_start().starts_with("//") && l.contains(pat)).expect("pattern in example") + 1
}

#[test]
fn the_example_itself_is_valid() {
    check(GOOD).unwrap();
}

#[test]
fn syntax_error() {
    refused("cell_size: [0.3125, 0.3125]", "cell_size: [0.3125 0.3125]", line_of("cell_size"), &["bad.ron:"]);
}

#[test]
fn unknown_key() {
    refused("basis: Gimp,", "basis: Gimp, bass: 1,", line_of("basis: Gimp"), &["bass", "title"]);
}

#[test]
fn unknown_enum_variant_lists_the_valid_ones() {
    refused("basis: Gimp,", "basis: Cubic,", line_of("basis: Gimp"), &["Cubic", "Linear", "Gimp"]);
}

#[test]
fn missing_field() {
    let e = check(&GOOD.replacen("    gravity: [0.0, -10.0],\n", "", 1)).unwrap_err();
    assert!(e.to_string().contains("gravity"), "{e}");
    assert!(e.line > 1);
}

#[test]
fn non_positive_young_modulus() {
    refused("young: 1e5", "young: -1e5", line_of("young"), &["Young's modulus", "positive"]);
    let e = refused("young: 1e5", "young: 0.0", line_of("young"), &["must be positive"]);
    // The column points at the value's key inside the material line.
    let col = GOOD.lines().nth(e.line - 1).unwrap().find("young").unwrap() + 1;
    assert_eq!(e.column, col);
}

#[test]
fn poisson_ratio_at_or_above_one_half() {
    refused("poisson: 0.0", "poisson: 0.5", line_of("poisson"), &["Poisson", "(-1, 0.5)"]);
}

#[test]
fn non_positive_density() {
    refused("density: 2000.0", "density: 0.0", line_of("density"), &["density", "positive"]);
}

#[test]
fn points_outside_the_grid() {
    refused("max: [0.3125, 10.0]", "max: [0.3125, 12.0]", line_of("max: [0.3125"), &["outside the grid"]);
}

#[test]
fn empty_material_region() {
    refused(
        "min: [0.0, 0.0], max: [0.3125, 10.0]",
        "min: [0.0, 5.0], max: [0.3125, 5.01]",
        line_of("max: [0.3125"),
        &["contains no point"],
    );
}

#[test]
fn constraint_on_no_node_plane() {
    refused("Roller(axis: Y, at: 0.0)", "Roller(axis: Y, at: 0.1)", line_of("axis: Y"), &["not a plane of grid nodes"]);
}

#[test]
fn constraint_that_touches_no_active_node() {
    // The top node plane (y = 33 cells) lies above the column: no point has support there.
    refused(
        "Roller(axis: Y, at: 0.0)",
        "Roller(axis: Y, at: 10.3125)",
        line_of("axis: Y"),
        &["touches no active node"],
    );
}

#[test]
fn zero_load_steps() {
    refused("load_steps: 40", "load_steps: 0", line_of("load_steps"), &["at least 1"]);
}

#[test]
fn unknown_material_name() {
    refused("(material: \"soil\"", "(material: \"clay\"", line_of("(material:"), &["clay", "not defined", "soil"]);
}

#[test]
fn wrong_vector_length_for_the_dimension() {
    refused("gravity: [0.0, -10.0]", "gravity: [0.0, -10.0, 0.0]", line_of("gravity"), &["2D scene needs 2"]);
}

#[test]
fn non_positive_cell_size() {
    refused(
        "cell_size: [0.3125, 0.3125]",
        "cell_size: [0.3125, -0.3125]",
        line_of("cell_size"),
        &["cell size", "positive"],
    );
}

#[test]
fn unreadable_file_names_the_path() {
    let e = LoadedScene::read(Path::new("/nonexistent/scene.ron")).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/scene.ron"), "{e}");
}

// ------------------------------------------------------------------ dynamic scenes

const BAR: &str = include_str!("../../examples/vibrating_bar.ron");
const DISKS: &str = include_str!("../../examples/disks.ron");

fn check_text(source: &str) -> Result<(), SceneError> {
    let scene = LoadedScene::parse(Path::new("dyn.ron"), source.to_string())?;
    scene.build::<2>().map(|_| ())
}

#[test]
fn the_dynamic_examples_are_valid() {
    check_text(BAR).unwrap();
    check_text(DISKS).unwrap();
}

/// γ < ½ makes Newmark unstable: refused at the analysis line, naming the setting.
#[test]
fn newmark_gamma_below_one_half() {
    let src = BAR.replacen(
        "ImplicitDynamic(time_step: 0.5, duration: 30.0)",
        "ImplicitDynamic(time_step: 0.5, duration: 30.0, gamma: 0.4)",
        1,
    );
    let e = check_text(&src).unwrap_err();
    let line = BAR.lines().position(|l| l.contains("ImplicitDynamic")).unwrap() + 1;
    assert_eq!(e.line, line, "{e}");
    assert!(e.to_string().contains("gamma") && e.to_string().contains("½"), "{e}");
}

/// A fixed explicit step above the critical one is refused before any output, with the
/// critical step and the ways out in the message; allowed when the scene says so.
#[test]
fn explicit_step_above_the_critical_one() {
    // Disks: c_p = √(M/ρ) ≈ 1.16, h = 0.05, so Δt_c ≈ 0.042.
    let src = DISKS.replacen("time_step: Cfl(0.5)", "time_step: Fixed(dt: 0.1)", 1);
    let e = check_text(&src).unwrap_err();
    let line = DISKS.lines().position(|l| l.contains("Explicit(")).unwrap() + 1;
    assert_eq!(e.line, line, "{e}");
    for s in ["critical", "Cfl", "allow_above_critical"] {
        assert!(e.to_string().contains(s), "{e} should say {s}");
    }
    let allowed = DISKS.replacen("time_step: Cfl(0.5)", "time_step: Fixed(dt: 0.1, allow_above_critical: true)", 1);
    check_text(&allowed).unwrap();
}

#[test]
fn explicit_damping_out_of_range() {
    let src = DISKS.replacen("flip: 1.0", "flip: 1.0, damping: 1.5", 1);
    let e = check_text(&src).unwrap_err();
    assert!(e.to_string().contains("damping") && e.to_string().contains("[0, 1)"), "{e}");
}

#[test]
fn initial_velocity_with_the_wrong_length() {
    let src = DISKS.replacen("Uniform([0.1, 0.1])", "Uniform([0.1])", 1);
    let e = check_text(&src).unwrap_err();
    let line = DISKS.lines().position(|l| l.contains("Uniform([0.1, 0.1])")).unwrap() + 1;
    assert_eq!(e.line, line, "{e}");
    assert!(e.to_string().contains("2 finite components"), "{e}");
}

/// The FEM reference meshes Box bodies only, takes 1–3 Gauss points per axis, and runs
/// with the implicit analyses only; each mistake names its place.
#[test]
fn fem_method_limits_are_named() {
    let fem = GOOD.replacen("basis: Gimp,", "method: UpdatedLagrangianFem,", 1);
    check(&fem).unwrap();
    refused_source(
        &fem.replacen("points_per_cell: 2", "points_per_cell: 4", 1),
        line_of("points_per_cell"),
        &["Gauss order 4"],
    );
    let e = check(&fem.replacen(
        "shape: Box(min: [0.0, 0.0], max: [0.3125, 10.0])",
        "shape: Polygon(vertices: [(0.0, 0.0), (0.3125, 0.0), (0.0, 10.0)])",
        1,
    ))
    .unwrap_err();
    assert!(e.to_string().contains("Box bodies only"), "{e}");
    refused_source(
        &fem.replacen("QuasiStatic(load_steps: 40)", "Explicit(duration: 1.0)", 1),
        line_of("basis: Gimp"),
        &["implicit analyses"],
    );
}

/// Plastic laws in scenes: each parameter out of range is refused at its own place, with
/// what is valid; φ ≥ 90° and ψ > φ included (φ = 0 is valid: Tresca).
#[test]
fn plastic_law_parameters_are_checked() {
    let mc = |c: &str, phi: &str, psi: &str| {
        GOOD.replacen(
            "law: Elastic(young: 1e5, poisson: 0.0)",
            &format!("law: MohrCoulomb(young: 1e5, poisson: 0.0, cohesion: {c}, friction: {phi}, dilation: {psi})"),
            1,
        )
    };
    check(&mc("10.0", "0.0", "0.0")).unwrap();
    check(&mc("10.0", "30.0", "5.0")).unwrap();
    let line = line_of("law: Elastic");
    for (scene, says) in [
        (mc("10.0", "90.0", "0.0"), "friction = 90"),
        (mc("10.0", "20.0", "25.0"), "dilation = 25"),
        (mc("0.0", "0.0", "0.0"), "cohesion = 0"),
        (mc("-1.0", "20.0", "0.0"), "cohesion = -1"),
    ] {
        refused_source(&scene, line, &[says]);
    }
    let vm = GOOD.replacen(
        "law: Elastic(young: 1e5, poisson: 0.0)",
        "law: VonMises(young: 1e5, poisson: 0.0, yield_stress: 17.3)",
        1,
    );
    check(&vm).unwrap();
    let e = check(&vm.replacen("yield_stress: 17.3", "yield_stress: 0.0", 1)).unwrap_err();
    assert!(e.to_string().contains("yield_stress = 0; it must be positive"), "{e}");
}

/// A prescribed displacement needs D entries with at least one Some, and only quasi-static
/// analysis applies it.
#[test]
fn displacement_constraints_are_checked() {
    let push = |d: &str| {
        GOOD.replacen(
            "Roller(axis: Y, at: 0.0),",
            &format!("Roller(axis: Y, at: 0.0),\n        Displacement(axis: Y, at: 10.0, displacement: {d}),"),
            1,
        )
    };
    check(&push("[None, Some(-0.1)]")).unwrap();
    let e = check(&push("[None, None]")).unwrap_err();
    assert!(e.to_string().contains("at least one Some"), "{e}");
    let e = check(&push("[Some(-0.1)]")).unwrap_err();
    assert!(e.to_string().contains("needs 2 entries"), "{e}");
    let e = check(&push("[None, Some(-0.1)]").replacen(
        "QuasiStatic(load_steps: 40)",
        "ImplicitDynamic(time_step: 0.1, duration: 1.0)",
        1,
    ))
    .unwrap_err();
    assert!(e.to_string().contains("QuasiStatic"), "{e}");
}

/// B-bar is refused where it does not apply (finite strain, GIMP), naming the key.
#[test]
fn bbar_needs_small_strain_and_the_linear_basis() {
    refused("basis: Gimp,", "basis: Gimp,\n    anti_locking: BBar,", line_of("basis: Gimp") + 1, &["small-strain"]);
    let small = GOOD.replacen("kinematics: FiniteStrain,", "kinematics: SmallStrain,\n    anti_locking: BBar,", 1);
    let e = check(&small).unwrap_err();
    assert!(e.to_string().contains("Linear basis"), "{e}");
    check(&small.replacen("basis: Gimp,", "basis: Linear,", 1)).unwrap();
}

/// The assumed strain takes a stabilization in (0, 1], and like B-bar needs small strain
/// and the linear basis; each refusal names the key.
#[test]
fn assumed_strain_is_checked() {
    let small = |beta: &str| {
        GOOD.replacen(
            "kinematics: FiniteStrain,",
            &format!("kinematics: SmallStrain,\n    anti_locking: AssumedStrain(stabilization: {beta}),"),
            1,
        )
        .replacen("basis: Gimp,", "basis: Linear,", 1)
    };
    let at = line_of("kinematics: FiniteStrain") + 1;
    check(&small("0.1")).unwrap();
    check(&small("1.0")).unwrap();
    for bad in ["0.0", "-0.1", "1.5"] {
        refused_source(&small(bad), at, &["0 < β ≤ 1"]);
    }
    refused_source(&small("0.1").replacen("basis: Linear,", "basis: Gimp,", 1), at, &["Linear basis"]);
    let e =
        check(&GOOD.replacen("basis: Gimp,", "basis: Gimp,\n    anti_locking: AssumedStrain(stabilization: 0.1),", 1))
            .unwrap_err();
    assert!(e.to_string().contains("small-strain"), "{e}");
}

/// A geometrically linear scene needs small strain and an implicit analysis; each refusal
/// names the key.
#[test]
fn geometrically_linear_is_checked() {
    let key = |kinematics: &str| {
        GOOD.replacen(
            "kinematics: FiniteStrain,",
            &format!("kinematics: {kinematics},\n    geometrically_linear: true,"),
            1,
        )
    };
    let at = line_of("kinematics: FiniteStrain") + 1;
    check(&key("SmallStrain")).unwrap();
    refused_source(&key("FiniteStrain"), at, &["SmallStrain"]);
    refused_source(
        &key("SmallStrain").replacen("QuasiStatic(load_steps: 40)", "Explicit(duration: 1.0)", 1),
        at,
        &["explicit"],
    );
}

/// A geostatic start is checked against the laws: an elastic column takes any K0 > 0, a
/// non-positive K0 is refused at its key.
#[test]
fn geostatic_initial_stress_is_checked() {
    let k0 =
        |v: &str| GOOD.replacen("basis: Gimp,", &format!("basis: Gimp,\n    initial_stress: Geostatic(k0: {v}),"), 1);
    check(&k0("0.5")).unwrap();
    refused_source(&k0("-0.5"), line_of("basis: Gimp") + 1, &["K0 is -0.5"]);
}

/// Strength reduction is checked at its keys: a bracket that is not (holds, fails) with
/// 0 < holds < fails, a tolerance wider than the bracket, and a scene with only elastic
/// materials (nothing to reduce) are refused before any trial runs.
#[test]
fn strength_reduction_is_checked() {
    let srf = |spec: &str| {
        GOOD.replacen(
            "QuasiStatic(load_steps: 40)",
            &format!("QuasiStatic(load_steps: 40,\n        strength_reduction: Some({spec}))"),
            1,
        )
    };
    let at = line_of("QuasiStatic(load_steps: 40)") + 1;
    refused_source(&srf("(bracket: (2.0, 1.0))"), at, &["0 < F_holds < F_fails"]);
    refused_source(&srf("(bracket: (1.0, 1.5), tolerance: 0.6)"), at, &["below the bracket's width"]);
    let e = check(&srf("(tolerance: 0.01)")).unwrap_err();
    assert!(e.to_string().contains("every material here is elastic"), "{e}");
    let plastic = GOOD.replacen(
        "law: Elastic(young: 1e5, poisson: 0.0)",
        "law: VonMises(young: 1e5, poisson: 0.0, yield_stress: 1e6)",
        1,
    );
    assert_ne!(plastic, GOOD, "test setup: the law is in the example");
    check(&plastic.replacen(
        "QuasiStatic(load_steps: 40)",
        "QuasiStatic(load_steps: 40, strength_reduction: Some(()))",
        1,
    ))
    .unwrap();
}

/// The ghost penalty is checked at its key: a non-positive factor, and an explicit
/// analysis (which has no tangent to stabilise), are refused.
#[test]
fn ghost_penalty_is_checked() {
    let ghost = |v: &str| GOOD.replacen("basis: Gimp,", &format!("basis: Gimp,\n    ghost_penalty: {v},"), 1);
    let at = line_of("basis: Gimp") + 1;
    check(&ghost("Some(0.1)")).unwrap();
    refused_source(&ghost("Some(-1.0)"), at, &["positive"]);
    refused_source(
        &ghost("Some(0.1)").replacen("QuasiStatic(load_steps: 40)", "Explicit(duration: 1.0)", 1),
        at,
        &["Explicit"],
    );
}

/// A body velocity of 1e150 makes the critical time step 1e-152: `loam check` refuses it,
/// naming the point and its speed, instead of a run that loops with time stuck at 0 and
/// fills the disk with frames (as 1e300 did, which now overflows the kinetic energy and is
/// refused at the velocity).
#[test]
fn explicit_time_step_that_cannot_reach_the_end() {
    let src = DISKS.replacen("Uniform([0.1, 0.1])", "Uniform([1e150, 0.1])", 1);
    let e = check_text(&src).unwrap_err();
    // All points move alike: the one named is whichever the grid's carried speed (1e150 to
    // round-off) makes fastest.
    for s in ["time step", "below", "speed 1.0000e150", "point ", "velocity"] {
        assert!(e.to_string().contains(s), "{e} should say {s}");
    }
    let src = DISKS.replacen("Uniform([0.1, 0.1])", "Uniform([1e300, 0.1])", 1);
    let e = check_text(&src).unwrap_err();
    assert!(e.to_string().contains("kinetic energy overflow"), "{e}");
    // A fixed step of 1e-12 over the disks' duration is more than 10⁹ steps: refused too.
    let src = DISKS.replacen("time_step: Cfl(0.5)", "time_step: Fixed(dt: 1e-12)", 1);
    let e = check_text(&src).unwrap_err();
    assert!(e.to_string().contains("1e-12") && e.to_string().contains("below"), "{e}");
}

/// A file that is not UTF-8 is named as such at its first bad byte, not reported at 0:0.
#[test]
fn binary_scene_file_names_the_first_bad_byte() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ron");
    std::fs::write(&path, b"(\n  title: \"\xff\xfe\",\n)").unwrap();
    let e = LoadedScene::read(&path).unwrap_err();
    assert_eq!((e.line, e.column), (2, 11), "{e}");
    assert!(e.to_string().contains("not UTF-8"), "{e}");
}

/// The read is bounded: `/dev/zero` (endless) is refused after 16 MiB instead of being read
/// until memory runs out.
#[cfg(unix)]
#[test]
fn endless_scene_file_is_refused() {
    let e = LoadedScene::read(Path::new("/dev/zero")).unwrap_err();
    assert!(e.to_string().contains("larger than 16 MiB"), "{e}");
}

/// A UTF-8 byte-order mark (written by some Windows editors) is skipped, and errors keep
/// their lines.
#[test]
fn byte_order_mark_is_skipped() {
    check(&format!("\u{feff}{GOOD}")).unwrap();
    refused_source(
        &format!("\u{feff}{}", GOOD.replacen("young: 1e5", "young: -1e5", 1)),
        line_of("young"),
        &["positive"],
    );
}

/// A quasi-static scene without constraints is refused by `loam check` as unsupported,
/// naming the free motions, instead of failing in the factorisation with a pivot index;
/// with only a roller on the base it names the horizontal translation alone.
#[test]
fn unsupported_body_names_its_free_motions() {
    let start = GOOD.find("constraints: [").unwrap();
    let end = start + GOOD[start..].find("],").unwrap();
    let free = format!("{}constraints: [{}", &GOOD[..start], &GOOD[end..]);
    let e = refused_source(&free, line_of("constraints"), &["not supported against rigid motion"]);
    for s in ["the body against translation along x", "translation along y", "rotation about (0.1562, "] {
        assert!(e.to_string().contains(s), "{e} should say {s}");
    }
    let base_only = format!("{}constraints: [Roller(axis: Y, at: 0.0){}", &GOOD[..start], &GOOD[end..]);
    let e = check(&base_only).unwrap_err();
    assert!(e.to_string().contains("the body against translation along x;"), "{e}");
}

/// A scene of two blocks 2 m apart (2D, linear basis, 1 m cells) with `constraints`.
fn two_blocks(constraints: &str) -> String {
    format!(
        "Scene(title: \"two blocks\", dimension: 2,
            grid: (origin: [0.0, 0.0], cell_size: [1.0, 1.0], cells: [6, 3]),
            materials: [(name: \"soil\", density: 2.0, law: Elastic(young: 1e5, poisson: 0.3))],
            bodies: [(material: \"soil\", shape: Box(min: [0.0, 0.0], max: [2.0, 2.0]), points_per_cell: 2),
                     (material: \"soil\", shape: Box(min: [4.0, 0.0], max: [6.0, 2.0]), points_per_cell: 2)],
            gravity: [0.0, -10.0],
            constraints: [{constraints}],
            analysis: QuasiStatic(load_steps: 1))"
    )
}

/// A second body that no constraint reaches is named, by its points and centre, while the
/// held one is not; held too, the scene is accepted.
#[test]
fn a_loose_second_body_is_named() {
    let left = "Fixed(axis: Y, at: 0.0, within: Some((min: [0.0, 0.0], max: [2.0, 0.0])))";
    let e = check(&two_blocks(left)).unwrap_err().to_string();
    let says = "no constraint holds the body of 16 points around (5, 1) against translation along x, \
                translation along y, rotation about (5, 1);";
    assert!(e.contains(says), "{e}");
    assert!(check(&two_blocks("Fixed(axis: Y, at: 0.0)")).is_ok());
}

/// In 3D, a block held at two corners of its base on a diagonal turns about that diagonal:
/// the rotation is named by its axis and the point of it nearest the block's centre.
#[test]
fn a_rotation_about_a_diagonal_is_named() {
    let pin = |x: f64| format!("Fixed(axis: Z, at: 0.0, within: Some((min: [{x}, {x}, 0.0], max: [{x}, {x}, 0.0])))");
    let scene = format!(
        "Scene(title: \"pinned on a diagonal\", dimension: 3,
            grid: (origin: [0.0, 0.0, 0.0], cell_size: [1.0, 1.0, 1.0], cells: [3, 3, 3]),
            materials: [(name: \"soil\", density: 2.0, law: Elastic(young: 1e5, poisson: 0.3))],
            bodies: [(material: \"soil\", shape: Box(min: [0.0, 0.0, 0.0], max: [2.0, 2.0, 2.0]), points_per_cell: 2)],
            gravity: [0.0, 0.0, -10.0],
            constraints: [{}, {}],
            analysis: QuasiStatic(load_steps: 1))",
        pin(0.0),
        pin(2.0)
    );
    let loaded = LoadedScene::parse(Path::new("pinned.ron"), scene).unwrap();
    let e = loaded.build::<3>().map(|_| ()).unwrap_err().to_string();
    assert!(e.contains("the body against rotation about the axis (0.7071, 0.7071, 0) through (1, 1, 0);"), "{e}");
}

/// Two identical bodies would double the mass: the second is refused at its shape, unless
/// it says it may overlap.
#[test]
fn overlapping_bodies_are_refused_unless_allowed() {
    let start = GOOD.find("bodies: [").unwrap() + "bodies: [".len();
    let end = start + GOOD[start..].find("\n    ],").unwrap();
    let body = GOOD[start..end].trim().trim_end_matches(',');
    let twice = format!("{}{body}, {body}{}", &GOOD[..start], &GOOD[end..]);
    let e = check(&twice).unwrap_err();
    assert!(e.to_string().contains("body 1 overlaps body 0") && e.to_string().contains("may_overlap"), "{e}");
    let allowed = body.replacen("shape:", "may_overlap: true, shape:", 1);
    check(&format!("{}{body}, {allowed}{}", &GOOD[..start], &GOOD[end..])).unwrap();
}

/// A material no body uses is a warning at its name, not an error.
#[test]
fn an_unused_material_is_a_warning() {
    let scene = LoadedScene::parse(Path::new("bad.ron"), GOOD.to_string()).unwrap();
    assert!(scene.warnings().is_empty());
    let start = GOOD.find("materials: [").unwrap() + "materials: [".len();
    let extra = format!(
        "{}\n        (name: \"sandd\", density: 1.0, law: Elastic(young: 1.0, poisson: 0.0)),{}",
        &GOOD[..start],
        &GOOD[start..]
    );
    let scene = LoadedScene::parse(Path::new("bad.ron"), extra.clone()).unwrap();
    scene.build::<2>().unwrap();
    let warnings = scene.warnings();
    assert_eq!(warnings.len(), 1);
    assert!(warnings[0].to_string().contains("\"sandd\" is used by no body"), "{}", warnings[0]);
    assert_eq!(warnings[0].line, extra.lines().position(|l| l.contains("sandd")).unwrap() + 1);
}

/// A modulus or a weight whose products overflow the solver's arithmetic is refused at the
/// material, pointing to the units, instead of failing in the factorisation.
#[test]
fn parameters_that_overflow_are_refused() {
    refused("young: 1e5", "young: 1e308", line_of("young"), &["stiffness per cell", "1.0e308", "units"]);
    refused("density: 2000.0", "density: 1e300", line_of("density"), &["weight over the grid's height", "units"]);
}

/// A value where a field name belongs gets a message about named fields, not the parser's
/// "invalid std identifier, try the raw identifier".
#[test]
fn positional_fields_are_explained() {
    let e = refused(
        "Roller(axis: Y, at: 0.0)",
        "Fixed(-0.001)",
        line_of("Roller(axis: Y"),
        &["expected a field name here"],
    );
    assert!(e.to_string().contains("Fixed(axis: Y, at: 0.0)") && !e.to_string().contains("raw identifier"), "{e}");
}

/// A mistyped cell size of 1e-308 under a 10 m body: refused as reaching outside the grid
/// (the fill walks the grid's sub-cells, not the body's 1e309 of them, which hung `loam
/// check`; found by the scene fuzz test).
#[test]
fn a_body_of_astronomically_many_cells_is_refused_at_once() {
    refused("cell_size: [0.3125, 0.3125]", "cell_size: [0.3125, 1e-308]", line_of("shape: Box"), &["outside the grid"]);
}

/// A plastic material in an implicit analysis without anti-locking is a warning at its
/// law, naming the treatments; with F-bar (finite strain, linear basis) it is not, and an
/// explicit analysis, which has no anti-locking, is not warned.
#[test]
fn a_plastic_material_without_anti_locking_is_a_warning() {
    let plastic = GOOD.replacen(
        "law: Elastic(young: 1e5, poisson: 0.0)",
        "law: VonMises(young: 1e5, poisson: 0.3, yield_stress: 1e5)",
        1,
    );
    let scene = LoadedScene::parse(Path::new("bad.ron"), plastic.clone()).unwrap();
    scene.build::<2>().unwrap();
    let warnings = scene.warnings();
    assert_eq!(warnings.len(), 1);
    let w = warnings[0].to_string();
    assert!(w.contains("\"soil\" is plastic") && w.contains("anti_locking: FBar") && w.contains("BBar"), "{w}");
    assert_eq!(warnings[0].line, plastic.lines().position(|l| l.contains("VonMises")).unwrap() + 1);
    let treated = plastic.replacen("basis: Gimp,", "basis: Linear,\n    anti_locking: FBar,", 1);
    let scene = LoadedScene::parse(Path::new("bad.ron"), treated).unwrap();
    scene.build::<2>().unwrap();
    assert!(scene.warnings().is_empty());
    let explicit = plastic.replacen(
        "analysis: QuasiStatic(load_steps: 40)",
        "analysis: Explicit(duration: 0.01, time_step: Cfl(0.5))",
        1,
    );
    assert!(explicit.contains("Explicit"), "test setup");
    assert!(LoadedScene::parse(Path::new("bad.ron"), explicit).unwrap().warnings().is_empty());
}
