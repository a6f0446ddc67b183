//! One stepping interface over the three analyses — quasi-static load stepping, implicit
//! Newmark dynamics and explicit MPM — for a program that runs whichever a problem asks
//! for (the scene runner, the CLI) without knowing a file format.

use loam_explicit::{Explicit, ExplicitError, ExplicitState};
use loam_implicit::{Dynamic, DynamicState, QuasiStatic, QuasiStaticState, StepError, StepReport};
use loam_kernels::ConnectError;
use loam_model::{LoadLevel, Model, ModelError, ModelState, PointChange};
use std::time::Duration;

/// One of the three analyses.
#[allow(clippy::large_enum_variant)] // one per run; boxing buys nothing
pub enum Analysis<const D: usize> {
    QuasiStatic(QuasiStatic<D>),
    Dynamic(Dynamic<D>),
    Explicit(Explicit<D>),
}

/// What an analysis carries from step to step beside its model (a checkpoint's).
#[derive(Debug, Clone, PartialEq)]
pub enum AnalysisState {
    QuasiStatic(QuasiStaticState),
    Dynamic(DynamicState),
    Explicit(ExplicitState),
}

/// Why a step failed.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    #[error(transparent)]
    Implicit(#[from] StepError),
    #[error(transparent)]
    Explicit(#[from] ExplicitError),
}

impl AnalysisError {
    /// The failure to connect the points to the background (a point outside the grid, a
    /// constraint that holds no node), whichever analysis met it.
    pub fn connect_error(&self) -> Option<&ConnectError> {
        match self {
            AnalysisError::Implicit(StepError::Connect(e)) | AnalysisError::Explicit(ExplicitError::Connect(e)) => {
                Some(e)
            }
            _ => None,
        }
    }
}

/// What one step did, whatever the analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct Progress {
    /// 1-based step number.
    pub step: usize,
    /// Time reached (quasi-static: the pseudo-time, equal to the load factor).
    pub time: f64,
    pub load_factor: f64,
    /// Where the loads stand after the step: the load factor (quasi-static) or the time.
    pub level: LoadLevel,
    /// Time (or load) increment of the step.
    pub increment: f64,
    /// Newton corrections over the step (0 for explicit steps).
    pub iterations: usize,
    /// Krylov iterations of their linear solves (0 with a direct solver).
    pub linear_iterations: usize,
    /// Time the linear solvers took to prepare (factorisations, or multigrid set-up).
    pub linear_setup: Duration,
    /// Corrections whose Krylov solve failed and were solved by sparse LU instead, over
    /// all the step's attempts (converged or cut back).
    pub direct_fallbacks: usize,
    pub substeps: usize,
    pub cutbacks: usize,
    /// Relative residual at convergence (NaN for explicit steps, which have none).
    pub final_residual: f64,
    pub active_nodes: usize,
    pub dofs: usize,
    /// Support reaction of each constraint (implicit analyses; empty for explicit steps).
    pub reactions: Vec<[f64; 3]>,
    pub wall_time: Duration,
}

impl Progress {
    /// The progress of an implicit (quasi-static or dynamic) step that started at `before`.
    fn implicit(r: StepReport, before: f64, level: LoadLevel) -> Self {
        Progress {
            step: r.step,
            time: r.time,
            load_factor: r.load_factor,
            level,
            increment: r.time - before,
            iterations: r.iterations,
            linear_iterations: r.linear_iterations,
            linear_setup: r.linear_setup,
            direct_fallbacks: r.direct_fallbacks,
            substeps: r.substeps,
            cutbacks: r.cutbacks,
            final_residual: r.final_residual(),
            active_nodes: r.active_nodes,
            dofs: r.dofs,
            reactions: r.reactions,
            wall_time: r.wall_time,
        }
    }
}

