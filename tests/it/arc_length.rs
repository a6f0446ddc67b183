//! Arc-length load control (docs/theory.md §21): a load followed past its peak and down a
//! softening branch, against the closed form of a homogeneous test.

use crate::support::{column, run, table};
use loam::run::{run_scene, RunEvent};
use loam::scene::LoadedScene;
use std::path::Path;

/// A column in uniaxial compression (0.5 m × 0.5 m × 2 m, one cell across, on smooth
/// planes x = 0, y = 0, z = 0, its other sides free) of von Mises material that softens
/// linearly (E = 10 MPa, ν = 0.3, σ_y = 10 kPa, H = −2 MPa), under
/// q = 20 kPa on its top at full load, as a quarter of q A at each top corner node (the
/// nodal forces of a uniform pressure on one bilinear face). The stress is uniaxial and
/// uniform, σ_zz = −λ q (the trilinear basis and points placed symmetrically in their
/// cells hold it exactly), and the axial
/// strain is the closed form of the law: ε = λq / E below σ_y; on the softening branch
/// ε̄p = (λq − σ_y) / H and ε = λq / E + ε̄p, descending in λ as the strain grows
/// (|H| < E). Load control ends at the peak λ = σ_y / q = ½; arc-length control follows
/// the curve down (its ten steps, each at most twice the first, end before the strength is
/// spent at ε = 5e-3). Every step's load factor and a monitored
/// point's strain u_z / z (the point at z = 1.875) must lie on the curve: 1e-6 of the
/// peak strain covers the Newton tolerance (1e-10) with the round-off a softening tangent
/// amplifies.
#[test]
fn a_softening_column_is_followed_past_its_peak() {
    let (young, yield_stress, hardening, q) = (1e7, 1e4, -2e6, 2e4);
    let scene = column_scene(
        &format!("VonMises(young: {young}, poisson: 0.3, yield_stress: {yield_stress}, hardening: {hardening})"),
        q,
        10,
    );
    // How far the run says it is grows with every step, though λ falls past the peak.
    let dir = tempfile::tempdir().unwrap();
    let loaded = LoadedScene::parse(Path::new("scene.ron"), scene).unwrap();
    let mut done = Vec::new();
    run_scene(&loaded, dir.path(), &mut |e| {
        if let RunEvent::Step { done: d, .. } = e {
            done.push(d);
        }
    })
    .unwrap();
    assert!(done.windows(2).all(|w| w[1] > w[0]), "progress {done:?}");
    assert_eq!(done.last(), Some(&1.0));
    let (header, log) = table(&dir.path().join("run_log.csv"));
    let (lambda, uz, szz) =
        (column(&header, "load_factor"), column(&header, "monitor_top_uz"), column(&header, "monitor_top_szz"));
    let peak_strain = yield_stress / young;
    let mut softened = false;
    let mut strain_before = 0.0f64;
    for row in &log {
        let (l, strain) = (row[lambda], -row[uz] / 1.875);
        let stress = l * q;
        assert!((-row[szz] / stress - 1.0).abs() < 1e-6, "σ_zz {} at λ = {l}", row[szz]);
        let plastic = if strain <= peak_strain * (1.0 + 1e-9) { 0.0 } else { (stress - yield_stress) / hardening };
        let expected = stress / young + plastic;
        assert!((strain - expected).abs() < 1e-6 * peak_strain, "ε = {strain} at λ = {l}, closed form {expected}");
        assert!(strain > strain_before, "the strain grows along the arc: {strain} after {strain_before}");
        strain_before = strain;
        softened |= l < 0.5 * 0.9 && strain > peak_strain;
    }
    let last = log.last().unwrap()[lambda];
    assert!(softened, "the run reached the softening branch (last λ = {last})");
    assert!(log.iter().any(|r| (r[lambda] - 0.5).abs() < 0.01), "a step near the peak λ = ½");
}

/// The column of the tests here, of material `law`, q at full load, at most `steps`
/// arc-length steps, each at most twice the first.
fn column_scene(law: &str, q: f64, steps: usize) -> String {
    let corner = |x, y| format!("PointLoad(at: [{x}, {y}, 2.0], force: [0.0, 0.0, {}])", -q * 0.25 / 4.0);
    let loads = [corner(0.0, 0.0), corner(0.5, 0.0), corner(0.0, 0.5), corner(0.5, 0.5)].join(", ");
    format!(
        r#"Scene(
    dimension: 3,
    grid: (origin: [0.0, 0.0, 0.0], cell_size: [0.5, 0.5, 0.5], cells: [2, 2, 5]),
    basis: Linear,
    kinematics: SmallStrain,
    geometrically_linear: true,
    materials: [(name: "rock", density: 2000.0, law: {law})],
    bodies: [(material: "rock", shape: Box(min: [0.0, 0.0, 0.0], max: [0.5, 0.5, 2.0]))],
    gravity: [0.0, 0.0, 0.0],
    constraints: [Roller(axis: X, at: 0.0), Roller(axis: Y, at: 0.0), Roller(axis: Z, at: 0.0)],
    loads: [{loads}],
    monitor: [(name: "top", at: [0.375, 0.375, 1.875])],
    analysis: QuasiStatic(load_steps: 4, control: ArcLength(steps: {steps}, max_growth: 2.0)),
    solver: (residual_tolerance: 1e-10),
    output: (vtu_every: 0),
)"#
    )
}

/// Where nothing limits the load, the arc ends on the full load: the step that would pass
/// λ = 1 is taken onto it by load control, and the column's strain is q / E (elastic; the
/// closed form to the Newton tolerance).
#[test]
fn an_arc_that_reaches_the_full_load_ends_on_it() {
    let (young, q) = (1e7, 2e4);
    let dir = run(&column_scene(&format!("Elastic(young: {young}, poisson: 0.3)"), q, 40));
    let (header, log) = table(&dir.path().join("run_log.csv"));
    let last = log.last().unwrap();
    assert_eq!(last[column(&header, "load_factor")], 1.0);
    let strain = -last[column(&header, "monitor_top_uz")] / 1.875;
    assert!((strain / (q / young) - 1.0).abs() < 1e-9, "ε = {strain}");
    assert!(log.len() < 40, "{} steps", log.len());
}
