//! The state the outputs read from a law: the accumulated plastic strain and the yield
//! flag. Driven by simple shear past the yield point, each plastic law reports a positive
//! plastic strain (its own history value) and a yielding stress; an elastic state inside
//! the surface reports neither; the elastic law reports no plasticity at all.

use loam_constitutive::{ConstitutiveLaw, Elastic, MohrCoulomb, VonMises};
use nalgebra::Matrix3;

/// Simple shear γ in the xy plane plus a confining volumetric strain (compression).
fn shear(gamma: f64, confining: f64) -> Matrix3<f64> {
    let mut e = Matrix3::identity() * (-confining);
    e[(0, 1)] = 0.5 * gamma;
    e[(1, 0)] = 0.5 * gamma;
    e
}

#[test]
fn plastic_laws_report_their_plastic_strain_and_yielding() {
    let elastic = Elastic::new(1e4, 0.3).unwrap();
    let laws: Vec<Box<dyn ConstitutiveLaw>> = vec![
        Box::new(VonMises::new(elastic, 20.0, 0.0).unwrap()),
        Box::new(MohrCoulomb::from_degrees(elastic, 5.0, 30.0, 10.0).unwrap()),
    ];
    for law in &laws {
        assert_eq!(law.history_names().len(), law.history_len(), "{}", law.name());
        let h0 = vec![0.0; law.history_len()];
        let mut h = vec![0.0; law.history_len()];
        // Far past yield: plastic, on the surface.
        let plastic = law.update(&shear(0.05, 1e-3), &h0, &mut h).unwrap();
        assert!(law.plastic_strain(&h) > 0.0, "{}: plastic strain {}", law.name(), law.plastic_strain(&h));
        assert_eq!(law.plastic_strain(&h), h[0]);
        assert!(law.is_yielding(&plastic.stress, &h), "{}: not yielding after a plastic step", law.name());
        // A tenth of the way there: elastic, inside.
        let mut h_el = vec![0.0; law.history_len()];
        let inside = law.update(&shear(1e-5, 1e-3), &h0, &mut h_el).unwrap();
        assert_eq!(law.plastic_strain(&h_el), 0.0, "{}", law.name());
        assert!(!law.is_yielding(&inside.stress, &h_el), "{}: yielding inside the surface", law.name());
    }
    let mut none = [];
    let update = elastic.update(&shear(0.05, 0.0), &[], &mut none).unwrap();
    assert!(!elastic.is_yielding(&update.stress, &[]) && elastic.plastic_strain(&[]) == 0.0);
    assert!(elastic.history_names().is_empty());
}
