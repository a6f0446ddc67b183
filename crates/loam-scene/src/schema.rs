//! The scene file's schema: the types RON text deserialises into, with their defaults.
//! Nothing here checks a value; the builder parts of `scene` do, each at its place in
//! the file. `docs/scene-format.md` documents every key.

use loam_implicit::QuasiStaticSettings;
use loam_solve::NewtonSettings;
use serde::Deserialize;

/// A scene as written in the file.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// One line saying what the scene is.
    #[serde(default)]
    pub title: String,
    /// 2 (plane strain, or axisymmetric with `axisymmetric: true`) or 3.
    pub dimension: usize,
    /// A 2D scene read as the meridian plane of a body of revolution about the y axis, x
    /// the radius (docs/theory.md §20; default false).
    #[serde(default)]
    pub axisymmetric: bool,
    pub grid: GridSpec,
    #[serde(default = "default_basis")]
    pub basis: BasisSpec,
    #[serde(default = "default_kinematics")]
    pub kinematics: KinematicsSpec,
    /// The material point method (default), or the updated Lagrangian FEM reference.
    #[serde(default)]
    pub method: MethodSpec,
    /// Volumetric-locking treatment: `None` (default), `BBar` or
    /// `AssumedStrain(stabilization: β)` (small strain), `FBar` (finite strain); linear
    /// basis or the FEM reference.
    #[serde(default)]
    pub anti_locking: AntiLockingSpec,
    /// Small strain on the initial configuration: points keep their places (default false).
    #[serde(default)]
    pub geometrically_linear: bool,
    /// Face ghost penalty γ on cut cells (implicit MPM; docs/theory.md §15): `None`
    /// (default) or `Some(γ)`, γ > 0, 0.01–1 useful.
    #[serde(default)]
    pub ghost_penalty: Option<f64>,
    /// Initial stress: `None` (default: unstressed, gravity applied with the load factor)
    /// or `Geostatic(k0: ..)` (level or layered ground; gravity acts in full from the start).
    #[serde(default)]
    pub initial_stress: InitialStressSpec,
    pub materials: Vec<MaterialSpec>,
    pub bodies: Vec<BodySpec>,
    /// Body force per unit mass at full load; D components.
    pub gravity: Vec<f64>,
    #[serde(default)]
    pub constraints: Vec<ConstraintSpec>,
    /// Rollers on inclined planes: the nodes on or beyond each plane held along its normal
    /// (every analysis; default none).
    #[serde(default)]
    pub inclined_rollers: Vec<InclinedRollerSpec>,
    /// Rigid planes with Coulomb friction that the material may leave (every analysis;
    /// default none).
    #[serde(default)]
    pub frictional_planes: Vec<FrictionalPlaneSpec>,
    /// The bodies in frictional contact with each other, a velocity field each (Explicit;
    /// default `None`: bodies that meet move together).
    #[serde(default)]
    pub body_contact: Option<BodyContactSpec>,
    /// Named bodies moved as rigid wholes at a prescribed velocity, in frictional contact
    /// with the material (Explicit; default none).
    #[serde(default)]
    pub rigid_bodies: Vec<RigidBodySpec>,
    /// Constraints on named bodies: the nodes each body's points (inside a box, if given)
    /// reach, held or displaced; they follow the body through the grid (implicit
    /// analyses; default none).
    #[serde(default)]
    pub body_constraints: Vec<BodyConstraintSpec>,
    /// Loads beside gravity: forces at points, tractions and pressures on the bodies'
    /// boundaries.
    #[serde(default)]
    pub loads: Vec<LoadSpec>,
    /// Static groundwater: `Some((unit_weight: γ_w, level: Horizontal(h)))`, a 2D
    /// `Polyline([(x, h), ...])` or an inclined `Plane(height, slope)` level (default
    /// none). Implicit analyses.
    #[serde(default)]
    pub water: Option<WaterSpec>,
    pub analysis: AnalysisSpec,
    /// Monitoring points: each names the material point nearest `at` (where the points
    /// start), whose displacement and stress `run_log.csv` writes every step (default
    /// none).
    #[serde(default)]
    pub monitor: Vec<MonitorSpec>,
    /// Excavation stages: after step `after_step`, the points whose place lies in `region`
    /// are removed (default none).
    #[serde(default)]
    pub excavation: Vec<ExcavationSpec>,
    #[serde(default)]
    pub solver: SolverSpec,
    #[serde(default)]
    pub output: OutputSpec,
}

