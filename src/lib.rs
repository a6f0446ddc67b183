//! loam: an implicit material point method for geotechnics.
//!
//! This facade re-exports the layered crates so that a user can depend on one crate:
//! - [`grid`]: background grid, linear and GIMP basis functions, connectivity;
//! - [`points`]: the material point store and its generation;
//! - [`constitutive`]: constitutive laws and the small/finite strain updates;
//! - [`solve`]: sparse assembly, linear solvers, Newton's method;
//! - [`model`]: what a run is made of (grid, points, materials, constraints, loads);
//! - [`implicit`]: quasi-static and Newmark-dynamic implicit analysis;
//! - [`explicit`]: explicit MPM (USF, USL, MUSL) for comparison;
//! - [`io`]: scenes, output writers.
//!
//! The verification problems (closed forms, fixtures, norms, bounds) are not part of the
//! facade: they live in the unpublished `loam-verification` crate, which the tests, the
//! benches, the examples and `cargo xtask verify` use.

pub use loam_constitutive as constitutive;
pub use loam_explicit as explicit;
pub use loam_grid as grid;
pub use loam_implicit as implicit;
pub use loam_io as io;
pub use loam_model as model;
pub use loam_points as points;
pub use loam_solve as solve;
