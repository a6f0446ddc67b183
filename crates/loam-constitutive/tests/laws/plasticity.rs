//! Plasticity checks (docs/theory.md §16, the table of failures and checks): elastic trial states unchanged,
//! consistency after return, the algorithmic tangent against central differences in every
//! return region, rotation invariance, symmetry for associated flow, no NaN at apexes and
//! edges, and closed-form oedometer / triaxial / Tresca paths.
//!
//! Tolerances used throughout (each assertion says which one applies):
//! - `FD_TOL` = 1e-6 (docs/theory.md §16): relative difference between the tangent and the
//!   central-difference derivative.
//! - `F_TOL` = 1e-10 (docs/theory.md §16): f(σ) ≤ 1e-10 · scale after return, where scale is the
//!   largest |trial principal stress| or the strength (c, σ_y) whichever is larger.
//! - Round-off bounds (1e-12 … 1e-10 relative) where the result is a closed form evaluated
//!   with a handful of operations.

use loam_constitutive::tensor::{central_difference, idx, symmetric_unit_directions, Tensor4};
use loam_constitutive::{
    finite_strain_update, small_strain_update, ConstitutiveError, ConstitutiveLaw, Elastic, MohrCoulomb,
    MohrCoulombRegion, StressUpdate, VonMises, VonMisesRegion,
};
use nalgebra::{Matrix3, Rotation3, Vector3};
use proptest::prelude::*;
use std::collections::BTreeMap;
use std::sync::Mutex;

use MohrCoulombRegion as R;

const FD_TOL: f64 = 1e-6;
const F_TOL: f64 = 1e-10;

// ---------------------------------------------------------------- helpers

fn rot(r: [f64; 3]) -> Matrix3<f64> {
    Rotation3::from_scaled_axis(Vector3::from(r)).into_inner()
}

/// Rotation of a fourth-order tensor: D'_ijkl = Q_ia Q_jb Q_kc Q_ld D_abcd, i.e.
/// (Q⊗Q) D (Q⊗Q)ᵀ in the 9×9 convention (row-major pairs = Kronecker product).
fn rotate4(q: &Matrix3<f64>, d: &Tensor4) -> Tensor4 {
    let qq = q.kronecker(q);
    qq * d * qq.transpose()
}

/// Strain whose elastic trial stress has principal values `s` along the axes of `rot(r)`.
fn strain_for_stress(el: &Elastic, s: [f64; 3], r: [f64; 3]) -> Matrix3<f64> {
    let (l, g) = el.lame();
    let tr = s.iter().sum::<f64>();
    let e = Vector3::from(s).map(|x| (x - l / (3.0 * l + 2.0 * g) * tr) / (2.0 * g));
    let q = rot(r);
    q * Matrix3::from_diagonal(&e) * q.transpose()
}

/// Central differences of `law.update(·).stress` along the six symmetric unit directions,
/// step `h = 1e-6 ‖ε‖`: truncation ~(h/ε)² ≈ 1e-12 relative, round-off ~1e-16/1e-6 = 1e-10
/// relative; both well below FD_TOL provided the state is 1e-6 ‖ε‖ away from a region
/// boundary (the tests pick such states, or check that ±h stay in the same region).
fn fd_tangent(law: &dyn ConstitutiveLaw, eps: &Matrix3<f64>, h_n: &[f64]) -> Tensor4 {
    let mut h_out = vec![0.0; h_n.len()];
    central_difference(|e| law.update(e, h_n, &mut h_out).unwrap().stress, eps, 1e-6 * eps.norm())
}

/// Relative tangent error ‖D − D_fd‖ / ‖D‖; when D vanishes to round-off (‖D‖ ≤ 1e-8 ‖Dᵉ‖:
/// the perfectly plastic apexes, where σ is constant) a relative error against ‖D‖ = 0 is
/// undefined and ‖Dᵉ‖ (`del_norm`) is the reference instead.
fn tangent_error(d: &Tensor4, fd: &Tensor4, del_norm: f64) -> f64 {
    let reference = if d.norm() <= 1e-8 * del_norm { del_norm } else { d.norm() };
    (d - fd).norm() / reference
}

fn principal(s: &Matrix3<f64>) -> Vector3<f64> {
    let mut v = s.symmetric_eigenvalues();
    v.as_mut_slice().sort_by(|a, b| b.total_cmp(a));
    v
}

fn finite(up: &StressUpdate) -> bool {
    up.stress.iter().chain(up.elastic_strain.iter()).chain(up.tangent.iter()).all(|v| v.is_finite())
}

/// Largest FD error seen per (law, region), printed by `report_fd_errors`
/// (`cargo test -- --nocapture` shows the table).
static FD_ERRORS: Mutex<BTreeMap<String, f64>> = Mutex::new(BTreeMap::new());

fn record(key: String, err: f64) {
    let mut m = FD_ERRORS.lock().unwrap();
    let e = m.entry(key).or_insert(0.0);
    *e = e.max(err);
}

/// How often each (law, region) was visited by the property tests.
static COUNTS: Mutex<BTreeMap<String, usize>> = Mutex::new(BTreeMap::new());

fn record_count(key: String) {
    *COUNTS.lock().unwrap().entry(key).or_insert(0) += 1;
}

fn el() -> Elastic {
    Elastic::new(1.0e4, 0.3).unwrap()
}

// ---------------------------------------------------------------- von Mises

fn vm_laws() -> Vec<(&'static str, VonMises)> {
    let g = el().lame().1;
    vec![
        ("perfect", VonMises::new(el(), 30.0, 0.0).unwrap()),
        ("hardening", VonMises::new(el(), 30.0, 0.1 * g).unwrap()),
        ("softening", VonMises::new(el(), 30.0, -0.2 * g).unwrap().with_residual_yield_stress(20.0).unwrap()),
    ]
}

#[test]
fn von_mises_regions_fd_and_consistency() {
    // q_tr ≈ 218 > every σ_y(ε̄p_n) used below (largest: 30 + 0.1 G · 0.2 ≈ 107).
    let eps = Matrix3::new(4e-3, 1e-3, -5e-4, 1e-3, -2e-3, 7e-4, -5e-4, 7e-4, 1e-3) * 5.0;
    for (name, law) in vm_laws() {
        for eqps_n in [0.0, 0.01, 0.2] {
            let mut h = [0.0];
            let (up, region) = law.update_with_region(&eps, &[eqps_n], &mut h).unwrap();
            assert_ne!(region, VonMisesRegion::Elastic);
            // F_TOL: q = σ_y(ε̄p_{n+1}).
            let dev = up.stress - Matrix3::identity() * (up.stress.trace() / 3.0);
            let q = 1.5f64.sqrt() * dev.norm();
            let sy = law.current_yield_stress(h[0]);
            assert!((q - sy).abs() <= F_TOL * sy.max(30.0), "{name}: q {q} σy {sy}");
            let fd = fd_tangent(&law, &eps, &[eqps_n]);
            let r = tangent_error(&up.tangent, &fd, law.elastic.stiffness().norm());
            record(format!("von Mises {name} {region:?}"), r);
            assert!(r < FD_TOL, "{name} ε̄p {eqps_n}: rel {r}");
            // Associated: symmetric tangent (round-off, 1e-12 relative).
            assert!((up.tangent - up.tangent.transpose()).norm() < 1e-12 * up.tangent.norm());
        }
    }
    // The softening law reaches its floor from ε̄p = 0.2 (σ_y0 + H·0.2 < σ_res).
    let (_, soft) = &vm_laws()[2];
    let (_, region) = soft.update_with_region(&eps, &[0.2], &mut [0.0]).unwrap();
    assert_eq!(region, VonMisesRegion::Residual);
}

