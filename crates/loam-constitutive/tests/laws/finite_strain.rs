//! Finite-strain driver checks (docs/theory.md §2). The key one is that the spatial tangent is
//! the exact linearisation of the internal force: with δΔF = g ΔF,
//! `J a : g = δτ − τ gᵀ` (f_int per reference volume is τ_ij ∂N/∂x_j and
//! δ(∂N/∂x_j) = −∂N/∂x_m g_mj).

use loam_constitutive::tensor::{b_operator, contract, idx, isotropic, log_derivative, sym_exp, sym_identity, Tensor4};
use loam_constitutive::{
    finite_strain_update, small_strain_update, ConstitutiveError, ConstitutiveLaw, Elastic, StressUpdate,
};
use nalgebra::{Matrix3, Rotation3, Vector3};
use proptest::prelude::*;

/// FD step for the directional derivative: truncation ~ε²·|τ'''| ≈ 1e-12 relative, round-off
/// of the eigen-decomposition ~1e-16/ε ≈ 1e-10 relative; both far below the 1e-6 tolerance.
const FD_EPS: f64 = 1e-6;
/// The tangent-check tolerance of docs/theory.md §16: relative difference ≤ 1e-6.
const TOL: f64 = 1e-6;

fn rel(a: &Matrix3<f64>, b: &Matrix3<f64>) -> f64 {
    (a - b).norm() / b.norm()
}

fn rot(r: [f64; 3]) -> Matrix3<f64> {
    Rotation3::from_scaled_axis(Vector3::from(r)).into_inner()
}

/// SPD b^e_n = Q exp(2 diag(e)) Qᵀ.
fn be_from(angles: [f64; 3], e: [f64; 3]) -> Matrix3<f64> {
    let q = rot(angles);
    q * Matrix3::from_diagonal(&Vector3::from(e).map(|x| (2.0 * x).exp())) * q.transpose()
}

fn mat(v: [f64; 9]) -> Matrix3<f64> {
    Matrix3::from_row_slice(&v)
}

// ---------------------------------------------------------------- test-only laws

/// Nonlinear isotropic law τ = λ tr ε I + 2μ ε + c ε², exercising a strain-dependent D.
#[derive(Debug)]
struct Quadratic {
    lambda: f64,
    mu: f64,
    c: f64,
}

impl ConstitutiveLaw for Quadratic {
    fn name(&self) -> &'static str {
        "quadratic"
    }
    fn update(&self, e: &Matrix3<f64>, _: &[f64], _: &mut [f64]) -> Result<StressUpdate, ConstitutiveError> {
        let stress = Matrix3::identity() * (self.lambda * e.trace()) + e * (2.0 * self.mu) + e * e * self.c;
        let mut d = isotropic(self.lambda, self.mu);
        let dl = |a: usize, b: usize| if a == b { 1.0 } else { 0.0 };
        for i in 0..3 {
            for j in 0..3 {
                for k in 0..3 {
                    for l in 0..3 {
                        d[(idx(i, j), idx(k, l))] += 0.5
                            * self.c
                            * (dl(i, k) * e[(l, j)]
                                + e[(i, k)] * dl(j, l)
                                + dl(i, l) * e[(k, j)]
                                + e[(i, l)] * dl(j, k));
                    }
                }
            }
        }
        Ok(StressUpdate { stress, elastic_strain: *e, tangent: d })
    }
    fn p_wave_modulus(&self, _state: &loam_constitutive::MaterialState) -> f64 {
        self.lambda + 2.0 * self.mu
    }
    fn stored_energy(&self, e: &Matrix3<f64>) -> f64 {
        // W with ∂W/∂ε = τ: the c ε² term integrates to (c/3) tr(ε³).
        0.5 * self.lambda * e.trace().powi(2) + self.mu * e.component_mul(e).sum() + self.c * (e * e * e).trace() / 3.0
    }
}

/// A "return mapping" that removes a fixed fraction β of the trial strain along a fixed
/// direction m (ε^e = ε_tr − β (m:ε_tr) m). Not isotropic, so ε^e is not coaxial with
/// b_tr and the b^e update must take the general path; carries one history variable.
#[derive(Debug)]
struct Relax {
    el: Elastic,
    beta: f64,
    m: Matrix3<f64>,
}

