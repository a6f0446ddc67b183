//! What every implicit analysis does around its Newton solve: the point–node connectivity
//! of the committed state, the constrained dofs, the sparse pattern, the external forces,
//! the scratch trial state and the commit of a converged step (DESIGN.md "Data flow of one
//! implicit step", steps 1, 4). Quasi-static load stepping and Newmark dynamics differ only
//! in what they add to the Newton system and in how they advance time or load.

use crate::step::PointUpdateError;
use crate::step::{CellAverage, Inertia, PointCouplings, StepSystem, TrialState};
use crate::{StepError, StepReport};
use loam_grid::{ghost_faces, Connectivity, GhostFace, INACTIVE};
use loam_model::Model;
use loam_points::stretched_half_length;
use loam_solve::{
    gather_nodal, BlockPattern, LinearSolverKind, NewtonError, NewtonReport, NewtonSettings, NewtonSolver,
    SparseDirectSolver,
};
use nalgebra::SVector;
use rayon::prelude::*;
use std::time::Instant;

pub(crate) struct Engine<const D: usize> {
    pub model: Model<D>,
    pub conn: Connectivity<D>,
    conn_current: bool,
    pub pattern: BlockPattern,
    pub values: Vec<f64>,
    pub constrained: Vec<bool>,
    pub f_ext: Vec<f64>,
    pub reaction: Vec<f64>,
    /// Per constraint, the support reaction Σ (f_int − f_ext) over its nodes and fixed
    /// components, at the last committed state.
    pub reactions: Vec<[f64; 3]>,
    pub du: Vec<f64>,
    /// B-bar or assumed strain: the cell-averaged support gradients, `stride` per point
    /// (empty without them).
    pub cell_gradients: Vec<SVector<f64, D>>,
    /// Ghost-penalty faces over active nodes, scaled by γ M (empty without the penalty),
    /// and the node couplings they add to the pattern.
    pub ghost: Vec<GhostFace>,
    ghost_couplings: Vec<Vec<u32>>,
    pub trial: TrialState<D>,
    pub newton: NewtonSolver,
}

impl<const D: usize> Engine<D> {
    /// The linear solver is the one asked for, or chosen from the tangent: Cholesky when
    /// every material's tangent is symmetric and none softens, LU otherwise (never a
    /// silent symmetrisation; a softening tangent is indefinite and Cholesky would stop
    /// at the first negative pivot).
    pub fn new(model: Model<D>, newton: NewtonSettings, linear_solver: Option<LinearSolverKind>) -> Self {
        let (kind, source) = match linear_solver {
            Some(kind) => (kind, "as the settings ask"),
            None if model.symmetric_tangent() && !model.indefinite_tangent() => {
                (LinearSolverKind::Cholesky, "chosen from the tangent's symmetry and definiteness")
            }
            None => (LinearSolverKind::Lu, "chosen from the tangent's symmetry and definiteness"),
        };
        tracing::info!(solver = %kind, "linear solver {source}");
        Self {
            conn: Connectivity::new(model.basis),
            model,
            conn_current: false,
            pattern: BlockPattern::new(D),
            values: Vec::new(),
            constrained: Vec::new(),
            f_ext: Vec::new(),
            reaction: Vec::new(),
            reactions: Vec::new(),
            du: Vec::new(),
            cell_gradients: Vec::new(),
            ghost: Vec::new(),
            ghost_couplings: Vec::new(),
            trial: TrialState::default(),
            newton: NewtonSolver::new(newton, SparseDirectSolver::new(kind)),
        }
    }

    /// Connectivity of the committed configuration (computed once per committed state).
    /// `step` names the step in an error.
    pub fn connect(&mut self, step: usize) -> Result<(), StepError> {
        if self.conn_current {
            return Ok(());
        }
        let pts = &self.model.points;
        match &self.model.mesh {
            None => self
                .conn
                .compute(&self.model.grid, self.model.configuration(), &pts.half_length)
                .map_err(|source| StepError::PointOutsideGrid { step, source })?,
            Some(mesh) => self.conn.compute_mesh(mesh).map_err(|source| StepError::Element { step, source })?,
        }
        if let Some(gamma) = self.model.ghost_penalty {
            self.ghost = scaled_ghost_faces(&self.model, &self.conn, gamma);
            ghost_couplings(&self.ghost, self.conn.active_nodes().len(), &mut self.ghost_couplings);
        }
        self.pattern.update_with(&PointCouplings(&self.conn), &self.ghost_couplings);
        self.model.constrained_dofs(self.conn.active_nodes(), &mut self.constrained);
        if self.model.anti_locking.deviatoric_weight().is_some() {
            cell_averaged_gradients(&self.model, &self.conn, &mut self.cell_gradients);
        }
        self.conn_current = true;
        Ok(())
    }

