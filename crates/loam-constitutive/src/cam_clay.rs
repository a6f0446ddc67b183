//! Modified Cam clay (Roscoe & Burland 1968) with pressure-dependent elasticity and an
//! implicit return in the invariants, after Borja & Lee (1990), *Cam-clay plasticity,
//! part I*, CMAME 78, 49–72, with the consistent tangent (docs/theory.md §16).
//!
//! # The model
//! Pressures are compression-positive here (p = −tr σ/3, ε_v = −tr ε), stress tension-
//! positive as everywhere else. With q = √(3J₂), the critical-state slope M and the
//! preconsolidation pressure p_c:
//!
//! ```text
//! f = q²/M² + p (p − p_c)              (associated flow)
//! p = p_ref exp(ε^e_v / κ̂)            (elastic volume: the κ line, κ̂ = κ/(1 + e₀))
//! G = G₀ or 3 (1 − 2ν) K / (2 (1 + ν)) with K = p/κ̂
//! p_c = p_c,n exp(Δε^p_v / (λ̂ − κ̂))   (hardening: the λ line, λ̂ = λ/(1 + e₀))
//! ```
//!
//! Optionally M follows the Lode angle ([`ModifiedCamClay::with_lode_dependence`]): M in
//! triaxial compression, Mohr–Coulomb's ratio of it in extension, the Lode angle the
//! trial's, kept through the return.
//!
//! p_ref = 1 in the scene's stress unit: it fixes only where the elastic volumetric strain
//! is counted from (the stress depends on its changes). Isotropic compression follows
//! e = e₀ − (1 + e₀) ε_v, whose slopes against ln p are λ on the virgin line and κ in
//! unloading, exactly.
//!
//! # Return
//! With the trial ε^e_v,tr, ε^e_s,tr = √(2/3) ‖dev ε_tr‖ and n̂ = dev ε_tr/‖dev ε_tr‖, the
//! unknowns Δε^p_v and Δγ solve
//!
//! ```text
//! r₁ = Δε^p_v − Δγ (2p − p_c) = 0,    r₂ = f(p, q, p_c) = 0,
//! p = p(ε^e_v,tr − Δε^p_v),  q = 3G ε^e_s,tr / (1 + 6GΔγ/M²),  p_c = p_c(Δε^p_v)
//! ```
//!
//! (nested scalar solves, each by Newton's method kept in a bracket), and σ = −p I + √(2/3) q n̂.
//! The tangent differentiates the converged system with respect to (ε^e_v,tr, ε^e_s,tr):
//!
//! ```text
//! D = p_v I⊗I − √(2/3) p_s I⊗n̂ − √(2/3) q_v n̂⊗I + ⅔ q_s n̂⊗n̂ + 2G/(1 + 6GΔγ/M²) (I_d − n̂⊗n̂)
//! ```
//!
//! (p_v = dp/dε^e_v,tr and so on; in the elastic case Δγ = 0 and the same formula gives the
//! elastic tangent, not symmetric when G follows p).
//!
//! History slots: `[0]` the accumulated plastic shear strain Σ Δε^p_s (Δε^p_s = 2qΔγ/M²,
//! the measure Mohr–Coulomb softens with), `[1]` the accumulated volumetric plastic strain
//! (tension positive, as Mohr–Coulomb's), `[2]` p_c.

use nalgebra::{Matrix2, Matrix3, Vector2};

use crate::tensor::{flatten, identity_dyad, sym_identity, Tensor4};
use crate::{
    check_finite, check_update_inputs, ConstitutiveError, ConstitutiveLaw, Elastic, MaterialState, StressUpdate,
    SQRT_2_3,
};

/// How the shear modulus is given.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CamClayShear {
    /// A constant shear modulus G.
    Modulus(f64),
    /// A constant Poisson's ratio ν: G = 3 (1 − 2ν) K / (2 (1 + ν)) follows p.
    Poisson(f64),
}

/// How the preconsolidation pressure of a point follows from its initial stress.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CamClayInitial {
    /// p_c = OCR × the size of the yield surface through the initial stress
    /// (p + q²/(M² p)): OCR = 1 is normally consolidated.
    OverConsolidation(f64),
    /// The same p_c everywhere; the initial stress must lie inside its surface.
    Preconsolidation(f64),
}

/// Modified Cam clay (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModifiedCamClay {
    lambda: f64,
    kappa: f64,
    void_ratio: f64,
    m: f64,
    shear: CamClayShear,
    initial: CamClayInitial,
    /// M follows the Lode angle (Sheng, Sloan & Yu 2000), M in compression, Mohr–Coulomb's
    /// ratio in extension.
    lode: bool,
}

