//! The stages every implicit step runs, quasi-static and dynamic alike (docs/theory.md §1):
//! connect the committed points to the background, the external forces, Newton's method —
//! assemble, solve, update points, check — and the commit of a converged step. The two
//! analyses differ only in what they add around these stages (prescribed displacements,
//! the Newmark predictor and inertia) and in how they advance the load or time.

use crate::cell_average::{cell_averaged_gradients, CellAverage, CellGroups};
use crate::follower::{add_follower_tangent, follower_couplings, has_follower, FollowerInputs};
use crate::frames::LocalFrames;
use crate::ghost::{ghost_couplings, scaled_ghost_faces};
use crate::inertia::Inertia;
use crate::points::{update_points, PointInputs, PointUpdateError, TrialState};
use crate::residual::{residual, water_body_force, ResidualInputs};
use crate::tangent::{assemble, PointCouplings, TangentInputs};
use crate::StepError;
use loam_grid::{Connectivity, GhostFace, NodeLayout};
use loam_kernels::{
    advance_deformation, check_constraints_connected, connect, interpolate_add, scatter_nodal, trial_vertices,
    LoadSupports,
};
use loam_model::{AntiLocking, FreeBody, Kinematics, LoadLevel, Model, ModelError, PointChange};
use loam_solve::{
    norm, BlockPattern, LinearSolveError, LinearSolveStats, LinearSolver, LinearSolverChoice, LinearSolverKind,
    LinearSystem, NewtonControl, NewtonError, NewtonReport, NewtonSettings, NodeLattice, SparseDirectSolver,
    SymmetricPart, SystemMatrix,
};
use nalgebra::SVector;
use rayon::prelude::*;

/// The state of the implicit stages over one model: the committed model, the connectivity
/// of its committed configuration, the step's increment, trial state and linear system.
pub(crate) struct Engine<const D: usize> {
    pub model: Model<D>,
    /// The fields of every active node and their dofs: one body's displacement (the
    /// kernels of this crate assemble that one field, D dofs a node).
    pub layout: NodeLayout,
    pub conn: Connectivity<D>,
    /// The connectivity is that of the committed configuration (recomputed after a commit
    /// that moved the points).
    conn_current: bool,
    pub pattern: BlockPattern,
    /// The tangent, in the layout of the linear solver.
    pub matrix: SystemMatrix,
    /// The held dofs, in the nodes' frames (`frames`).
    pub constrained: Vec<bool>,
    /// The local frames at the nodes of inclined rollers.
    pub frames: LocalFrames<D>,
    pub f_ext: Vec<f64>,
    /// The loads' vertices on the active nodes, and the level the external forces are at.
    loads: LoadSupports,
    level: LoadLevel,
    /// f_ext with the follower loads at the trial increment (empty without them).
    f_follower: Vec<f64>,
    /// The water's force per unit volume on each point, −∇p_w (empty without water), at
    /// gravity's factor `body_factor` of the external forces.
    pub water_force: Vec<SVector<f64, D>>,
    body_factor: f64,
    /// f_int − f_ext on the constrained dofs at the last residual; zero on free dofs.
    reaction: Vec<f64>,
    /// Per constraint, the support reaction Σ (f_int − f_ext) over its nodes and fixed
    /// components, at the last committed state.
    pub reactions: Vec<[f64; 3]>,
    /// The step's increment Δu, per active dof.
    pub du: Vec<f64>,
    residual: Vec<f64>,
    /// −R, the right-hand side of a correction's solve.
    rhs: Vec<f64>,
    correction: Vec<f64>,
    /// The increment a Newton solve started from, for its second try.
    du_start: Vec<f64>,
    /// Whether a correction of the solve under way raised the residual's norm or left a
    /// point that cannot be updated: where none did, a second try would be the first again.
    overshot: bool,
    /// B-bar or assumed strain: the cell-averaged support gradients, `stride` per point
    /// (empty without them).
    cell_gradients: Vec<SVector<f64, D>>,
    /// With anti-locking, the points of every cell (element) of the connectivity.
    groups: CellGroups,
    /// Ghost-penalty faces over active nodes, scaled by γ M (empty without the penalty),
    /// and the node couplings they add to the pattern.
    ghost: Vec<GhostFace>,
    /// The couplings the ghost faces and the follower loads add to the pattern.
    extra_couplings: Vec<Vec<u32>>,
    trial: TrialState<D>,
    newton: NewtonSettings,
    linear: Box<dyn LinearSolver>,
    /// The direct solver an iterative one falls back on when a Krylov solve fails (made on
    /// the first failure, below `DIRECT_FALLBACK_MAX_DOFS`), and how often it did.
    fallback: Option<SparseDirectSolver>,
    fallbacks: usize,
    /// What the settings asked, resolved against the size of the first connectivity.
    linear_choice: LinearSolverChoice,
    linear_resolved: bool,
    /// The active nodes' grid coordinates, for multigrid (empty otherwise), and the
    /// pattern generation they belong to.
    lattice: Option<NodeLattice>,
}

