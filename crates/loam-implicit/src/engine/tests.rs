//! The engine's residual and tangent are consistent: the assembled tangent is the exact
//! derivative of the residual, which is what makes Newton quadratic.

use super::*;
use crate::{AntiLocking, PlaneConstraint, QuasiStatic, QuasiStaticSettings};
use loam_constitutive::{ConstitutiveLaw, Elastic, MohrCoulomb, VonMises};
use loam_grid::{BasisKind, Grid};
use loam_model::Kinematics;
use loam_points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

/// A 2×2-cell block on a 5×5 grid, pre-loaded by gravity to a stressed state. With a
/// ghost penalty the block is shifted along x, so that it cuts cells;
/// `axisymmetric`, it is a ring of radii 1 to 3 about the grid's x = 0 axis.
fn stressed_block_with(
    kinematics: Kinematics,
    basis: BasisKind,
    anti_locking: AntiLocking,
    ghost: Option<f64>,
    law: Arc<dyn ConstitutiveLaw>,
    axisymmetric: bool,
) -> Model<2> {
    let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [5, 5]).unwrap();
    let mut points = PointStore::new();
    // An axisymmetric model starts unmoved: its cut block is filled from a shifted box
    // (points at x = 1.75 … 3.25, half-filled cells at either side).
    let left = if ghost.is_some() && axisymmetric { 1.3 } else { 1.0 };
    let shape = Shape::Box { min: Vector2::new(left, 0.0), max: Vector2::new(left + 2.0, 2.0) };
    points.fill(&grid, &shape, 2, 1000.0, 0).unwrap();
    if ghost.is_some() && !axisymmetric {
        points.position_mut().iter_mut().for_each(|x| x[0] += 0.3);
    }
    let fixed = PlaneConstraint::new(1, 0, [true, true, false]);
    // A sideways pull shears the plane block; a body of revolution's gravity is axial.
    let gravity = if axisymmetric { Vector2::new(0.0, -10.0) } else { Vector2::new(3.0, -10.0) };
    let mut model = Model::new(grid, basis, kinematics, points, vec![law], vec![fixed], gravity).unwrap();
    if axisymmetric {
        model = model.with_axisymmetry().unwrap();
    }
    let mut model = model.with_anti_locking(anti_locking).unwrap();
    if let Some(gamma) = ghost {
        model = model.with_ghost_penalty(gamma).unwrap();
    }
    let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps: 2, ..Default::default() });
    qs.step().unwrap();
    qs.step().unwrap();
    qs.into_model()
}

/// Deterministic pseudo-random numbers in [-1, 1) (64-bit LCG, Knuth's constants).
fn noise(n: usize, seed: u64) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        })
        .collect()
}

/// The residual (internal force, with f_ext = 0 and no dof constrained) at `du`.
fn residual_at<const D: usize>(engine: &mut Engine<D>, du: &[f64]) -> Vec<f64> {
    engine.du.copy_from_slice(du);
    engine.update_points_and_residual(None).unwrap();
    engine.residual().to_vec()
}

/// The Euclidean norm.
fn norm(x: &[f64]) -> f64 {
    x.iter().map(|k| k * k).sum::<f64>().sqrt()
}

/// Assemble K at `du` and check K v against the central difference of the residual along
/// `v` (step 1e-7, relative tolerance 1e-6 as below); returns K v.
fn assert_tangent_matches_differences<const D: usize>(engine: &mut Engine<D>, du: &[f64], v: &[f64]) -> Vec<f64> {
    let eps = 1e-7;
    let plus: Vec<f64> = du.iter().zip(v).map(|(a, b)| a + eps * b).collect();
    let minus: Vec<f64> = du.iter().zip(v).map(|(a, b)| a - eps * b).collect();
    let (rp, rm) = (residual_at(engine, &plus), residual_at(engine, &minus));
    residual_at(engine, du);
    engine.assemble(None);
    let mut kv = vec![0.0; du.len()];
    engine.matrix.mul_vec(&engine.pattern, v, &mut kv);
    let diff: Vec<f64> = kv.iter().zip(rp.iter().zip(&rm)).map(|(k, (p, m))| k - (p - m) / (2.0 * eps)).collect();
    assert!(norm(&diff) <= 1e-6 * norm(&kv), "|Kv − FD| / |Kv| = {:e}", norm(&diff) / norm(&kv));
    kv
}