#[test]
fn von_mises_rotation_invariance() {
    let eps = Matrix3::new(4e-3, 1e-3, -5e-4, 1e-3, -2e-3, 7e-4, -5e-4, 7e-4, 1e-3);
    let q = rot([0.4, -1.1, 0.8]);
    for (name, law) in vm_laws() {
        let a = law.update(&eps, &[0.01], &mut [0.0]).unwrap();
        let b = law.update(&(q * eps * q.transpose()), &[0.01], &mut [0.0]).unwrap();
        // Round-off of a few products (1e-12 relative).
        assert!((b.stress - q * a.stress * q.transpose()).norm() < 1e-12 * a.stress.norm(), "{name}");
        assert!((b.tangent - rotate4(&q, &a.tangent)).norm() < 1e-12 * a.tangent.norm(), "{name}");
    }
}

/// (a) Oedometer (uniaxial strain ε_zz = −ε, ε_xx = ε_yy = 0), elastic–perfectly plastic.
///
/// Derivation: dev ε = −ε (−1/3, −1/3, 2/3), s = 2G dev ε, so
/// q = √(3/2) ‖s‖ = √(3/2) · 2Gε · √(6)/3 = 2Gε. Yield at q = σ_y:
/// ε_y = σ_y / (2G) = σ_y (1 + ν) / E. (The axial stress there is
/// M ε_y = σ_y (1 − ν)/(1 − 2ν), with M = E(1−ν)/((1+ν)(1−2ν)); the often
/// quoted "ε = σ_y(1 − ν)/(E(1 − 2ν))" is this stress divided by E, not the yield strain.)
/// Elastic branch: σ_zz = −M ε, σ_xx = −λ ε. Plastic branch: q stays σ_y, the mean stress
/// is −K ε, so σ_zz = −K ε − (2/3) σ_y and dσ_zz/dε = −K (bulk modulus), and
/// σ_xx = σ_zz + σ_y.
#[test]
fn von_mises_oedometer_closed_form() {
    let (young, nu, sy) = (1.0e4, 0.3, 30.0);
    let law = VonMises::new(Elastic::new(young, nu).unwrap(), sy, 0.0).unwrap();
    let (lambda, g) = law.elastic.lame();
    let k = lambda + 2.0 * g / 3.0;
    let m = lambda + 2.0 * g;
    let eps_y = sy * (1.0 + nu) / young;
    assert!((eps_y - sy / (2.0 * g)).abs() < 1e-15);
    // Strain-driven incrementally through the small-strain driver, as the solver does.
    let n = 200;
    let eps_max = 5.0 * eps_y;
    let mut ee = Matrix3::zeros();
    let mut h = [0.0];
    for step in 1..=n {
        let de = eps_max / n as f64;
        let mut grad = Matrix3::zeros();
        grad[(2, 2)] = -de;
        let mut h_out = [0.0];
        let (up, _) = {
            let up = small_strain_update(&law, &grad, &ee, &h, &mut h_out).unwrap();
            let region = law.update_with_region(&(ee + grad), &h, &mut [0.0]).unwrap().1;
            (up, region)
        };
        ee = up.elastic_strain;
        h = h_out;
        let eps = step as f64 * de;
        let (szz, sxx) = (up.stress[(2, 2)], up.stress[(0, 0)]);
        // Closed form, round-off of an incremental sum (1e-10 relative to σ_y).
        if eps <= eps_y * (1.0 - 1e-9) {
            assert!((szz + m * eps).abs() < 1e-10 * sy, "elastic step {step}");
            assert!((sxx + lambda * eps).abs() < 1e-10 * sy);
            assert_eq!(h[0], 0.0);
        } else if eps >= eps_y * (1.0 + 1e-9) {
            assert!((szz - (-k * eps - 2.0 * sy / 3.0)).abs() < 1e-10 * sy, "plastic step {step}: {szz}");
            assert!((sxx - (szz + sy)).abs() < 1e-10 * sy);
            // Plastic branch slope: D_zzzz = K exactly for perfect plasticity (round-off).
            assert!((up.tangent[(idx(2, 2), idx(2, 2))] - k).abs() < 1e-10 * k);
        }
    }
    assert!(h[0] > 0.0);
}

/// (a′) Oedometer, Mohr–Coulomb (tension positive): ε_zz = −ε, ε_xx = ε_yy = 0, c = 10,
/// φ = 30°, ν = 0.2, so that the elastic K0 line (σ_xx/σ_zz = ν/(1 − ν) = 1/4) meets the
/// surface (it does not for ν = 0.3 at φ = 30°: 3/7 > k = 1/3). Closed form, with
/// s = sin φ, k = (1 − s)/(1 + s), m = (1 − sin ψ)/(1 + sin ψ), M = λ + 2G:
/// - elastic: σ_zz = −M ε, σ_xx = −λ ε, up to ε_y = 2c cos φ / ((1 − s) M − (1 + s) λ);
/// - then the stress stays on the edge σ₁ = σ₂ = σ_xx (both planes with σ₃ = σ_zz, equal
///   multipliers by symmetry): σ_xx = k σ_zz + 2c cos φ/(1 + s), and ε_xx = 0 with the flow
///   of both planes gives dσ_zz/dε_zz = E / (1 − 2νk + 2m((1 − ν)k − ν)).
///
/// Linear planes, fixed axes and a fixed flow direction make the return exact for any
/// increment, so the incremental result matches to round-off (1e-10 of c).
#[test]
fn mohr_coulomb_oedometer_closed_form() {
    let (young, nu, c, phi) = (1.0e4, 0.2, 10.0, 30.0f64);
    for psi in [30.0f64, 10.0, 0.0] {
        let law = MohrCoulomb::from_degrees(Elastic::new(young, nu).unwrap(), c, phi, psi).unwrap();
        let (lambda, g) = law.elastic.lame();
        let m_el = lambda + 2.0 * g;
        let (s, co) = (phi.to_radians().sin(), phi.to_radians().cos());
        let k = (1.0 - s) / (1.0 + s);
        let m = (1.0 - psi.to_radians().sin()) / (1.0 + psi.to_radians().sin());
        let eps_y = 2.0 * c * co / ((1.0 - s) * m_el - (1.0 + s) * lambda);
        let m_p = young / (1.0 - 2.0 * nu * k + 2.0 * m * ((1.0 - nu) * k - nu));
        let n = 150;
        let de = 5.05 * eps_y / n as f64;
        let mut ee = Matrix3::zeros();
        let mut h = vec![0.0; law.history_len()];
        law.init_history(&mut h, &Matrix3::zeros());
        let mut plastic_steps = 0;
        for step in 1..=n {
            let mut grad = Matrix3::zeros();
            grad[(2, 2)] = -de;
            let mut h_out = vec![0.0; h.len()];
            // grad is symmetric, so ε_trial = ε^e_n + grad (what small_strain_update forms).
            let (up, info) = law.update_with_info(&(ee + grad), &h, &mut h_out).unwrap();
            ee = up.elastic_strain;
            h = h_out;
            let eps = step as f64 * de;
            let (szz, sxx, syy) = (up.stress[(2, 2)], up.stress[(0, 0)], up.stress[(1, 1)]);
            let tol = 1e-10 * c;
            if eps < eps_y {
                assert_eq!(info.region, R::Elastic, "ψ {psi} step {step}");
                assert!((szz + m_el * eps).abs() < tol, "ψ {psi} step {step}: {szz}");
                assert!((sxx + lambda * eps).abs() < tol);
            } else {
                plastic_steps += 1;
                assert_eq!(info.region, R::Edge12, "ψ {psi} step {step}");
                let szz_ref = -m_el * eps_y - m_p * (eps - eps_y);
                assert!((szz - szz_ref).abs() < tol, "ψ {psi} step {step}: {szz} vs {szz_ref}");
                assert!((sxx - (k * szz + 2.0 * c * co / (1.0 + s))).abs() < tol, "ψ {psi} step {step}");
                assert!((syy - sxx).abs() < tol);
                // The algorithmic tangent on the edge is the closed-form constrained
                // modulus (round-off, 1e-9 relative).
                let d = up.tangent[(idx(2, 2), idx(2, 2))];
                assert!((d - m_p).abs() < 1e-9 * m_p, "ψ {psi} step {step}: D_zzzz {d} vs {m_p}");
            }
        }
        // 5.05 ε_y in 150 steps (no step ends on ε_y itself): steps 30 to 150 are plastic.
        assert_eq!(plastic_steps, 121, "ψ {psi}");
    }
}

