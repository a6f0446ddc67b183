//! The soil of the V3 footing and the V4a/V4b slopes: docs/verification.md §V3 and §V4 give
//! both the same elasticity and strength. And the von Mises law of an undrained strength,
//! which the footing, the undrained slope and its run-out share.

use anyhow::Result;
use loam::constitutive::{ConstitutiveLaw, Elastic, VonMises};
use std::sync::Arc;

/// Cohesion c (the undrained strength c_u for von Mises).
pub const COHESION: f64 = 10.0;
/// Young's modulus and Poisson's ratio.
pub const YOUNG: f64 = 1e5;
pub const POISSON: f64 = 0.3;

/// Perfectly plastic von Mises of undrained strength `c_u`: σ_y = √3 c_u in plane strain.
pub fn undrained(elastic: Elastic, c_u: f64) -> Result<Arc<dyn ConstitutiveLaw>> {
    Ok(Arc::new(VonMises::new(elastic, 3f64.sqrt() * c_u, 0.0)?))
}
