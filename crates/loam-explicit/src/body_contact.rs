//! Frictional contact between bodies at the grid nodes of an explicit step (docs/theory.md
//! §10): each body moves with its own velocity field (`fields`), and where two or more
//! fields have mass at a node, the ones approaching the others are corrected — the
//! multi-velocity-field contact of Bardenhagen, Brackbill & Sulsky (2000), "The
//! material-point method for granular materials", Comput. Methods Appl. Mech. Engrg. 187,
//! and Bardenhagen et al. (2001), "An improved contact algorithm for the material point
//! method and application to stress propagation in granular material", CMES 2.
//!
//! At a node with fields b of mass m_b and trial velocity v*_b, the centre of mass moves at
//! v_cm = Σ m_b v*_b / Σ m_b. With g_b = Σ_p m_p ∇N_I(x_p) over b's points (∇N_I at a
//! point points back to node I, so g_b points from the body out through the node: −∇ of
//! the smoothed mass density), the normal is the one of the field whose |g| is largest at
//! the node, the flattest surface there (Nairn 2013, "Modeling imperfect interfaces in the
//! material point method using multimaterial methods", CMES 92): n_b = ĝ_b for that field,
//! −ĝ of it for the others. A body's corner then takes the normal of the surface it slides
//! on, not its own diagonal one, which would resist the sliding; for two bodies n_1 = −n_2,
//! so the corrections conserve momentum. With δ = v*_b − v_cm and δ_n = δ·n_b > 0 (b moves
//! into the others) the normal part of δ is removed and the tangential part δ_t loses
//! μ δ_n, or all of it (stick: v_b = v_cm); a field that leaves the others is free.
//!
//! A rigid body's field (`Model::with_rigid_bodies`) has its prescribed velocity v_R at
//! every node; where it meets the material, v_R takes the place of v_cm, its μ the
//! bodies', and its own normal the flattest one's (a rigid surface is the one it was
//! given; a deforming body's corner turns its g). The material fields' changes, summed,
//! are the rigid body's force on the material.

use crate::contact::{put, GridUpdate};
use crate::explicit::NodeRecord;
use crate::fields::{Fields, RigidMotion};
use nalgebra::SVector;
use rayon::prelude::*;

/// What the fields that meet at a node obey: the Coulomb coefficient between deformable
/// bodies, and per field the prescribed velocity and the friction against the material of
/// the rigid body it is, if it is one.
pub(crate) struct BodyContact<'a, const D: usize> {
    pub friction: f64,
    pub rigid: &'a [RigidMotion<D>],
}

/// The nodal buffers contact writes: per slot, whether contact set its velocity, and the
/// force a rigid body's field exerted on the material at the node (D).
pub(crate) struct Settled<'a> {
    pub settled: &'a mut [bool],
    pub reaction: &'a mut [f64],
}

/// After the grid momentum update: every rigid body's field takes its prescribed velocity,
/// and at every node where bodies meet, the deformable fields in contact take the corrected
/// undamped trial velocity (local damping would change the normal force friction is taken
/// from, as at a frictional plane); each with its FLIP acceleration (v_b − p_b / m_b) / Δt
/// and marked in `out.settled`. The others keep their damped update.
pub(crate) fn apply<const D: usize>(
    grid: &GridUpdate,
    contact: &BodyContact<D>,
    velocity: &mut [f64],
    acceleration: &mut [f64],
    out: Settled,
) {
    let fields = grid.fields;
    let per_node = (velocity.par_chunks_mut(fields.count * D).zip(acceleration.par_chunks_mut(fields.count * D)))
        .zip(out.settled.par_chunks_mut(fields.count).zip(out.reaction.par_chunks_mut(fields.count * D)))
        .zip(grid.gathered.par_chunks(fields.count * fields.width));
    per_node.enumerate().for_each(|(node, (((v, a), (settled, reaction)), records))| {
        let fixed = &grid.constrained[node * D..(node + 1) * D];
        let record = |f: usize| &records[f * fields.width..(f + 1) * fields.width];
        settled.fill(false);
        reaction.fill(0.0);
        for (f, motion) in contact.rigid.iter().enumerate() {
            if let (Some((velocity, _)), true) = (motion, record(f)[NodeRecord::<D>::MASS] > grid.m_min) {
                put(record(f), grid.dt, velocity, &mut v[f * D..(f + 1) * D], &mut a[f * D..(f + 1) * D]);
                settled[f] = true;
            }
        }
        let trial = |f: usize| grid.undamped_trial::<D>(node, f);
        settle(records, fields, grid.m_min, contact, fixed, trial, |f, corrected, against| {
            let m = record(f)[NodeRecord::<D>::MASS];
            if let Some(r) = against {
                let change = corrected - trial(f);
                (0..D).for_each(|i| reaction[r * D + i] += m * change[i] / grid.dt);
            }
            put(record(f), grid.dt, &corrected, &mut v[f * D..(f + 1) * D], &mut a[f * D..(f + 1) * D]);
            settled[f] = true;
        });
    });
}