/// K v equals the central difference of the residual along v, on a stressed state and
/// a finite increment. Relative tolerance 1e-6: central differences with step 1e-7 on a
/// residual of magnitude ~1e3 carry truncation ~1e-10 and rounding ~1e-9 relative.
/// The plastic cases (von Mises σ_y = 2.4e4, associated Mohr–Coulomb c = 8e3, φ = 30°,
/// strong enough to carry the gravity preload) take a simple shear of 0.2 and nodal
/// noise of up to 20 % of a cell, so that points return to the yield surface in it,
/// and check that some do.
#[test]
fn assembled_tangent_is_the_derivative_of_the_residual() {
    let elastic = Elastic::new(1e5, 0.3).unwrap();
    let linear: Arc<dyn ConstitutiveLaw> = Arc::new(elastic);
    let von_mises: Arc<dyn ConstitutiveLaw> = Arc::new(VonMises::new(elastic, 2.4e4, 0.0).unwrap());
    let mohr_coulomb: Arc<dyn ConstitutiveLaw> = Arc::new(MohrCoulomb::from_degrees(elastic, 8e3, 30.0, 30.0).unwrap());
    let assumed = AntiLocking::AssumedStrain { stabilization: 0.2 };
    let cases = [
        (Kinematics::FiniteStrain, BasisKind::Gimp, AntiLocking::None, None, &linear, false),
        (Kinematics::SmallStrain, BasisKind::Gimp, AntiLocking::None, None, &linear, false),
        (Kinematics::SmallStrain, BasisKind::Linear, AntiLocking::BBar, None, &linear, false),
        (Kinematics::SmallStrain, BasisKind::Linear, assumed, None, &linear, false),
        (Kinematics::SmallStrain, BasisKind::Linear, AntiLocking::BBar, None, &von_mises, false),
        (Kinematics::SmallStrain, BasisKind::Linear, assumed, None, &von_mises, false),
        (Kinematics::SmallStrain, BasisKind::Linear, assumed, None, &mohr_coulomb, false),
        (Kinematics::FiniteStrain, BasisKind::Gimp, AntiLocking::None, Some(1.0), &linear, false),
        // Axisymmetric (docs/theory.md §20): the hoop rows and B-bar's hoop dilatation.
        (Kinematics::FiniteStrain, BasisKind::Gimp, AntiLocking::None, None, &linear, true),
        (Kinematics::SmallStrain, BasisKind::Gimp, AntiLocking::None, None, &mohr_coulomb, true),
        (Kinematics::SmallStrain, BasisKind::Linear, AntiLocking::BBar, None, &linear, true),
        (Kinematics::SmallStrain, BasisKind::Linear, AntiLocking::BBar, None, &von_mises, true),
        (Kinematics::FiniteStrain, BasisKind::Gimp, AntiLocking::None, None, &von_mises, true),
        (Kinematics::FiniteStrain, BasisKind::Gimp, AntiLocking::None, Some(1.0), &linear, true),
        // F-bar (finite strain): plane strain's square root and the ring's cube root.
        (Kinematics::FiniteStrain, BasisKind::Linear, AntiLocking::FBar, None, &linear, false),
        (Kinematics::FiniteStrain, BasisKind::Linear, AntiLocking::FBar, None, &von_mises, false),
        (Kinematics::FiniteStrain, BasisKind::Linear, AntiLocking::FBar, None, &mohr_coulomb, false),
        (Kinematics::FiniteStrain, BasisKind::Linear, AntiLocking::FBar, None, &linear, true),
        (Kinematics::FiniteStrain, BasisKind::Linear, AntiLocking::FBar, None, &von_mises, true),
    ];
    for (kinematics, basis, anti_locking, ghost, law, axisymmetric) in cases {
        let plastic = !Arc::ptr_eq(law, &linear);
        let model = stressed_block_with(kinematics, basis, anti_locking, ghost, law.clone(), axisymmetric);
        let mut engine = Engine::new(model, NewtonSettings::default(), loam_solve::LinearSolverChoice::Auto, false);
        engine.connect(1).unwrap();
        assert_eq!(engine.ghost.is_empty(), ghost.is_none(), "the shifted block must cut cells");
        // No dof constrained, no external force: the residual is the internal force and
        // every row of the tangent is its derivative.
        engine.constrained.iter_mut().for_each(|c| *c = false);
        let n = engine.num_dofs();
        engine.f_ext = vec![0.0; n];
        engine.size_buffers();
        // A finite increment (up to 2 % of a cell, 20 % for the plastic laws) so that ΔF ≠ I.
        let amplitude = if plastic { 0.2 } else { 0.02 };
        let mut du: Vec<f64> = noise(n, 7).iter().map(|x| amplitude * x).collect();
        if plastic {
            // Plus a simple shear of 0.2, which survives the cell averages.
            for (a, &g) in engine.conn.active_nodes().active_to_grid.iter().enumerate() {
                du[a * 2] += 0.2 * engine.model.grid().node_position(g as usize)[1];
            }
            // At Δu = 0 every point is elastic (the committed state is admissible).
            residual_at(&mut engine, &vec![0.0; n]);
            let elastic_tangents = engine.trial.tangent.clone();
            residual_at(&mut engine, &du);
            let returned = elastic_tangents
                .iter()
                .zip(&engine.trial.tangent)
                .filter(|(e, t)| (*e - *t).norm() > 1e-6 * e.norm())
                .count();
            assert!(returned > 0, "{anti_locking:?}: no point returned to the yield surface");
        }
        let v = noise(n, 11);
        let eps = 1e-7;
        let plus: Vec<f64> = du.iter().zip(&v).map(|(a, b)| a + eps * b).collect();
        let minus: Vec<f64> = du.iter().zip(&v).map(|(a, b)| a - eps * b).collect();
        let rp = residual_at(&mut engine, &plus);
        let rm = residual_at(&mut engine, &minus);
        residual_at(&mut engine, &du);
        engine.assemble(None);
        let mut kv = vec![0.0; n];
        engine.matrix.mul_vec(&engine.pattern, &v, &mut kv);
        let diff: f64 = kv
            .iter()
            .zip(rp.iter().zip(&rm))
            .map(|(k, (p, m))| (k - (p - m) / (2.0 * eps)).powi(2))
            .sum::<f64>()
            .sqrt();
        let scale: f64 = kv.iter().map(|k| k * k).sum::<f64>().sqrt();
        assert!(
            diff <= 1e-6 * scale,
            "{kinematics:?} {anti_locking:?} plastic {plastic} axisymmetric {axisymmetric}: |Kv - FD| / |Kv| = {:e}",
            diff / scale
        );
        if anti_locking == AntiLocking::FBar {
            assert_fbar_terms_matter(&mut engine, &v, &kv);
            continue;
        }
        // Hyperelastic (Hencky), linear elastic and associated tangents are symmetric
        // as a whole (F-bar's is not: its average is on the trial side only).
        let asym = engine.matrix.asymmetry(&engine.pattern);
        assert!(asym < 1e-10, "{kinematics:?} axisymmetric {axisymmetric}: asymmetry {asym:e}");
    }
}

