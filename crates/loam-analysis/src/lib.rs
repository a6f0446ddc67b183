//! One stepping interface over the three analyses — quasi-static load stepping, implicit
//! Newmark dynamics and explicit MPM — for a program that runs whichever a problem asks
//! for (the scene runner, the CLI) without knowing a file format; and the procedures built
//! on a quasi-static analysis: the strength-reduction search for a factor of safety
//! ([`StrengthReduction`]).

mod strength_reduction;

pub use strength_reduction::{
    has_strength, reduced_strength, FactorOfSafety, SearchSoFar, StrengthReduction, StrengthReductionError,
    StrengthTrial, TrialStart,
};

use loam_explicit::{Explicit, ExplicitError, ExplicitState};
use loam_implicit::{Dynamic, DynamicState, Peak, QuasiStatic, QuasiStaticState, StepError, StepReport};
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

/// A load-controlled quasi-static step that could not go on: the load factor reached is the
/// most the model carries, the limit load (as close as the step's cut-backs resolve it).
#[derive(Debug, Clone, PartialEq)]
pub struct Collapse {
    /// The step that could not be completed.
    pub step: usize,
    /// The load factor reached, the last converged: the most the model carried.
    pub load_factor: f64,
    /// The load factor of the smallest attempt beyond it, which failed.
    pub attempted: f64,
    /// Why that attempt failed.
    pub reason: String,
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
    /// The force of each support on the material, in the order: grid-plane constraints,
    /// inclined rollers, body constraints, frictional planes, rigid bodies. Implicit
    /// analyses give the first four; explicit ones the rollers', frictional planes' and
    /// rigid bodies' (NaN for the rest).
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

    /// How far the analysis is, in [0, 1] (what a progress bar shows): the share of the
    /// duration reached, or of the load ([`QuasiStatic::fraction_done`]).
    pub fn fraction_done(&self) -> f64 {
        match self {
            Analysis::QuasiStatic(a) => a.fraction_done(),
            _ => (self.time() / self.end_time()).clamp(0.0, 1.0),
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
            Analysis::QuasiStatic(a) => a.linear_solver_description(),
            Analysis::Dynamic(a) => a.linear_solver_description(),
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

    /// The same analysis from its start with every material's strength divided by `factor`
    /// (strength reduction's trial law, [`reduced_strength`]): after a search
    /// has bracketed the factor of safety, the run carries on at the largest factor that
    /// held, so its outputs show the state just before failure. Quasi-static analyses.
    pub fn with_strength_reduced(&self, factor: f64) -> Result<Self, StrengthReductionError> {
        match self {
            Analysis::QuasiStatic(a) => {
                let reduced = reduced_strength(a.model(), factor)?;
                Ok(Analysis::QuasiStatic(QuasiStatic::new(reduced, a.settings().clone())))
            }
            _ => Err(StrengthReductionError::NotQuasiStatic(self.name())),
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

    /// Under arc-length control, the most load carried so far and the step that carried
    /// it (`None` otherwise).
    pub fn peak(&self) -> Option<Peak> {
        match self {
            Analysis::QuasiStatic(a) => a.peak(),
            _ => None,
        }
    }

    /// The collapse `error` means, if it is one: a quasi-static step that could not go on
    /// while a load follows the load factor ([`Model::load_controlled`]), after some of it
    /// was carried. A failure at the first increment, under prescribed displacements, or
    /// of another analysis, is no limit load.
    pub fn collapse(&self, error: &AnalysisError) -> Option<Collapse> {
        match (self, error) {
            (
                Analysis::QuasiStatic(a),
                AnalysisError::Implicit(StepError::NotConverged { step, reached, load_factor, reason, .. }),
            ) if a.model().load_controlled() && *reached > 0.0 => {
                Some(Collapse { step: *step, load_factor: *reached, attempted: *load_factor, reason: reason.clone() })
            }
            _ => None,
        }
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
                    reactions: explicit_reactions(a.model(), &r.plane_forces, &r.rigid_forces),
                    wall_time: r.wall_time,
                }
            }
        })
    }
}

