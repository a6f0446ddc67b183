//! The laws' integration tests in one binary (one link instead of five): element tests
//! against closed forms, and property tests of the return maps and their tangents.

mod cam_clay;
mod drucker_prager;
mod finite_strain;
mod plasticity;
mod state_outputs;
