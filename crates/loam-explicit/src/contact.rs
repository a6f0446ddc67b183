//! Rigid planes at the grid nodes of an explicit step (docs/theory.md §5): inclined rollers
//! (held along the normal both ways, smooth) and frictional planes (Coulomb friction, the
//! material free to leave), applied to the nodal velocities after the momentum update.
//!
//! At a node on the plane or beyond it, with the trial velocity v* and the plane's unit
//! normal n into the material, v*_n = v*·n < 0 (approaching) is stopped and the tangential
//! part v*_t = v* − v*_n n keeps what Coulomb friction leaves of it: the normal impulse per
//! unit mass is |v*_n|, the tangential one at most μ |v*_n|, so
//! v = v*_t max(0, 1 − μ |v*_n| / |v*_t|). This is the rigid-body case of the multi-field
//! contact of Bardenhagen, Brackbill & Sulsky (2000), "The material-point method for
//! granular materials", Comput. Methods Appl. Mech. Engrg. 187, with the rigid body's
//! velocity zero and the normal given by the plane. Summed over a plane's nodes, the
//! impulse over the step gives the force the plane exerts on the material.

use crate::explicit::NodeRecord;
use crate::fields::Fields;
use loam_model::{InclinedRoller, Model};
use nalgebra::SVector;

/// One plane and the grid nodes it acts on.
#[derive(Debug)]
struct PlaneContact<const D: usize> {
    normal: SVector<f64, D>,
    friction: f64,
    /// Held along the normal both ways (an inclined roller), not only against approach.
    bilateral: bool,
    /// The grid nodes on the plane or beyond it, as indices into `PlaneContacts::nodes`.
    slots: Vec<usize>,
}

/// The model's inclined rollers, then its frictional planes, with the force each exerted
/// on the material in the last step.
#[derive(Debug, Default)]
pub(crate) struct PlaneContacts<const D: usize> {
    planes: Vec<PlaneContact<D>>,
    /// Every node some plane acts on, in increasing order.
    nodes: Vec<usize>,
    forces: Vec<[f64; 3]>,
    /// Per node of `nodes` and field, its damped velocity (D) and whether a plane changed it.
    damped: Vec<f64>,
    touched: Vec<bool>,
}

/// The nodal state `PlaneContacts::apply` reads: the scattered records, the internal force
/// where the stress was updated first (USF), the constrained dofs, the empty-node mass, the
/// time step and the local damping coefficient.
pub(crate) struct GridUpdate<'a> {
    pub gathered: &'a [f64],
    pub fields: Fields,
    pub internal: Option<&'a [f64]>,
    pub constrained: &'a [bool],
    pub m_min: f64,
    pub dt: f64,
    pub damping: f64,
}

impl GridUpdate<'_> {
    /// The undamped trial velocity (p + Δt f) / m of `field` at grid node `node`, zero in
    /// its held components, for a slot with mass.
    pub(crate) fn undamped_trial<const D: usize>(&self, node: usize, field: usize) -> SVector<f64, D> {
        let slot = self.fields.slot(node, field);
        let r = &self.gathered[slot * self.fields.width..(slot + 1) * self.fields.width];
        let m = r[NodeRecord::<D>::MASS];
        SVector::from_fn(|i, _| {
            if self.constrained[node * D + i] {
                return 0.0;
            }
            let force = r[NodeRecord::<D>::FORCE + i] + self.internal.map_or(0.0, |fi| fi[slot * D + i]);
            (r[NodeRecord::<D>::MOMENTUM + i] + self.dt * force) / m
        })
    }
}

