//! The strength of a frictional law — peak cohesion c, friction φ and dilation ψ with an
//! optional linear softening to residual values — shared by [`MohrCoulomb`](crate::MohrCoulomb)
//! and [`DruckerPrager`](crate::DruckerPrager): its checks, its value and κ-derivative on
//! each branch of the softening law, the branch a return ends on, and its reduction by a
//! strength-reduction factor (docs/theory.md §16).
//!
//! X(κ) = X_res + (X₀ − X_res) max(0, 1 − κ/κ_res) for X ∈ {c, φ, ψ}, κ the accumulated
//! equivalent deviatoric plastic strain.

use nalgebra::Matrix3;

use crate::{check_update_inputs, ConstitutiveError};

/// Linear softening of c, φ, ψ to residual values at κ = κ_res (angles in radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Softening {
    /// Residual cohesion c_res.
    pub cohesion: f64,
    /// Residual friction angle φ_res (radians).
    pub friction: f64,
    /// Residual dilation angle ψ_res (radians).
    pub dilation: f64,
    /// κ_res: the accumulated equivalent deviatoric plastic strain at which the residual
    /// values are reached.
    pub kappa: f64,
}

/// The branch of the softening law a return is solved on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Branch {
    /// No softening: peak values.
    Peak,
    /// X(κ) = X₀ + (X_res − X₀) κ/κ_res, not clamped (the clamp is the Residual branch).
    Softening,
    /// X = X_res.
    Residual,
}

/// c, φ, ψ at some κ on a branch, with their κ-derivatives (angles in radians).
#[derive(Debug, Clone, Copy)]
pub(crate) struct OnBranch {
    pub c: f64,
    pub phi: f64,
    pub psi: f64,
    pub dc: f64,
    pub dphi: f64,
    pub dpsi: f64,
}

/// Peak c, φ, ψ (radians) and the optional softening of a frictional law.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct FrictionalStrength {
    pub cohesion: f64,
    pub friction: f64,
    pub dilation: f64,
    pub softening: Option<Softening>,
}

impl FrictionalStrength {
    /// c ≥ 0, 0 ≤ φ < π/2, 0 ≤ ψ ≤ φ (all finite); an error naming the first that is not.
    pub fn validate_peak(&self) -> Result<(), ConstitutiveError> {
        let bad = |name: &'static str, value: f64| Err(ConstitutiveError::InvalidParameter { name, value });
        if !(self.cohesion.is_finite() && self.cohesion >= 0.0) {
            return bad("cohesion", self.cohesion);
        }
        if !(self.friction.is_finite() && self.friction >= 0.0 && self.friction < std::f64::consts::FRAC_PI_2) {
            return bad("friction", self.friction);
        }
        if !(self.dilation.is_finite() && self.dilation >= 0.0 && self.dilation <= self.friction) {
            return bad("dilation", self.dilation);
        }
        Ok(())
    }

    /// 0 ≤ c_res ≤ c, 0 ≤ φ_res ≤ φ, 0 ≤ ψ_res ≤ min(ψ, φ_res), κ_res > 0.
    pub fn validate_softening(&self) -> Result<(), ConstitutiveError> {
        let bad = |name: &'static str, value: f64| Err(ConstitutiveError::InvalidParameter { name, value });
        let Some(s) = self.softening else { return Ok(()) };
        if !(s.cohesion.is_finite() && s.cohesion >= 0.0 && s.cohesion <= self.cohesion) {
            return bad("residual cohesion", s.cohesion);
        }
        if !(s.friction.is_finite() && s.friction >= 0.0 && s.friction <= self.friction) {
            return bad("residual friction", s.friction);
        }
        if !(s.dilation.is_finite() && s.dilation >= 0.0 && s.dilation <= self.dilation && s.dilation <= s.friction) {
            return bad("residual dilation", s.dilation);
        }
        if !(s.kappa.is_finite() && s.kappa > 0.0) {
            return bad("kappa_res", s.kappa);
        }
        Ok(())
    }

    /// True when the softening law makes c, φ or ψ vary.
    pub fn softens(&self) -> bool {
        self.softening
            .is_some_and(|s| s.cohesion != self.cohesion || s.friction != self.friction || s.dilation != self.dilation)
    }

    /// (c, φ, ψ) at accumulated plastic strain κ (angles in radians).
    pub fn at(&self, kappa: f64) -> (f64, f64, f64) {
        match self.softening {
            None => (self.cohesion, self.friction, self.dilation),
            Some(s) => {
                let w = (1.0 - kappa / s.kappa).max(0.0);
                (
                    s.cohesion + (self.cohesion - s.cohesion) * w,
                    s.friction + (self.friction - s.friction) * w,
                    s.dilation + (self.dilation - s.dilation) * w,
                )
            }
        }
    }