/// With the automatic choice, multigrid CG from this many dofs, by dimension, for symmetric
/// positive definite tangents (docs/theory.md §19 gives the measurements): in 3D just above
/// the measured crossover (3 000 to 4 000 dofs); in 2D well above it (8 000), so that the
/// plastic 2D problems, where the iterative solver is not yet verified, keep the direct one.
const ITERATIVE_FROM_DOFS: [usize; 3] = [usize::MAX, 100_000, 5_000];

/// In 3D, where the LU is most of a correction, a non-symmetric tangent of 20 000 dofs or
/// more that the settings did not force onto LU (`Auto`, `Direct`) is solved by GMRES
/// preconditioned by the LDLᵀ factor of its symmetric part, with at most 100 iterations
/// before its LU (docs/theory.md §19: on the 1 m slope, 35 217 dofs, the symmetric part's
/// factor costs a fifth of the LU, an iteration a hundredth, and GMRES took 1 to 59; on
/// the 2 m one, 5 187 dofs, the LU is cheap and near collapse GMRES did not converge, so
/// its strength search took longer). In 2D the LU costs a few solves, and stays.
const SYMMETRIC_PART: [Option<SymmetricPart>; 3] =
    [None, None, Some(SymmetricPart { from_dofs: 20_000, max_iterations: 100 })];

/// A failed Krylov solve is repeated by sparse LU up to this many dofs, by dimension: about
/// 4 GB of factor in 3D (32³ cells took 3 GB with Cholesky), far less in 2D. Above it the
/// step is cut back.
const DIRECT_FALLBACK_MAX_DOFS: [usize; 3] = [usize::MAX, 2_000_000, 120_000];

/// `groups` when the model updates its points with F-bar (a free function, so that it
/// borrows only the two fields it reads).
fn fbar_groups<'a, const D: usize>(model: &Model<D>, groups: &'a CellGroups) -> Option<&'a CellGroups> {
    (model.anti_locking() == AntiLocking::FBar).then_some(groups)
}

impl<const D: usize> Engine<D> {
    /// The linear solver is the one asked for, or chosen from the tangent: Cholesky when
    /// every material's tangent is symmetric, none softens, no load follows the surface
    /// and no buoyancy follows a changing volume, LU otherwise (never a silent
    /// symmetrisation; a softening tangent is indefinite and Cholesky would stop at the
    /// first negative pivot; the stiffness of a follower load, or of the buoyancy on a
    /// point's current volume in finite strain, and the friction of a slipping node on a
    /// frictional plane are not symmetric). `indefinite` says the analysis goes where the
    /// tangent is indefinite whatever the model (past a limit point).
    pub fn new(model: Model<D>, newton: NewtonSettings, linear_choice: LinearSolverChoice, indefinite: bool) -> Self {
        let definite = !indefinite
            && model.symmetric_tangent()
            && !model.can_soften()
            && !has_follower(model.loads())
            && (model.water().is_none() || model.kinematics() == Kinematics::SmallStrain)
            && model.frictional_planes().iter().all(|p| p.friction() == 0.0);
        let kind = match linear_choice {
            LinearSolverChoice::Forced(kind) => kind,
            LinearSolverChoice::Iterative => LinearSolverKind::for_tangent(true, definite),
            LinearSolverChoice::Direct | LinearSolverChoice::Auto => LinearSolverKind::for_tangent(false, definite),
        };
        let linear = Self::solver_for(kind, linear_choice);
        let layout = NodeLayout::motion(D);
        Self {
            conn: Connectivity::new(model.basis()),
            model,
            pattern: BlockPattern::new(layout.dofs_per_node()),
            layout,
            conn_current: false,
            matrix: SystemMatrix::new(linear.layout()),
            constrained: Vec::new(),
            frames: LocalFrames::default(),
            f_ext: Vec::new(),
            loads: LoadSupports::default(),
            level: LoadLevel::Factor(0.0),
            f_follower: Vec::new(),
            water_force: Vec::new(),
            body_factor: 0.0,
            reaction: Vec::new(),
            reactions: Vec::new(),
            du: Vec::new(),
            residual: Vec::new(),
            rhs: Vec::new(),
            correction: Vec::new(),
            du_start: Vec::new(),
            overshot: false,
            cell_gradients: Vec::new(),
            groups: CellGroups::default(),
            ghost: Vec::new(),
            extra_couplings: Vec::new(),
            trial: TrialState::default(),
            newton,
            linear,
            fallback: None,
            fallbacks: 0,
            linear_choice,
            linear_resolved: false,
            lattice: None,
        }
    }

