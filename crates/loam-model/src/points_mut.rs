//! The evolving state of a model's points, open to the analyses that advance it: slices
//! (so no point can be added or removed) of everything that changes from step to step,
//! beside the initial GIMP domains the current ones stretch from. What a point keeps for
//! ever (mass, material, initial position and volume) is not writable through it, so a
//! model's invariants — every point's material exists, the history layout is the laws' —
//! hold whatever an analysis writes.

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
    /// Every point's history, the laws' history length each.
    pub history: &'a mut [f64],
    /// The initial GIMP half-lengths, which the current ones stretch from.
    pub half_length0: &'a [SVector<f64, D>],
}

/// Whole fields of the points' evolving state, exchanged with a model's in O(1) by
/// [`Model::swap_state`](crate::Model::swap_state): an explicit step computes them anew
/// for every point and commits by exchange, with no copy.
#[derive(Debug, Default)]
pub struct StateFields<const D: usize> {
    pub position: Vec<SVector<f64, D>>,
    pub velocity: Vec<SVector<f64, D>>,
    pub deformation_gradient: Vec<Matrix3<f64>>,
    pub volume: Vec<f64>,
    pub half_length: Vec<SVector<f64, D>>,
    pub stress: Vec<Matrix3<f64>>,
    pub elastic_strain: Vec<Matrix3<f64>>,
    /// The laws' history values per point, or anything (not exchanged) where the laws keep
    /// none.
    pub history: Vec<f64>,
}

impl<'a, const D: usize> PointsMut<'a, D> {
    pub(crate) fn new(points: &'a mut PointStore<D>) -> Self {
        let PointStore {
            position,
            volume,
            velocity,
            acceleration,
            deformation_gradient,
            elastic_strain,
            stress,
            half_length0,
            half_length,
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
            half_length0,
        }
    }

    pub fn len(&self) -> usize {
        self.position.len()
    }

    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }
}