// ---------------------------------------------------------------- Mohr–Coulomb laws

fn mc(c: f64, phi: f64, psi: f64) -> MohrCoulomb {
    MohrCoulomb::from_degrees(el(), c, phi, psi).unwrap()
}

/// Laws exercised by the region table and the property tests.
fn mc_laws() -> Vec<(&'static str, MohrCoulomb)> {
    vec![
        ("assoc", mc(10.0, 30.0, 30.0)),
        ("nonassoc", mc(10.0, 30.0, 5.0)),
        ("tresca", mc(10.0, 0.0, 0.0)),
        ("assoc+cut", mc(10.0, 30.0, 30.0).with_tension_cutoff(5.0).unwrap()),
        ("nonassoc+cut", mc(10.0, 30.0, 10.0).with_tension_cutoff(5.0).unwrap()),
        ("softening", mc(10.0, 30.0, 10.0).with_softening(2.0, 20.0, 0.0, 0.05).unwrap()),
        (
            "softening+cut",
            mc(10.0, 30.0, 10.0).with_tension_cutoff(5.0).unwrap().with_softening(2.0, 20.0, 0.0, 0.05).unwrap(),
        ),
        ("tiny-phi", MohrCoulomb::new(el(), 10.0, 1e-8, 1e-8).unwrap()),
        ("sand", mc(0.0, 35.0, 0.0)),
        ("sand-assoc", mc(0.0, 35.0, 35.0)),
        ("tresca+cut", mc(10.0, 0.0, 0.0).with_tension_cutoff(5.0).unwrap()),
    ]
}

fn law_named(name: &str) -> MohrCoulomb {
    mc_laws().into_iter().find(|(n, _)| *n == name).unwrap().1
}

/// Scale for F_TOL: largest |trial principal stress| or c.
fn f_scale(law: &MohrCoulomb, sig_tr: &[f64; 3]) -> f64 {
    sig_tr.iter().fold(law.cohesion.max(1.0), |a, &v| a.max(v.abs()))
}

/// Checks one plastic update: region, no fallback (unless allowed), consistency for every
/// surface, σ = C:ε^e, FD tangent. Returns the FD error.
fn check_mc_case(
    name: &str,
    law: &MohrCoulomb,
    sig_tr: [f64; 3],
    kappa_n: f64,
    expect: MohrCoulombRegion,
    expect_residual: Option<bool>,
) -> f64 {
    let eps = strain_for_stress(&law.elastic, sig_tr, [0.3, -0.5, 0.7]);
    let h_n = [kappa_n, 0.0];
    let mut h = [0.0; 2];
    let (up, info) = law.update_with_info(&eps, &h_n, &mut h).unwrap();
    assert_eq!(info.region, expect, "{name} {sig_tr:?} κn {kappa_n}");
    assert!(!info.fallback, "{name} {sig_tr:?}: fallback");
    if let Some(r) = expect_residual {
        assert_eq!(info.residual_branch, r, "{name} {sig_tr:?}: residual branch");
    }
    assert!(finite(&up));
    // F_TOL for both surfaces.
    let scale = f_scale(law, &sig_tr);
    let (f, ft) = law.yield_function(&up.stress, h[0]).unwrap();
    assert!(f <= F_TOL * scale, "{name} {sig_tr:?}: f {f}");
    if let Some(ft) = ft {
        assert!(ft <= F_TOL * scale, "{name} {sig_tr:?}: f_t {ft}");
    }
    // κ never decreases; σ = C : ε^e (round-off, 1e-12 relative).
    assert!(h[0] >= kappa_n);
    assert!((law.elastic.stress(&up.elastic_strain) - up.stress).norm() <= 1e-12 * scale.max(up.stress.norm()));
    let fd = fd_tangent(law, &eps, &h_n);
    let r = tangent_error(&up.tangent, &fd, law.elastic.stiffness().norm());
    record(format!("MC {name} {expect:?}"), r);
    assert!(r < FD_TOL, "{name} {sig_tr:?} {expect:?}: FD rel {r}");
    r
}

