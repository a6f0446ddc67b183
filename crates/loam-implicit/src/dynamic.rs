//! Implicit dynamics (docs/theory.md §9): Newmark's method on the grid with Newton per time
//! step, optionally with Bossak's numerical dissipation.
//!
//! Each step maps the points' mass, velocity and acceleration to the active nodes, predicts
//! Δũ = Δt vₙ + Δt² (½ − β) aₙ, and solves M [(1 − α_B) a_{n+1} + α_B aₙ] + f_int − f_ext = 0
//! for Δu with a_{n+1} = (Δu − Δũ) / (β Δt²) and the tangent c M + K, c = (1 − α_B)/(β Δt²).
//! After convergence the points take a_p = Σ N_I a_I and
//! v_p ← v_p + Δt [(1 − γ) a_p,n + γ a_p,n+1] — γ is honoured at the points as well as in the
//! nodal update. A step Newton cannot solve is retried from the committed state with half
//! the time step (cut-back), exactly as in quasi-static analysis.
//!
//! Where the background's nodes move with the body and persist (the updated Lagrangian
//! FEM reference) they keep their velocity and acceleration from step to step and the
//! Gauss points take interpolated values, the usual FEM Newmark update.
//!
//! Trapezoidal rule (β = ¼, γ = ½, α_B = 0): unconditionally stable, no amplitude decay,
//! period elongation ωΔt / (2 arctan(ωΔt/2)). Bossak (α_B ∈ [−⅓, 0], β = (1 − α_B)²/4,
//! γ = ½ − α_B): second order, damps the highest frequencies.

use crate::cell_average::CellAverage;
use crate::cutback::{CutBack, StepScale};
use crate::engine::Engine;
use crate::inertia::Inertia;
use crate::points::PointUpdateError;
use crate::{StepError, StepReport};
use loam_kernels::{
    internal_force, interpolate, interpolate_pair, on_pool, scatter_internal_force, scatter_nodal, InvalidSetting,
};
use loam_model::{AnalysisKind, LoadLevel, Model, ModelError, ModelState, PointChange};
use loam_solve::{LinearSolverChoice, LinearSolverKind, NewtonError, NewtonReport, NewtonSettings};
use rayon::prelude::*;
use std::time::Instant;

/// Mass matrix of the inertial term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum MassMatrix {
    /// Row-sum lumped: m_I = Σ_p m_p N_I (the default; no extra coupling).
    #[default]
    Lumped,
    /// Consistent: M_IJ = Σ_p m_p N_I N_J.
    Consistent,
}

/// Settings of an implicit dynamic analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct DynamicSettings {
    /// Time step Δt.
    pub time_step: f64,
    /// End time; the last step is shortened to land on it.
    pub duration: f64,
    /// Newmark β (¼: average acceleration).
    pub beta: f64,
    /// Newmark γ (½: no numerical damping).
    pub gamma: f64,
    /// Bossak α_B ≤ 0 (0: plain Newmark).
    pub bossak_alpha: f64,
    pub mass: MassMatrix,
    pub newton: NewtonSettings,
    /// How many halvings a sub-step may reach before a failure stops the run.
    pub max_cutbacks: usize,
    /// Force a linear solver; `None` chooses Cholesky for symmetric tangents, LU otherwise.
    pub linear_solver: LinearSolverChoice,
}

impl DynamicSettings {
    /// Trapezoidal rule (β = ¼, γ = ½), lumped mass.
    pub fn trapezoidal(time_step: f64, duration: f64) -> Self {
        Self {
            time_step,
            duration,
            beta: 0.25,
            gamma: 0.5,
            bossak_alpha: 0.0,
            mass: MassMatrix::Lumped,
            newton: NewtonSettings::default(),
            max_cutbacks: 8,
            linear_solver: LinearSolverChoice::Auto,
        }
    }

    /// Bossak's method with α_B ∈ [−⅓, 0] and its second-order β, γ.
    pub fn bossak(mut self, alpha: f64) -> Self {
        self.bossak_alpha = alpha;
        self.beta = 0.25 * (1.0 - alpha).powi(2);
        self.gamma = 0.5 - alpha;
        self
    }

