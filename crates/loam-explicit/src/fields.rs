//! The motion fields at the grid nodes of an explicit step: one, or one per body when the
//! model's bodies are in contact (`Model::with_body_contact`, docs/theory.md §10). Every
//! nodal array holds, per grid node, one record (or velocity) per field, node-major: the
//! slot of field f at node I is I × count + f. A point scatters to, and moves with, its own
//! body's field; `body_contact` settles the fields that meet at a node.

use crate::explicit::NodeRecord;
use loam_model::Model;
use rayon::prelude::*;

/// How many fields each node carries and how wide a field's record is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Fields {
    /// Fields per node: 1, or the number of bodies (the largest body id + 1) in contact.
    pub(crate) count: usize,
    /// Values per field's record: [m, p, f] (`NodeRecord`), then with contact
    /// g = Σ_p m_p ∇N_I(x_p) (D), whose direction is the field's outward normal.
    pub(crate) width: usize,
}

impl Fields {
    /// The fields of `model`'s points as they are now.
    pub(crate) fn of<const D: usize>(model: &Model<D>) -> Self {
        match model.body_contact() {
            None => Self { count: 1, width: NodeRecord::<D>::WIDTH },
            Some(_) => {
                let bodies = model.points().body().par_iter().copied().max().map_or(1, |b| b as usize + 1);
                Self { count: bodies, width: NodeRecord::<D>::WIDTH + D }
            }
        }
    }

    /// Whether the nodes carry a field per body.
    pub(crate) fn in_contact(&self) -> bool {
        self.count > 1
    }

    /// The field point `p` of `model` scatters to and moves with.
    #[inline]
    pub(crate) fn of_point<const D: usize>(&self, model: &Model<D>, p: usize) -> usize {
        if self.count == 1 {
            0
        } else {
            model.points().body()[p] as usize
        }
    }

    /// The slot of field `field` at grid node `node`.
    #[inline]
    pub(crate) fn slot(&self, node: usize, field: usize) -> usize {
        node * self.count + field
    }
}
