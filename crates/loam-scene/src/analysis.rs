//! The analysis part of a scene: a quasi-static, implicit dynamic or explicit analysis of
//! the model with its settings, and the checks that need the whole analysis — every
//! constraint holds a node, every point's basis lies in the grid, an explicit fixed step
//! is stable — so that a scene is refused before its first step.

use super::locate::Seg;
use super::solver::Solver;
use super::{
    AnalysisSpec, ControlSpec, LawSpec, LinearSpec, LoadedScene, MethodSpec, SceneError, StrengthReductionSpec,
};
use loam_analysis::{has_strength, Analysis, AnalysisError};
use loam_explicit::{Explicit, ExplicitError, ExplicitSettings, TimeStep};
use loam_implicit::{
    ArcLengthSettings, Dynamic, DynamicSettings, LoadControl, QuasiStatic, QuasiStaticSettings, StepError,
};
use loam_kernels::{ConnectError, InvalidSetting};
use loam_model::{AnalysisKind, Model, ModelOption, Unaccepted};

/// The path of the analysis's `key`.
fn analysis_key(key: &str) -> [Seg<'_>; 2] {
    [Seg::Key("analysis"), Seg::Key(key)]
}

/// The most halvings of a step.
const MAX_CUTBACKS: usize = 40;

impl LoadedScene {
    /// The scene's analysis of `model`; each setting the analysis refuses is reported at
    /// its key.
    pub(super) fn analysis<const D: usize>(&self, model: Model<D>, solver: Solver) -> Result<Analysis<D>, SceneError> {
        let Solver { newton, linear_solver, extrapolate } = solver;
        self.check_cutbacks()?;
        Ok(match self.scene.analysis {
            AnalysisSpec::QuasiStatic {
                load_steps,
                max_cutbacks,
                strength_reduction,
                control,
                limit_resolution,
                ..
            } => {
                if load_steps == 0 {
                    return Err(self.error(&analysis_key("load_steps"), "load_steps is 0; it must be at least 1"));
                }
                if !(0.0..1.0).contains(&limit_resolution) {
                    return Err(self.error(&analysis_key("limit_resolution"), format!("limit_resolution is {limit_resolution}; it must be from 0 (halve max_cutbacks times) to below 1 (a fraction of the full load)")));
                }
                if let Some(srf) = strength_reduction {
                    self.check_strength_reduction(&srf, &model)?;
                }
                let control = self.load_control(control, &model, newton.max_iterations)?;
                let settings = QuasiStaticSettings {
                    load_steps,
                    newton,
                    max_cutbacks,
                    linear_solver,
                    extrapolate,
                    control,
                    limit_resolution,
                };
                model.check_accepted_by(AnalysisKind::QuasiStatic).map_err(|r| self.unaccepted(&r))?;
                Analysis::QuasiStatic(QuasiStatic::new(model, settings))
            }
            AnalysisSpec::ImplicitDynamic { time_step, duration, beta, gamma, bossak_alpha, mass, max_cutbacks } => {
                let mass = mass.into();
                let settings = DynamicSettings {
                    time_step,
                    duration,
                    beta,
                    gamma,
                    bossak_alpha,
                    mass,
                    newton,
                    max_cutbacks,
                    linear_solver,
                };
                self.dynamic(model, settings)?
            }
            AnalysisSpec::Explicit { duration, ref time_step, scheme, flip, damping } => {
                let time_step = time_step.into();
                let settings = ExplicitSettings { scheme: scheme.into(), flip, time_step, damping, duration };
                self.explicit(model, settings)?
            }
        })
    }

    /// At most `MAX_CUTBACKS` halvings of a step: 2⁻⁴⁰ of a load step is below what
    /// round-off resolves, and each halving that fails costs a Newton solve, so a larger
    /// limit only makes a failing run look hung.
    fn check_cutbacks(&self) -> Result<(), SceneError> {
        let max_cutbacks = match self.scene.analysis {
            AnalysisSpec::QuasiStatic { max_cutbacks, .. } | AnalysisSpec::ImplicitDynamic { max_cutbacks, .. } => {
                max_cutbacks
            }
            AnalysisSpec::Explicit { .. } => return Ok(()),
        };
        if max_cutbacks > MAX_CUTBACKS {
            let message = format!("max_cutbacks is {max_cutbacks}; it must be at most {MAX_CUTBACKS} (2^-{MAX_CUTBACKS} of a step is below round-off)");
            return Err(self.error(&analysis_key("max_cutbacks"), message));
        }
        Ok(())
    }

