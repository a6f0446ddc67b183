//! The model's checks: every constructor refuses what it would otherwise index out of
//! range or run with silently wrong.

use super::*;
use loam_constitutive::{Elastic, MaterialState, VonMises};
use loam_points::{PointsError, Shape};
use nalgebra::{Matrix3, Vector2};

fn elastic() -> Arc<dyn ConstitutiveLaw> {
    Arc::new(Elastic::new(1e5, 0.3).unwrap())
}

fn grid() -> Grid<2> {
    Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [4, 3]).unwrap()
}

/// A 2 × 2-cell block of 2 × 2 points per cell, all of material `material`.
fn points(material: u32) -> PointStore<2> {
    let mut points = PointStore::new();
    let shape = Shape::Box { min: Vector2::zeros(), max: Vector2::new(2.0, 2.0) };
    points.fill(&grid(), &shape, 2, 1000.0, material).unwrap();
    points
}

/// The block on `basis` with `kinematics`, elastic, no constraints or gravity.
fn model_on(basis: BasisKind, kinematics: Kinematics) -> Model<2> {
    Model::new(grid(), basis, kinematics, points(0), vec![elastic()], vec![], Vector2::zeros()).unwrap()
}

/// A linear-basis, small-strain elastic model of `points` with `constraints`, no gravity.
fn model_of(points: PointStore<2>, constraints: Vec<PlaneConstraint>) -> Result<Model<2>, ModelError> {
    Model::new(
        grid(),
        BasisKind::Linear,
        Kinematics::SmallStrain,
        points,
        vec![elastic()],
        constraints,
        Vector2::zeros(),
    )
}

fn model_with(constraints: Vec<PlaneConstraint>) -> Result<Model<2>, ModelError> {
    model_of(points(0), constraints)
}

#[test]
fn a_constraint_on_an_axis_the_model_lacks_is_refused_not_indexed() {
    let e = model_with(vec![PlaneConstraint::new(2, 0, [true; 3])]).unwrap_err();
    assert_eq!(e, ModelError::ConstraintAxis { index: 0, axis: 2, dimension: 2 });
    let e = model_with(vec![PlaneConstraint::new(1, 0, [true; 3]), PlaneConstraint::new(0, 5, [true; 3])]).unwrap_err();
    assert_eq!(e, ModelError::ConstraintPlane { index: 1, axis: 0, plane: 5, max: 4 });
    assert!(model_with(vec![PlaneConstraint::new(0, 4, [true; 3])]).is_ok());
}

#[test]
fn a_point_of_a_material_that_does_not_exist_is_refused() {
    let e = Model::new(
        grid(),
        BasisKind::Linear,
        Kinematics::SmallStrain,
        points(1),
        vec![elastic()],
        vec![],
        Vector2::zeros(),
    )
    .unwrap_err();
    assert_eq!(e, ModelError::MissingMaterial { point: 0, material: 1, count: 1 });
    let e = Model::new(
        grid(),
        BasisKind::Linear,
        Kinematics::SmallStrain,
        PointStore::new(),
        vec![elastic()],
        vec![],
        Vector2::zeros(),
    )
    .unwrap_err();
    assert_eq!(e, ModelError::NoPoints);
}

#[test]
fn gravity_must_be_finite() {
    let e = Model::new(
        grid(),
        BasisKind::Linear,
        Kinematics::SmallStrain,
        points(0),
        vec![elastic()],
        vec![],
        Vector2::new(0.0, f64::NAN),
    )
    .unwrap_err();
    assert!(matches!(e, ModelError::Gravity { axis: 1, .. }), "{e}");
}

#[test]
fn point_forces_need_one_finite_force_per_point() {
    let model = model_with(vec![]).unwrap();
    let n = model.points().len();
    assert!(matches!(model.clone().with_point_forces(vec![Vector2::zeros(); n - 1]), Err(ModelError::PointForces(_))));
    let mut forces = vec![Vector2::zeros(); n];
    forces[3] = Vector2::new(f64::INFINITY, 0.0);
    let e = model.clone().with_point_forces(forces).unwrap_err();
    assert_eq!(e, ModelError::PointForces("the force on point 3 is not finite".into()));
    let loaded = model.with_point_forces(vec![Vector2::new(1.0, 2.0); n]).unwrap();
    // Half the force at half the load, no gravity.
    assert_eq!(loaded.point_load_at(0, 0.5), Vector2::new(0.5, 1.0));
}

