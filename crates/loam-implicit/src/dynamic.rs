//! Implicit dynamics: Newmark's method on the grid with Newton per time step (THEORY.md §4;
//! the seed paper's dynamic formulation), optionally with Bossak's numerical dissipation.
//!
//! Each step maps the points' mass, velocity and acceleration to the active nodes, predicts
//! Δũ = Δt vₙ + Δt² (½ − β) aₙ, and solves M [(1 − α_B) a_{n+1} + α_B aₙ] + f_int − f_ext = 0
//! for Δu with a_{n+1} = (Δu − Δũ) / (β Δt²) and the tangent c M + K, c = (1 − α_B)/(β Δt²).
//! After convergence the points take a_p = Σ N_I a_I and
//! v_p ← v_p + Δt [(1 − γ) a_p,n + γ a_p,n+1] — γ is honoured at the points as well as in the
//! nodal update. A step Newton cannot solve is retried from the committed state with half
//! the time step (cut-back), exactly as in quasi-static analysis.
//!
//! In the updated Lagrangian FEM reference (`Model::updated_lagrangian_fem`) the mesh
//! nodes persist: they keep their velocity and acceleration from step to step and the
//! Gauss points take interpolated values, the usual FEM Newmark update.
//!
//! Trapezoidal rule (β = ¼, γ = ½, α_B = 0): unconditionally stable, no amplitude decay,
//! period elongation ωΔt / (2 arctan(ωΔt/2)). Bossak (α_B ∈ [−⅓, 0], β = (1 − α_B)²/4,
//! γ = ½ − α_B): second order, damps the highest frequencies.

use crate::engine::{advance, CutBack, Engine};
use crate::step::{Inertia, PointCouplings, PointUpdateError};
use crate::{StepError, StepReport};
use loam_model::{internal_force, Model};
use loam_solve::{gather_nodal, LinearSolverKind, NewtonError, NewtonReport, NewtonSettings};
use nalgebra::SVector;
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
    pub linear_solver: Option<LinearSolverKind>,
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
            linear_solver: None,
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
            Err(StepError::InvalidSettings { field, value, valid })
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

/// Implicit Newmark / Bossak dynamics of a model. See the module docs.
pub struct Dynamic<const D: usize> {
    engine: Engine<D>,
    settings: DynamicSettings,
    step: usize,
    time: f64,
    started: bool,
    nodal_mass: Vec<f64>,
    velocity: Vec<f64>,
    acceleration: Vec<f64>,
    predictor: Vec<f64>,
    bossak_term: Vec<f64>,
    x: Vec<f64>,
    point_x: Vec<f64>,
    force: Vec<f64>,
}

