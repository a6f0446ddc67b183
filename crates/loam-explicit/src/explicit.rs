//! The explicit analysis: one time step as described in the crate docs.

use crate::body_contact::{self, BodyContact, Settled};
use crate::contact::{GridUpdate, PlaneContacts};
use crate::fields::{rigid_motions, Fields, RigidMotion};
use crate::{ExplicitError, ExplicitSettings, TimeStep, UpdateScheme};
use loam_grid::{ActiveNodes, AxisBasis, BandScatter, BasisError, NodeLayout, PointBasisError};
use loam_kernels::{
    check_constraints, embed, internal_force, on_pool, update_point_stress, Committed, ConnectError, LoadSupports,
    RunError,
};
use loam_model::{AnalysisKind, Kinematics, LoadLevel, Model, ModelError, ModelState, PointChange, StateFields};
use loam_points::{stretched_half_length, stretched_half_lengths};
use nalgebra::{Matrix3, SMatrix, SVector};
use rayon::prelude::*;
use std::time::{Duration, Instant};

/// Nodes whose mass is at most this fraction of the largest nodal mass are empty: their
/// velocity and acceleration are zero instead of a division by a tiny mass.
const EMPTY_NODE_MASS: f64 = 1e-12;
/// A step within this fraction of the remaining time is stretched to land on the end time
/// (no sliver step from rounding in the accumulated time).
const LAND_ON_END: f64 = 1e-9;
/// A time step shorter than this fraction of the duration stops the run: it would need more
/// than 10⁹ steps, and a step that short comes from a point moving absurdly fast (a velocity
/// of 1e300 gave Δt = 1e-300 with time stuck at 0 while frames filled the disk) or a
/// material whose wave speed is out of all proportion to the grid.
const MIN_STEP_FRACTION: f64 = 1e-9;

/// What one explicit step did.
#[derive(Debug, Clone, PartialEq)]
pub struct ExplicitStepReport {
    /// 1-based step number.
    pub step: usize,
    /// Time at the end of the step.
    pub time: f64,
    pub dt: f64,
    /// The critical time step of the state the step started from.
    pub critical_dt: f64,
    /// The grid nodes with mass (a node with several bodies' fields counts once).
    pub active_nodes: usize,
    pub wall_time: Duration,
    /// Where the wall time went, stage by stage.
    pub phases: StepPhases,
    /// The force each inclined roller, then each frictional plane, exerted on the
    /// material over the step (D components used).
    pub plane_forces: Vec<[f64; 3]>,
    /// The force each rigid body exerted on the material over the step (D components used).
    pub rigid_forces: Vec<[f64; 3]>,
}

/// The wall time of a step's stages (the crate docs' numbering): where to look first when
/// a step is slow (`cargo xtask bench`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepPhases {
    /// Stage 1.
    pub connectivity: Duration,
    /// Stage 2, points to grid, the critical time step (and USF's stress update and
    /// internal force).
    pub to_grid: Duration,
    /// Stages 3–4.
    pub grid_update: Duration,
    /// Stage 5.
    pub to_points: Duration,
    /// Stage 6 (USL, MUSL).
    pub stress: Duration,
    /// Stage 7.
    pub commit: Duration,
}

impl StepPhases {
    /// The phases of two steps added (to sum a run's).
    pub fn add(&self, other: &StepPhases) -> StepPhases {
        StepPhases {
            connectivity: self.connectivity + other.connectivity,
            to_grid: self.to_grid + other.to_grid,
            grid_update: self.grid_update + other.grid_update,
            to_points: self.to_points + other.to_points,
            stress: self.stress + other.stress,
            commit: self.commit + other.commit,
        }
    }

    /// The phases with their names, in order.
    pub fn named(&self) -> [(&'static str, Duration); 6] {
        [
            ("connectivity", self.connectivity),
            ("to_grid", self.to_grid),
            ("grid_update", self.grid_update),
            ("to_points", self.to_points),
            ("stress", self.stress),
            ("commit", self.commit),
        ]
    }
}

/// The record the points scatter to every grid node: its mass, momentum (D) and force (D),
/// `WIDTH` values in that order.
pub(crate) struct NodeRecord<const D: usize>;

impl<const D: usize> NodeRecord<D> {
    pub(crate) const WIDTH: usize = 1 + 2 * D;
    pub(crate) const MASS: usize = 0;
    pub(crate) const MOMENTUM: usize = 1;
    pub(crate) const FORCE: usize = 1 + D;
}

/// Nodal scratch of one step, reused across steps: dense over the grid's nodes (an empty
/// node has zero mass and is left at rest).
#[derive(Debug, Default)]
struct NodalScratch {
    /// Per node its [`NodeRecord`] as scattered from the points.
    gathered: Vec<f64>,
    /// USF: internal force of the updated stress (D per node).
    internal: Vec<f64>,
    /// v_I^{n+1} (D per node).
    velocity: Vec<f64>,
    /// The FLIP acceleration (v_I^{n+1} − p_I / m_I) / Δt (D per node, `nodal_update`).
    acceleration: Vec<f64>,
    /// First the carried velocity p_I / m_I, which the critical step reads and USF's strain
    /// update uses; then, for MUSL, the re-mapped velocity (D per node). USL uses `velocity`.
    strain_velocity: Vec<f64>,
    /// The loads on surfaces and at points (D per node with mass; empty without loads).
    loads: Vec<f64>,
    /// Per node, 1 where a held body's point reaches it (empty without body constraints).
    held: Vec<f64>,
    /// Per slot, whether contact between bodies set its velocity (empty without it).
    settled: Vec<bool>,
    /// Per slot of a rigid body's field, the force it exerted on the material at the node
    /// (D; empty without contact).
    reaction: Vec<f64>,
}

/// Per-point trial state of one step, committed only when the whole step succeeded.
#[derive(Debug, Default)]
struct PointScratch<const D: usize> {
    /// New position, velocity, deformation gradient, volume, half-lengths, stress, elastic
    /// strain and history, exchanged with the model's at the commit; the history
    /// `max(history_stride, 1)` per point so that every point has its own chunk.
    fields: StateFields<D>,
}

impl<const D: usize> PointScratch<D> {
    fn resize(&mut self, n: usize, history_stride: usize) {
        let f = &mut self.fields;
        f.position.resize(n, SVector::zeros());
        f.velocity.resize(n, SVector::zeros());
        f.deformation_gradient.resize(n, Matrix3::identity());
        f.volume.resize(n, 0.0);
        f.half_length.resize(n, SVector::zeros());
        f.stress.resize(n, Matrix3::zeros());
        f.elastic_strain.resize(n, Matrix3::zeros());
        f.history.resize(n * history_stride.max(1), 0.0);
    }
}

/// The time since the last lap.
struct PhaseClock(Instant);

impl PhaseClock {
    fn new() -> Self {
        Self(Instant::now())
    }

    fn lap(&mut self) -> Duration {
        let now = Instant::now();
        let lap = now - self.0;
        self.0 = now;
        lap
    }
}

/// Why a point stopped a step.
enum PointFailure {
    Unstable(String),
    Outside,
}

type PointResult = Result<(), (usize, PointFailure)>;

/// Explicit MPM analysis of a model (see the crate docs).
pub struct Explicit<const D: usize> {
    model: Model<D>,
    settings: ExplicitSettings,
    time: f64,
    steps: usize,
    /// P-wave modulus of each material whose law's stiffness is constant, for the critical
    /// time step (`None`: per point, from its state).
    p_wave: Vec<Option<f64>>,
    /// The step's basis at the points, as 1D factors.
    basis: AxisBasis<D>,
    /// The points grouped for the deterministic scatter.
    bands: BandScatter,
    /// The constrained dofs of every grid node (D per node): the grid planes', marked
    /// once, and the held bodies', marked again every step.
    constrained: Vec<bool>,
    /// The grid planes' constrained dofs (empty without body constraints, when
    /// `constrained` is all there is).
    on_planes: Vec<bool>,
    /// The nodes with mass of the step, numbered for the loads and the constraint check.
    loaded: ActiveNodes,
    /// The load vertices on the nodes of `loaded`.
    loads: LoadSupports,
    /// The inclined rollers and frictional planes at their grid nodes.
    contacts: PlaneContacts<D>,
    /// The motion fields at each node (one per body in contact), found at every connect.
    fields: Fields,
    /// Per field, the velocity over the step and the friction of the rigid body it is, if
    /// any (`fields::rigid_motions`, at every grid update).
    rigid_motions: Vec<RigidMotion<D>>,
    /// Nodes with mass in the step.
    active_nodes: usize,
    nodes: NodalScratch,
    points: PointScratch<D>,
}

/// What an explicit analysis carries from step to step beside its model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExplicitState {
    pub steps: usize,
    pub time: f64,
}

