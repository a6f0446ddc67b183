//! Constitutive laws and stress-update kinematics for loam.
//!
//! - [`tensor`]: spectral helpers for symmetric 3×3 tensors (logarithm, exponential,
//!   derivative of the logarithm) and the fourth-order [`Tensor4`] convention.
//! - [`ConstitutiveLaw`]: a small-strain return mapping from a trial elastic strain,
//!   with history kept in caller-owned slices (points store it struct-of-arrays).
//! - [`Elastic`]: linear isotropic elasticity (Hencky elasticity when driven by
//!   logarithmic strain).
//! - [`VonMises`]: J2 plasticity with linear hardening/softening and a residual floor
//!   (radial return, consistent tangent).
//! - [`MohrCoulomb`]: Mohr–Coulomb in principal stresses (plane, edges, apex, optional
//!   tension cut-off, linear softening of c, φ, ψ), consistent tangent mapped back
//!   through the eigenbasis; φ = 0 is Tresca.
//! - [`DruckerPrager`]: the smooth cone fitted to Mohr–Coulomb in plane strain, triaxial
//!   compression or extension ([`ConeFit`]), cone and apex returns, the same softening,
//!   consistent tangent.
//! - [`ModifiedCamClay`]: the critical-state model with pressure-dependent elasticity,
//!   an implicit return in (p, q) and its consistent tangent.
//! - [`ElementTest`]: one point of a law along a laboratory path (triaxial, oedometer,
//!   simple shear) under mixed strain and stress control.
//! - [`small_strain_update`] and [`finite_strain_update`]: the two kinematic drivers
//!   (docs/theory.md §3 and §2). The finite-strain spatial tangent is de Souza Neto, Perić &
//!   Owen (2008), *Computational Methods for Plasticity*, eq. 14.103.
//!
//! Stress is tension-positive. Fourth-order tensors are full (not Voigt) 9×9 matrices
//! with entry `(3*i + j, 3*k + l) = A_ijkl`, so that `A : g` is a matrix–vector product
//! on the row-major flattening of `g` and `A : B` is a matrix product.

pub mod tensor;

mod cam_clay;
mod drucker_prager;
mod elastic;
mod element;
mod frictional;
mod kinematics;
mod mohr_coulomb;
mod von_mises;

pub use cam_clay::{CamClayInitial, CamClayShear, ModifiedCamClay};
pub use drucker_prager::{ConeFit, DruckerPrager, DruckerPragerRegion};
pub use elastic::Elastic;
pub use element::{ElementPath, ElementTest, Held};
pub use frictional::Softening;
pub use kinematics::{
    finite_strain_stress, finite_strain_update, small_strain_stress, small_strain_update, FiniteStrainStress,
    FiniteStrainUpdate,
};
pub use mohr_coulomb::{MohrCoulomb, MohrCoulombRegion, MohrCoulombReturn};
pub use tensor::Tensor4;
pub use von_mises::{VonMises, VonMisesRegion};

use nalgebra::Matrix3;

