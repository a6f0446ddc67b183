//! Drucker–Prager against independent references (docs/theory.md §16): the consistent
//! tangent against central differences of the stress update at random states in every
//! region, with and without softening, in every cone fit; consistency after return; the
//! symmetric tangent of associated flow; rotation invariance.
//!
//! Tolerances: `FD_TOL` = 1e-6 relative (docs/theory.md §16, as for the other laws);
//! consistency f ≤ 1e-10 of the stress scale.

use loam_constitutive::tensor::{central_difference, Tensor4};
use loam_constitutive::{ConeFit, ConstitutiveLaw, DruckerPrager, DruckerPragerRegion, Elastic};
use nalgebra::{Matrix3, Rotation3, Vector3};
use proptest::prelude::*;
use proptest::strategy::ValueTree;

const FD_TOL: f64 = 1e-6;

fn el() -> Elastic {
    Elastic::new(1.0e4, 0.3).unwrap()
}

/// The laws the properties range over: associated and not, each fit, φ = 0, softening of
/// c alone and of c, φ, ψ together; each with its κ_res where it softens (the residual
/// branch starts there: a kink of the stress).
fn laws() -> Vec<(DruckerPrager, Option<f64>)> {
    let fits = [ConeFit::PlaneStrain, ConeFit::Compression, ConeFit::Extension];
    let mut out = Vec::new();
    for fit in fits {
        out.push((DruckerPrager::from_degrees(el(), 10.0, 30.0, 30.0, fit).unwrap(), None));
        out.push((DruckerPrager::from_degrees(el(), 10.0, 30.0, 0.0, fit).unwrap(), None));
        out.push((DruckerPrager::from_degrees(el(), 5.0, 20.0, 10.0, fit).unwrap(), None));
        let soft = DruckerPrager::from_degrees(el(), 10.0, 35.0, 15.0, fit).unwrap();
        out.push((soft.with_softening(2.0, 25.0, 5.0, 0.02).unwrap(), Some(0.02)));
        out.push((soft.with_softening(3.0, 35.0, 15.0, 0.01).unwrap(), Some(0.01)));
    }
    let tresca = DruckerPrager::from_degrees(el(), 10.0, 0.0, 0.0, ConeFit::PlaneStrain).unwrap();
    out.push((tresca, None));
    out.push((tresca.with_softening(4.0, 0.0, 0.0, 0.05).unwrap(), Some(0.05)));
    out
}

fn rot(r: [f64; 3]) -> Matrix3<f64> {
    Rotation3::from_scaled_axis(Vector3::from(r)).into_inner()
}

fn strain(e: [f64; 3], r: [f64; 3]) -> Matrix3<f64> {
    let q = rot(r);
    q * Matrix3::from_diagonal(&Vector3::from(e)) * q.transpose()
}

