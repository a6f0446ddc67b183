//! Contact in explicit runs (docs/verification.md §V9): a block slides down a frictional
//! incline, and down an elastic slab as a body of its own, at the rigid block's rate, and
//! stays on one steeper than its angle of friction; bodies in contact keep their momentum.
//! `cargo xtask verify` runs the longer cases; these are shortened to 0.6 s.

use crate::common::assert_same_state;
use loam_constitutive::Elastic;
use loam_explicit::{
    Explicit, ExplicitError, ExplicitSettings, Kinematics, LeapfrogEnergy, Model, TimeStep, UpdateScheme,
};
use loam_grid::{BasisKind, Grid};
use loam_model::{FrictionalPlane, RigidBody};
use loam_points::{PointStore, Shape};
use loam_verification::sliding::{block_displacement, block_speed, fitted_slope, SlidingBlock};
use nalgebra::{SVector, Vector2};
use std::sync::Arc;

const DURATION: f64 = 0.6;

/// Run `model`, `block` posed on a plane or a slab, for `DURATION` with local damping
/// `damping`: the fitted acceleration of the block's centre of mass down the slope after
/// 0.1 s, and the block's mean displacement down it at half the run and at its end.
fn slide(block: SlidingBlock, model: Model<2>, damping: f64) -> (f64, [f64; 2]) {
    // Bodies in contact need USL (`ExplicitError::ContactScheme`).
    let scheme = if model.body_contact().is_some() { UpdateScheme::Usl } else { UpdateScheme::Musl };
    let cfl = TimeStep::Cfl { safety: 0.5 };
    let settings = ExplicitSettings { time_step: cfl, damping, scheme, ..ExplicitSettings::new(DURATION) };
    let mut ex = Explicit::new(model, settings).unwrap();
    let (mut times, mut speeds, mut halfway) = (Vec::new(), Vec::new(), None);
    let downhill = block.downhill();
    while !ex.is_finished() {
        let r = ex.step().unwrap();
        if r.time >= 0.1 {
            times.push(r.time);
            speeds.push(block_speed(ex.model(), &downhill));
        }
        if r.time >= 0.5 * DURATION {
            halfway.get_or_insert(block_displacement(ex.model(), &downhill));
        }
    }
    (fitted_slope(&times, &speeds), [halfway.unwrap(), block_displacement(ex.model(), &downhill)])
}

/// Room for the block's travel over the run.
fn travel(block: &SlidingBlock) -> f64 {
    0.5 * block.acceleration() * DURATION * DURATION + 0.1
}

/// θ = 30°, μ = 0.3 on an inclined plane that cuts the cells: a = g (sin θ − μ cos θ)
/// within 1 % (the bound; the verification case measures 1e-4 over 1 s).
#[test]
fn a_block_slides_down_a_frictional_incline_at_the_rigid_rate() {
    let block = SlidingBlock { slope_deg: 30.0, friction: 0.3, inclined: true };
    let (a, _) = slide(block, block.model(travel(&block)), 0.0);
    println!("a = {a}, rigid block {}", block.acceleration());
    assert!((a / block.acceleration() - 1.0).abs() < 0.01, "a = {a}");
}

/// θ = 30°, μ = 0.7 > tan θ on a level base with gravity turned: with local damping to stop
/// the released block's bouncing (which would ratchet it down), it moves by its elastic
/// shear alone, below 1e-3 of the frictionless block's travel ½ g sin θ t² (measured
/// 5e-4 of it, 4.6e-4 m: twice the mean shear ρ g sin θ h² / 3G = 2.2e-4 m of a long layer
/// as thick as the block, whose free ends make it more compliant), and it has stopped:
/// over the second half of the run it moves less than 1e-5 m (measured 6e-7 m). The planes
/// act on the undamped trial velocity: damping a node in contact would change the normal
/// force that its friction is taken from, and the block would creep at about 2 mm/s, 6e-4 m
/// over that half.
#[test]
fn friction_holds_a_block_on_a_slope_below_its_angle() {
    let block = SlidingBlock { slope_deg: 30.0, friction: 0.7, inclined: false };
    let (_, [halfway, moved]) = slide(block, block.model(travel(&block)), 0.5);
    let free = 0.5 * 10.0 * 0.5 * DURATION * DURATION;
    println!("moved {halfway} m at half the run, {moved} m at its end, frictionless {free} m");
    assert!(moved.abs() < 1e-3 * free, "moved {moved}");
    assert!((moved - halfway).abs() < 1e-5, "still moving: {halfway} m, then {moved} m");
}