#[test]
fn replaced_materials_keep_count_and_history_layout() {
    let model = model_with(vec![]).unwrap();
    let plastic: Arc<dyn ConstitutiveLaw> =
        Arc::new(VonMises::new(Elastic::new(1e5, 0.3).unwrap(), 10.0, 0.0).unwrap());
    assert!(matches!(model.with_materials(vec![elastic(), elastic()]), Err(ModelError::Materials(_))));
    // Von Mises keeps one history value, elasticity none: the points' history would not fit.
    assert!(matches!(model.with_materials(vec![plastic]), Err(ModelError::Materials(_))));
    let softer: Arc<dyn ConstitutiveLaw> = Arc::new(Elastic::new(1e3, 0.3).unwrap());
    let replaced = model.with_materials(vec![softer]).unwrap();
    assert_eq!(replaced.constant_p_wave_moduli()[0].unwrap(), Elastic::new(1e3, 0.3).unwrap().p_wave_modulus());
}

#[test]
fn treatments_are_refused_where_they_do_not_apply() {
    let gimp = model_on(BasisKind::Gimp, Kinematics::SmallStrain);
    assert!(matches!(gimp.clone().with_anti_locking(AntiLocking::BBar), Err(ModelError::AntiLocking(_))));
    let linear = model_with(vec![]).unwrap();
    let bad = AntiLocking::AssumedStrain { stabilization: 0.0 };
    assert!(matches!(linear.clone().with_anti_locking(bad), Err(ModelError::AntiLocking(_))));
    assert!(linear.clone().with_anti_locking(AntiLocking::BBar).is_ok());
    let spline = model_on(BasisKind::QuadraticBSpline, Kinematics::SmallStrain);
    assert!(matches!(spline.with_ghost_penalty(0.1), Err(ModelError::GhostPenalty(_))));
    assert!(matches!(gimp.clone().with_ghost_penalty(-1.0), Err(ModelError::GhostPenalty(_))));
    let finite = model_on(BasisKind::Gimp, Kinematics::FiniteStrain);
    assert!(matches!(finite.with_geometrically_linear(), Err(ModelError::GeometricallyLinear(_))));
}

/// A follower pressure needs a configuration that moves: taken in small strain on the
/// updated configuration, refused in a geometrically linear model whichever comes first.
#[test]
fn a_follower_pressure_is_refused_where_the_configuration_does_not_move() {
    let follower = || {
        let top = loam_points::Surface {
            vertices: vec![Vector2::new(0.0, 1.0), Vector2::new(1.0, 1.0)],
            facets: vec![[0, 1]],
        };
        crate::Load::pressure(top, vec![1.0, 1.0], true, crate::TimeFunction::Constant).unwrap()
    };
    let small = model_with(vec![]).unwrap();
    assert!(small.clone().with_loads(vec![follower()]).is_ok());
    let linear = small.clone().with_geometrically_linear().unwrap();
    assert!(matches!(linear.with_loads(vec![follower()]), Err(ModelError::Load { index: 0, .. })));
    let loaded = small.with_loads(vec![follower()]).unwrap();
    assert!(matches!(loaded.with_geometrically_linear(), Err(ModelError::GeometricallyLinear(_))));
}

#[test]
fn the_fem_reference_refuses_a_ghost_penalty_and_blocks_without_density() {
    let mesh = FeMesh::block(Vector2::zeros(), Vector2::new(2.0, 2.0), [2, 2], 2).unwrap();
    let fem = |density: &[f64]| {
        Model::updated_lagrangian_fem(
            grid(),
            Kinematics::SmallStrain,
            mesh.clone(),
            density,
            &[0],
            vec![elastic()],
            vec![],
            Vector2::zeros(),
        )
    };
    assert!(matches!(fem(&[]), Err(ModelError::MeshBlock { block: 0, .. })));
    assert!(matches!(fem(&[-1.0]), Err(ModelError::Density { block: 0, .. })));
    let model = fem(&[1000.0]).unwrap();
    assert_eq!(model.points().len(), 16);
    assert!(model.background().moves_with_body());
    assert!(matches!(model.with_ghost_penalty(0.1), Err(ModelError::GhostPenalty(_))));
}

