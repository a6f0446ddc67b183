//! Frictional planes in explicit runs (docs/verification.md §V9): a block slides down a
//! frictional incline at the rigid block's rate and stays on one steeper than its angle
//! of friction. `cargo xtask verify` runs the longer cases; these are shortened to 0.6 s.

use loam_explicit::{Explicit, ExplicitSettings, TimeStep};
use loam_verification::sliding::{fitted_slope, SlidingBlock};

const DURATION: f64 = 0.6;

/// Run `block` (2D) for `DURATION` with local damping `damping`: the fitted acceleration
/// of the centre of mass down the slope after 0.1 s, and the mean displacement down it.
fn slide(block: SlidingBlock, damping: f64) -> (f64, f64) {
    let travel = 0.5 * block.acceleration() * DURATION * DURATION + 0.1;
    let settings =
        ExplicitSettings { time_step: TimeStep::Cfl { safety: 0.5 }, damping, ..ExplicitSettings::new(DURATION) };
    let mut ex = Explicit::new(block.model(travel), settings).unwrap();
    let (mut times, mut speeds) = (Vec::new(), Vec::new());
    let downhill = block.downhill();
    while !ex.is_finished() {
        let r = ex.step().unwrap();
        let pts = ex.model().points();
        if r.time >= 0.1 {
            times.push(r.time);
            speeds.push(pts.momentum().dot(&downhill) / pts.total_mass());
        }
    }
    let pts = ex.model().points();
    let moved: f64 = pts.position().iter().zip(pts.position0()).map(|(x, x0)| (x - x0).dot(&downhill)).sum();
    (fitted_slope(&times, &speeds), moved / pts.len() as f64)
}

/// θ = 30°, μ = 0.3 on an inclined plane that cuts the cells: a = g (sin θ − μ cos θ)
/// within 1 % (the bound; the verification case measures 1e-4 over 1 s).
#[test]
fn a_block_slides_down_a_frictional_incline_at_the_rigid_rate() {
    let block = SlidingBlock { slope_deg: 30.0, friction: 0.3, inclined: true };
    let (a, _) = slide(block, 0.0);
    println!("a = {a}, rigid block {}", block.acceleration());
    assert!((a / block.acceleration() - 1.0).abs() < 0.01, "a = {a}");
}

/// θ = 30°, μ = 0.7 > tan θ on a level base with gravity turned: with local damping to stop
/// the released block's bouncing (which would ratchet it down), it moves by its elastic
/// shear alone, below 1e-3 of the frictionless block's travel ½ g sin θ t² (measured
/// 5e-4). The planes act on the undamped trial velocity: damping a node in contact would
/// change the normal force that its friction is taken from, and the block would creep.
#[test]
fn friction_holds_a_block_on_a_slope_below_its_angle() {
    let block = SlidingBlock { slope_deg: 30.0, friction: 0.7, inclined: false };
    let (_, moved) = slide(block, 0.5);
    let free = 0.5 * 10.0 * 0.5 * DURATION * DURATION;
    println!("moved {moved} m, frictionless {free} m");
    assert!(moved.abs() < 1e-3 * free, "moved {moved}");
}