/// The region an update ends in and whether κ ended on the residual branch: a central
/// difference is a derivative only where every probe lands on the same side of both.
fn side(law: &DruckerPrager, kink: Option<f64>, eps: &Matrix3<f64>, h_n: &[f64]) -> (DruckerPragerRegion, bool) {
    let mut h = [0.0, 0.0];
    let (_, region) = law.update_with_region(eps, h_n, &mut h).unwrap();
    (region, kink.is_some_and(|k| h[0] >= k))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    /// The consistent tangent equals central differences of the stress (step 1e-6 ‖ε‖,
    /// truncation ~1e-12, round-off ~1e-10 relative) to FD_TOL at 1 000 random states,
    /// unless a probe crosses a region boundary or the softening's kink (then the stress
    /// has no derivative there; such states are skipped, and are rare: they lie within
    /// 1e-6 ‖ε‖ of a boundary). After a return the state is on the yield surface.
    #[test]
    fn tangent_matches_central_differences(
        law_index in 0usize..17,
        e in prop::array::uniform3(-3e-2f64..1.5e-2),
        r in prop::array::uniform3(-3.0f64..3.0),
        kappa_n in 0.0f64..0.04,
    ) {
        let (law, kink) = laws()[law_index];
        let eps = strain(e, r);
        let h_n = [kappa_n, 0.0];
        let mut h_out = [0.0, 0.0];
        let (up, region) = law.update_with_region(&eps, &h_n, &mut h_out).unwrap();
        let step = 1e-6 * eps.norm();
        let fd = central_difference(|x| law.update(x, &h_n, &mut [0.0, 0.0]).unwrap().stress, &eps, step);
        let reference = if up.tangent.norm() > 1e-8 * el().stiffness().norm() { up.tangent.norm() } else { el().stiffness().norm() };
        let err = (up.tangent - fd).norm() / reference;
        if err > FD_TOL {
            // Only a kink between the probes excuses a difference.
            let here = side(&law, kink, &eps, &h_n);
            let crossed = loam_constitutive::tensor::symmetric_unit_directions()
                .flat_map(|(_, _, d)| [eps + d * step, eps - d * step])
                .any(|x| side(&law, kink, &x, &h_n) != here);
            prop_assert!(crossed, "{law:?} {region:?}: tangent error {err:e}");
        }
        if region == DruckerPragerRegion::Cone {
            let f = law.yield_function(&up.stress, h_out[0]);
            prop_assert!(f.abs() <= 1e-10 * up.stress.norm().max(10.0), "f = {f:e}");
        }
    }

    /// Rotating the strain rotates the stress and the tangent (isotropy), to round-off.
    #[test]
    fn rotation_invariance(
        law_index in 0usize..17,
        e in prop::array::uniform3(-3e-2f64..1.5e-2),
        r in prop::array::uniform3(-3.0f64..3.0),
        q in prop::array::uniform3(-3.0f64..3.0),
    ) {
        let (law, _) = laws()[law_index];
        let eps = strain(e, r);
        let q = rot(q);
        let a = law.update(&eps, &[0.0, 0.0], &mut [0.0, 0.0]).unwrap();
        let b = law.update(&(q * eps * q.transpose()), &[0.0, 0.0], &mut [0.0, 0.0]).unwrap();
        let scale = a.stress.norm().max(1.0);
        prop_assert!((q * a.stress * q.transpose() - b.stress).norm() <= 1e-9 * scale);
        let qq = q.kronecker(&q);
        let rotated: Tensor4 = qq * a.tangent * qq.transpose();
        prop_assert!((rotated - b.tangent).norm() <= 1e-9 * el().stiffness().norm());
    }
}

/// Associated flow without softening gives a symmetric tangent on the cone; non-associated
/// flow does not (η̄ ≠ η).
#[test]
fn associated_tangent_is_symmetric() {
    let eps = strain([-2e-2, 4e-3, -1e-3], [0.3, -0.2, 1.0]);
    for (psi, symmetric) in [(30.0, true), (5.0, false)] {
        let law = DruckerPrager::from_degrees(el(), 10.0, 30.0, psi, ConeFit::PlaneStrain).unwrap();
        assert_eq!(law.symmetric_tangent(), symmetric);
        let (up, region) = law.update_with_region(&eps, &[0.0, 0.0], &mut [0.0, 0.0]).unwrap();
        assert_eq!(region, DruckerPragerRegion::Cone);
        let asym = (up.tangent - up.tangent.transpose()).norm() / up.tangent.norm();
        assert_eq!(asym < 1e-12, symmetric, "ψ {psi}: asymmetry {asym:e}");
    }
}

/// The random states of the tangent property visit all three regions with every law
/// family (a property that never reached the apex would prove nothing about it).
#[test]
fn the_random_states_reach_every_region() {
    let mut seen = std::collections::BTreeSet::new();
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let strat = (0usize..17, prop::array::uniform3(-3e-2f64..1.5e-2), prop::array::uniform3(-3.0f64..3.0));
    for _ in 0..1000 {
        let (i, e, r) = strat.new_tree(&mut runner).unwrap().current();
        let (_, region) = laws()[i].0.update_with_region(&strain(e, r), &[0.0, 0.0], &mut [0.0, 0.0]).unwrap();
        seen.insert(format!("{region:?}"));
    }
    assert_eq!(seen.len(), 3, "{seen:?}");
}