    /// The solver of `kind` under `choice`: LU preconditions by the symmetric part where
    /// `SYMMETRIC_PART` says so, unless the settings forced the method.
    fn solver_for(kind: LinearSolverKind, choice: LinearSolverChoice) -> Box<dyn LinearSolver> {
        match SYMMETRIC_PART[D - 1] {
            Some(part) if kind == LinearSolverKind::Lu && !matches!(choice, LinearSolverChoice::Forced(_)) => {
                Box::new(SparseDirectSolver::new(kind).with_symmetric_part(part))
            }
            _ => kind.solver(),
        }
    }

    /// A new solver as the engine's was made (for profiling it apart).
    pub fn new_linear_solver(&self) -> Box<dyn LinearSolver> {
        Self::solver_for(self.linear.kind(), self.linear_choice)
    }

    /// Corrections whose Krylov solve failed and were solved by sparse LU, so far.
    pub fn direct_fallbacks(&self) -> usize {
        self.fallbacks
    }

    /// Whether the connectivity is that of the committed points.
    pub fn is_connected(&self) -> bool {
        self.conn_current
    }

    pub fn linear_solver(&self) -> &dyn LinearSolver {
        self.linear.as_ref()
    }

    /// Use `solver` instead of the settings' choice (as if forced; an iterative one still
    /// needs a grid).
    pub fn set_linear_solver(&mut self, solver: Box<dyn LinearSolver>) {
        self.linear_choice = LinearSolverChoice::Forced(solver.kind());
        // The next connect resolves (logs) the new solver.
        self.install_linear_solver(solver, false);
    }

    /// `solver` in place of the engine's, `resolved` or to be resolved at the next connect,
    /// which gives it the lattice it may want.
    fn install_linear_solver(&mut self, solver: Box<dyn LinearSolver>, resolved: bool) {
        self.matrix = SystemMatrix::new(solver.layout());
        self.linear = solver;
        self.linear_resolved = resolved;
        self.conn_current = false;
    }

    /// The linear solver as resolved at the first connectivity (what a resumed run must
    /// keep, whatever its size then); `None` before.
    pub fn resolved_linear_solver(&self) -> Option<LinearSolverKind> {
        self.linear_resolved.then(|| self.linear.kind())
    }

    /// Resume with the linear solver `kind` resolved by the run that saved the state
    /// (nothing when `None`: the first step resolves it), under the settings' own choice
    /// (so that `new_linear_solver` makes the same solver, with its symmetric part).
    pub fn resume_linear_solver(&mut self, kind: Option<LinearSolverKind>) {
        if let Some(kind) = kind {
            self.install_linear_solver(Self::solver_for(kind, self.linear_choice), true);
        }
        self.conn_current = false;
    }

    /// At the first connectivity: the automatic choice turns to multigrid CG on a grid from
    /// `ITERATIVE_FROM_DOFS` where the tangent is symmetric positive definite (BiCGStab is
    /// only taken when asked for); an iterative solver asked for on a body-fitted mesh (which
    /// has no lattice for multigrid) is an error. Logs the solver and why.
    fn resolve_linear_solver(&mut self) -> Result<(), StepError> {
        if self.linear_resolved {
            return Ok(());
        }
        self.linear_resolved = true;
        let on_grid = self.model.background().mesh().is_none();
        let dofs = self.num_dofs();
        let source = match self.linear_choice {
            LinearSolverChoice::Auto
                if on_grid
                    && dofs >= ITERATIVE_FROM_DOFS[D - 1]
                    && self.linear.kind() == LinearSolverKind::Cholesky =>
            {
                self.linear = LinearSolverKind::Cg.solver();
                self.matrix = SystemMatrix::new(self.linear.layout());
                "from the number of dofs (iterative from this size) and the tangent (symmetric positive definite)"
            }
            LinearSolverChoice::Auto => {
                "from the tangent's symmetry and definiteness (direct below the size for iteration)"
            }
            LinearSolverChoice::Forced(_) => "as the settings ask",
            _ => "from the tangent's symmetry and definiteness, in the family the settings ask",
        };
        if self.linear.wants_lattice() && !on_grid {
            return Err(StepError::LinearSolver(LinearSolveError::NoLattice));
        }
        tracing::info!(solver = %self.linear.description(), dofs, "linear solver chosen {source}");
        Ok(())
    }