impl<const D: usize> Explicit<D> {
    /// An explicit analysis of `model` from t = 0 to `settings.duration`. Refuses invalid
    /// settings with [`ExplicitError::InvalidSettings`].
    pub fn new(model: Model<D>, settings: ExplicitSettings) -> Result<Self, ExplicitError> {
        settings.validate()?;
        model.check_accepted_by(AnalysisKind::Explicit)?;
        let in_contact = model.body_contact().is_some() || !model.rigid_bodies().is_empty();
        if in_contact && settings.scheme != UpdateScheme::Usl {
            return Err(ExplicitError::ContactScheme(settings.scheme));
        }
        tracing::info!(scheme = ?settings.scheme, flip = settings.flip, time_step = ?settings.time_step,
            damping = settings.damping, duration = settings.duration, "explicit analysis");
        let p_wave = model.constant_p_wave_moduli();
        let mut constrained = Vec::new();
        let every_node = ActiveNodes::all(model.grid().num_nodes());
        model.constrained_dofs(&NodeLayout::motion(D), &every_node, &mut constrained);
        let on_planes = if model.body_constraints().is_empty() { Vec::new() } else { constrained.clone() };
        let (contacts, fields) = (PlaneContacts::of(&model), Fields::of(&model));
        Ok(Self {
            basis: AxisBasis::new(model.basis()),
            model,
            settings,
            time: 0.0,
            steps: 0,
            p_wave,
            bands: BandScatter::default(),
            constrained,
            on_planes,
            loaded: ActiveNodes::default(),
            loads: LoadSupports::default(),
            rigid_motions: Vec::new(),
            contacts,
            fields,
            active_nodes: 0,
            nodes: NodalScratch::default(),
            points: PointScratch::default(),
        })
    }

    pub fn model(&self) -> &Model<D> {
        &self.model
    }

    pub fn into_model(self) -> Model<D> {
        self.model
    }

    pub fn settings(&self) -> &ExplicitSettings {
        &self.settings
    }

    /// Time reached by the committed state.
    pub fn time(&self) -> f64 {
        self.time
    }

    pub fn steps_done(&self) -> usize {
        self.steps
    }

    pub fn is_finished(&self) -> bool {
        self.time >= self.settings.duration
    }

    /// The step count and time, the state beside the model a checkpoint needs (every
    /// nodal field is rebuilt from the points each step).
    pub fn state(&self) -> ExplicitState {
        ExplicitState { steps: self.steps, time: self.time }
    }

    /// Add or remove points between steps ([`Model::change_points`]); returns how many.
    /// The next step connects the points anew.
    pub fn change_points(&mut self, change: PointChange<D>) -> Result<usize, ModelError> {
        self.model.change_points(change)
    }

    /// Go on from `state` and `model`, saved by an analysis of the same scene; a state that
    /// does not fit is refused and nothing changes.
    pub fn resume(&mut self, state: ExplicitState, model: ModelState<D>) -> Result<(), ModelError> {
        let (time, duration) = (state.time, self.settings.duration);
        if !(time.is_finite() && (0.0..=duration).contains(&time)) {
            return Err(ModelError::Restore(format!("time {time} outside the run's 0 to {duration}")));
        }
        self.model.restore(model)?;
        self.steps = state.steps;
        self.time = time;
        Ok(())
    }

    /// Check what can only be checked against the connectivity: every point's basis lies in
    /// the grid, every load is on the material, and every constraint holds at least one
    /// node with mass (the rule of `QuasiStatic::check`); and that the next time step is
    /// long enough for the run to reach its end (a fixed step above the critical one is the
    /// caller's to judge). Scene validation calls this before the first step.
    pub fn check(&mut self) -> Result<(), ExplicitError> {
        let step = self.steps + 1;
        self.connect(step)?;
        self.size_buffers();
        let m_min = self.map_to_grid(step)?;
        self.number_nodes_with_mass(m_min);
        check_constraints(&self.model, &self.loaded)?;
        let critical = self.carried_critical_step(m_min);
        let dt = match self.time_step(step, critical) {
            Err(ExplicitError::AboveCritical { dt, .. }) => dt,
            dt => dt?,
        };
        self.check_time_advances(step, dt)
    }

    /// Critical time step of the committed state (docs/theory.md §10):
    /// h_min / (max_p c_p + max_I |v_I|), c_p = √(M / ρ_p) (ρ_p the point's density in small
    /// strain, the one it started with in finite strain, `squared_wave_speed`), with
    /// v_I = p_I / m_I the velocity the grid carries the material at (zero at held dofs
    /// and empty nodes). An error if a point's basis leaves the grid.
    pub fn critical_time_step(&self) -> Result<f64, ExplicitError> {
        let model = &self.model;
        let (mut basis, mut bands) = (AxisBasis::new(model.basis()), BandScatter::default());
        locate(model, &mut basis, &mut bands, self.steps + 1)?;
        let fields = Fields::of(model);
        let slots = model.grid().num_nodes() * fields.count;
        let mut gathered = vec![0.0; slots * fields.width];
        scatter_grid(model, &basis, &bands, fields, false, &mut gathered);
        let mut velocity = vec![0.0; slots * D];
        let m_min = empty_node_mass::<D>(&gathered, fields);
        carried_velocity::<D>(&gathered, fields, &self.constrained, m_min, &mut velocity);
        Ok(critical_step(model, &self.p_wave, &velocity, self.time))
    }

    /// The critical time step of the wave speeds alone, h_min / max_p c_p (c_p as
    /// [`Self::critical_time_step`] takes it): what the CFL step comes back to as the
    /// material comes to rest.
    pub fn wave_step(&self) -> f64 {
        self.model.grid().cell_size().min() / max_squared_wave_speed(&self.model, &self.p_wave).sqrt()
    }

    /// The critical time step of the step being taken, from its scattered momentum: the
    /// carried nodal velocity p_I / m_I goes to `strain_velocity` (USF's, and what
    /// [`Self::fastest_point`] reads).
    fn carried_critical_step(&mut self, m_min: f64) -> f64 {
        let nodes = &mut self.nodes;
        carried_velocity::<D>(&nodes.gathered, self.fields, &self.constrained, m_min, &mut nodes.strain_velocity);
        critical_step(&self.model, &self.p_wave, &nodes.strain_velocity, self.time)
    }

    /// The time step of step `step` given the critical one, shortened to land on the end.
    fn time_step(&self, step: usize, critical: f64) -> Result<f64, ExplicitError> {
        let remaining = self.settings.duration - self.time;
        let (nominal, check) = match self.settings.time_step {
            TimeStep::Cfl { safety } => (safety * critical, false),
            TimeStep::Fixed { dt, allow_above_critical } => (dt, !allow_above_critical),
        };
        if check && nominal.min(remaining) > critical {
            return Err(ExplicitError::AboveCritical { step, dt: nominal, critical });
        }
        // Land on the end with a step within round-off of the remaining time, or with one
        // that would leave less than the shortest step allowed: rounding in the summed time
        // must not leave a sliver that the floor then refuses.
        let floor = MIN_STEP_FRACTION * self.settings.duration;
        let lands = nominal >= remaining * (1.0 - LAND_ON_END) || remaining - nominal < floor;
        Ok(if lands { remaining } else { nominal })
    }

