//! Implicit MPM analyses over the grid, points, constitutive and solver crates: the
//! updated-Lagrangian step as a Newton system (`step`), and quasi-static load stepping with
//! cut-back (`quasi_static`), strength reduction on top of it (`strength_reduction`). The formulation is the seed paper's (Wang et al. 2016) with
//! the finite-strain extension of THEORY.md §2.

mod dynamic;
mod engine;
mod quasi_static;
mod step;
mod strength_reduction;

pub use dynamic::{Dynamic, DynamicSettings, MassMatrix};
pub use loam_model::{AntiLocking, Kinematics, Model, ModelError, PlaneConstraint};
pub use quasi_static::{IterationProfile, QuasiStatic, QuasiStaticSettings, RunError, StepError, StepReport};
pub use step::PointUpdateError;
pub use strength_reduction::{FactorOfSafety, StrengthReduction, StrengthReductionError, StrengthTrial};