/// f ≤ ELASTIC_TOL p_c² is elastic.
const ELASTIC_TOL: f64 = 1e-12;
/// Newton's tolerance on the scaled residuals.
const NEWTON_TOL: f64 = 1e-13;
const MAX_ITERATIONS: usize = 60;
/// p_ref of the elastic volume law, in the scene's stress unit.
const P_REF: f64 = 1.0;

impl Local {
    /// ∂q/∂G and ∂q/∂Δγ of q = 3G ε^e_s,tr/(1 + 6GΔγ/M²) at this state (trial shear
    /// strain `eps_s`, slope `m`): the derivatives the Jacobian and the tangents share.
    fn q_derivatives(&self, eps_s: f64, m: f64) -> (f64, f64) {
        (3.0 * eps_s / (self.den * self.den), -self.q * 6.0 * self.g / (m * m * self.den))
    }
}

/// The trial state in invariants, with M at its Lode angle.
struct Trial {
    eps_v: f64,
    eps_s: f64,
    n_hat: Matrix3<f64>,
    pc_n: f64,
    m: f64,
}

/// A converged state: Δε^p_v, Δγ and what follows from them.
#[derive(Debug, Clone, Copy)]
struct Local {
    x: f64,
    dgamma: f64,
    p: f64,
    q: f64,
    pc: f64,
    g: f64,
    /// 1 + 6GΔγ/M².
    den: f64,
}

impl ModifiedCamClay {
    /// λ and κ the slopes of the virgin and unloading lines in e–ln p, e₀ the void ratio
    /// their modified forms use (λ̂ = λ/(1 + e₀)), M the critical-state slope. Validates
    /// λ > κ > 0, e₀ > 0, M > 0, a positive G or −1 < ν < 0.5, OCR ≥ 1 or p_c > 0.
    pub fn new(
        lambda: f64,
        kappa: f64,
        void_ratio: f64,
        m: f64,
        shear: CamClayShear,
        initial: CamClayInitial,
    ) -> Result<Self, ConstitutiveError> {
        let bad = |name: &'static str, value: f64| Err(ConstitutiveError::InvalidParameter { name, value });
        if !(kappa.is_finite() && kappa > 0.0) {
            return bad("kappa", kappa);
        }
        if !(lambda.is_finite() && lambda > kappa) {
            return bad("lambda", lambda);
        }
        if !(void_ratio.is_finite() && void_ratio > 0.0) {
            return bad("void_ratio", void_ratio);
        }
        if !(m.is_finite() && m > 0.0) {
            return bad("critical state slope M", m);
        }
        match shear {
            CamClayShear::Modulus(g) if !(g.is_finite() && g > 0.0) => return bad("shear_modulus", g),
            CamClayShear::Poisson(nu) if !(nu.is_finite() && nu > -1.0 && nu < 0.5) => return bad("poisson", nu),
            _ => {}
        }
        match initial {
            CamClayInitial::OverConsolidation(ocr) if !(ocr.is_finite() && ocr >= 1.0) => {
                return bad("over-consolidation ratio", ocr)
            }
            CamClayInitial::Preconsolidation(pc) if !(pc.is_finite() && pc > 0.0) => {
                return bad("preconsolidation pressure", pc)
            }
            _ => {}
        }
        Ok(Self { lambda, kappa, void_ratio, m, shear, initial, lode: false })
    }

    /// M follows the Lode angle θ (Sheng, Sloan & Yu 2000): M(θ) = M g(θ),
    /// g = (2α⁴/(1 + α⁴ + (1 − α⁴) sin 3θ))^¼ with α = (3 − sin φ)/(3 + sin φ), φ the
    /// critical-state friction angle of M: M in triaxial compression, α M in extension,
    /// Mohr–Coulomb's ratio. The flow stays radial in the deviatoric plane: θ is the
    /// trial's, kept through the return.
    /// Refused for M ≥ 3 (no friction angle has it: sin φ = 3M/(6 + M) ≥ 1).
    pub fn with_lode_dependence(mut self) -> Result<Self, ConstitutiveError> {
        if self.m >= 3.0 {
            return Err(ConstitutiveError::InvalidParameter {
                name: "critical state slope M (Lode-dependent)",
                value: self.m,
            });
        }
        self.lode = true;
        Ok(self)
    }

    /// M(θ) and dM/d(sin 3θ) for the deviatoric direction `n_hat` (unit, or zero), with
    /// sin 3θ = √6 tr(n̂³) (−1 in triaxial compression, 1 in extension, tension positive).
    fn slope_at(&self, n_hat: &Matrix3<f64>) -> (f64, f64) {
        if !self.lode || n_hat.norm_squared() == 0.0 {
            return (self.m, 0.0);
        }
        let s3 = (6f64.sqrt() * (n_hat * n_hat * n_hat).trace()).clamp(-1.0, 1.0);
        let sin_phi = 3.0 * self.m / (6.0 + self.m);
        let a4 = ((3.0 - sin_phi) / (3.0 + sin_phi)).powi(4);
        let den = 1.0 + a4 + (1.0 - a4) * s3;
        let g = (2.0 * a4 / den).powf(0.25);
        (self.m * g, -0.25 * self.m * g * (1.0 - a4) / den)
    }