    /// Stage 1, connect: the connectivity of the committed configuration, its constrained
    /// dofs, ghost faces, sparsity pattern and cell averages (computed once per committed
    /// state). `step` names the step in an error.
    pub fn connect(&mut self, step: usize) -> Result<(), StepError> {
        if self.conn_current {
            return Ok(());
        }
        connect(&self.model, &self.layout, &mut self.conn, &mut self.constrained, step)?;
        if !self.model.inclined_rollers().is_empty() || !self.model.frictional_planes().is_empty() {
            self.frames.connect(&self.model, self.conn.active_nodes(), &mut self.constrained);
        }
        self.loads.connect(&self.model, self.conn.active_nodes(), step)?;
        if let Some(gamma) = self.model.ghost_penalty() {
            self.ghost = scaled_ghost_faces(&self.model, &self.conn, gamma);
        }
        ghost_couplings(&self.ghost, self.conn.active_nodes().len(), &mut self.extra_couplings);
        follower_couplings(&self.model, &self.conn, &self.loads, &mut self.extra_couplings);
        let changed = self.pattern.update_with(&PointCouplings(&self.conn), &self.extra_couplings);
        self.resolve_linear_solver()?;
        let on_grid = self.model.background().mesh().is_none();
        if on_grid && self.linear.uses_lattice() && (changed || self.lattice.is_none()) {
            self.lattice = Some(self.node_lattice());
        }
        if self.model.anti_locking() != AntiLocking::None {
            self.groups.build(&self.model);
        }
        if self.model.anti_locking().deviatoric_weight().is_some() {
            let scratch = &mut self.trial.group_sums;
            cell_averaged_gradients(&self.model, &self.conn, &self.groups, scratch, &mut self.cell_gradients);
        }
        self.conn_current = true;
        Ok(())
    }

    /// The grid coordinates of the active nodes.
    fn node_lattice(&self) -> NodeLattice {
        let background = self.model.background();
        let coords = self
            .conn
            .active_nodes()
            .active_to_grid
            .iter()
            .map(|&g| {
                let c = background.lattice_coordinates(g as usize).expect("checked: the background is a grid");
                std::array::from_fn(|a| if a < D { c[a] as u32 } else { 0 })
            })
            .collect();
        NodeLattice::new(coords)
    }

    /// Add or remove points between steps ([`Model::change_points`]); the next step
    /// connects anew.
    pub fn change_points(&mut self, change: PointChange<D>) -> Result<usize, ModelError> {
        self.invalidate();
        self.model.change_points(change)
    }

    /// Force the next `connect` to recompute (e.g. before profiling a cold iteration).
    pub fn invalidate(&mut self) {
        self.conn_current = false;
    }

    /// Before a first step: the points connect, and every constraint holds a node.
    pub fn check(&mut self, step: usize) -> Result<(), StepError> {
        self.connect(step)?;
        Ok(check_constraints_connected(&self.model, &self.conn)?)
    }

    /// The bodies with rigid-body motions no constraint holds on the active nodes.
    pub fn free_rigid_bodies(&self) -> Vec<FreeBody> {
        self.model.free_rigid_bodies(&self.conn)
    }

    pub fn num_dofs(&self) -> usize {
        self.layout.num_dofs(self.conn.active_nodes().len())
    }

    /// Stage 3, external forces at `level` (a load factor, or the time of a dynamic step):
    /// the model's dead loads on the points scattered to the nodes, then the dead loads on
    /// its surfaces spread to them, and the water's force on the points at that level. Follower
    /// loads are added with the trial increment in each residual.
    pub fn external_forces(&mut self, level: LoadLevel) {
        let lambda = level.body_factor();
        self.body_factor = lambda;
        self.update_water_forces();
        let (model, conn, water) = (&self.model, &self.conn, &self.water_force);
        let volume = model.points().volume();
        self.f_ext.resize(self.layout.num_dofs(conn.active_nodes().len()), 0.0);
        // The water's force on the committed volumes joins the point loads (a finite-strain
        // residual adds its change with the volume).
        scatter_nodal(conn, D, &mut self.f_ext, |p, a, out| {
            let n = conn.support_values(p)[a];
            let f = model.point_load_at(p, lambda) * n + water_body_force(water, p, volume[p], n);
            for i in 0..D {
                out[i] += f[i];
            }
        });
        self.loads.add_dead(model, level, &mut self.f_ext);
        self.level = level;
    }

