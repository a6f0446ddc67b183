//! The root crate's integration tests, one module per subject, in one test binary: each
//! binary links the whole of loam again, so one binary instead of nine saves most of the
//! link time of `cargo test` and runs every test in one parallel pool. None needs a
//! process of its own (no test sets global state: rayon pools are built per test, outputs
//! go to temporary folders), so there is no reason to split.

mod anti_locking;
mod arc_length;
mod axisymmetric;
mod body_constraint;
mod docs;
mod excavation;
mod frictional_plane;
mod geostatic;
mod ghost;
mod implicit_dynamics;
mod implicit_mpm;
mod inclined;
mod loads;
mod newton_retry;
mod prescribed_displacement;
mod restart;
mod run_scenes;
mod scene_errors;
mod slope;
mod solvers;
mod support;
mod ul_fem;
