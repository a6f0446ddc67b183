//! Benchmarks of the implicit MPM (criterion; `cargo xtask bench`).
//!
//! - `v1c_column_64_cells_40_steps`: the V1c column, GIMP, 64 cells high, 2x2 points per
//!   cell, 40 load steps, from model construction to the last step (issue target ≤ 50 ms;
//!   the AMPLE peer takes about 90 s on that size); and the same column read as a cylinder
//!   (`_axisymmetric`, docs/theory.md §20), the hoop terms' cost beside it.
//! - `block_256_one_iteration`: a 256 × 256-cell elastic block, 2x2 points per cell, under
//!   gravity: one Newton iteration (point update + residual + assembly + symbolic and
//!   numeric factorisation + solve), target ≤ 2 s. The phase split is printed first.

use criterion::{criterion_group, criterion_main, Criterion};
use loam::grid::BasisKind;
use loam::implicit::{Kinematics, QuasiStatic, QuasiStaticSettings};
use loam_verification::{column_model, elastic_block, Column};
use std::hint::black_box;

fn column(c: &mut Criterion) {
    for (name, axisymmetric) in
        [("v1c_column_64_cells_40_steps", false), ("v1c_column_64_cells_40_steps_axisymmetric", true)]
    {
        let col = Column::V1C;
        c.bench_function(name, |b| {
            b.iter(|| {
                let mut m =
                    column_model::<2>(&col, col.height / 64.0, 64, 2, BasisKind::Gimp, Kinematics::FiniteStrain);
                if axisymmetric {
                    m = m.with_axisymmetry().expect("a 2D column on the axis");
                }
                let mut qs = QuasiStatic::new(m, QuasiStaticSettings { load_steps: 40, ..Default::default() });
                while !qs.is_finished() {
                    black_box(qs.step().unwrap());
                }
                qs
            })
        });
    }
}

fn block(n: usize) -> QuasiStatic<2> {
    let m = elastic_block::<2>(n, Kinematics::FiniteStrain, true);
    QuasiStatic::new(m, QuasiStaticSettings { load_steps: 1, ..Default::default() })
}

fn block_iteration(c: &mut Criterion) {
    let n = 256;
    let mut qs = block(n);
    let p = qs.profile_iteration().unwrap();
    println!(
        "block {n}x{n}, {} points, {} dofs, {} nonzeros, {} threads: connectivity {:.3} s | points+residual {:.3} s | assembly {:.3} s | symbolic {:.3} s | numeric {:.3} s | solve {:.3} s | one iteration {:.3} s",
        qs.model().points().len(), p.dofs, p.nonzeros, rayon::current_num_threads(),
        p.connectivity.as_secs_f64(), p.points_and_residual.as_secs_f64(), p.assembly.as_secs_f64(),
        p.symbolic.as_secs_f64(), p.numeric.as_secs_f64(), p.solve.as_secs_f64(), p.iteration().as_secs_f64()
    );
    let mut g = c.benchmark_group("block");
    g.sample_size(10);
    g.bench_function("block_256_one_iteration", |b| b.iter(|| black_box(qs.profile_iteration().unwrap())));
    g.finish();
}

criterion_group!(benches, column, block_iteration);
criterion_main!(benches);