    /// The external force per unit load factor, ∂f_ext/∂λ, into `out`, on the free dofs
    /// and in the nodes' frames (as a linear solve takes it); leaves the external forces at
    /// load factor `lambda`. Dead loads, gravity and the water's force follow the load
    /// factor linearly, so the difference of two levels is exact.
    pub fn load_direction(&mut self, lambda: f64, out: &mut Vec<f64>) {
        self.external_forces(LoadLevel::Factor(lambda + 1.0));
        out.clone_from(&self.f_ext);
        self.external_forces(LoadLevel::Factor(lambda));
        let held = self.frames.assembly_mask(&self.constrained);
        for ((d, f), &h) in out.iter_mut().zip(&self.f_ext).zip(held) {
            *d = if h { 0.0 } else { *d - f };
        }
        self.frames.hold_in_load(out);
    }

    /// The water's force per unit volume on every point, b_w = −∇p_w (the buoyancy below a
    /// level water table; docs/theory.md §18), at the points' committed places and gravity's
    /// factor of the external forces. Nothing without water.
    pub fn update_water_forces(&mut self) {
        let model = &self.model;
        if model.water().is_none() {
            return;
        }
        let bf = self.body_factor;
        self.water_force = (0..model.points().len()).into_par_iter().map(|p| model.water_force(p, bf)).collect();
    }

    /// The external force of the committed state with the follower loads on their
    /// committed places (the dynamic start's equilibrium).
    pub fn external_forces_at_rest(&self) -> Vec<f64> {
        let mut f = self.f_ext.clone();
        self.loads.add_follower(&self.model, self.level, |_, l| l.positions().to_vec(), &mut f);
        f
    }

    /// `f_follower` = f_ext plus the follower loads at the trial increment `du`; false (and
    /// nothing done) without follower loads.
    fn follower_forces(&mut self) -> bool {
        if !has_follower(self.model.loads()) {
            return false;
        }
        self.f_follower.clone_from(&self.f_ext);
        let (conn, du, delta_f) = (&self.conn, &self.du, &self.trial.delta_f);
        let points = self.model.points();
        let places = |_, load: &_| trial_vertices(conn, load, points, du, delta_f);
        self.loads.add_follower(&self.model, self.level, places, &mut self.f_follower);
        true
    }

    /// Stage 4, Newton's method (docs/theory.md §6) from the increment in `du` (zero, a
    /// prescribed displacement or a predictor): update the points and the residual, then
    /// until converged assemble, solve, update the points along the correction (shortened
    /// where the residual grew) and check. Where that fails with whole corrections, one of
    /// which raised the residual, once more from the same increment with the line search
    /// (`NewtonSettings::retry`); where both fail, the first failure is the error.
    /// `inertia` adds the Newmark terms of a dynamic step. On success `du` holds the
    /// converged increment and the trial state is the step's; nothing is committed either
    /// way.
    pub fn newton(&mut self, inertia: Option<&mut Inertia>) -> Result<NewtonReport, NewtonError<PointUpdateError>> {
        self.newton_under(self.newton, inertia)
    }

    /// [`Engine::newton`] under `settings` instead of the analysis's own.
    pub fn newton_under(
        &mut self,
        settings: NewtonSettings,
        mut inertia: Option<&mut Inertia>,
    ) -> Result<NewtonReport, NewtonError<PointUpdateError>> {
        self.size_buffers();
        let Some(retry) = settings.retry() else {
            return self.newton_with(settings, inertia);
        };
        self.du_start.clone_from(&self.du);
        self.overshot = false;
        let first = match self.newton_with(settings, inertia.as_deref_mut()) {
            Err(first) => first,
            converged => return converged,
        };
        if !self.overshot {
            // No correction raised the residual, so the line search would shorten none:
            // the second try would repeat the first.
            return Err(first);
        }
        tracing::debug!(%first, "Newton tried again from the same start, with the line search");
        self.du.copy_from_slice(&self.du_start);
        match self.newton_with(retry, inertia) {
            Ok(report) => Ok(report.after_failed_try(first.report())),
            // The first failure says what whole corrections met (a lost pivot traced to
            // slivers, a divergence), which is what a cut-back reports.
            Err(second) => {
                tracing::debug!(%second, "the second try failed too");
                Err(first)
            }
        }
    }