/// The evolving state can be written, but the view has no way to add a point or change
/// one's material: the model's invariant holds whatever an analysis does through it.
#[test]
fn the_mutable_view_writes_state_and_keeps_the_points() {
    let mut model = model_with(vec![]).unwrap();
    let n = model.points().len();
    let view = model.points_mut();
    assert_eq!(view.position.len(), n);
    view.stress[0] = Matrix3::identity();
    view.velocity.iter_mut().for_each(|v| *v = Vector2::new(1.0, 0.0));
    assert_eq!(model.points().stress()[0], Matrix3::identity());
    assert_eq!(model.points().momentum(), Vector2::new(model.points().total_mass(), 0.0));
}

/// A point with no volume, a point that starts stressed and a constraint with a NaN
/// displacement are refused with what is wrong, not indexed into a panic later (a store's
/// fields cannot disagree in length: they are private, and checked when read back from a
/// checkpoint's columns, `loam_points`'s `columns_round_trip`).
#[test]
fn inconsistent_points_and_constraint_values_are_refused() {
    let build = model_of;
    let mut empty = points(0);
    empty.volume_mut()[3] = 0.0;
    assert!(matches!(build(empty, vec![]), Err(ModelError::Points(PointsError::Point { point: 3, .. }))));
    let mut stressed = points(0);
    stressed.stress_mut()[5][(0, 0)] = -1.0;
    assert_eq!(build(stressed, vec![]).unwrap_err(), ModelError::Prestrained(5));
    let nan = PlaneConstraint::new(1, 0, [false, true, false]).displaced([0.0, f64::NAN, 0.0]);
    assert_eq!(
        build(points(0), vec![nan]).unwrap_err(),
        ModelError::ConstraintValue { index: 0, what: "displacement" }
    );
}

/// The free rigid bodies of a model whose points fill `shapes`, with `constraints`.
fn free_bodies(shapes: &[(f64, f64)], constraints: Vec<PlaneConstraint>) -> Vec<FreeBody> {
    let mut points = PointStore::new();
    for &(x0, x1) in shapes {
        let shape = Shape::Box { min: Vector2::new(x0, 0.0), max: Vector2::new(x1, 2.0) };
        points.fill(&grid(), &shape, 2, 1000.0, 0).unwrap();
    }
    let model = model_of(points, constraints).unwrap();
    let mut conn = loam_grid::Connectivity::new(BasisKind::Linear);
    conn.compute(model.grid(), model.points().position(), model.points().half_length()).unwrap();
    model.free_rigid_bodies(&conn)
}

/// The rigid motions no constraint holds on the 2 × 2-cell block at the grid's corner: all
/// three with none (the rotation about its centre); x alone with a roller on the base; none
/// with rollers on the base and a side; the rotation about the pin alone when one node is
/// pinned in both components; with a second block apart, held, the first alone is named.
#[test]
fn free_rigid_bodies_are_those_no_constraint_holds() {
    let block = [(0.0, 2.0)];
    let base = PlaneConstraint::new(1, 0, [false, true, false]);
    let side = PlaneConstraint::new(0, 0, [true, false, false]);
    let pin = PlaneConstraint::new(1, 0, [true, true, false]).within([-0.1, -1.0, 0.0], [0.1, 1.0, 0.0]);
    use RigidMode::*;
    let about = |x: f64, y: f64| Rotation { axis: [0.0, 0.0, 1.0], through: [x, y, 0.0] };
    let modes = |bodies: Vec<FreeBody>| bodies.into_iter().flat_map(|b| b.modes).collect::<Vec<_>>();
    let free = free_bodies(&block, vec![]);
    assert_eq!((free.len(), free[0].alone, free[0].points), (1, true, 16));
    let close = |m: &RigidMode, n: &RigidMode| match (m, n) {
        (Rotation { axis: a, through: p }, Rotation { axis: b, through: q }) => {
            (0..3).all(|i| (a[i] - b[i]).abs() < 1e-9 && (p[i] - q[i]).abs() < 1e-9)
        }
        _ => m == n,
    };
    let expect = |got: Vec<RigidMode>, want: &[RigidMode]| {
        assert!(got.len() == want.len() && got.iter().zip(want).all(|(m, n)| close(m, n)), "{got:?} != {want:?}");
    };
    expect(modes(free), &[Translation(0), Translation(1), about(1.0, 1.0)]);
    expect(modes(free_bodies(&block, vec![base.clone()])), &[Translation(0)]);
    expect(modes(free_bodies(&block, vec![base.clone(), side])), &[]);
    expect(modes(free_bodies(&block, vec![pin])), &[about(0.0, 0.0)]);
    let held_left = PlaneConstraint::new(1, 0, [true, true, false]).within([-1.0, -1.0, 0.0], [1.0, 1.0, 0.0]);
    let two = free_bodies(&[(0.0, 1.0), (3.0, 4.0)], vec![held_left]);
    assert_eq!((two.len(), two[0].alone, two[0].points, two[0].centre), (1, false, 8, [3.5, 1.0, 0.0]));
    expect(two[0].modes.clone(), &[Translation(0), Translation(1), about(3.5, 1.0)]);
    assert_eq!(two[0].describe(2), "the body of 8 points around (3.5, 1) against translation along x, translation along y, rotation about (3.5, 1)");
}

