//! V9, a block on a frictional incline (docs/verification.md §V9): explicit and implicit
//! dynamic runs of `loam_verification::sliding` against the rigid block's a = g (sin θ − μ cos θ), the
//! plane's force against Coulomb's cone, and a block that friction holds; V10, a rigid
//! retaining wall against Rankine's active and passive thrust (`loam_verification::wall`).

use crate::report::{Report, Row};
use anyhow::Result;
use loam::explicit::{Explicit, ExplicitSettings, TimeStep, UpdateScheme};
use loam::implicit::{Dynamic, DynamicSettings};
use loam::model::Model;
use loam_verification::sliding::{block_displacement, block_speed, bounds, fitted_slope, SlidingBlock};
use loam_verification::wall::{self, WallMove, SETTLE};
use nalgebra::SVector;
use std::fmt::Write as _;
use std::time::Instant;

/// How a case poses the slope.
#[derive(Clone, Copy, PartialEq)]
enum Posed {
    /// On a rigid frictional plane, in 2D.
    Plane,
    /// On a rigid frictional plane, in 3D.
    Plane3d,
    /// On an elastic slab, the contact between the two bodies.
    Slab,
    /// On a rigid slab moved at this speed down the slope (a rigid body).
    Belt(f64),
}

/// One case: the block, how it is posed, how long it runs, its local damping, and
/// whether it runs in implicit dynamics instead of explicit MPM.
struct Case {
    name: &'static str,
    block: SlidingBlock,
    posed: Posed,
    duration: f64,
    damping: f64,
    implicit: bool,
}

/// The implicit cases' time step: about six steps a period of the block's ringing
/// (40 Hz), which Bossak's α = −0.3 damps; the sliding itself, a constant acceleration,
/// the Newmark family integrates exactly.
const IMPLICIT_STEP: f64 = 0.004;

/// What a run measured: the fitted acceleration down the slope, the plane's mean
/// tangential over normal force, the mean displacement down the slope, steps and wall time.
struct Measured {
    acceleration: f64,
    force_ratio: f64,
    displacement: f64,
    steps: usize,
    wall: f64,
}

/// Run `model` for the case, sampling the centre of mass's velocity along `downhill`; the
/// first fifth of the run (the block settling onto the plane) is left out of the fits.
fn run<const D: usize>(case: &Case, model: Model<D>, downhill: SVector<f64, D>) -> Result<Measured> {
    if case.implicit {
        return run_implicit(case, model, downhill);
    }
    // Bodies in contact take their stress from the contact-corrected grid velocities (USL).
    let scheme =
        if matches!(case.posed, Posed::Slab | Posed::Belt(_)) { UpdateScheme::Usl } else { UpdateScheme::Musl };
    let settings = ExplicitSettings {
        time_step: TimeStep::Cfl { safety: 0.5 },
        damping: case.damping,
        scheme,
        ..ExplicitSettings::new(case.duration)
    };
    let start = Instant::now();
    let mut ex = Explicit::new(model, settings)?;
    let (mut times, mut speeds) = (Vec::new(), Vec::new());
    let (mut normal, mut tangential) = (0.0, 0.0);
    let mut steps = 0;
    while !ex.is_finished() {
        let r = ex.step()?;
        steps = r.step;
        if r.time < 0.2 * case.duration {
            continue;
        }
        times.push(r.time);
        speeds.push(block_speed(ex.model(), &downhill));
        let Some(force) = r.plane_forces.first().or(r.rigid_forces.first()) else { continue };
        let (n, t) = normal_and_tangential(force, &downhill);
        normal += n * r.dt;
        tangential += t * r.dt;
    }
    Ok(Measured {
        acceleration: fitted_slope(&times, &speeds),
        force_ratio: tangential / normal,
        displacement: block_displacement(ex.model(), &downhill),
        steps,
        wall: start.elapsed().as_secs_f64(),
    })
}

/// The sizes of a plane's `force` (D components used) across and along `downhill`.
fn normal_and_tangential<const D: usize>(force: &[f64; 3], downhill: &SVector<f64, D>) -> (f64, f64) {
    let f = SVector::<f64, D>::from_fn(|i, _| force[i]);
    let along = f.dot(downhill) * downhill;
    ((f - along).norm(), along.norm())
}

/// [`run`] in implicit dynamics: Bossak's α = −0.3 (β and γ from it), Δt =
/// `IMPLICIT_STEP`, the plane's force its reaction at each step's end.
fn run_implicit<const D: usize>(case: &Case, model: Model<D>, downhill: SVector<f64, D>) -> Result<Measured> {
    let alpha = -0.3;
    let settings = DynamicSettings {
        bossak_alpha: alpha,
        beta: 0.25 * (1.0 - alpha) * (1.0 - alpha),
        gamma: 0.5 - alpha,
        ..DynamicSettings::trapezoidal(IMPLICIT_STEP, case.duration)
    };
    let start = Instant::now();
    let mut dynamic = Dynamic::new(model, settings)?;
    let (mut times, mut speeds) = (Vec::new(), Vec::new());
    let (mut normal, mut tangential, mut steps) = (0.0, 0.0, 0);
    while !dynamic.is_finished() {
        let r = dynamic.step()?;
        steps = r.step;
        if r.time < 0.2 * case.duration {
            continue;
        }
        times.push(r.time);
        speeds.push(block_speed(dynamic.model(), &downhill));
        // The plane is the model's only support: its reaction comes first.
        let (n, t) = normal_and_tangential(&r.reactions[0], &downhill);
        normal += n;
        tangential += t;
    }
    Ok(Measured {
        acceleration: fitted_slope(&times, &speeds),
        force_ratio: tangential / normal,
        displacement: block_displacement(dynamic.model(), &downhill),
        steps,
        wall: start.elapsed().as_secs_f64(),
    })
}

