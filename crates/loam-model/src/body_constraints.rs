//! Constraints on bodies ([`BodyConstraint`]): which active nodes one holds at a step —
//! those touched by a point of the body that started in its box, found node by node
//! through the connectivity's node → point adjacency (in parallel, each node on its own)
//! — their constrained dofs and their prescribed increments (docs/theory.md §5).

use crate::{motion_fields, BodyConstraint, Model, ModelError};
use loam_grid::{Connectivity, NodeLayout};
use rayon::prelude::*;

impl<const D: usize> Model<D> {
    /// Constrain bodies: each constraint's body must have points, it must prescribe at
    /// least one of the `D` components, and its displacement and box must be finite
    /// numbers (the box may be unbounded).
    pub fn with_body_constraints(mut self, constraints: Vec<BodyConstraint>) -> Result<Self, ModelError> {
        for (index, c) in constraints.iter().enumerate() {
            let what = if !self.rigid_bodies().is_empty() {
                Some("rigid bodies move with a velocity field of their own, and a body constraint holds every field at its nodes (not built yet)".into())
            } else if self.body_contact.is_some() {
                Some("bodies in contact have a velocity field each, and a body constraint holds every field at its nodes (not built yet)".into())
            } else if !self.points.body().contains(&c.body) {
                Some(format!("body {} has no points", c.body))
            } else if !c.fixed[..D].iter().any(|&f| f) {
                Some(format!("it prescribes none of the {D} displacement components"))
            } else if !c.displacement.iter().all(|u| u.is_finite()) {
                Some(format!("its displacement {:?} must be finite", &c.displacement[..D]))
            } else if c.within.is_some_and(|(lo, hi)| lo.iter().chain(&hi).any(|x| x.is_nan())) {
                Some("its box (within) must be numbers".to_string())
            } else {
                None
            };
            if let Some(what) = what {
                return Err(ModelError::BodyConstraint { index, what });
            }
        }
        self.body_constraints = constraints;
        Ok(self)
    }

    /// The constraints on bodies.
    pub fn body_constraints(&self) -> &[BodyConstraint] {
        &self.body_constraints
    }

    /// The active nodes (ascending) that body constraint `k` holds at the connectivity
    /// `conn`: those touched by a point of its body that started inside its box.
    pub fn body_constraint_nodes(&self, conn: &Connectivity<D>, k: usize) -> Vec<usize> {
        let adjacency = conn.node_points();
        (0..conn.active_nodes().len())
            .into_par_iter()
            .filter(|&a| adjacency.of(a).iter().any(|&(p, _)| self.body_constraint_holds(k, p as usize)))
            .collect()
    }

    /// Whether body constraint `k` holds point `p`: one of its body that started in its box.
    #[inline]
    pub fn body_constraint_holds(&self, k: usize, p: usize) -> bool {
        let c = &self.body_constraints[k];
        let x0 = &self.points.position0()[p];
        self.points.body()[p] == c.body && c.within.as_ref().is_none_or(|b| self.background.in_box(x0, b, None))
    }

    /// Mark in `out` (one per dof of `layout`, already sized) the dofs the body
    /// constraints hold at the connectivity `conn`, on every motion field.
    pub fn mark_body_constrained_dofs(&self, layout: &NodeLayout, conn: &Connectivity<D>, out: &mut [bool]) {
        for (k, c) in self.body_constraints.iter().enumerate() {
            for a in self.body_constraint_nodes(conn, k) {
                for field in motion_fields(layout) {
                    (0..D).filter(|&i| c.fixed[i]).for_each(|i| out[layout.dof(a, field, i)] = true);
                }
            }
        }
    }

    /// Put every body constraint's increment from load factor `from` to `to` (zero for a
    /// held one) on its nodes' dofs in `out`, after the planes': a body constraint prevails
    /// where both prescribe a component, so that its points move by its increment.
    pub(crate) fn put_body_increments(
        &self,
        layout: &NodeLayout,
        conn: &Connectivity<D>,
        (from, to): (f64, f64),
        out: &mut [f64],
    ) {
        for (k, c) in self.body_constraints.iter().enumerate() {
            let nodes = self.body_constraint_nodes(conn, k);
            put_increment::<D>(layout, &nodes, (&c.fixed, &c.displacement), to - from, out);
        }
    }
}

/// Put `factor` times `displacement` on the `fixed` components of every motion field of
/// the active `nodes` in `out`.
pub(crate) fn put_increment<const D: usize>(
    layout: &NodeLayout,
    nodes: &[usize],
    (fixed, displacement): (&[bool; 3], &[f64; 3]),
    factor: f64,
    out: &mut [f64],
) {
    for &a in nodes {
        for field in motion_fields(layout) {
            for i in (0..D).filter(|&i| fixed[i]) {
                out[layout.dof(a, field, i)] = factor * displacement[i];
            }
        }
    }
}