/// F-bar's coupling is what makes the tangent match: assembled without it (the plain
/// finite-strain tangent at the same trial state), K v misses the differences that the
/// full one met to 1e-6 by more than 1e-4 of |K v|, and the full tangent is not
/// symmetric.
fn assert_fbar_terms_matter<const D: usize>(engine: &mut Engine<D>, v: &[f64], kv: &[f64]) {
    assert!(engine.matrix.asymmetry(&engine.pattern) > 1e-6, "F-bar's tangent is not symmetric");
    let inputs = TangentInputs {
        conn: &engine.conn,
        pattern: &engine.pattern,
        average: None,
        ghost: &[],
        constrained: &engine.constrained,
        mass: engine.model.points().mass(),
        water_force: &[],
        axisymmetric: engine.model.axisymmetric(),
        fbar: false,
    };
    assemble(&inputs, &engine.trial, None, &mut engine.matrix);
    let mut plain = vec![0.0; kv.len()];
    engine.matrix.mul_vec(&engine.pattern, v, &mut plain);
    let miss: Vec<f64> = plain.iter().zip(kv).map(|(a, b)| a - b).collect();
    assert!(norm(&miss) > 1e-4 * norm(kv), "F-bar's terms must matter: {:e}", norm(&miss) / norm(kv));
}