impl ConstitutiveLaw for Relax {
    fn name(&self) -> &'static str {
        "relax"
    }
    fn history_len(&self) -> usize {
        1
    }
    fn symmetric_tangent(&self) -> bool {
        false
    }
    fn update(&self, e: &Matrix3<f64>, h_n: &[f64], h_out: &mut [f64]) -> Result<StressUpdate, ConstitutiveError> {
        let s = self.m.dot(e);
        let ee = e - self.m * (self.beta * s);
        h_out[0] = h_n[0] + self.beta * s.abs();
        let del = self.el.stiffness();
        // D = Del (I^s − β m ⊗ m)
        let mf = loam_constitutive::tensor::flatten(&self.m);
        let proj = sym_identity() - mf * mf.transpose() * self.beta;
        Ok(StressUpdate { stress: self.el.stress(&ee), elastic_strain: ee, tangent: del * proj })
    }
    fn p_wave_modulus(&self, _state: &loam_constitutive::MaterialState) -> f64 {
        self.el.p_wave_modulus()
    }
    fn stored_energy(&self, e: &Matrix3<f64>) -> f64 {
        self.el.stored_energy(e)
    }
}

fn relax_law() -> Relax {
    let m = mat([0.6, 0.2, 0.0, 0.2, -0.3, 0.1, 0.0, 0.1, 0.4]);
    Relax { el: Elastic::new(800.0, 0.25).unwrap(), beta: 0.4, m: m / m.norm() }
}

// ---------------------------------------------------------------- the consistency check

/// Returns the relative difference between `J a : g` and `δτ − τ gᵀ`.
fn consistency(law: &dyn ConstitutiveLaw, df: &Matrix3<f64>, be_n: &Matrix3<f64>, g: &Matrix3<f64>) -> f64 {
    let nh = law.history_len();
    let h_n = vec![0.0; nh];
    let mut h = vec![0.0; nh];
    let det_fn = be_n.determinant().sqrt();
    let j = df.determinant() * det_fn;
    let base = finite_strain_update(law, df, be_n, j, &h_n, &mut h).unwrap();
    let tau_at = |s: f64| {
        let dfe = (Matrix3::identity() + g * s) * df;
        let je = dfe.determinant() * det_fn;
        let mut h = vec![0.0; nh];
        finite_strain_update(law, &dfe, be_n, je, &h_n, &mut h).unwrap().kirchhoff
    };
    let dtau = (tau_at(FD_EPS) - tau_at(-FD_EPS)) / (2.0 * FD_EPS);
    let lhs = contract(&base.spatial_tangent, g) * j;
    let rhs = dtau - base.kirchhoff * g.transpose();
    rel(&lhs, &rhs)
}

fn elastic() -> Elastic {
    Elastic::new(1000.0, 0.3).unwrap()
}

fn quadratic() -> Quadratic {
    Quadratic { lambda: 500.0, mu: 300.0, c: 2000.0 }
}

