//! Linear and nonlinear solvers for the implicit MPM: the block sparsity pattern of a
//! nodal system with deterministic parallel assembly, sparse direct solvers (faer
//! Cholesky and LU) that reuse their symbolic factorisation, and Newton's method with
//! relative-residual and increment criteria. Nothing here knows about grids or points.

mod linear;
mod newton;
mod pattern;

pub use linear::{LinearSolveError, LinearSolverKind, LinearSolverTimings, SparseDirectSolver};
pub use newton::{norm, NewtonControl, NewtonError, NewtonReport, NewtonSettings};
pub use pattern::{BlockPattern, Couplings};