/// The block as a body of its own on an elastic slab of the same soil, θ = 30°, μ = 0.3
/// between the two bodies' velocity fields: a = g (sin θ − μ cos θ) within 1 % (the
/// verification case measures 6e-5 over 1 s). The normal at a node is the flatter
/// surface's (the slab's), not the block's own diagonal one at its corners, which would
/// hold the block back.
#[test]
fn a_block_slides_down_an_elastic_slab_at_the_rigid_rate() {
    let block = SlidingBlock { slope_deg: 30.0, friction: 0.3, inclined: false };
    let (a, _) = slide(block, block.model_on_slab(travel(&block)), 0.0);
    println!("a = {a}, rigid block {}", block.acceleration());
    assert!((a / block.acceleration() - 1.0).abs() < 0.01, "a = {a}");
}

/// Two free elastic blocks 0.5 m wide, one sent at 1 m/s into the other at rest, a cell
/// apart, no gravity and no support, smooth contact between them (USL, as contact needs;
/// MUSL is refused): momentum is kept through the impact (the corrections of two fields at
/// a node are equal and opposite; what leaves is the momentum of nodes below the empty-node
/// mass, 1e-12 of the largest, over 830 steps: 1.6e-10 of it, and 1.1e-9 for the same
/// blocks as one field; bound 1e-8), the
/// leapfrog energy never rises above its start (V5's bound, 1e-3 of it: the contact's
/// normal corrections are inelastic at a node, and the run loses 16 %), and the struck
/// block moves on ahead of the other: they part instead of moving on as one, as one field
/// would bond them where they meet.
#[test]
fn bodies_in_contact_keep_their_momentum_and_part_after_impact() {
    let (drift, highest, [v0, v1]) = impact([40, 8]);
    println!("2D: momentum drift {drift:e}, highest energy {highest} of the start, velocities {v0} and {v1}");
    assert!(drift < 1e-8, "momentum drift {drift:e}");
    assert!(highest <= 1.0 + 1e-3, "energy rose to {highest} of the start");
    assert!(v1 > 0.5 && v1 > v0 + 0.1, "the struck block moves on ahead: {v0}, {v1}");
}

/// The same impact in 3D, the blocks 0.4 m deep: the same bounds (the contact's normal is
/// the flattest surface's in 3D too, and two fields' corrections are equal and opposite;
/// measured drift 9.7e-10, no energy gained, the blocks part at 0.12 and 0.88 m/s).
#[test]
fn bodies_in_contact_keep_their_momentum_in_3d() {
    let (drift, highest, [v0, v1]) = impact([40, 8, 8]);
    println!("3D: momentum drift {drift:e}, highest energy {highest} of the start, velocities {v0} and {v1}");
    assert!(drift < 1e-8, "momentum drift {drift:e}");
    assert!(highest <= 1.0 + 1e-3, "energy rose to {highest} of the start");
    assert!(v1 > 0.5 && v1 > v0 + 0.1, "the struck block moves on ahead: {v0}, {v1}");
}

/// Two blocks of the impact tests, 0.5 m long and 0.4 m across, a cell apart, the left one
/// sent at 1 m/s, run 0.5 s: the relative drift of the momentum, the highest leapfrog
/// energy over its start, and each block's mean velocity along x at the end.
fn impact<const D: usize>(cells: [usize; D]) -> (f64, f64, [f64; 2]) {
    let grid = Grid::new(SVector::zeros(), SVector::repeat(0.1), cells).unwrap();
    let across = |x: [f64; 2]| Shape::Box {
        min: SVector::from_fn(|i, _| if i == 0 { x[0] } else { 0.2 }),
        max: SVector::from_fn(|i, _| if i == 0 { x[1] } else { 0.6 }),
    };
    let mut points = PointStore::new();
    points.fill(&grid, &across([0.5, 1.0]), 2, 2.0, 0).unwrap();
    let first = points.len();
    points.fill(&grid, &across([1.1, 1.6]), 2, 2.0, 0).unwrap();
    points.assign_body(first..points.len(), 1);
    points.velocity_mut()[..first].iter_mut().for_each(|v| v[0] = 1.0);
    let law = Arc::new(Elastic::new(1e4, 0.3).unwrap());
    let model =
        Model::new(grid, BasisKind::Gimp, Kinematics::FiniteStrain, points, vec![law], vec![], SVector::zeros())
            .unwrap()
            .with_body_contact(0.0)
            .unwrap();
    let musl = ExplicitSettings::new(0.5);
    assert!(matches!(Explicit::new(model.clone(), musl).err(), Some(ExplicitError::ContactScheme(UpdateScheme::Musl))));
    let (p0, mut energy) = (model.points().momentum(), LeapfrogEnergy::new(UpdateScheme::Usl, &model));
    let e0 = energy.advance(&model);
    let cfl = TimeStep::Cfl { safety: 0.5 };
    let settings = ExplicitSettings { time_step: cfl, scheme: UpdateScheme::Usl, ..ExplicitSettings::new(0.5) };
    let mut ex = Explicit::new(model, settings).unwrap();
    let mut highest = e0;
    while !ex.is_finished() {
        ex.step().unwrap();
        highest = highest.max(energy.advance(ex.model()));
    }
    let pts = ex.model().points();
    let body_velocity = |b: u32| {
        let (q, m) = (0..pts.len())
            .filter(|&p| pts.body()[p] == b)
            .fold((0.0, 0.0), |(q, m), p| (q + pts.velocity()[p][0] * pts.mass()[p], m + pts.mass()[p]));
        q / m
    };
    ((pts.momentum() - p0).norm() / p0.norm(), highest / e0, [body_velocity(0), body_velocity(1)])
}