/// Every return region, with trial principal stresses (tension positive, σ₁ ≥ σ₂ ≥ σ₃)
/// chosen well inside the region (the ±h FD states stay there). c = 10, φ = 30°
/// (apex c cot φ = 17.32), σ_t = 5.
#[test]
fn mc_every_region_fd_and_consistency() {
    let cases: &[(&str, [f64; 3], f64, MohrCoulombRegion)] = &[
        ("assoc", [-50.0, -100.0, -250.0], 0.0, R::Plane),
        ("assoc", [30.0, -20.0, -60.0], 0.0, R::Plane),
        ("assoc", [-60.0, -62.0, -250.0], 0.0, R::Edge12),
        ("assoc", [300.0, 200.0, -100.0], 0.0, R::Edge12),
        ("assoc", [30.0, -5.0, -10.0], 0.0, R::Edge23),
        ("assoc", [40.0, 35.0, 30.0], 0.0, R::Apex),
        ("nonassoc", [-50.0, -100.0, -250.0], 0.0, R::Plane),
        ("nonassoc", [-60.0, -62.0, -250.0], 0.0, R::Edge12),
        ("nonassoc", [-50.0, -240.0, -250.0], 0.0, R::Edge23),
        ("nonassoc", [300.0, 200.0, -100.0], 0.0, R::Apex),
        ("tresca", [30.0, -20.0, -60.0], 0.0, R::Plane),
        ("tresca", [-60.0, -62.0, -250.0], 0.0, R::Edge12),
        ("tresca", [-50.0, -240.0, -250.0], 0.0, R::Edge23),
        ("tiny-phi", [30.0, -20.0, -60.0], 0.0, R::Plane),
        ("tiny-phi", [-60.0, -62.0, -250.0], 0.0, R::Edge12),
        ("tiny-phi", [-50.0, -240.0, -250.0], 0.0, R::Edge23),
        ("assoc+cut", [8.0, -5.0, -10.0], 0.0, R::Cutoff),
        ("assoc+cut", [30.0, -5.0, -10.0], 0.0, R::CutoffPlane),
        ("assoc+cut", [9.0, 8.5, -3.0], 0.0, R::CutoffEdge12),
        ("assoc+cut", [50.0, -8.0, -10.0], 0.0, R::CutoffCorner23),
        ("assoc+cut", [30.0, 28.0, -10.0], 0.0, R::CutoffCorner12),
        ("assoc+cut", [40.0, 35.0, 30.0], 0.0, R::CutoffApex),
        ("nonassoc+cut", [8.0, -5.0, -10.0], 0.0, R::Cutoff),
        ("nonassoc+cut", [30.0, -5.0, -10.0], 0.0, R::CutoffPlane),
        ("nonassoc+cut", [300.0, 200.0, -100.0], 0.0, R::CutoffCorner12),
        ("nonassoc+cut", [30.0, 28.0, 26.0], 0.0, R::CutoffApex),
        ("tresca+cut", [8.0, -5.0, -10.0], 0.0, R::Cutoff),
        ("tresca+cut", [9.0, 8.5, -3.0], 0.0, R::CutoffEdge12),
        ("tresca+cut", [30.0, 28.0, -10.0], 0.0, R::CutoffCorner12),
        ("sand", [-50.0, -100.0, -250.0], 0.0, R::Plane),
        ("sand", [10.0, -20.0, -30.0], 0.0, R::Edge23),
        ("sand-assoc", [-50.0, -100.0, -250.0], 0.0, R::Plane),
        ("sand-assoc", [20.0, 10.0, 5.0], 0.0, R::Apex),
    ];
    for &(name, s, k, region) in cases {
        check_mc_case(name, &law_named(name), s, k, region, None);
    }
}

/// Softening: every MC region on the softening branch (κ stays below κ_res = 0.05), on the
/// residual branch (κ_n ≥ κ_res), and crossing into it during the step.
#[test]
fn mc_softening_regions_fd_and_consistency() {
    let cases: &[(&str, [f64; 3], f64, MohrCoulombRegion, bool)] = &[
        ("softening", [-50.0, -100.0, -250.0], 0.0, R::Plane, false),
        ("softening", [-50.0, -100.0, -250.0], 0.03, R::Plane, false),
        ("softening", [-60.0, -62.0, -250.0], 0.0, R::Edge12, false),
        ("softening", [-50.0, -240.0, -250.0], 0.0, R::Edge23, false),
        ("softening", [40.0, 35.0, 30.0], 0.0, R::Apex, false),
        ("softening", [40.0, 35.0, 30.0], 0.03, R::Apex, false),
        ("softening", [-50.0, -100.0, -250.0], 0.06, R::Plane, true),
        ("softening", [-60.0, -62.0, -250.0], 0.06, R::Edge12, true),
        ("softening", [-50.0, -240.0, -250.0], 0.06, R::Edge23, true),
        // Crossing κ_res during the step (κ_n = 0.045 < 0.05 < κ_{n+1}).
        ("softening", [-50.0, -100.0, -250.0], 0.045, R::Plane, true),
        ("softening+cut", [8.0, -5.0, -10.0], 0.0, R::Cutoff, false),
        ("softening+cut", [30.0, -5.0, -10.0], 0.0, R::CutoffPlane, false),
        ("softening+cut", [30.0, -5.0, -10.0], 0.03, R::CutoffCorner23, false),
        ("softening+cut", [9.0, 8.5, -3.0], 0.0, R::CutoffEdge12, false),
        ("softening+cut", [30.0, 28.0, -10.0], 0.0, R::CutoffCorner12, false),
        ("softening+cut", [300.0, 200.0, -100.0], 0.03, R::CutoffCorner12, true),
        ("softening+cut", [40.0, 35.0, 30.0], 0.0, R::CutoffApex, false),
    ];
    for &(name, s, k, region, residual) in cases {
        check_mc_case(name, &law_named(name), s, k, region, Some(residual));
    }
    // The apex on the residual branch with ψ_res = 0: no non-dilatant flow reaches the
    // apex, so the return is flagged as a fallback (documented); it is still consistent.
    let law = law_named("softening");
    let eps = strain_for_stress(&law.elastic, [300.0, 200.0, -100.0], [0.1, 0.2, 0.3]);
    let mut h = [0.0; 2];
    let (up, info) = law.update_with_info(&eps, &[0.03, 0.0], &mut h).unwrap();
    assert_eq!(info.region, R::Apex);
    assert!(info.fallback && info.residual_branch);
    let (c, phi, _) = law.strength(h[0]);
    // Apex value c cot φ at κ_{n+1} (round-off, 1e-12 relative).
    let apex = c / phi.tan();
    assert!((principal(&up.stress) - Vector3::repeat(apex)).amax() < 1e-12 * apex);
}

#[test]
fn mc_strength_softens_linearly() {
    let law = law_named("softening");
    let (c0, p0, s0) = law.strength(0.0);
    assert_eq!((c0, p0, s0), (10.0, 30f64.to_radians(), 10f64.to_radians()));
    let (c, p, s) = law.strength(0.025);
    // Halfway: exact mid-values up to round-off.
    assert!((c - 6.0).abs() < 1e-12 && (p - 25f64.to_radians()).abs() < 1e-12 && (s - 5f64.to_radians()).abs() < 1e-12);
    assert_eq!(law.strength(0.05), law.strength(1.0));
    assert_eq!(law.strength(1.0), (2.0, 20f64.to_radians(), 0.0));
}

#[test]
fn mc_elastic_trial_unchanged() {
    for (name, law) in mc_laws() {
        let eps = strain_for_stress(&law.elastic, [-20.0, -22.0, -25.0], [0.3, 0.1, -0.2]);
        let mut h = [0.0; 2];
        let (up, info) = law.update_with_info(&eps, &[0.01, 0.002], &mut h).unwrap();
        assert_eq!(info.region, R::Elastic, "{name}");
        assert_eq!(up.stress, law.elastic.stress(&eps), "{name}");
        assert_eq!(up.tangent, law.elastic.stiffness(), "{name}");
        assert_eq!(up.elastic_strain, eps, "{name}");
        assert_eq!(h, [0.01, 0.002], "{name}");
    }
    // Zero strain, and with c = 0 (sand): zero stress is admissible, not a plastic state.
    for (name, law) in mc_laws() {
        let (up, info) = law.update_with_info(&Matrix3::zeros(), &[0.0, 0.0], &mut [0.0; 2]).unwrap();
        assert_eq!(info.region, R::Elastic, "{name}");
        assert_eq!(up.stress, Matrix3::zeros());
    }
}