/// F-bar in 3D (the cube root of the whole ΔF; eight points a cell): on a 2 × 2 × 2-cell
/// block pre-loaded by gravity and a sideways pull, von Mises points taken past yield by a
/// simple shear and nodal noise, K v equals the central difference of the residual
/// (tolerance as above), and F-bar's coupling matters.
#[test]
fn fbar_tangent_in_3d_is_the_derivative_of_the_residual() {
    use nalgebra::Vector3;
    let grid = Grid::new(Vector3::zeros(), Vector3::new(1.0, 1.0, 1.0), [4, 4, 4]).unwrap();
    let mut points = PointStore::new();
    let block = Shape::Box { min: Vector3::new(1.0, 1.0, 0.0), max: Vector3::new(3.0, 3.0, 2.0) };
    points.fill(&grid, &block, 2, 1000.0, 0).unwrap();
    let law: Arc<dyn ConstitutiveLaw> = Arc::new(VonMises::new(Elastic::new(1e5, 0.3).unwrap(), 2.4e4, 0.0).unwrap());
    let fixed = PlaneConstraint::new(2, 0, [true, true, true]);
    let model = Model::new(
        grid,
        BasisKind::Linear,
        Kinematics::FiniteStrain,
        points,
        vec![law],
        vec![fixed],
        Vector3::new(3.0, 0.0, -10.0),
    )
    .and_then(|m| m.with_anti_locking(AntiLocking::FBar))
    .unwrap();
    let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps: 2, ..Default::default() });
    qs.step().unwrap();
    qs.step().unwrap();
    let mut engine =
        Engine::new(qs.into_model(), NewtonSettings::default(), loam_solve::LinearSolverChoice::Auto, false);
    engine.connect(1).unwrap();
    engine.constrained.iter_mut().for_each(|c| *c = false);
    let n = engine.num_dofs();
    engine.f_ext = vec![0.0; n];
    engine.size_buffers();
    let mut du: Vec<f64> = noise(n, 23).iter().map(|x| 0.2 * x).collect();
    for (a, &g) in engine.conn.active_nodes().active_to_grid.iter().enumerate() {
        du[a * 3] += 0.2 * engine.model.grid().node_position(g as usize)[2];
    }
    residual_at(&mut engine, &vec![0.0; n]);
    let elastic_tangents = engine.trial.tangent.clone();
    residual_at(&mut engine, &du);
    let returned =
        elastic_tangents.iter().zip(&engine.trial.tangent).filter(|(e, t)| (*e - *t).norm() > 1e-6 * e.norm()).count();
    assert!(returned > 0, "no point returned to the yield surface");
    let v = noise(n, 29);
    let kv = assert_tangent_matches_differences(&mut engine, &du, &v);
    assert_fbar_terms_matter(&mut engine, &v, &kv);
}