    /// Refuse a step too short to bring the run to its end, naming the point that sets the
    /// critical time step and its speed.
    fn check_time_advances(&self, step: usize, dt: f64) -> Result<(), ExplicitError> {
        let floor = MIN_STEP_FRACTION * self.settings.duration;
        if dt >= floor && self.time + dt > self.time {
            return Ok(());
        }
        let (point, wave_speed, speed) = self.fastest_point();
        Err(ExplicitError::TimeStepCollapsed { step, time: self.time, dt, floor, point, wave_speed, speed })
    }

    /// The point of the smallest critical time step (the lowest index among equals), its
    /// P-wave speed and its carried speed (after [`Self::carried_critical_step`]).
    fn fastest_point(&self) -> (usize, f64, f64) {
        let pts = self.model.points();
        let (p_wave, basis, velocity) = (&self.p_wave, &self.basis, &self.nodes.strain_velocity);
        let speeds = |p: usize| {
            // By hypot, so that 1e300 is reported as such and not as its overflowed square.
            (
                p,
                wave_speed(&self.model, p_wave, p),
                carried(basis, (self.fields, self.fields.of_point(&self.model, p)), velocity, p)
                    .iter()
                    .fold(0.0, |a: f64, &b| a.hypot(b)),
            )
        };
        // A NaN speed counts as the fastest: it is the point to name.
        let key = |t: &(usize, f64, f64)| if (t.1 + t.2).is_nan() { f64::INFINITY } else { t.1 + t.2 };
        let faster = |a: (usize, f64, f64), b: (usize, f64, f64)| {
            let (ka, kb) = (key(&a), key(&b));
            if kb > ka || (kb == ka && b.0 < a.0) {
                b
            } else {
                a
            }
        };
        (0..pts.len()).into_par_iter().map(speeds).reduce(|| (usize::MAX, f64::NEG_INFINITY, 0.0), faster)
    }

    /// Advance one time step (the last one shortened to land on `duration`), stage by
    /// stage as the crate docs number them. On error the committed state is that of the last
    /// successful step.
    pub fn step(&mut self) -> Result<ExplicitStepReport, ExplicitError> {
        if let Some(report) = on_pool(|| self.step()) {
            return report;
        }
        if self.is_finished() {
            return Err(ExplicitError::Finished(self.steps));
        }
        let start = Instant::now();
        let mut clock = PhaseClock::new();
        let step = self.steps + 1;
        self.connect(step)?;
        self.size_buffers();
        let connectivity = clock.lap();
        let m_min = self.map_to_grid(step)?;
        let critical = self.carried_critical_step(m_min);
        let dt = self.time_step(step, critical)?;
        self.check_time_advances(step, dt)?;
        if self.settings.scheme == UpdateScheme::Usf {
            self.update_stress_first(step, dt, m_min)?;
        }
        let to_grid = clock.lap();
        self.update_grid(dt, m_min);
        let grid_update = clock.lap();
        let (basis, nodes) = (&self.basis, &self.nodes);
        let grid_motion = (&nodes.velocity[..], &nodes.acceleration[..]);
        let step_flip = (dt, self.settings.flip);
        let fields = (self.fields, &self.rigid_motions[..]);
        let moved = grid_to_points(&self.model, basis, fields, grid_motion, step_flip, &mut self.points);
        moved.map_err(|e| self.failure(step, e))?;
        self.stop_held_points();
        let to_points = clock.lap();
        self.update_stress_last(step, dt, m_min)?;
        let stress = clock.lap();
        self.commit();
        let phases = StepPhases { connectivity, to_grid, grid_update, to_points, stress, commit: clock.lap() };
        let remaining = self.settings.duration - self.time;
        self.time = if dt >= remaining { self.settings.duration } else { self.time + dt };
        self.steps = step;
        let active_nodes = self.active_nodes;
        tracing::debug!(step, time = self.time, dt, critical, active_nodes, "explicit step");
        Ok(ExplicitStepReport {
            step,
            time: self.time,
            dt,
            critical_dt: critical,
            active_nodes,
            wall_time: start.elapsed(),
            phases,
            plane_forces: self.contacts.forces().to_vec(),
            rigid_forces: self.rigid_forces(),
        })
    }

    /// Stage 1: the basis of every point at its start-of-step place, and the points grouped
    /// for the scatter.
    fn connect(&mut self, step: usize) -> Result<(), ExplicitError> {
        self.fields = Fields::of(&self.model);
        locate(&self.model, &mut self.basis, &mut self.bands, step)?;
        match self.hold_bodies() {
            Some(index) => Err(ConnectError::BodyConstraintTouchesNoNode { index }.into()),
            None => Ok(()),
        }
    }

    /// With body constraints, mark the grid planes' dofs and those of the nodes each held
    /// body's points reach (a scatter of a flag: deterministic); the first constraint
    /// that holds no node, if any.
    fn hold_bodies(&mut self) -> Option<usize> {
        let (model, basis, bands) = (&self.model, &self.basis, &self.bands);
        if model.body_constraints().is_empty() {
            return None;
        }
        self.constrained.copy_from_slice(&self.on_planes);
        let held = &mut self.nodes.held;
        held.resize(model.grid().num_nodes(), 0.0);
        let mut empty = None;
        for (k, c) in model.body_constraints().iter().enumerate() {
            bands.scatter(1, held, |p, window| {
                if model.body_constraint_holds(k, p) {
                    basis.for_each_node(p, |node, _, _| window.node(node)[0] = 1.0);
                }
            });
            if !held.par_iter().any(|&h| h > 0.0) {
                empty.get_or_insert(k);
            }
            let fixed = c.fixed;
            (self.constrained.par_chunks_mut(D).zip(held.par_iter())).filter(|(_, &h)| h > 0.0).for_each(
                |(dofs, _)| {
                    (0..D).for_each(|i| dofs[i] |= fixed[i]);
                },
            );
        }
        empty
    }

    /// With body constraints, the held components of the held points' new velocities are
    /// zero, as their nodes' are: every node a held point reaches is held, so the grid
    /// carries it nowhere, and FLIP would keep what those nodes' momentum was before.
    fn stop_held_points(&mut self) {
        let model = &self.model;
        if model.body_constraints().is_empty() {
            return;
        }
        self.points.fields.velocity.par_iter_mut().enumerate().for_each(|(p, v)| {
            for (k, c) in model.body_constraints().iter().enumerate() {
                if model.body_constraint_holds(k, p) {
                    (0..D).filter(|&i| c.fixed[i]).for_each(|i| v[i] = 0.0);
                }
            }
        });
    }

    /// Size the nodal and point scratch to the grid and the points.
    fn size_buffers(&mut self) {
        let n_nodes = self.model.grid().num_nodes();
        let nodes = &mut self.nodes;
        let slots = n_nodes * self.fields.count;
        nodes.gathered.resize(slots * self.fields.width, 0.0);
        for v in [&mut nodes.internal, &mut nodes.velocity, &mut nodes.acceleration, &mut nodes.strain_velocity] {
            v.resize(slots * D, 0.0);
        }
        self.points.resize(self.model.points().len(), self.model.points().history_stride());
    }

    /// Stage 2, points to grid: [m_I, p_I, f_I] per node, with the internal force of the
    /// committed stress unless USF updates the stress first; returns the mass below which
    /// a node counts as empty.
    fn map_to_grid(&mut self, step: usize) -> Result<f64, ExplicitError> {
        let usf = self.settings.scheme == UpdateScheme::Usf;
        let fields = self.fields;
        scatter_grid(&self.model, &self.basis, &self.bands, fields, !usf, &mut self.nodes.gathered);
        let m_min = empty_node_mass::<D>(&self.nodes.gathered, fields);
        // Nodes, not slots: a node counts once whichever bodies have mass there.
        let nodes = self.nodes.gathered.par_chunks(fields.count * fields.width);
        let massive = |node: &[f64]| node.chunks(fields.width).any(|g| g[NodeRecord::<D>::MASS] > m_min);
        self.active_nodes = nodes.filter(|node| massive(node)).count();
        self.add_loads(step, m_min)?;
        Ok(m_min)
    }