#[test]
fn mc_rotation_invariance() {
    let q = rot([0.4, -1.1, 0.8]);
    for (name, s, k) in [
        ("assoc", [-50.0, -100.0, -250.0], 0.0),
        ("assoc", [-60.0, -62.0, -250.0], 0.0),
        ("assoc", [30.0, -5.0, -10.0], 0.0),
        ("nonassoc", [300.0, 200.0, -100.0], 0.0),
        ("assoc+cut", [30.0, -5.0, -10.0], 0.0),
        ("assoc+cut", [30.0, 28.0, -10.0], 0.0),
        ("softening", [-50.0, -100.0, -250.0], 0.02),
        ("softening", [40.0, 35.0, 30.0], 0.02),
        ("tresca", [-60.0, -62.0, -250.0], 0.0),
    ] {
        let law = law_named(name);
        let eps = strain_for_stress(&law.elastic, s, [0.3, -0.5, 0.7]);
        let h_n = [k, 0.0];
        let (mut ha, mut hb) = ([0.0; 2], [0.0; 2]);
        let a = law.update(&eps, &h_n, &mut ha).unwrap();
        let b = law.update(&(q * eps * q.transpose()), &h_n, &mut hb).unwrap();
        // Two eigen-decompositions: round-off well inside 1e-10 relative.
        let sc = a.stress.norm();
        assert!((b.stress - q * a.stress * q.transpose()).norm() < 1e-10 * sc, "{name} {s:?}");
        assert!((b.elastic_strain - q * a.elastic_strain * q.transpose()).norm() < 1e-10 * eps.norm());
        let dt = law.elastic.stiffness().norm();
        assert!((b.tangent - rotate4(&q, &a.tangent)).norm() < 1e-9 * dt, "{name} {s:?}");
        assert!((ha[0] - hb[0]).abs() < 1e-12 * ha[0].max(1e-3));
    }
}

#[test]
fn mc_tangent_symmetry() {
    assert!(law_named("assoc").symmetric_tangent());
    assert!(law_named("tresca").symmetric_tangent());
    assert!(law_named("assoc+cut").symmetric_tangent());
    assert!(!law_named("nonassoc").symmetric_tangent());
    assert!(!law_named("softening").symmetric_tangent());
    // Associated flow: symmetric in every region (round-off, 1e-12 relative to ‖Dᵉ‖).
    let dnorm = el().stiffness().norm();
    for (name, s) in [
        ("assoc", [-50.0, -100.0, -250.0]),
        ("assoc", [-60.0, -62.0, -250.0]),
        ("assoc", [30.0, -5.0, -10.0]),
        ("assoc", [40.0, 35.0, 30.0]),
        ("tresca", [-50.0, -240.0, -250.0]),
        ("assoc+cut", [8.0, -5.0, -10.0]),
        ("assoc+cut", [30.0, -5.0, -10.0]),
        ("assoc+cut", [9.0, 8.5, -3.0]),
        ("assoc+cut", [50.0, -8.0, -10.0]),
        ("assoc+cut", [30.0, 28.0, -10.0]),
    ] {
        let law = law_named(name);
        let eps = strain_for_stress(&law.elastic, s, [0.3, -0.5, 0.7]);
        let d = law.update(&eps, &[0.0, 0.0], &mut [0.0; 2]).unwrap().tangent;
        assert!((d - d.transpose()).norm() < 1e-12 * dnorm, "{name} {s:?}");
    }
    // ψ ≠ φ: clearly non-symmetric on the plane and the edges (> 1 % of ‖D‖).
    for s in [[-50.0, -100.0, -250.0], [-60.0, -62.0, -250.0], [-50.0, -240.0, -250.0]] {
        let law = law_named("nonassoc");
        let eps = strain_for_stress(&law.elastic, s, [0.3, -0.5, 0.7]);
        let d = law.update(&eps, &[0.0, 0.0], &mut [0.0; 2]).unwrap().tangent;
        assert!((d - d.transpose()).norm() > 1e-2 * d.norm(), "{s:?}");
    }
}

/// Apexes, edges and repeated principal values never give NaN, and the result is admissible.
#[test]
fn mc_no_nan_at_apex_edges_and_repeated_values() {
    let mut strains = vec![
        // Hydrostatic tension far beyond the apex (1e6 × c cot φ in stress).
        Matrix3::identity() * 1e3,
        Matrix3::identity() * 1e-3,
        Matrix3::identity() * -1e-2,
        Matrix3::zeros(),
        // Two equal principal values, both orderings, exactly.
        Matrix3::from_diagonal(&Vector3::new(1e-2, 1e-2, -2e-2)),
        Matrix3::from_diagonal(&Vector3::new(2e-2, -1e-2, -1e-2)),
        Matrix3::from_diagonal(&Vector3::new(-1e-2, -1e-2, 5e-3)),
        // Nearly equal (1e-14 apart).
        Matrix3::from_diagonal(&Vector3::new(1e-2, 1e-2 * (1.0 + 1e-14), -2e-2)),
        // Pure shear.
        Matrix3::new(0.0, 1e-2, 0.0, 1e-2, 0.0, 0.0, 0.0, 0.0, 0.0),
        // Huge deviatoric strain.
        Matrix3::from_diagonal(&Vector3::new(10.0, 0.0, -10.0)),
    ];
    let q = rot([0.7, 0.2, -0.4]);
    let rotated: Vec<_> = strains.iter().map(|e| q * e * q.transpose()).collect();
    strains.extend(rotated);
    for (name, law) in mc_laws() {
        for eps in &strains {
            for kappa_n in [0.0, 0.04, 1.0] {
                let mut h = [0.0; 2];
                let (up, info) =
                    law.update_with_info(eps, &[kappa_n, 0.0], &mut h).unwrap_or_else(|e| panic!("{name} {eps}: {e}"));
                assert!(finite(&up), "{name} {eps} {info:?}");
                assert!(h.iter().all(|v| v.is_finite()));
                let sc = law.elastic.stress(eps).amax().max(law.cohesion).max(1.0);
                let (f, ft) = law.yield_function(&up.stress, h[0]).unwrap();
                // F_TOL on both surfaces.
                assert!(f <= F_TOL * sc, "{name} {eps} {info:?}: f {f}");
                assert!(ft.unwrap_or(0.0) <= F_TOL * sc, "{name} {eps}: f_t {ft:?}");
            }
        }
    }
    // Hydrostatic tension beyond the apex lands on it (φ > 0) or is elastic (Tresca).
    let eps = Matrix3::identity() * 1e3;
    let (up, info) = law_named("assoc").update_with_info(&eps, &[0.0, 0.0], &mut [0.0; 2]).unwrap();
    assert_eq!(info.region, R::Apex);
    let apex = 10.0 / 30f64.to_radians().tan();
    // Closed form c cot φ (round-off, 1e-12 relative).
    assert!((up.stress - Matrix3::identity() * apex).norm() < 1e-12 * apex);
    assert_eq!(up.tangent, Tensor4::zeros());
    let (_, info) = law_named("tresca").update_with_info(&eps, &[0.0, 0.0], &mut [0.0; 2]).unwrap();
    assert_eq!(info.region, R::Elastic);
    let (up, info) = law_named("tresca+cut").update_with_info(&eps, &[0.0, 0.0], &mut [0.0; 2]).unwrap();
    assert_eq!(info.region, R::CutoffApex);
    // Round-off relative to the trial stress (~1e7 here), 1e-12.
    assert!(
        (up.stress - Matrix3::identity() * 5.0).norm() < 1e-12 * law_named("tresca+cut").elastic.stress(&eps).norm()
    );
}

