//! Constraints on the nodes of a plane of the background grid, on the nodes a body's points
//! reach, and rollers on inclined planes held in a local frame at the nodes.

use nalgebra::{SMatrix, SVector};

/// A constraint on the nodes of a grid plane: the listed displacement components are
/// prescribed — zero (a roller fixes the component normal to the plane, a fixed plane all
/// of them), or `displacement` at full load, applied in proportion to the load factor
/// (a footing pushed into the ground). `within` limits it to the nodes of the plane inside
/// a box (all axes; the plane's own axis is ignored).
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneConstraint {
    /// Axis normal to the plane.
    pub axis: usize,
    /// Index of the node plane along `axis`.
    pub plane: usize,
    /// Which displacement components are prescribed (first D entries used).
    pub fixed: [bool; 3],
    /// Prescribed displacement of the fixed components at full load (zero: held).
    pub displacement: [f64; 3],
    /// Only nodes with min ≤ x ≤ max (per axis, to within 1e-9 of a cell), if given.
    pub within: Option<([f64; 3], [f64; 3])>,
}

impl PlaneConstraint {
    /// Hold the `fixed` components of every node of the plane at zero.
    pub fn new(axis: usize, plane: usize, fixed: [bool; 3]) -> Self {
        Self { axis, plane, fixed, displacement: [0.0; 3], within: None }
    }

    /// Prescribe `displacement` (at full load) on the fixed components instead of zero.
    pub fn displaced(mut self, displacement: [f64; 3]) -> Self {
        self.displacement = displacement;
        self
    }

    /// Only the nodes of the plane inside the box [min, max].
    pub fn within(mut self, min: [f64; 3], max: [f64; 3]) -> Self {
        self.within = Some((min, max));
        self
    }

    /// Whether the constraint prescribes a non-zero displacement.
    pub fn is_displaced(&self) -> bool {
        displaces(&self.fixed, &self.displacement)
    }
}

/// A constraint on a body (a footing or a pile pushed into the ground, a wall held, or
/// the part of the soil inside a box): at every step, the nodes that the supports of the
/// body's points inside `within` reach have the listed components prescribed — held, or
/// displaced by `displacement` at full load in proportion to the load factor. Unlike a
/// plane constraint it follows the body through the grid: every support node of a held
/// point moves by the same increment, so the point moves by it too (partition of unity).
#[derive(Debug, Clone, PartialEq)]
pub struct BodyConstraint {
    /// The body whose points it holds (`PointStore::body`).
    pub body: u32,
    /// Which displacement components are prescribed (first D entries used).
    pub fixed: [bool; 3],
    /// Prescribed displacement of the fixed components at full load (zero: held).
    pub displacement: [f64; 3],
    /// Only the body's points that started with min ≤ x ≤ max (per axis, to within 1e-9 of
    /// a cell), if given: the same points at every step, wherever they go.
    pub within: Option<([f64; 3], [f64; 3])>,
}

impl BodyConstraint {
    /// Hold the `fixed` components of the nodes the points of `body` reach at zero.
    pub fn new(body: u32, fixed: [bool; 3]) -> Self {
        Self { body, fixed, displacement: [0.0; 3], within: None }
    }

    /// Prescribe `displacement` (at full load) on the fixed components instead of zero.
    pub fn displaced(mut self, displacement: [f64; 3]) -> Self {
        self.displacement = displacement;
        self
    }

    /// Only the body's points that start inside the box [min, max].
    pub fn within(mut self, min: [f64; 3], max: [f64; 3]) -> Self {
        self.within = Some((min, max));
        self
    }

    /// Whether the constraint prescribes a non-zero displacement.
    pub fn is_displaced(&self) -> bool {
        displaces(&self.fixed, &self.displacement)
    }
}

/// Whether `displacement` is non-zero on some `fixed` component: a constraint that moves
/// its nodes, not one that holds them.
fn displaces(fixed: &[bool; 3], displacement: &[f64; 3]) -> bool {
    displacement.iter().zip(fixed).any(|(d, &f)| f && *d != 0.0)
}

/// A roller on an inclined plane (a slope's base, a tilted wall): every active node on the
/// plane or beyond it (on the side away from the material, to within 1e-9 of a cell) is
/// held along the plane's normal and free along the plane, in a local frame at the node
/// whose first axis is the normal (docs/theory.md §5).
#[derive(Debug, Clone, PartialEq)]
pub struct InclinedRoller<const D: usize> {
    point: SVector<f64, D>,
    normal: SVector<f64, D>,
}