/// The block of the slab test sliding into a rough wall (μ 0.2) 0.3 m ahead of it, with
/// local damping 0.1, so that at the nodes where the block meets both the slab and the wall
/// contact between bodies, the plane and damping act together (the plane on the velocity
/// contact settled): one and two threads give bitwise identical states (every transfer and
/// each plane's force sum in a fixed order), and no point of the block is more than half a
/// cell (0.05 m) past the wall (its front stops 0.11 m short: contact acts from a cell
/// before the points meet), and the wall pushes the block back up the slope.
#[test]
fn contact_against_a_wall_is_the_same_on_one_or_two_threads() {
    let block = SlidingBlock { slope_deg: 30.0, friction: 0.3, inclined: false };
    let wall = FrictionalPlane::new(Vector2::new(1.4, 0.0), Vector2::new(-1.0, 0.0), 0.2).unwrap();
    let model = block.model_on_slab(0.6).with_frictional_planes(vec![wall]).unwrap();
    let cfl = TimeStep::Cfl { safety: 0.5 };
    let settings =
        ExplicitSettings { time_step: cfl, damping: 0.1, scheme: UpdateScheme::Usl, ..ExplicitSettings::new(0.8) };
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut ex = Explicit::new(model.clone(), settings.clone()).unwrap();
            let mut pushed = 0.0f64;
            while !ex.is_finished() {
                pushed = pushed.min(ex.step().unwrap().plane_forces[0][0]);
            }
            (ex.into_model(), pushed)
        })
    };
    let ((one, pushed), (two, _)) = (run(1), run(2));
    assert_same_state(&one, &two);
    let pts = one.points();
    let past =
        (0..pts.len()).filter(|&p| pts.body()[p] == 1).map(|p| pts.position()[p].x - 1.4).fold(f64::MIN, f64::max);
    println!("the block's front {past} m past the wall; the wall's largest push {pushed} kN/m");
    assert!(past < 0.05, "{past} m past the wall");
    assert!(pushed < 0.0, "the wall pushes the block back: {pushed}");
}

/// A block dropped at rest onto a level conveyor belt, a rigid slab moving at 1 m/s with
/// μ = 0.3 against it: friction drives the block at μ g = 3 m/s² (Coulomb, the block
/// slipping) until it moves with the belt at t = 1/3 s, then carries it along (stick). The
/// fitted acceleration over 0.05–0.25 s within 1 % of μ g, the block's speed at 0.6 s
/// within 1 % of the belt's, and the belt's force on the block while it slips μ times its
/// normal force within 1 % (the bound; measured −0.6 %, +0.003 % and −0.3 %). The
/// contact normal is the rigid body's: once the belt's trailing end has slid under the
/// block, the block's own corner normal there took the slip for an approach and threw the
/// block forward at 1.3 m/s.
#[test]
fn a_conveyor_belt_drags_a_block_by_friction_until_it_rides_along() {
    let block = SlidingBlock { slope_deg: 0.0, friction: 0.3, inclined: false };
    let model = block.model_on_belt(1.0, 0.6);
    let settings = ExplicitSettings {
        time_step: TimeStep::Cfl { safety: 0.5 },
        scheme: UpdateScheme::Usl,
        ..ExplicitSettings::new(0.6)
    };
    let mut ex = Explicit::new(model, settings).unwrap();
    let (mut times, mut speeds, (mut normal, mut tangential)) = (Vec::new(), Vec::new(), (0.0, 0.0));
    let along = Vector2::new(1.0, 0.0);
    while !ex.is_finished() {
        let r = ex.step().unwrap();
        if (0.05..=0.25).contains(&r.time) {
            times.push(r.time);
            speeds.push(block_speed(ex.model(), &along));
            tangential += r.rigid_forces[0][0] * r.dt;
            normal += r.rigid_forces[0][1] * r.dt;
        }
    }
    let (a, v) = (fitted_slope(&times, &speeds), block_speed(ex.model(), &along));
    let ratio = tangential / normal;
    println!("a = {a} (μ g = 3), speed at the end {v} (belt 1), force ratio {ratio} (μ = 0.3)");
    assert!((a / 3.0 - 1.0).abs() < 0.01, "a = {a}");
    assert!((v - 1.0).abs() < 0.01, "speed {v}");
    assert!((ratio / 0.3 - 1.0).abs() < 0.01, "force ratio {ratio}");
}