/// φ → 0 approaches Tresca continuously: φ = 1e-8 rad changes the stress by O(φ·|σ|).
#[test]
fn mc_tresca_limit_is_continuous() {
    let tresca = law_named("tresca");
    for phi in [1e-8, 1e-6] {
        let near = MohrCoulomb::new(el(), 10.0, phi, phi).unwrap();
        for s in [[30.0, -20.0, -60.0], [-60.0, -62.0, -250.0], [-50.0, -240.0, -250.0], [500.0, 0.0, -500.0]] {
            let eps = strain_for_stress(&el(), s, [0.3, -0.5, 0.7]);
            let a = tresca.update(&eps, &[0.0, 0.0], &mut [0.0; 2]).unwrap();
            let b = near.update(&eps, &[0.0, 0.0], &mut [0.0; 2]).unwrap();
            // The yield function changes by ~φ(σ₁ + σ₃) + φ² c: bound 10 φ |σ|.
            let sc = f_scale(&tresca, &s);
            assert!((a.stress - b.stress).norm() < 10.0 * phi * sc, "φ {phi} {s:?}");
            assert!((a.tangent - b.tangent).norm() < 1e3 * phi * el().stiffness().norm(), "φ {phi} {s:?}");
        }
    }
}

// ---------------------------------------------------------------- triaxial paths

/// Drained triaxial compression, small strain, strain-driven with mixed control: the
/// lateral stresses σ_xx = σ_yy are held at −p_c by solving for the lateral strain with
/// Newton's method on the algorithmic tangent (D_xxxx + D_xxyy), while the axial strain
/// ε_zz decreases in equal steps. Returns the deviator q = σ_xx − σ_zz (compression
/// positive: σ'₁ − σ'₃) after each step and the number of Newton iterations per step.
fn triaxial(law: &dyn ConstitutiveLaw, p_c: f64, steps: usize, de_axial: f64) -> (Vec<f64>, usize) {
    let el = el();
    let (lambda, g) = el.lame();
    let k = lambda + 2.0 * g / 3.0;
    let mut ee = Matrix3::identity() * (-p_c / (3.0 * k));
    let nh = law.history_len();
    let mut h = vec![0.0; nh];
    let mut out = Vec::new();
    let mut max_it = 0;
    for _ in 0..steps {
        let mut x = 0.0;
        let mut it = 0;
        let up = loop {
            let grad = Matrix3::from_diagonal(&Vector3::new(x, x, -de_axial));
            let mut h_out = vec![0.0; nh];
            let up = small_strain_update(law, &grad, &ee, &h, &mut h_out).unwrap();
            let r = up.stress[(0, 0)] + p_c;
            if r.abs() < 1e-12 * p_c.max(10.0) {
                h = h_out;
                break up;
            }
            let d = up.tangent[(idx(0, 0), idx(0, 0))] + up.tangent[(idx(0, 0), idx(1, 1))];
            x -= r / d;
            it += 1;
            assert!(it < 50, "lateral Newton did not converge");
        };
        max_it = max_it.max(it);
        ee = up.elastic_strain;
        // Axisymmetric: σ_yy = σ_xx exactly by symmetry of the loading (round-off).
        assert!((up.stress[(1, 1)] - up.stress[(0, 0)]).abs() < 1e-10 * p_c.max(10.0));
        out.push(up.stress[(0, 0)] - up.stress[(2, 2)]);
    }
    (out, max_it)
}

/// (b) Mohr–Coulomb drained triaxial compression. Compression positive: σ'₃ = p_c
/// (confining), σ'₁ axial; MC failure σ'₁ − σ'₃ = 2c cos φ + (σ'₁ + σ'₃) sin φ, so
/// q_f = σ'₁ − σ'₃ = (2c cos φ + 2 p_c sin φ)/(1 − sin φ). In the tension-positive law
/// σ_xx = σ_yy = −p_c = σ₁ = σ₂ and σ_zz = −σ'₁ = σ₃: the state sits on the σ₁ = σ₂ edge.
/// Elastic slope dq/dε_axial = E (drained, constant lateral stress).
#[test]
fn mc_triaxial_compression_closed_form() {
    let (c, p_c) = (10.0, 100.0);
    for (phi, psi) in [(30.0f64, 30.0f64), (30.0, 0.0), (20.0, 10.0)] {
        let law = mc(c, phi, psi);
        let (s, co) = (phi.to_radians().sin(), phi.to_radians().cos());
        let q_f = (2.0 * c * co + 2.0 * p_c * s) / (1.0 - s);
        let de = 1e-4;
        let (q, max_it) = triaxial(&law, p_c, 400, de);
        // Elastic start: q = E ε_axial (round-off of the Newton solution, 1e-9 relative).
        assert!((q[0] - 1e4 * de).abs() < 1e-9 * q_f, "φ {phi}: {}", q[0]);
        // Perfect plasticity: the deviator plateaus at q_f (F_TOL-level consistency).
        let last = *q.last().unwrap();
        assert!((last - q_f).abs() < F_TOL * 10.0 * p_c, "φ {phi} ψ {psi}: q {last} vs {q_f}");
        assert!(q.iter().all(|&v| v <= q_f * (1.0 + 1e-10)));
        // A consistent tangent: the lateral stress condition converges in a few iterations.
        assert!(max_it <= 6, "φ {phi} ψ {psi}: {max_it} iterations");
    }
}

/// (c) Tresca (φ = 0) limit: deviator 2c whatever the confining pressure; von Mises on the
/// same path (axisymmetric, q = √(3J₂)) plateaus at σ_y.
#[test]
fn tresca_and_von_mises_triaxial_limits() {
    let c = 10.0;
    for p_c in [0.0, 50.0, 400.0] {
        let (q, _) = triaxial(&mc(c, 0.0, 0.0), p_c, 300, 1e-4);
        let last = *q.last().unwrap();
        // F_TOL-level consistency at the plateau.
        assert!((last - 2.0 * c).abs() < F_TOL * 10.0 * p_c.max(2.0 * c), "p_c {p_c}: {last}");
    }
    let vm = VonMises::new(el(), 30.0, 0.0).unwrap();
    let (q, _) = triaxial(&vm, 100.0, 300, 1e-4);
    assert!((q.last().unwrap() - 30.0).abs() < F_TOL * 1e3);
}

// ---------------------------------------------------------------- drivers