    /// M = 6 sin φ/(3 − sin φ): the critical-state slope matched to Mohr–Coulomb in
    /// triaxial compression at the critical-state friction angle φ (degrees).
    pub fn slope_from_friction(friction_deg: f64) -> f64 {
        let s = friction_deg.to_radians().sin();
        6.0 * s / (3.0 - s)
    }

    /// κ̂ = κ/(1 + e₀) and λ̂ − κ̂.
    fn moduli(&self) -> (f64, f64) {
        let v = 1.0 + self.void_ratio;
        (self.kappa / v, (self.lambda - self.kappa) / v)
    }

    /// G(p) = g₀ + g₁ p: (g₀, g₁).
    fn shear_law(&self) -> (f64, f64) {
        match self.shear {
            CamClayShear::Modulus(g) => (g, 0.0),
            CamClayShear::Poisson(nu) => (0.0, 3.0 * (1.0 - 2.0 * nu) / (2.0 * (1.0 + nu) * self.moduli().0)),
        }
    }

    /// The critical-state slope M.
    pub fn critical_state_slope(&self) -> f64 {
        self.m
    }

    /// f = q²/M² + p (p − p_c) of `stress` with preconsolidation pressure p_c (M at the
    /// stress's Lode angle where it follows it).
    pub fn yield_function(&self, stress: &Matrix3<f64>, pc: f64) -> f64 {
        let (p, q) = invariants(stress);
        let m = self.slope_at(&unit_deviator(stress)).0;
        q * q / (m * m) + p * (p - pc)
    }

    /// The converged local state for the trial `tr` and its Jacobian's inverse, or the
    /// elastic one (Δγ = 0) when the trial is inside the surface. The two equations are
    /// solved nested, each by Newton's method kept inside a bracket (bisection where a
    /// step leaves it): for a given Δγ, r₁ is increasing in Δε^p_v with one root; f along
    /// those roots is positive at Δγ = 0 and negative for a Δγ large enough (the state then
    /// nears the critical state, q → 0 with p_c → 2p), so a bracket of Δγ holds a root.
    fn solve(&self, tr: &Trial) -> Result<(Local, Option<Matrix2<f64>>), ConstitutiveError> {
        let elastic = self.local(tr, 0.0, 0.0);
        let scale = tr.pc_n * tr.pc_n;
        if self.residual(tr, &elastic).1 <= ELASTIC_TOL * scale {
            return Ok((elastic, None));
        }
        let failed = |residual: f64| ConstitutiveError::ReturnMappingFailed {
            law: "modified-cam-clay",
            iterations: MAX_ITERATIONS,
            residual,
        };
        // f and df/dΔγ along r₁ = 0, scaled by p_c,n².
        let along = |dgamma: f64| -> Result<(Local, f64, f64), ConstitutiveError> {
            let l = self.local(tr, self.plastic_volume(tr, dgamma)?, dgamma);
            let jac = self.jacobian(tr, &l, scale);
            let dx = -jac[(0, 1)] / jac[(0, 0)];
            Ok((l, self.residual(tr, &l).1 / scale, jac[(1, 0)] * dx + jac[(1, 1)]))
        };
        let m2 = tr.m * tr.m;
        // Δγ = M²/(6G) halves q: the first guess of the upper end.
        let mut hi = m2 / (6.0 * elastic.g.max(f64::MIN_POSITIVE));
        let mut lo = 0.0;
        loop {
            // f is positive at Δγ = 0 and negative for Δγ large enough: a bracket not found
            // by 4⁶⁰ times the first guess, or a NaN f, is a failure, not a result.
            let f = along(hi)?.1;
            if f < 0.0 {
                break;
            }
            if f.is_nan() || hi > 1e36 * m2 / elastic.g.max(f64::MIN_POSITIVE) {
                return Err(failed(f));
            }
            (lo, hi) = (hi, hi * 4.0);
        }
        let mut dgamma = 0.5 * (lo + hi);
        for _ in 0..MAX_ITERATIONS {
            let (l, f, df) = along(dgamma)?;
            if f.is_nan() {
                return Err(failed(f));
            }
            // Round-off in f is relative to its largest term, not to p_c,n².
            let terms = (l.q * l.q / m2).max(l.p * l.p).max(l.p * l.pc) / scale;
            if f.abs() <= NEWTON_TOL * terms || hi - lo <= 4.0 * f64::EPSILON * hi {
                let inv = self.jacobian(tr, &l, scale).try_inverse().ok_or_else(|| failed(f))?;
                return Ok((l, Some(inv)));
            }
            if f > 0.0 {
                lo = dgamma;
            } else {
                hi = dgamma;
            }
            let newton = dgamma - f / df;
            dgamma = if newton > lo && newton < hi { newton } else { 0.5 * (lo + hi) };
        }
        Err(failed(f64::NAN))
    }