/// A follower pressure's load stiffness: on the stressed block in finite strain with a
/// follower pressure on its top and right faces (p = 5e3, 5 % of E, so the load term is
/// a sizeable part of the tangent), K v equals the central difference of the residual
/// along v at a finite increment; the tangent is not symmetric, and without the load
/// stiffness it would not match (the check has teeth). On the ring (axisymmetric) the
/// faces are rings whose area grows with the radius: the share's derivative is checked
/// too. Tolerance as above.
#[test]
fn follower_pressure_tangent_is_the_derivative_of_the_residual() {
    for axisymmetric in [false, true] {
        for (kinematics, basis, anti_locking) in [
            (Kinematics::FiniteStrain, BasisKind::Gimp, AntiLocking::None),
            (Kinematics::SmallStrain, BasisKind::Linear, AntiLocking::BBar),
            (Kinematics::SmallStrain, BasisKind::Linear, AntiLocking::AssumedStrain { stabilization: 0.3 }),
            (Kinematics::FiniteStrain, BasisKind::Linear, AntiLocking::FBar),
        ] {
            // Assumed strain is plane only.
            if !(axisymmetric && matches!(anti_locking, AntiLocking::AssumedStrain { .. })) {
                follower_tangent_matches_differences(kinematics, basis, anti_locking, axisymmetric);
            }
        }
    }
}

fn follower_tangent_matches_differences(
    kinematics: Kinematics,
    basis: BasisKind,
    anti_locking: AntiLocking,
    axisymmetric: bool,
) {
    use loam_model::{Load, LoadLevel, TimeFunction};
    let law: Arc<dyn ConstitutiveLaw> = Arc::new(Elastic::new(1e5, 0.3).unwrap());
    let model = stressed_block_with(kinematics, basis, anti_locking, None, law, axisymmetric);
    let faces = Shape::Box { min: Vector2::new(1.0, 0.0), max: Vector2::new(3.0, 2.0) }
        .boundary(0.25)
        .unwrap()
        .select(|c| c[1] > 1.99 || c[0] > 2.99);
    let n_vertices = faces.vertices.len();
    let pressure = Load::pressure(faces, vec![5e3; n_vertices], true, TimeFunction::Constant).unwrap();
    let model = model.with_loads(vec![pressure]).unwrap();
    let mut engine = Engine::new(model, NewtonSettings::default(), loam_solve::LinearSolverChoice::Auto, false);
    engine.connect(1).unwrap();
    engine.constrained.iter_mut().for_each(|c| *c = false);
    let n = engine.num_dofs();
    engine.f_ext = vec![0.0; n];
    engine.level = LoadLevel::Factor(1.0);
    engine.size_buffers();
    let du: Vec<f64> = noise(n, 5).iter().map(|x| 0.02 * x).collect();
    let v = noise(n, 13);
    let kv = assert_tangent_matches_differences(&mut engine, &du, &v);
    assert!(engine.matrix.asymmetry(&engine.pattern) > 1e-6, "a follower load's stiffness is not symmetric");
    // Without the load stiffness (the load made dead) the same check fails.
    let load_term: Vec<f64> = {
        let mut dead = loam_solve::SystemMatrix::Columns(vec![0.0; engine.pattern.nnz()]);
        let inputs = crate::follower::FollowerInputs {
            model: &engine.model,
            conn: &engine.conn,
            supports: &engine.loads,
            level: engine.level,
            du: &engine.du,
            delta_f: &engine.trial.delta_f,
            average: crate::cell_average::CellAverage::of(&engine.model, &engine.cell_gradients),
            fbar: engine.fbar().map(|_| &engine.trial),
        };
        crate::follower::add_follower_tangent(&inputs, &engine.pattern, &engine.constrained, &mut dead);
        let mut kv = vec![0.0; n];
        dead.mul_vec(&engine.pattern, &v, &mut kv);
        kv
    };
    assert!(norm(&load_term) > 1e-3 * norm(&kv), "the load stiffness must matter here");
}