    /// The branch of the softening law that κ lies on.
    pub fn branch_at(&self, kappa: f64) -> Branch {
        match self.softening {
            None => Branch::Peak,
            Some(s) if kappa >= s.kappa => Branch::Residual,
            Some(_) => Branch::Softening,
        }
    }

    /// c, φ, ψ and their κ-derivatives at κ on `branch` (the softening branch is not
    /// clamped: a return solves on it and checks where κ ended).
    pub fn on_branch(&self, kappa: f64, branch: Branch) -> OnBranch {
        let (c, phi, psi, dc, dphi, dpsi) = match (branch, self.softening) {
            (Branch::Softening, Some(s)) => {
                let r = kappa / s.kappa;
                (
                    self.cohesion + (s.cohesion - self.cohesion) * r,
                    self.friction + (s.friction - self.friction) * r,
                    self.dilation + (s.dilation - self.dilation) * r,
                    (s.cohesion - self.cohesion) / s.kappa,
                    (s.friction - self.friction) / s.kappa,
                    (s.dilation - self.dilation) / s.kappa,
                )
            }
            (Branch::Residual, Some(s)) => (s.cohesion, s.friction, s.dilation, 0.0, 0.0, 0.0),
            _ => (self.cohesion, self.friction, self.dilation, 0.0, 0.0, 0.0),
        };
        OnBranch { c, phi, psi, dc, dphi, dpsi }
    }

    /// Runs `solve` on the branch(es) the softening law needs: without softening on the
    /// peak values; from κ_n ≥ κ_res on the residual ones; otherwise on the softening
    /// branch, and again on the residual one when κ (read by `kappa_of`) ended beyond κ_res.
    pub fn on_branches<C, E>(
        &self,
        kappa_n: f64,
        kappa_of: impl Fn(&C) -> f64,
        solve: impl Fn(Branch) -> Result<Option<C>, E>,
    ) -> Result<Option<C>, E> {
        let Some(s) = self.softening else {
            return solve(Branch::Peak);
        };
        if kappa_n >= s.kappa {
            return solve(Branch::Residual);
        }
        let soft = solve(Branch::Softening);
        if let Ok(Some(c)) = &soft {
            if kappa_of(c) <= s.kappa {
                return soft;
            }
        }
        let res = solve(Branch::Residual);
        if let Ok(Some(c)) = &res {
            if kappa_of(c) >= s.kappa {
                return res;
            }
        }
        // Neither branch is self-consistent (not expected for a monotone softening law):
        // prefer a converged answer over an error.
        match (soft, res) {
            (Ok(Some(c)), _) | (_, Ok(Some(c))) => Ok(Some(c)),
            (soft, _) => soft,
        }
    }

    /// The strength divided by `factor` > 0 (Griffiths & Lane 1999): c/F,
    /// φ_F = atan(tan φ / F), ψ_F = min(ψ, φ_F) (a dilation above the reduced friction
    /// would break ψ ≤ φ), and the residual values of softening alike.
    pub fn reduced(&self, factor: f64) -> Result<Self, ConstitutiveError> {
        if !(factor.is_finite() && factor > 0.0) {
            return Err(ConstitutiveError::InvalidParameter { name: "strength reduction factor", value: factor });
        }
        let reduce = |phi: f64| (phi.tan() / factor).atan();
        let friction = reduce(self.friction);
        Ok(Self {
            cohesion: self.cohesion / factor,
            friction,
            dilation: self.dilation.min(friction),
            softening: self.softening.map(|s| {
                let friction_res = reduce(s.friction);
                Softening {
                    cohesion: s.cohesion / factor,
                    friction: friction_res,
                    dilation: s.dilation.min(friction_res).min(self.dilation.min(friction)),
                    kappa: s.kappa,
                }
            }),
        })
    }
}

/// The inputs of a frictional law's update: a finite trial strain and the law's two history
/// values (κ ≥ 0, the accumulated plastic volumetric strain), returned; `what` names the
/// history in the error.
pub(crate) fn frictional_inputs(
    eps_trial: &Matrix3<f64>,
    h_n: &[f64],
    h_out: &[f64],
    what: &'static str,
) -> Result<(f64, f64), ConstitutiveError> {
    check_update_inputs(eps_trial, h_n, h_out, 2)?;
    let (kappa_n, evp_n) = (h_n[0], h_n[1]);
    if !(kappa_n.is_finite() && kappa_n >= 0.0 && evp_n.is_finite()) {
        return Err(ConstitutiveError::NonFinite { what });
    }
    Ok((kappa_n, evp_n))
}
