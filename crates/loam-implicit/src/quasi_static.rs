//! Quasi-static implicit analysis (docs/theory.md §1, §6): loads applied in steps, Newton
//! per step, automatic cut-back, commit of the converged state.
//!
//! [`QuasiStatic::step`] advances one load step through the cut-back control;
//! [`QuasiStatic::attempt`] is one attempt at a sub-step, the algorithm stage by stage.
//! With arc-length control (`arc_length`) the steps after the first are held to a length
//! of the displacement increment instead of a load factor.

use crate::arc_length::{ArcLengthSettings, ArcLengthState, ArcScratch, Peak};
use crate::cutback::{CutBack, StepScale};
use crate::engine::Engine;
use crate::points::PointUpdateError;
use crate::{IterationProfile, StepError, StepReport};
use loam_constitutive::ConstitutiveLaw;
use loam_kernels::{on_pool, RunError};
use loam_model::{AnalysisKind, LoadLevel, Model, ModelError, ModelState, PointChange};
use loam_solve::{
    norm, BlockPattern, LinearSolver, LinearSolverChoice, LinearSolverKind, LinearSolverTimings, NewtonError,
    NewtonReport, NewtonSettings,
};
use std::sync::Arc;
use std::time::Instant;

/// Settings of a quasi-static analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct QuasiStaticSettings {
    /// Number of equal load steps from zero to full load.
    pub load_steps: usize,
    pub newton: NewtonSettings,
    /// How many halvings a sub-step may reach before a failure stops the run (the smallest
    /// sub-step is the load step over 2^max_cutbacks, or `limit_resolution` of the load).
    pub max_cutbacks: usize,
    /// The linear solver: by default direct (Cholesky for symmetric positive definite
    /// tangents, LU otherwise) below a size and multigrid-preconditioned Krylov above it.
    pub linear_solver: LinearSolverChoice,
    /// Start each step's Newton iterate on the free dofs from the last converged
    /// increment, scaled to the new load increment (node by node, through the grid or mesh
    /// numbering), instead of from zero. Off by default: docs/theory.md §6 gives where it
    /// pays (the geometrically linear footings) and where it changes the load path (moving
    /// points).
    pub extrapolate: bool,
    /// How the load advances: by the load factor in `load_steps` equal steps (the
    /// default), or by arc length after a first step of 1 / `load_steps`.
    pub control: LoadControl,
    /// Where only forces follow the load factor (`Model::load_controlled`), the smallest
    /// load increment an attempt takes, as a fraction of the full load: the resolution of
    /// a limit load's search, which then stops after fewer halvings than `max_cutbacks`
    /// (docs/theory.md §6). 0: `max_cutbacks` alone.
    pub limit_resolution: f64,
}

/// How a quasi-static analysis advances the load.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum LoadControl {
    /// The load factor, in `load_steps` equal steps from 0 to 1.
    #[default]
    LoadFactor,
    /// Arc length (docs/theory.md §21): the load factor is an unknown of each step, which
    /// follows the load past a limit point.
    ArcLength(ArcLengthSettings),
}

impl Default for QuasiStaticSettings {
    fn default() -> Self {
        Self {
            load_steps: 10,
            newton: NewtonSettings::default(),
            max_cutbacks: 8,
            linear_solver: LinearSolverChoice::Auto,
            extrapolate: false,
            control: LoadControl::LoadFactor,
            limit_resolution: 1e-3,
        }
    }
}

/// What a quasi-static analysis carries from step to step beside its model: all a
/// checkpoint needs to resume it.
#[derive(Debug, Clone, PartialEq)]
pub struct QuasiStaticState {
    pub step: usize,
    pub load_factor: f64,
    /// The last converged increment per background node dof and its load increment (with
    /// `extrapolate`; empty and `None` otherwise).
    pub previous: Vec<f64>,
    pub previous_increment: Option<f64>,
    /// The linear solver resolved at the first step.
    pub linear_solver: Option<LinearSolverKind>,
    /// Under arc-length control, from the first step on.
    pub arc_length: Option<ArcLengthState>,
}

