//! Quasi-static implicit analysis: loads applied in steps, Newton per step, automatic
//! cut-back, commit of the converged state (DESIGN.md "Data flow of one implicit step").
//!
//! A load step that Newton cannot solve is retried from the last committed state with half
//! the load increment, down to `max_cutbacks` halvings; after two converged sub-steps in a
//! row the sub-step doubles again, up to the step's own increment. An attempt that fails at
//! the smallest size stops the run with an error naming the step, the load factor and the
//! residual history. An unconverged state is never committed.

use crate::engine::{advance, CutBack, Engine};
use crate::step::PointUpdateError;
use loam_grid::{ElementError, PointBasisError};
use loam_model::Model;
use loam_solve::{
    LinearSolverKind, LinearSolverTimings, NewtonError, NewtonReport, NewtonSettings, SparseDirectSolver,
};
use std::time::{Duration, Instant};

/// Settings of a quasi-static analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct QuasiStaticSettings {
    /// Number of equal load steps from zero to full load.
    pub load_steps: usize,
    pub newton: NewtonSettings,
    /// How many halvings a sub-step may reach before a failure stops the run (the smallest
    /// sub-step is the load step over 2^max_cutbacks).
    pub max_cutbacks: usize,
    /// Force a linear solver; `None` chooses Cholesky for symmetric tangents, LU otherwise.
    pub linear_solver: Option<LinearSolverKind>,
    /// Start each step's Newton iterate on the free dofs from the last converged
    /// increment, scaled to the new load increment (node by node, through the grid or mesh
    /// numbering), instead of from zero. On the geometrically linear V3 footings it gives
    /// the same peaks with 4–8 times fewer Newton iterations. Off by default: with moving
    /// points (updated small strain, B-bar) it led the frictional footings at 8 cells per b
    /// onto another load path (docs/theory.md §6).
    pub extrapolate: bool,
}

impl Default for QuasiStaticSettings {
    fn default() -> Self {
        Self {
            load_steps: 10,
            newton: NewtonSettings::default(),
            max_cutbacks: 8,
            linear_solver: None,
            extrapolate: false,
        }
    }
}

/// What one load step did.
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
    /// Relative residuals of the last sub-step, before the first and after each correction.
    pub residuals: Vec<f64>,
    /// Relative residuals of the converged sub-step with the most corrections (the first
    /// such sub-step on a tie); see [`most_iterations`](Self::most_iterations).
    pub hardest_residuals: Vec<f64>,
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

    /// The most corrections one converged sub-step needed (its residual history holds the
    /// one before the first correction and one after each).
    pub fn most_iterations(&self) -> usize {
        self.hardest_residuals.len().saturating_sub(1)
    }
}

/// Why a run stopped.
#[derive(Debug, Clone, thiserror::Error)]
pub enum StepError {
    #[error("step {step}: {source}; the point left the grid (enlarge the grid)")]
    PointOutsideGrid { step: usize, source: PointBasisError },
    #[error("step {step}: {source} (updated Lagrangian FEM: the mesh is too distorted to go on)")]
    Element { step: usize, source: ElementError },
    #[error("constraint {index} (axis {axis}, node plane {plane}) touches no active node: no material point has support on that plane")]
    ConstraintTouchesNoNode { index: usize, axis: usize, plane: usize },
    #[error("step {step} did not converge at load factor {load_factor:.6} after {cutbacks} cut-backs: {reason}")]
    NotConverged { step: usize, load_factor: f64, cutbacks: usize, reason: String, residuals: Vec<f64> },
    #[error("invalid analysis setting {field} = {value}: valid is {valid}")]
    InvalidSettings { field: &'static str, value: f64, valid: &'static str },
    #[error("constraint {index} prescribes a non-zero displacement; displacements follow the load factor of a quasi-static analysis and are not applied in dynamics")]
    DisplacementInDynamics { index: usize },
    #[error("the analysis is already finished ({0} steps)")]
    Finished(usize),
}

/// Quasi-static implicit analysis of a model. See the module docs.
pub struct QuasiStatic<const D: usize> {
    engine: Engine<D>,
    settings: QuasiStaticSettings,
    step: usize,
    load_factor: f64,
    /// The last converged increment per grid (mesh) node dof (reused from step to step)
    /// and its load increment; `None` until a step has converged.
    previous: Vec<f64>,
    previous_increment: Option<f64>,
}