    fn validate(&self) -> Result<(), StepError> {
        let bad = |field: &'static str, value: f64, valid: &'static str| {
            Err(StepError::InvalidSettings(InvalidSetting { field, value, valid }))
        };
        if !(self.time_step.is_finite() && self.time_step > 0.0) {
            return bad("time_step", self.time_step, "a positive number");
        }
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return bad("duration", self.duration, "a positive number");
        }
        if !(self.beta > 0.0 && self.beta <= 0.5) {
            return bad("beta", self.beta, "0 < β ≤ ½ (¼ is the trapezoidal rule)");
        }
        if !(self.gamma >= 0.5 && self.gamma <= 1.0) {
            return bad("gamma", self.gamma, "½ ≤ γ ≤ 1 (below ½ the scheme is unstable)");
        }
        if !(self.bossak_alpha >= -1.0 / 3.0 && self.bossak_alpha <= 0.0) {
            return bad("bossak_alpha", self.bossak_alpha, "−⅓ ≤ α_B ≤ 0");
        }
        Ok(())
    }
}

/// What an implicit dynamic analysis carries from step to step beside its model: all a
/// checkpoint needs to resume it. The nodal fields matter where the nodes persist (the
/// FEM reference); on a grid they are scattered again every step.
#[derive(Debug, Clone, PartialEq)]
pub struct DynamicState {
    pub step: usize,
    pub time: f64,
    /// The initial acceleration has been computed.
    pub started: bool,
    pub nodal_mass: Vec<f64>,
    pub nodal_velocity: Vec<f64>,
    pub nodal_acceleration: Vec<f64>,
    /// The linear solver resolved at the first step.
    pub linear_solver: Option<LinearSolverKind>,
}

/// Implicit Newmark / Bossak dynamics of a model. See the module docs.
pub struct Dynamic<const D: usize> {
    engine: Engine<D>,
    settings: DynamicSettings,
    step: usize,
    time: f64,
    started: bool,
    /// Nodal mass, velocity, predictor and scratch of the inertial terms.
    inertia: Inertia,
    /// Nodal acceleration aₙ per dof.
    acceleration: Vec<f64>,
}

impl<const D: usize> Dynamic<D> {
    /// The points' velocities are the initial condition; their accelerations are replaced
    /// at the first step by the equilibrium acceleration M a₀ = f_ext − f_int (lumped), so
    /// a suddenly applied load starts from the right acceleration.
    pub fn new(model: Model<D>, settings: DynamicSettings) -> Result<Self, StepError> {
        settings.validate()?;
        model.check_accepted_by(AnalysisKind::Dynamic)?;
        let inertia = Inertia::new(settings.mass == MassMatrix::Consistent);
        Ok(Self {
            engine: Engine::new(model, settings.newton, settings.linear_solver, false),
            settings,
            step: 0,
            time: 0.0,
            started: false,
            inertia,
            acceleration: Vec::new(),
        })
    }

    pub fn model(&self) -> &Model<D> {
        &self.engine.model
    }

    pub fn into_model(self) -> Model<D> {
        self.engine.model
    }

    pub fn settings(&self) -> &DynamicSettings {
        &self.settings
    }

    pub fn steps_done(&self) -> usize {
        self.step
    }

    pub fn time(&self) -> f64 {
        self.time
    }

    pub fn is_finished(&self) -> bool {
        self.time >= self.settings.duration * (1.0 - 1e-12)
    }

    pub fn linear_solver_kind(&self) -> LinearSolverKind {
        self.engine.linear_solver().kind()
    }

    /// The linear solver's method in words.
    pub fn linear_solver_description(&self) -> String {
        self.engine.linear_solver().description()
    }

