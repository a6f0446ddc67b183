//! The evolving state of a model's points, open to the analyses that advance it: slices
//! (so no point can be added or removed) of everything that changes from step to step,
//! beside read-only slices of what a point keeps for ever (mass, material, initial
//! position, volume and domain). A model's invariants — every point's material exists,
//! the history layout is the laws' — hold whatever an analysis writes through it.

use loam_points::PointStore;
use nalgebra::{Matrix3, SVector};

/// Mutable view of the points' evolving state. See the module docs.
pub struct PointsMut<'a, const D: usize> {
    pub position: &'a mut [SVector<f64, D>],
    pub velocity: &'a mut [SVector<f64, D>],
    pub acceleration: &'a mut [SVector<f64, D>],
    pub deformation_gradient: &'a mut [Matrix3<f64>],
    pub volume: &'a mut [f64],
    pub half_length: &'a mut [SVector<f64, D>],
    pub stress: &'a mut [Matrix3<f64>],
    pub elastic_strain: &'a mut [Matrix3<f64>],
    /// Every point's history, `history_stride` values each.
    pub history: &'a mut [f64],
    pub history_stride: usize,
    pub position0: &'a [SVector<f64, D>],
    pub volume0: &'a [f64],
    pub half_length0: &'a [SVector<f64, D>],
    pub mass: &'a [f64],
    pub material: &'a [u32],
}

impl<'a, const D: usize> PointsMut<'a, D> {
    pub(crate) fn new(points: &'a mut PointStore<D>) -> Self {
        let history_stride = points.history_stride();
        let PointStore {
            position,
            position0,
            volume,
            volume0,
            mass,
            velocity,
            acceleration,
            deformation_gradient,
            elastic_strain,
            stress,
            half_length0,
            half_length,
            material,
            history,
            ..
        } = points;
        Self {
            position,
            velocity,
            acceleration,
            deformation_gradient,
            volume,
            half_length,
            stress,
            elastic_strain,
            history,
            history_stride,
            position0,
            volume0,
            half_length0,
            mass,
            material,
        }
    }

    pub fn len(&self) -> usize {
        self.position.len()
    }

    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }
}
