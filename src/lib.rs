//! loam: an implicit material point method for geotechnics.
//!
//! This facade re-exports the layered crates so that a user can depend on one crate:
//! - [`grid`]: the background (Cartesian grid or body-fitted mesh), basis functions,
//!   connectivity, the band scatter of points to nodes;
//! - [`points`]: the material point store and its generation;
//! - [`constitutive`]: constitutive laws and the small/finite strain updates;
//! - [`solve`]: sparse assembly, linear solvers, Newton's control;
//! - [`model`]: what a run is made of (background, points, materials, constraints, loads);
//! - [`kernels`]: the point–node stages every analysis shares;
//! - [`implicit`]: quasi-static and Newmark-dynamic implicit analysis;
//! - [`explicit`]: explicit MPM (USF, USL, MUSL) for comparison;
//! - [`analysis`]: one stepping interface over the three analyses, and the
//!   strength-reduction search for a factor of safety;
//! - [`format`]: the file formats: VTU/PVD/CSV outputs, plots, the checkpoint container;
//! - [`scene`]: scene files: their schema, validation and the model and analysis they build;
//! - [`run`]: the runner of a scene with its outputs, checkpoint and restart.
//!
//! The verification problems (closed forms, fixtures, norms, bounds) are not part of the
//! facade: they live in the unpublished `loam-verification` crate, which the tests, the
//! benches, the examples and `cargo xtask verify` use.

pub use loam_analysis as analysis;
pub use loam_constitutive as constitutive;
pub use loam_explicit as explicit;
pub use loam_format as format;
pub use loam_grid as grid;
pub use loam_implicit as implicit;
pub use loam_kernels as kernels;
pub use loam_model as model;
pub use loam_points as points;
pub use loam_run as run;
pub use loam_scene as scene;
pub use loam_solve as solve;