/// The contact at one node (module docs): `records` its fields' records, `trial(f)` field
/// f's velocity before contact; `put(f, v, against)` for every deformable field whose
/// velocity contact changes, `against` the rigid field it met, if it met one. Where a rigid
/// body has mass, its prescribed velocity takes the place of the centre of mass's and its
/// friction the bodies' (the first rigid field, if several meet).
fn settle<const D: usize>(
    records: &[f64],
    fields: Fields,
    m_min: f64,
    contact: &BodyContact<D>,
    fixed: &[bool],
    trial: impl Fn(usize) -> SVector<f64, D>,
    mut put: impl FnMut(usize, SVector<f64, D>, Option<usize>),
) {
    let record = |f: usize| &records[f * fields.width..(f + 1) * fields.width];
    let massive = || (0..fields.count).filter(|&f| record(f)[NodeRecord::<D>::MASS] > m_min);
    if massive().nth(1).is_none() {
        return;
    }
    let outward = |f: usize| SVector::<f64, D>::from_column_slice(&record(f)[NodeRecord::<D>::WIDTH..][..D]);
    let (mut mass, mut momentum) = (0.0, SVector::<f64, D>::zeros());
    let mut flattest = (usize::MAX, 0.0);
    for f in massive() {
        let m = record(f)[NodeRecord::<D>::MASS];
        mass += m;
        momentum += trial(f) * m;
        let size = outward(f).norm();
        if size > flattest.1 {
            flattest = (f, size);
        }
    }
    // A rigid body's surface is the one it was given, while a deforming body's corners and
    // free edges turn its g: where a rigid body meets the others, its normal is taken.
    let rigid = massive().find(|&f| contact.rigid.get(f).is_some_and(Option::is_some));
    if let Some(r) = rigid.filter(|&r| outward(r).norm() > 0.0) {
        flattest = (r, outward(r).norm());
    }
    if flattest.1 == 0.0 {
        return;
    }
    let (centre, friction) = match rigid.and_then(|r| contact.rigid[r]) {
        Some((velocity, friction)) => (velocity, friction),
        None => (momentum / mass, contact.friction),
    };
    let normal = outward(flattest.0) / flattest.1;
    for f in massive().filter(|&f| !contact.rigid.get(f).is_some_and(Option::is_some)) {
        let (n, v) = (if f == flattest.0 { normal } else { -normal }, trial(f));
        let relative = v - centre;
        let approach = relative.dot(&n);
        if approach <= 0.0 {
            continue;
        }
        let slip = relative - n * approach;
        let (speed, limit) = (slip.norm(), friction * approach);
        let mut corrected = if speed <= limit { centre } else { v - n * approach - slip * (limit / speed) };
        (0..D).filter(|&i| fixed[i]).for_each(|i| corrected[i] = 0.0);
        put(f, corrected, rigid);
    }
}

/// Per rigid body of `bodies` (by its field), the force it exerted on the material over the
/// step: the nodes' `reaction`s summed in blocks of nodes in parallel, then the blocks in
/// order, so that any number of threads gives the same sums.
pub(crate) fn rigid_forces<const D: usize>(fields: Fields, bodies: &[usize], reaction: &[f64]) -> Vec<[f64; 3]> {
    const NODES: usize = 4096;
    let width = fields.count * D;
    let blocks: Vec<Vec<f64>> = (reaction.par_chunks(NODES * width))
        .map(|block| {
            let mut sum = vec![0.0; width];
            block.chunks(width).for_each(|node| sum.iter_mut().zip(node).for_each(|(s, r)| *s += r));
            sum
        })
        .collect();
    let mut total = vec![0.0; width];
    blocks.iter().for_each(|block| total.iter_mut().zip(block).for_each(|(t, b)| *t += b));
    bodies.iter().map(|&f| std::array::from_fn(|i| if i < D { total[f * D + i] } else { 0.0 })).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    /// Two fields at a node, body 0 below moving up into body 1 above: the normal parts of
    /// their relative velocity go, the slip loses μ times that, and momentum is kept; with
    /// enough friction both move with the centre of mass; moving apart, nothing changes.
    #[test]
    fn two_fields_meeting_keep_their_momentum_and_obey_coulomb() {
        let fields = Fields { count: 2, width: NodeRecord::<2>::WIDTH + 2, per_body: true, rigid: 0 };
        let contact = |friction| BodyContact { friction, rigid: &[None, None] };
        // [m, p (2), f (2), g (2)]: body 0's g points up (out of it), body 1's down.
        let records = [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 3.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0];
        let trials = [Vector2::new(2.0, 1.0), Vector2::new(0.0, -1.0)];
        let run = |friction: f64| {
            let mut out = trials;
            settle(&records, fields, 0.0, &contact(friction), &[false; 2], |f| trials[f], |f, v, _| out[f] = v);
            out
        };
        let centre = (trials[0] + trials[1] * 3.0) / 4.0;
        let smooth = run(0.0);
        assert_eq!(smooth[0], Vector2::new(2.0, centre.y));
        assert_eq!(smooth[1], Vector2::new(0.0, centre.y));
        let rough = run(0.1);
        let momentum = rough[0] + rough[1] * 3.0;
        assert!((momentum - centre * 4.0).norm() < 1e-15, "{momentum}");
        // Body 0: δ = v*_0 − v_cm = (1.5, 1.5), δ_n = 1.5, so its slip 1.5 loses 0.15.
        assert!((rough[0] - Vector2::new(2.0 - 0.15, centre.y)).norm() < 1e-15, "{}", rough[0]);
        assert_eq!(run(10.0), [centre, centre]);
        let apart = [Vector2::new(0.0, -1.0), Vector2::new(0.0, 1.0)];
        let mut out = apart;
        settle(&records, fields, 0.0, &contact(0.3), &[false; 2], |f| apart[f], |f, v, _| out[f] = v);
        assert_eq!(out, apart);
    }
}