/// What a load-controlled quasi-static run does at collapse.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(deny_unknown_fields)]
pub enum CollapseSpec {
    /// End the run with the collapse load as its result (exit status 0).
    #[default]
    Report,
    /// Stop the run with the step's error (exit status 1).
    Error,
}

/// How a QuasiStatic analysis advances the load.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Default)]
pub enum ControlSpec {
    /// The load factor, in `load_steps` equal steps from 0 to 1.
    #[default]
    LoadFactor,
    /// Arc-length control (docs/theory.md §21): at most `steps` steps (the first,
    /// load-controlled, included), each aiming at `iterations` Newton corrections (default
    /// 6), none longer than `max_growth` (default 10) times the first. The run ends after
    /// its steps, or once the load factor reaches 1 or falls back to 0.
    ArcLength {
        steps: usize,
        #[serde(default = "default_arc_iterations")]
        iterations: usize,
        #[serde(default = "default_arc_growth")]
        max_growth: f64,
    },
}

fn default_limit_resolution() -> f64 {
    QuasiStaticSettings::default().limit_resolution
}

fn default_arc_iterations() -> usize {
    loam_implicit::ArcLengthSettings::default().iterations
}

fn default_arc_growth() -> f64 {
    loam_implicit::ArcLengthSettings::default().max_growth
}

/// A constraint on a body, named by its `name`: the nodes that its points inside
/// `within` (all of them if not given) reach.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum BodyConstraintSpec {
    /// All displacement components are zero.
    Fixed {
        body: String,
        #[serde(default)]
        within: Option<RegionSpec>,
    },
    /// Prescribed displacement at full load: one entry per axis, `Some(u)` prescribed
    /// (`Some(0.0)` held), `None` free. Applied with the load factor of a quasi-static
    /// analysis (a rigid footing or a pile pushed into the ground).
    Displacement {
        body: String,
        displacement: Vec<Option<f64>>,
        #[serde(default)]
        within: Option<RegionSpec>,
    },
}

/// A roller on an inclined plane.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct InclinedRollerSpec {
    /// A point of the plane.
    pub point: Vec<f64>,
    /// The plane's normal, pointing into the material.
    pub normal: Vec<f64>,
}

/// A rigid plane with Coulomb friction.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct FrictionalPlaneSpec {
    /// A point of the plane.
    pub point: Vec<f64>,
    /// The plane's normal, pointing into the material.
    pub normal: Vec<f64>,
    /// The Coulomb coefficient μ (0: smooth).
    pub friction: f64,
}

/// Contact between bodies.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BodyContactSpec {
    /// The Coulomb coefficient μ between every two bodies (0: smooth).
    pub friction: f64,
}

/// A rigid body.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RigidBodySpec {
    /// The name of the body (in `bodies`) that moves as a rigid whole.
    pub body: String,
    /// Its velocity from the start; D components.
    pub velocity: Vec<f64>,
    /// The Coulomb coefficient μ against the material (default 0: smooth).
    #[serde(default)]
    pub friction: f64,
    /// The factor of the velocity against time (default `Constant`: moved from the start);
    /// e.g. `Table([(0.0, 0.0), (1.0, 0.0), (1.1, 1.0)])` holds it for 1 s, then moves it.
    #[serde(default)]
    pub time: TimeFunctionSpec,
}