/// Every kind of contact at once on a grid of more nodes than one block of the rigid
/// force's sums (4096): a rigid belt (body 0) moving at 0.5 m/s along x under two elastic
/// blocks stacked on each other (bodies 1 and 2, `body_contact` μ 0.3 between them, μ 0.4
/// against the belt), dragged into a frictional wall (μ 0.2) 0.2 m ahead, with local
/// damping 0.1. One and two threads give bitwise identical states and rigid forces (every
/// sum in a fixed order); the belt drags the material forward (a force along +x on it,
/// summed over the run), the blocks reach the wall, which pushes back, and no point of
/// either block is more than half a cell (0.025 m) past it.
#[test]
fn a_rigid_belt_bodies_in_contact_and_a_wall_are_the_same_on_one_or_two_threads() {
    let h = 0.05;
    let grid = Grid::new(Vector2::zeros(), Vector2::repeat(h), [80, 60]).unwrap();
    assert!(grid.num_nodes() > 4096);
    let mut points = PointStore::new();
    let mut fill = |min: [f64; 2], max: [f64; 2], body: u32| {
        let first = points.len();
        let shape = Shape::Box { min: Vector2::from(min), max: Vector2::from(max) };
        points.fill(&grid, &shape, 2, 2.0, 0).unwrap();
        points.assign_body(first..points.len(), body);
        first..points.len()
    };
    let belt = fill([0.0, 0.0], [3.5, 0.2], 0);
    fill([0.5, 0.2], [1.0, 0.45], 1);
    fill([0.55, 0.45], [0.95, 0.7], 2);
    points.velocity_mut()[belt].iter_mut().for_each(|v| *v = Vector2::new(0.5, 0.0));
    let law = Arc::new(Elastic::new(1e4, 0.3).unwrap());
    let gravity = Vector2::new(0.0, -10.0);
    let model = Model::new(grid, BasisKind::Gimp, Kinematics::FiniteStrain, points, vec![law], vec![], gravity)
        .unwrap()
        .with_frictional_planes(vec![
            FrictionalPlane::new(Vector2::new(1.2, 0.0), Vector2::new(-1.0, 0.0), 0.2).unwrap()
        ])
        .unwrap()
        .with_body_contact(0.3)
        .unwrap()
        .with_rigid_bodies(vec![RigidBody::new(0, Vector2::new(0.5, 0.0), 0.4).unwrap()])
        .unwrap();
    let cfl = TimeStep::Cfl { safety: 0.5 };
    let settings =
        ExplicitSettings { time_step: cfl, damping: 0.1, scheme: UpdateScheme::Usl, ..ExplicitSettings::new(0.5) };
    let run = |threads| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let mut ex = Explicit::new(model.clone(), settings.clone()).unwrap();
            let mut forces = Vec::new();
            while !ex.is_finished() {
                let r = ex.step().unwrap();
                forces.push((r.rigid_forces[0], r.plane_forces[0], r.dt));
            }
            (ex.into_model(), forces)
        })
    };
    let ((one, forces), (two, forces_two)) = (run(1), run(2));
    assert_same_state(&one, &two);
    assert_eq!(forces, forces_two);
    let impulse: f64 = forces.iter().map(|(f, _, dt)| f[0] * dt).sum();
    let pushed = forces.iter().map(|(_, w, _)| w[0]).fold(0.0, f64::min);
    let pts = one.points();
    let past =
        (0..pts.len()).filter(|&p| pts.body()[p] > 0).map(|p| pts.position()[p].x - 1.2).fold(f64::MIN, f64::max);
    println!("the belt's impulse on the blocks along x {impulse} kN s/m; their front {past} m past the wall; the wall's largest push {pushed} kN/m");
    assert!(impulse > 0.0, "the belt drags the blocks forward: {impulse}");
    assert!(pushed < 0.0, "the blocks reach the wall, which pushes them back: {pushed}");
    assert!(past < 0.025, "{past} m past the wall");
}