    /// The loads on surfaces and at points at the step's start time, added to the nodal
    /// forces; their vertices are connected to the nodes with mass above `m_min`, those the
    /// grid update moves (a share on any other node goes to the vertex's other nodes,
    /// `LoadSupports`).
    fn add_loads(&mut self, step: usize, m_min: f64) -> Result<(), ExplicitError> {
        if self.model.loads().is_empty() {
            return Ok(());
        }
        // Loads are refused with bodies in contact (`Model::with_body_contact`): one field.
        debug_assert_eq!(self.fields.count, 1, "loads with several fields per node");
        let stride = self.fields.width;
        self.number_nodes_with_mass(m_min);
        self.loads.connect(&self.model, &self.loaded, step)?;
        let level = LoadLevel::Time(self.time);
        let f = &mut self.nodes.loads;
        f.clear();
        f.resize(self.loaded.len() * D, 0.0);
        self.loads.add_dead(&self.model, level, f);
        self.loads.add_follower(&self.model, level, |_, l| l.positions().to_vec(), f);
        for (&g, f) in self.loaded.active_to_grid.iter().zip(f.chunks(D)) {
            let node = &mut self.nodes.gathered[g as usize * stride..(g as usize + 1) * stride];
            for i in 0..D {
                node[NodeRecord::<D>::FORCE + i] += f[i];
            }
        }
        Ok(())
    }

    /// Number the nodes whose scattered mass is above `m_min`, those the grid update moves,
    /// into `loaded`.
    fn number_nodes_with_mass(&mut self, m_min: f64) {
        let (gathered, fields) = (&self.nodes.gathered, self.fields);
        let mass = |slot: usize| gathered[slot * fields.width + NodeRecord::<D>::MASS];
        let any = |g: usize| (0..fields.count).any(|f| mass(fields.slot(g, f)) > m_min);
        self.loaded.fill_from(self.model.grid().num_nodes(), any);
    }

    /// USF: the stress updated from the start-of-step nodal velocity p_I / m_I (the carried
    /// velocity the critical step was taken from) before the grid update, and the internal
    /// force of that stress.
    fn update_stress_first(&mut self, step: usize, dt: f64, m_min: f64) -> Result<(), ExplicitError> {
        let nodes = &mut self.nodes;
        if !self.contacts.is_empty() {
            self.contacts.project(&nodes.gathered, self.fields, &self.constrained, m_min, &mut nodes.strain_velocity);
        }
        let (basis, fields) = (&self.basis, self.fields);
        let updated = update_stress(&self.model, basis, fields, &nodes.strain_velocity, dt, &mut self.points);
        updated.map_err(|e| self.failure(step, e))?;
        let (basis, bands) = (&self.basis, &self.bands);
        negative_internal_force(&self.model, basis, bands, fields, &self.points, &mut self.nodes.internal);
        Ok(())
    }

    /// Stages 3–4: local damping, the grid momentum update, the contact between bodies and
    /// the rigid planes.
    fn update_grid(&mut self, dt: f64, m_min: f64) {
        let nodes = &mut self.nodes;
        let internal = (self.settings.scheme == UpdateScheme::Usf).then_some(&nodes.internal[..]);
        nodal_update::<D>(
            &nodes.gathered,
            self.fields,
            internal,
            &self.constrained,
            m_min,
            dt,
            self.settings.damping,
            &mut nodes.velocity,
            &mut nodes.acceleration,
        );
        let grid = GridUpdate {
            gathered: &nodes.gathered,
            fields: self.fields,
            internal,
            constrained: &self.constrained,
            m_min,
            dt,
            damping: self.settings.damping,
        };
        if self.fields.in_contact() {
            rigid_motions(&self.model, self.fields, (self.time, dt), &mut self.rigid_motions);
            nodes.settled.resize(nodes.velocity.len() / D, false);
            nodes.reaction.resize(nodes.velocity.len(), 0.0);
            let contact =
                BodyContact { friction: self.model.body_contact().unwrap_or(0.0), rigid: &self.rigid_motions };
            let out = Settled { settled: &mut nodes.settled, reaction: &mut nodes.reaction };
            body_contact::apply::<D>(&grid, &contact, &mut nodes.velocity, &mut nodes.acceleration, out);
        }
        if !self.contacts.is_empty() {
            // Flags of the step's own layout only: with one field left there are none.
            let settled = if self.fields.in_contact() { &nodes.settled[..] } else { &[] };
            self.contacts.apply(&grid, settled, &mut nodes.velocity, &mut nodes.acceleration);
        }
    }

    /// Stage 6 for USL (the new grid velocity) and MUSL (the velocity re-mapped from the
    /// updated points); USF updated the stress first.
    fn update_stress_last(&mut self, step: usize, dt: f64, m_min: f64) -> Result<(), ExplicitError> {
        let (model, basis, nodes, fields) = (&self.model, &self.basis, &mut self.nodes, self.fields);
        let updated = match self.settings.scheme {
            UpdateScheme::Usf => return Ok(()),
            UpdateScheme::Usl => update_stress(model, basis, fields, &nodes.velocity, dt, &mut self.points),
            UpdateScheme::Musl => {
                let velocity = &self.points.fields.velocity;
                remap_momentum(model, basis, &self.bands, fields, velocity, &mut nodes.strain_velocity);
                let remapped = &mut nodes.strain_velocity;
                momentum_to_velocity::<D>(&nodes.gathered, fields, &self.constrained, m_min, remapped);
                if !self.contacts.is_empty() {
                    self.contacts.project(
                        &nodes.gathered,
                        fields,
                        &self.constrained,
                        m_min,
                        &mut nodes.strain_velocity,
                    );
                }
                update_stress(model, basis, fields, &nodes.strain_velocity, dt, &mut self.points)
            }
        };
        updated.map_err(|e| self.failure(step, e))
    }

    /// The force each rigid body exerted on the material over the last step.
    fn rigid_forces(&self) -> Vec<[f64; 3]> {
        let bodies: Vec<usize> = self.model.rigid_bodies().iter().map(|r| self.fields.of_body(r.body())).collect();
        if bodies.is_empty() {
            return Vec::new();
        }
        body_contact::rigid_forces::<D>(self.fields, &bodies, &self.nodes.reaction)
    }

    /// The error of step `step` for a point that failed it.
    fn failure(&self, step: usize, (point, failure): (usize, PointFailure)) -> ExplicitError {
        match failure {
            PointFailure::Unstable(reason) => ExplicitError::Unstable { step, time: self.time, point, reason },
            PointFailure::Outside => {
                let source = outside_error(&self.model, point, &self.points.fields.position[point]);
                ConnectError::PointOutsideGrid { step, source }.into()
            }
        }
    }

    /// Commit the trial state of a successful step (docs/theory.md §1) by exchange: the
    /// stress update computed every point's F ← ΔF F, V_p ← det ΔF V_p and half-lengths
    /// stretched with F (iGIMP) beside its stress; the load vertices follow their carrier
    /// points.
    fn commit(&mut self) {
        self.model.swap_state(&mut self.points.fields);
        self.model.update_load_vertices();
    }

    /// Run every remaining step, calling `on_step` after each.
    pub fn run<E: std::error::Error + 'static>(
        &mut self,
        mut on_step: impl FnMut(&ExplicitStepReport, &Model<D>) -> Result<(), E>,
    ) -> Result<(), RunError<ExplicitError, E>> {
        while !self.is_finished() {
            let report = self.step().map_err(RunError::Step)?;
            on_step(&report, &self.model).map_err(RunError::Observer)?;
        }
        Ok(())
    }
}

/// The error for a point whose new position `x` lies outside the grid.
fn outside_error<const D: usize>(model: &Model<D>, point: usize, x: &SVector<f64, D>) -> PointBasisError {
    let g = model.grid();
    let (lo, hi) = (g.origin(), g.extent_max());
    let axis = (0..D).find(|&a| !(x[a] >= lo[a] && x[a] < hi[a])).unwrap_or(0);
    PointBasisError {
        point,
        position: x.iter().copied().collect(),
        source: BasisError::OutsideGrid { axis, coordinate: x[axis], min: lo[axis], max: hi[axis] },
    }
}