impl<const D: usize> QuasiStatic<D> {
    pub fn new(model: Model<D>, settings: QuasiStaticSettings) -> Self {
        Self {
            engine: Engine::new(model, settings.newton, settings.linear_solver),
            settings,
            step: 0,
            load_factor: 0.0,
            previous: Vec::new(),
            previous_increment: None,
        }
    }

    pub fn model(&self) -> &Model<D> {
        &self.engine.model
    }

    pub fn into_model(self) -> Model<D> {
        self.engine.model
    }

    pub fn settings(&self) -> &QuasiStaticSettings {
        &self.settings
    }

    pub fn steps_done(&self) -> usize {
        self.step
    }

    pub fn load_factor(&self) -> f64 {
        self.load_factor
    }

    pub fn is_finished(&self) -> bool {
        self.step >= self.settings.load_steps
    }

    pub fn linear_solver_kind(&self) -> LinearSolverKind {
        self.engine.newton.linear_solver().kind()
    }

    pub fn linear_solver_timings(&self) -> LinearSolverTimings {
        self.engine.newton.linear_solver().timings()
    }

    /// Check what can only be checked against the connectivity: every constraint must
    /// hold at least one active node. Scene validation calls this before the first step.
    pub fn check(&mut self) -> Result<(), StepError> {
        self.engine.check(self.step + 1)
    }

    /// Try to reach `lambda` from the committed state. On success the state is committed.
    fn attempt(&mut self, lambda: f64) -> Result<NewtonReport, NewtonError<PointUpdateError>> {
        self.engine.external_forces(lambda);
        // Prescribed displacements enter as the starting increment on their dofs; Newton
        // never corrects constrained dofs, so they keep it.
        let e = &mut self.engine;
        e.du.clear();
        e.du.resize(e.num_dofs(), 0.0);
        e.model.prescribed_increment(e.conn.active_nodes(), self.load_factor, lambda, &mut e.du);
        let increment = lambda - self.load_factor;
        if let (true, Some(previous_increment)) = (self.settings.extrapolate, self.previous_increment) {
            let ratio = increment / previous_increment;
            for (a, &g) in e.conn.active_nodes().active_to_grid.iter().enumerate() {
                for i in (0..D).filter(|&i| !e.constrained[a * D + i]) {
                    e.du[a * D + i] = ratio * self.previous[g as usize * D + i];
                }
            }
        }
        let (mut system, du, newton) = self.engine.system(None);
        let report = newton.solve(&mut system, du)?;
        if self.settings.extrapolate {
            let e = &self.engine;
            let nodes = e.conn.active_nodes().grid_to_active.len();
            self.previous.clear();
            self.previous.resize(nodes * D, 0.0);
            for (a, &g) in e.conn.active_nodes().active_to_grid.iter().enumerate() {
                self.previous[g as usize * D..(g as usize + 1) * D].copy_from_slice(&e.du[a * D..(a + 1) * D]);
            }
            self.previous_increment = Some(increment);
        }
        self.engine.commit();
        self.load_factor = lambda;
        Ok(report)
    }

    /// Time the phases of one Newton iteration of the next load step from the committed
    /// state, with a fresh linear solver (so the symbolic factorisation is included), and
    /// commit nothing. For benchmarks and for sizing a run.
    pub fn profile_iteration(&mut self) -> Result<IterationProfile, StepError> {
        let t = Instant::now();
        self.engine.invalidate();
        self.engine.connect(self.step + 1)?;
        let connectivity = t.elapsed();
        let (step, lambda) = self.prepare_next_step();
        let not_converged = |reason: String| inspection_error(step, lambda, reason);
        let (mut system, du, newton) = self.engine.system(None);
        let kind = newton.linear_solver().kind();
        let n = du.len();
        let mut r = vec![0.0; n];
        let t = Instant::now();
        loam_solve::NewtonProblem::evaluate(&mut system, du, &mut r).map_err(|e| not_converged(e.to_string()))?;
        let points_and_residual = t.elapsed();
        let t = Instant::now();
        loam_solve::NewtonProblem::assemble(&mut system);
        let assembly = t.elapsed();
        let mut solver = SparseDirectSolver::new(kind);
        solver.factorize(&self.engine.pattern, &self.engine.values).map_err(|e| not_converged(e.to_string()))?;
        r.iter_mut().for_each(|v| *v = -*v);
        solver.solve_in_place(&mut r).map_err(|e| not_converged(e.to_string()))?;
        let lt = solver.timings();
        Ok(IterationProfile {
            dofs: n,
            nonzeros: self.engine.pattern.nnz(),
            connectivity,
            points_and_residual,
            assembly,
            symbolic: lt.symbolic,
            numeric: lt.numeric,
            solve: lt.solve,
        })
    }