/// Quasi-static implicit analysis of a model. See the module docs.
pub struct QuasiStatic<const D: usize> {
    pub(crate) engine: Engine<D>,
    pub(crate) settings: QuasiStaticSettings,
    step: usize,
    pub(crate) load_factor: f64,
    /// The last converged increment per background node dof (reused from step to step)
    /// and its load increment; `None` until a step has converged.
    previous: Vec<f64>,
    pub(crate) previous_increment: Option<f64>,
    /// Under arc-length control, once the first step has converged.
    pub(crate) arc: Option<ArcLengthState>,
    pub(crate) arc_scratch: ArcScratch,
    /// The load factor of the last arc-length iterate (what a failed step tried).
    pub(crate) arc_tried: f64,
}

impl<const D: usize> QuasiStatic<D> {
    /// A quasi-static analysis of `model`. Under arc-length control the linear solver is
    /// chosen for an indefinite tangent (LU, BiCGStab), as past a limit point it is.
    pub fn new(model: Model<D>, settings: QuasiStaticSettings) -> Self {
        let indefinite = matches!(settings.control, LoadControl::ArcLength(_));
        Self {
            engine: Engine::new(model, settings.newton, settings.linear_solver, indefinite),
            settings,
            step: 0,
            load_factor: 0.0,
            previous: Vec::new(),
            previous_increment: None,
            arc: None,
            arc_scratch: ArcScratch::default(),
            arc_tried: 0.0,
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

    /// Load control: after the last load step. Arc-length control: after its most steps,
    /// or once the load factor has reached 1 or fallen back to 0.
    pub fn is_finished(&self) -> bool {
        match self.settings.control {
            LoadControl::LoadFactor => self.step >= self.settings.load_steps,
            LoadControl::ArcLength(arc) => {
                let reached = self.load_factor >= 1.0 - 1e-12;
                self.step >= arc.steps || reached || (self.step > 0 && self.load_factor <= 0.0)
            }
        }
    }

    /// How far the analysis is, in [0, 1]: the load factor under load control; under
    /// arc-length control the share of its most steps taken, which grows with every step
    /// where the load factor stalls on a plateau or falls past a peak (1 once finished,
    /// which may come sooner, at λ = 1).
    pub fn fraction_done(&self) -> f64 {
        if self.is_finished() {
            return 1.0;
        }
        let done = match self.settings.control {
            LoadControl::ArcLength(arc) => self.step as f64 / arc.steps as f64,
            LoadControl::LoadFactor => self.load_factor,
        };
        done.clamp(0.0, 1.0)
    }

    /// The most steps the analysis takes.
    fn most_steps(&self) -> usize {
        match self.settings.control {
            LoadControl::LoadFactor => self.settings.load_steps,
            LoadControl::ArcLength(arc) => arc.steps,
        }
    }

    /// Under arc-length control, the most load carried so far and the step that carried
    /// it; `None` under load control (whose last load factor is its most) and before the
    /// first step.
    pub fn peak(&self) -> Option<Peak> {
        self.arc.map(|a| a.peak)
    }

    /// The state [`QuasiStatic::resume`] takes back.
    pub fn state(&self) -> QuasiStaticState {
        QuasiStaticState {
            step: self.step,
            load_factor: self.load_factor,
            previous: self.previous.clone(),
            previous_increment: self.previous_increment,
            linear_solver: self.engine.resolved_linear_solver(),
            arc_length: self.arc,
        }
    }

    /// Add or remove points between steps ([`Model::change_points`]); returns how many.
    /// The next step connects the points anew.
    pub fn change_points(&mut self, change: PointChange<D>) -> Result<usize, ModelError> {
        self.engine.change_points(change)
    }

    /// Go on from `state` and `model`, saved by an analysis of the same scene: the next
    /// step is the one after `state.step`, with the numbers the saving run would have had.
    /// A state that does not fit is refused and nothing changes.
    pub fn resume(&mut self, state: QuasiStaticState, model: ModelState<D>) -> Result<(), ModelError> {
        let steps = self.most_steps();
        let fits = match self.settings.control {
            LoadControl::LoadFactor => state.arc_length.is_none(),
            LoadControl::ArcLength(_) => state.arc_length.is_some() == (state.step > 0),
        };
        if state.step > steps || !(0.0..=1.0).contains(&state.load_factor) || !fits {
            let (step, lambda) = (state.step, state.load_factor);
            let control = if state.arc_length.is_some() { "arc-length" } else { "load" };
            return Err(ModelError::Restore(format!(
                "step {step} at load factor {lambda} under {control} control, of {steps} steps"
            )));
        }
        self.engine.model.restore(model)?;
        self.engine.resume_linear_solver(state.linear_solver);
        self.step = state.step;
        self.load_factor = state.load_factor;
        self.previous = state.previous;
        self.previous_increment = state.previous_increment;
        self.arc = state.arc_length;
        Ok(())
    }

    /// Solve with `solver` instead of the settings' choice: a solver of the caller's (a
    /// distributed backend, a wrapper that records the systems), behind the same trait.
    /// Before the first step.
    pub fn set_linear_solver(&mut self, solver: Box<dyn LinearSolver>) {
        self.engine.set_linear_solver(solver);
    }

    pub fn linear_solver_kind(&self) -> LinearSolverKind {
        self.engine.linear_solver().kind()
    }

    /// The linear solver's method in words.
    pub fn linear_solver_description(&self) -> String {
        self.engine.linear_solver().description()
    }

    pub fn linear_solver_timings(&self) -> LinearSolverTimings {
        self.engine.linear_solver().timings()
    }

    /// Check that the analysis takes every option of the model (`loam_model::options`), and
    /// what can only be checked against the connectivity: every constraint must
    /// hold at least one active node, and together they must hold the body against every
    /// rigid-body motion (without inertia its tangent would be singular). Scene validation
    /// calls this before the first step.
    pub fn check(&mut self) -> Result<(), StepError> {
        self.engine.model.check_accepted_by(AnalysisKind::QuasiStatic)?;
        if matches!(self.settings.control, LoadControl::ArcLength(_)) && !self.model().frictional_planes().is_empty() {
            // The arc's load direction is taken once a step, on the dofs held then; the
            // contact states change them within the step.
            return Err(StepError::ArcLength(
                "arc-length control does not take frictional planes yet (their contact states change the held dofs within a step); use load control".into(),
            ));
        }
        self.engine.check(self.step + 1)?;
        let bodies = self.engine.free_rigid_bodies();
        if bodies.is_empty() {
            Ok(())
        } else {
            Err(StepError::Unsupported { bodies, dimension: D })
        }
    }

    /// Advance one load step, cutting back as needed: connect, then attempt the increment;
    /// a failed attempt is retried from the committed state with half the increment.
    pub fn step(&mut self) -> Result<StepReport, StepError> {
        if let Some(report) = on_pool(|| self.step()) {
            return report;
        }
        if self.is_finished() {
            return Err(StepError::Finished(self.most_steps()));
        }
        let start = Instant::now();
        let step = self.step + 1;
        let report = match (self.settings.control, self.arc) {
            (LoadControl::ArcLength(arc), Some(state)) => self.arc_step(step, arc, state, start)?,
            (control, _) => {
                let report = self.load_step(step, step as f64 / self.settings.load_steps as f64, start)?;
                if let LoadControl::ArcLength(arc) = control {
                    self.start_arc(step, arc)?;
                }
                report
            }
        };
        self.step = step;
        if let Some(state) = self.arc.as_mut().filter(|a| self.load_factor > a.peak.load_factor) {
            state.peak = Peak { step, load_factor: self.load_factor };
        }
        Ok(report)
    }

    /// After the first, load-controlled step of an arc-length analysis: the first length
    /// is that of its increment (its last sub-step's, scaled to the step where it was cut
    /// back). A step that moved nothing gives the arc no length: an error.
    fn start_arc(&mut self, step: usize, arc: ArcLengthSettings) -> Result<(), StepError> {
        let last = self.previous_increment.unwrap_or(0.0);
        let length = norm(&self.previous) * self.load_factor / last;
        if !(length.is_finite() && length > 0.0) {
            return Err(StepError::ArcLength(format!("the first step (to load factor {}) moved no node, so there is no length to hold the next steps to; load the body so that it deforms", self.load_factor)));
        }
        let peak = Peak { step, load_factor: self.load_factor };
        self.arc = Some(ArcLengthState { length, max_length: arc.max_growth * length, peak });
        Ok(())
    }

    /// Step `step` by load control from the committed load factor to `target`, cutting
    /// back as needed: connect, then attempt the increment; a failed attempt is retried
    /// from the committed state with half the increment.
    pub(crate) fn load_step(&mut self, step: usize, target: f64, start: Instant) -> Result<StepReport, StepError> {
        let floor = if self.engine.model.load_controlled() { self.settings.limit_resolution } else { 0.0 };
        let mut control =
            CutBack::new(self.load_factor, target, StepScale::LoadFactor, self.settings.max_cutbacks).with_floor(floor);
        while let Some(lambda) = control.next_end(self.load_factor) {
            self.engine.connect(step)?;
            match self.attempt(lambda) {
                Ok(report) => control.converged(report, self.engine.conn.active_nodes().len()),
                Err(e) => control.failed(step, self.load_factor, lambda, e.to_string(), e.report())?,
            }
        }
        let reactions = self.engine.reactions.clone();
        Ok(control.into_report(step, self.load_factor, self.load_factor, reactions, D, start))
    }

    /// One attempt to reach load factor `lambda` from the committed state, on the
    /// connectivity of that state: the algorithm of a quasi-static step, stage by stage.
    /// On success the state is committed; on failure nothing changes.
    fn attempt(&mut self, lambda: f64) -> Result<NewtonReport, NewtonError<PointUpdateError>> {
        self.engine.external_forces(LoadLevel::Factor(lambda));
        self.prescribe(lambda);
        let report = self.engine.newton(None)?;
        self.remember_increment(lambda);
        self.engine.commit();
        self.load_factor = lambda;
        Ok(report)
    }

    /// Connect the committed state to the background, as its next attempt will see it (a
    /// no-op where it is connected already).
    pub fn connect_committed(&mut self) -> Result<(), StepError> {
        self.engine.connect(self.step)
    }

    /// One attempt to bring the committed state back to equilibrium at its own load factor
    /// under the laws `materials` (a strength-reduction search lowering the strength of a
    /// state that held; connected by [`QuasiStatic::connect_committed`]): the stages of
    /// [`QuasiStatic::attempt`] at zero load increment. Converged: the state is committed
    /// with the new laws. Not converged: nothing changes, the laws included. The outer error
    /// is the model's refusal of the laws.
    pub fn attempt_with_materials(
        &mut self,
        materials: Vec<Arc<dyn ConstitutiveLaw>>,
    ) -> Result<Result<NewtonReport, NewtonError<PointUpdateError>>, ModelError> {
        debug_assert!(self.engine.is_connected(), "connect_committed comes first");
        let before = self.engine.model.materials().to_vec();
        self.engine.model.set_materials(materials)?;
        let attempt = self.attempt_at_held_load();
        if attempt.is_err() {
            self.engine.model.set_materials(before)?;
        }
        Ok(attempt)
    }

    /// [`QuasiStatic::attempt_with_materials`] once the laws are set. The extrapolated
    /// increment is left as it was (this attempt has no load increment to scale it by).
    /// Newton takes whole corrections without a second try (`NewtonSettings::retry`): a
    /// strength step's failure is the search's sign of collapse, and a line search carries
    /// Newton to equilibria of the discrete problem beyond it (docs/theory.md §14).
    fn attempt_at_held_load(&mut self) -> Result<NewtonReport, NewtonError<PointUpdateError>> {
        self.engine.external_forces(LoadLevel::Factor(self.load_factor));
        self.prescribe(self.load_factor);
        let whole = NewtonSettings { retry_backtracks: 0, ..self.settings.newton };
        let report = self.engine.newton_under(whole, None)?;
        self.engine.commit();
        Ok(report)
    }

    /// The increment Newton starts from: the prescribed displacements on their dofs
    /// (Newton never corrects constrained dofs, so they keep them), and zero — or, with
    /// `extrapolate`, the last converged increment scaled to this one — on the free dofs.
    fn prescribe(&mut self, lambda: f64) {
        let e = &mut self.engine;
        e.du.clear();
        e.du.resize(e.num_dofs(), 0.0);
        e.model.prescribed_increment(&e.layout, &e.conn, self.load_factor, lambda, &mut e.du);
        let increment = lambda - self.load_factor;
        if let (true, Some(previous_increment)) = (self.settings.extrapolate, self.previous_increment) {
            self.carry_previous(increment / previous_increment);
        }
    }

    /// `ratio` times the last converged increment on the free dofs of `du`, carried to
    /// the active nodes by their grid numbers.
    pub(crate) fn carry_previous(&mut self, ratio: f64) {
        let e = &mut self.engine;
        let n = e.layout.dofs_per_node();
        let held = e.frames.assembly_mask(&e.constrained);
        for (a, &g) in e.conn.active_nodes().active_to_grid.iter().enumerate() {
            for c in (0..n).filter(|&c| !held[a * n + c]) {
                e.du[a * n + c] = ratio * self.previous.get(g as usize * n + c).copied().unwrap_or(0.0);
            }
        }
    }

    /// With `extrapolate` or arc-length control (the secant predictor), keep the
    /// converged increment to `lambda` per background node.
    pub(crate) fn remember_increment(&mut self, lambda: f64) {
        if !self.settings.extrapolate && !matches!(self.settings.control, LoadControl::ArcLength(_)) {
            return;
        }
        let e = &self.engine;
        let (nodes, n) = (e.conn.active_nodes().grid_to_active.len(), e.layout.dofs_per_node());
        self.previous.clear();
        self.previous.resize(nodes * n, 0.0);
        for (a, &g) in e.conn.active_nodes().active_to_grid.iter().enumerate() {
            self.previous[g as usize * n..(g as usize + 1) * n].copy_from_slice(&e.du[a * n..(a + 1) * n]);
        }
        self.previous_increment = Some(lambda - self.load_factor);
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
        let not_converged = |reason: String| inspection_error(step, (self.load_factor, lambda), reason);
        let t = Instant::now();
        self.engine.update_points_and_residual(None).map_err(|e| not_converged(e.to_string()))?;
        let points_and_residual = t.elapsed();
        let t = Instant::now();
        self.engine.assemble(None);
        let assembly = t.elapsed();
        let e = &self.engine;
        let mut solver = e.new_linear_solver();
        let system = e.linear_system();
        solver.prepare(&system).map_err(|e| not_converged(e.to_string()))?;
        let rhs: Vec<f64> = e.residual().iter().map(|v| -v).collect();
        let mut x = vec![0.0; rhs.len()];
        // The first Newton iteration's forcing term (an iterative solver's tolerance).
        let tolerance = loam_solve::NewtonControl::start::<PointUpdateError>(self.settings.newton, 1.0, 1.0)
            .map(|c| c.linear_tolerance())
            .unwrap_or(1e-3);
        let stats = solver.solve(&system, &rhs, &mut x, tolerance).map_err(|e| not_converged(e.to_string()))?;
        let lt = solver.timings();
        Ok(IterationProfile {
            dofs: rhs.len(),
            nonzeros: e.pattern.nnz(),
            krylov_iterations: stats.iterations,
            solver_bytes: solver.bytes(),
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
    pub fn start_tangent(&mut self) -> Result<(BlockPattern, Vec<f64>, Vec<bool>), StepError> {
        self.engine.connect(self.step + 1)?;
        let (step, lambda) = self.prepare_next_step();
        self.engine
            .update_points_and_residual(None)
            .map_err(|e| inspection_error(step, (self.load_factor, lambda), e.to_string()))?;
        self.engine.assemble(None);
        let e = &self.engine;
        Ok((e.pattern.clone(), e.matrix.to_columns(&e.pattern).into_owned(), e.constrained.clone()))
    }

    /// Set up the next load step at zero increment (the committed state) with its external
    /// forces and sized buffers, as `profile_iteration` and `start_tangent` inspect it; its
    /// number and load factor.
    fn prepare_next_step(&mut self) -> (usize, f64) {
        let step = self.step + 1;
        let lambda = match self.settings.control {
            LoadControl::LoadFactor => step as f64 / self.settings.load_steps as f64,
            // The arc's next load factor is unknown: one load step on.
            LoadControl::ArcLength(_) => self.load_factor + 1.0 / self.settings.load_steps as f64,
        }
        .min(1.0);
        self.engine.external_forces(LoadLevel::Factor(lambda));
        self.engine.du.clear();
        self.engine.size_buffers();
        // An inspection assembles before any Newton solve: the contact states of a solve's
        // start, not the last step's.
        let e = &mut self.engine;
        e.frames.reset_contacts(&mut e.constrained);
        (step, lambda)
    }

    /// Run every remaining step, calling `on_step` after each.
    pub fn run<E>(
        &mut self,
        mut on_step: impl FnMut(&StepReport, &Model<D>) -> Result<(), E>,
    ) -> Result<(), RunError<StepError, E>>
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

/// A failure while inspecting the next step's start (`profile_iteration`, `start_tangent`),
/// reported like a step that did not converge, with nothing cut back or committed.
fn inspection_error(step: usize, (reached, load_factor): (f64, f64), reason: String) -> StepError {
    StepError::NotConverged { step, reached, load_factor, cutbacks: 0, reason, residuals: vec![] }
}
