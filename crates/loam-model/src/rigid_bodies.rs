//! Rigid bodies (docs/theory.md §10): a footing, a wall or a pile, made of material points
//! like the soil but moved at a prescribed velocity, stress-free, meeting the other bodies
//! by frictional contact at the grid nodes (`Model::with_rigid_bodies`).

use crate::constraint::check_friction;
use crate::{Model, ModelError, TimeFunction};
use nalgebra::SVector;

/// The largest body id a rigid body may have: the rigid bodies are a 64-bit mask.
pub const MAX_RIGID_BODY_ID: u32 = 63;

/// A body moved as a rigid whole at a prescribed velocity v f(t), with Coulomb friction μ
/// against the material it meets.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidBody<const D: usize> {
    body: u32,
    velocity: SVector<f64, D>,
    time: TimeFunction,
    friction: f64,
}

impl<const D: usize> RigidBody<D> {
    /// The points of `body` moved at `velocity` from the start (see [`Self::in_time`]), with
    /// friction μ against the material; refused unless the velocity is finite and μ finite
    /// and ≥ 0.
    pub fn new(body: u32, velocity: SVector<f64, D>, friction: f64) -> Result<Self, String> {
        if !velocity.iter().all(|v| v.is_finite()) {
            return Err(format!("the velocity {:?} must be finite", velocity.as_slice()));
        }
        check_friction(friction)?;
        Ok(Self { body, velocity, time: TimeFunction::Constant, friction })
    }

    /// The body with its velocity scaled by `time` (held, then moved: f = 0, then 1);
    /// refused for an invalid function.
    pub fn in_time(self, time: TimeFunction) -> Result<Self, String> {
        time.check()?;
        Ok(Self { time, ..self })
    }

    /// The body id of its points.
    pub fn body(&self) -> u32 {
        self.body
    }

    /// The velocity v that the time function scales.
    pub fn velocity(&self) -> &SVector<f64, D> {
        &self.velocity
    }

    /// Its velocity at time `t`, v f(t).
    pub fn velocity_at(&self, t: f64) -> SVector<f64, D> {
        self.velocity * self.time.at(t)
    }

    /// Its mean velocity over [t, t + Δt]: what it moves by over the step, over Δt.
    pub fn step_velocity(&self, t: f64, dt: f64) -> SVector<f64, D> {
        self.velocity * ((self.time.integral(t + dt) - self.time.integral(t)) / dt)
    }

    /// The Coulomb coefficient against the material.
    pub fn friction(&self) -> f64 {
        self.friction
    }

    /// The least and greatest displacement per component over 0 ≤ t ≤ `end`.
    pub fn displacement_range(&self, end: f64) -> (SVector<f64, D>, SVector<f64, D>) {
        let (lo, hi) = self.time.integral_range(end);
        (self.velocity.map(|v| (v * lo).min(v * hi)), self.velocity.map(|v| (v * lo).max(v * hi)))
    }

    /// Its displacement at time `t`, v ∫₀ᵗ f.
    pub fn displacement(&self, t: f64) -> SVector<f64, D> {
        self.velocity * self.time.integral(t)
    }
}

impl<const D: usize> Model<D> {
    /// Move bodies as rigid wholes (docs/theory.md §10): each one's points keep their
    /// prescribed velocity and no stress, and meet the other bodies, each of which moves
    /// with its own velocity field at the nodes where they meet, by frictional contact.
    /// Refused: a body without points, a body named twice or with an id above
    /// [`MAX_RIGID_BODY_ID`], every body rigid, loads or body constraints beside them
    /// (their nodal forces and holds belong to no one body's field yet), and a model
    /// already in its geostatic stress (which must leave the rigid points out).
    pub fn with_rigid_bodies(mut self, bodies: Vec<RigidBody<D>>) -> Result<Self, ModelError> {
        for (index, b) in bodies.iter().enumerate() {
            let what = if b.body > MAX_RIGID_BODY_ID {
                format!("body {} is above the largest id a rigid body may have, {MAX_RIGID_BODY_ID}", b.body)
            } else if !self.points().body().contains(&b.body) {
                format!("body {} has no points", b.body)
            } else if bodies[..index].iter().any(|a| a.body == b.body) {
                format!("body {} is rigid twice", b.body)
            } else if !self.loads().is_empty() {
                "loads beside rigid bodies are not supported yet (their nodal forces belong to no body's field)".into()
            } else if self.gravity_preloaded() {
                "the points are already in their initial stress; make the bodies rigid before the geostatic stress, which leaves their points out".into()
            } else if !self.body_constraints().is_empty() {
                "body constraints beside rigid bodies are not supported yet (they would hold every body's field)".into()
            } else {
                continue;
            };
            return Err(ModelError::RigidBody { index, what });
        }
        if !bodies.is_empty() && self.points().body().iter().all(|b| bodies.iter().any(|r| r.body == *b)) {
            let what = "every body is rigid: there is no material to move".to_string();
            return Err(ModelError::RigidBody { index: 0, what });
        }
        self.rigid_bodies = bodies;
        Ok(self)
    }

    /// The rigid bodies.
    pub fn rigid_bodies(&self) -> &[RigidBody<D>] {
        &self.rigid_bodies
    }

    /// Whether point `p` belongs to a rigid body.
    pub fn is_rigid_point(&self, p: usize) -> bool {
        !self.rigid_bodies.is_empty() && self.rigid_body_of(self.points.body()[p]).is_some()
    }

    /// The rigid body whose points carry body id `body`, if one does.
    pub fn rigid_body_of(&self, body: u32) -> Option<&RigidBody<D>> {
        self.rigid_bodies.iter().find(|r| r.body == body)
    }
}
