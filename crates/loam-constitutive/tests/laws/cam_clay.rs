//! Modified Cam clay's consistent tangent against central differences of the stress
//! update at random states (docs/theory.md §16): normally and over-consolidated, loading
//! and unloading, G constant or following p, wet and dry of critical, M constant or
//! following the Lode angle.
//!
//! Tolerance: `FD_TOL` = 1e-6 relative (docs/theory.md §16, as for the other laws).

use loam_constitutive::tensor::{central_difference, symmetric_unit_directions};
use loam_constitutive::{CamClayInitial, CamClayShear, ConstitutiveLaw, ModifiedCamClay};
use nalgebra::{Matrix3, Rotation3, Vector3};
use proptest::prelude::*;

const FD_TOL: f64 = 1e-6;

fn law(ocr: f64, constant_shear: bool, lode: bool) -> ModifiedCamClay {
    let shear = if constant_shear { CamClayShear::Modulus(2000.0) } else { CamClayShear::Poisson(0.3) };
    let law = ModifiedCamClay::new(0.25, 0.05, 1.2, 1.1, shear, CamClayInitial::OverConsolidation(ocr)).unwrap();
    if lode {
        law.with_lode_dependence().unwrap()
    } else {
        law
    }
}

/// Whether an update from `eps` flows (its history changes).
fn flows(law: &ModifiedCamClay, eps: &Matrix3<f64>, h: &[f64]) -> bool {
    let mut out = [0.0; 3];
    law.update(eps, h, &mut out).unwrap();
    out[0] != h[0] || out[1] != h[1]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    /// The tangent equals central differences (step 1e-6 ‖ε‖: truncation ~1e-12, round-off
    /// ~1e-10 relative) to FD_TOL at 1 000 random states, unless a probe crosses the
    /// elastic–plastic boundary (no derivative there; such states lie within 1e-6 ‖ε‖ of it).
    #[test]
    fn tangent_matches_central_differences(
        p0 in 20.0f64..200.0,
        q_ratio in 0.0f64..0.8,
        ocr in 1.0f64..4.0,
        constant_shear in any::<bool>(),
        lode in any::<bool>(),
        d in prop::array::uniform3(-2e-2f64..2e-2),
        r in prop::array::uniform3(-3.0f64..3.0),
    ) {
        let law = law(ocr, constant_shear, lode);
        // A triaxial initial stress inside (OCR > 1) or on (OCR = 1) the surface.
        let sigma0 = Matrix3::from_diagonal(&Vector3::new(-p0 + q_ratio * p0 / 3.0, -p0 + q_ratio * p0 / 3.0, -p0 - 2.0 * q_ratio * p0 / 3.0));
        let mut h = [0.0; 3];
        law.init_history(&mut h, &sigma0);
        let e0 = law.elastic_strain_of(&sigma0, &h).unwrap();
        let q = Rotation3::from_scaled_axis(Vector3::from(r)).into_inner();
        let eps = e0 + q * Matrix3::from_diagonal(&Vector3::from(d)) * q.transpose();
        let up = law.update(&eps, &h, &mut [0.0; 3]).unwrap();
        let step = 1e-6 * eps.norm();
        let fd = central_difference(|x| law.update(x, &h, &mut [0.0; 3]).unwrap().stress, &eps, step);
        let err = (up.tangent - fd).norm() / up.tangent.norm();
        if err > FD_TOL {
            let here = flows(&law, &eps, &h);
            let crossed = symmetric_unit_directions()
                .flat_map(|(_, _, e)| [eps + e * step, eps - e * step])
                .any(|x| flows(&law, &x, &h) != here);
            prop_assert!(crossed, "tangent error {err:e}");
        }
        // The initial stress is carried exactly by the elastic strain of `elastic_strain_of`.
        let at_rest = law.update(&e0, &h, &mut [0.0; 3]).unwrap();
        prop_assert!((at_rest.stress - sigma0).norm() <= 1e-10 * p0);
    }
}

/// In finite strain (the exponential-map driver of docs/theory.md §2 around the return),
/// Cam clay's spatial tangent is consistent: J a : g equals the central difference of the
/// Kirchhoff stress along ΔF → (I + s g) ΔF minus τ gᵀ, to 1e-6 relative (step 1e-6), for
/// plastic steps from a normally consolidated state, compressing and shearing, with M
/// constant and Lode-dependent.
#[test]
fn finite_strain_tangent_is_consistent() {
    use loam_constitutive::finite_strain_update;
    use loam_constitutive::tensor::{contract, sym_exp};
    let sigma0 = Matrix3::from_diagonal(&Vector3::new(-80.0, -80.0, -120.0));
    let g = Matrix3::new(0.3, -0.7, 0.2, 0.5, 0.1, -0.4, -0.6, 0.9, 0.25);
    for (lode, df) in [
        (false, Matrix3::new(0.97, 0.04, 0.0, 0.01, 0.99, 0.02, 0.0, 0.03, 0.96)),
        (true, Matrix3::new(0.98, 0.06, 0.01, -0.02, 1.01, 0.0, 0.02, 0.0, 0.97)),
    ] {
        let law = law(1.0, false, lode);
        let mut h = [0.0; 3];
        law.init_history(&mut h, &sigma0);
        let be_n = sym_exp(&(law.elastic_strain_of(&sigma0, &h).unwrap() * 2.0)).unwrap();
        let det_fn = be_n.determinant().sqrt();
        let tau_at = |s: f64| {
            let dfe = (Matrix3::identity() + g * s) * df;
            let j = dfe.determinant() * det_fn;
            finite_strain_update(&law, &dfe, &be_n, j, &h, &mut [0.0; 3]).unwrap()
        };
        let base = tau_at(0.0);
        let mut out = [0.0; 3];
        finite_strain_update(&law, &df, &be_n, df.determinant() * det_fn, &h, &mut out).unwrap();
        assert!(out[0] > 0.0, "the step flows");
        let dtau = (tau_at(1e-6).kirchhoff - tau_at(-1e-6).kirchhoff) / 2e-6;
        let lhs = contract(&base.spatial_tangent, &g) * (df.determinant() * det_fn);
        let rhs = dtau - base.kirchhoff * g.transpose();
        let rel = (lhs - rhs).norm() / rhs.norm();
        assert!(rel < 1e-6, "lode {lode}: rel {rel:e}");
    }
}
