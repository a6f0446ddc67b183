//! Energies of a model's state: the stored elastic energy of the points and the work of
//! the dead loads on their motion (the energy histories of dynamic runs).

use crate::{Kinematics, Model};
use loam_constitutive::tensor::sym_log;
use nalgebra::SVector;
use rayon::prelude::*;

impl<const D: usize> Model<D> {
    /// Stored elastic energy Σ_p V⁰_p W(ε^e_p): with finite strain ε^e = ½ ln b^e and W
    /// per unit reference volume (Hencky); with small strain W(ε^e) on the initial volume.
    pub fn stored_energy(&self) -> f64 {
        let pts = &self.points;
        (0..pts.len())
            .into_par_iter()
            .map(|p| {
                let law = self.law(p);
                let eps = match self.kinematics {
                    Kinematics::SmallStrain => pts.elastic_strain[p],
                    Kinematics::FiniteStrain => match sym_log(&pts.elastic_strain[p]) {
                        Ok(l) => l * 0.5,
                        Err(_) => return f64::NAN,
                    },
                };
                pts.volume0[p] * law.stored_energy(&eps)
            })
            .collect::<Vec<_>>()
            .iter()
            .sum()
    }
}

/// Work of the dead loads (gravity, point forces) on the points' motion, accumulated
/// step by step with the trapezoidal rule in the load factor: exact for loads held
/// constant, and for loads ramped linearly with displacement increments of one step.
#[derive(Debug, Clone, Default)]
pub struct ExternalWork<const D: usize> {
    previous: Vec<SVector<f64, D>>,
    previous_factor: f64,
    work: f64,
}

impl<const D: usize> ExternalWork<D> {
    /// Start at the model's current positions and load factor.
    pub fn new(model: &Model<D>, load_factor: f64) -> Self {
        Self { previous: model.points().position.clone(), previous_factor: load_factor, work: 0.0 }
    }

    /// Add the work done since the last call; the load factor went linearly from the last
    /// one to `load_factor`. Returns the accumulated work.
    pub fn advance(&mut self, model: &Model<D>, load_factor: f64) -> f64 {
        let pts = model.points();
        let dw: f64 = (0..pts.len())
            .map(|p| {
                let mean = (model.point_load_at(p, self.previous_factor) + model.point_load_at(p, load_factor)) * 0.5;
                mean.dot(&(pts.position[p] - self.previous[p]))
            })
            .sum();
        self.work += dw;
        self.previous.copy_from_slice(&pts.position);
        self.previous_factor = load_factor;
        self.work
    }

    pub fn work(&self) -> f64 {
        self.work
    }
}
