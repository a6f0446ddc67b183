//! Strength-reduction analysis (Griffiths & Lane 1999, Géotechnique 49(3)): the factor of
//! safety F of a slope is the factor by which c and tan φ (σ_y for von Mises) must be
//! divided for the slope to fail under its own weight. Each trial rebuilds the model with
//! the reduced strength ([`reduced_strength`]) and applies gravity in
//! quasi-static load steps from zero; a trial whose load cannot be carried — a step that
//! does not converge after all its cut-backs, or that runs away (points leaving the grid,
//! an FEM mesh too distorted) — has failed. Bisection between a stable and a
//! failed factor brackets F to the asked tolerance. The failure criterion is Griffiths &
//! Lane's (non-convergence of the equilibrium iterations), with Newton and cut-back in
//! place of their viscoplastic iterations.

use crate::{LoadControl, QuasiStatic, QuasiStaticSettings, StepError};
use loam_constitutive::ConstitutiveLaw;
use loam_kernels::{ConnectError, InvalidSetting};
use loam_model::{Model, ModelError};
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
    /// Bisection stops when the bracket is narrower than this.
    pub tolerance: f64,
}

/// One trial factor and what it did.
#[derive(Debug, Clone, PartialEq)]
pub struct StrengthTrial {
    pub factor: f64,
    /// The full load was carried.
    pub stable: bool,
    /// Load factor reached (1 when stable).
    pub load_factor: f64,
    /// Newton corrections over the trial, cut-back attempts included only where converged.
    pub iterations: usize,
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
    /// `on_trial` after each trial.
    pub fn factor_of_safety<const D: usize>(
        &self,
        model: &Model<D>,
        on_trial: impl FnMut(&StrengthTrial),
    ) -> Result<FactorOfSafety, StrengthReductionError> {
        self.factor_of_safety_after(model, &[], on_trial)
    }

    /// [`StrengthReduction::factor_of_safety`] resumed after the trials `done` (a
    /// checkpoint's): the bisection takes their outcomes instead of running them again, so
    /// it goes on with the factors the interrupted search would have tried. `on_trial` is
    /// called for the new trials only; trials that are not this search's are refused.
    pub fn factor_of_safety_after<const D: usize>(
        &self,
        model: &Model<D>,
        done: &[StrengthTrial],
        mut on_trial: impl FnMut(&StrengthTrial),
    ) -> Result<FactorOfSafety, StrengthReductionError> {
        self.validate()?;
        let (lo, hi) = self.bracket;
        let mut trials: Vec<StrengthTrial> = Vec::new();
        let mut run = |factor: f64| -> Result<bool, StrengthReductionError> {
            let t = match done.get(trials.len()) {
                Some(t) if t.factor.to_bits() == factor.to_bits() => t.clone(),
                Some(t) => {
                    return Err(StrengthReductionError::Reduction(format!(
                        "saved trial {} is at F = {}, where this search tries F = {factor}: it is another search's",
                        trials.len() + 1,
                        t.factor
                    )))
                }
                None => {
                    let t = self.trial(model, factor)?;
                    on_trial(&t);
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

    /// Apply the full load to the model reduced by `factor`.
    pub fn trial<const D: usize>(
        &self,
        model: &Model<D>,
        factor: f64,
    ) -> Result<StrengthTrial, StrengthReductionError> {
        let start = Instant::now();
        let settings = QuasiStaticSettings { control: LoadControl::LoadFactor, ..self.trial.clone() };
        let mut qs = QuasiStatic::new(reduced_strength(model, factor)?, settings);
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
                // A trial that runs away (points out of the grid, a mesh too distorted)
                // has failed too: near collapse the motion is large.
                Err(StepError::Connect(ConnectError::PointOutsideGrid { .. } | ConnectError::Element { .. })) => {
                    stable = false;
                    break;
                }
                Err(source) => return Err(StrengthReductionError::Trial { factor, source }),
            }
        }
        let max_displacement = qs.model().points().max_displacement();
        Ok(StrengthTrial {
            factor,
            stable,
            load_factor: qs.load_factor(),
            iterations,
            cutbacks,
            max_displacement,
            wall_time: start.elapsed(),
        })
    }
}

/// The model with every material's strength divided by `factor` (c/F, tan φ/F, σ_y/F:
/// [`loam_constitutive::StrengthReducible`]); materials without a strength (elastic) are
/// kept. A model without any material that has a strength is refused.
pub fn reduced_strength<const D: usize>(model: &Model<D>, factor: f64) -> Result<Model<D>, StrengthReductionError> {
    if !(factor.is_finite() && factor > 0.0) {
        return Err(StrengthReductionError::Reduction(format!("the factor is {factor}; it must be a positive number")));
    }
    if !has_strength(model) {
        return Err(StrengthReductionError::Reduction("no material has a strength to reduce (all are elastic)".into()));
    }
    let materials = model
        .materials()
        .iter()
        .enumerate()
        .map(|(m, law)| match law.as_strength_reducible() {
            None => Ok(law.clone()),
            Some(strength) => strength
                .with_strength_reduced(factor)
                .map_err(|e| StrengthReductionError::Reduction(format!("material {m} at F = {factor}: {e}"))),
        })
        .collect::<Result<Vec<Arc<dyn ConstitutiveLaw>>, _>>()?;
    Ok(model.with_materials(materials)?)
}

/// Whether some material of `model` has a strength that strength reduction can divide.
pub fn has_strength<const D: usize>(model: &Model<D>) -> bool {
    model.materials().iter().any(|law| law.as_strength_reducible().is_some())
}
