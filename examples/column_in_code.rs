//! Build and run the V1c self-weight column in Rust, without a scene file, and compare
//! the result with the closed-form Hencky solution. Units: SI (m, kg, s; Pa, kg/m3, 10 m/s2).
//!
//! cargo run --release --example column_in_code

use loam::grid::BasisKind;
use loam::implicit::{Kinematics, QuasiStatic, QuasiStaticSettings};
use loam_verification::{column_errors, column_model, Column};

fn main() {
    let column = Column::V1C;
    let cells = 32;
    let model =
        column_model::<2>(&column, column.height / cells as f64, cells, 2, BasisKind::Gimp, Kinematics::FiniteStrain);
    let mut analysis = QuasiStatic::new(model, QuasiStaticSettings { load_steps: 40, ..Default::default() });
    while !analysis.is_finished() {
        let r = analysis.step().expect("the column converges");
        if r.step % 10 == 0 {
            println!(
                "step {:3}  load factor {:.3}  Newton iterations {}  residuals {:?}",
                r.step, r.load_factor, r.iterations, r.residuals
            );
        }
    }
    let e = column_errors(analysis.model().points(), &column, 1, |y| column.hencky_displacement(y));
    println!(
        "top settlement {:.4} m (closed form {:.4} m at the top point), stress error e_sigma = {:.2e}",
        e.top_displacement_value,
        column.hencky_displacement(analysis.model().points().position0().iter().map(|x| x[1]).fold(0.0, f64::max)),
        e.stress
    );
}
