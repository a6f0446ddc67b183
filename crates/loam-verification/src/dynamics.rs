//! Time histories of dynamic runs and what is measured on them: the centre-of-mass
//! velocity, the energies, zero crossings and the period they give. Shared by the dynamic
//! cases (the V2 bar, the V5 disks, the column under sudden gravity), the tests,
//! `cargo xtask verify` and `cargo xtask steps`, so that a period is measured one way.

use loam_model::Model;
use loam_points::PointStore;

/// Centre-of-mass velocity along `axis`.
pub fn centre_of_mass_velocity<const D: usize>(points: &PointStore<D>, axis: usize) -> f64 {
    points.momentum()[axis] / points.total_mass()
}

/// Times where a sampled signal changes sign, by linear interpolation between samples.
pub fn zero_crossings(times: &[f64], values: &[f64]) -> Vec<f64> {
    let mut out = Vec::new();
    for k in 1..times.len().min(values.len()) {
        let (a, b) = (values[k - 1], values[k]);
        if a == 0.0 && k == 1 {
            out.push(times[0]);
        }
        if (a < 0.0 && b >= 0.0) || (a > 0.0 && b <= 0.0) {
            if b == 0.0 {
                out.push(times[k]);
            } else {
                out.push(times[k - 1] + (times[k] - times[k - 1]) * a / (a - b));
            }
        }
    }
    out.dedup();
    out
}

/// Period of an oscillation from its zero crossings: twice the mean spacing from the first
/// crossing to the last. `None` with fewer than two crossings.
pub fn period_from_crossings(crossings: &[f64]) -> Option<f64> {
    if crossings.len() < 2 {
        return None;
    }
    let n = crossings.len() - 1;
    Some(2.0 * (crossings[n] - crossings[0]) / n as f64)
}

/// Time histories of a dynamic run, sampled after every step: centre-of-mass velocity,
/// kinetic and stored energy.
#[derive(Debug, Clone, Default)]
pub struct DynamicRecord {
    pub time: Vec<f64>,
    /// Centre-of-mass velocity along x.
    pub vcm_x: Vec<f64>,
    pub kinetic: Vec<f64>,
    pub stored: Vec<f64>,
}

impl DynamicRecord {
    pub fn push<const D: usize>(&mut self, time: f64, model: &Model<D>) {
        self.time.push(time);
        self.vcm_x.push(centre_of_mass_velocity(model.points(), 0));
        self.kinetic.push(model.points().kinetic_energy());
        self.stored.push(model.stored_energy());
    }

    /// Kinetic + stored energy at sample k.
    pub fn energy(&self, k: usize) -> f64 {
        self.kinetic[k] + self.stored[k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sampled cosine of period 4 crosses zero at 1, 3, 5, ... whatever the sampling.
    #[test]
    fn the_period_of_a_sampled_cosine_is_found_from_its_crossings() {
        let times: Vec<f64> = (0..=300).map(|k| k as f64 * 0.037).collect();
        let values: Vec<f64> = times.iter().map(|t| (std::f64::consts::FRAC_PI_2 * t).cos()).collect();
        let crossings = zero_crossings(&times, &values);
        assert_eq!(crossings.len(), 6);
        assert!((crossings[0] - 1.0).abs() < 1e-3, "{crossings:?}");
        let period = period_from_crossings(&crossings).unwrap();
        assert!((period - 4.0).abs() < 1e-3, "{period}");
        assert_eq!(period_from_crossings(&crossings[..1]), None);
    }
}