    /// The state [`Dynamic::resume`] takes back.
    pub fn state(&self) -> DynamicState {
        DynamicState {
            step: self.step,
            time: self.time,
            started: self.started,
            nodal_mass: self.inertia.nodal_mass.clone(),
            nodal_velocity: self.inertia.velocity.clone(),
            nodal_acceleration: self.acceleration.clone(),
            linear_solver: self.engine.resolved_linear_solver(),
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
    pub fn resume(&mut self, state: DynamicState, model: ModelState<D>) -> Result<(), ModelError> {
        let (step, time, duration) = (state.step, state.time, self.settings.duration);
        let nodes = state.nodal_mass.len();
        if !(time.is_finite() && (0.0..=duration).contains(&time))
            || state.nodal_velocity.len() != nodes * D
            || state.nodal_acceleration.len() != nodes * D
        {
            return Err(ModelError::Restore(format!(
                "step {step} at time {time} of {duration} with nodal fields of {nodes}, {} and {} values",
                state.nodal_velocity.len(),
                state.nodal_acceleration.len()
            )));
        }
        self.engine.model.restore(model)?;
        self.engine.resume_linear_solver(state.linear_solver);
        self.step = step;
        self.time = time;
        self.started = state.started;
        self.inertia.nodal_mass = state.nodal_mass;
        self.inertia.velocity = state.nodal_velocity;
        self.acceleration = state.nodal_acceleration;
        Ok(())
    }

    /// Every constraint must hold at least one active node.
    pub fn check(&mut self) -> Result<(), StepError> {
        self.engine.check(self.step + 1)
    }

    /// Advance one time step, cutting back as needed: before the first step the points take
    /// the equilibrium acceleration; then connect and attempt the step, a failed attempt
    /// retried from the committed state with half the time step.
    pub fn step(&mut self) -> Result<StepReport, StepError> {
        if let Some(report) = on_pool(|| self.step()) {
            return report;
        }
        if self.is_finished() {
            return Err(StepError::Finished(self.step));
        }
        let start = Instant::now();
        let step = self.step + 1;
        let dt = self.settings.time_step;
        let mut target = (self.time + dt).min(self.settings.duration);
        // Do not leave a sliver of a step at the end.
        if self.settings.duration - target < 1e-6 * dt {
            target = self.settings.duration;
        }
        if !self.started {
            self.engine.connect(step)?;
            self.initial_acceleration();
            self.started = true;
        }
        let mut control = CutBack::new(self.time, target, StepScale::Time(dt), self.settings.max_cutbacks);
        while let Some(size) = control.next(self.time) {
            self.engine.connect(step)?;
            let h = size.min(target - self.time);
            match self.attempt(h) {
                Ok(report) => control.converged(report, self.engine.conn.active_nodes().len()),
                Err(e) => {
                    let reason = format!("at time {:.6e} with time step {h:.3e}: {e}", self.time);
                    control.failed(step, self.time, 1.0, reason, e.report())?
                }
            }
        }
        self.time = target;
        self.step = step;
        let reactions = self.engine.reactions.clone();
        Ok(control.into_report(step, 1.0, self.time, reactions, D, start))
    }

    /// One attempt at a time step of length `dt` from the committed state, on the
    /// connectivity of that state: the algorithm of an implicit dynamic step, stage by
    /// stage. On success the state is committed; on failure nothing changes.
    fn attempt(&mut self, dt: f64) -> Result<NewtonReport, NewtonError<PointUpdateError>> {
        self.map_to_nodes();
        self.engine.external_forces(LoadLevel::Time(self.time + dt));
        self.predict(dt);
        let report = self.engine.newton(Some(&mut self.inertia))?;
        self.update_motion(dt);
        self.engine.commit();
        self.time += dt;
        Ok(report)
    }

    /// The nodal mass, velocity and acceleration of the committed points, scattered
    /// mass-weighted (zero on constrained dofs and along an inclined roller's normal, and
    /// into a frictional plane).
    /// Nodes that persist from step to step keep their own velocity and acceleration,
    /// mapped once at the start.
    fn map_to_nodes(&mut self) {
        if self.engine.model.background().moves_with_body() {
            return;
        }
        self.scatter_nodal_motion();
    }

    /// The mass-weighted scatter of the committed points' mass, velocity and acceleration.
    fn scatter_nodal_motion(&mut self) {
        let e = &self.engine;
        let (conn, pts) = (&e.conn, e.model.points());
        let n_nodes = conn.active_nodes().len();
        let nodal_mass = &mut self.inertia.nodal_mass;
        nodal_mass.resize(n_nodes, 0.0);
        scatter_nodal(conn, 1, nodal_mass, |p, a, out| {
            out[0] += conn.support_values(p)[a] * pts.mass()[p];
        });
        for (field, point_field) in
            [(&mut self.inertia.velocity, pts.velocity()), (&mut self.acceleration, pts.acceleration())]
        {
            field.resize(n_nodes * D, 0.0);
            scatter_nodal(conn, D, field, |p, a, out| {
                let w = conn.support_values(p)[a] * pts.mass()[p];
                for i in 0..D {
                    out[i] += w * point_field[p][i];
                }
            });
            per_unit_mass(e, nodal_mass, field, |_, momentum| momentum);
        }
    }

    /// Before the first step: the equilibrium acceleration of the committed state,
    /// a = M_L⁻¹ (f_ext − f_int), onto the points (a_p = Σ N_I a_I); nodes that persist keep
    /// the nodal mass, velocity and acceleration scattered here.
    fn initial_acceleration(&mut self) {
        self.scatter_nodal_motion();
        self.engine.external_forces(LoadLevel::Time(self.time));
        let f_ext = self.engine.external_forces_at_rest();
        let e = &mut self.engine;
        let (conn, pts) = (&e.conn, e.model.points());
        let average = CellAverage::of(&e.model, e.cell_gradients());
        let (stride, axisymmetric, x) = (conn.stride(), e.model.axisymmetric(), e.model.configuration());
        let mut f_int = vec![0.0; e.f_ext.len()];
        scatter_internal_force(conn, &mut f_int, |p, a| {
            let k = p * stride + a;
            let g = &conn.support_gradients(p)[a];
            let c = average.map_or(*g, |avg| avg.strain_gradient(k, g));
            let hoop = axisymmetric.then(|| conn.support_values(p)[a] / x[p][0]);
            internal_force(pts.volume()[p], &pts.stress()[p], &c, average.map(|avg| avg.average(k)), hoop)
        });
        per_unit_mass(e, &self.inertia.nodal_mass, &mut self.acceleration, |k, _| f_ext[k] - f_int[k]);
        let (acc, conn) = (&self.acceleration, &e.conn);
        e.model
            .points_mut()
            .acceleration
            .par_iter_mut()
            .enumerate()
            .for_each(|(p, ap)| *ap = interpolate(conn, p, acc));
    }

    /// The Newmark predictor Δũ = Δt vₙ + Δt² (½ − β) aₙ, the Bossak term α_B aₙ and the
    /// inertial factor c of a step of length `dt`; Newton starts from Δũ.
    fn predict(&mut self, dt: f64) {
        let (beta, alpha) = (self.settings.beta, self.settings.bossak_alpha);
        let inertia = &mut self.inertia;
        inertia.predictor.clear();
        inertia
            .predictor
            .extend(inertia.velocity.iter().zip(&self.acceleration).map(|(v, a)| dt * v + dt * dt * (0.5 - beta) * a));
        inertia.bossak_term.clear();
        inertia.bossak_term.extend(self.acceleration.iter().map(|a| alpha * a));
        inertia.factor = (1.0 - alpha) / (beta * dt * dt);
        inertia.time_step = dt;
        let n = self.engine.num_dofs();
        self.engine.du.clear();
        self.engine.du.extend_from_slice(&inertia.predictor[..n]);
    }

    /// After convergence: the new nodal accelerations a_{n+1} = (Δu − Δũ) / (β Δt²) (where
    /// a frictional plane holds a node, those that stop it: `LocalFrames::stop_held_motion`),
    /// and the points' velocity and acceleration (before the commit moves the points; the
    /// connectivity is that of the step's start).
    fn update_motion(&mut self, dt: f64) {
        let (beta, gamma) = (self.settings.beta, self.settings.gamma);
        let e = &mut self.engine;
        let mut a_new: Vec<f64> =
            e.du.iter().zip(&self.inertia.predictor).map(|(u, p)| (u - p) / (beta * dt * dt)).collect();
        e.frames.stop_held_motion(&mut a_new, &self.inertia.velocity, &self.acceleration, dt, gamma);
        let conn = &e.conn;
        let persist = e.model.background().moves_with_body();
        let pts = e.model.points_mut();
        if persist {
            // Nodes that persist take the Newmark update; the points interpolate it.
            for ((v, a), an) in self.inertia.velocity.iter_mut().zip(self.acceleration.iter_mut()).zip(&a_new) {
                *v += dt * ((1.0 - gamma) * *a + gamma * an);
                *a = *an;
            }
            let (vel, acc) = (&self.inertia.velocity, &self.acceleration);
            (pts.velocity.par_iter_mut(), pts.acceleration.par_iter_mut())
                .into_par_iter()
                .enumerate()
                .for_each(|(p, (v, a))| (*v, *a) = interpolate_pair(conn, p, vel, acc));
        } else {
            (pts.velocity.par_iter_mut(), pts.acceleration.par_iter_mut()).into_par_iter().enumerate().for_each(
                |(p, (v, a))| {
                    let an = interpolate(conn, p, &a_new);
                    *v += (*a * (1.0 - gamma) + an * gamma) * dt;
                    *a = an;
                },
            );
        }
    }
}

/// A nodal velocity or acceleration a step starts from: `value(k, field[k]) / m_I` on every
/// dof k of a node I with mass that no constraint holds, zero elsewhere, and without its
/// normal component at the nodes of inclined rollers, and a normal component into a
/// frictional plane at its nodes (docs/theory.md §5).
fn per_unit_mass<const D: usize>(
    engine: &Engine<D>,
    nodal_mass: &[f64],
    field: &mut [f64],
    value: impl Fn(usize, f64) -> f64,
) {
    let held = engine.frames.assembly_mask(&engine.constrained);
    for (k, (v, &fixed)) in field.iter_mut().zip(held).enumerate() {
        let m = nodal_mass[k / D];
        *v = if fixed || m <= 0.0 { 0.0 } else { value(k, *v) / m };
    }
    engine.frames.hold_in_field(field);
}

#[cfg(test)]
mod tests {
    use super::*;
    use loam_constitutive::Elastic;
    use loam_grid::{BasisKind, Grid};
    use loam_model::Kinematics;
    use loam_points::{PointStore, Shape};
    use nalgebra::Vector2;
    use std::sync::Arc;

    /// A 2 × 2-cell elastic block, 2 × 2 points per cell, in an 8 × 8 grid, under gravity
    /// −10 along y and nothing else: free fall.
    fn falling_block() -> Model<2> {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [8, 8]).unwrap();
        let mut points = PointStore::new();
        points
            .fill(&grid, &Shape::Box { min: Vector2::new(3.0, 4.0), max: Vector2::new(5.0, 6.0) }, 2, 1000.0, 0)
            .unwrap();
        let law = Arc::new(Elastic::new(1e6, 0.3).unwrap());
        Model::new(grid, BasisKind::Gimp, Kinematics::FiniteStrain, points, vec![law], vec![], Vector2::new(0.0, -10.0))
            .unwrap()
    }

    /// A body in free fall has no strain, so Newmark integrates its constant acceleration
    /// exactly whatever β, γ and α_B: after t every point has fallen ½ g t² and moves at g t
    /// — for the trapezoidal rule and Bossak, lumped and consistent mass alike. Tolerance
    /// 1e-12 relative: round-off of a few dozen steps.
    #[test]
    fn free_fall_is_integrated_exactly() {
        let (dt, duration, g) = (0.01, 0.25, -10.0);
        for (settings, mass) in [
            (DynamicSettings::trapezoidal(dt, duration), MassMatrix::Lumped),
            (DynamicSettings::trapezoidal(dt, duration), MassMatrix::Consistent),
            (DynamicSettings::trapezoidal(dt, duration).bossak(-0.1), MassMatrix::Lumped),
        ] {
            let mut dynamic = Dynamic::new(falling_block(), DynamicSettings { mass, ..settings }).unwrap();
            dynamic.check().unwrap();
            while !dynamic.is_finished() {
                let report = dynamic.step().unwrap();
                assert_eq!(report.cutbacks, 0);
            }
            let t = dynamic.time();
            assert!((t - duration).abs() < 1e-15);
            let pts = dynamic.model().points();
            let (fall, speed) = (0.5 * g * t * t, g * t);
            for p in 0..pts.len() {
                let u = pts.position()[p] - pts.position0()[p];
                assert!(
                    u[0].abs() < 1e-12 && (u[1] - fall).abs() < 1e-12 * fall.abs(),
                    "{mass:?}: point {p} moved {u}"
                );
                let v = pts.velocity()[p];
                assert!(v[0].abs() < 1e-12 && (v[1] - speed).abs() < 1e-12 * speed.abs(), "{mass:?}: v = {v}");
            }
        }
    }

    /// Bossak's β and γ are the second-order ones of its α_B, and settings outside the
    /// stable ranges are refused with the field named.
    #[test]
    fn settings_are_second_order_and_checked() {
        let bossak = DynamicSettings::trapezoidal(0.1, 1.0).bossak(-0.2);
        assert!((bossak.beta - 0.36).abs() < 1e-15 && (bossak.gamma - 0.7).abs() < 1e-15);
        let refused = |s: DynamicSettings| match Dynamic::new(falling_block(), s) {
            Err(StepError::InvalidSettings(e)) => e.field,
            other => panic!("accepted: {:?}", other.map(|_| ())),
        };
        let base = DynamicSettings::trapezoidal(0.1, 1.0);
        assert_eq!(refused(DynamicSettings { gamma: 0.4, ..base.clone() }), "gamma");
        assert_eq!(refused(DynamicSettings { beta: 0.0, ..base.clone() }), "beta");
        assert_eq!(refused(DynamicSettings { bossak_alpha: -0.5, ..base.clone() }), "bossak_alpha");
        assert_eq!(refused(DynamicSettings { time_step: f64::NAN, ..base }), "time_step");
    }
}