impl<const D: usize> InclinedRoller<D> {
    /// The plane through `point` with normal `normal` pointing into the material (scaled
    /// to unit length); refused unless both are finite and the normal is not zero.
    pub fn new(point: SVector<f64, D>, normal: SVector<f64, D>) -> Result<Self, String> {
        let length = normal.norm();
        if !(point.iter().chain(normal.iter()).all(|v| v.is_finite()) && length > 0.0) {
            return Err("the plane needs a finite point and a finite, non-zero normal".into());
        }
        Ok(Self { point, normal: normal / length })
    }

    pub fn point(&self) -> &SVector<f64, D> {
        &self.point
    }

    /// The unit normal, into the material.
    pub fn normal(&self) -> &SVector<f64, D> {
        &self.normal
    }

    /// Whether a node at `x` is held: on the plane or beyond it, to within `tolerance`.
    pub fn holds(&self, x: &SVector<f64, D>, tolerance: f64) -> bool {
        (x - self.point).dot(&self.normal) <= tolerance
    }

    /// The local frame at a held node: an orthonormal basis, its first column the normal,
    /// then the tangents (in 3D the first tangent across the coordinate axis least aligned
    /// with the normal).
    pub fn frame(&self) -> SMatrix<f64, D, D> {
        let n = self.normal;
        let mut q = SMatrix::<f64, D, D>::zeros();
        q.set_column(0, &n);
        match D {
            2 => q.set_column(1, &SVector::from_fn(|i, _| if i == 0 { -n[1] } else { n[0] })),
            3 => {
                let n3 = nalgebra::Vector3::new(n[0], n[1], n[2]);
                let least = (0..3).min_by(|&a, &b| n3[a].abs().total_cmp(&n3[b].abs())).unwrap_or(0);
                let t1 = n3.cross(&nalgebra::Vector3::ith(least, 1.0)).normalize();
                let t2 = n3.cross(&t1);
                q.set_column(1, &SVector::from_fn(|i, _| t1[i]));
                q.set_column(2, &SVector::from_fn(|i, _| t2[i]));
            }
            _ => {}
        }
        q
    }
}

/// A rigid plane with Coulomb friction (a rough base, a wall the material runs into;
/// docs/theory.md §5): at every node on the plane or beyond it (the nodes an inclined
/// roller there would hold), a grid velocity that moves into the plane loses its normal
/// component, and its tangential component loses μ times the normal component lost, down
/// to zero (stick); a velocity that leaves the plane is free (the material separates).
#[derive(Debug, Clone, PartialEq)]
pub struct FrictionalPlane<const D: usize> {
    /// The plane and its normal into the material.
    plane: InclinedRoller<D>,
    friction: f64,
}

impl<const D: usize> FrictionalPlane<D> {
    /// The plane through `point` with `normal` into the material and Coulomb coefficient
    /// `friction` (0: smooth); refused unless the plane is finite with a non-zero normal and
    /// the coefficient finite and not negative.
    pub fn new(point: SVector<f64, D>, normal: SVector<f64, D>, friction: f64) -> Result<Self, String> {
        check_friction(friction)?;
        Ok(Self { plane: InclinedRoller::new(point, normal)?, friction })
    }

    /// The plane (point and unit normal into the material).
    pub fn plane(&self) -> &InclinedRoller<D> {
        &self.plane
    }

    /// The Coulomb coefficient μ.
    pub fn friction(&self) -> f64 {
        self.friction
    }
}

/// A Coulomb coefficient is finite and not negative (a plane's, a rigid body's).
pub(crate) fn check_friction(friction: f64) -> Result<(), String> {
    match friction.is_finite() && friction >= 0.0 {
        true => Ok(()),
        false => Err(format!("a friction coefficient must be finite and ≥ 0, not {friction}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};

    /// The frame is orthonormal with the normal first, in 2D and 3D; the held side is the
    /// one away from the material.
    #[test]
    fn the_local_frame_is_orthonormal_with_the_normal_first() {
        let roller = InclinedRoller::new(Vector2::new(1.0, 0.0), Vector2::new(-1.0, 3f64.sqrt())).unwrap();
        let q = roller.frame();
        assert!((q.transpose() * q - nalgebra::Matrix2::identity()).norm() < 1e-15);
        assert_eq!(q.column(0).into_owned(), *roller.normal());
        assert!(roller.holds(&Vector2::new(2.0, 0.0), 0.0) && !roller.holds(&Vector2::new(0.0, 1.0), 0.0));
        let roller = InclinedRoller::new(Vector3::zeros(), Vector3::new(0.2, -0.5, 1.0)).unwrap();
        let q = roller.frame();
        assert!((q.transpose() * q - nalgebra::Matrix3::identity()).norm() < 1e-15);
        assert!((q.column(0) - roller.normal()).norm() < 1e-16);
        assert!(InclinedRoller::new(Vector2::zeros(), Vector2::zeros()).is_err());
    }
}
