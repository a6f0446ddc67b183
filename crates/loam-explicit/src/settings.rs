//! Settings of an explicit analysis and their validation.

use crate::ExplicitError;
use loam_kernels::InvalidSetting;

/// When the point stresses are updated relative to the grid momentum update
/// (Bardenhagen 2002; Nairn 2003; Buzzi et al. 2008 compare the three).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum UpdateScheme {
    /// Update Stress First: the strain increment comes from the nodal velocities of the
    /// start of the step, p_I / m_I, and the internal force from the updated stress.
    Usf,
    /// Update Stress Last: the strain increment comes from the updated nodal velocities
    /// v_I^{n+1}; the internal force uses the stress of the start of the step.
    ///
    /// Less stable than the CFL step suggests: with FLIP the point round trip softens the
    /// momentum update but not the strain update, and the mismatch is stable only for
    /// cΔt/h < 0.756 in 1D, less near nearly empty nodes (docs/theory.md §10, with the
    /// runs that show it). Use MUSL, or USL with GIMP and a safety of at most 0.5.
    Usl,
    /// Modified USL (Sulsky, Zhou & Schreyer 1995): as USL, but the nodal velocities for
    /// the strain increment are re-mapped from the updated point velocities. Robust near
    /// nearly empty nodes and the usual default. Like USF it is symplectic Euler on the
    /// softened modes, stable to about √3 h/c in 1D (linear basis, 2 points per cell), so
    /// the CFL estimate is conservative for it (docs/theory.md §10).
    #[default]
    Musl,
}

/// How the time step is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TimeStep {
    /// Δt = safety · Δt_crit, recomputed every step (docs/theory.md §10).
    Cfl { safety: f64 },
    /// A fixed Δt; refused with [`ExplicitError::AboveCritical`] at the first step where it
    /// exceeds Δt_crit unless `allow_above_critical`.
    Fixed { dt: f64, allow_above_critical: bool },
}

impl Default for TimeStep {
    fn default() -> Self {
        TimeStep::Cfl { safety: 0.5 }
    }
}

/// Settings of an [`Explicit`](crate::Explicit) analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct ExplicitSettings {
    pub scheme: UpdateScheme,
    /// FLIP fraction in [0, 1]: v_p ← flip (v_p + Δt Σ N a_I) + (1 − flip) Σ N v_I^{n+1}.
    /// 1 is pure FLIP (no numerical dissipation, noisier), 0 pure PIC (strongly
    /// dissipative).
    pub flip: f64,
    pub time_step: TimeStep,
    /// Local (Cundall) damping α in [0, 1): f_I ← f_I − α |f_I| sign(v_I), per component,
    /// with v_I the nodal velocity of the start of the step. For quasi-static explicit runs.
    pub damping: f64,
    /// End time of the run (the analysis starts at t = 0).
    pub duration: f64,
}

impl ExplicitSettings {
    /// The default FLIP fraction, 1 % PIC. Pure FLIP keeps the point velocities that map to
    /// no nodal momentum (more points than nodes): a body coming to rest keeps them, and a
    /// granular flow sprays single points far beyond its deposit (docs/theory.md §10). 1 %
    /// of PIC takes them out; runs that measure energy conservation set 1.
    pub const DEFAULT_FLIP: f64 = 0.99;

    /// The default settings for a run to `duration`: MUSL, [`Self::DEFAULT_FLIP`], CFL time
    /// step with safety 0.5, no damping.
    pub fn new(duration: f64) -> Self {
        let (scheme, time_step) = (UpdateScheme::default(), TimeStep::default());
        Self { scheme, flip: Self::DEFAULT_FLIP, time_step, damping: 0.0, duration }
    }

    /// Check every setting; the error names the first invalid field and its valid range.
    pub fn validate(&self) -> Result<(), ExplicitError> {
        let invalid = |field, value, valid| Err(ExplicitError::InvalidSettings(InvalidSetting { field, value, valid }));
        if !(self.flip >= 0.0 && self.flip <= 1.0) {
            return invalid("flip", self.flip, "[0, 1] (1 = pure FLIP, 0 = pure PIC)");
        }
        if !(self.damping >= 0.0 && self.damping < 1.0) {
            return invalid("damping", self.damping, "[0, 1) (0 = no damping; 0.1-0.3 is usual)");
        }
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return invalid("duration", self.duration, "a positive finite time");
        }
        match self.time_step {
            TimeStep::Cfl { safety } => {
                if !(safety > 0.0 && safety <= 1.0) {
                    return invalid("time_step.safety", safety, "(0, 1] (0.5-0.9 is usual)");
                }
            }
            TimeStep::Fixed { dt, .. } => {
                if !(dt.is_finite() && dt > 0.0) {
                    return invalid("time_step.dt", dt, "a positive finite time step");
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn field_of(s: &ExplicitSettings) -> Option<&'static str> {
        match s.validate() {
            Err(ExplicitError::InvalidSettings(e)) => Some(e.field),
            Err(e) => panic!("unexpected error {e}"),
            Ok(()) => None,
        }
    }

    #[test]
    fn defaults_are_valid() {
        let s = ExplicitSettings::new(1.0);
        assert_eq!(field_of(&s), None);
        assert_eq!(s.scheme, UpdateScheme::Musl);
        assert_eq!(s.flip, 0.99);
        assert_eq!(s.time_step, TimeStep::Cfl { safety: 0.5 });
        assert_eq!(s.damping, 0.0);
    }

    #[test]
    fn each_invalid_setting_is_named() {
        let base = ExplicitSettings::new(1.0);
        let cases: Vec<(ExplicitSettings, &str)> = vec![
            (ExplicitSettings { flip: 1.5, ..base.clone() }, "flip"),
            (ExplicitSettings { flip: -0.1, ..base.clone() }, "flip"),
            (ExplicitSettings { flip: f64::NAN, ..base.clone() }, "flip"),
            (ExplicitSettings { damping: 1.0, ..base.clone() }, "damping"),
            (ExplicitSettings { damping: -0.2, ..base.clone() }, "damping"),
            (ExplicitSettings { duration: 0.0, ..base.clone() }, "duration"),
            (ExplicitSettings { duration: f64::INFINITY, ..base.clone() }, "duration"),
            (ExplicitSettings { time_step: TimeStep::Cfl { safety: 0.0 }, ..base.clone() }, "time_step.safety"),
            (ExplicitSettings { time_step: TimeStep::Cfl { safety: 1.01 }, ..base.clone() }, "time_step.safety"),
            (
                ExplicitSettings {
                    time_step: TimeStep::Fixed { dt: -1e-3, allow_above_critical: false },
                    ..base.clone()
                },
                "time_step.dt",
            ),
            (
                ExplicitSettings {
                    time_step: TimeStep::Fixed { dt: f64::NAN, allow_above_critical: true },
                    ..base.clone()
                },
                "time_step.dt",
            ),
        ];
        for (s, field) in cases {
            assert_eq!(field_of(&s), Some(field), "{s:?}");
            let msg = s.validate().unwrap_err().to_string();
            assert!(msg.contains(field), "message does not name the field: {msg}");
        }
        // The edges of the valid ranges are accepted.
        for s in [
            ExplicitSettings { flip: 0.0, damping: 0.99, ..base.clone() },
            ExplicitSettings { time_step: TimeStep::Cfl { safety: 1.0 }, ..base.clone() },
        ] {
            assert_eq!(field_of(&s), None, "{s:?}");
        }
    }
}