impl<const D: usize> PlaneContacts<D> {
    /// The planes of `model`, each with the grid nodes it acts on (the grid does not move).
    pub(crate) fn of(model: &Model<D>) -> Self {
        let rollers = model.inclined_rollers().iter().map(|r| (r, 0.0, true));
        let frictional = model.frictional_planes().iter().map(|f| (f.plane(), f.friction(), false));
        let held: Vec<(&InclinedRoller<D>, f64, bool, Vec<usize>)> = rollers
            .chain(frictional)
            .map(|(plane, mu, bilateral)| (plane, mu, bilateral, model.nodes_beyond(plane)))
            .collect();
        let mut nodes: Vec<usize> = held.iter().flat_map(|h| h.3.iter().copied()).collect();
        nodes.sort_unstable();
        nodes.dedup();
        let slot = |node: &usize| nodes.binary_search(node).expect("the union holds every plane's nodes");
        let planes: Vec<PlaneContact<D>> = (held.iter())
            .map(|(plane, friction, bilateral, on)| PlaneContact {
                normal: *plane.normal(),
                friction: *friction,
                bilateral: *bilateral,
                slots: on.iter().map(slot).collect(),
            })
            .collect();
        let forces = vec![[f64::NAN; 3]; planes.len()];
        Self { damped: Vec::new(), touched: Vec::new(), planes, nodes, forces }
    }

    /// The force each plane exerted on the material over the last step, inclined rollers
    /// first (NaN before the first step).
    pub(crate) fn forces(&self) -> &[[f64; 3]] {
        &self.forces
    }

    /// After the grid momentum update: at every node with mass on a plane, the planes act
    /// on each field's undamped trial velocity (p_I + Δt f_I) / m_I, so that local damping
    /// does not change the normal force that friction is taken from; a field no plane acts
    /// on keeps its damped velocity, one in contact is not damped (friction dissipates
    /// there). Then the FLIP acceleration (v_I − p_I / m_I) / Δt and each plane's force
    /// Σ m_I Δv_I / Δt. Serial over the planes' nodes (a surface of the grid), so forces sum
    /// in one order.
    pub(crate) fn apply(&mut self, grid: &GridUpdate, velocity: &mut [f64], acceleration: &mut [f64]) {
        let fields = grid.fields;
        let record = |slot: usize| &grid.gathered[slot * fields.width..(slot + 1) * fields.width];
        let slots = self.nodes.len() * fields.count;
        self.damped.resize(slots * D, 0.0);
        self.touched.resize(slots, false);
        for (k, &node) in self.nodes.iter().enumerate() {
            for f in 0..fields.count {
                let (at, slot) = (k * fields.count + f, fields.slot(node, f));
                self.touched[at] = false;
                let (r, v) = (record(slot), &mut velocity[slot * D..(slot + 1) * D]);
                let m = r[NodeRecord::<D>::MASS];
                if m <= grid.m_min || grid.damping == 0.0 {
                    continue;
                }
                self.damped[at * D..(at + 1) * D].copy_from_slice(v);
                v.copy_from_slice(grid.undamped_trial::<D>(node, f).as_slice());
            }
        }
        for (plane, force) in self.planes.iter().zip(&mut self.forces) {
            *force = [0.0; 3];
            for (&k, f) in plane.slots.iter().flat_map(|k| std::iter::repeat(k).zip(0..fields.count)) {
                let node = self.nodes[k];
                let (slot, m) = (fields.slot(node, f), record(fields.slot(node, f))[NodeRecord::<D>::MASS]);
                if m <= grid.m_min {
                    continue;
                }
                let v = &mut velocity[slot * D..(slot + 1) * D];
                let before = SVector::<f64, D>::from_column_slice(v);
                let after = plane.admissible(before, &grid.constrained[node * D..(node + 1) * D]);
                if after != before {
                    self.touched[k * fields.count + f] = true;
                    v.copy_from_slice(after.as_slice());
                    (0..D).for_each(|i| force[i] += m * (after[i] - before[i]) / grid.dt);
                }
            }
        }
        for (k, &node) in self.nodes.iter().enumerate() {
            for f in 0..fields.count {
                let (at, slot) = (k * fields.count + f, fields.slot(node, f));
                let r = record(slot);
                let m = r[NodeRecord::<D>::MASS];
                if m <= grid.m_min {
                    continue;
                }
                let v = &mut velocity[slot * D..(slot + 1) * D];
                if !self.touched[at] && grid.damping != 0.0 {
                    v.copy_from_slice(&self.damped[at * D..(at + 1) * D]);
                }
                for i in 0..D {
                    acceleration[slot * D + i] = (v[i] - r[NodeRecord::<D>::MOMENTUM + i] / m) / grid.dt;
                }
            }
        }
    }