/// Failures of a stress update. Updates never panic on bad input; the caller (Newton
/// loop) reacts to these by cutting the step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ConstitutiveError {
    #[error("non-finite value in {what}")]
    NonFinite { what: &'static str },
    #[error("non-positive Jacobian J = {j}")]
    NonPositiveJacobian { j: f64 },
    #[error("the deformation-gradient increment cannot be inverted (det = {det:e})")]
    SingularIncrement { det: f64 },
    #[error("tensor is not positive definite (smallest eigenvalue {min_eigenvalue})")]
    NotPositiveDefinite { min_eigenvalue: f64 },
    #[error("symmetric eigen-decomposition did not converge")]
    EigenFailed,
    #[error("invalid material parameter {name} = {value}")]
    InvalidParameter { name: &'static str, value: f64 },
    #[error("history slice has length {got}, law needs {expected}")]
    HistoryLength { expected: usize, got: usize },
    #[error("the initial stress {why}")]
    InitialStress { why: &'static str },
    #[error("{law} return mapping did not converge after {iterations} iterations (residual {residual})")]
    ReturnMappingFailed { law: &'static str, iterations: usize, residual: f64 },
}

/// Output of a small-strain return mapping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StressUpdate {
    /// σ, or the Kirchhoff stress τ when driven by logarithmic strain.
    pub stress: Matrix3<f64>,
    /// Updated elastic strain ε^e.
    pub elastic_strain: Matrix3<f64>,
    /// Algorithmic modulus D = ∂σ/∂ε_trial (minor-symmetric).
    pub tangent: Tensor4,
}

/// A constitutive law in small-strain form: a return mapping from a trial elastic strain.
/// History lives in caller-owned slices so that points can store it struct-of-arrays.
pub trait ConstitutiveLaw: Send + Sync + std::fmt::Debug {
    fn name(&self) -> &'static str;
    fn history_len(&self) -> usize {
        0
    }
    /// The law's own slots of a point's history, the first `history_len()`: a store holds
    /// as many slots a point as the law that needs most, and each law is given its own (a
    /// law given fewer than it keeps reports the mismatch when it updates).
    fn own_history<'a>(&self, slots: &'a [f64]) -> &'a [f64] {
        &slots[..self.history_len().min(slots.len())]
    }
    /// The history of a point that starts at `initial_stress` (the law's own stress; zero
    /// for unloaded ground, a geostatic state otherwise): zero (accumulated plastic
    /// strains) unless a law says otherwise — a hardening law's size of yield surface may
    /// follow from the initial stress.
    fn init_history(&self, h: &mut [f64], _initial_stress: &Matrix3<f64>) {
        h.iter_mut().for_each(|v| *v = 0.0);
    }
    /// What each history value is, one name per value (the output fields' names).
    fn history_names(&self) -> &'static [&'static str] {
        &[]
    }
    /// The accumulated equivalent plastic (shear) strain of history `h`, the field a shear
    /// band is read from; 0 for a law without plasticity.
    fn plastic_strain(&self, _h: &[f64]) -> f64 {
        0.0
    }
    /// Whether `stress` (the law's own: Kirchhoff stress in finite strain) with history `h`
    /// lies on the yield surface, to 1e-6 of the strength: the point is yielding. Always
    /// false for a law without plasticity.
    fn is_yielding(&self, _stress: &Matrix3<f64>, _h: &[f64]) -> bool {
        false
    }
    /// true when the algorithmic tangent is symmetric (elastic, associated flow)
    fn symmetric_tangent(&self) -> bool {
        true
    }
    /// true when the law's strength can fall as plastic strain accumulates (softening):
    /// its tangent can then turn indefinite.
    fn can_soften(&self) -> bool {
        false
    }
    fn update(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<StressUpdate, ConstitutiveError>;
    /// The stress and elastic strain of [`ConstitutiveLaw::update`] (the same values, the
    /// same history), without the algorithmic modulus, for an analysis with no use for it
    /// (explicit MPM). By default `update`'s; a law whose modulus costs overrides it.
    fn update_stress(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<(Matrix3<f64>, Matrix3<f64>), ConstitutiveError> {
        let u = self.update(eps_trial, h_n, h_out)?;
        Ok((u.stress, u.elastic_strain))
    }
    /// The law's isotropic elasticity at `state`, if it has one: initial stress states (K0)
    /// are turned into elastic strains with it.
    fn elasticity(&self, _state: &MaterialState) -> Option<Elastic> {
        None
    }
    /// The elastic strain that carries `stress` with history `history`: an initial stress
    /// state is turned into the point's elastic strain with it. By default the inverse of
    /// [`ConstitutiveLaw::elasticity`] at that state; a law whose elasticity is not linear
    /// gives its own exact inverse. `None` where the law has none.
    fn elastic_strain_of(&self, stress: &Matrix3<f64>, history: &[f64]) -> Option<Matrix3<f64>> {
        let state = MaterialState { stress: *stress, elastic_strain: &ZERO, history };
        self.elasticity(&state).map(|e| e.strain(stress))
    }
    /// Whether the law's stiffness is the same in every state ([`ConstitutiveLaw::p_wave_modulus`]
    /// and [`ConstitutiveLaw::elasticity`] ignore the state): callers may then take it once
    /// per material instead of once per point.
    fn constant_stiffness(&self) -> bool {
        true
    }
    /// The law's strength, if it has one that a strength-reduction analysis can divide
    /// ([`StrengthReducible`]); `None` for a law without a strength (elastic).
    fn as_strength_reducible(&self) -> Option<&dyn StrengthReducible> {
        None
    }
    /// P-wave (constrained) modulus λ + 2μ at `state`: the stiffness of the explicit CFL
    /// condition (docs/theory.md §10), of the ghost penalty and of stiffness scaling.
    fn p_wave_modulus(&self, state: &MaterialState) -> f64;
    /// Stored (elastic) energy per unit volume at elastic strain ε^e: ½ ε^e : C : ε^e for
    /// isotropic linear elasticity. With logarithmic strain it is the Hencky energy per unit
    /// reference volume. Energy histories (kinetic + stored − external work) use it.
    fn stored_energy(&self, elastic_strain: &Matrix3<f64>) -> f64;
}

/// A point's material state, on which a law's stiffness may depend (a pressure-dependent
/// law's moduli follow the mean stress): the law's own stress (Kirchhoff in finite
/// strain), its elastic strain and its history.
#[derive(Debug, Clone, Copy)]
pub struct MaterialState<'a> {
    pub stress: Matrix3<f64>,
    pub elastic_strain: &'a Matrix3<f64>,
    pub history: &'a [f64],
}