    /// Force the next `connect` to recompute (e.g. before profiling a cold iteration).
    pub fn invalidate(&mut self) {
        self.conn_current = false;
    }

    /// Every constraint must hold at least one active node.
    pub fn check(&mut self, step: usize) -> Result<(), StepError> {
        self.connect(step)?;
        match self.model.constraint_without_nodes(self.conn.active_nodes()) {
            Some((index, c)) => Err(StepError::ConstraintTouchesNoNode { index, axis: c.axis, plane: c.plane }),
            None => Ok(()),
        }
    }

    pub fn num_dofs(&self) -> usize {
        self.conn.active_nodes().len() * D
    }

    /// External nodal forces at load factor `lambda`: the model's dead loads.
    pub fn external_forces(&mut self, lambda: f64) {
        let model = &self.model;
        let conn = &self.conn;
        self.f_ext.resize(conn.active_nodes().len() * D, 0.0);
        gather_nodal(&PointCouplings(conn), D, &mut self.f_ext, |p, a, out| {
            let n = conn.support_values(p)[a];
            let f = model.point_load_at(p, lambda);
            for i in 0..D {
                out[i] += n * f[i];
            }
        });
    }

    /// The Newton system of a step from the committed state, with the external forces
    /// already set and the trial buffers sized; the increment (zero unless the caller set a
    /// predictor) and the Newton solver are lent beside it.
    pub fn system<'a>(
        &'a mut self,
        inertia: Option<Inertia<'a>>,
    ) -> (StepSystem<'a, D>, &'a mut Vec<f64>, &'a mut NewtonSolver) {
        let n = self.num_dofs();
        self.du.resize(n, 0.0);
        self.trial.resize(self.model.points.len(), self.conn.stride(), self.model.points.history_stride());
        let system = StepSystem {
            model: &self.model,
            conn: &self.conn,
            pattern: &self.pattern,
            values: &mut self.values,
            constrained: &self.constrained,
            f_ext: &self.f_ext,
            reaction: &mut self.reaction,
            trial: &mut self.trial,
            inertia,
            cell_average: cell_average(&self.model, &self.cell_gradients),
            ghost: &self.ghost,
        };
        (system, &mut self.du, &mut self.newton)
    }

    /// Commit the converged trial state (THEORY.md §1): positions, F, volume, stress,
    /// elastic strain, history, and GIMP half-lengths stretched with F (iGIMP). The
    /// connectivity stays readable until the next `connect`.
    pub fn commit(&mut self) {
        let active = self.conn.active_nodes();
        self.reactions = self
            .model
            .constraints
            .iter()
            .map(|c| {
                let mut sum = [0.0; 3];
                for a in self.model.constraint_nodes(active, c) {
                    for i in (0..D).filter(|&i| c.fixed[i]) {
                        sum[i] += self.reaction.get(a * D + i).copied().unwrap_or(0.0);
                    }
                }
                sum
            })
            .collect();
        let conn = &self.conn;
        let du = &self.du;
        let trial = &self.trial;
        // Geometrically linear: the configuration (and with it the connectivity, the
        // pattern and the cell averages) stays that of the start.
        let moves = !self.model.geometrically_linear;
        let pts = &mut self.model.points;
        let hs = pts.history_stride();
        (
            pts.position.par_iter_mut(),
            pts.deformation_gradient.par_iter_mut(),
            pts.volume.par_iter_mut(),
            pts.half_length.par_iter_mut(),
            pts.half_length0.par_iter(),
        )
            .into_par_iter()
            .enumerate()
            .for_each(|(p, (x, f, v, l, l0))| {
                // Positions carry the displacement in either case (what the output reports);
                // a geometrically linear model computes on `Model::configuration`.
                for (&node, &n) in conn.support_nodes(p).iter().zip(conn.support_values(p)) {
                    for i in 0..D {
                        x[i] += n * du[node as usize * D + i];
                    }
                }
                let df = trial.delta_f[p];
                *f = df * *f;
                if moves {
                    *v *= df.determinant();
                    *l = stretched_half_length(l0, f);
                }
            });
        if let (Some(mesh), true) = (&mut self.model.mesh, moves) {
            // Every mesh node belongs to an element, so all are active.
            let g2a = &conn.active_nodes().grid_to_active;
            mesh.displace(|n| SVector::from_fn(|i, _| du[g2a[n] as usize * D + i]));
        }
        pts.stress.copy_from_slice(&trial.stress);
        pts.elastic_strain.copy_from_slice(&trial.elastic_strain);
        if hs > 0 {
            let n = pts.history.len();
            pts.history.copy_from_slice(&trial.history[..n]);
        }
        self.conn_current = !moves;
    }
}

