//! Energy of the explicit scheme as the scheme conserves it.
//!
//! MUSL and USL are leapfrog schemes: after step k the points carry x^k, σ^k and v^{k−½}
//! (v^{k−½} = v^{k−3/2} + Δt a(σ^{k−1}), x^k = x^{k−1} + Δt v^{k−½}); USF updates the stress
//! first, so after step k they carry σ^k and v^{k+½}. The energy
//! E_k = W(σ^k) + ½ Σ m v^{k−½}·v^{k+½} is what leapfrog conserves, without the O(ωΔt)
//! oscillation of W + ½ Σ m |v|² read at one step.

use crate::UpdateScheme;
use loam_model::Model;
use nalgebra::SVector;

/// Kinetic + stored energy with the velocities read at the half steps they belong to.
pub struct LeapfrogEnergy<const D: usize> {
    /// Velocities lead the stress by half a step (USF).
    leads: bool,
    stored: f64,
    velocity: Vec<SVector<f64, D>>,
}

impl<const D: usize> LeapfrogEnergy<D> {
    pub fn new(scheme: UpdateScheme, initial: &Model<D>) -> Self {
        Self {
            leads: scheme == UpdateScheme::Usf,
            stored: initial.stored_energy(),
            velocity: initial.points().velocity().to_vec(),
        }
    }

    /// Feed the state after a step; returns E of the latest time level it can: this step's
    /// (USF) or the previous step's (MUSL, USL).
    pub fn advance(&mut self, m: &Model<D>) -> f64 {
        let p = &m.points();
        let kinetic = 0.5 * (0..p.len()).map(|i| p.mass()[i] * self.velocity[i].dot(&p.velocity()[i])).sum::<f64>();
        let stored = m.stored_energy();
        let e = kinetic + if self.leads { stored } else { self.stored };
        self.stored = stored;
        self.velocity.clear();
        self.velocity.extend_from_slice(p.velocity());
        e
    }
}