/// A law whose stiffness follows the state and whose history starts from the initial
/// stress (the shape of a pressure-dependent law): elastic, but M = M₀ (1 + p / p_ref) at
/// mean stress p = −tr σ / 3, and the history the initial p.
#[derive(Debug)]
struct PressureDependent(Elastic);

impl ConstitutiveLaw for PressureDependent {
    fn name(&self) -> &'static str {
        "pressure-dependent"
    }
    fn history_len(&self) -> usize {
        1
    }
    fn init_history(&self, h: &mut [f64], initial_stress: &Matrix3<f64>) {
        h[0] = -initial_stress.trace() / 3.0;
    }
    fn update(
        &self,
        eps: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<loam_constitutive::StressUpdate, loam_constitutive::ConstitutiveError> {
        h_out.copy_from_slice(h_n);
        self.0.update(eps, &[], &mut [])
    }
    fn elasticity(&self, _state: &MaterialState) -> Option<Elastic> {
        Some(self.0)
    }
    fn constant_stiffness(&self) -> bool {
        false
    }
    fn p_wave_modulus(&self, state: &MaterialState) -> f64 {
        self.0.p_wave_modulus() * (1.0 - state.stress.trace() / 3.0 / 100.0)
    }
    fn stored_energy(&self, e: &Matrix3<f64>) -> f64 {
        self.0.stored_energy(e)
    }
}

/// A law that says its stiffness follows the state is asked at every point, in the
/// point's state (a constant one once per material); its history starts from each point's
/// geostatic stress. Elastic E = 1e5, ν = 0.3: M₀ = 134 615.38…; the block 2 m deep of
/// 1000 kg/m³ under g = 10 has σ_v = −ρ g depth at its points (depths 0.25 … 1.75 m).
#[test]
fn a_law_may_state_its_stiffness_and_history_from_the_state() {
    let law: Arc<dyn ConstitutiveLaw> = Arc::new(PressureDependent(Elastic::new(1e5, 0.3).unwrap()));
    let mut model = Model::new(
        grid(),
        BasisKind::Linear,
        Kinematics::SmallStrain,
        points(1),
        vec![elastic(), law],
        vec![],
        Vector2::new(0.0, -10.0),
    )
    .unwrap();
    let m0 = Elastic::new(1e5, 0.3).unwrap().p_wave_modulus();
    assert_eq!(model.constant_p_wave_moduli(), vec![Some(m0), None]);
    assert_eq!(model.points().history(0), &[0.0], "unstressed before the geostatic stress");
    model.geostatic_stress(0.5).unwrap();
    let moduli = model.constant_p_wave_moduli();
    for p in 0..model.points().len() {
        let s = model.points().stress()[p];
        let mean = -s.trace() / 3.0;
        assert!(mean > 0.0);
        assert_eq!(model.points().history(p), &[mean], "point {p}: history from its initial stress");
        let expected = m0 * (1.0 + mean / 100.0);
        assert!((model.p_wave_modulus(&moduli, p) / expected - 1.0).abs() < 1e-15, "point {p}");
    }
}