    /// Δε^p_v solving r₁ = Δε^p_v − Δγ (2p − p_c) = 0 for `dgamma` (r₁ increases with it).
    fn plastic_volume(&self, tr: &Trial, dgamma: f64) -> Result<f64, ConstitutiveError> {
        let (kh, hard) = self.moduli();
        // r₁, its derivative and the size of its terms (round-off is relative to them).
        let r1 = |x: f64| {
            let l = self.local(tr, x, dgamma);
            let terms = x.abs().max(dgamma * (2.0 * l.p + l.pc));
            (l.x - dgamma * (2.0 * l.p - l.pc), 1.0 + dgamma * (2.0 * l.p / kh + l.pc / hard), terms)
        };
        // A bracket: widen from ±(κ̂ + λ̂ − κ̂) until r₁ changes sign.
        let (mut lo, mut hi) = (-(kh + hard), kh + hard);
        let mut widened = 0;
        while !(r1(lo).0 <= 0.0 && r1(hi).0 >= 0.0) {
            // r₁ runs from −∞ to ∞ (NaN where the exponentials overflow): no bracket within
            // 2⁶⁰ times the first is a failure.
            widened += 1;
            if widened > MAX_ITERATIONS {
                return Err(ConstitutiveError::ReturnMappingFailed {
                    law: "modified-cam-clay",
                    iterations: widened,
                    residual: f64::NAN,
                });
            }
            (lo, hi) = (lo * 2.0, hi * 2.0);
        }
        let mut x = 0.0f64.clamp(lo, hi);
        for _ in 0..MAX_ITERATIONS {
            let (r, dr, terms) = r1(x);
            if r.is_nan() {
                break;
            }
            if r.abs() <= NEWTON_TOL * terms || hi - lo <= 4.0 * f64::EPSILON * x.abs() {
                return Ok(x);
            }
            if r < 0.0 {
                lo = x;
            } else {
                hi = x;
            }
            let newton = x - r / dr;
            x = if newton > lo && newton < hi && newton.is_finite() { newton } else { 0.5 * (lo + hi) };
        }
        Err(ConstitutiveError::ReturnMappingFailed {
            law: "modified-cam-clay",
            iterations: MAX_ITERATIONS,
            residual: r1(x).0 / r1(x).2,
        })
    }

    /// p, q, p_c, G at Δε^p_v = x and Δγ.
    fn local(&self, tr: &Trial, x: f64, dgamma: f64) -> Local {
        let (kh, hard) = self.moduli();
        let (g0, g1) = self.shear_law();
        let p = P_REF * ((tr.eps_v - x) / kh).exp();
        let g = g0 + g1 * p;
        let den = 1.0 + 6.0 * g * dgamma / (tr.m * tr.m);
        let q = 3.0 * g * tr.eps_s / den;
        let pc = tr.pc_n * (x / hard).exp();
        Local { x, dgamma, p, q, pc, g, den }
    }

    /// (r₁, f) of a local state.
    fn residual(&self, tr: &Trial, l: &Local) -> (f64, f64) {
        (l.x - l.dgamma * (2.0 * l.p - l.pc), l.q * l.q / (tr.m * tr.m) + l.p * (l.p - l.pc))
    }

    /// ∂(r₁, f/scale)/∂(Δε^p_v, Δγ).
    fn jacobian(&self, tr: &Trial, l: &Local, scale: f64) -> Matrix2<f64> {
        let (kh, hard) = self.moduli();
        let (_, g1) = self.shear_law();
        let m2 = tr.m * tr.m;
        let dp_dx = -l.p / kh;
        let dpc_dx = l.pc / hard;
        let (dq_dg, dq_dgamma) = l.q_derivatives(tr.eps_s, tr.m);
        let dq_dx = dq_dg * g1 * dp_dx;
        Matrix2::new(
            1.0 - l.dgamma * (2.0 * dp_dx - dpc_dx),
            -(2.0 * l.p - l.pc),
            (2.0 * l.q * dq_dx / m2 + dp_dx * (2.0 * l.p - l.pc) - l.p * dpc_dx) / scale,
            2.0 * l.q * dq_dgamma / m2 / scale,
        )
    }