    /// The load control of a quasi-static analysis. Arc-length control scales the dead
    /// loads along its arc: it needs one (gravity not preloaded, a point force or a load),
    /// and takes no prescribed displacement (the analysis is then displacement-controlled
    /// already), no follower load (its load direction is the dead loads'), and no strength
    /// reduction (whose trials are load-controlled).
    fn load_control<const D: usize>(
        &self,
        control: ControlSpec,
        model: &Model<D>,
        max_iterations: usize,
    ) -> Result<LoadControl, SceneError> {
        let ControlSpec::ArcLength { steps, iterations, max_growth } = control else {
            return Ok(LoadControl::LoadFactor);
        };
        let at = |key: &'static str| [Seg::Key("analysis"), Seg::Key("control"), Seg::Key(key)];
        if steps < 2 {
            return Err(self.error(&at("steps"), format!("steps is {steps}; it must be at least 2 (the first step is load-controlled, the arc starts at the second)")));
        }
        if !(1..=max_iterations).contains(&iterations) {
            return Err(self.error(
                &at("iterations"),
                format!(
                    "iterations is {iterations}; it must be from 1 to the solver's max_iterations ({max_iterations})"
                ),
            ));
        }
        if !(max_growth.is_finite() && max_growth >= 1.0) {
            return Err(self.error(&at("max_growth"), format!("max_growth is {max_growth}; it must be a number of at least 1 (a multiple of the first step's length)")));
        }
        let arc = "arc-length control (analysis.control)";
        if let AnalysisSpec::QuasiStatic { load_steps: 1, .. } = self.scene.analysis {
            return Err(self.error(&analysis_key("load_steps"), format!("load_steps is 1, so the first, load-controlled step of {arc} would carry the whole load and the arc never start; use at least 2 (the first step carries 1 / load_steps)")));
        }
        if let Some(linear @ (LinearSpec::Cholesky | LinearSpec::Cg)) = self.scene.solver.linear {
            return Err(self.error(&[Seg::Key("solver"), Seg::Key("linear")], format!("linear: {linear:?} needs a positive definite tangent, which {arc} leaves at a peak; use Direct (LU), Iterative (BiCGStab), Lu or BiCgStab")));
        }
        if let Some(k) = model.constraints().iter().position(|c| c.is_displaced()) {
            return Err(self.error(&[Seg::Key("constraints"), Seg::Index(k)], format!("constraint {k} prescribes a displacement, and {arc} scales loads, not displacements: a displacement-controlled analysis follows a peak without it; use control: LoadFactor, or replace the displacement by a load")));
        }
        if let Some(k) = model.body_constraints().iter().position(|c| c.is_displaced()) {
            return Err(self.error(&[Seg::Key("body_constraints"), Seg::Index(k)], format!("body constraint {k} prescribes a displacement, and {arc} scales loads, not displacements: a displacement-controlled analysis follows a peak without it; use control: LoadFactor, or replace the displacement by a load")));
        }
        if let Some(k) = model.loads().iter().position(|l| l.is_follower()) {
            return Err(self.error(
                &[Seg::Key("loads"), Seg::Index(k), Seg::Key("follower")],
                format!("load {k} follows the surface; {arc} scales dead loads only: use follower: false"),
            ));
        }
        if self.scene_strength_reduction() {
            return Err(self.error(
                &[Seg::Key("analysis"), Seg::Key("strength_reduction")],
                format!("strength reduction runs load-controlled trials; remove it, or {arc}"),
            ));
        }
        if !model.load_controlled() {
            return Err(self.error(&[Seg::Key("analysis"), Seg::Key("control")], format!("{arc} needs a load that the load factor scales: gravity (not preloaded by a geostatic stress), a point force or a load; this scene has none")));
        }
        Ok(LoadControl::ArcLength(ArcLengthSettings { steps, iterations, max_growth }))
    }