/// A body constraint is refused on a body without points, when it prescribes none of the
/// model's components, and with a displacement or box that is not a number; accepted, it
/// holds exactly the active nodes its body's points inside its box reach: with the linear
/// basis the block's points in the cell [0, 1]² reach the 4 nodes of that cell.
#[test]
fn a_body_constraint_holds_the_nodes_its_points_reach() {
    let model = || model_with(vec![]).unwrap();
    let refused = |c: BodyConstraint| match model().with_body_constraints(vec![c]) {
        Err(ModelError::BodyConstraint { index: 0, what }) => what,
        other => panic!("{other:?}"),
    };
    assert!(refused(BodyConstraint::new(1, [true; 3])).contains("body 1 has no points"));
    assert!(refused(BodyConstraint::new(0, [false, false, true])).contains("none of the 2"));
    assert!(refused(BodyConstraint::new(0, [true; 3]).displaced([f64::NAN, 0.0, 0.0])).contains("finite"));
    assert!(refused(BodyConstraint::new(0, [true; 3]).within([f64::NAN; 3], [1.0; 3])).contains("box"));
    let held = BodyConstraint::new(0, [false, true, false]).within([0.0, 0.0, 0.0], [1.0, 1.0, 0.0]);
    let model = model().with_body_constraints(vec![held]).unwrap();
    let mut conn = Connectivity::new(BasisKind::Linear);
    model.background().connect(&mut conn, model.configuration(), model.points().half_length()).unwrap();
    let grid_nodes: Vec<u32> =
        model.body_constraint_nodes(&conn, 0).iter().map(|&a| conn.active_nodes().active_to_grid[a]).collect();
    // Nodes numbered x fastest on 5 nodes a row: (0,0), (1,0), (0,1), (1,1).
    assert_eq!(grid_nodes, vec![0, 1, 5, 6]);
    let layout = NodeLayout::motion(2);
    let mut constrained = vec![false; layout.num_dofs(conn.active_nodes().len())];
    model.mark_body_constrained_dofs(&layout, &conn, &mut constrained);
    let held_dofs: Vec<usize> = (0..constrained.len()).filter(|&k| constrained[k]).collect();
    let expected: Vec<usize> = [0u32, 1, 5, 6]
        .iter()
        .map(|&g| layout.dof(conn.active_nodes().grid_to_active[g as usize] as usize, 0, 1))
        .collect();
    assert_eq!(held_dofs, expected);
}

/// A rigid footing on level ground is left out of the geostatic stress: its points carry
/// none and keep their elastic strain, and the ground's stresses are bitwise those of the
/// ground alone (the footing weighs on no column; its motion is prescribed). Making a
/// body rigid after the stress is set is refused, as the stress would have counted it.
#[test]
fn the_geostatic_stress_leaves_rigid_bodies_out() {
    let ground = || {
        let mut m = model_of(points(0), vec![]).unwrap();
        m.gravity = Vector2::new(0.0, -10.0);
        m
    };
    let mut alone = ground();
    alone.geostatic_stress(0.5).unwrap();
    let mut pts = points(0);
    let mut footing = PointStore::new();
    let shape = Shape::Box { min: Vector2::new(0.0, 2.0), max: Vector2::new(1.0, 3.0) };
    footing.fill(&grid(), &shape, 2, 7000.0, 0).unwrap();
    let first = pts.append(&footing).unwrap();
    pts.assign_body(first..pts.len(), 1);
    let mut with_footing = model_of(pts, vec![]).unwrap();
    with_footing.gravity = Vector2::new(0.0, -10.0);
    let rigid = || vec![RigidBody::new(1, Vector2::new(0.0, -0.1), 0.0).unwrap()];
    let mut with_footing = with_footing.with_rigid_bodies(rigid()).unwrap();
    let before = with_footing.points().elastic_strain().to_vec();
    with_footing.geostatic_stress(0.5).unwrap();
    let n = alone.points().len();
    assert_eq!(&with_footing.points().stress()[..n], alone.points().stress());
    assert!(with_footing.points().stress()[n..].iter().all(|s| *s == Matrix3::zeros()));
    assert_eq!(&with_footing.points().elastic_strain()[n..], &before[n..]);
    let mut stressed = ground();
    stressed.geostatic_stress(0.5).unwrap();
    match stressed.with_rigid_bodies(vec![RigidBody::new(0, Vector2::zeros(), 0.0).unwrap()]) {
        Err(ModelError::RigidBody { index: 0, what }) => assert!(what.contains("initial stress"), "{what}"),
        other => panic!("{other:?}"),
    }
}