/// The cell averages of the model's anti-locking treatment over the cell-averaged
/// gradients `cell_gradients`; `None` without anti-locking.
pub(crate) fn cell_average<'a, const D: usize>(
    model: &Model<D>,
    cell_gradients: &'a [SVector<f64, D>],
) -> Option<CellAverage<'a, D>> {
    model
        .anti_locking
        .deviatoric_weight()
        .map(|deviatoric_weight| CellAverage { gradients: cell_gradients, deviatoric_weight })
}

/// B-bar's b̄ of every point's support slot: Σ_q v_q ∂N_a(x_q) / Σ_q v_q over the points q
/// of its averaging cell (docs/theory.md §13), `stride` per point. Points are grouped by
/// sorting on the cell, so the sums run in a fixed order (deterministic).
pub(crate) fn cell_averaged_gradients<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
    out: &mut Vec<SVector<f64, D>>,
) {
    let n = model.points.len();
    let stride = conn.stride();
    let mut order: Vec<(usize, usize)> = (0..n).map(|p| (model.averaging_cell(p), p)).collect();
    order.sort_unstable();
    out.clear();
    out.resize(n * stride, SVector::zeros());
    let mut sums: Vec<(u32, SVector<f64, D>)> = Vec::new();
    for group in order.chunk_by(|a, b| a.0 == b.0) {
        sums.clear();
        let mut volume = 0.0;
        for &(_, p) in group {
            let v = model.points.volume[p];
            volume += v;
            for (&node, g) in conn.support_nodes(p).iter().zip(conn.support_gradients(p)) {
                match sums.iter_mut().find(|(m, _)| *m == node) {
                    Some((_, s)) => *s += g * v,
                    None => sums.push((node, g * v)),
                }
            }
        }
        for &(_, p) in group {
            for (k, node) in conn.support_nodes(p).iter().enumerate() {
                let s = sums.iter().find(|(m, _)| m == node).map_or(SVector::zeros(), |(_, s)| *s);
                out[p * stride + k] = s / volume;
            }
        }
    }
}

/// An implicit analysis that advances a load factor or a time by Newton steps, each of which
/// may be cut back (THEORY.md §7): the one cut-back rule for quasi-static and dynamic runs.
pub(crate) trait CutBack<const D: usize> {
    fn engine(&mut self) -> &mut Engine<D>;
    /// The load factor or time of the committed state.
    fn position(&self) -> f64;
    /// Try to advance the committed state by `increment`, not past `target`; commit on
    /// success, change nothing on failure.
    fn attempt(&mut self, increment: f64, target: f64) -> Result<NewtonReport, NewtonError<PointUpdateError>>;
    /// The load factor and a description of a failed attempt, for the error.
    fn failure(&self, increment: f64, target: f64, error: &NewtonError<PointUpdateError>) -> (f64, String);
}

/// What advancing to one step's target took.
pub(crate) struct Advanced {
    pub substeps: usize,
    pub cutbacks: usize,
    pub iterations: usize,
    /// Relative residuals of the last sub-step.
    pub residuals: Vec<f64>,
    /// Relative residuals of the converged sub-step with the most corrections.
    pub hardest_residuals: Vec<f64>,
    pub active_nodes: usize,
    pub dofs: usize,
}

impl Advanced {
    /// The report of step `step`, which reached `load_factor` and `time`, started at `start`.
    pub fn into_report(
        self,
        step: usize,
        load_factor: f64,
        time: f64,
        reactions: Vec<[f64; 3]>,
        start: Instant,
    ) -> StepReport {
        StepReport {
            step,
            load_factor,
            time,
            substeps: self.substeps,
            cutbacks: self.cutbacks,
            iterations: self.iterations,
            residuals: self.residuals,
            hardest_residuals: self.hardest_residuals,
            active_nodes: self.active_nodes,
            dofs: self.dofs,
            reactions,
            wall_time: start.elapsed(),
        }
    }
}