impl<const D: usize> Analysis<D> {
    /// Short name for logs: "quasi-static", "implicit dynamic", "explicit".
    pub fn name(&self) -> &'static str {
        match self {
            Analysis::QuasiStatic(_) => "quasi-static",
            Analysis::Dynamic(_) => "implicit dynamic",
            Analysis::Explicit(_) => "explicit",
        }
    }

    pub fn model(&self) -> &Model<D> {
        match self {
            Analysis::QuasiStatic(a) => a.model(),
            Analysis::Dynamic(a) => a.model(),
            Analysis::Explicit(a) => a.model(),
        }
    }

    pub fn into_model(self) -> Model<D> {
        match self {
            Analysis::QuasiStatic(a) => a.into_model(),
            Analysis::Dynamic(a) => a.into_model(),
            Analysis::Explicit(a) => a.into_model(),
        }
    }

    pub fn is_finished(&self) -> bool {
        match self {
            Analysis::QuasiStatic(a) => a.is_finished(),
            Analysis::Dynamic(a) => a.is_finished(),
            Analysis::Explicit(a) => a.is_finished(),
        }
    }

    pub fn steps_done(&self) -> usize {
        match self {
            Analysis::QuasiStatic(a) => a.steps_done(),
            Analysis::Dynamic(a) => a.steps_done(),
            Analysis::Explicit(a) => a.steps_done(),
        }
    }

    /// Time reached (quasi-static: the load factor).
    pub fn time(&self) -> f64 {
        match self {
            Analysis::QuasiStatic(a) => a.load_factor(),
            Analysis::Dynamic(a) => a.time(),
            Analysis::Explicit(a) => a.time(),
        }
    }

    /// Load factor of the dead loads now: ramped in quasi-static analysis, full at once in
    /// dynamics.
    pub fn load_factor(&self) -> f64 {
        match self {
            Analysis::QuasiStatic(a) => a.load_factor(),
            _ => 1.0,
        }
    }

    /// Where the loads stand now: the load factor of a quasi-static analysis, the time of
    /// the others.
    pub fn load_level(&self) -> LoadLevel {
        match self {
            Analysis::QuasiStatic(a) => LoadLevel::Factor(a.load_factor()),
            _ => LoadLevel::Time(self.time()),
        }
    }

    /// Time (or load factor) at the end of the analysis.
    pub fn end_time(&self) -> f64 {
        match self {
            Analysis::QuasiStatic(_) => 1.0,
            Analysis::Dynamic(a) => a.settings().duration,
            Analysis::Explicit(a) => a.settings().duration,
        }
    }

    /// The linear solver, or that explicit analysis has none.
    pub fn solver(&self) -> String {
        match self {
            Analysis::QuasiStatic(a) => a.linear_solver_kind().to_string(),
            Analysis::Dynamic(a) => a.linear_solver_kind().to_string(),
            Analysis::Explicit(_) => "no linear solver (explicit)".to_string(),
        }
    }

    /// The state [`Analysis::resume`] takes back, with the model's (a `ModelState` of its
    /// points, load vertices and mesh nodes).
    pub fn state(&self) -> AnalysisState {
        match self {
            Analysis::QuasiStatic(a) => AnalysisState::QuasiStatic(a.state()),
            Analysis::Dynamic(a) => AnalysisState::Dynamic(a.state()),
            Analysis::Explicit(a) => AnalysisState::Explicit(a.state()),
        }
    }

    /// Go on from a state saved by an analysis of the same scene: the next step is the one
    /// the saving run would have taken next, with the same numbers. A state of another
    /// analysis, or one that does not fit, is refused and nothing changes.
    pub fn resume(&mut self, state: AnalysisState, model: ModelState<D>) -> Result<(), ModelError> {
        match (self, state) {
            (Analysis::QuasiStatic(a), AnalysisState::QuasiStatic(s)) => a.resume(s, model),
            (Analysis::Dynamic(a), AnalysisState::Dynamic(s)) => a.resume(s, model),
            (Analysis::Explicit(a), AnalysisState::Explicit(s)) => a.resume(s, model),
            (a, _) => Err(ModelError::Restore(format!("the state is not of a {} analysis", a.name()))),
        }
    }

    /// Add or remove points between steps ([`Model::change_points`]); returns how many.
    pub fn change_points(&mut self, change: PointChange<D>) -> Result<usize, ModelError> {
        match self {
            Analysis::QuasiStatic(a) => a.change_points(change),
            Analysis::Dynamic(a) => a.change_points(change),
            Analysis::Explicit(a) => a.change_points(change),
        }
    }

    /// Connectivity checks that need the active nodes (constraints that touch no node,
    /// points whose basis leaves the grid).
    pub fn check(&mut self) -> Result<(), AnalysisError> {
        match self {
            Analysis::QuasiStatic(a) => a.check()?,
            Analysis::Dynamic(a) => a.check()?,
            Analysis::Explicit(a) => a.check()?,
        }
        Ok(())
    }

    /// Advance one step.
    pub fn step(&mut self) -> Result<Progress, AnalysisError> {
        let before = self.time();
        Ok(match self {
            Analysis::QuasiStatic(a) => {
                let r = a.step()?;
                Progress::implicit(r, before, LoadLevel::Factor(a.load_factor()))
            }
            Analysis::Dynamic(a) => {
                let r = a.step()?;
                Progress::implicit(r, before, LoadLevel::Time(a.time()))
            }
            Analysis::Explicit(a) => {
                let r = a.step()?;
                Progress {
                    step: r.step,
                    time: r.time,
                    load_factor: 1.0,
                    level: LoadLevel::Time(r.time),
                    increment: r.dt,
                    iterations: 0,
                    linear_iterations: 0,
                    linear_setup: Duration::ZERO,
                    direct_fallbacks: 0,
                    substeps: 1,
                    cutbacks: 0,
                    final_residual: f64::NAN,
                    active_nodes: r.active_nodes,
                    dofs: r.active_nodes * D,
                    reactions: Vec::new(),
                    wall_time: r.wall_time,
                }
            }
        })
    }
}
