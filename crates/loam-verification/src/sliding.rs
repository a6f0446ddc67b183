//! V9, a block on a frictional incline (docs/verification.md §V9): an elastic block resting
//! on a rigid plane with Coulomb friction μ, under gravity g at θ to the plane's normal,
//! slides with the acceleration of a rigid block, a = g (sin θ − μ cos θ), when tan θ > μ,
//! and stays when tan θ < μ. Once every node under the block slips, the plane's tangential
//! force is μ times its normal force at every step, so the centre of mass follows the
//! rigid block's law whatever the block's elastic vibration; a block released unstressed
//! bounces, though, and a bouncing block ratchets down a slope it would rest on, so the
//! sticking case is run with local damping.
//!
//! Two ways of posing the slope: a level base with gravity turned by θ (the block is a box
//! of the grid), and a plane inclined at θ with gravity vertical (the block a polygon
//! across the cells, the plane cutting them); in 3D the level base with gravity turned
//! along the diagonal of x and z, so that friction has to oppose a slip along no axis; and
//! the block as a body of its own on an elastic slab of the same soil, the contact between
//! the two bodies' velocity fields (`Model::with_body_contact`) in place of the plane.
//! The plane cases run in explicit MPM and in implicit dynamics, the bodies' and the rigid
//! slab's in explicit MPM (where contact between bodies is built); units m, t, s, kN, kPa.

use crate::Bound;
use loam_constitutive::{ConstitutiveLaw, Elastic};
use loam_grid::{BasisKind, Grid};
use loam_model::{FrictionalPlane, Kinematics, Model, RigidBody};
use loam_points::{PointStore, Shape};
use nalgebra::{SVector, Vector2, Vector3};
use std::sync::Arc;

/// The block and its slope.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SlidingBlock {
    /// θ, the slope's angle, in degrees.
    pub slope_deg: f64,
    /// μ.
    pub friction: f64,
    /// Posed on a plane inclined at θ (gravity vertical) instead of a level base.
    pub inclined: bool,
}

const LENGTH: f64 = 1.0;
const HEIGHT: f64 = 0.5;
const CELL: f64 = 0.1;
/// The slab under the block in the case of two bodies.
const SLAB: f64 = 0.3;
const DENSITY: f64 = 2.0;
const GRAVITY: f64 = 10.0;
/// c_p = 83 m/s: the block rings at about 40 Hz, many periods within a run.
const YOUNG: f64 = 1e4;
const POISSON: f64 = 0.3;

impl SlidingBlock {
    /// The rigid block's acceleration down the slope, g (sin θ − μ cos θ), or zero when
    /// friction holds it.
    pub fn acceleration(&self) -> f64 {
        let theta = self.slope_deg.to_radians();
        (GRAVITY * (theta.sin() - self.friction * theta.cos())).max(0.0)
    }

    /// The block's acceleration down the slope while a faster belt under it drags it,
    /// g (sin θ + μ cos θ).
    pub fn dragged_acceleration(&self) -> f64 {
        let theta = self.slope_deg.to_radians();
        GRAVITY * (theta.sin() + self.friction * theta.cos())
    }

    /// The unit vector down the slope.
    pub fn downhill(&self) -> Vector2<f64> {
        let theta = self.slope_deg.to_radians();
        if self.inclined {
            Vector2::new(-theta.cos(), -theta.sin())
        } else {
            Vector2::new(1.0, 0.0)
        }
    }

    /// The 2D model: a 1 × 0.5 m block at 2 × 2 points a cell of 0.1 m, GIMP, finite strain,
    /// with room for `travel` metres of sliding.
    pub fn model(&self, travel: f64) -> Model<2> {
        let theta = self.slope_deg.to_radians();
        let (tangent, normal) = (Vector2::new(theta.cos(), theta.sin()), Vector2::new(-theta.sin(), theta.cos()));
        let (grid, shape, gravity, normal) = if self.inclined {
            // The block's lower uphill corner `travel` + one cell up the plane from the origin.
            let start = tangent * (travel + CELL);
            let (along, up) = (tangent * LENGTH, normal * HEIGHT);
            let corners = [start, start + along, start + along + up, start + up];
            let top = (start + along + up).y + CELL;
            let nx = ((start + along).x / CELL).ceil() as usize + 3;
            let grid = Grid::new(
                Vector2::new(-2.0 * CELL, -2.0 * CELL),
                Vector2::repeat(CELL),
                [nx, (top / CELL) as usize + 3],
            );
            (grid, Shape::Polygon(corners.to_vec()), Vector2::new(0.0, -GRAVITY), normal)
        } else {
            let grid = Grid::new(Vector2::zeros(), Vector2::repeat(CELL), [((LENGTH + travel) / CELL) as usize + 4, 8]);
            let shape = Shape::Box { min: Vector2::new(CELL, 0.0), max: Vector2::new(CELL + LENGTH, HEIGHT) };
            (grid, shape, Vector2::new(theta.sin(), -theta.cos()) * GRAVITY, Vector2::new(0.0, 1.0))
        };
        let grid = grid.expect("valid V9 grid");
        self.on(grid, shape, gravity, FrictionalPlane::new(Vector2::zeros(), normal, self.friction))
    }