/// An explicit step's supports' forces in the order of [`Progress::reactions`]: the
/// rollers' and frictional planes' from `plane_forces` (rollers first), the rigid bodies'
/// from `rigid_forces`, NaN for the rest.
fn explicit_reactions<const D: usize>(
    model: &Model<D>,
    plane_forces: &[[f64; 3]],
    rigid_forces: &[[f64; 3]],
) -> Vec<[f64; 3]> {
    let unknown = |n: usize| std::iter::repeat_n([f64::NAN; 3], n);
    let rollers = model.inclined_rollers().len();
    (unknown(model.constraints().len()).chain(plane_forces[..rollers].iter().copied()))
        .chain(unknown(model.body_constraints().len()))
        .chain(plane_forces[rollers..].iter().copied())
        .chain(rigid_forces.iter().copied())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use loam_constitutive::{Elastic, VonMises};
    use loam_explicit::ExplicitSettings;
    use loam_grid::{BasisKind, Grid};
    use loam_implicit::QuasiStaticSettings;
    use loam_model::{Kinematics, PlaneConstraint};
    use loam_points::{PointStore, Shape};
    use nalgebra::{Matrix3, Vector2};
    use std::sync::Arc;

    /// A 2 × 2 m von Mises block (σ_y = 10, 2 × 2 points per 0.5 m cell) on rollers,
    /// under gravity.
    fn block() -> Model<2> {
        block_under(Vector2::new(0.0, -10.0), vec![])
    }

    /// The block under gravity `g`, with `more` constraints beside its base.
    fn block_under(g: Vector2<f64>, more: Vec<PlaneConstraint>) -> Model<2> {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(0.5, 0.5), [6, 6]).unwrap();
        let mut points = PointStore::new();
        let shape = Shape::Box { min: Vector2::new(0.5, 0.0), max: Vector2::new(2.5, 2.0) };
        points.fill(&grid, &shape, 2, 1.0, 0).unwrap();
        let law = Arc::new(VonMises::new(Elastic::new(1e4, 0.3).unwrap(), 10.0, 0.0).unwrap());
        let base = PlaneConstraint::new(1, 0, [true, true, false]);
        let constraints = [vec![base], more].concat();
        Model::new(grid, BasisKind::Gimp, Kinematics::SmallStrain, points, vec![law], constraints, g).unwrap()
    }

    fn quasi_static() -> Analysis<2> {
        Analysis::QuasiStatic(QuasiStatic::new(block(), QuasiStaticSettings { load_steps: 4, ..Default::default() }))
    }

    /// The interface reports each analysis's step the same way: a quasi-static step is a
    /// load increment of 1/4 with Newton iterations and a reaction (the base carries the
    /// weight, 4 m² × 1 × 10 / 4 = 10 per step, to Newton's tolerance); an explicit step
    /// reports its time step as the increment, no Newton iterations, NaN residual and NaN
    /// reactions of grid planes.
    #[test]
    fn steps_report_their_progress() {
        let mut qs = quasi_static();
        let r = qs.step().unwrap();
        assert_eq!((r.step, r.load_factor, r.increment), (1, 0.25, 0.25));
        assert!(r.iterations >= 1 && r.final_residual < 1e-6);
        assert!((r.reactions[0][1].abs() - 10.0).abs() < 1e-6, "{:?}", r.reactions);
        assert_eq!((qs.time(), qs.load_level()), (0.25, LoadLevel::Factor(0.25)));
        let mut ex = Analysis::Explicit(Explicit::new(block(), ExplicitSettings::new(0.01)).unwrap());
        let r = ex.step().unwrap();
        assert_eq!((r.step, r.iterations, r.substeps), (1, 0, 1));
        // The block's grid-plane constraints have no explicit reaction: NaN, one each.
        let unknown = r.reactions.iter().all(|f| f.iter().all(|v| v.is_nan()));
        assert!(r.final_residual.is_nan() && r.reactions.len() == ex.model().constraints().len() && unknown);
        assert_eq!((r.increment, r.time, ex.time()), (r.time, r.time, r.time));
        assert_eq!((ex.name(), ex.end_time(), ex.load_factor()), ("explicit", 0.01, 1.0));
    }

    /// The strength-reduced analysis starts again with σ_y / F: a deviatoric stress of
    /// q = σ_y / 2 = 5 is on the yield surface of F = 2, not of the original.
    #[test]
    fn a_strength_reduced_analysis_starts_again_weaker() {
        let mut qs = quasi_static();
        qs.step().unwrap();
        let reduced = qs.with_strength_reduced(2.0).unwrap();
        assert_eq!(reduced.steps_done(), 0);
        let q = 5.0;
        let stress = Matrix3::new(q / 3f64.sqrt(), 0.0, 0.0, 0.0, -q / 3f64.sqrt(), 0.0, 0.0, 0.0, 0.0);
        let h = [0.0];
        assert!(reduced.model().materials()[0].is_yielding(&stress, &h));
        assert!(!qs.model().materials()[0].is_yielding(&stress, &h));
        let ex = Analysis::Explicit(Explicit::new(block(), ExplicitSettings::new(0.01)).unwrap());
        assert!(matches!(ex.with_strength_reduced(2.0), Err(StrengthReductionError::NotQuasiStatic("explicit"))));
    }

    /// A state of another analysis is refused and changes nothing; points removed through
    /// the interface are gone from the model the next step runs on.
    #[test]
    fn states_of_other_analyses_are_refused_and_points_change() {
        let mut qs = quasi_static();
        let explicit = AnalysisState::Explicit(ExplicitState { steps: 3, time: 0.5 });
        let saved = ModelState { points: block().points().clone(), load_vertices: Vec::new(), mesh_nodes: None };
        let e = qs.resume(explicit, saved).unwrap_err();
        assert!(e.to_string().contains("not of a quasi-static analysis"), "{e}");
        assert_eq!(qs.steps_done(), 0);
        let top = Shape::Box { min: Vector2::new(0.0, 1.5), max: Vector2::new(3.0, 3.0) };
        assert_eq!(qs.change_points(PointChange::RemoveIn(top)).unwrap(), 16);
        let r = qs.step().unwrap();
        assert!((r.reactions[0][1].abs() - 7.5).abs() < 1e-6, "three quarters of the weight: {:?}", r.reactions);
    }

    /// A quasi-static step that cannot go on while gravity follows the load factor is a
    /// collapse at the load factor it reached; the same failure of a block pushed by a
    /// prescribed displacement (weightless or not), one at the first increment, another
    /// error, or an explicit analysis's, is none.
    #[test]
    fn a_failed_step_is_a_collapse_only_under_load() {
        let failed = || {
            AnalysisError::Implicit(StepError::NotConverged {
                step: 3,
                reached: 0.61,
                load_factor: 0.62,
                cutbacks: 9,
                reason: "indefinite".into(),
                residuals: vec![],
            })
        };
        let collapse = quasi_static().collapse(&failed()).unwrap();
        assert_eq!((collapse.step, collapse.load_factor, collapse.attempted), (3, 0.61, 0.62));
        assert_eq!(collapse.reason, "indefinite");
        let top = PlaneConstraint::new(1, 4, [false, true, false]).displaced([0.0, -0.01, 0.0]);
        let pushed = block_under(Vector2::zeros(), vec![top]);
        let pushed = Analysis::QuasiStatic(QuasiStatic::new(pushed, QuasiStaticSettings::default()));
        assert_eq!(pushed.collapse(&failed()), None);
        let top = PlaneConstraint::new(1, 4, [false, true, false]).displaced([0.0, -0.01, 0.0]);
        let heavy_and_pushed = block_under(Vector2::new(0.0, -10.0), vec![top]);
        let heavy_and_pushed =
            Analysis::QuasiStatic(QuasiStatic::new(heavy_and_pushed, QuasiStaticSettings::default()));
        assert_eq!(heavy_and_pushed.collapse(&failed()), None, "mixed control is no limit load");
        let at_once = AnalysisError::Implicit(StepError::NotConverged {
            step: 1,
            reached: 0.0,
            load_factor: 0.001,
            cutbacks: 8,
            reason: "indefinite".into(),
            residuals: vec![],
        });
        assert_eq!(quasi_static().collapse(&at_once), None, "nothing carried: no limit load");
        assert_eq!(quasi_static().collapse(&AnalysisError::Implicit(StepError::Finished(4))), None);
        let ex = Analysis::Explicit(Explicit::new(block(), ExplicitSettings::new(0.01)).unwrap());
        assert_eq!(ex.collapse(&failed()), None);
    }
}
