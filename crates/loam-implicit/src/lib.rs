//! Implicit MPM analyses over the grid, points, constitutive and solver crates, after the
//! seed paper (Wang et al. 2016) with the finite-strain extension of docs/theory.md §2:
//!
//! - [`QuasiStatic`]: loads applied in steps, Newton per step, automatic cut-back
//!   ([`CutBack`], also the strength steps of `loam_analysis::StrengthReduction`);
//! - [`Dynamic`]: Newmark / Bossak time stepping with Newton per step.
//!
//! Each analysis's step is one driver over named stages (docs/theory.md §1): connect the
//! committed points to the background (`engine`), external forces, Newton — update points
//! (`points`), residual (`residual`), assemble (`tangent`), solve, check — and commit;
//! cut-back (`cutback`) wraps the attempts. Cell averages (`cell_average`), F-bar
//! (`fbar`), the ghost penalty (`ghost`) and inertia (`inertia`) enter the residual and
//! tangent where a model asks for them.

mod arc_length;
mod cell_average;
mod cutback;
mod dynamic;
mod engine;
mod fbar;
mod follower;
mod frames;
mod ghost;
mod inertia;
mod points;
mod quasi_static;
mod report;
mod residual;
mod slivers;
mod tangent;

pub use arc_length::{ArcLengthSettings, ArcLengthState, Peak};
pub use cutback::{CutBack, StepScale};
pub use dynamic::{Dynamic, DynamicSettings, DynamicState, MassMatrix};
pub use loam_kernels::{ConnectError, InvalidSetting, RunError};
pub use loam_model::{AntiLocking, Kinematics, Model, ModelError, PlaneConstraint};
pub use points::PointUpdateError;
pub use quasi_static::{LoadControl, QuasiStatic, QuasiStaticSettings, QuasiStaticState};
pub use report::{IterationProfile, StepError, StepReport};