/// A monitoring point.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MonitorSpec {
    /// Its name in the run log's columns: letters, digits and `_`.
    pub name: String,
    /// Where it is: the material point that starts nearest this place.
    pub at: Vec<f64>,
}

/// One excavation stage.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ExcavationSpec {
    /// The step after which the region is excavated (1 or more).
    pub after_step: usize,
    /// Where the points go: any body shape.
    pub region: ShapeSpec,
}

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct GridSpec {
    pub origin: Vec<f64>,
    pub cell_size: Vec<f64>,
    pub cells: Vec<usize>,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
pub enum BasisSpec {
    Linear,
    Gimp,
    QuadraticBSpline,
}

/// Initial stress of the points.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Default)]
pub enum InitialStressSpec {
    #[default]
    None,
    /// σ_v = weight of the material above, σ_h = k0 σ_v.
    Geostatic { k0: f64 },
}

/// Volumetric-locking treatment.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Default)]
pub enum AntiLockingSpec {
    #[default]
    None,
    /// B-bar: each point's dilatation averaged over its cell (element).
    BBar,
    /// Assumed strain: the cell's average strain plus β times each point's deviatoric
    /// deviation from it (0 < β ≤ 1).
    AssumedStrain { stabilization: f64 },
    /// F-bar (finite strain): each point's increment of deformation scaled to its cell's
    /// volume change.
    FBar,
}

/// How the bodies are discretised.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
pub enum MethodSpec {
    /// Material points on the background grid, reset every step.
    #[default]
    Mpm,
    /// The updated Lagrangian FEM reference: every Box body meshed by elements of about
    /// one grid cell, `points_per_cell` Gauss points per axis (1–3) as the points; the mesh
    /// moves with the body and is never reset. Implicit analyses only.
    UpdatedLagrangianFem,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
pub enum KinematicsSpec {
    SmallStrain,
    FiniteStrain,
}

fn default_basis() -> BasisSpec {
    BasisSpec::Gimp
}

fn default_kinematics() -> KinematicsSpec {
    KinematicsSpec::FiniteStrain
}

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    pub name: String,
    pub density: f64,
    pub law: LawSpec,
}

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum LawSpec {
    /// Linear elasticity in small strain; Hencky elasticity in finite strain.
    Elastic { young: f64, poisson: f64 },
    /// J2 plasticity: yield stress σ_y (c_u = σ_y/√3 in plane strain), linear hardening
    /// (negative: softening) down to an optional residual yield stress.
    VonMises {
        young: f64,
        poisson: f64,
        yield_stress: f64,
        #[serde(default)]
        hardening: f64,
        #[serde(default)]
        residual_yield_stress: Option<f64>,
    },
    /// Mohr–Coulomb: cohesion, friction and dilation angles in degrees (associated when
    /// dilation = friction), optional tension cut-off and linear softening.
    MohrCoulomb {
        young: f64,
        poisson: f64,
        cohesion: f64,
        friction: f64,
        dilation: f64,
        #[serde(default)]
        tension_cutoff: Option<f64>,
        #[serde(default)]
        softening: Option<SofteningSpec>,
    },
    /// Modified Cam clay: λ and κ (e–ln p′ slopes), the void ratio e₀ of the modified
    /// indices, the critical-state slope, the shear stiffness and the initial
    /// preconsolidation (default normally consolidated, OCR 1). Needs an initial stress.
    ModifiedCamClay {
        lambda: f64,
        kappa: f64,
        void_ratio: f64,
        critical_state: CriticalStateSpec,
        shear: CamClayShearSpec,
        #[serde(default = "normally_consolidated")]
        initial: CamClayInitialSpec,
        /// M follows the Lode angle: M in triaxial compression, Mohr–Coulomb's ratio
        /// (3 − sin φ′)/(3 + sin φ′) of it in extension (default false: M everywhere).
        #[serde(default)]
        lode_dependent: bool,
    },
    /// Drucker–Prager: the smooth cone fitted to Mohr–Coulomb's c, φ, ψ (degrees) in plane
    /// strain (default), triaxial compression or extension; optional linear softening.
    DruckerPrager {
        young: f64,
        poisson: f64,
        cohesion: f64,
        friction: f64,
        dilation: f64,
        #[serde(default)]
        fit: ConeFitSpec,
        #[serde(default)]
        softening: Option<SofteningSpec>,
    },
}

/// Modified Cam clay's critical-state slope: M itself, or the critical-state friction
/// angle φ′ (degrees) it is matched to in triaxial compression (M = 6 sin φ′/(3 − sin φ′)).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
pub enum CriticalStateSpec {
    Slope(f64),
    Friction(f64),
}

/// Modified Cam clay's shear stiffness: a constant modulus G, or a Poisson's ratio ν with
/// which G follows the pressure-dependent bulk modulus.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
pub enum CamClayShearSpec {
    Modulus(f64),
    Poisson(f64),
}

/// Modified Cam clay's initial preconsolidation pressure: an over-consolidation ratio on
/// the surface through each point's initial stress, or one p_c for every point.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
pub enum CamClayInitialSpec {
    OverConsolidation(f64),
    Preconsolidation(f64),
}

fn normally_consolidated() -> CamClayInitialSpec {
    CamClayInitialSpec::OverConsolidation(1.0)
}

/// How a Drucker–Prager cone is fitted to Mohr–Coulomb.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
pub enum ConeFitSpec {
    /// Mohr–Coulomb's collapse stresses in plane strain (inscribed for associated flow,
    /// wider for ψ < φ).
    #[default]
    PlaneStrain,
    /// Through the triaxial-compression meridian.
    Compression,
    /// Through the triaxial-extension meridian.
    Extension,
}

/// Linear softening of a Mohr–Coulomb or Drucker–Prager strength to residual values (angles in degrees),
/// reached at the accumulated plastic shear strain `plastic_strain`.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SofteningSpec {
    pub cohesion: f64,
    pub friction: f64,
    pub dilation: f64,
    pub plastic_strain: f64,
}

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// The body's name, by which a body constraint names it (default "": unnamed).
    #[serde(default)]
    pub name: String,
    /// Name of a material in `materials`.
    pub material: String,
    pub shape: ShapeSpec,
    #[serde(default = "default_ppc")]
    pub points_per_cell: usize,
    /// Initial velocity of the body's points (dynamic analyses); default at rest.
    #[serde(default)]
    pub velocity: Option<VelocitySpec>,
    /// This body may overlap the bodies before it: the points of both fill the overlap, so
    /// its mass and stiffness count twice there. Default false: an overlap is refused.
    #[serde(default)]
    pub may_overlap: bool,
}

