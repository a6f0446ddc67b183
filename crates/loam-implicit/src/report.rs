//! What an implicit step reports, and why one stops.

use loam_kernels::{ConnectError, InvalidSetting};
use std::time::Duration;

/// What one load or time step did.
#[derive(Debug, Clone, PartialEq)]
pub struct StepReport {
    /// 1-based step number.
    pub step: usize,
    pub load_factor: f64,
    /// Time reached (dynamics); in quasi-static analysis the pseudo-time, equal to the load
    /// factor.
    pub time: f64,
    /// Sub-steps the step needed (1 without cut-back).
    pub substeps: usize,
    /// Failed attempts that were cut back.
    pub cutbacks: usize,
    /// Newton corrections over all converged sub-steps.
    pub iterations: usize,
    /// Krylov iterations of their linear solves (0 with a direct solver).
    pub linear_iterations: usize,
    /// Time their linear solvers took to prepare (factorisations, or multigrid set-up).
    pub linear_setup: Duration,
    /// Corrections whose Krylov solve failed and were solved by sparse LU instead, over
    /// all the step's attempts (converged or cut back).
    pub direct_fallbacks: usize,
    /// Relative residuals of the last sub-step, before the first and after each correction.
    pub residuals: Vec<f64>,
    /// Relative residuals of the converged sub-step with the most corrections (the first
    /// such sub-step on a tie); see [`most_iterations`](Self::most_iterations). Where that
    /// sub-step abandoned a first try, its second try's.
    pub hardest_residuals: Vec<f64>,
    /// Corrections of the first try that sub-step abandoned (0 where it had none).
    pub hardest_abandoned: usize,
    pub active_nodes: usize,
    pub dofs: usize,
    /// Per constraint (scene order), the support reaction Σ (f_int − f_ext) over its nodes
    /// on its prescribed components: the force the support exerts is its negative. A
    /// footing pushed down reads negative here; the load it carries is −reaction.
    pub reactions: Vec<[f64; 3]>,
    pub wall_time: Duration,
}

impl StepReport {
    pub fn final_residual(&self) -> f64 {
        self.residuals.last().copied().unwrap_or(f64::NAN)
    }

    /// The most corrections one converged sub-step needed, those of an abandoned first try
    /// included (its residual history holds the one before the first correction and one
    /// after each).
    pub fn most_iterations(&self) -> usize {
        self.hardest_abandoned + self.hardest_residuals.len().saturating_sub(1)
    }
}

/// Why a step, and with it the run, stopped.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepError {
    /// The points could not be connected to the background, or a constraint holds no node.
    #[error(transparent)]
    Connect(#[from] ConnectError),
    /// Step `step` reached `reached` (its load factor, or time) and could not go on to
    /// `load_factor` with the smallest increment allowed; `cutbacks` counts every halving
    /// of the step, which may exceed `max_cutbacks` (a sub-step size doubles back after two
    /// converged attempts).
    #[error("step {step} did not converge: it reached {reached:.6} and could not go on to {load_factor:.6}, after {cutbacks} cut-backs in the step (the last one as small as max_cutbacks and the limit resolution allow): {reason}")]
    NotConverged { step: usize, reached: f64, load_factor: f64, cutbacks: usize, reason: String, residuals: Vec<f64> },
    #[error("analysis: {0}")]
    InvalidSettings(InvalidSetting),
    /// Arc-length control cannot go on (docs/theory.md §21).
    #[error("arc-length control: {0}")]
    ArcLength(String),
    #[error("linear solver: {0}")]
    LinearSolver(loam_solve::LinearSolveError),
    /// The model uses an option the analysis does not accept (`loam_model`'s table).
    #[error(transparent)]
    Unaccepted(#[from] loam_model::Unaccepted),
    #[error("the analysis is already finished ({0} steps)")]
    Finished(usize),
    #[error(
        "not supported against rigid motion: no constraint holds {}; a quasi-static analysis needs \
         supports against every rigid motion of every body (e.g. Fixed on the base, Roller on the sides)",
        bodies.iter().map(|b| b.describe(*dimension)).collect::<Vec<_>>().join("; ")
    )]
    Unsupported { bodies: Vec<loam_model::FreeBody>, dimension: usize },
}

/// Wall time of the phases of one Newton iteration (see `QuasiStatic::profile_iteration`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IterationProfile {
    pub dofs: usize,
    pub nonzeros: usize,
    /// Krylov iterations of the solve (0 for a direct solver).
    pub krylov_iterations: usize,
    /// Bytes the linear solver holds beyond the assembled tangent (0 where not known).
    pub solver_bytes: usize,
    /// Basis evaluation, active nodes, adjacency, the points' bands, sparsity pattern.
    pub connectivity: Duration,
    /// Point kinematics, stress update and tangent, internal force scatter.
    pub points_and_residual: Duration,
    /// Global tangent assembly.
    pub assembly: Duration,
    /// Symbolic factorisation, or the multigrid structure.
    pub symbolic: Duration,
    /// Numeric factorisation, or the multigrid values (Galerkin products, smoothers).
    pub numeric: Duration,
    pub solve: Duration,
}

impl IterationProfile {
    /// Assembly (points, residual, tangent) plus factorisation and solve: one iteration.
    pub fn iteration(&self) -> Duration {
        self.points_and_residual + self.assembly + self.symbolic + self.numeric + self.solve
    }
}
