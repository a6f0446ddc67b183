//! Strength-reduction analysis (Griffiths & Lane 1999, Géotechnique 49(3)): the factor of
//! safety F of a slope is the factor by which c and tan φ (σ_y for von Mises) must be
//! divided for the slope to fail under its own weight ([`reduced_strength`]). A factor
//! has failed when the equilibrium iterations cannot converge — Griffiths & Lane's
//! criterion, with Newton and cut-back in place of their viscoplastic iterations — or the
//! body runs away (points leaving the grid, an FEM mesh too distorted).
//!
//! The search starts with the loads applied, in quasi-static load steps from zero, at the
//! lower factor of its bracket, which must hold. Then, by default
//! ([`TrialStart::LastHeld`]), it lowers the strength of that state and of every state
//! that held after it: the factor advances towards the upper end in `load_steps` equal
//! strength steps at full load, each cut back as a load step is; an attempt from the last
//! state that held which fails at an increment below half the tolerance ends the search
//! between the two (docs/theory.md §14). With [`TrialStart::Zero`] each trial applies the
//! loads from zero at its factor and bisection between a factor that held and one that
//! failed brackets F to the tolerance.

use loam_constitutive::ConstitutiveLaw;
use loam_implicit::{CutBack, LoadControl, QuasiStatic, QuasiStaticSettings, QuasiStaticState, StepError, StepScale};
use loam_kernels::{ConnectError, InvalidSetting};
use loam_model::{Model, ModelError, ModelState};
use loam_solve::NewtonReport;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Settings of a strength-reduction analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct StrengthReduction {
    /// How each trial applies gravity (load steps, Newton, cut-backs). A trial is
    /// load-controlled whatever `trial.control` says: it holds or fails at the full load.
    pub trial: QuasiStaticSettings,
    /// Factors that bracket F: the lower must hold, the upper must fail.
    pub bracket: (f64, f64),
    /// The search stops when the bracket is narrower than this.
    pub tolerance: f64,
    /// Where each trial after the first starts.
    pub start: TrialStart,
}

/// Where the trials of a strength-reduction search after the first start.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TrialStart {
    /// From the last state that held, its strength lowered in steps at full load (module
    /// docs).
    #[default]
    LastHeld,
    /// From zero load, each trial applying the loads anew at its factor; bisection.
    Zero,
}

/// What a search interrupted after some trials (a checkpoint's) hands back to resume it.
#[derive(Debug, Clone, Default)]
pub struct SearchSoFar<const D: usize> {
    pub trials: Vec<StrengthTrial>,
    /// Under [`TrialStart::LastHeld`], the state that held after the last of them.
    pub held: Option<(QuasiStaticState, ModelState<D>)>,
}

/// One trial factor and what it did.
#[derive(Debug, Clone, PartialEq)]
pub struct StrengthTrial {
    pub factor: f64,
    /// The full load was carried.
    pub stable: bool,
    /// Load factor reached (1 when stable, and in a trial from the last state that held,
    /// which keeps the full load).
    pub load_factor: f64,
    /// Newton corrections over the trial, cut-back attempts included only where converged.
    pub iterations: usize,
    /// Attempts cut back (in a trial from the last state that held: since the one before).
    pub cutbacks: usize,
    /// Largest point displacement at the end of the trial (at the last converged step).
    pub max_displacement: f64,
    pub wall_time: Duration,
}

/// The bracketed factor of safety and every trial.
#[derive(Debug, Clone, PartialEq)]
pub struct FactorOfSafety {
    /// The largest factor that held.
    pub stable: f64,
    /// The smallest factor that failed.
    pub failed: f64,
    pub trials: Vec<StrengthTrial>,
}

impl FactorOfSafety {
    /// The bracket's midpoint.
    pub fn value(&self) -> f64 {
        0.5 * (self.stable + self.failed)
    }
}