pub fn verify(_quick: bool, report: &mut Report) -> Result<()> {
    let slide = |friction, inclined| SlidingBlock { slope_deg: 30.0, friction, inclined };
    let level = |friction| SlidingBlock { slope_deg: 0.0, friction, inclined: false };
    let case = |name, block, posed, duration, damping| Case { name, block, posed, duration, damping, implicit: false };
    let implicit = |name, block, posed, duration| Case { name, block, posed, duration, damping: 0.0, implicit: true };
    let cases = [
        case("level base, gravity turned", slide(0.3, false), Posed::Plane, 1.0, 0.0),
        case("level base, smooth", slide(0.0, false), Posed::Plane, 0.6, 0.0),
        case("inclined plane", slide(0.3, true), Posed::Plane, 1.0, 0.0),
        case("level base, 3D, slip along x = z", slide(0.3, false), Posed::Plane3d, 0.5, 0.0),
        case("level base, stuck (damping 0.5)", slide(0.7, false), Posed::Plane, 1.0, 0.5),
        case("elastic slab, two bodies", slide(0.3, false), Posed::Slab, 1.0, 0.0),
        case("elastic slab, two bodies, smooth", slide(0.0, false), Posed::Slab, 0.6, 0.0),
        case("elastic slab, two bodies, stuck (damping 0.5)", slide(0.7, false), Posed::Slab, 1.0, 0.5),
        case("rigid slab (a rigid body)", slide(0.3, false), Posed::Belt(0.0), 1.0, 0.0),
        case("conveyor belt at 1 m/s, level", level(0.3), Posed::Belt(1.0), 0.3, 0.0),
        implicit("level base, gravity turned, implicit dynamics", slide(0.3, false), Posed::Plane, 1.0),
        implicit("inclined plane, implicit dynamics", slide(0.3, true), Posed::Plane, 1.0),
        implicit("level base, 3D, slip along x = z, implicit dynamics", slide(0.3, false), Posed::Plane3d, 0.5),
    ];
    writeln!(report.md, "## V9 block on a frictional incline\n\nAn elastic block (1 × 0.5 m, 0.4 m deep in 3D; ρ = 2 t/m³, E = 10 MPa, ν = 0.3) released unstressed on a rigid frictional plane (`frictional_planes`), or on an elastic slab of the same soil 0.3 m thick held at its base, the two bodies in contact (`body_contact`), or on a rigid slab 0.3 m thick and as long as the block travels (`rigid_bodies`, at rest or moved at 1 m/s on a level base: a conveyor belt that drags the block at g (sin θ + μ cos θ) until it rides along), θ = 30°, g = 10 m/s², cells of 0.1 m, 2 points a cell per axis, GIMP, finite strain, explicit MUSL (USL for the two bodies, as contact needs), CFL 0.5. Acceleration: the least-squares slope of the centre of mass's velocity down the slope after the first fifth of the run; force ratio: the plane's time-averaged tangential over normal force over the same window. References: a = g (sin θ − μ cos θ), the ratio μ while sliding (the plane's or the rigid body's force); a block with tan θ < μ stays put (its mean displacement over the frictionless block's travel ½ g sin θ t²).\n")?;
    report.mark_table("sliding")?;
    writeln!(report.md, "| case | μ | steps | a [m/s²] | reference | a / ref − 1 | force ratio / μ − 1 | displacement / free travel |\n|---|---:|---:|---:|---:|---:|---:|---:|")?;
    for case in &cases {
        let b = case.block;
        let travel = 0.5 * b.acceleration() * case.duration.powi(2) + 0.1;
        let m = match case.posed {
            Posed::Plane3d => {
                let d = std::f64::consts::FRAC_1_SQRT_2;
                run(case, b.model_3d(travel), nalgebra::Vector3::new(d, 0.0, d))?
            }
            Posed::Plane => run(case, b.model(travel), b.downhill())?,
            Posed::Slab => run(case, b.model_on_slab(travel), b.downhill())?,
            Posed::Belt(speed) => run(case, b.model_on_belt(speed, case.duration), b.downhill())?,
        };
        // A faster belt drags the block (until it rides along, after the run).
        let dragged = matches!(case.posed, Posed::Belt(speed) if speed > 0.0);
        let reference = if dragged { b.dragged_acceleration() } else { b.acceleration() };
        let label = format!("V9 {} mu {}", case.name, b.friction);
        let free_travel = 0.5 * 10.0 * b.slope_deg.to_radians().sin() * case.duration.powi(2);
        let stuck = m.displacement / free_travel;
        let (error, ratio) = if reference > 0.0 {
            let on_plane = b.friction > 0.0 && case.posed != Posed::Slab;
            let ratio = if on_plane { m.force_ratio / b.friction - 1.0 } else { f64::NAN };
            (m.acceleration / reference - 1.0, ratio)
        } else {
            (f64::NAN, f64::NAN)
        };
        writeln!(
            report.md,
            "| {} | {} | {} | {:.4} | {reference:.4} | {} | {} | {} |",
            case.name,
            b.friction,
            m.steps,
            m.acceleration,
            signed(error),
            signed(ratio),
            if reference > 0.0 { "—".to_string() } else { format!("{stuck:.1e}") }
        )?;
        if reference > 0.0 {
            report.rows.push(Row::checked(&label, "acceleration_error", error.abs(), bounds::SLIDING_ACCELERATION));
            if !ratio.is_nan() {
                report.rows.push(Row::checked(&label, "coulomb_ratio_error", ratio.abs(), bounds::COULOMB_RATIO));
            }
        } else {
            report.rows.push(Row::checked(
                &label,
                "displacement_over_free_travel",
                stuck.abs(),
                bounds::STUCK_DISPLACEMENT,
            ));
        }
        report.rows.push(Row::info(&label, "wall_time_s", m.wall));
    }
    writeln!(report.md)?;
    verify_wall(report)
}

