//! The model's checks: every constructor refuses what it would otherwise index out of
//! range or run with silently wrong.

use super::*;
use loam_constitutive::{Elastic, VonMises};
use loam_points::{PointsError, Shape};
use nalgebra::Vector2;

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

fn model_with(constraints: Vec<PlaneConstraint>) -> Result<Model<2>, ModelError> {
    Model::new(
        grid(),
        BasisKind::Linear,
        Kinematics::SmallStrain,
        points(0),
        vec![elastic()],
        constraints,
        Vector2::zeros(),
    )
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
    assert_eq!(replaced.materials()[0].p_wave_modulus(), Elastic::new(1e3, 0.3).unwrap().p_wave_modulus());
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
    assert_eq!(view.len(), n);
    view.stress[0] = Matrix3::identity();
    view.velocity.iter_mut().for_each(|v| *v = Vector2::new(1.0, 0.0));
    assert_eq!(model.points().stress[0], Matrix3::identity());
    assert_eq!(model.points().momentum(), Vector2::new(model.points().total_mass(), 0.0));
}

/// A store whose fields disagree in length, a point with no volume, a point that starts
/// stressed and a constraint with a NaN displacement are refused with what is wrong, not
/// indexed into a panic later.
#[test]
fn inconsistent_points_and_constraint_values_are_refused() {
    let build = |points: PointStore<2>, constraints: Vec<PlaneConstraint>| {
        Model::new(
            grid(),
            BasisKind::Linear,
            Kinematics::SmallStrain,
            points,
            vec![elastic()],
            constraints,
            Vector2::zeros(),
        )
    };
    let mut short = points(0);
    short.mass.pop();
    assert!(matches!(build(short, vec![]), Err(ModelError::Points(PointsError::FieldLength { field: "mass", .. }))));
    let mut empty = points(0);
    empty.volume[3] = 0.0;
    assert!(matches!(build(empty, vec![]), Err(ModelError::Points(PointsError::Point { point: 3, .. }))));
    let mut stressed = points(0);
    stressed.stress[5][(0, 0)] = -1.0;
    assert_eq!(build(stressed, vec![]).unwrap_err(), ModelError::Prestrained(5));
    let nan = PlaneConstraint::new(1, 0, [false, true, false]).displaced([0.0, f64::NAN, 0.0]);
    assert_eq!(
        build(points(0), vec![nan]).unwrap_err(),
        ModelError::ConstraintValue { index: 0, what: "displacement" }
    );
}

/// The rigid modes no constraint holds on a 4 × 3-cell grid, every node active: all three
/// with none; x alone with a roller on the base; none with rollers on the base and a side;
/// the rotation alone when one node is pinned in both components.
#[test]
fn free_rigid_modes_are_those_no_constraint_holds() {
    let nodes = 5 * 4;
    let active = ActiveNodes { grid_to_active: (0..nodes).collect(), active_to_grid: (0..nodes).collect() };
    let modes = |constraints| model_with(constraints).unwrap().free_rigid_modes(&active);
    let base = PlaneConstraint::new(1, 0, [false, true, false]);
    let side = PlaneConstraint::new(0, 0, [true, false, false]);
    let pin = PlaneConstraint::new(1, 0, [true, true, false]).within([-0.1, -1.0, 0.0], [0.1, 1.0, 0.0]);
    use RigidMode::*;
    assert_eq!(modes(vec![]), vec![Translation(0), Translation(1), Rotation(0, 1)]);
    assert_eq!(modes(vec![base.clone()]), vec![Translation(0)]);
    assert_eq!(modes(vec![base, side]), vec![]);
    assert_eq!(modes(vec![pin]), vec![Rotation(0, 1)]);
    assert_eq!(Rotation(0, 2).to_string(), "rotation in the x-z plane");
}