/// √(2/3): the equivalent deviatoric strain √(2/3) ‖dev ε‖ of the laws' histories.
pub(crate) const SQRT_2_3: f64 = 0.816_496_580_927_726;

static ZERO: Matrix3<f64> = Matrix3::from_array_storage(nalgebra::ArrayStorage([[0.0; 3]; 3]));

impl<'a> MaterialState<'a> {
    /// Unstressed and unstrained (small-strain ε^e = 0) with history `history`: the state a
    /// constant law's stiffness is read at.
    pub fn at_rest(history: &'a [f64]) -> Self {
        Self { stress: Matrix3::zeros(), elastic_strain: &ZERO, history }
    }
}

/// A law whose strength a strength-reduction analysis (Griffiths & Lane 1999) divides by a
/// factor F: c/F and tan φ/F with the dilation capped at the reduced friction, yield
/// stresses over F. A law offers it through [`ConstitutiveLaw::as_strength_reducible`].
pub trait StrengthReducible {
    /// The law with its strength divided by `factor` > 0; an error where the reduced
    /// parameters are invalid.
    fn with_strength_reduced(&self, factor: f64) -> Result<std::sync::Arc<dyn ConstitutiveLaw>, ConstitutiveError>;
}

/// The checks every law's update starts with: a finite trial strain, and `expected`
/// history values in and out.
#[inline]
pub(crate) fn check_update_inputs(
    eps_trial: &Matrix3<f64>,
    h_n: &[f64],
    h_out: &[f64],
    expected: usize,
) -> Result<(), ConstitutiveError> {
    check_finite(eps_trial, "trial strain")?;
    match [h_n.len(), h_out.len()].into_iter().find(|&got| got != expected) {
        Some(got) => Err(ConstitutiveError::HistoryLength { expected, got }),
        None => Ok(()),
    }
}

#[inline]
pub(crate) fn check_finite(m: &Matrix3<f64>, what: &'static str) -> Result<(), ConstitutiveError> {
    // v · 0 is ±0 for a finite v and NaN for ±∞ or NaN: one test of a branch-free sum
    // instead of nine branches, on the explicit step's path of every point.
    if !m.iter().fold(0.0, |sum, v| sum + v * 0.0).is_nan() {
        Ok(())
    } else {
        Err(ConstitutiveError::NonFinite { what })
    }
}