    /// [`Engine::newton`]'s loop under `settings`, from the increment `du` holds.
    fn newton_with(
        &mut self,
        settings: NewtonSettings,
        mut inertia: Option<&mut Inertia>,
    ) -> Result<NewtonReport, NewtonError<PointUpdateError>> {
        self.frames.reset_contacts(&mut self.constrained);
        let reference = self
            .update_points_and_residual(inertia.as_deref_mut())
            .map_err(|source| NewtonError::Problem { source, report: NewtonReport::default() })?;
        let mut newton = NewtonControl::start(settings, norm(&self.residual), reference)?;
        loop {
            newton.next_iteration()?;
            self.assemble(inertia.as_deref());
            let fallbacks = self.fallbacks;
            let (iterations, setup) = self.solve(newton.linear_tolerance()).map_err(|e| newton.linear_failure(e))?;
            newton.linear_solved(iterations, setup, self.fallbacks > fallbacks);
            let (reference, alpha) =
                self.update_along_correction(&newton, inertia.as_deref_mut()).map_err(|e| newton.problem_failure(e))?;
            newton.corrected(alpha * norm(&self.correction), norm(&self.du));
            // An iterate where a contact changed state is not an equilibrium of its own.
            if newton.converged(norm(&self.residual), reference)? && !self.frames.contact_changed() {
                return Ok(newton.into_report());
            }
        }
    }

    /// Stage 4c, update the points at the increment the correction just reached, with the
    /// line search: while the residual's norm is above the one the correction was solved
    /// for (or a point cannot be updated there) and `newton` allows, the same at a shorter
    /// step along the correction (docs/theory.md §6). Returns the reference force norm and
    /// the step length kept; a point that cannot be updated at the last length tried is
    /// the error.
    fn update_along_correction(
        &mut self,
        newton: &NewtonControl,
        mut inertia: Option<&mut Inertia>,
    ) -> Result<(f64, f64), PointUpdateError> {
        // `rhs` holds −R of the iterate the correction was solved from.
        let before = norm(&self.rhs);
        let (mut alpha, mut backtracks) = (1.0, 0);
        loop {
            let updated = self.update_points_and_residual(inertia.as_deref_mut());
            let after = if updated.is_ok() { norm(&self.residual) } else { f64::INFINITY };
            self.overshot |= after > before || after.is_nan();
            let Some(shorter) = newton.backtrack(before, after, alpha, backtracks) else {
                return updated.map(|reference| (reference, alpha));
            };
            for (u, c) in self.du.iter_mut().zip(&self.correction) {
                *u -= (alpha - shorter) * c;
            }
            tracing::debug!(from = alpha, to = shorter, before, after, "Newton correction shortened");
            (alpha, backtracks) = (shorter, backtracks + 1);
        }
    }

    /// Size the increment (zero-filled where new), the residual and the trial state to the
    /// connectivity.
    pub fn size_buffers(&mut self) {
        let n = self.num_dofs();
        self.du.resize(n, 0.0);
        self.residual.resize(n, 0.0);
        self.rhs.resize(n, 0.0);
        self.correction.resize(n, 0.0);
        let pts = self.model.points();
        self.trial.resize(pts.len(), self.conn.stride(), pts.history_stride(), self.fbar().is_some());
    }

    /// Update points, then the residual at `du`; returns the reference force norm.
    pub fn update_points_and_residual(&mut self, inertia: Option<&mut Inertia>) -> Result<f64, PointUpdateError> {
        self.frames.settle(&mut self.du, &mut self.constrained);
        let average = CellAverage::of(&self.model, &self.cell_gradients);
        let fbar = fbar_groups(&self.model, &self.groups);
        let inputs = PointInputs { model: &self.model, conn: &self.conn, average, fbar, du: &self.du };
        update_points(inputs, &mut self.trial)?;
        // The follower loads act on the vertices the trial state carries.
        let follower = self.follower_forces();
        let average = CellAverage::of(&self.model, &self.cell_gradients);
        let inputs = ResidualInputs {
            conn: &self.conn,
            average,
            ghost: &self.ghost,
            constrained: self.frames.assembly_mask(&self.constrained),
            f_ext: if follower { &self.f_follower } else { &self.f_ext },
            mass: self.model.points().mass(),
            water_force: if self.model.kinematics() == Kinematics::FiniteStrain { &self.water_force } else { &[] },
            committed_volume: self.model.points().volume(),
            axisymmetric: self.model.axisymmetric(),
        };
        let reference = residual(&inputs, &self.trial, inertia, &self.du, &mut self.residual, &mut self.reaction);
        if self.frames.is_empty() {
            return Ok(reference);
        }
        let held = self.frames.hold_in_residual(&mut self.residual, &mut self.reaction, &mut self.constrained);
        Ok((reference * reference + held).sqrt())
    }