    /// The consistent tangent at a converged state (the module docs' D), `inv` the inverse
    /// of the local Jacobian (None: elastic).
    fn tangent(&self, tr: &Trial, l: &Local, inv: Option<Matrix2<f64>>) -> Tensor4 {
        let (kh, _) = self.moduli();
        let (_, g1) = self.shear_law();
        let m2 = tr.m * tr.m;
        let scale = tr.pc_n * tr.pc_n;
        // Explicit derivatives at fixed (Δε^p_v, Δγ) with respect to a = (ε_v,tr, ε_s,tr).
        let p_a = l.p / kh;
        let (dq_dg, dq_dgamma) = l.q_derivatives(tr.eps_s, tr.m);
        let q_a = Vector2::new(dq_dg * g1 * p_a, 3.0 * l.g / l.den);
        // dz/da = −J⁻¹ ∂R/∂a, z = (Δε^p_v, Δγ).
        let dz = match inv {
            None => Matrix2::zeros(),
            Some(inv) => {
                let dr = Matrix2::new(
                    -l.dgamma * 2.0 * p_a,
                    0.0,
                    (2.0 * l.q * q_a[0] / m2 + p_a * (2.0 * l.p - l.pc)) / scale,
                    2.0 * l.q * q_a[1] / m2 / scale,
                );
                -(inv * dr)
            }
        };
        let dp = Vector2::new(p_a * (1.0 - dz[(0, 0)]), -p_a * dz[(0, 1)]);
        let dq = Vector2::new(
            dq_dg * g1 * dp[0] + dq_dgamma * dz[(1, 0)],
            dq_dg * g1 * dp[1] + dq_dgamma * dz[(1, 1)] + 3.0 * l.g / l.den,
        );
        let (i, n) = (flatten(&Matrix3::identity()), flatten(&tr.n_hat));
        let i_dev = sym_identity() - identity_dyad() / 3.0;
        let d =
            identity_dyad() * dp[0] - i * n.transpose() * (SQRT_2_3 * dp[1]) - n * i.transpose() * (SQRT_2_3 * dq[0])
                + n * n.transpose() * (2.0 / 3.0 * dq[1])
                + (i_dev - n * n.transpose()) * (2.0 * l.g / l.den);
        match inv {
            Some(inv) if self.lode => d + self.lode_term(tr, l, &inv),
            _ => d,
        }
    }

    /// What the Lode dependence adds to a plastic tangent: ∂σ/∂M ⊗ dM/dε_tr, M being the
    /// trial's (dM/dε_tr = dM/d sin 3θ · 3√6 (dev n̂² − tr(n̂³) n̂)/‖dev ε_tr‖).
    fn lode_term(&self, tr: &Trial, l: &Local, inv: &Matrix2<f64>) -> Tensor4 {
        let e_norm = tr.eps_s / SQRT_2_3;
        if e_norm == 0.0 {
            return Tensor4::zeros();
        }
        let (kh, _) = self.moduli();
        let (_, g1) = self.shear_law();
        let (m, scale) = (tr.m, tr.pc_n * tr.pc_n);
        let m2 = m * m;
        // ∂q/∂M and ∂f/∂M at fixed (Δε^p_v, Δγ), then dz/dM = −J⁻¹ ∂R/∂M.
        let q_m = l.q * 12.0 * l.g * l.dgamma / (m2 * m * l.den);
        let r_m = (2.0 * l.q * q_m / m2 - 2.0 * l.q * l.q / (m2 * m)) / scale;
        let dz = -(inv * Vector2::new(0.0, r_m));
        let dp = -l.p / kh * dz[0];
        let (dq_dg, dq_dgamma) = l.q_derivatives(tr.eps_s, m);
        let dq = dq_dg * g1 * dp + dq_dgamma * dz[1] + q_m;
        let dsigma = Matrix3::identity() * -dp + tr.n_hat * (SQRT_2_3 * dq);
        let n2 = tr.n_hat * tr.n_hat;
        let ds3 = (n2 - Matrix3::identity() * (n2.trace() / 3.0) - tr.n_hat * (n2 * tr.n_hat).trace())
            * (3.0 * 6f64.sqrt() / e_norm);
        flatten(&dsigma) * flatten(&ds3).transpose() * self.slope_at(&tr.n_hat).1
    }