/// Why a strength-reduction analysis could not give a factor.
#[derive(Debug, thiserror::Error)]
pub enum StrengthReductionError {
    #[error("strength reduction: {0}")]
    InvalidSettings(InvalidSetting),
    #[error("the slope already fails at the lower bracket factor F = {0}: lower it")]
    FailsAtLower(f64),
    #[error("the slope still holds at the upper bracket factor F = {0}: raise it")]
    HoldsAtUpper(f64),
    #[error("strength reduction: {0}")]
    Reduction(String),
    #[error(transparent)]
    Model(#[from] ModelError),
    #[error("trial F = {factor}: {source}")]
    Trial { factor: f64, source: StepError },
    #[error("strength reduction runs quasi-static analyses, not {0} ones")]
    NotQuasiStatic(&'static str),
}

impl StrengthReduction {
    /// Bracket the factor of safety of `model` (at full strength, unloaded), calling
    /// `on_trial` after each trial with, from the last state that held, that analysis.
    pub fn factor_of_safety<const D: usize>(
        &self,
        model: &Model<D>,
        on_trial: impl FnMut(&StrengthTrial, Option<&QuasiStatic<D>>),
    ) -> Result<FactorOfSafety, StrengthReductionError> {
        self.factor_of_safety_after(model, SearchSoFar::default(), on_trial)
    }

    /// [`StrengthReduction::factor_of_safety`] resumed after the trials `so_far` (a
    /// checkpoint's): the search takes their outcomes instead of running them again (and,
    /// from the last state that held, goes on from the held state saved with them), so it
    /// goes on with the factors the interrupted search would have tried. `on_trial` is
    /// called for the new trials only; trials that are not this search's are refused.
    pub fn factor_of_safety_after<const D: usize>(
        &self,
        model: &Model<D>,
        so_far: SearchSoFar<D>,
        on_trial: impl FnMut(&StrengthTrial, Option<&QuasiStatic<D>>),
    ) -> Result<FactorOfSafety, StrengthReductionError> {
        self.validate()?;
        match self.start {
            TrialStart::Zero => self.bisect(model, &so_far.trials, on_trial),
            TrialStart::LastHeld => self.lower_held(model, so_far, on_trial),
        }
    }

    /// Bisection between trials that each apply the loads from zero.
    fn bisect<const D: usize>(
        &self,
        model: &Model<D>,
        done: &[StrengthTrial],
        mut on_trial: impl FnMut(&StrengthTrial, Option<&QuasiStatic<D>>),
    ) -> Result<FactorOfSafety, StrengthReductionError> {
        let (lo, hi) = self.bracket;
        let mut trials: Vec<StrengthTrial> = Vec::new();
        let mut run = |factor: f64| -> Result<bool, StrengthReductionError> {
            let t = match done.get(trials.len()) {
                Some(t) => saved_trial(t, trials.len(), factor)?,
                None => {
                    let t = self.trial(model, factor)?;
                    on_trial(&t, None);
                    t
                }
            };
            let stable = t.stable;
            trials.push(t);
            Ok(stable)
        };
        if !run(lo)? {
            return Err(StrengthReductionError::FailsAtLower(lo));
        }
        if run(hi)? {
            return Err(StrengthReductionError::HoldsAtUpper(hi));
        }
        let (mut stable, mut failed) = (lo, hi);
        while failed - stable > self.tolerance {
            let mid = 0.5 * (stable + failed);
            // A tolerance below the floating-point spacing of the factors would loop for
            // ever: stop when the bracket cannot be split.
            if mid <= stable || mid >= failed {
                break;
            }
            if run(mid)? {
                stable = mid;
            } else {
                failed = mid;
            }
        }
        Ok(FactorOfSafety { stable, failed, trials })
    }

    /// From the state that held at the lower factor, lower the strength in `load_steps`
    /// equal steps towards the upper one, each cut back down to half the tolerance
    /// (module docs); every attempt that converged is a trial that held, and the attempt
    /// that failed at the smallest increment the one that failed.
    fn lower_held<const D: usize>(
        &self,
        model: &Model<D>,
        so_far: SearchSoFar<D>,
        mut on_trial: impl FnMut(&StrengthTrial, Option<&QuasiStatic<D>>),
    ) -> Result<FactorOfSafety, StrengthReductionError> {
        let (mut held, first) = self.held_at_lower(model, &so_far, &mut on_trial)?;
        let mut trials = so_far.trials;
        trials.extend(first);
        let mut ladder = StrengthSteps::new(self);
        if let Some((stable, failed)) = ladder.replay(&trials)? {
            return Ok(FactorOfSafety { stable, failed, trials });
        }
        let mut clock = Instant::now();
        while let Some(target) = ladder.next_attempt() {
            match lower_strength(&mut held, model, target)? {
                Ok(report) => {
                    let t = ladder.held(target, report, &held, clock.elapsed());
                    on_trial(&t, Some(&held));
                    trials.push(t);
                    clock = Instant::now();
                }
                Err(reason) => {
                    if let Some(t) = ladder.failed(target, reason, &held, clock.elapsed()) {
                        let stable = ladder.position;
                        on_trial(&t, Some(&held));
                        trials.push(t);
                        return Ok(FactorOfSafety { stable, failed: target, trials });
                    }
                }
            }
        }
        Err(StrengthReductionError::HoldsAtUpper(self.bracket.1))
    }

    /// The analysis that held: run from zero at the lower factor (with that first trial),
    /// or (resuming) rebuilt from the state saved after the trials so far, at the factor of
    /// the last that held.
    fn held_at_lower<const D: usize>(
        &self,
        model: &Model<D>,
        so_far: &SearchSoFar<D>,
        on_trial: &mut impl FnMut(&StrengthTrial, Option<&QuasiStatic<D>>),
    ) -> Result<(QuasiStatic<D>, Option<StrengthTrial>), StrengthReductionError> {
        let lo = self.bracket.0;
        let Some(first) = so_far.trials.first() else {
            let (t, qs) = self.trial_analysis(model, lo)?;
            on_trial(&t, Some(&qs));
            return if t.stable { Ok((qs, Some(t))) } else { Err(StrengthReductionError::FailsAtLower(lo)) };
        };
        saved_trial(first, 0, lo)?;
        if !first.stable {
            return Err(StrengthReductionError::FailsAtLower(lo));
        }
        let Some((state, points)) = so_far.held.clone() else {
            return Err(StrengthReductionError::Reduction(
                "the saved search holds no state that held to go on from".into(),
            ));
        };
        let factor = so_far.trials.iter().rev().find(|t| t.stable).map_or(lo, |t| t.factor);
        let mut qs = QuasiStatic::new(reduced_strength(model, factor)?, self.trial_settings());
        qs.resume(state, points)?;
        Ok((qs, None))
    }

    /// Refuse a bracket that is not 0 < lower < upper or a tolerance that is not positive.
    fn validate(&self) -> Result<(), StrengthReductionError> {
        let (lo, hi) = self.bracket;
        if !(lo.is_finite() && lo > 0.0) {
            return Err(StrengthReductionError::InvalidSettings(InvalidSetting {
                field: "bracket.0",
                value: lo,
                valid: "a positive number",
            }));
        }
        if !(hi.is_finite() && hi > lo) {
            return Err(StrengthReductionError::InvalidSettings(InvalidSetting {
                field: "bracket.1",
                value: hi,
                valid: "a number above the lower factor",
            }));
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(StrengthReductionError::InvalidSettings(InvalidSetting {
                field: "tolerance",
                value: self.tolerance,
                valid: "a positive number",
            }));
        }
        Ok(())
    }

    /// A trial's settings: load-controlled whatever `trial.control` says (it holds or
    /// fails at the full load). A trial from zero, whose failure is the search's sign of
    /// collapse, takes whole Newton corrections without a second try
    /// (`NewtonSettings::retry`; docs/theory.md §14); under [`TrialStart::LastHeld`]
    /// only the first trial runs here, at the lower factor, which must hold.
    fn trial_settings(&self) -> QuasiStaticSettings {
        let mut newton = self.trial.newton;
        if self.start == TrialStart::Zero {
            newton.retry_backtracks = 0;
        }
        QuasiStaticSettings { control: LoadControl::LoadFactor, newton, ..self.trial.clone() }
    }

    /// Apply the full load to the model reduced by `factor`.
    pub fn trial<const D: usize>(
        &self,
        model: &Model<D>,
        factor: f64,
    ) -> Result<StrengthTrial, StrengthReductionError> {
        self.trial_analysis(model, factor).map(|(t, _)| t)
    }

    /// [`StrengthReduction::trial`], and the analysis at its end.
    fn trial_analysis<const D: usize>(
        &self,
        model: &Model<D>,
        factor: f64,
    ) -> Result<(StrengthTrial, QuasiStatic<D>), StrengthReductionError> {
        let start = Instant::now();
        let mut qs = QuasiStatic::new(reduced_strength(model, factor)?, self.trial_settings());
        let (mut iterations, mut cutbacks, mut stable) = (0, 0, true);
        while !qs.is_finished() {
            match qs.step() {
                Ok(r) => {
                    iterations += r.iterations;
                    cutbacks += r.cutbacks;
                }
                Err(StepError::NotConverged { cutbacks: c, .. }) => {
                    cutbacks += c;
                    stable = false;
                    break;
                }
                Err(e) if runs_away(&e) => {
                    stable = false;
                    break;
                }
                Err(source) => return Err(StrengthReductionError::Trial { factor, source }),
            }
        }
        let max_displacement = qs.model().points().max_displacement();
        let trial = StrengthTrial {
            factor,
            stable,
            load_factor: qs.load_factor(),
            iterations,
            cutbacks,
            max_displacement,
            wall_time: start.elapsed(),
        };
        Ok((trial, qs))
    }
}

/// A trial that runs away (points out of the grid, a mesh too distorted) has failed too:
/// near collapse the motion is large.
fn runs_away(e: &StepError) -> bool {
    matches!(e, StepError::Connect(ConnectError::PointOutsideGrid { .. } | ConnectError::Element { .. }))
}

/// Trial `t`, saved as the `index`th of a search, if it is at the factor this search
/// tries there.
fn saved_trial(t: &StrengthTrial, index: usize, factor: f64) -> Result<StrengthTrial, StrengthReductionError> {
    if t.factor.to_bits() == factor.to_bits() {
        return Ok(t.clone());
    }
    Err(StrengthReductionError::Reduction(format!(
        "saved trial {} is at F = {}, where this search tries F = {factor}: it is another search's",
        index + 1,
        t.factor
    )))
}

/// Lower the strength of the state `held` holds to `factor` (of `model`'s): connect, the
/// reduced laws, then Newton at the held load. Converged: the state is committed at
/// `factor`. Not converged (or the body ran away): why, and nothing changed, the laws
/// included. Other errors end the search.
fn lower_strength<const D: usize>(
    held: &mut QuasiStatic<D>,
    model: &Model<D>,
    factor: f64,
) -> Result<Result<NewtonReport, String>, StrengthReductionError> {
    match held.connect_committed() {
        Err(e) if runs_away(&e) => return Ok(Err(e.to_string())),
        Err(source) => return Err(StrengthReductionError::Trial { factor, source }),
        Ok(()) => {}
    }
    let attempt = held.attempt_with_materials(reduced_materials(model, factor)?)?;
    Ok(attempt.map_err(|e| e.to_string()))
}

/// The strength steps of a search from the last state that held: `steps` equal steps from
/// the lower factor to the upper, each an attempt cut back as a load step is, down to half
/// the tolerance.
struct StrengthSteps {
    /// The bracket and the number of equal steps across it.
    bracket: (f64, f64),
    steps: usize,
    /// The smallest increment an attempt takes: half the tolerance.
    floor: f64,
    /// The step being taken (1-based) and its control.
    step: usize,
    control: CutBack,
    /// The factor of the state that holds.
    position: f64,
    /// Attempts cut back since the last that held.
    cutbacks: usize,
}

impl StrengthSteps {
    /// At the lower factor, the first step begun.
    fn new(search: &StrengthReduction) -> Self {
        let (bracket, steps, floor) = (search.bracket, search.trial.load_steps.max(1), 0.5 * search.tolerance);
        let control = Self::control(bracket, steps, floor, 1, bracket.0);
        Self { bracket, steps, floor, step: 1, control, position: bracket.0, cutbacks: 0 }
    }

    /// The control of step `step` from `position` to the step's factor, halved down to
    /// `floor` (no limit on the number of halvings: the floor is the resolution).
    fn control(bracket: (f64, f64), steps: usize, floor: f64, step: usize, position: f64) -> CutBack {
        let (lo, hi) = bracket;
        let target = lo + (hi - lo) * step as f64 / steps as f64;
        CutBack::new(position, target, StepScale::LoadFactor, usize::MAX).with_floor(floor)
    }

    /// The factor of the next attempt, or `None` once the upper factor has held.
    fn next_attempt(&mut self) -> Option<f64> {
        loop {
            if let Some(end) = self.control.next_end(self.position) {
                return Some(end);
            }
            if self.step >= self.steps {
                return None;
            }
            self.step += 1;
            self.control = Self::control(self.bracket, self.steps, self.floor, self.step, self.position);
        }
    }

    /// The attempt at `factor` converged with `report`: the trial that held there.
    fn held<const D: usize>(
        &mut self,
        factor: f64,
        report: NewtonReport,
        qs: &QuasiStatic<D>,
        wall_time: Duration,
    ) -> StrengthTrial {
        let iterations = report.iterations();
        self.control.converged(report, 0);
        self.position = factor;
        let cutbacks = std::mem::take(&mut self.cutbacks);
        trial_at_held_load(factor, true, iterations, cutbacks, qs, wall_time)
    }

    /// The attempt at `factor` failed for `reason`: cut back (`None`), or, at the smallest
    /// increment, the trial that failed.
    fn failed<const D: usize>(
        &mut self,
        factor: f64,
        reason: String,
        qs: &QuasiStatic<D>,
        wall_time: Duration,
    ) -> Option<StrengthTrial> {
        match self.control.failed(self.step, self.position, factor, reason, &NewtonReport::default()) {
            Ok(()) => {
                self.cutbacks += 1;
                None
            }
            Err(_) => Some(trial_at_held_load(factor, false, 0, self.cutbacks, qs, wall_time)),
        }
    }

    /// Walk the saved trials after the first (each reached after the cut-backs it counts)
    /// to where the search stopped; the bracket if it had ended. A trial at another factor
    /// than this search reaches there is another search's.
    fn replay(&mut self, trials: &[StrengthTrial]) -> Result<Option<(f64, f64)>, StrengthReductionError> {
        for (k, t) in trials.iter().enumerate().skip(1) {
            let mut factor = self.next_attempt();
            for _ in 0..t.cutbacks {
                self.control.cut();
                factor = self.next_attempt();
            }
            let Some(factor) = factor else {
                return Err(StrengthReductionError::Reduction(format!(
                    "saved trial {} follows the upper factor",
                    k + 1
                )));
            };
            saved_trial(t, k, factor)?;
            if !t.stable {
                return Ok(Some((self.position, t.factor)));
            }
            self.control.advance();
            self.position = factor;
        }
        Ok(None)
    }
}

/// A trial at the held load, `stable` or not, at `factor` after `cutbacks`, on the state of
/// `qs`.
fn trial_at_held_load<const D: usize>(
    factor: f64,
    stable: bool,
    iterations: usize,
    cutbacks: usize,
    qs: &QuasiStatic<D>,
    wall_time: Duration,
) -> StrengthTrial {
    let max_displacement = qs.model().points().max_displacement();
    StrengthTrial { factor, stable, load_factor: qs.load_factor(), iterations, cutbacks, max_displacement, wall_time }
}

/// The model with every material's strength divided by `factor` (c/F, tan φ/F, σ_y/F:
/// [`loam_constitutive::StrengthReducible`]); materials without a strength (elastic) are
/// kept. A model without any material that has a strength is refused.
pub fn reduced_strength<const D: usize>(model: &Model<D>, factor: f64) -> Result<Model<D>, StrengthReductionError> {
    Ok(model.with_materials(reduced_materials(model, factor)?)?)
}

/// The laws of [`reduced_strength`].
fn reduced_materials<const D: usize>(
    model: &Model<D>,
    factor: f64,
) -> Result<Vec<Arc<dyn ConstitutiveLaw>>, StrengthReductionError> {
    if !(factor.is_finite() && factor > 0.0) {
        return Err(StrengthReductionError::Reduction(format!("the factor is {factor}; it must be a positive number")));
    }
    if !has_strength(model) {
        return Err(StrengthReductionError::Reduction("no material has a strength to reduce (all are elastic)".into()));
    }
    if !model.frictional_planes().is_empty() {
        // A mechanism along the plane would be found at the soil's factor with the
        // interface at full strength: a factor of safety that is not one.
        return Err(StrengthReductionError::Reduction(
            "a frictional plane's μ is not reduced with the materials' strength yet; remove the strength reduction or the plane".into(),
        ));
    }
    model
        .materials()
        .iter()
        .enumerate()
        .map(|(m, law)| match law.as_strength_reducible() {
            None => Ok(law.clone()),
            Some(strength) => strength
                .with_strength_reduced(factor)
                .map_err(|e| StrengthReductionError::Reduction(format!("material {m} at F = {factor}: {e}"))),
        })
        .collect()
}

/// Whether some material of `model` has a strength that strength reduction can divide.
pub fn has_strength<const D: usize>(model: &Model<D>) -> bool {
    model.materials().iter().any(|law| law.as_strength_reducible().is_some())
}