    /// The 3D model on a level base, gravity turned by θ along the diagonal of x and z: a
    /// 1 × 0.5 × 0.4 m block, room for `travel` metres along x and z.
    pub fn model_3d(&self, travel: f64) -> Model<3> {
        let theta = self.slope_deg.to_radians();
        let side = travel / std::f64::consts::SQRT_2;
        let cells = [((LENGTH + side) / CELL) as usize + 4, 8, ((0.4 + side) / CELL) as usize + 4];
        let grid = Grid::new(Vector3::zeros(), Vector3::repeat(CELL), cells).expect("valid V9 grid");
        let shape =
            Shape::Box { min: Vector3::new(CELL, 0.0, CELL), max: Vector3::new(CELL + LENGTH, HEIGHT, CELL + 0.4) };
        let along = GRAVITY * theta.sin() / std::f64::consts::SQRT_2;
        let gravity = Vector3::new(along, -GRAVITY * theta.cos(), along);
        self.on(
            grid,
            shape,
            gravity,
            FrictionalPlane::new(Vector3::zeros(), Vector3::new(0.0, 1.0, 0.0), self.friction),
        )
    }

    /// The 2D block on a slab 0.3 m thick of the same soil (body 0, its base held on the
    /// grid plane y = 0), gravity turned by θ, friction μ between the two bodies.
    pub fn model_on_slab(&self, travel: f64) -> Model<2> {
        let theta = self.slope_deg.to_radians();
        let cells = [((LENGTH + travel) / CELL) as usize + 4, 11];
        let grid = Grid::new(Vector2::zeros(), Vector2::repeat(CELL), cells).expect("valid V9 grid");
        let mut points = PointStore::new();
        let slab = Shape::Box { min: Vector2::zeros(), max: Vector2::new(cells[0] as f64 * CELL, SLAB) };
        points.fill(&grid, &slab, 2, DENSITY, 0).expect("the slab fits the grid");
        let first = points.len();
        let block = Shape::Box { min: Vector2::new(CELL, SLAB), max: Vector2::new(CELL + LENGTH, SLAB + HEIGHT) };
        points.fill(&grid, &block, 2, DENSITY, 0).expect("the block fits the grid");
        points.assign_body(first..points.len(), 1);
        let law: Arc<dyn ConstitutiveLaw> = Arc::new(Elastic::new(YOUNG, POISSON).expect("valid elasticity"));
        let base = vec![loam_model::PlaneConstraint::new(1, 0, [true, true, false])];
        let gravity = Vector2::new(theta.sin(), -theta.cos()) * GRAVITY;
        let model = Model::new(grid, BasisKind::Gimp, Kinematics::FiniteStrain, points, vec![law], base, gravity)
            .expect("valid V9 model");
        model.with_body_contact(self.friction).expect("valid friction")
    }

    /// The 2D block on a rigid slab 0.3 m thick (body 0, `Model::with_rigid_bodies`) moved
    /// at `belt` m/s along x, friction μ against it, gravity turned by θ, for a run of
    /// `duration` seconds: the slab is long enough for the block to slide ½ g t² along it
    /// and the grid reaches beyond it as far as the slab travels.
    pub fn model_on_belt(&self, belt: f64, duration: f64) -> Model<2> {
        let theta = self.slope_deg.to_radians();
        let slab_length = LENGTH + 2.0 * CELL + 0.5 * GRAVITY * duration * duration;
        let cells = [((slab_length + belt.abs() * duration) / CELL).ceil() as usize + 2, 11];
        let grid = Grid::new(Vector2::zeros(), Vector2::repeat(CELL), cells).expect("valid V9 grid");
        let mut points = PointStore::new();
        let slab = Shape::Box { min: Vector2::zeros(), max: Vector2::new(slab_length, SLAB) };
        points.fill(&grid, &slab, 2, DENSITY, 0).expect("the slab fits the grid");
        let first = points.len();
        let block = Shape::Box { min: Vector2::new(CELL, SLAB), max: Vector2::new(CELL + LENGTH, SLAB + HEIGHT) };
        points.fill(&grid, &block, 2, DENSITY, 0).expect("the block fits the grid");
        points.assign_body(first..points.len(), 1);
        points.velocity_mut()[..first].iter_mut().for_each(|v| *v = Vector2::new(belt, 0.0));
        let law: Arc<dyn ConstitutiveLaw> = Arc::new(Elastic::new(YOUNG, POISSON).expect("valid elasticity"));
        let gravity = Vector2::new(theta.sin(), -theta.cos()) * GRAVITY;
        let model = Model::new(grid, BasisKind::Gimp, Kinematics::FiniteStrain, points, vec![law], vec![], gravity)
            .expect("valid V9 model");
        let rigid = RigidBody::new(0, Vector2::new(belt, 0.0), self.friction).expect("valid rigid body");
        model.with_rigid_bodies(vec![rigid]).expect("the slab is a body")
    }