/// An initial velocity field.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum VelocitySpec {
    /// The same velocity everywhere; D components.
    Uniform(Vec<f64>),
    /// v(x) = amplitude · sin(2π (x_axis − origin) / wavelength): a standing-wave mode,
    /// e.g. the vibrating bar's first mode with wavelength 4L.
    Sine {
        amplitude: Vec<f64>,
        axis: Axis,
        wavelength: f64,
        #[serde(default)]
        origin: f64,
    },
}

fn default_ppc() -> usize {
    2
}

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum ShapeSpec {
    Box {
        min: Vec<f64>,
        max: Vec<f64>,
    },
    /// 2D only: vertices [x, y] in order.
    Polygon {
        vertices: Vec<[f64; 2]>,
    },
    /// A disk (2D) or ball (3D).
    Ball {
        centre: Vec<f64>,
        radius: f64,
    },
    /// 3D only: the polygon `section` (vertices in the two other axes, in increasing axis
    /// order: (x, z) for `axis: Y`) extruded along `axis` from `from` to `to`.
    Prism {
        section: Vec<[f64; 2]>,
        axis: Axis,
        from: f64,
        to: f64,
    },
    /// A box less the half-space on the side of `normal` of the plane through `point`.
    CutBox {
        min: Vec<f64>,
        max: Vec<f64>,
        point: Vec<f64>,
        normal: Vec<f64>,
    },
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    pub(super) fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum ConstraintSpec {
    /// The displacement normal to the grid plane `axis = at` is zero.
    Roller {
        axis: Axis,
        at: f64,
        #[serde(default)]
        within: Option<RegionSpec>,
    },
    /// All displacement components on the grid plane `axis = at` are zero.
    Fixed {
        axis: Axis,
        at: f64,
        #[serde(default)]
        within: Option<RegionSpec>,
    },
    /// Prescribed displacement at full load on the nodes of the grid plane `axis = at`
    /// (inside `within`, if given): one entry per axis, `Some(u)` prescribed, `None` free.
    /// Applied with the load factor of a quasi-static analysis (a footing pushed down).
    Displacement {
        axis: Axis,
        at: f64,
        displacement: Vec<Option<f64>>,
        #[serde(default)]
        within: Option<RegionSpec>,
    },
}

/// A load. Each follows the load factor of a QuasiStatic analysis, and its `time` function
/// in ImplicitDynamic and Explicit ones (default: in full from t = 0).
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum LoadSpec {
    /// A force at a point of the material (D components each), spread to the nodes
    /// through the basis at its place; the point moves with the body.
    PointLoad {
        at: Vec<f64>,
        force: Vec<f64>,
        #[serde(default)]
        time: TimeFunctionSpec,
    },
    /// A dead traction (force per unit area, D components) on the boundary of body `body`
    /// (index in `bodies`, default 0) inside the box `within` (default: all of it).
    Traction {
        #[serde(default)]
        body: usize,
        #[serde(default)]
        within: Option<RegionSpec>,
        traction: Vec<f64>,
        #[serde(default)]
        time: TimeFunctionSpec,
    },
    /// A pressure (positive pushes into the body) on the boundary of body `body` inside
    /// `within`; `follower: true` (finite strain) turns and stretches it with the surface.
    Pressure {
        #[serde(default)]
        body: usize,
        #[serde(default)]
        within: Option<RegionSpec>,
        pressure: PressureSpec,
        #[serde(default)]
        follower: bool,
        #[serde(default)]
        time: TimeFunctionSpec,
    },
}

/// Static groundwater: the water's unit weight and its phreatic level.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct WaterSpec {
    pub unit_weight: f64,
    pub level: LevelSpec,
}

