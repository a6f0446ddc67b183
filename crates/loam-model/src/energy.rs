//! Energies of a model's state: the stored elastic energy of the points and the work of
//! the dead loads on their motion (the energy histories of dynamic runs).

use crate::{Kinematics, LoadLevel, Model};
use loam_constitutive::tensor::sym_log;
use loam_points::{PointId, PointStore};
use nalgebra::SVector;
use rayon::prelude::*;
use std::collections::HashMap;

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
                    Kinematics::SmallStrain => pts.elastic_strain()[p],
                    Kinematics::FiniteStrain => match sym_log(&pts.elastic_strain()[p]) {
                        Ok(l) => l * 0.5,
                        Err(_) => return f64::NAN,
                    },
                };
                pts.volume0()[p] * law.stored_energy(&eps)
            })
            .collect::<Vec<_>>()
            .iter()
            .sum()
    }
}

/// Work of the loads (gravity, point forces, the water's force, the loads on surfaces) on
/// the motion of the points and load vertices, accumulated step by step with the trapezoidal rule: exact for
/// dead loads held constant, and for loads ramped linearly with displacement increments of
/// one step. Points removed between two calls do no work in that interval, points added
/// start doing work from the next one.
#[derive(Debug, Clone)]
pub struct ExternalWork<const D: usize> {
    /// Every point's place at the last call, and its id.
    previous: Vec<SVector<f64, D>>,
    previous_ids: Vec<PointId>,
    previous_loads: Vec<Vec<(SVector<f64, D>, SVector<f64, D>)>>,
    previous_level: LoadLevel,
    work: f64,
}

impl<const D: usize> ExternalWork<D> {
    /// Start at the model's current positions and load level.
    pub fn new(model: &Model<D>, level: LoadLevel) -> Self {
        Self {
            previous: model.points().position().to_vec(),
            previous_ids: model.points().id().to_vec(),
            previous_loads: vertex_forces(model, level),
            previous_level: level,
            work: 0.0,
        }
    }

    /// Go on accumulating from `work`, done before the model reached its current state at
    /// `level` (a resumed run's): the same as the accumulator that reached it.
    pub fn resumed(model: &Model<D>, level: LoadLevel, work: f64) -> Self {
        Self { work, ..Self::new(model, level) }
    }

    /// Add the work done since the last call; the loads went linearly from their level then
    /// to `level`. Returns the accumulated work.
    pub fn advance(&mut self, model: &Model<D>, level: LoadLevel) -> f64 {
        let pts = model.points();
        if self.previous_ids != pts.id() {
            self.follow_ids(pts);
        }
        let (before, now) = (self.previous_level.body_factor(), level.body_factor());
        let dw: f64 = (0..pts.len())
            .map(|p| {
                let mean = (model.point_load_at(p, before) + model.point_load_at(p, now)) * 0.5;
                mean.dot(&(pts.position()[p] - self.previous[p]))
            })
            .sum();
        // The water's force on the points, on their current volumes.
        let (wb, wn) = (self.previous_level.body_factor(), level.body_factor());
        let dw_water: f64 = (0..pts.len())
            .map(|p| {
                let mean = (model.water_force(p, wb) + model.water_force(p, wn)) * (0.5 * pts.volume()[p]);
                mean.dot(&(pts.position()[p] - self.previous[p]))
            })
            .sum();
        let loads = vertex_forces(model, level);
        let dw_loads: f64 = loads
            .iter()
            .zip(&self.previous_loads)
            .flat_map(|(now, before)| now.iter().zip(before))
            .map(|((x, f), (x0, f0))| ((f + f0) * 0.5).dot(&(x - x0)))
            .sum();
        self.work += dw + dw_water + dw_loads;
        self.previous.copy_from_slice(pts.position());
        self.previous_loads = loads;
        self.previous_level = level;
        self.work
    }

    pub fn work(&self) -> f64 {
        self.work
    }

    /// The last places of `points` by id, after points came or went: a point added since
    /// starts where it is now.
    fn follow_ids(&mut self, points: &PointStore<D>) {
        let last: HashMap<PointId, SVector<f64, D>> =
            self.previous_ids.iter().copied().zip(self.previous.iter().copied()).collect();
        self.previous = points.id().iter().zip(points.position()).map(|(id, x)| *last.get(id).unwrap_or(x)).collect();
        self.previous_ids = points.id().to_vec();
    }
}

/// Per load, every vertex's place and force at `level`.
fn vertex_forces<const D: usize>(model: &Model<D>, level: LoadLevel) -> Vec<Vec<(SVector<f64, D>, SVector<f64, D>)>> {
    let mut f = Vec::new();
    model
        .loads()
        .iter()
        .enumerate()
        .map(|(k, load)| {
            load.forces_on(load.positions(), &mut f);
            let scale = model.load_scale(k, level);
            load.positions().iter().zip(&f).map(|(x, f)| (*x, f * scale)).collect()
        })
        .collect()
}