    fn scene_strength_reduction(&self) -> bool {
        matches!(self.scene.analysis, AnalysisSpec::QuasiStatic { strength_reduction: Some(_), .. })
    }

    /// A bracket (holds, fails) with 0 < holds < fails, a tolerance below its width, and a
    /// material with a strength to reduce.
    fn check_strength_reduction<const D: usize>(
        &self,
        srf: &StrengthReductionSpec,
        model: &Model<D>,
    ) -> Result<(), SceneError> {
        let at = |key: &'static str| [Seg::Key("analysis"), Seg::Key("strength_reduction"), Seg::Key(key)];
        let (lo, hi) = srf.bracket;
        if !(lo.is_finite() && lo > 0.0 && hi.is_finite() && hi > lo) {
            return Err(self.error(
                &at("bracket"),
                format!("bracket is ({lo}, {hi}); it must be (F_holds, F_fails) with 0 < F_holds < F_fails"),
            ));
        }
        if !(srf.tolerance.is_finite() && srf.tolerance > 0.0 && srf.tolerance < hi - lo) {
            return Err(self.error(
                &at("tolerance"),
                format!(
                    "tolerance is {}; it must be positive and below the bracket's width {}",
                    srf.tolerance,
                    hi - lo
                ),
            ));
        }
        let cam_clay = self.scene.materials.iter().position(|m| matches!(m.law, LawSpec::ModifiedCamClay { .. }));
        if let Some(i) = cam_clay {
            return Err(self.error(
                &[Seg::Key("materials"), Seg::Index(i), Seg::Key("law")],
                format!(
                    "material \"{}\": strength reduction is not defined for ModifiedCamClay (its strength follows its \
                     state, with no c and tan φ to divide); use MohrCoulomb or DruckerPrager for a factor of safety",
                    self.scene.materials[i].name
                ),
            ));
        }
        if !has_strength(model) {
            return Err(self.error(&[Seg::Key("materials")], "strength reduction needs a material with a strength (VonMises, MohrCoulomb or DruckerPrager); every material here is elastic"));
        }
        Ok(())
    }

    fn dynamic<const D: usize>(&self, model: Model<D>, settings: DynamicSettings) -> Result<Analysis<D>, SceneError> {
        match Dynamic::new(model, settings) {
            Ok(d) => Ok(Analysis::Dynamic(d)),
            Err(StepError::InvalidSettings(InvalidSetting { field, value, valid })) => {
                Err(self.error(&analysis_key(field), format!("{field} is {value}; valid: {valid}")))
            }
            Err(StepError::Unaccepted(refusal)) => Err(self.unaccepted(&refusal)),
            Err(e) => Err(self.error(&[Seg::Key("analysis")], e.to_string())),
        }
    }

    /// A model option the analysis does not take, reported at the option's key.
    fn unaccepted(&self, refusal: &Unaccepted) -> SceneError {
        let at: Vec<Seg> = match refusal.option {
            ModelOption::InclinedRoller { index } => vec![Seg::Key("inclined_rollers"), Seg::Index(index)],
            ModelOption::FrictionalPlane { index } => vec![Seg::Key("frictional_planes"), Seg::Index(index)],
            ModelOption::BodyContact => vec![Seg::Key("body_contact")],
            ModelOption::RigidBody { index } => vec![Seg::Key("rigid_bodies"), Seg::Index(index)],
            ModelOption::BodyConstraint { index } | ModelOption::DisplacedBodyConstraint { index } => {
                vec![Seg::Key("body_constraints"), Seg::Index(index)]
            }
            ModelOption::DisplacedConstraint { index } => vec![Seg::Key("constraints"), Seg::Index(index)],
            ModelOption::GhostPenalty => vec![Seg::Key("ghost_penalty")],
            ModelOption::GeometricallyLinear => vec![Seg::Key("geometrically_linear")],
            ModelOption::Water => vec![Seg::Key("water")],
            ModelOption::AntiLocking => vec![Seg::Key("anti_locking")],
            ModelOption::BodyFittedMesh => vec![Seg::Key("method")],
        };
        self.error(&at, refusal.to_string())
    }