/// The phreatic level.
#[derive(Debug, Clone, Deserialize, PartialEq)]
pub enum LevelSpec {
    /// A level water table at this height (the coordinate along gravity's axis).
    Horizontal(f64),
    /// 2D: (horizontal coordinate, height) pairs, horizontal coordinates increasing; held
    /// level beyond the ends.
    Polyline(Vec<(f64, f64)>),
    /// A plane (a line in 2D): `height` above the origin of the horizontal axes, rising by
    /// `slope[a]` per unit along each axis (D entries; the vertical one must be 0).
    Plane { height: f64, slope: Vec<f64> },
}

/// How a pressure varies over the surface, in the initial configuration.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum PressureSpec {
    Uniform(f64),
    /// p(x) = value + gradient · (x − at).
    Linear {
        value: f64,
        at: Vec<f64>,
        gradient: Vec<f64>,
    },
    /// p = unit_weight × (level − x_v) below `level`, 0 above; x_v is the last coordinate
    /// (y in 2D, z in 3D).
    Hydrostatic {
        level: f64,
        unit_weight: f64,
    },
}

/// The factor on a load over time (dynamic and explicit analyses).
#[derive(Debug, Clone, Deserialize, PartialEq, Default)]
pub enum TimeFunctionSpec {
    #[default]
    Constant,
    /// 0 at t = 0 up to 1 at t = duration, then held.
    Ramp { duration: f64 },
    /// Piecewise linear through (time, factor) pairs, times increasing.
    Table(Vec<(f64, f64)>),
}