impl<const D: usize> Dynamic<D> {
    /// The points' velocities are the initial condition; their accelerations are replaced
    /// at the first step by the equilibrium acceleration M a₀ = f_ext − f_int (lumped), so
    /// a suddenly applied load starts from the right acceleration.
    pub fn new(model: Model<D>, settings: DynamicSettings) -> Result<Self, StepError> {
        settings.validate()?;
        if let Some(index) = model.constraints.iter().position(|c| c.is_displaced()) {
            return Err(StepError::DisplacementInDynamics { index });
        }
        Ok(Self {
            engine: Engine::new(model, settings.newton, settings.linear_solver),
            settings,
            step: 0,
            time: 0.0,
            started: false,
            nodal_mass: Vec::new(),
            velocity: Vec::new(),
            acceleration: Vec::new(),
            predictor: Vec::new(),
            bossak_term: Vec::new(),
            x: Vec::new(),
            point_x: Vec::new(),
            force: Vec::new(),
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
        self.engine.newton.linear_solver().kind()
    }

    /// Every constraint must hold at least one active node.
    pub fn check(&mut self) -> Result<(), StepError> {
        self.engine.check(self.step + 1)
    }

    /// Mass-weighted nodal mass, velocity and acceleration of the committed points
    /// (zero on constrained dofs).
    fn map_to_nodes(&mut self) {
        let e = &self.engine;
        let conn = &e.conn;
        let pts = &e.model.points;
        let n_nodes = conn.active_nodes().len();
        self.nodal_mass.resize(n_nodes, 0.0);
        gather_nodal(&PointCouplings(conn), 1, &mut self.nodal_mass, |p, a, out| {
            out[0] += conn.support_values(p)[a] * pts.mass[p];
        });
        for (field, point_field) in [(&mut self.velocity, &pts.velocity), (&mut self.acceleration, &pts.acceleration)] {
            field.resize(n_nodes * D, 0.0);
            gather_nodal(&PointCouplings(conn), D, field, |p, a, out| {
                let w = conn.support_values(p)[a] * pts.mass[p];
                for i in 0..D {
                    out[i] += w * point_field[p][i];
                }
            });
            for (k, (v, &fixed)) in field.iter_mut().zip(&e.constrained).enumerate() {
                let m = self.nodal_mass[k / D];
                *v = if fixed || m <= 0.0 { 0.0 } else { *v / m };
            }
        }
    }

    /// Equilibrium acceleration of the committed state, a = M_L⁻¹ (f_ext − f_int), onto the
    /// points (a_p = Σ N_I a_I).
    fn initial_acceleration(&mut self) {
        self.map_to_nodes();
        self.engine.external_forces(1.0);
        let e = &mut self.engine;
        let conn = &e.conn;
        let pts = &e.model.points;
        let mut f_int = vec![0.0; e.f_ext.len()];
        let average = crate::engine::cell_average(&e.model, &e.cell_gradients);
        let stride = conn.stride();
        gather_nodal(&PointCouplings(conn), D, &mut f_int, |p, a, out| {
            let k = p * stride + a;
            let g = &conn.support_gradients(p)[a];
            let c = average.map_or(*g, |avg| avg.strain_gradient(k, g));
            let f = internal_force(pts.volume[p], &pts.stress[p], &c, average.map(|avg| avg.average(k)));
            for i in 0..D {
                out[i] += f[i];
            }
        });
        for (k, a) in self.acceleration.iter_mut().enumerate() {
            let m = self.nodal_mass[k / D];
            *a = if e.constrained[k] || m <= 0.0 { 0.0 } else { (e.f_ext[k] - f_int[k]) / m };
        }
        let acc = &self.acceleration;
        e.model.points.acceleration.par_iter_mut().enumerate().for_each(|(p, ap)| {
            *ap = SVector::zeros();
            for (&node, &n) in conn.support_nodes(p).iter().zip(conn.support_values(p)) {
                for i in 0..D {
                    ap[i] += n * acc[node as usize * D + i];
                }
            }
        });
    }

    /// Try one time step of length `dt` from the committed state; commit on success.
    fn attempt_step(&mut self, dt: f64) -> Result<NewtonReport, NewtonError<PointUpdateError>> {
        let (beta, gamma, alpha) = (self.settings.beta, self.settings.gamma, self.settings.bossak_alpha);
        // MPM: the grid is new every step, so the nodal state is mapped from the points.
        // FEM: the nodes persist and carry their own velocity and acceleration (mapped once,
        // at the start, by `initial_acceleration`).
        let fem = self.engine.model.mesh.is_some();
        if !fem {
            self.map_to_nodes();
        }
        self.engine.external_forces(1.0);
        let n = self.engine.num_dofs();
        self.predictor.clear();
        self.predictor
            .extend(self.velocity.iter().zip(&self.acceleration).map(|(v, a)| dt * v + dt * dt * (0.5 - beta) * a));
        self.bossak_term.clear();
        self.bossak_term.extend(self.acceleration.iter().map(|a| alpha * a));
        self.engine.du.clear();
        self.engine.du.extend_from_slice(&self.predictor[..n]);
        let inertia = Inertia {
            consistent: self.settings.mass == MassMatrix::Consistent,
            nodal_mass: &self.nodal_mass,
            factor: (1.0 - alpha) / (beta * dt * dt),
            predictor: &self.predictor,
            bossak_term: &self.bossak_term,
            velocity: &self.velocity,
            time_step: dt,
            x: &mut self.x,
            point_x: &mut self.point_x,
            force: &mut self.force,
        };
        let (mut system, du, newton) = self.engine.system(Some(inertia));
        let report = newton.solve(&mut system, du)?;

        // New nodal accelerations, then the points' velocity and acceleration (before the
        // commit moves the points; the connectivity is that of the step's start).
        let e = &mut self.engine;
        let a_new: Vec<f64> = e.du.iter().zip(&self.predictor).map(|(u, p)| (u - p) / (beta * dt * dt)).collect();
        let conn = &e.conn;
        let pts = &mut e.model.points;
        let interpolate = |p: usize, field: &[f64]| {
            let mut x = SVector::<f64, D>::zeros();
            for (&node, &w) in conn.support_nodes(p).iter().zip(conn.support_values(p)) {
                for i in 0..D {
                    x[i] += w * field[node as usize * D + i];
                }
            }
            x
        };
        if fem {
            for ((v, a), an) in self.velocity.iter_mut().zip(self.acceleration.iter_mut()).zip(&a_new) {
                *v += dt * ((1.0 - gamma) * *a + gamma * an);
                *a = *an;
            }
            let (vel, acc) = (&self.velocity, &self.acceleration);
            (pts.velocity.par_iter_mut(), pts.acceleration.par_iter_mut()).into_par_iter().enumerate().for_each(
                |(p, (v, a))| {
                    *v = interpolate(p, vel);
                    *a = interpolate(p, acc);
                },
            );
        } else {
            (pts.velocity.par_iter_mut(), pts.acceleration.par_iter_mut()).into_par_iter().enumerate().for_each(
                |(p, (v, a))| {
                    let an = interpolate(p, &a_new);
                    *v += (*a * (1.0 - gamma) + an * gamma) * dt;
                    *a = an;
                },
            );
        }
        e.commit();
        Ok(report)
    }

    /// Advance one time step, cutting back as needed.
    pub fn step(&mut self) -> Result<StepReport, StepError> {
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
        let done = advance(self, step, target, dt, self.settings.max_cutbacks)?;
        self.time = target;
        self.step = step;
        Ok(done.into_report(step, 1.0, self.time, self.engine.reactions.clone(), start))
    }
}

impl<const D: usize> CutBack<D> for Dynamic<D> {
    fn engine(&mut self) -> &mut Engine<D> {
        &mut self.engine
    }

    fn position(&self) -> f64 {
        self.time
    }

    fn attempt(&mut self, increment: f64, target: f64) -> Result<NewtonReport, NewtonError<PointUpdateError>> {
        if !self.started {
            self.initial_acceleration();
            self.started = true;
        }
        let h = increment.min(target - self.time);
        let report = self.attempt_step(h)?;
        self.time += h;
        Ok(report)
    }

    fn failure(&self, increment: f64, target: f64, error: &NewtonError<PointUpdateError>) -> (f64, String) {
        let h = increment.min(target - self.time);
        (1.0, format!("at time {:.6e} with time step {h:.3e}: {error}", self.time))
    }
}