/// Stage 1 into `basis` and `bands`: every point's basis at its start-of-step place, and the
/// points grouped for the scatter.
fn locate<const D: usize>(
    model: &Model<D>,
    basis: &mut AxisBasis<D>,
    bands: &mut BandScatter,
    step: usize,
) -> Result<(), ExplicitError> {
    let grid = model.grid();
    let located = basis.compute(grid, model.configuration(), model.points().half_length());
    located.map_err(|source| ConnectError::PointOutsideGrid { step, source })?;
    bands.group(grid, basis);
    Ok(())
}

/// The mass at or below which a node of the scattered `gathered` is empty.
fn empty_node_mass<const D: usize>(gathered: &[f64], fields: Fields) -> f64 {
    EMPTY_NODE_MASS * gathered.par_chunks(fields.width).map(|g| g[NodeRecord::<D>::MASS]).reduce(|| 0.0, f64::max)
}

/// The velocity the grid carries the material at, p_I / m_I, from the scattered
/// [m, p, f] per node and field; zero at held dofs and empty nodes.
fn carried_velocity<const D: usize>(
    gathered: &[f64],
    fields: Fields,
    constrained: &[bool],
    m_min: f64,
    out: &mut [f64],
) {
    out.par_chunks_mut(D)
        .zip(gathered.par_chunks(fields.width))
        .for_each(|(v, g)| v.copy_from_slice(&g[NodeRecord::<D>::MOMENTUM..NodeRecord::<D>::MOMENTUM + D]));
    momentum_to_velocity::<D>(gathered, fields, constrained, m_min, out);
}

/// Σ_I N_I v_I at point `p` of field `field` for the nodal velocities `velocity`.
#[inline]
fn carried<const D: usize>(
    basis: &AxisBasis<D>,
    (fields, field): (Fields, usize),
    velocity: &[f64],
    p: usize,
) -> SVector<f64, D> {
    let mut v = SVector::<f64, D>::zeros();
    basis.for_each_node(p, |node, n, _| {
        let slot = fields.slot(node, field);
        for i in 0..D {
            v[i] += n * velocity[slot * D + i];
        }
    });
    v
}

/// h_min / (max_p c_p + max_I |v_I|), v_I the velocity the grid carries the material at
/// (docs/theory.md §10): a lower bound of min_p h_min / (c_p + |v̄_p|), since the carried
/// velocity of a point v̄_p = Σ N_I v_I is a convex combination of the v_I (weights ≥ 0
/// summing to 1), reached at rest and wherever the stiffest point moves fastest; a pass
/// over the nodes instead of an interpolation at every point. Not the points' own
/// velocities: under FLIP a point keeps the part of its velocity that maps to no nodal
/// momentum (more points than nodes), and a held node stops its own part without moving
/// the point, so a body at rest can carry point velocities that shorten the step and move
/// nothing.
///
/// A rigid body's speed at time `t` counts too: the grid carries its velocity of the last
/// step, which a time function may have raised since.
fn critical_step<const D: usize>(model: &Model<D>, p_wave: &[Option<f64>], velocity: &[f64], t: f64) -> f64 {
    let h = model.grid().cell_size().min();
    // max √x = √(max x) exactly (the root is correctly rounded and monotonic): one root for
    // the body instead of one per point and one per node.
    let c2_max = max_squared_wave_speed(model, p_wave);
    let v2_max = velocity.par_chunks(D).map(|v| v.iter().map(|c| c * c).sum::<f64>()).reduce(|| 0.0, f64::max);
    let rigid2_max = (model.rigid_bodies().iter()).map(|r| r.velocity_at(t).norm_squared()).fold(0.0, f64::max);
    h / (c2_max.sqrt() + v2_max.max(rigid2_max).sqrt())
}

/// max_p c_p² over the points ([`squared_wave_speed`]).
fn max_squared_wave_speed<const D: usize>(model: &Model<D>, p_wave: &[Option<f64>]) -> f64 {
    let c2 = |p: usize| squared_wave_speed(model, p_wave, p);
    (0..model.points().len()).into_par_iter().map(c2).reduce(|| 0.0, f64::max)
}

/// The P-wave speed c_p of point `p` ([`squared_wave_speed`]).
fn wave_speed<const D: usize>(model: &Model<D>, p_wave: &[Option<f64>], p: usize) -> f64 {
    squared_wave_speed(model, p_wave, p).sqrt()
}

/// c_p² = M / ρ_p of point `p` (docs/theory.md §10), M its material's where constant
/// (`p_wave`); zero for a rigid body's point, which carries no waves. In small strain
/// ρ_p = m_p / v_p. In finite strain the laws' M relates the Kirchhoff stress τ = J σ to
/// the logarithmic strain, so the Cauchy stiffness is M / J and c_p² = (M / J) / (ρ₀ / J)
/// = M / ρ₀: the density the point started with, however far it has swollen or been
/// compressed (its force V σ ∇N = V₀ τ ∇N grows with V₀, not with V).
#[inline]
fn squared_wave_speed<const D: usize>(model: &Model<D>, p_wave: &[Option<f64>], p: usize) -> f64 {
    let pts = model.points();
    if model.is_rigid_point(p) {
        return 0.0;
    }
    let volume = match model.kinematics() {
        Kinematics::FiniteStrain => pts.volume0()[p],
        Kinematics::SmallStrain => pts.volume()[p],
    };
    model.p_wave_modulus(p_wave, p) / (pts.mass()[p] / volume)
}

/// Sign with sign(0) = 0 (`f64::signum` gives ±1 at zero).
#[inline]
fn sign(x: f64) -> f64 {
    if x > 0.0 {
        1.0
    } else if x < 0.0 {
        -1.0
    } else {
        0.0
    }
}

/// Scatter [m_I, p_I, f_I] per node and field (and Σ_p m_p ∇N_I with bodies in contact); f_I is
/// the external force, plus the internal force of the committed stress when `with_internal`.
fn scatter_grid<const D: usize>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    bands: &BandScatter,
    fields: Fields,
    with_internal: bool,
    out: &mut [f64],
) {
    // Compiled once for each, so that a plane run's scatter has no hoop test per node, and
    // a run of one field no field lookup.
    match (model.axisymmetric(), fields.in_contact()) {
        (true, true) => scatter_grid_in::<D, true, true>(model, basis, bands, fields, with_internal, out),
        (true, false) => scatter_grid_in::<D, true, false>(model, basis, bands, fields, with_internal, out),
        (false, true) => scatter_grid_in::<D, false, true>(model, basis, bands, fields, with_internal, out),
        (false, false) => scatter_grid_in::<D, false, false>(model, basis, bands, fields, with_internal, out),
    }
}

/// [`scatter_grid`] in axisymmetry (`AXISYMMETRIC`: the hoop force) or not, with a field
/// per body (`MANY`) or one.
fn scatter_grid_in<const D: usize, const AXISYMMETRIC: bool, const MANY: bool>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    bands: &BandScatter,
    fields: Fields,
    with_internal: bool,
    out: &mut [f64],
) {
    let pts = model.points();
    bands.scatter(fields.count * fields.width, out, |p, window| {
        let (m, v, load) = (pts.mass()[p], &pts.velocity()[p], model.point_load(p));
        let (volume, stress) = (pts.volume()[p], &pts.stress()[p]);
        let inv_r = AXISYMMETRIC.then(|| 1.0 / pts.position()[p][0]);
        let record = if MANY { fields.of_point(model, p) * fields.width } else { 0 };
        basis.for_each_node(p, |node, n, grad| {
            let values = window.node(node);
            let record = if MANY { &mut values[record..] } else { values };
            if MANY {
                for i in 0..D {
                    record[NodeRecord::<D>::WIDTH + i] += m * grad[i];
                }
            }
            // Cut to the record's width, which D fixes, and indexed by the record's own
            // constants (not locals the closure would capture): the indexing below then
            // needs one bounds check, not one per entry.
            let o = &mut record[..NodeRecord::<D>::WIDTH];
            let nm = n * m;
            o[NodeRecord::<D>::MASS] += nm;
            for i in 0..D {
                o[NodeRecord::<D>::MOMENTUM + i] += nm * v[i];
                o[NodeRecord::<D>::FORCE + i] += n * load[i];
            }
            if with_internal {
                // f_ext − f_int, point by point in one sum.
                let f = internal_force(volume, stress, &grad, None, inv_r.map(|i| n * i));
                for i in 0..D {
                    o[NodeRecord::<D>::FORCE + i] -= f[i];
                }
            }
        });
    });
}

