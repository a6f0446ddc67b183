//! The verification program's command line: bad arguments are refused with what is valid.
//!
//! This test also makes `cargo test` build the `xtask` binary (Cargo builds a package's
//! binaries for its integration tests), with the features the test build resolves. CI then
//! runs that binary for `verify --quick` instead of `cargo xtask`, which would resolve the
//! dependencies' features without the dev-dependencies and compile most of the workspace a
//! second time (.ci/run).

use std::process::Command;

fn xtask(args: &[&str]) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_xtask")).args(args).output().expect("running xtask");
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
fn an_unknown_verify_section_is_refused_with_the_sections_that_exist() {
    let (ok, stderr) = xtask(&["verify", "--quick", "--only", "footings"]);
    assert!(!ok);
    assert!(stderr.contains("no verify section \"footings\""), "{stderr}");
    assert!(stderr.contains("columns, dynamics, footing, slope"), "{stderr}");
}

#[test]
fn a_slope_cell_size_that_does_not_divide_the_grid_is_refused() {
    let (ok, stderr) = xtask(&["scale", "--slope", "3"]);
    assert!(!ok);
    assert!(stderr.contains("--slope 3: the cell size must divide the grid's extent [52.0, 12.0, 22.0]"), "{stderr}");
}
