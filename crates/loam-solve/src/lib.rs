//! Linear and nonlinear solvers for the implicit MPM: the block sparsity pattern of a
//! nodal system with deterministic parallel assembly, sparse direct solvers (faer
//! Cholesky and LU) that reuse their symbolic factorisation and order a lattice's nodes
//! by nested dissection, GMRES on a non-symmetric tangent preconditioned by the factor
//! of its symmetric part, Krylov solvers (CG,
//! BiCGStab) preconditioned by geometric multigrid on a node lattice, and Newton's method
//! with relative-residual and increment criteria and an inexact-Newton forcing term.
//! Nothing here knows about grids or points: multigrid sees integer node coordinates.

mod block_matrix;
mod krylov;
mod linear;
mod multigrid;
mod newton;
mod ordering;
mod pattern;
mod system_matrix;

pub use block_matrix::BlockMatrix;
pub use krylov::IterativeSolver;
pub use linear::{
    KrylovFailure, LinearSolveError, LinearSolveStats, LinearSolver, LinearSolverChoice, LinearSolverKind,
    LinearSolverTimings, LinearSystem, SparseDirectSolver, SymmetricPart,
};
pub use multigrid::{Multigrid, NodeLattice};
pub use newton::{norm, NewtonControl, NewtonError, NewtonReport, NewtonSettings};
pub use pattern::{BlockPattern, Couplings};
pub use system_matrix::{MatrixLayout, SystemMatrix};