    /// A nodal velocity field without forces (MUSL's re-mapped one) made admissible at
    /// every node and field with mass on a plane.
    pub(crate) fn project(
        &self,
        gathered: &[f64],
        fields: Fields,
        constrained: &[bool],
        m_min: f64,
        velocity: &mut [f64],
    ) {
        for plane in &self.planes {
            for (node, f) in plane.slots.iter().flat_map(|&k| std::iter::repeat(self.nodes[k]).zip(0..fields.count)) {
                let slot = fields.slot(node, f);
                if gathered[slot * fields.width + NodeRecord::<D>::MASS] <= m_min {
                    continue;
                }
                let v = &mut velocity[slot * D..(slot + 1) * D];
                let after = plane.admissible(SVector::from_column_slice(v), &constrained[node * D..(node + 1) * D]);
                v.copy_from_slice(after.as_slice());
            }
        }
    }

    pub(crate) fn is_empty(&self) -> bool {
        self.planes.is_empty()
    }
}

impl<const D: usize> PlaneContact<D> {
    /// The velocity the plane leaves of `v` at a node whose `constrained` components are
    /// held (the module docs); where a held component keeps the result moving into the
    /// plane (or off an inclined roller), the node is stopped.
    fn admissible(&self, v: SVector<f64, D>, constrained: &[bool]) -> SVector<f64, D> {
        let vn = v.dot(&self.normal);
        if vn >= 0.0 && !(self.bilateral && vn > 0.0) {
            return v;
        }
        let tangential = v - self.normal * vn;
        let (speed, limit) = (tangential.norm(), self.friction * vn.abs());
        let mut after = if speed <= limit { SVector::zeros() } else { tangential * (1.0 - limit / speed) };
        if (0..D).any(|i| constrained[i] && after[i] != 0.0) {
            (0..D).filter(|&i| constrained[i]).for_each(|i| after[i] = 0.0);
            let n = after.dot(&self.normal);
            if n < 0.0 || (self.bilateral && n != 0.0) {
                after = SVector::zeros();
            }
        }
        after
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    fn plane(normal: Vector2<f64>, friction: f64, bilateral: bool) -> PlaneContact<2> {
        PlaneContact { normal: normal.normalize(), friction, bilateral, slots: Vec::new() }
    }

    /// Coulomb's law at a node: an approaching velocity loses its normal part and μ times
    /// that from its tangential part, or all of it (stick); a leaving one is kept; an
    /// inclined roller also stops a leaving normal part and never touches the tangent.
    #[test]
    fn a_plane_stops_approach_and_takes_friction_from_the_slip() {
        let base = plane(Vector2::new(0.0, 1.0), 0.25, false);
        let free = [false; 2];
        assert_eq!(base.admissible(Vector2::new(2.0, -4.0), &free), Vector2::new(1.0, 0.0));
        assert_eq!(base.admissible(Vector2::new(-0.5, -4.0), &free), Vector2::zeros());
        assert_eq!(base.admissible(Vector2::new(2.0, 3.0), &free), Vector2::new(2.0, 3.0));
        let roller = plane(Vector2::new(-1.0, 1.0), 0.0, true);
        let v = roller.admissible(Vector2::new(3.0, 1.0), &free);
        assert!((v - Vector2::new(2.0, 2.0)).norm() < 1e-15, "{v}");
        let v = roller.admissible(Vector2::new(-1.0, 3.0), &free);
        assert!((v - Vector2::new(1.0, 1.0)).norm() < 1e-15, "{v}");
        // Held in x as well: what is left along the incline would still cross it.
        assert_eq!(roller.admissible(Vector2::new(3.0, 1.0), &[true, false]), Vector2::zeros());
        // Held in x on a level base: the slip along x is the constraint's, not friction's.
        assert_eq!(base.admissible(Vector2::new(0.0, -1.0), &[true, false]), Vector2::zeros());
    }
}