    /// The update with its tangent: the trial invariants, the return, the state.
    fn returned(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
        with_tangent: bool,
    ) -> Result<StressUpdate, ConstitutiveError> {
        let (es_n, evp_n, pc_n) = check_inputs(eps_trial, h_n, h_out)?;
        let eps = (eps_trial + eps_trial.transpose()) * 0.5;
        let dev = eps - Matrix3::identity() * (eps.trace() / 3.0);
        let nd = dev.norm();
        let n_hat = if nd > 0.0 { dev / nd } else { Matrix3::zeros() };
        let (m, _) = self.slope_at(&n_hat);
        let tr = Trial { eps_v: -eps.trace(), eps_s: SQRT_2_3 * nd, n_hat, pc_n, m };
        let (l, inv) = self.solve(&tr)?;
        let stress = Matrix3::identity() * -l.p + tr.n_hat * (SQRT_2_3 * l.q);
        check_finite(&stress, "Modified Cam clay stress")?;
        // ε^e = −ε^e_v/3 I + √(3/2) ε^e_s n̂ with ε^e_s = q/(3G).
        let eps_s_e = if l.g > 0.0 { l.q / (3.0 * l.g) } else { 0.0 };
        let elastic_strain = Matrix3::identity() * (-(tr.eps_v - l.x) / 3.0) + tr.n_hat * (eps_s_e / SQRT_2_3);
        h_out[0] = es_n + 2.0 * l.q * l.dgamma / (tr.m * tr.m);
        h_out[1] = evp_n - l.x;
        h_out[2] = l.pc;
        let tangent = if with_tangent { self.tangent(&tr, &l, inv) } else { Tensor4::zeros() };
        if !tangent.iter().all(|v| v.is_finite()) {
            return Err(ConstitutiveError::NonFinite { what: "Modified Cam clay tangent" });
        }
        Ok(StressUpdate { stress, elastic_strain, tangent })
    }

    /// K = p/κ̂ and G at pressure p (both zero for p ≤ 0).
    fn moduli_at(&self, p: f64) -> (f64, f64) {
        let p = p.max(0.0);
        let (g0, g1) = self.shear_law();
        (p / self.moduli().0, if p > 0.0 { g0 + g1 * p } else { 0.0 })
    }
}

/// The unit deviatoric direction of a stress (zero for an isotropic one).
fn unit_deviator(stress: &Matrix3<f64>) -> Matrix3<f64> {
    let s = stress - Matrix3::identity() * (stress.trace() / 3.0);
    let n = s.norm();
    if n > 0.0 {
        s / n
    } else {
        Matrix3::zeros()
    }
}

/// p = −tr σ/3 and q = √(3J₂) of a stress.
fn invariants(stress: &Matrix3<f64>) -> (f64, f64) {
    let p = -stress.trace() / 3.0;
    let s = stress + Matrix3::identity() * p;
    (p, (1.5 * s.norm_squared()).sqrt())
}

/// The input checks: a finite trial strain and the three history values, p_c > 0.
fn check_inputs(eps_trial: &Matrix3<f64>, h_n: &[f64], h_out: &[f64]) -> Result<(f64, f64, f64), ConstitutiveError> {
    check_update_inputs(eps_trial, h_n, h_out, 3)?;
    if !(h_n[0].is_finite() && h_n[1].is_finite()) {
        return Err(ConstitutiveError::NonFinite { what: "Modified Cam clay history" });
    }
    if !(h_n[2].is_finite() && h_n[2] > 0.0) {
        // A point whose initial stress had no pressure has no yield surface.
        return Err(ConstitutiveError::InvalidParameter { name: "preconsolidation pressure", value: h_n[2] });
    }
    Ok((h_n[0], h_n[1], h_n[2]))
}