    /// The tangent the next load step starts from (zero increment: the committed state),
    /// with its pattern and the constrained-dof flags (rows and columns eliminated but for
    /// the diagonal). For inspecting conditioning; commits nothing.
    pub fn start_tangent(&mut self) -> Result<(loam_solve::BlockPattern, Vec<f64>, Vec<bool>), StepError> {
        self.engine.connect(self.step + 1)?;
        let (step, lambda) = self.prepare_next_step();
        let (mut system, du, _) = self.engine.system(None);
        let mut r = vec![0.0; du.len()];
        loam_solve::NewtonProblem::evaluate(&mut system, du, &mut r)
            .map_err(|e| inspection_error(step, lambda, e.to_string()))?;
        loam_solve::NewtonProblem::assemble(&mut system);
        let e = &self.engine;
        Ok((e.pattern.clone(), e.values.clone(), e.constrained.clone()))
    }

    /// Set up the next load step at zero increment (the committed state) with its external
    /// forces, as `profile_iteration` and `start_tangent` inspect it; its number and load
    /// factor.
    fn prepare_next_step(&mut self) -> (usize, f64) {
        let step = self.step + 1;
        let lambda = (step as f64 / self.settings.load_steps as f64).min(1.0);
        self.engine.external_forces(lambda);
        self.engine.du.clear();
        (step, lambda)
    }

    /// Advance one load step, cutting back as needed.
    pub fn step(&mut self) -> Result<StepReport, StepError> {
        if self.is_finished() {
            return Err(StepError::Finished(self.settings.load_steps));
        }
        let start = Instant::now();
        let step = self.step + 1;
        let target = step as f64 / self.settings.load_steps as f64;
        let done = advance(self, step, target, 1.0, self.settings.max_cutbacks)?;
        self.step = step;
        Ok(done.into_report(step, self.load_factor, self.load_factor, self.engine.reactions.clone(), start))
    }

    /// Run every remaining step, calling `on_step` after each.
    pub fn run<E>(
        &mut self,
        mut on_step: impl FnMut(&StepReport, &Model<D>) -> Result<(), E>,
    ) -> Result<(), RunError<E>>
    where
        E: std::error::Error + 'static,
    {
        while !self.is_finished() {
            let report = self.step().map_err(RunError::Step)?;
            on_step(&report, &self.engine.model).map_err(RunError::Observer)?;
        }
        Ok(())
    }
}

impl<const D: usize> CutBack<D> for QuasiStatic<D> {
    fn engine(&mut self) -> &mut Engine<D> {
        &mut self.engine
    }

    fn position(&self) -> f64 {
        self.load_factor
    }

    fn attempt(&mut self, increment: f64, target: f64) -> Result<NewtonReport, NewtonError<PointUpdateError>> {
        self.attempt((self.load_factor + increment).min(target))
    }

    fn failure(&self, increment: f64, target: f64, error: &NewtonError<PointUpdateError>) -> (f64, String) {
        ((self.load_factor + increment).min(target), error.to_string())
    }
}

/// A failure while inspecting the next step's start (`profile_iteration`, `start_tangent`),
/// reported like a step that did not converge, with nothing cut back or committed.
fn inspection_error(step: usize, load_factor: f64, reason: String) -> StepError {
    StepError::NotConverged { step, load_factor, cutbacks: 0, reason, residuals: vec![] }
}

/// Wall time of the phases of one Newton iteration (see `QuasiStatic::profile_iteration`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IterationProfile {
    pub dofs: usize,
    pub nonzeros: usize,
    /// Basis evaluation, active nodes, adjacency, sparsity pattern.
    pub connectivity: Duration,
    /// Point kinematics, stress update and tangent, internal force gather.
    pub points_and_residual: Duration,
    /// Global tangent assembly.
    pub assembly: Duration,
    pub symbolic: Duration,
    pub numeric: Duration,
    pub solve: Duration,
}

impl IterationProfile {
    /// Assembly (points, residual, tangent) plus factorisation and solve: one iteration.
    pub fn iteration(&self) -> Duration {
        self.points_and_residual + self.assembly + self.symbolic + self.numeric + self.solve
    }
}

/// A run stopped by the analysis or by the step observer (e.g. an output error).
#[derive(Debug, thiserror::Error)]
pub enum RunError<E: std::error::Error + 'static> {
    #[error(transparent)]
    Step(StepError),
    #[error(transparent)]
    Observer(E),
}
