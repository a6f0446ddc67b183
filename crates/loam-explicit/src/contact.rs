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

/// One plane.
#[derive(Debug)]
struct PlaneContact<const D: usize> {
    normal: SVector<f64, D>,
    friction: f64,
    /// Held along the normal both ways (an inclined roller), not only against approach.
    bilateral: bool,
}

/// The model's inclined rollers, then its frictional planes, the grid nodes they act on,
/// and the force each exerted on the material in the last step.
#[derive(Debug, Default)]
pub(crate) struct PlaneContacts<const D: usize> {
    planes: Vec<PlaneContact<D>>,
    /// Every node some plane acts on, in increasing order.
    nodes: Vec<usize>,
    /// Per node of `nodes`, the range `first[k]..first[k + 1]` of `acting` holding the
    /// planes on it, in the order of `planes`.
    first: Vec<usize>,
    acting: Vec<usize>,
    forces: Vec<[f64; 3]>,
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
    /// The record of slot `slot` (`Fields::slot`).
    pub(crate) fn record(&self, slot: usize) -> &[f64] {
        &self.gathered[slot * self.fields.width..(slot + 1) * self.fields.width]
    }

    /// The undamped trial velocity (p + Δt f) / m of `field` at grid node `node`, zero in
    /// its held components, for a slot with mass.
    pub(crate) fn undamped_trial<const D: usize>(&self, node: usize, field: usize) -> SVector<f64, D> {
        let slot = self.fields.slot(node, field);
        let r = self.record(slot);
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

/// Set a field's velocity (its D values in `velocity`) to `v` and its FLIP acceleration to
/// (v − p / m) / Δt, for the field's scattered `record`.
pub(crate) fn put<const D: usize>(
    record: &[f64],
    dt: f64,
    v: &SVector<f64, D>,
    velocity: &mut [f64],
    acceleration: &mut [f64],
) {
    let m = record[NodeRecord::<D>::MASS];
    for i in 0..D {
        velocity[i] = v[i];
        acceleration[i] = (v[i] - record[NodeRecord::<D>::MOMENTUM + i] / m) / dt;
    }
}

impl<const D: usize> PlaneContacts<D> {
    /// The planes of `model`, each with the grid nodes it acts on (the grid does not move).
    pub(crate) fn of(model: &Model<D>) -> Self {
        let rollers = model.inclined_rollers().iter().map(|r| (r, 0.0, true));
        let frictional = model.frictional_planes().iter().map(|f| (f.plane(), f.friction(), false));
        let held: Vec<(&InclinedRoller<D>, f64, bool)> = rollers.chain(frictional).collect();
        let mut on: Vec<(usize, usize)> = (held.iter().enumerate())
            .flat_map(|(j, h)| model.nodes_beyond(h.0).into_iter().map(move |node| (node, j)))
            .collect();
        on.sort_unstable();
        let (mut nodes, mut first, acting) = (Vec::new(), Vec::new(), on.iter().map(|&(_, j)| j).collect());
        for (at, &(node, _)) in on.iter().enumerate() {
            if nodes.last() != Some(&node) {
                nodes.push(node);
                first.push(at);
            }
        }
        first.push(on.len());
        let planes = (held.iter())
            .map(|&(plane, friction, bilateral)| PlaneContact { normal: *plane.normal(), friction, bilateral })
            .collect::<Vec<_>>();
        let forces = vec![[f64::NAN; 3]; planes.len()];
        Self { planes, nodes, first, acting, forces }
    }

    /// The force each plane exerted on the material over the last step, inclined rollers
    /// first (NaN before the first step).
    pub(crate) fn forces(&self) -> &[[f64; 3]] {
        &self.forces
    }

    /// After the grid momentum update and the contact between bodies: at every node with
    /// mass on a plane, the planes act on each field's undamped trial velocity
    /// (p_I + Δt f_I) / m_I, so that local damping does not change the normal force
    /// friction is taken from, or on the velocity contact between bodies `settled` (per
    /// slot; empty without it). A field the planes change takes their velocity, undamped
    /// (friction dissipates there), and its FLIP acceleration; the others keep their
    /// update. Each plane's force is Σ m_I Δv_I / Δt. Serial over the nodes on the planes
    /// or beyond them (a region of the grid, not of the points), so forces sum in one order.
    pub(crate) fn apply(
        &mut self,
        grid: &GridUpdate,
        settled: &[bool],
        velocity: &mut [f64],
        acceleration: &mut [f64],
    ) {
        let mut forces = std::mem::take(&mut self.forces);
        forces.iter_mut().for_each(|f| *f = [0.0; 3]);
        for (k, node, f, slot) in self.massive(grid.gathered, grid.fields, grid.m_min) {
            let m = grid.record(slot)[NodeRecord::<D>::MASS];
            let carried = grid.damping == 0.0 || settled.get(slot) == Some(&true);
            let trial = if carried {
                SVector::from_column_slice(&velocity[slot * D..][..D])
            } else {
                grid.undamped_trial::<D>(node, f)
            };
            let after = self.admissible_at(k, trial, &grid.constrained[node * D..][..D], |j, change| {
                (0..D).for_each(|i| forces[j][i] += m * change[i] / grid.dt);
            });
            if after != trial {
                let range = slot * D..(slot + 1) * D;
                put(grid.record(slot), grid.dt, &after, &mut velocity[range.clone()], &mut acceleration[range]);
            }
        }
        self.forces = forces;
    }

    /// A nodal velocity field without forces (MUSL's re-mapped one, USF's carried one) made
    /// admissible at every node and field with mass on a plane.
    pub(crate) fn project(
        &self,
        gathered: &[f64],
        fields: Fields,
        constrained: &[bool],
        m_min: f64,
        velocity: &mut [f64],
    ) {
        for (k, node, _, slot) in self.massive(gathered, fields, m_min) {
            let v = &mut velocity[slot * D..(slot + 1) * D];
            let after = self.admissible_at(k, SVector::from_column_slice(v), &constrained[node * D..][..D], |_, _| ());
            v.copy_from_slice(after.as_slice());
        }
    }

    /// (k, node, field, slot) of every field with mass above `m_min` at the k-th node on a
    /// plane, but a rigid body's (its velocity is prescribed).
    fn massive<'a>(
        &'a self,
        gathered: &'a [f64],
        fields: Fields,
        m_min: f64,
    ) -> impl Iterator<Item = (usize, usize, usize, usize)> + 'a {
        let with =
            move |(k, &node): (usize, &usize)| (0..fields.count).map(move |f| (k, node, f, fields.slot(node, f)));
        (self.nodes.iter().enumerate().flat_map(with)).filter(move |&(_, _, f, slot)| {
            gathered[slot * fields.width + NodeRecord::<D>::MASS] > m_min && !fields.is_rigid(f)
        })
    }

