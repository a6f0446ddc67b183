//! The verification problems of loam in one place: for every case its closed-form (or
//! published) reference, the model that runs it, the error norm that measures a run and the
//! bounds the run must meet. `cargo xtask verify`, the root tests, the explicit tests, the
//! benches and the examples all take their fixtures and reference numbers from here, so
//! every consumer measures the same thing the same way and no two copies can drift apart.
//!
//! The cases (described with their sources in `docs/verification.md`):
//! - [`column`](mod@column): V1, the self-weight column (small and large deformation),
//!   and the layered column of the stiffness-contrast hard case;
//! - [`bar`]: V2, the axially vibrating bar;
//! - [`footing`]: V3, the rigid strip footing against Prandtl;
//! - [`slope`]: V4, slopes against Taylor's chart and Griffiths & Lane;
//! - [`disks`]: V5, two colliding elastic disks;
//! - [`cylinder`]: V6, the thick-walled cylinder under internal pressure (Lamé);
//! - [`sphere`], [`cavity`](mod@cavity): V6 posed axisymmetrically, the thick sphere and
//!   a spherical cavity expanded from a small radius;
//! - [`water`]: V7, columns under a water table and submerged;
//! - [`granular`]: V8, the collapse of a granular column (explicit);
//! - [`sliding`]: V9, a block on a frictional incline (explicit and implicit);
//! - [`hard_cases`]: where implicit MPM usually breaks (softening, small cuts, ...).
//!
//! Shared tools: [`block`] (the elastic block that sizes the solvers), [`dynamics`] (time histories and the periods measured from them),
//! [`conditioning`] (condition numbers of small tangents), [`bound`] (what a bound is).
//!
//! Not published: it exists for loam's own verification, and its builders `expect` valid
//! input rather than returning errors.

pub mod bar;
pub mod block;
pub mod bound;
pub mod cam_clay;
pub mod cavity;
pub mod column;
pub mod conditioning;
pub mod cylinder;
pub mod disks;
pub mod dynamics;
pub mod footing;
pub mod granular;
pub mod hard_cases;
pub mod sliding;
pub mod slope;
pub mod sphere;
pub mod wall;
pub mod water;

pub use bar::{BarErrors, VibratingBar};
pub use block::{cut_block, elastic_block, layered_block};
pub use bound::{Bound, BoundKind};
pub use column::{
    column_errors, column_fem_model, column_model, column_model_with_spare_cells, column_stress_error, lambert_w0,
    Column, ColumnErrors, LayeredColumn,
};
pub use conditioning::condition_number;
pub use cylinder::{Cylinder, CylinderErrors};
pub use disks::{disks_model, disks_model_with, inscribed_polygon, polygon_area_ratio, DiskOutline};
pub use dynamics::{centre_of_mass_velocity, period_from_crossings, zero_crossings, DynamicRecord};
pub use footing::{circular_footing_model, finite_strain_footing_model, footing_load_model, footing_model, prandtl_nc};
pub use hard_cases::{softening_specimen, translated_block};
pub use slope::{slope_model, slope_model_with, SlopeGeometry};
pub use sphere::ThickSphere;
pub use water::{WaterColumn, WaterColumnErrors};