/// The water's force in finite strain: −∇p_w on each point's current volume (the
/// buoyancy below the level), which changes with the volume, so the tangent needs its
/// term. On the stressed block half under water (level at y = 1, γ_w = 5e3, a body force
/// of half the block's weight), K v equals the central difference of the residual
/// (tolerance as above), on the plane block and on the ring (axisymmetric: the volume
/// changes with the hoop strain too), with F-bar too (the volume follows the cell's), and
/// leaving the water's term out would miss by far more than that.
#[test]
fn water_force_tangent_is_the_derivative_of_the_residual() {
    for axisymmetric in [false, true] {
        for (basis, anti_locking) in [(BasisKind::Gimp, AntiLocking::None), (BasisKind::Linear, AntiLocking::FBar)] {
            water_tangent_matches_differences(basis, anti_locking, axisymmetric);
        }
    }
}

/// The check of [`water_force_tangent_is_the_derivative_of_the_residual`] on the plane
/// block or the ring (whose volume changes with its hoop strain too).
fn water_tangent_matches_differences(basis: BasisKind, anti_locking: AntiLocking, axisymmetric: bool) {
    use loam_model::{PhreaticLevel, Water};
    let law: Arc<dyn ConstitutiveLaw> = Arc::new(Elastic::new(1e5, 0.3).unwrap());
    let model = stressed_block_with(Kinematics::FiniteStrain, basis, anti_locking, None, law, axisymmetric);
    let water = Water::new(5e3, PhreaticLevel::Horizontal(1.0), &Vector2::new(0.0, -10.0)).unwrap();
    let model = model.with_water(water).unwrap();
    let mut engine = Engine::new(model, NewtonSettings::default(), loam_solve::LinearSolverChoice::Auto, false);
    engine.connect(1).unwrap();
    engine.constrained.iter_mut().for_each(|c| *c = false);
    let n = engine.num_dofs();
    engine.f_ext = vec![0.0; n];
    engine.body_factor = 1.0;
    engine.update_water_forces();
    let submerged = engine.water_force.iter().filter(|b| b.norm() > 0.0).count();
    assert!(submerged > 0 && submerged < engine.water_force.len(), "half the block under water");
    engine.size_buffers();
    let du: Vec<f64> = noise(n, 17).iter().map(|x| 0.02 * x).collect();
    let v = noise(n, 19);
    let kv = assert_tangent_matches_differences(&mut engine, &du, &v);
    // The same tangent without the water's term misses.
    let water_force = std::mem::take(&mut engine.water_force);
    engine.assemble(None);
    engine.water_force = water_force;
    let mut kv_dry = vec![0.0; n];
    engine.matrix.mul_vec(&engine.pattern, &v, &mut kv_dry);
    let miss: Vec<f64> = kv_dry.iter().zip(&kv).map(|(a, b)| a - b).collect();
    // 1e-4 of K v is a hundred times what the 1e-6 check resolves.
    assert!(norm(&miss) > 1e-4 * norm(&kv), "the water's term must matter here: {:e}", norm(&miss) / norm(&kv));
}

/// A slipping node's rows are the derivative of its residual (docs/theory.md §5): a block
/// on a frictional plane (μ = 0.3, gravity's tangential part twice what friction holds, so
/// the base nodes slip), moved by a finite increment along the slip; in the nodes' frames,
/// K v equals the central difference of the held-and-frictional residual along v (v zero
/// on the held dofs, which the residual does not see), to 1e-6 of |K v| as above, in 2D
/// and in 3D, where the slip direction turns with the iterate (the μ N (I − s sᵀ)/|Δu_t|
/// block). The states do not change between the differences; the tangent is not symmetric.
#[test]
fn slipping_contact_tangent_is_the_derivative_of_the_residual() {
    slipping_tangent_matches_differences::<2>();
    slipping_tangent_matches_differences::<3>();
}