/// USF: minus the internal force of the updated stress (finite strain: on the updated
/// volume; small strain: on the start-of-step volume, as the implicit small-strain step),
/// so that the grid update adds it to the external force.
fn negative_internal_force<const D: usize>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    bands: &BandScatter,
    fields: Fields,
    sc: &PointScratch<D>,
    out: &mut [f64],
) {
    if model.axisymmetric() {
        negative_internal_force_in::<D, true>(model, basis, bands, fields, sc, out);
    } else {
        negative_internal_force_in::<D, false>(model, basis, bands, fields, sc, out);
    }
}

/// [`negative_internal_force`] in axisymmetry (`AXISYMMETRIC`: the hoop force) or not.
fn negative_internal_force_in<const D: usize, const AXISYMMETRIC: bool>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    bands: &BandScatter,
    fields: Fields,
    sc: &PointScratch<D>,
    out: &mut [f64],
) {
    let finite = model.kinematics() == Kinematics::FiniteStrain;
    let pts = model.points();
    bands.scatter(fields.count * D, out, |p, window| {
        let field = fields.of_point(model, p) * D;
        let v = if finite { sc.fields.volume[p] } else { pts.volume()[p] };
        let stress = &sc.fields.stress[p];
        // The hoop force on the start-of-step radius, as the gradients are (USF).
        let inv_r = AXISYMMETRIC.then(|| 1.0 / pts.position()[p][0]);
        basis.for_each_node(p, |node, n, grad| {
            let f = -internal_force(v, stress, &grad, None, inv_r.map(|i| n * i));
            let o = &mut window.node(node)[field..][..D]; // of the field's width (`scatter_grid`)
            for i in 0..D {
                o[i] += f[i];
            }
        });
    });
}

/// MUSL: p_I = Σ N_I m_p v_p^{n+1} from the updated point velocities.
fn remap_momentum<const D: usize>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    bands: &BandScatter,
    fields: Fields,
    velocity: &[SVector<f64, D>],
    out: &mut [f64],
) {
    if fields.in_contact() {
        remap_momentum_in::<D, true>(model, basis, bands, fields, velocity, out);
    } else {
        remap_momentum_in::<D, false>(model, basis, bands, fields, velocity, out);
    }
}

/// [`remap_momentum`] with a field per body (`MANY`) or one.
fn remap_momentum_in<const D: usize, const MANY: bool>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    bands: &BandScatter,
    fields: Fields,
    velocity: &[SVector<f64, D>],
    out: &mut [f64],
) {
    let mass = model.points().mass();
    bands.scatter(fields.count * D, out, |p, window| {
        let (m, v) = (mass[p], &velocity[p]);
        let field = if MANY { fields.of_point(model, p) * D } else { 0 };
        basis.for_each_node(p, |node, n, _| {
            let nm = n * m;
            let values = window.node(node);
            let o = &mut (if MANY { &mut values[field..] } else { values })[..D]; // of the field's width
            for i in 0..D {
                o[i] += nm * v[i];
            }
        });
    });
}

/// In place: nodal momentum → velocity p_I / m_I of every field; zero at empty nodes and
/// constrained dofs.
fn momentum_to_velocity<const D: usize>(
    gathered: &[f64],
    fields: Fields,
    constrained: &[bool],
    m_min: f64,
    v: &mut [f64],
) {
    let per_node = (v.par_chunks_mut(fields.count * D).zip(gathered.par_chunks(fields.count * fields.width)))
        .zip(constrained.par_chunks(D));
    per_node.for_each(|((v, g), fixed)| {
        for (v, g) in v.chunks_mut(D).zip(g.chunks(fields.width)) {
            let m = g[NodeRecord::<D>::MASS];
            for i in 0..D {
                v[i] = if m > m_min && !fixed[i] { v[i] / m } else { 0.0 };
            }
        }
    });
}

/// Damped grid momentum update: v_I^{n+1} = (p_I + Δt f_I) / m_I, zero at constrained dofs
/// and empty nodes; and the acceleration the FLIP update carries to the points, the change
/// of the nodal velocity over the step, (v_I^{n+1} − v_I^n) / Δt with v_I^n = p_I / m_I:
/// f_I / m_I at a free dof and −p_I / (m_I Δt) at a held one, whose velocity the support
/// stops. Taken as zero there (as it was), a held dof would never tell a point's velocity
/// that its nodes stand still: in a column one cell wide between rollers, every x-dof is
/// held, and the points' x-velocities stayed at 2e-2 m/s (5.6e-3 of the peak) after 120 s
/// of damped settling while no point moved (docs/theory.md §10).
#[allow(clippy::too_many_arguments)]
fn nodal_update<const D: usize>(
    gathered: &[f64],
    fields: Fields,
    internal: Option<&[f64]>,
    constrained: &[bool],
    m_min: f64,
    dt: f64,
    damping: f64,
    velocity: &mut [f64],
    acceleration: &mut [f64],
) {
    let stride = fields.width;
    velocity.par_chunks_mut(D).zip(acceleration.par_chunks_mut(D)).enumerate().for_each(|(j, (v, a))| {
        let g = &gathered[j * stride..(j + 1) * stride];
        let m = g[NodeRecord::<D>::MASS];
        // The node of slot j: the slot itself with one field (no division on that path).
        let node = if fields.count == 1 { j } else { j / fields.count };
        for i in 0..D {
            let p = g[NodeRecord::<D>::MOMENTUM + i];
            if m <= m_min || constrained[node * D + i] {
                v[i] = 0.0;
                a[i] = if m > m_min { -p / (m * dt) } else { 0.0 };
                continue;
            }
            let mut f = g[NodeRecord::<D>::FORCE + i] + internal.map_or(0.0, |fi| fi[j * D + i]);
            // sign(v_I) = sign(p_I) since m_I > 0.
            f -= damping * f.abs() * sign(p);
            a[i] = f / m;
            v[i] = (p + dt * f) / m;
        }
    });
}

/// Grid → points into the scratch: FLIP/PIC velocity and the new position; a rigid body's
/// points move at its velocity over the step (`fields.1`, per field). Fails for a
/// non-finite result or a point leaving the grid (lowest point index first).
fn grid_to_points<const D: usize>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    fields: (Fields, &[RigidMotion<D>]),
    (velocity, acceleration): (&[f64], &[f64]),
    (dt, flip): (f64, f64),
    sc: &mut PointScratch<D>,
) -> PointResult {
    if fields.0.in_contact() {
        grid_to_points_in::<D, true>(model, basis, fields, velocity, acceleration, dt, flip, sc)
    } else {
        grid_to_points_in::<D, false>(model, basis, fields, velocity, acceleration, dt, flip, sc)
    }
}