    /// The velocity the planes on the k-th node leave of `v`, each in turn, with each
    /// plane's change of it passed to `change`. Where what is left still crosses one of
    /// them (a corner: the slope and the wall a landslide runs into), the node is stopped,
    /// the last change put to the first plane it crosses, as a node two constraints hold
    /// is held in every direction in the implicit analyses.
    fn admissible_at(
        &self,
        k: usize,
        mut v: SVector<f64, D>,
        constrained: &[bool],
        mut change: impl FnMut(usize, SVector<f64, D>),
    ) -> SVector<f64, D> {
        let on = &self.acting[self.first[k]..self.first[k + 1]];
        for &j in on {
            let after = self.planes[j].admissible(v, constrained);
            if after != v {
                change(j, after - v);
                v = after;
            }
        }
        if let Some(&j) = on.iter().find(|&&j| on.len() > 1 && self.planes[j].crosses(&v)) {
            change(j, -v);
            v = SVector::zeros();
        }
        v
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

    /// Whether `v` moves into the plane (or off an inclined roller) by more than round-off.
    fn crosses(&self, v: &SVector<f64, D>) -> bool {
        let (vn, tolerance) = (v.dot(&self.normal), 1e-12 * v.norm());
        vn < -tolerance || (self.bilateral && vn > tolerance)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    fn plane(normal: Vector2<f64>, friction: f64, bilateral: bool) -> PlaneContact<2> {
        PlaneContact { normal: normal.normalize(), friction, bilateral }
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

    /// At a node on a rough 30° slope (normal (sin 30°, cos 30°)) and a smooth wall
    /// (normal −x) ahead of it, soil sliding down the slope into the wall: the slope leaves
    /// it moving down the slope, the wall takes its x part, and what is left, straight
    /// down, would cross the slope, so the node stops, the rest put to the slope; soil
    /// leaving the wall upwards along the slope is left alone by both.
    #[test]
    fn a_node_in_a_corner_is_stopped_when_the_planes_disagree() {
        let (s, c) = (30f64.to_radians().sin(), 30f64.to_radians().cos());
        let contacts = PlaneContacts {
            planes: vec![plane(Vector2::new(s, c), 0.2, false), plane(Vector2::new(-1.0, 0.0), 0.0, false)],
            nodes: vec![7],
            first: vec![0, 2],
            acting: vec![0, 1],
            forces: Vec::new(),
        };
        let v = Vector2::new(1.0, -1.0);
        let mut changes = [Vector2::zeros(); 2];
        let after = contacts.admissible_at(0, v, &[false; 2], |j, dv| changes[j] += dv);
        assert_eq!(after, Vector2::zeros());
        assert!((changes[0] + changes[1] + v).norm() < 1e-15, "{changes:?}");
        assert!(changes[1].x < 0.0 && changes[1].y == 0.0, "the smooth wall pushes along −x: {:?}", changes[1]);
        let up = Vector2::new(-c, s) * 2.0;
        assert_eq!(contacts.admissible_at(0, up, &[false; 2], |_, _| panic!("no plane acts")), up);
    }
}