fn slipping_tangent_matches_differences<const D: usize>() {
    use loam_model::FrictionalPlane;
    use nalgebra::SVector;
    let grid = Grid::new(SVector::<f64, D>::zeros(), SVector::repeat(1.0), [5; D]).unwrap();
    let mut points = PointStore::new();
    let max = SVector::<f64, D>::from_fn(|i, _| if i == 1 { 2.0 } else { 3.0 });
    points
        .fill(&grid, &Shape::Box { min: SVector::from_fn(|i, _| if i == 1 { 0.0 } else { 1.0 }), max }, 2, 1000.0, 0)
        .unwrap();
    // Downwards 10, along the plane 6 (split over x and z in 3D): μ g_n = 3 holds half.
    let along = if D == 3 { 6.0 / 2f64.sqrt() } else { 6.0 };
    let gravity = SVector::<f64, D>::from_fn(|i, _| if i == 1 { -10.0 } else { along });
    let law: Arc<dyn ConstitutiveLaw> = Arc::new(Elastic::new(1e5, 0.3).unwrap());
    let model =
        Model::new(grid, BasisKind::Gimp, Kinematics::FiniteStrain, points, vec![law], vec![], gravity).unwrap();
    let normal = SVector::<f64, D>::from_fn(|i, _| if i == 1 { 1.0 } else { 0.0 });
    let plane = FrictionalPlane::new(SVector::zeros(), normal, 0.3).unwrap();
    let model = model.with_frictional_planes(vec![plane]).unwrap();
    let mut engine = Engine::new(model, NewtonSettings::default(), loam_solve::LinearSolverChoice::Auto, false);
    engine.connect(1).unwrap();
    engine.size_buffers();
    engine.external_forces(LoadLevel::Factor(1.0));
    let n = engine.num_dofs();
    // The states from the forces at a small increment: the base nodes slip.
    engine.frames.reset_contacts(&mut engine.constrained);
    let small: Vec<f64> = noise(n, 3).iter().map(|x| 1e-4 * x).collect();
    residual_at(&mut engine, &small);
    // Then a slide of 1 % of a cell along gravity's tangential part, with noise.
    let slide = SVector::<f64, D>::from_fn(|i, _| if i == 1 { 0.0 } else { 1e-2 / (D as f64 - 1.0).sqrt() });
    let du: Vec<f64> = (0..n).map(|k| small[k] + slide[k % D]).collect();
    residual_at(&mut engine, &du);
    assert!(engine.frames.slipping() > 0, "{D}D: no node slips");
    let mut v = noise(n, 11);
    (0..n).filter(|&k| engine.constrained[k]).for_each(|k| v[k] = 0.0);
    let mut v_global = v.clone();
    engine.frames.to_global(&mut v_global);
    let eps = 1e-7;
    let at = |sign: f64| -> Vec<f64> { du.iter().zip(&v_global).map(|(a, b)| a + sign * eps * b).collect() };
    let rp = residual_at(&mut engine, &at(1.0));
    assert!(!engine.frames.contact_changed(), "{D}D: a state changed");
    let rm = residual_at(&mut engine, &at(-1.0));
    assert!(!engine.frames.contact_changed(), "{D}D: a state changed");
    residual_at(&mut engine, &du);
    engine.assemble(None);
    let mut kv = vec![0.0; n];
    engine.matrix.mul_vec(&engine.pattern, &v, &mut kv);
    let diff: Vec<f64> = kv.iter().zip(rp.iter().zip(&rm)).map(|(k, (p, m))| k - (p - m) / (2.0 * eps)).collect();
    assert!(norm(&diff) <= 1e-6 * norm(&kv), "{D}D: |Kv − FD| / |Kv| = {:e}", norm(&diff) / norm(&kv));
    let asym = engine.matrix.asymmetry(&engine.pattern);
    assert!(asym > 1e-3, "{D}D: asymmetry {asym:e}: the friction rows are missing");
}