impl ConstitutiveLaw for ModifiedCamClay {
    fn name(&self) -> &'static str {
        "modified-cam-clay"
    }

    fn history_len(&self) -> usize {
        3
    }

    fn history_names(&self) -> &'static [&'static str] {
        &["plastic_shear_strain", "plastic_volumetric_strain", "preconsolidation_pressure"]
    }

    /// p_c from the initial stress (OCR × the surface through it) or as given; zero where
    /// the initial stress has no pressure (the update then refuses the point).
    fn init_history(&self, h: &mut [f64], initial_stress: &Matrix3<f64>) {
        let (p, q) = invariants(initial_stress);
        h[0] = 0.0;
        h[1] = 0.0;
        h[2] = match self.initial {
            CamClayInitial::Preconsolidation(pc) => pc,
            CamClayInitial::OverConsolidation(_) if p <= 0.0 => 0.0,
            CamClayInitial::OverConsolidation(ocr) => {
                let m = self.slope_at(&unit_deviator(initial_stress)).0;
                ocr * (p + q * q / (m * m * p))
            }
        };
    }

    fn plastic_strain(&self, h: &[f64]) -> f64 {
        h[0]
    }

    fn is_yielding(&self, stress: &Matrix3<f64>, h: &[f64]) -> bool {
        self.yield_function(stress, h[2]) >= -1e-6 * h[2] * h[2]
    }

    /// Not symmetric in general (G following p, the hardening's coupling).
    fn symmetric_tangent(&self) -> bool {
        false
    }

    /// On the dry side of critical (p < p_c/2) the surface shrinks as the clay dilates.
    fn can_soften(&self) -> bool {
        true
    }

    fn update(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<StressUpdate, ConstitutiveError> {
        self.returned(eps_trial, h_n, h_out, true)
    }

    fn update_stress(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<(Matrix3<f64>, Matrix3<f64>), ConstitutiveError> {
        self.returned(eps_trial, h_n, h_out, false).map(|u| (u.stress, u.elastic_strain))
    }

    /// The tangent elasticity K = p/κ̂, G at the state's pressure (None at p ≤ 0).
    fn elasticity(&self, state: &MaterialState) -> Option<Elastic> {
        let (k, g) = self.moduli_at(invariants(&state.stress).0);
        let young = 9.0 * k * g / (3.0 * k + g);
        let poisson = (3.0 * k - 2.0 * g) / (2.0 * (3.0 * k + g));
        Elastic::new(young, poisson).ok()
    }

    /// ε^e_v = κ̂ ln(p/p_ref), dev ε^e = s/(2G): the exact inverse of the elastic law.
    fn elastic_strain_of(&self, stress: &Matrix3<f64>, _history: &[f64]) -> Option<Matrix3<f64>> {
        let (p, _) = invariants(stress);
        let (_, g) = self.moduli_at(p);
        if !(p > 0.0 && g > 0.0) {
            return None;
        }
        let s = stress + Matrix3::identity() * p;
        Some(Matrix3::identity() * (-self.moduli().0 * (p / P_REF).ln() / 3.0) + s / (2.0 * g))
    }

    fn constant_stiffness(&self) -> bool {
        false
    }

    /// K + 4G/3 at the state's pressure.
    fn p_wave_modulus(&self, state: &MaterialState) -> f64 {
        let (k, g) = self.moduli_at(invariants(&state.stress).0);
        k + 4.0 * g / 3.0
    }

    /// κ̂ p_ref (exp(ε^e_v/κ̂) − 1) + G dev ε^e : dev ε^e, G at the elastic strain's
    /// pressure (exact for a constant G; with G following p the law is not hyperelastic and
    /// this is the energy of the current shear modulus).
    fn stored_energy(&self, elastic_strain: &Matrix3<f64>) -> f64 {
        let kh = self.moduli().0;
        let ev = -elastic_strain.trace();
        let p = P_REF * (ev / kh).exp();
        let dev = elastic_strain + Matrix3::identity() * (ev / 3.0);
        kh * P_REF * ((ev / kh).exp() - 1.0) + self.moduli_at(p).1 * dev.norm_squared()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ElementPath, ElementTest, Held};

    /// λ = 0.2, κ = 0.04, e₀ = 1.5, M = 1.0 (a soft clay), G from ν = 0.25.
    fn clay(initial: CamClayInitial) -> ModifiedCamClay {
        ModifiedCamClay::new(0.2, 0.04, 1.5, 1.0, CamClayShear::Poisson(0.25), initial).unwrap()
    }

    /// Undrained triaxial compression from p₀ = 100 at OCR 1 and 1.5. Constant volume
    /// fixes the path in closed form: ε^e_v = −ε^p_v, so p_c = p_c0 (p₀/p)^(κ̂/(λ̂ − κ̂))
    /// and q = M √(p (p_c − p)) once yielding (vertical in p before); it ends at the
    /// critical state p_f = (p_c0/2)^Λ p₀^(1−Λ), q_f = M p_f, Λ = (λ − κ)/λ. Every step's
    /// (p, q) is on the closed form to 1e-9 (each step ends on the surface with the exact
    /// exponentials); at 30 % axial strain (p, q) is within 0.1 % of the critical state.
    #[test]
    fn undrained_triaxial_follows_the_closed_form_path() {
        for ocr in [1.0, 1.5] {
            let law = clay(CamClayInitial::OverConsolidation(ocr));
            let p0 = 100.0;
            let start = Matrix3::identity() * -p0;
            let mut t = ElementTest::new(&law, start).unwrap();
            let (kh, hard) = law.moduli();
            let pc0 = ocr * p0;
            let big_lambda = (0.2 - 0.04) / 0.2;
            for _ in 0..600 {
                t.step(ElementPath::TriaxialUndrained.held(5e-4, &start)).unwrap();
                let (p, q) = t.p_q();
                let pc = pc0 * (p0 / p).powf(kh / hard);
                let expected = if t.history()[0] == 0.0 { q } else { (p * (pc - p)).sqrt() };
                assert!((q - expected).abs() <= 1e-9 * p0, "OCR {ocr}: q {q} vs {expected}");
                assert!(t.strain().trace().abs() < 1e-15);
            }
            let pf = (pc0 / 2.0).powf(big_lambda) * p0.powf(1.0 - big_lambda);
            let (p, q) = t.p_q();
            assert!((p / pf - 1.0).abs() < 1e-3 && (q / pf - 1.0).abs() < 1e-3, "OCR {ocr}: ({p}, {q}) vs {pf}");
        }
    }

    /// Isotropic compression on the virgin line and unloading: Δe/Δ ln p = −λ and −κ to
    /// round-off (e = e₀ − (1 + e₀) ε_v).
    #[test]
    fn isotropic_lines_have_slopes_lambda_and_kappa() {
        let law = clay(CamClayInitial::OverConsolidation(1.0));
        let p0 = 50.0;
        let mut t = ElementTest::new(&law, Matrix3::identity() * -p0).unwrap();
        let e = |t: &ElementTest| 1.5 - 2.5 * -t.strain().trace();
        let iso = |de: f64| {
            [
                Held::Strain(de),
                Held::Strain(de),
                Held::Strain(de),
                Held::Strain(0.0),
                Held::Strain(0.0),
                Held::Strain(0.0),
            ]
        };
        let (e_a, p_a) = (e(&t), t.p_q().0);
        for _ in 0..50 {
            t.step(iso(-1e-3)).unwrap();
        }
        let (e_b, p_b) = (e(&t), t.p_q().0);
        let slope = (e_b - e_a) / (p_b / p_a).ln();
        assert!((slope + 0.2).abs() < 1e-12, "virgin slope {slope}");
        for _ in 0..20 {
            t.step(iso(5e-4)).unwrap();
        }
        let (e_c, p_c) = (e(&t), t.p_q().0);
        let slope = (e_c - e_b) / (p_c / p_b).ln();
        assert!((slope + 0.04).abs() < 1e-12, "unloading slope {slope}");
        assert!(t.history()[2] > p_b * (1.0 - 1e-12) && t.history()[2] < p_b * (1.0 + 1e-12));
    }

    /// With M following the Lode angle, drained triaxial compression ends at q = M p′ and
    /// drained extension (the axial stress unloaded, the lateral held) at q = α M p′,
    /// α = (3 − sin φ)/(3 + sin φ) = 0.75 for M = 1 (sin φ = 3/7): Mohr–Coulomb's ratio,
    /// to 1e-3 of the critical state after 100 % (compression) and 60 % (extension) axial
    /// strain (small strain: the path only has to reach its asymptote).
    #[test]
    fn lode_dependent_slope_is_mohr_coulomb_in_extension() {
        let law = clay(CamClayInitial::OverConsolidation(1.0)).with_lode_dependence().unwrap();
        let start = Matrix3::identity() * -100.0;
        for (increment, ratio) in [(2.5e-3, 1.0), (-1.5e-3, 0.75)] {
            let mut t = ElementTest::new(&law, start).unwrap();
            for _ in 0..400 {
                t.step(ElementPath::TriaxialDrained.held(increment, &start)).unwrap();
            }
            let (p, q) = t.p_q();
            assert!((q / p / ratio - 1.0).abs() < 1e-3, "increment {increment}: q/p = {}", q / p);
        }
        // Without the option extension ends at M.
        let plain = clay(CamClayInitial::OverConsolidation(1.0));
        let mut t = ElementTest::new(&plain, start).unwrap();
        for _ in 0..400 {
            t.step(ElementPath::TriaxialDrained.held(-1.5e-3, &start)).unwrap();
        }
        assert!((t.p_q().1 / t.p_q().0 - 1.0).abs() < 1e-3);
    }

    #[test]
    fn refuses_bad_parameters_and_a_point_without_pressure() {
        let (s, i) = (CamClayShear::Modulus(1e3), CamClayInitial::OverConsolidation(1.0));
        let name = |r: Result<ModifiedCamClay, ConstitutiveError>| match r {
            Err(ConstitutiveError::InvalidParameter { name, .. }) => name,
            other => panic!("{other:?}"),
        };
        assert_eq!(name(ModifiedCamClay::new(0.04, 0.04, 1.0, 1.0, s, i)), "lambda");
        assert_eq!(name(ModifiedCamClay::new(0.2, 0.0, 1.0, 1.0, s, i)), "kappa");
        assert_eq!(name(ModifiedCamClay::new(0.2, 0.04, 1.0, 0.0, s, i)), "critical state slope M");
        assert_eq!(
            name(ModifiedCamClay::new(0.2, 0.04, 1.0, 1.0, s, CamClayInitial::OverConsolidation(0.9))),
            "over-consolidation ratio"
        );
        let law = clay(i);
        let mut h = [0.0; 3];
        law.init_history(&mut h, &Matrix3::zeros());
        assert!(law.update(&Matrix3::zeros(), &h, &mut [0.0; 3]).is_err());
        assert!((ModifiedCamClay::slope_from_friction(30.0) - 1.2).abs() < 1e-15);
    }
}