/// V10: the wall's force on the backfill at rest (the settling's last fifth) and at the
/// end of each move (its last fifth), against Rankine's thrust.
fn verify_wall(report: &mut Report) -> Result<()> {
    writeln!(report.md, "## V10 retaining wall, active and passive\n\nA smooth rigid wall (`rigid_bodies`) 2.2 m tall holds a cohesionless Mohr–Coulomb backfill (φ = 30°, ψ = 0, E = 20 MPa, ν = 0.3, γ = 20 kN/m³) 2 m high and 4 m long on a smooth base, a roller at the far end; 0.1 m cells, 2 × 2 points a cell, GIMP, explicit USL, CFL 0.5, local damping 0.2. The sand settles for 0.8 s with the wall held, then the wall moves at 2 cm/s away from it by 1.5 cm or towards it by 3 cm. References: ½ K γ H² with K_0 = ν / (1 − ν) at rest, Rankine's K_a = (1 − sin φ) / (1 + sin φ) and K_p = 1 / K_a after the move.\n")?;
    report.mark_table("wall")?;
    writeln!(report.md, "| case | steps | wall moved [m] | force at rest [kN/m] | ½ K_0 γ H² | at rest / ref − 1 | force after the move [kN/m] | ½ K γ H² | after / ref − 1 |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    for (name, moved) in [("active", WallMove::ACTIVE), ("passive", WallMove::PASSIVE)] {
        let start = Instant::now();
        let settings = ExplicitSettings {
            time_step: TimeStep::Cfl { safety: 0.5 },
            scheme: UpdateScheme::Usl,
            damping: wall::DAMPING,
            ..ExplicitSettings::new(moved.duration())
        };
        let mut ex = Explicit::new(moved.model(), settings)?;
        let (mut rest, mut after, mut steps) = ((0.0, 0.0), (0.0, 0.0), 0);
        while !ex.is_finished() {
            let r = ex.step()?;
            steps = r.step;
            let force = r.rigid_forces[0][0] * r.dt;
            if (0.8 * SETTLE..SETTLE).contains(&r.time) {
                rest = (rest.0 + force, rest.1 + r.dt);
            } else if r.time > moved.duration() - 0.2 * moved.moving {
                after = (after.0 + force, after.1 + r.dt);
            }
        }
        let (at_rest, thrust) = (rest.0 / rest.1, after.0 / after.1);
        let (rest_ref, thrust_ref) = (WallMove::thrust(WallMove::at_rest()), WallMove::thrust(moved.rankine()));
        let (rest_error, error) = (at_rest / rest_ref - 1.0, thrust / thrust_ref - 1.0);
        let label = format!("V10 retaining wall, {name}");
        writeln!(
            report.md,
            "| {name} | {steps} | {:.3} | {at_rest:.2} | {rest_ref:.2} | {} | {thrust:.2} | {thrust_ref:.2} | {} |",
            moved.speed * moved.moving,
            signed(rest_error),
            signed(error)
        )?;
        report.rows.push(Row::checked(&label, "at_rest_error", rest_error.abs(), wall::bounds::AT_REST_THRUST));
        report.rows.push(Row::checked(&label, "rankine_error", error.abs(), wall::bounds::RANKINE_THRUST));
        report.rows.push(Row::info(&label, "wall_time_s", start.elapsed().as_secs_f64()));
    }
    writeln!(report.md)?;
    Ok(())
}

/// A relative difference as the table prints it (— where there is none).
fn signed(x: f64) -> String {
    if x.is_nan() {
        "—".into()
    } else {
        format!("{x:+.1e}")
    }
}