/// A box limiting a constraint to part of its plane.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RegionSpec {
    pub min: Vec<f64>,
    pub max: Vec<f64>,
}

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum AnalysisSpec {
    /// Loads applied in `load_steps` equal steps with Newton's method per step.
    QuasiStatic {
        load_steps: usize,
        #[serde(default = "default_cutbacks")]
        max_cutbacks: usize,
        /// Find the factor of safety first (strength reduction), then run the analysis with
        /// the largest factor that held, so the outputs show the state just before failure.
        #[serde(default)]
        strength_reduction: Option<StrengthReductionSpec>,
        /// A step that cannot go on where a load follows the load factor: `Report` (the
        /// default) ends the run with the load factor carried at most, its state written in
        /// full; `Error` stops it with the step's error.
        #[serde(default)]
        at_collapse: CollapseSpec,
        /// How the load advances: `LoadFactor` (the default), in `load_steps` equal steps;
        /// or `ArcLength(steps: N)`, a first step of 1 / `load_steps` and then steps of a
        /// length of the displacement increment, which follow the load past its peak.
        #[serde(default)]
        control: ControlSpec,
        /// Where only forces follow the load factor, the smallest load increment an
        /// attempt takes, as a fraction of the full load: a collapse is found to this
        /// resolution (default 1e-3; 0: by `max_cutbacks` alone).
        #[serde(default = "default_limit_resolution")]
        limit_resolution: f64,
    },
    /// Implicit Newmark dynamics (Bossak with `bossak_alpha` < 0), loads applied in full at
    /// t = 0, Newton per time step, a failed step halved up to `max_cutbacks` times.
    ImplicitDynamic {
        time_step: f64,
        duration: f64,
        #[serde(default = "default_beta")]
        beta: f64,
        #[serde(default = "default_gamma")]
        gamma: f64,
        #[serde(default)]
        bossak_alpha: f64,
        #[serde(default)]
        mass: MassSpec,
        #[serde(default = "default_cutbacks")]
        max_cutbacks: usize,
    },
    /// Explicit MPM (no Newton): `time_step` Cfl(safety) or Fixed(dt); a fixed step above
    /// the critical one is refused unless `allow_above_critical`.
    Explicit {
        duration: f64,
        #[serde(default = "default_explicit_step")]
        time_step: TimeStepSpec,
        #[serde(default)]
        scheme: SchemeSpec,
        #[serde(default = "default_flip")]
        flip: f64,
        #[serde(default)]
        damping: f64,
    },
}

fn default_beta() -> f64 {
    0.25
}

fn default_gamma() -> f64 {
    0.5
}

fn default_flip() -> f64 {
    loam_explicit::ExplicitSettings::DEFAULT_FLIP
}