    fn on<const D: usize>(
        &self,
        grid: Grid<D>,
        shape: Shape<D>,
        gravity: SVector<f64, D>,
        plane: Result<FrictionalPlane<D>, String>,
    ) -> Model<D> {
        let mut points = PointStore::new();
        points.fill(&grid, &shape, 2, DENSITY, 0).expect("the block fits the grid");
        let law: Arc<dyn ConstitutiveLaw> = Arc::new(Elastic::new(YOUNG, POISSON).expect("valid elasticity"));
        let model = Model::new(grid, BasisKind::Gimp, Kinematics::FiniteStrain, points, vec![law], Vec::new(), gravity)
            .expect("valid V9 model");
        model.with_frictional_planes(vec![plane.expect("valid plane")]).expect("the plane holds nodes")
    }
}

/// Whether point `p` of a V9 model is the block's: every point on a plane, body 1's on a
/// slab or a belt.
pub fn in_block<const D: usize>(model: &Model<D>, p: usize) -> bool {
    let alone = model.body_contact().is_none() && model.rigid_bodies().is_empty();
    alone || model.points().body()[p] == 1
}

/// The velocity of the block's centre of mass along `downhill`.
pub fn block_speed<const D: usize>(model: &Model<D>, downhill: &SVector<f64, D>) -> f64 {
    let pts = model.points();
    let block = (0..pts.len()).filter(|&p| in_block(model, p));
    let (momentum, mass) =
        block.fold((0.0, 0.0), |(q, m), p| (q + pts.velocity()[p].dot(downhill) * pts.mass()[p], m + pts.mass()[p]));
    momentum / mass
}

/// The mean displacement of the block's points along `downhill`.
pub fn block_displacement<const D: usize>(model: &Model<D>, downhill: &SVector<f64, D>) -> f64 {
    let pts = model.points();
    let block: Vec<usize> = (0..pts.len()).filter(|&p| in_block(model, p)).collect();
    let moved: f64 = block.iter().map(|&p| (pts.position()[p] - pts.position0()[p]).dot(downhill)).sum();
    moved / block.len() as f64
}

/// The least-squares slope of `values` against `times`: the mean acceleration of a sampled
/// velocity, which averages the block's elastic ringing out.
pub fn fitted_slope(times: &[f64], values: &[f64]) -> f64 {
    let n = times.len().min(values.len()) as f64;
    let (mt, mv) = (times.iter().sum::<f64>() / n, values.iter().sum::<f64>() / n);
    let covariance: f64 = times.iter().zip(values).map(|(t, v)| (t - mt) * (v - mv)).sum();
    let variance: f64 = times.iter().map(|t| (t - mt).powi(2)).sum();
    covariance / variance
}

/// The bounds of V9.
pub mod bounds {
    use super::Bound;
    /// |a / (g (sin θ − μ cos θ)) − 1| of the sliding block.
    pub const SLIDING_ACCELERATION: Bound =
        Bound::upper(0.01, "docs/verification.md §V9: a = g (sin θ − μ cos θ) within 1 % (issue 35)");
    /// |mean tangential / mean normal force of the plane| / μ − 1 while it slides.
    pub const COULOMB_RATIO: Bound =
        Bound::upper(0.01, "docs/verification.md §V9: the plane's force on the cone of Coulomb while sliding, 1 %");
    /// The stuck block's mean displacement over the frictionless block's travel.
    pub const STUCK_DISPLACEMENT: Bound =
        Bound::upper(1e-3, "docs/verification.md §V9: stays put when tan θ < μ (elastic shear only)");
}