/// [`grid_to_points`] with a field per body (`MANY`) or one.
#[allow(clippy::too_many_arguments)]
fn grid_to_points_in<const D: usize, const MANY: bool>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    (fields, rigid): (Fields, &[RigidMotion<D>]),
    velocity: &[f64],
    acceleration: &[f64],
    dt: f64,
    flip: f64,
    sc: &mut PointScratch<D>,
) -> PointResult {
    let pts = model.points();
    let grid = model.grid();
    let state = &mut sc.fields;
    let failure = state
        .position
        .par_iter_mut()
        .zip(state.velocity.par_iter_mut())
        .enumerate()
        .filter_map(|(p, (x, v))| {
            let (mut vi, mut ai) = (SVector::<f64, D>::zeros(), SVector::<f64, D>::zeros());
            let field = if MANY { fields.of_point(model, p) } else { 0 };
            if MANY && fields.is_rigid(field) {
                // A rigid body's point keeps its prescribed velocity, whatever the grid's.
                *v = rigid[field].expect("a rigid field has its motion").0;
                *x = pts.position()[p] + *v * dt;
                return (!grid.contains(x)).then_some((p, PointFailure::Outside));
            }
            basis.for_each_node(p, |node, n, _| {
                let slot = if MANY { fields.slot(node, field) } else { node };
                for i in 0..D {
                    vi[i] += n * velocity[slot * D + i];
                    ai[i] += n * acceleration[slot * D + i];
                }
            });
            *v = (pts.velocity()[p] + ai * dt) * flip + vi * (1.0 - flip);
            *x = pts.position()[p] + vi * dt;
            if !(v.iter().all(|c| c.is_finite()) && x.iter().all(|c| c.is_finite())) {
                let reason = format!(
                    "non-finite velocity {:?} or position {:?} after the grid update",
                    v.as_slice(),
                    x.as_slice()
                );
                return Some((p, PointFailure::Unstable(reason)));
            }
            if !grid.contains(x) {
                return Some((p, PointFailure::Outside));
            }
            None
        })
        .min_by_key(|(p, _)| *p);
    failure.map_or(Ok(()), Err)
}

/// Stress update of every point from the nodal velocities `velocity` into the scratch,
/// with the rest of its new state the commit exchanges: F ← ΔF F, the volume det ΔF v_p
/// and the half-lengths stretched with the new F (iGIMP, `stretched_half_length`) — in the
/// same pass over the points that reads their committed F, instead of a second one at the
/// commit.
fn update_stress<const D: usize>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    fields: Fields,
    velocity: &[f64],
    dt: f64,
    sc: &mut PointScratch<D>,
) -> PointResult {
    // Compiled once for each: a plane run's increment keeps its known zero zz entry, which
    // the law's update folds (1.5 % of the 2D step's instructions when tested per point).
    match (model.axisymmetric(), fields.in_contact()) {
        (true, true) => update_stress_in::<D, true, true>(model, basis, fields, velocity, dt, sc),
        (true, false) => update_stress_in::<D, true, false>(model, basis, fields, velocity, dt, sc),
        (false, true) => update_stress_in::<D, false, true>(model, basis, fields, velocity, dt, sc),
        (false, false) => update_stress_in::<D, false, false>(model, basis, fields, velocity, dt, sc),
    }
}

/// [`update_stress`] in axisymmetry (`AXISYMMETRIC`: the hoop strain) or not, with a field
/// per body (`MANY`) or one.
fn update_stress_in<const D: usize, const AXISYMMETRIC: bool, const MANY: bool>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    fields: Fields,
    velocity: &[f64],
    dt: f64,
    sc: &mut PointScratch<D>,
) -> PointResult {
    let pts = model.points();
    let hs = pts.history_stride();
    let f = &mut sc.fields;
    // Blocks of points zipped, not single points: rayon's zip of six fields costs per item
    // what the block's plain loop does not (27 instructions a point-step in 2D).
    let failure = (
        f.deformation_gradient.par_chunks_mut(POINT_BLOCK),
        f.volume.par_chunks_mut(POINT_BLOCK),
        f.half_length.par_chunks_mut(POINT_BLOCK),
        f.stress.par_chunks_mut(POINT_BLOCK),
        f.elastic_strain.par_chunks_mut(POINT_BLOCK),
        f.history.par_chunks_mut(POINT_BLOCK * hs.max(1)),
    )
        .into_par_iter()
        .enumerate()
        .filter_map(|(block, (f_new, volume, half_length, stress, elastic, history))| {
            for k in 0..f_new.len() {
                let p = block * POINT_BLOCK + k;
                let out = PointOut {
                    deformation_gradient: &mut f_new[k],
                    volume: &mut volume[k],
                    stress: &mut stress[k],
                    elastic_strain: &mut elastic[k],
                    history: &mut history[k * hs.max(1)..][..hs],
                };
                let field = (fields, if MANY { fields.of_point(model, p) } else { 0 });
                if let Err(reason) = point_stress::<D, AXISYMMETRIC, MANY>(model, basis, field, velocity, dt, p, out) {
                    return Some((p, PointFailure::Unstable(reason)));
                }
            }
            // In a loop of its own, eight points at a time: the closed-form stretch is a chain
            // of roots, a division and an arc cosine, which the next points' stretches
            // overlap here but not when a whole stress update lies between them (3D block:
            // the step 3-4 % faster), and more when computed stage by stage together (2 %).
            let l0 = &pts.half_length0()[block * POINT_BLOCK..][..f_new.len()];
            let lanes = f_new.len() - f_new.len() % STRETCH_LANES;
            for k in (0..lanes).step_by(STRETCH_LANES) {
                let l = stretched_half_lengths::<D, STRETCH_LANES>(
                    std::array::from_fn(|j| &l0[k + j]),
                    std::array::from_fn(|j| &f_new[k + j]),
                );
                half_length[k..k + STRETCH_LANES].copy_from_slice(&l);
            }
            for k in lanes..f_new.len() {
                half_length[k] = stretched_half_length(&l0[k], &f_new[k]);
            }
            None
        })
        .min_by_key(|(p, _)| *p);
    failure.map_or(Ok(()), Err)
}

/// Points per block of a pass that zips several per-point fields.
const POINT_BLOCK: usize = 256;

/// Points whose iGIMP stretches are computed together (`stretched_half_lengths`).
const STRETCH_LANES: usize = 8;

/// Where a point's update goes: its new F, volume, stress, elastic strain and history.
struct PointOut<'a> {
    deformation_gradient: &'a mut Matrix3<f64>,
    volume: &'a mut f64,
    stress: &'a mut Matrix3<f64>,
    elastic_strain: &'a mut Matrix3<f64>,
    history: &'a mut [f64],
}