fn default_explicit_step() -> TimeStepSpec {
    TimeStepSpec::Cfl(0.5)
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
pub enum MassSpec {
    #[default]
    Lumped,
    Consistent,
}

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub enum TimeStepSpec {
    /// Δt = safety × the critical step, every step.
    Cfl(f64),
    /// A fixed Δt.
    Fixed {
        dt: f64,
        #[serde(default)]
        allow_above_critical: bool,
    },
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
pub enum SchemeSpec {
    Usf,
    Usl,
    #[default]
    Musl,
}

/// A strength-reduction analysis (Griffiths & Lane 1999): c and tan φ (σ_y for von Mises)
/// divided by F; the loads are applied in the analysis's load steps at `bracket.0` (which
/// must hold), then F is raised towards `bracket.1` (which must fail) until it is
/// bracketed to `tolerance` (`start` says how).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StrengthReductionSpec {
    #[serde(default = "default_bracket")]
    pub bracket: (f64, f64),
    #[serde(default = "default_srf_tolerance")]
    pub tolerance: f64,
    #[serde(default)]
    pub start: TrialStartSpec,
}

/// Where each strength-reduction trial after the first starts.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
pub enum TrialStartSpec {
    /// From the last state that held, its strength lowered in `load_steps` steps at full
    /// load (the default).
    #[default]
    LastHeld,
    /// From zero load, the loads applied anew at each trial's factor; bisection.
    Zero,
}

fn default_bracket() -> (f64, f64) {
    (1.0, 3.0)
}

fn default_srf_tolerance() -> f64 {
    0.01
}

fn default_cutbacks() -> usize {
    8
}

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct SolverSpec {
    pub residual_tolerance: f64,
    pub increment_tolerance: f64,
    pub max_iterations: usize,
    /// Most backtracks of the line search along one Newton correction (0: none).
    pub max_backtracks: usize,
    /// With `max_backtracks: 0`, the backtracks of the second try of a solve that failed
    /// with whole corrections, before the step is cut back (0: no second try).
    pub retry_backtracks: usize,
    /// `None`: `Auto`.
    pub linear: Option<LinearSpec>,
    /// Quasi-static: start each load step from the last increment, scaled (default false).
    pub extrapolate: bool,
}

impl Default for SolverSpec {
    fn default() -> Self {
        let n = NewtonSettings::default();
        Self {
            residual_tolerance: n.residual_tolerance,
            increment_tolerance: n.increment_tolerance,
            max_iterations: n.max_iterations,
            max_backtracks: n.max_backtracks,
            retry_backtracks: n.retry_backtracks,
            linear: None,
            extrapolate: QuasiStaticSettings::default().extrapolate,
        }
    }
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
pub enum LinearSpec {
    /// Direct below a size, iterative above it (the default).
    Auto,
    /// Sparse Cholesky or LU, from the tangent.
    Direct,
    /// Multigrid-preconditioned CG or BiCGStab, from the tangent.
    Iterative,
    Cholesky,
    Lu,
    Cg,
    BiCgStab,
}

#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields, default)]
pub struct OutputSpec {
    /// Write a VTU frame every this many steps (and always after the last); 0 = none.
    pub vtu_every: usize,
    /// Write `points_final.csv` after the last step.
    pub final_csv: bool,
    /// Write a `history.csv` row (time, energies, momentum) every this many steps (and
    /// after the last); 0 = none.
    pub history_every: usize,
    /// The per-point fields of the VTU frames (and the extra columns of
    /// `points_final.csv`); `None`: every field the model has.
    pub fields: Option<Vec<FieldSpec>>,
    /// How the VTU frames store their arrays: `Binary` (default: zlib-compressed, appended,
    /// Float32), `BinaryDouble` (the same, Float64) or `Ascii`.
    pub vtu_format: VtuFormatSpec,
}

/// How the VTU frames store their arrays (mirrors `output::VtuFormat`).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default)]
pub enum VtuFormatSpec {
    #[default]
    Binary,
    BinaryDouble,
    Ascii,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self { vtu_every: 1, final_csv: true, history_every: 1, fields: None, vtu_format: VtuFormatSpec::Binary }
    }
}

/// A per-point output field.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
pub enum FieldSpec {
    Displacement,
    Velocity,
    /// The Cauchy stress tensor.
    Stress,
    /// p = −tr σ / 3 (compression positive).
    MeanStress,
    /// q = √(3/2 s:s).
    DeviatoricStress,
    Volume,
    Mass,
    Material,
    /// The accumulated equivalent plastic (shear) strain (0 for elastic materials).
    PlasticStrain,
    /// 1 where the point is on its yield surface, 0 elsewhere.
    Yielding,
    /// Every history value of the laws, by name.
    History,
    /// The pore pressure p_w (with water).
    PorePressure,
    /// The total stress σ′ − p_w I (with water; `Stress` is the effective stress σ′).
    TotalStress,
}