    /// Assemble the tangent at the trial state.
    pub fn assemble(&mut self, inertia: Option<&Inertia>) {
        let inputs = TangentInputs {
            conn: &self.conn,
            pattern: &self.pattern,
            average: CellAverage::of(&self.model, &self.cell_gradients),
            ghost: &self.ghost,
            constrained: self.frames.assembly_mask(&self.constrained),
            mass: self.model.points().mass(),
            water_force: if self.model.kinematics() == Kinematics::FiniteStrain { &self.water_force } else { &[] },
            axisymmetric: self.model.axisymmetric(),
            fbar: self.fbar().is_some(),
        };
        assemble(&inputs, &self.trial, inertia, &mut self.matrix);
        if has_follower(self.model.loads()) {
            let inputs = FollowerInputs {
                model: &self.model,
                conn: &self.conn,
                supports: &self.loads,
                level: self.level,
                du: &self.du,
                delta_f: &self.trial.delta_f,
                average: CellAverage::of(&self.model, &self.cell_gradients),
                fbar: self.fbar().map(|_| &self.trial),
            };
            add_follower_tangent(
                &inputs,
                &self.pattern,
                self.frames.assembly_mask(&self.constrained),
                &mut self.matrix,
            );
        }
        if !self.frames.is_empty() {
            self.frames.hold_in_matrix(&self.pattern, &mut self.matrix);
        }
    }

    /// Solve K δ = −R to the relative residual `tolerance` (an iterative solver; a direct
    /// one does better) and add the correction to the increment: Δu ← Δu + δ. Returns the
    /// Krylov iterations and the time the solver's set-up took.
    fn solve(&mut self, tolerance: f64) -> Result<(usize, std::time::Duration), LinearSolveError> {
        let setup = self.prepare_solver()?;
        let (mut rhs, mut correction) = (std::mem::take(&mut self.rhs), std::mem::take(&mut self.correction));
        for (b, r) in rhs.iter_mut().zip(&self.residual) {
            *b = -r;
        }
        let solved = self.solve_prepared(&rhs, &mut correction, tolerance);
        (self.rhs, self.correction) = (rhs, correction);
        let stats = solved?;
        for (u, c) in self.du.iter_mut().zip(&self.correction) {
            *u += c;
        }
        Ok((stats.iterations, setup + stats.factorised))
    }

    /// Prepare the linear solver for the assembled tangent (factorise it, or set up the
    /// preconditioner); returns the time it took.
    pub fn prepare_solver(&mut self) -> Result<std::time::Duration, LinearSolveError> {
        let start = std::time::Instant::now();
        let system = LinearSystem {
            pattern: &self.pattern,
            matrix: &self.matrix,
            constrained: &self.constrained,
            lattice: self.lattice.as_ref(),
        };
        let prepared = self.linear.prepare(&system);
        prepared.map_err(|e| self.traced(e))?;
        Ok(start.elapsed())
    }

    /// A linear solver's failure, with its cause in the grid where it can be named
    /// (`slivers::traced`).
    fn traced(&self, error: LinearSolveError) -> LinearSolveError {
        crate::slivers::traced(error, &self.model, &self.conn, &self.constrained)
    }

    /// Solve K x = b with the prepared solver to the relative residual `tolerance`, `b` in
    /// the nodes' frames (as the residual is), `x` turned back to the global frame; a failed
    /// Krylov solve is repeated by sparse LU below `DIRECT_FALLBACK_MAX_DOFS`. Returns the
    /// Krylov iterations and the time of any factorisation the solve made (a fallback's).
    pub fn solve_prepared(
        &mut self,
        b: &[f64],
        x: &mut [f64],
        tolerance: f64,
    ) -> Result<LinearSolveStats, LinearSolveError> {
        let system = LinearSystem {
            pattern: &self.pattern,
            matrix: &self.matrix,
            constrained: &self.constrained,
            lattice: self.lattice.as_ref(),
        };
        let solved = match self.linear.solve(&system, b, x, tolerance) {
            Err(e @ (LinearSolveError::NotConverged(_) | LinearSolveError::NotPositiveDefinite(_)))
                if self.linear.kind().is_iterative() && self.num_dofs() <= DIRECT_FALLBACK_MAX_DOFS[D - 1] =>
            {
                tracing::warn!(error = %e, "the Krylov solve failed; solving this correction by sparse LU");
                self.fallbacks += 1;
                let direct = self.fallback.get_or_insert_with(|| SparseDirectSolver::new(LinearSolverKind::Lu));
                let columns = SystemMatrix::Columns(self.matrix.to_columns(&self.pattern).into_owned());
                let system = LinearSystem { matrix: &columns, ..system };
                let start = std::time::Instant::now();
                direct.prepare(&system).and_then(|()| {
                    let factorised = start.elapsed();
                    let stats = direct.solve(&system, b, x, tolerance)?;
                    Ok(LinearSolveStats { factorised: stats.factorised + factorised, ..stats })
                })
            }
            result => result,
        };
        // The LU fallback's failures (a NaN solution, a missing pivot) are traced as well.
        let stats = solved.map_err(|e| self.traced(e))?;
        self.frames.to_global(x);
        Ok(stats)
    }