/// Advance `a` to `target` in step `step`: try the whole increment; halve it after a failed
/// attempt, and double it again after two converged sub-steps in a row, so that one hard
/// stretch does not hold the rest of the step at the smallest size. Stop with
/// `NotConverged` when an attempt fails at `max_cutbacks` halvings. `scale` sets the
/// round-off allowance on reaching the target (1 for load factors, Δt for time).
pub(crate) fn advance<const D: usize, A: CutBack<D>>(
    a: &mut A,
    step: usize,
    target: f64,
    scale: f64,
    max_cutbacks: usize,
) -> Result<Advanced, StepError> {
    let full = target - a.position();
    let (mut depth, mut streak) = (0usize, 0usize);
    let mut done = Advanced {
        substeps: 0,
        cutbacks: 0,
        iterations: 0,
        residuals: Vec::new(),
        hardest_residuals: Vec::new(),
        active_nodes: 0,
        dofs: 0,
    };
    while a.position() < target - 1e-12 * target.abs().max(scale) {
        let increment = full * 0.5f64.powi(depth as i32);
        let engine = a.engine();
        engine.connect(step)?;
        done.active_nodes = engine.conn.active_nodes().len();
        done.dofs = done.active_nodes * D;
        match a.attempt(increment, target) {
            Ok(report) => {
                done.substeps += 1;
                done.iterations += report.iterations();
                if report.residuals.len() > done.hardest_residuals.len() {
                    done.hardest_residuals.clone_from(&report.residuals);
                }
                done.residuals = report.residuals;
                streak += 1;
                if depth > 0 && streak >= 2 {
                    depth -= 1;
                    streak = 0;
                }
            }
            Err(e) => {
                done.cutbacks += 1;
                streak = 0;
                let (load_factor, reason) = a.failure(increment, target, &e);
                // A cut-back is the step control doing its job (the run log and the progress
                // count them; strength reduction fails trials on purpose), so it is
                // information, not a warning; a run that cannot go on returns an error.
                tracing::info!(step, position = a.position(), increment, error = %e, "Newton failed; cutting the step back");
                if depth >= max_cutbacks {
                    return Err(StepError::NotConverged {
                        step,
                        load_factor,
                        cutbacks: done.cutbacks - 1,
                        reason,
                        residuals: e.report().residuals.clone(),
                    });
                }
                depth += 1;
            }
        }
    }
    Ok(done)
}

/// The ghost faces of the committed configuration (docs/theory.md §15): cell fill from the
/// volumes of the points whose centres lie in each cell, faces of cut cells whose nodes
/// are all active, renumbered to active nodes and scaled by γ times the largest P-wave
/// modulus of the points in the face's two cells (so a soft layer is not stiffened by a
/// stiff one elsewhere).
pub(crate) fn scaled_ghost_faces<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
    gamma: f64,
) -> Vec<GhostFace> {
    let grid = &model.grid;
    let (mut fill, mut modulus) = (vec![0.0; grid.num_cells()], vec![0.0f64; grid.num_cells()]);
    let moduli: Vec<f64> = model.materials.iter().map(|m| m.p_wave_modulus()).collect();
    let pts = &model.points;
    for ((x, v), &m) in model.configuration().iter().zip(&pts.volume).zip(&pts.material) {
        let c = grid.cell_index(grid.cell_coords(x));
        fill[c] += v / grid.cell_volume();
        modulus[c] = modulus[c].max(moduli[m as usize]);
    }
    let to_active = &conn.active_nodes().grid_to_active;
    let mut faces = ghost_faces(grid, &fill, |g| to_active[g] != INACTIVE);
    for face in &mut faces {
        let m = modulus[face.cells[0]].max(modulus[face.cells[1]]);
        face.nodes.iter_mut().for_each(|g| *g = to_active[*g as usize]);
        face.matrix.iter_mut().for_each(|v| *v *= gamma * m);
    }
    faces
}

/// The node couplings the ghost faces add to the sparsity pattern: every node of a face
/// with every other (lists are reused; `update_with` sorts and dedups them).
pub(crate) fn ghost_couplings(faces: &[GhostFace], active_nodes: usize, couplings: &mut Vec<Vec<u32>>) {
    couplings.iter_mut().for_each(Vec::clear);
    couplings.resize(active_nodes, Vec::new());
    for face in faces {
        for &a in &face.nodes {
            couplings[a as usize].extend_from_slice(&face.nodes);
        }
    }
}