#[test]
fn consistency_fixed_cases() {
    let df = mat([1.05, 0.1, -0.02, 0.03, 0.97, 0.04, -0.01, 0.02, 1.01]);
    let be_n = be_from([0.3, -0.5, 0.2], [0.05, -0.1, 0.02]);
    let g = mat([0.3, -0.7, 0.2, 0.5, 0.1, -0.4, -0.6, 0.9, 0.25]);
    for law in [&elastic() as &dyn ConstitutiveLaw, &quadratic(), &relax_law()] {
        let r = consistency(law, &df, &be_n, &g);
        assert!(r < TOL, "{}: rel {r}", law.name());
    }
    // From the undeformed state: b^e_n = I and ΔF = I (all eigenvalues repeated).
    let r = consistency(&elastic(), &Matrix3::identity(), &Matrix3::identity(), &g);
    assert!(r < TOL, "identity: rel {r}");
    // Pure rotation of a pre-stressed state (repeated trial eigenvalues: uniaxial b_n).
    let be_n = Matrix3::from_diagonal(&Vector3::new(1.2, 1.0, 1.0));
    let r = consistency(&elastic(), &rot([0.2, 0.4, -0.3]), &be_n, &g);
    assert!(r < TOL, "rotation: rel {r}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(128))]

    #[test]
    fn consistency_near_identity(
        d in prop::array::uniform9(-0.15f64..0.15),
        a in prop::array::uniform3(-3.0f64..3.0),
        e in prop::array::uniform3(-0.3f64..0.3),
        g in prop::array::uniform9(-1.0f64..1.0),
    ) {
        let df = Matrix3::identity() + mat(d);
        let be_n = be_from(a, e);
        let g = mat(g);
        for law in [&elastic() as &dyn ConstitutiveLaw, &quadratic(), &relax_law()] {
            let r = consistency(law, &df, &be_n, &g);
            prop_assert!(r < TOL, "{}: rel {}", law.name(), r);
        }
    }

    #[test]
    fn consistency_large_stretch(
        r1 in prop::array::uniform3(-3.0f64..3.0),
        r2 in prop::array::uniform3(-3.0f64..3.0),
        s in prop::array::uniform3(0.5f64..2.0),
        a in prop::array::uniform3(-3.0f64..3.0),
        e in prop::array::uniform3(-0.3f64..0.3),
        g in prop::array::uniform9(-1.0f64..1.0),
    ) {
        let df = rot(r1) * Matrix3::from_diagonal(&Vector3::from(s)) * rot(r2).transpose();
        let be_n = be_from(a, e);
        let g = mat(g);
        for law in [&elastic() as &dyn ConstitutiveLaw, &quadratic(), &relax_law()] {
            let r = consistency(law, &df, &be_n, &g);
            prop_assert!(r < TOL, "{}: rel {}", law.name(), r);
        }
    }

    #[test]
    fn consistency_plane_strain(
        d in prop::array::uniform4(-0.3f64..0.3),
        ang in -3.0f64..3.0,
        e in prop::array::uniform3(-0.3f64..0.3),
        g in prop::array::uniform4(-1.0f64..1.0),
    ) {
        let df = mat([1.0 + d[0], d[1], 0.0, d[2], 1.0 + d[3], 0.0, 0.0, 0.0, 1.0]);
        let be_n = be_from([0.0, 0.0, ang], e);
        let g = mat([g[0], g[1], 0.0, g[2], g[3], 0.0, 0.0, 0.0, 0.0]);
        for law in [&elastic() as &dyn ConstitutiveLaw, &quadratic()] {
            let r = consistency(law, &df, &be_n, &g);
            prop_assert!(r < TOL, "{}: rel {}", law.name(), r);
            let up = finite_strain_update(law, &df, &be_n, df.determinant() * be_n.determinant().sqrt(), &[], &mut []).unwrap();
            // Plane strain: no in-plane/out-of-plane shear appears (round-off only).
            let sc = up.kirchhoff.norm();
            prop_assert!(up.kirchhoff[(0, 2)].abs() < 1e-12 * sc && up.kirchhoff[(1, 2)].abs() < 1e-12 * sc);
        }
    }

    /// Hyperelastic (Hencky) law: a_ijkl = (1/J) F_jJ F_lL ∂P_iJ/∂F_kL inherits the major
    /// symmetry of ∂P/∂F = ∂²W/∂F∂F.
    #[test]
    fn elastic_spatial_tangent_major_symmetric(
        d in prop::array::uniform9(-0.3f64..0.3),
        a in prop::array::uniform3(-3.0f64..3.0),
        e in prop::array::uniform3(-0.3f64..0.3),
    ) {
        let df = Matrix3::identity() + mat(d);
        prop_assume!(df.determinant() > 0.2);
        let be_n = be_from(a, e);
        let j = df.determinant() * be_n.determinant().sqrt();
        let up = finite_strain_update(&elastic(), &df, &be_n, j, &[], &mut []).unwrap();
        let t = &up.spatial_tangent;
        prop_assert!((t - t.transpose()).norm() < 1e-10 * t.norm());
    }

    /// (1/2J) D:L:B for isotropic D (coaxial with b_tr) is major-symmetric on symmetric
    /// arguments: h:(DLB):g = 2λ tr h tr g + 2μ Σ_AB θ_AB (λ_A+λ_B) h_AB g_AB in the
    /// eigenbasis of b_tr. It is not major-symmetric on skew arguments: DLB:W ≠ 0 (a spin
    /// rotates the pre-stress) while W:DLB = 0 by the minor symmetry of D.
    #[test]
    fn dlb_major_symmetric_on_symmetric_arguments(
        a in prop::array::uniform3(-3.0f64..3.0),
        e in prop::array::uniform3(-0.5f64..0.5),
    ) {
        let b = be_from(a, e);
        let dlb = elastic().stiffness() * log_derivative(&b).unwrap() * b_operator(&b);
        let p = sym_identity();
        let s = p * dlb * p;
        prop_assert!((s - s.transpose()).norm() < 1e-10 * s.norm());
    }
}

#[test]
fn dlb_not_major_symmetric_on_skew_arguments_when_strained() {
    let b = be_from([0.1, 0.2, 0.3], [0.2, -0.1, 0.05]);
    let dlb = elastic().stiffness() * log_derivative(&b).unwrap() * b_operator(&b);
    assert!((dlb - dlb.transpose()).norm() > 1e-3 * dlb.norm());
    // At b = I, L:B = 2 I^s and DLB = 2D is fully major-symmetric.
    let i = Matrix3::identity();
    let dlb = elastic().stiffness() * log_derivative(&i).unwrap() * b_operator(&i);
    assert!((dlb - elastic().stiffness() * 2.0).norm() < 1e-12 * dlb.norm());
}

// ---------------------------------------------------------------- closed forms

#[test]
fn hencky_uniaxial_closed_form() {
    let young = 1000.0;
    let law = Elastic::new(young, 0.0).unwrap();
    for stretch in [0.5, 0.8, 1.0, 1.3, 2.0] {
        let df = Matrix3::from_diagonal(&Vector3::new(1.0, stretch, 1.0));
        let up = finite_strain_update(&law, &df, &Matrix3::identity(), stretch, &[], &mut []).unwrap();
        let expect = young * f64::ln(stretch) / stretch;
        // Closed form σ_yy = E ln λ / λ; only round-off in ln and the decomposition.
        assert!((up.cauchy[(1, 1)] - expect).abs() < 1e-12 * young, "λ {stretch}");
        assert!(up.cauchy[(0, 0)].abs() < 1e-12 * young && up.cauchy[(2, 2)].abs() < 1e-12 * young);
        assert!((up.be - df * df).norm() < 1e-14 * 4.0);
    }
}

#[test]
fn rigid_rotation_rotates_state() {
    let law = elastic();
    let be_n = be_from([0.4, -0.2, 0.7], [0.1, -0.05, 0.2]);
    let jn = be_n.determinant().sqrt();
    let before = finite_strain_update(&law, &Matrix3::identity(), &be_n, jn, &[], &mut []).unwrap();
    let r = rot([0.9, -1.3, 0.4]);
    let after = finite_strain_update(&law, &r, &be_n, jn, &[], &mut []).unwrap();
    let scale = before.kirchhoff.norm();
    assert!((after.kirchhoff - r * before.kirchhoff * r.transpose()).norm() < 1e-12 * scale);
    assert!((after.be - r * be_n * r.transpose()).norm() < 1e-13);
    // Tangent is objective: a'_ijkl = R_ip R_jq R_kr R_ls a_pqrs.
    let q = r.kronecker(&r);
    let rotated: Tensor4 = q * before.spatial_tangent * q.transpose();
    assert!((after.spatial_tangent - rotated).norm() < 1e-11 * rotated.norm());

    // From a stress-free state, a rotation produces no stress.
    let up = finite_strain_update(&law, &r, &Matrix3::identity(), 1.0, &[], &mut []).unwrap();
    assert!(up.kirchhoff.norm() < 1e-12 * law.young);
    assert!((up.be - Matrix3::identity()).norm() < 1e-14);
}

#[test]
fn identity_step_keeps_state_and_gives_small_strain_tangent() {
    let law = elastic();
    let up = finite_strain_update(&law, &Matrix3::identity(), &Matrix3::identity(), 1.0, &[], &mut []).unwrap();
    assert_eq!(up.kirchhoff, Matrix3::zeros());
    assert!(up.spatial_tangent.iter().all(|v| v.is_finite()));
    // At zero strain, a = D:I^s ... acting as D on sym(g): (1/2)·D·2I^s = D.
    assert!((up.spatial_tangent - law.stiffness()).norm() < 1e-12 * law.young);
}

#[test]
fn relax_law_updates_be_and_history() {
    let law = relax_law();
    let df = mat([1.1, 0.05, 0.0, -0.02, 0.95, 0.03, 0.01, 0.0, 1.02]);
    let be_n = be_from([0.2, 0.1, -0.4], [0.03, 0.0, -0.02]);
    let j = df.determinant() * be_n.determinant().sqrt();
    let mut h = [0.0];
    let up = finite_strain_update(&law, &df, &be_n, j, &[0.5], &mut h).unwrap();
    assert!(h[0] > 0.5);
    let b_tr = df * be_n * df.transpose();
    let eps_tr = loam_constitutive::tensor::sym_log(&b_tr).unwrap() * 0.5;
    let ee = law.update(&eps_tr, &[0.0], &mut [0.0]).unwrap().elastic_strain;
    assert!((up.be - sym_exp(&(ee * 2.0)).unwrap()).norm() < 1e-13);
    // Wrong history length is an error, not a panic.
    assert!(matches!(
        finite_strain_update(&law, &df, &be_n, j, &[], &mut []),
        Err(ConstitutiveError::HistoryLength { .. })
    ));
}

#[test]
fn finite_strain_errors() {
    let law = elastic();
    let i = Matrix3::identity();
    assert!(matches!(
        finite_strain_update(&law, &i, &i, 0.0, &[], &mut []),
        Err(ConstitutiveError::NonPositiveJacobian { .. })
    ));
    assert!(matches!(
        finite_strain_update(&law, &i, &i, -1.0, &[], &mut []),
        Err(ConstitutiveError::NonPositiveJacobian { .. })
    ));
    let inverted = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
    assert!(matches!(
        finite_strain_update(&law, &inverted, &i, 1.0, &[], &mut []),
        Err(ConstitutiveError::NonPositiveJacobian { .. })
    ));
    let mut nan = i;
    nan[(0, 1)] = f64::NAN;
    assert!(matches!(
        finite_strain_update(&law, &nan, &i, 1.0, &[], &mut []),
        Err(ConstitutiveError::NonFinite { .. })
    ));
    assert!(matches!(
        finite_strain_update(&law, &i, &nan, 1.0, &[], &mut []),
        Err(ConstitutiveError::NonFinite { .. })
    ));
    assert!(matches!(
        finite_strain_update(&law, &i, &i, f64::INFINITY, &[], &mut []),
        Err(ConstitutiveError::NonFinite { .. })
    ));
    let not_pd = Matrix3::from_diagonal(&Vector3::new(1.0, -0.5, 1.0));
    assert!(matches!(
        finite_strain_update(&law, &i, &not_pd, 1.0, &[], &mut []),
        Err(ConstitutiveError::NotPositiveDefinite { .. })
    ));
}

// ---------------------------------------------------------------- small strain

#[test]
fn small_strain_driver() {
    let law = Elastic::new(200.0, 0.25).unwrap();
    let (lambda, mu) = law.lame();
    let eps_n = mat([1e-4, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]);
    // Non-symmetric gradient: only its symmetric part strains the material.
    let grad = mat([0.0, 2e-4, 0.0, 0.0, 1e-3, 0.0, 0.0, 0.0, 0.0]);
    let up = small_strain_update(&law, &grad, &eps_n, &[], &mut []).unwrap();
    let eps = mat([1e-4, 1e-4, 0.0, 1e-4, 1e-3, 0.0, 0.0, 0.0, 0.0]);
    assert!((up.elastic_strain - eps).norm() < 1e-18);
    assert!((up.stress[(1, 1)] - ((lambda + 2.0 * mu) * 1e-3 + lambda * 1e-4)).abs() < 1e-14);
    assert!((up.stress[(0, 1)] - 2.0 * mu * 1e-4).abs() < 1e-14);
    let mut bad = grad;
    bad[(2, 2)] = f64::NAN;
    assert!(small_strain_update(&law, &bad, &eps_n, &[], &mut []).is_err());
    assert!(matches!(
        small_strain_update(&relax_law(), &grad, &eps_n, &[], &mut []),
        Err(ConstitutiveError::HistoryLength { .. })
    ));
}