    /// The assembled tangent as the linear solvers see it.
    pub fn linear_system(&self) -> LinearSystem<'_> {
        LinearSystem {
            pattern: &self.pattern,
            matrix: &self.matrix,
            constrained: &self.constrained,
            lattice: self.lattice.as_ref(),
        }
    }

    /// With F-bar, the points of every cell, which the point update averages over.
    fn fbar(&self) -> Option<&CellGroups> {
        fbar_groups(&self.model, &self.groups)
    }

    /// The cell-averaged support gradients of the connectivity (empty without cell
    /// averages).
    pub fn cell_gradients(&self) -> &[SVector<f64, D>] {
        &self.cell_gradients
    }

    /// The residual of the last update, for inspecting a step's start.
    pub fn residual(&self) -> &[f64] {
        &self.residual
    }

    /// Stage 5, commit the converged trial state (docs/theory.md §1): the reactions,
    /// positions, F, volume, stress, elastic strain, history, and GIMP half-lengths
    /// stretched with F (iGIMP); the body-fitted mesh moves with the increment. The
    /// connectivity stays readable until the next `connect`.
    pub fn commit(&mut self) {
        self.reactions = self.constraint_reactions();
        // Geometrically linear: the configuration (and with it the connectivity, the
        // pattern and the cell averages) stays that of the start.
        let moves = !self.model.geometrically_linear();
        let (conn, du, trial) = (&self.conn, &self.du, &self.trial);
        let pts = self.model.points_mut();
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
                interpolate_add(conn, p, du, x);
                let df = &trial.delta_f[p];
                if moves {
                    advance_deformation(df, f, l, l0);
                    *v *= df.determinant();
                } else {
                    *f = df * *f;
                }
            });
        pts.stress.copy_from_slice(&trial.stress);
        pts.elastic_strain.copy_from_slice(&trial.elastic_strain);
        let n = pts.history.len();
        pts.history.copy_from_slice(&trial.history[..n]);
        self.model.update_load_vertices();
        if moves {
            self.model.displace_background(conn.active_nodes(), du);
        }
        self.conn_current = !moves;
    }

    /// Per constraint, Σ (f_int − f_ext) over its nodes on its fixed components, then per
    /// inclined roller the sum over its nodes, then per body constraint over its nodes,
    /// then per frictional plane the force on the material at its nodes,
    /// from the reactions of the converged residual (one per dof, global).
    fn constraint_reactions(&self) -> Vec<[f64; 3]> {
        let (model, active) = (&self.model, self.conn.active_nodes());
        let planes = model.constraints().iter().map(|c| self.reaction_sum(model.constraint_nodes(active, c), &c.fixed));
        let mut reactions: Vec<[f64; 3]> = planes.collect();
        reactions.extend(self.frames.roller_reactions(&self.reaction));
        let bodies = (model.body_constraints().iter().enumerate())
            .map(|(k, c)| self.reaction_sum(model.body_constraint_nodes(&self.conn, k), &c.fixed));
        reactions.extend(bodies);
        reactions.extend(self.frames.plane_reactions(&self.reaction));
        reactions
    }

    /// Σ of the reactions over `nodes` on the `fixed` components of the first motion field.
    fn reaction_sum(&self, nodes: Vec<usize>, fixed: &[bool; 3]) -> [f64; 3] {
        let mut sum = [0.0; 3];
        for a in nodes {
            for i in (0..D).filter(|&i| fixed[i]) {
                sum[i] += self.reaction[self.layout.dof(a, 0, i)];
            }
        }
        sum
    }
}

#[cfg(test)]
mod tests;