    /// Explicit MPM; the FEM reference runs with the implicit analyses only.
    fn explicit<const D: usize>(&self, model: Model<D>, settings: ExplicitSettings) -> Result<Analysis<D>, SceneError> {
        if self.scene.method == MethodSpec::UpdatedLagrangianFem {
            return Err(self.error(&[Seg::Key("method")], "method UpdatedLagrangianFem runs with the implicit analyses (QuasiStatic, ImplicitDynamic) only; use method: Mpm for Explicit"));
        }
        match Explicit::new(model, settings) {
            Ok(e) => Ok(Analysis::Explicit(e)),
            Err(ExplicitError::InvalidSettings(InvalidSetting { field, value, valid })) => {
                let key = if field.starts_with("time_step") { "time_step" } else { field };
                Err(self.error(&analysis_key(key), format!("{field} is {value}; valid: {valid}")))
            }
            Err(ExplicitError::Unaccepted(refusal)) => Err(self.unaccepted(&refusal)),
            Err(e @ ExplicitError::ContactScheme(_)) => Err(self.error(&analysis_key("scheme"), e.to_string())),
            Err(e) => Err(self.error(&[Seg::Key("analysis")], e.to_string())),
        }
    }

    /// What only the whole analysis can tell: a constraint that holds no active node, a
    /// point whose basis reaches outside the grid, and (explicit) a fixed step above the
    /// critical one, refused here before any output.
    pub(super) fn check_before_the_first_step<const D: usize>(
        &self,
        analysis: &mut Analysis<D>,
    ) -> Result<(), SceneError> {
        analysis.check().map_err(|e| match e.connect_error() {
            Some(&ConnectError::ConstraintTouchesNoNode { index, .. }) => {
                self.error(&[Seg::Key("constraints"), Seg::Index(index)], format!("constraint {index}: {e}"))
            }
            Some(&ConnectError::InclinedRollerTouchesNoNode { index }) => {
                self.error(&[Seg::Key("inclined_rollers"), Seg::Index(index)], e.to_string())
            }
            Some(&ConnectError::BodyConstraintTouchesNoNode { index }) => {
                self.error(&[Seg::Key("body_constraints"), Seg::Index(index)], e.to_string())
            }
            Some(&ConnectError::LoadOffMaterial { load, .. }) => {
                self.error(&[Seg::Key("loads"), Seg::Index(load)], e.to_string())
            }
            Some(ConnectError::PointOutsideGrid { source, .. }) => self.error(
                &[Seg::Key("bodies")],
                format!("material point {} at {:?}: its basis reaches outside the grid ({}); enlarge the grid or move the body", source.point, source.position, source.source),
            ),
            _ => match &e {
                AnalysisError::Explicit(ExplicitError::TimeStepCollapsed { .. }) => self.error(&[Seg::Key("bodies")], e.to_string()),
                AnalysisError::Implicit(StepError::Unsupported { .. }) => self.error(&[Seg::Key("constraints")], e.to_string()),
                _ => self.error(&[], e.to_string()),
            },
        })?;
        if let Analysis::Explicit(e) = &*analysis {
            if let TimeStep::Fixed { dt, allow_above_critical: false } = e.settings().time_step {
                // `check` has located every point, so this finds them again.
                let critical = e.critical_time_step().map_err(|err| self.error(&[], err.to_string()))?;
                if dt > critical {
                    return Err(self.error(&analysis_key("time_step"), format!(
                        "the fixed time step {dt:e} is above the critical step {critical:e} (h / (max c_p + max |v_I|)): the explicit run would blow up; use Cfl(0.5), a step ≤ {critical:e}, or allow_above_critical: true"
                    )));
                }
            }
        }
        Ok(())
    }
}
