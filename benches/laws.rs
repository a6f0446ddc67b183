//! Benchmarks of the constitutive updates (criterion; `cargo xtask bench`): one stress
//! update with its consistent tangent (`update`, what an implicit step calls) and without it
//! (`update_stress`, the explicit step's), per point, over 1 000 trial strains that cross
//! the yield surface — Mohr–Coulomb, Drucker–Prager (plane-strain fit) and Modified Cam
//! clay (normally consolidated at p′ = 100); how many flow is printed first.
//! docs/benchmarks.md quotes the ratios.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use loam::constitutive::{
    CamClayInitial, CamClayShear, ConeFit, ConstitutiveLaw, DruckerPrager, Elastic, ModifiedCamClay, MohrCoulomb,
};
use nalgebra::{Matrix3, Rotation3, Vector3};
use std::hint::black_box;

const STATES: usize = 1000;

/// A benchmark case: its name, the law, the history the trials start from, the trials.
type Case<'a> = (&'static str, &'a dyn ConstitutiveLaw, Vec<f64>, Vec<Matrix3<f64>>);

/// Deterministic trial strains: `base` plus a deviatoric and volumetric increment of up to
/// `size` in a rotating frame (a fixed sequence, no random generator).
fn trials(base: Matrix3<f64>, size: f64) -> Vec<Matrix3<f64>> {
    (0..STATES)
        .map(|k| {
            let t = k as f64;
            let q = Rotation3::from_scaled_axis(Vector3::new(0.7 * t, 1.3 * t, 0.4 * t)).into_inner();
            let d = Vector3::new((0.37 * t).sin(), (0.91 * t).cos(), -(0.53 * t).sin()) * size;
            base + q * Matrix3::from_diagonal(&d) * q.transpose()
        })
        .collect()
}

fn laws(c: &mut Criterion) {
    let el = Elastic::new(1e4, 0.3).unwrap();
    let mc = MohrCoulomb::from_degrees(el, 10.0, 30.0, 5.0).unwrap();
    let dp = DruckerPrager::from_degrees(el, 10.0, 30.0, 5.0, ConeFit::PlaneStrain).unwrap();
    let cc =
        ModifiedCamClay::new(0.2, 0.04, 1.5, 1.0, CamClayShear::Poisson(0.25), CamClayInitial::OverConsolidation(1.0))
            .unwrap();
    let sigma0 = Matrix3::identity() * -100.0;
    let mut h_cc = vec![0.0; 3];
    cc.init_history(&mut h_cc, &sigma0);
    let e_cc = cc.elastic_strain_of(&sigma0, &h_cc).unwrap();
    let e_frictional = el.strain(&sigma0);
    let cases: [Case; 3] = [
        ("mohr_coulomb", &mc, vec![0.0; 2], trials(e_frictional, 1e-2)),
        ("drucker_prager", &dp, vec![0.0; 2], trials(e_frictional, 1e-2)),
        ("modified_cam_clay", &cc, h_cc, trials(e_cc, 1e-2)),
    ];
    let mut group = c.benchmark_group("law_update");
    group.throughput(Throughput::Elements(STATES as u64));
    for (name, law, h, strains) in &cases {
        let mut out = vec![0.0; h.len()];
        let plastic = strains.iter().filter(|e| {
            law.update(e, h, &mut out).unwrap();
            out[0] != h[0]
        });
        println!("{name}: {} of {STATES} trial states flow", plastic.count());
        group.bench_function(format!("{name}_with_tangent"), |b| {
            b.iter(|| strains.iter().map(|e| law.update(e, h, &mut out).unwrap().tangent[(0, 0)]).sum::<f64>())
        });
        group.bench_function(format!("{name}_stress_only"), |b| {
            b.iter(|| {
                strains.iter().map(|e| law.update_stress(black_box(e), h, &mut out).unwrap().0[(0, 0)]).sum::<f64>()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, laws);
criterion_main!(benches);