/// Point `p`'s update from the nodal velocities: ΔF = I + Δt Σ_I v_I ⊗ ∇N_I, checked for
/// a blow-up (non-finite, inverted or torn apart within the step), then the shared point
/// kernel, written into `out` (F ← ΔF F, V_p ← det ΔF V_p, σ, b^e or ε^e, history); or
/// why the point became unstable.
#[inline]
fn point_stress<const D: usize, const AXISYMMETRIC: bool, const MANY: bool>(
    model: &Model<D>,
    basis: &AxisBasis<D>,
    (fields, field): (Fields, usize),
    velocity: &[f64],
    dt: f64,
    p: usize,
    out: PointOut<'_>,
) -> Result<(), String> {
    let pts = model.points();
    if MANY && fields.is_rigid(field) {
        // A rigid body is not strained: its points keep their state.
        *out.deformation_gradient = pts.deformation_gradient()[p];
        *out.volume = pts.volume()[p];
        *out.stress = pts.stress()[p];
        *out.elastic_strain = pts.elastic_strain()[p];
        out.history.copy_from_slice(pts.history(p));
        return Ok(());
    }
    let mut l = SMatrix::<f64, D, D>::zeros();
    basis.for_each_node(p, |node, _, g| {
        let slot = if MANY { fields.slot(node, field) } else { node };
        let v = SVector::<f64, D>::from_column_slice(&velocity[slot * D..(slot + 1) * D]);
        l += v * g.transpose();
    });
    let mut grad_du = embed(&(l * dt));
    if AXISYMMETRIC {
        // The hoop strain increment Δt v_r / r (docs/theory.md §20).
        grad_du[(2, 2)] = dt * carried(basis, (fields, field), velocity, p)[0] / model.points().position()[p][0];
    }
    let df = Matrix3::identity() + grad_du;
    if !df.iter().all(|c| c.is_finite()) {
        return Err("non-finite velocity gradient".into());
    }
    let det = df.determinant();
    if !det.is_finite() || det <= 0.0 {
        return Err(format!("det ΔF = {det:e}: the point was inverted or torn apart within one step"));
    }
    let committed = Committed::of(pts, p);
    // Borrowed, not moved out of the Result: each move (or `map_err`) copies the update's
    // three tensors (such copies were 3.7 % of the 2D block's step: CHANGELOG.md,
    // Explicit speed).
    let updated = update_point_stress(model.kinematics(), model.law(p), &grad_du, committed, out.history);
    let u = match &updated {
        Ok(u) => u,
        Err(e) => return Err(format!("stress update failed: {e}")),
    };
    if !u.stress.iter().chain(u.elastic_strain.iter()).all(|c| c.is_finite()) {
        return Err("stress update failed: non-finite stress".into());
    }
    *out.stress = u.stress;
    *out.elastic_strain = u.elastic_strain;
    *out.volume = det * pts.volume()[p];
    *out.deformation_gradient = u.delta_f * pts.deformation_gradient()[p];
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use loam_constitutive::Elastic;
    use loam_grid::{BasisKind, Grid};
    use loam_points::{PointStore, Shape};
    use nalgebra::Vector2;
    use std::sync::Arc;

    /// A 2×2-cell block of 4 points per cell in a 6×6 grid, given velocity `v`.
    fn block(v: Vector2<f64>, gravity: Vector2<f64>) -> Model<2> {
        block_with(v, gravity, vec![])
    }

    /// The block of [`block`] with `constraints`.
    fn block_with(v: Vector2<f64>, gravity: Vector2<f64>, constraints: Vec<loam_model::PlaneConstraint>) -> Model<2> {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(0.5, 0.5), [6, 6]).unwrap();
        let mut points = PointStore::new();
        points
            .fill(&grid, &Shape::Box { min: Vector2::new(1.0, 1.0), max: Vector2::new(2.0, 2.0) }, 2, 800.0, 0)
            .unwrap();
        points.velocity_mut().iter_mut().for_each(|x| *x = v);
        let law = Elastic::new(2e5, 0.25).unwrap();
        Model::new(grid, BasisKind::Gimp, Kinematics::FiniteStrain, points, vec![Arc::new(law)], constraints, gravity)
            .unwrap()
    }

    /// The block moving at 0.1 along x, run for `duration` in fixed steps of `dt`.
    fn fixed_steps(dt: f64, duration: f64) -> Explicit<2> {
        let settings = ExplicitSettings {
            time_step: TimeStep::Fixed { dt, allow_above_critical: false },
            ..ExplicitSettings::new(duration)
        };
        Explicit::new(block(Vector2::new(0.1, 0.0), Vector2::zeros()), settings).unwrap()
    }

    #[test]
    fn sign_is_zero_at_zero() {
        assert_eq!(sign(0.0), 0.0);
        assert_eq!(sign(-0.0), 0.0);
        assert_eq!(sign(2.0), 1.0);
        assert_eq!(sign(-1e-300), -1.0);
    }

    /// The critical step is h / (c + |v|) with c = √(M/ρ) (docs/theory.md §10), to round-off.
    #[test]
    fn critical_time_step_is_the_cfl_limit() {
        let v = Vector2::new(3.0, 4.0);
        let ex = Explicit::new(block(v, Vector2::zeros()), ExplicitSettings::new(1.0)).unwrap();
        let (e, nu, rho): (f64, f64, f64) = (2e5, 0.25, 800.0);
        let m = e * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let expected = 0.5 / ((m / rho).sqrt() + 5.0);
        assert!((ex.critical_time_step().unwrap() - expected).abs() <= 1e-14 * expected);
    }

    /// A step that would leave less than the shortest step allowed is stretched to the end:
    /// 1e-12 short of a whole number of fixed steps, the run still lands exactly on its
    /// duration instead of refusing a 1e-12 sliver as a collapsed step.
    #[test]
    fn a_sliver_before_the_end_is_taken_with_the_last_step() {
        let mut ex = fixed_steps(1e-4, 1e-2);
        ex.time = 1e-2 - 1e-4 - 1e-12;
        let report = ex.step().unwrap();
        assert_eq!((report.dt, ex.time()), (1e-2 - (1e-2 - 1e-4 - 1e-12), 1e-2));
        assert!(ex.is_finished());
    }

    /// A body velocity of 1e300 makes Δt_crit = h / (c + |v|) ≈ 5e-301: the run stops at
    /// its first step naming the point, instead of looping with time stuck at 0. All points
    /// move alike, so the named one is any of them, with the grid's carried speed: 1e300 to
    /// round-off (p_I / m_I and Σ N_I are 1 to a few ulps).
    #[test]
    fn a_collapsed_time_step_stops_the_run() {
        let model = block(Vector2::new(1e300, 0.0), Vector2::zeros());
        let n = model.points().len();
        let mut ex = Explicit::new(model, ExplicitSettings::new(1.0)).unwrap();
        match ex.step() {
            Err(ExplicitError::TimeStepCollapsed { step: 1, time, dt, floor, point, speed, .. }) => {
                assert_eq!((time, floor), (0.0, 1e-9));
                assert!(point < n && (speed / 1e300 - 1.0).abs() < 1e-15, "point {point}, speed {speed:e}");
                assert!(dt < 1e-299, "dt {dt}");
            }
            other => panic!("expected a collapsed time step, got {other:?}"),
        }
        assert_eq!((ex.steps_done(), ex.time()), (0, 0.0));
    }

    /// Fixed steps that divide the duration up to rounding end exactly on it: no sliver
    /// step, and a step after the end is refused.
    #[test]
    fn the_last_step_lands_on_the_duration() {
        let mut ex = fixed_steps(1e-4, 1e-3);
        let mut reports = Vec::new();
        ex.run(|r, _| {
            reports.push(r.clone());
            Ok::<_, std::io::Error>(())
        })
        .unwrap();
        assert_eq!(reports.len(), 10);
        assert_eq!(ex.time(), 1e-3);
        assert!(ex.is_finished());
        assert!(matches!(ex.step(), Err(ExplicitError::Finished(10))));

        // A step that does not divide the duration: the last one is shortened.
        let mut ex = fixed_steps(3e-4, 1e-3);
        let mut dts = Vec::new();
        while !ex.is_finished() {
            dts.push(ex.step().unwrap().dt);
        }
        assert_eq!(dts.len(), 4);
        assert!((dts[3] - 1e-4).abs() < 1e-15, "last dt {}", dts[3]);
        assert_eq!(ex.time(), 1e-3);
    }

    /// A free block under gravity falls with the gravity acceleration: momentum grows by
    /// M g Δt per step exactly as the nodal forces sum to the total weight (partition of
    /// unity), to round-off (1e-12 relative).
    #[test]
    fn free_fall_gains_the_impulse_of_gravity() {
        let g = Vector2::new(0.0, -9.81);
        for scheme in [UpdateScheme::Usf, UpdateScheme::Usl, UpdateScheme::Musl] {
            let settings = ExplicitSettings { scheme, ..ExplicitSettings::new(0.02) };
            let mut ex = Explicit::new(block(Vector2::zeros(), g), settings).unwrap();
            while !ex.is_finished() {
                ex.step().unwrap();
            }
            let m = ex.model().points().total_mass();
            let p = ex.model().points().momentum();
            let expected = g * m * 0.02;
            assert!((p - expected).norm() <= 1e-12 * expected.norm(), "{scheme:?}: {p} vs {expected}");
            // Uniform acceleration produces no stress (rigid motion).
            let smax = ex.model().points().stress().iter().map(|s| s.amax()).fold(0.0, f64::max);
            assert!(smax < 1e-6, "{scheme:?}: stress {smax}");
        }
    }

    #[test]
    fn a_constraint_on_an_empty_plane_is_reported() {
        let base = loam_model::PlaneConstraint::new(1, 0, [true, true, false]);
        let model = block_with(Vector2::zeros(), Vector2::zeros(), vec![base]);
        let mut ex = Explicit::new(model, ExplicitSettings::new(1.0)).unwrap();
        let e = ex.check().unwrap_err();
        assert!(
            matches!(e, ExplicitError::Connect(ConnectError::ConstraintTouchesNoNode { index: 0, axis: 1, plane: 0 })),
            "{e}"
        );
    }
}