/// The laws work inside the finite-strain driver: the spatial tangent linearises the
/// Kirchhoff stress (J a : g = δτ − τ gᵀ, as in tests/finite_strain.rs) in plastic states.
#[test]
fn plastic_laws_in_finite_strain_driver() {
    let g = Matrix3::new(0.3, -0.7, 0.2, 0.5, 0.1, -0.4, -0.6, 0.9, 0.25);
    let df = Matrix3::new(0.97, 0.02, 0.0, 0.01, 1.01, 0.0, 0.0, 0.0, 0.99);
    let be_n = Matrix3::identity();
    let vm = VonMises::new(el(), 30.0, 0.0).unwrap();
    let laws: Vec<(&str, &dyn ConstitutiveLaw)> = vec![("von Mises", &vm)];
    let mcs: Vec<(&str, MohrCoulomb)> = mc_laws();
    let mut all = laws;
    for (n, l) in &mcs {
        all.push((n, l));
    }
    for (name, law) in all {
        let nh = law.history_len();
        let h_n = vec![0.0; nh];
        let j = df.determinant();
        let mut h_out = vec![0.0; nh];
        let base = finite_strain_update(law, &df, &be_n, j, &h_n, &mut h_out).unwrap();
        // The state is plastic (slot 0 is ε̄p or κ for both laws).
        assert!(h_out[0] > 0.0, "{name}: elastic state");
        let eps = 1e-6;
        let tau_at = |s: f64| {
            let dfe = (Matrix3::identity() + g * s) * df;
            finite_strain_update(law, &dfe, &be_n, dfe.determinant(), &h_n, &mut vec![0.0; nh]).unwrap().kirchhoff
        };
        let dtau = (tau_at(eps) - tau_at(-eps)) / (2.0 * eps);
        let lhs = loam_constitutive::tensor::contract(&base.spatial_tangent, &g) * j;
        let rhs = dtau - base.kirchhoff * g.transpose();
        let r = (lhs - rhs).norm() / rhs.norm();
        // FD_TOL (same directional check as tests/finite_strain.rs).
        assert!(r < FD_TOL, "{name}: rel {r}");
    }
}

#[test]
fn mc_errors_not_panics() {
    let law = law_named("assoc");
    let e = Matrix3::zeros();
    assert!(matches!(law.update(&e, &[0.0], &mut [0.0; 2]), Err(ConstitutiveError::HistoryLength { .. })));
    assert!(matches!(law.update(&e, &[0.0; 2], &mut [0.0; 3]), Err(ConstitutiveError::HistoryLength { .. })));
    assert!(law.update(&e, &[f64::NAN, 0.0], &mut [0.0; 2]).is_err());
    assert!(law.update(&e, &[-1.0, 0.0], &mut [0.0; 2]).is_err());
    let mut bad = e;
    bad[(0, 2)] = f64::INFINITY;
    assert!(law.update(&bad, &[0.0; 2], &mut [0.0; 2]).is_err());
    // Finite but overflowing strain: an error, not an infinite stress.
    let huge = Matrix3::from_diagonal(&Vector3::new(1e305, -1e305, 0.0));
    assert!(law.update(&huge, &[0.0; 2], &mut [0.0; 2]).is_err());
    let mut h = [1.0, 1.0];
    law.init_history(&mut h, &Matrix3::zeros());
    assert_eq!(h, [0.0, 0.0]);
    assert_eq!(law.history_len(), 2);
    let e2 = Matrix3::new(1e-3, 0.0, 2e-4, 0.0, -3e-4, 0.0, 2e-4, 0.0, 5e-4);
    assert_eq!(law.stored_energy(&e2), law.elastic.stored_energy(&e2));
    assert_eq!(law.p_wave_modulus(&loam_constitutive::MaterialState::at_rest(&h)), law.elastic.p_wave_modulus());
}

// ---------------------------------------------------------------- property tests

/// The relative error of a plastic update's tangent against central differences, or None
/// where the state is elastic or lies within the FD step of a region or branch boundary (a
/// kink, where the one-sided derivatives differ and a difference quotient means nothing).
fn mc_fd_error_away_from_kinks(
    law: &MohrCoulomb,
    eps: &Matrix3<f64>,
    h_n: &[f64],
    up: &StressUpdate,
    info: &loam_constitutive::MohrCoulombReturn,
) -> Option<f64> {
    if info.region == R::Elastic {
        return None;
    }
    let hstep = 1e-6 * eps.norm();
    for (_, _, d) in symmetric_unit_directions() {
        for sgn in [-1.0, 1.0] {
            let (_, i2) = law.update_with_info(&(eps + d * (sgn * hstep)), h_n, &mut [0.0; 2]).unwrap();
            if i2.region != info.region || i2.residual_branch != info.residual_branch {
                return None;
            }
        }
    }
    let fd = fd_tangent(law, eps, h_n);
    Some(tangent_error(&up.tangent, &fd, law.elastic.stiffness().norm()))
}

