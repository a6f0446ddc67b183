//! The motion fields at the grid nodes of an explicit step: one; or, where bodies meet by
//! contact (docs/theory.md §10), one per body (`Model::with_body_contact`), or one shared by
//! the deformable bodies and one per rigid body (`Model::with_rigid_bodies`). Every nodal
//! array holds, per grid node, one record (or velocity) per field, node-major: the slot of
//! field f at node I is I × count + f. A point scatters to, and moves with, its own body's
//! field; `body_contact` settles the fields that meet at a node.

use crate::explicit::NodeRecord;
use loam_model::Model;
use nalgebra::SVector;
use rayon::prelude::*;

/// How many fields each node carries, how wide a field's record is, and which body's
/// field each is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Fields {
    /// Fields per node.
    pub(crate) count: usize,
    /// Values per field's record: [m, p, f] (`NodeRecord`), then with contact
    /// g = Σ_p m_p ∇N_I(x_p) (D), whose direction is the field's outward normal.
    pub(crate) width: usize,
    /// Every body has its own field (field = body id); else the deformable bodies share
    /// field 0 and the k-th rigid body (by id) has field k + 1.
    pub(crate) per_body: bool,
    /// Bit b set: body b is rigid.
    pub(crate) rigid: u64,
}

impl Fields {
    /// The fields of `model`'s points as they are now.
    pub(crate) fn of<const D: usize>(model: &Model<D>) -> Self {
        let rigid = model.rigid_bodies().iter().fold(0u64, |mask, r| mask | 1 << r.body());
        let width = NodeRecord::<D>::WIDTH + D;
        match (model.body_contact(), rigid) {
            (None, 0) => Self { count: 1, width: NodeRecord::<D>::WIDTH, per_body: false, rigid },
            (None, _) => Self { count: 1 + rigid.count_ones() as usize, width, per_body: false, rigid },
            (Some(_), _) => {
                // A rigid body whose points are all gone keeps its field, so that every
                // rigid body's field index stays in range.
                let rigid_ids = model.rigid_bodies().iter().map(|r| r.body() as usize + 1).max().unwrap_or(1);
                let bodies = model.points().body().par_iter().copied().max().map_or(1, |b| b as usize + 1);
                let bodies = bodies.max(rigid_ids);
                Self { count: bodies, width, per_body: true, rigid }
            }
        }
    }

    /// Whether the nodes carry more than one field.
    pub(crate) fn in_contact(&self) -> bool {
        self.count > 1
    }

    /// The field of the points of body `body`.
    #[inline]
    pub(crate) fn of_body(&self, body: u32) -> usize {
        if self.per_body {
            body as usize
        } else if body < 64 && self.rigid >> body & 1 == 1 {
            1 + (self.rigid & ((1u64 << body) - 1)).count_ones() as usize
        } else {
            0
        }
    }

    /// The field point `p` of `model` scatters to and moves with.
    #[inline]
    pub(crate) fn of_point<const D: usize>(&self, model: &Model<D>, p: usize) -> usize {
        if self.count == 1 {
            0
        } else {
            self.of_body(model.points().body()[p])
        }
    }

    /// Whether field `field` is a rigid body's.
    #[inline]
    pub(crate) fn is_rigid(&self, field: usize) -> bool {
        if self.per_body {
            field < 64 && self.rigid >> field & 1 == 1
        } else {
            field > 0
        }
    }

    /// The body of field `field` if it is a rigid body's.
    pub(crate) fn rigid_body(&self, field: usize) -> Option<u32> {
        if self.per_body {
            (field < 64 && self.rigid >> field & 1 == 1).then_some(field as u32)
        } else {
            let mut bodies = (0..64u32).filter(|&b| self.rigid >> b & 1 == 1);
            field.checked_sub(1).and_then(|k| bodies.nth(k))
        }
    }

    /// The slot of field `field` at grid node `node`.
    #[inline]
    pub(crate) fn slot(&self, node: usize, field: usize) -> usize {
        node * self.count + field
    }
}

/// A field's rigid-body motion over the step: its velocity and its friction against the
/// material, or `None` for a deformable field.
pub(crate) type RigidMotion<const D: usize> = Option<(SVector<f64, D>, f64)>;

/// Into `motions`, per field, the velocity over the step [t, t + Δt] and the friction of
/// the rigid body it is, if it is one.
pub(crate) fn rigid_motions<const D: usize>(
    model: &Model<D>,
    fields: Fields,
    (t, dt): (f64, f64),
    motions: &mut Vec<RigidMotion<D>>,
) {
    motions.clear();
    motions.extend((0..fields.count).map(|f| {
        let body = model.rigid_body_of(fields.rigid_body(f)?)?;
        Some((body.step_velocity(t, dt), body.friction()))
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without contact between deformable bodies, rigid bodies 1 and 4 get fields 1 and 2
    /// and every other body field 0; with it, each body its own.
    #[test]
    fn rigid_bodies_get_fields_of_their_own() {
        let shared = Fields { count: 3, width: 7, per_body: false, rigid: 1 << 1 | 1 << 4 };
        let fields: Vec<usize> = (0..6).map(|b| shared.of_body(b)).collect();
        assert_eq!(fields, [0, 1, 0, 0, 2, 0]);
        assert_eq!((0..3).map(|f| shared.rigid_body(f)).collect::<Vec<_>>(), [None, Some(1), Some(4)]);
        let each = Fields { per_body: true, count: 5, ..shared };
        assert_eq!((0..5).map(|b| each.of_body(b)).collect::<Vec<_>>(), [0, 1, 2, 3, 4]);
        assert_eq!((0..5).map(|f| each.rigid_body(f)).collect::<Vec<_>>(), [None, Some(1), None, None, Some(4)]);
    }
}