/// Trial principal stresses spanning every region of the laws above (c = 10, σ_t = 5).
fn stress_triple() -> impl Strategy<Value = [f64; 3]> {
    prop_oneof![
        prop::array::uniform3(-400.0f64..100.0),
        prop::array::uniform3(-40.0f64..40.0),
        // Near-hydrostatic tension (apex regions).
        (0.0f64..200.0, prop::array::uniform3(-5.0f64..5.0)).prop_map(|(p, d)| [p + d[0], p + d[1], p + d[2]]),
        // Two nearly equal values (edges).
        (-300.0f64..50.0, -300.0f64..50.0, -1.0f64..1.0).prop_map(|(a, b, d)| [a, a + d, b]),
        // Around the tension cut-off σ_t = 5 and its corners.
        (5.0f64..80.0, -40.0f64..20.0, -40.0f64..20.0).prop_map(|(a, b, c)| [a, b, c]),
        (5.0f64..40.0, -1.0f64..1.0, -60.0f64..20.0).prop_map(|(a, d, c)| [a, a + d, c]),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(std::env::var("LOAM_PROPTEST_CASES").ok().and_then(|v| v.parse().ok()).unwrap_or(600)))]

    #[test]
    fn mc_random_states(
        which in 0usize..11,
        s in stress_triple(),
        r in prop::array::uniform3(-3.0f64..3.0),
        kappa_n in prop_oneof![Just(0.0), 0.0f64..0.1],
    ) {
        let (name, law) = mc_laws().swap_remove(which);
        let eps = strain_for_stress(&law.elastic, s, r);
        let h_n = [kappa_n, 0.0];
        let mut h = [0.0; 2];
        let (up, info) = law.update_with_info(&eps, &h_n, &mut h).unwrap();
        prop_assert!(finite(&up));
        // Without the tangent (the explicit step's update): the same stress, elastic strain
        // and history to the last bit.
        let mut h_stress = [0.0; 2];
        let only = law.update_stress(&eps, &h_n, &mut h_stress).unwrap();
        prop_assert_eq!((only, h_stress), ((up.stress, up.elastic_strain), h));
        let scale = f_scale(&law, &s);
        let (f, ft) = law.yield_function(&up.stress, h[0]).unwrap();
        // F_TOL on both surfaces.
        prop_assert!(f <= F_TOL * scale, "{} f {}", name, f);
        prop_assert!(ft.unwrap_or(0.0) <= F_TOL * scale, "{} f_t {:?}", name, ft);
        prop_assert!(h[0] >= kappa_n);
        // Associated flow without softening: the regions partition stress space.
        if law.symmetric_tangent() {
            prop_assert!(!info.fallback, "{} {:?}", name, info);
        }
        record_count(format!("{name:14} {:?}{}", info.region, if info.fallback { " (fallback)" } else { "" }));
        if let Some(err) = mc_fd_error_away_from_kinks(&law, &eps, &h_n, &up, &info) {
            record(format!("MC proptest {:?}", info.region), err);
            prop_assert!(err < FD_TOL, "{} {:?} κn {}: FD {}", name, info, kappa_n, err);
        }
        if law.symmetric_tangent() {
            // Round-off, 1e-12 relative to ‖Dᵉ‖.
            prop_assert!((up.tangent - up.tangent.transpose()).norm() < 1e-12 * law.elastic.stiffness().norm());
        }
    }

    /// The return map is continuous (Lipschitz) across region boundaries: a small change
    /// δ of the trial strain changes the stress by at most a few ‖Dᵉ‖‖δ‖ (the closest-point
    /// projection is non-expansive in the energy norm for associated flow; the bound 20 is
    /// loose enough for the non-associated laws and softening with these parameters, and
    /// far below what a jump between regions would give, ~‖σ‖).
    #[test]
    fn mc_return_map_is_continuous(
        which in 0usize..11,
        s in stress_triple(),
        r in prop::array::uniform3(-3.0f64..3.0),
        d in prop::array::uniform6(-1.0f64..1.0),
        kappa_n in prop_oneof![Just(0.0), 0.0f64..0.1],
    ) {
        let (name, law) = mc_laws().swap_remove(which);
        let eps = strain_for_stress(&law.elastic, s, r);
        let delta = Matrix3::new(d[0], d[3], d[4], d[3], d[1], d[5], d[4], d[5], d[2]) * (1e-5 * eps.norm().max(1e-4));
        let h_n = [kappa_n, 0.0];
        let (a, ia) = law.update_with_info(&eps, &h_n, &mut [0.0; 2]).unwrap();
        let (b, ib) = law.update_with_info(&(eps + delta), &h_n, &mut [0.0; 2]).unwrap();
        let bound = 20.0 * law.elastic.stiffness().norm() * delta.norm();
        prop_assert!((a.stress - b.stress).norm() <= bound,
            "{} {:?} -> {:?}: jump {} bound {}", name, ia, ib, (a.stress - b.stress).norm(), bound);
    }

    /// Random strain paths through the small-strain driver with the history carried over:
    /// every step is consistent (F_TOL), finite, κ never decreases, and each plastic step's
    /// tangent, with the history the path has built, matches central differences (FD_TOL)
    /// wherever ±h stays in the step's region and branch.
    #[test]
    fn mc_random_paths(
        which in 0usize..11,
        incs in prop::collection::vec(prop::array::uniform6(-2e-3f64..2e-3), 1..25),
    ) {
        let (name, law) = mc_laws().swap_remove(which);
        let mut ee = Matrix3::zeros();
        let mut h = [0.0; 2];
        for d in incs {
            let grad = Matrix3::new(d[0], d[3], d[4], 0.0, d[1], d[5], 0.0, 0.0, d[2]);
            let mut h_out = [0.0; 2];
            let up = small_strain_update(&law, &grad, &ee, &h, &mut h_out).unwrap();
            prop_assert!(finite(&up));
            let tr = law.elastic.stress(&(ee + (grad + grad.transpose()) * 0.5));
            let scale = tr.amax().max(law.cohesion).max(1.0);
            let (f, ft) = law.yield_function(&up.stress, h_out[0]).unwrap();
            // F_TOL on both surfaces.
            prop_assert!(f <= F_TOL * scale && ft.unwrap_or(0.0) <= F_TOL * scale, "{} f {} ft {:?}", name, f, ft);
            prop_assert!(h_out[0] >= h[0]);
            let eps = ee + (grad + grad.transpose()) * 0.5;
            let (at, info) = law.update_with_info(&eps, &h, &mut [0.0; 2]).unwrap();
            if let Some(err) = mc_fd_error_away_from_kinks(&law, &eps, &h, &at, &info) {
                record(format!("MC path proptest {:?}", info.region), err);
                prop_assert!(err < FD_TOL, "{} {:?} κn {}: FD {}", name, info, h[0], err);
            }
            ee = up.elastic_strain;
            h = h_out;
        }
    }

    #[test]
    fn von_mises_random_states(
        which in 0usize..3,
        e in prop::array::uniform6(-5e-3f64..5e-3),
        eqps_n in prop_oneof![Just(0.0), 0.0f64..0.3],
    ) {
        let (name, law) = vm_laws().swap_remove(which);
        let eps = Matrix3::new(e[0], e[3], e[4], e[3], e[1], e[5], e[4], e[5], e[2]);
        let mut h = [0.0];
        let (up, region) = law.update_with_region(&eps, &[eqps_n], &mut h).unwrap();
        prop_assert!(finite(&up));
        // Without the tangent (the explicit step's update): the same stress, elastic strain
        // and history to the last bit.
        let mut h_stress = [0.0];
        let only = law.update_stress(&eps, &[eqps_n], &mut h_stress).unwrap();
        prop_assert_eq!((only, h_stress), ((up.stress, up.elastic_strain), h));
        let dev = up.stress - Matrix3::identity() * (up.stress.trace() / 3.0);
        let q = 1.5f64.sqrt() * dev.norm();
        let sy = law.current_yield_stress(h[0]);
        // F_TOL.
        prop_assert!(q - sy <= F_TOL * sy.max(30.0), "{} q {} σy {}", name, q, sy);
        if region != VonMisesRegion::Elastic {
            prop_assert!((q - sy).abs() <= F_TOL * sy.max(30.0));
            // FD only where ±h stays on the same branch (not at yield onset or the floor kink).
            let hstep = 1e-6 * eps.norm();
            let mut same = true;
            for (_, _, d) in symmetric_unit_directions() {
                for sgn in [-1.0, 1.0] {
                    let (_, r2) = law.update_with_region(&(eps + d * (sgn * hstep)), &[eqps_n], &mut [0.0]).unwrap();
                    same &= r2 == region;
                }
            }
            if same {
                let fd = fd_tangent(&law, &eps, &[eqps_n]);
                let err = tangent_error(&up.tangent, &fd, law.elastic.stiffness().norm());
                record(format!("von Mises proptest {region:?}"), err);
                prop_assert!(err < FD_TOL, "{} FD {}", name, err);
            }
        }
        let rq = rot([e[0] * 300.0, e[1] * 300.0, e[2] * 300.0]);
        let b = law.update(&(rq * eps * rq.transpose()), &[eqps_n], &mut [0.0]).unwrap();
        // Rotation invariance (round-off, 1e-12 relative).
        prop_assert!((b.stress - rq * up.stress * rq.transpose()).norm() <= 1e-12 * up.stress.norm().max(1.0));
    }
}

/// Prints the largest FD error per (law, region) recorded by the tests that ran before it
/// in this process (run with `--nocapture --test-threads=1` to see a complete table).
#[test]
fn zz_report_fd_errors() {
    for (k, v) in FD_ERRORS.lock().unwrap().iter() {
        eprintln!("FD {k:40} max rel err {v:.2e}");
    }
    for (k, v) in COUNTS.lock().unwrap().iter() {
        eprintln!("visits {k:40} {v}");
    }
}
