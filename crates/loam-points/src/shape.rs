//! The regions of space that points fill.

use crate::PointsError;
use nalgebra::{SVector, Vector2};

/// A region of space that points fill.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape<const D: usize> {
    /// Axis-aligned box.
    Box { min: SVector<f64, D>, max: SVector<f64, D> },
    /// Simple polygon (2D only), vertices in order.
    Polygon(Vec<Vector2<f64>>),
    /// Disk (2D) or ball (3D).
    Ball { centre: SVector<f64, D>, radius: f64 },
    /// 3D only: the simple polygon `section`, in the coordinates of the two axes other than
    /// `axis` (in increasing axis order), extruded along `axis` from `from` to `to`. A
    /// slope's cross-section extruded across its width.
    Prism { section: Vec<Vector2<f64>>, axis: usize, from: f64, to: f64 },
    /// An axis-aligned box less the half-space beyond a plane: the points of the box with
    /// (x − point) · normal ≤ 0 (the normal points out of the material).
    CutBox { min: SVector<f64, D>, max: SVector<f64, D>, point: SVector<f64, D>, normal: SVector<f64, D> },
}

impl<const D: usize> Shape<D> {
    /// The shape's bounding box (min, max), or why the shape is not valid.
    pub fn bounds(&self) -> Result<(SVector<f64, D>, SVector<f64, D>), PointsError> {
        match self {
            Shape::Box { min, max } => {
                if (0..D).any(|a| min[a].partial_cmp(&max[a]) != Some(std::cmp::Ordering::Less)) {
                    return Err(PointsError::BoxOrder {
                        min: min.iter().copied().collect(),
                        max: max.iter().copied().collect(),
                    });
                }
                Ok((*min, *max))
            }
            Shape::Ball { centre, radius } => {
                if !(radius.is_finite() && *radius > 0.0) {
                    return Err(PointsError::Radius(*radius));
                }
                Ok((centre.add_scalar(-radius), centre.add_scalar(*radius)))
            }
            Shape::CutBox { min, max, point, normal } => {
                let ok = point.iter().chain(normal.iter()).all(|v| v.is_finite()) && normal.norm() > 0.0;
                if !ok {
                    return Err(PointsError::CutPlane);
                }
                Shape::Box { min: *min, max: *max }.bounds()
            }
            Shape::Prism { section, axis, from, to } => {
                if D != 3 || *axis > 2 || !(from < to && from.is_finite() && to.is_finite()) {
                    return Err(PointsError::Prism { axis: *axis, from: *from, to: *to });
                }
                let (lo2, hi2) = Shape::<2>::Polygon(section.clone()).bounds()?;
                let (a, b) = prism_section_axes(*axis);
                let mut lo = SVector::<f64, D>::zeros();
                let mut hi = SVector::<f64, D>::zeros();
                (lo[a], lo[b], lo[*axis]) = (lo2[0], lo2[1], *from);
                (hi[a], hi[b], hi[*axis]) = (hi2[0], hi2[1], *to);
                Ok((lo, hi))
            }
            Shape::Polygon(v) => {
                if D != 2 {
                    return Err(PointsError::PolygonDimension);
                }
                if v.len() < 3 {
                    return Err(PointsError::Polygon(v.len()));
                }
                let mut lo = SVector::<f64, D>::repeat(f64::INFINITY);
                let mut hi = SVector::<f64, D>::repeat(f64::NEG_INFINITY);
                for p in v {
                    for a in 0..2 {
                        lo[a] = lo[a].min(p[a]);
                        hi[a] = hi[a].max(p[a]);
                    }
                }
                Ok((lo, hi))
            }
        }
    }

    /// Whether `x` is inside (closed box; even–odd rule for polygons).
    pub fn contains(&self, x: &SVector<f64, D>) -> bool {
        match self {
            Shape::Box { min, max } => (0..D).all(|a| x[a] >= min[a] && x[a] <= max[a]),
            Shape::Ball { centre, radius } => (x - centre).norm() <= *radius,
            Shape::CutBox { min, max, point, normal } => {
                Shape::Box { min: *min, max: *max }.contains(x) && (x - point).dot(normal) <= 0.0
            }
            Shape::Prism { section, axis, from, to } => {
                let (a, b) = prism_section_axes(*axis);
                x[*axis] >= *from && x[*axis] <= *to && polygon_contains(section, x[a], x[b])
            }
            Shape::Polygon(v) => polygon_contains(v, x[0], x[1]),
        }
    }
}

/// Whether (px, py) is inside the polygon `v` (even–odd rule).
fn polygon_contains(v: &[Vector2<f64>], px: f64, py: f64) -> bool {
    let mut inside = false;
    let mut j = v.len() - 1;
    for i in 0..v.len() {
        let (xi, yi, xj, yj) = (v[i].x, v[i].y, v[j].x, v[j].y);
        if (yi > py) != (yj > py) && px < (xj - xi) * (py - yi) / (yj - yi) + xi {
            inside = !inside;
        }
        j = i;
    }
    inside
}

/// The two axes of a prism's section, in increasing order, for extrusion along `axis`.
fn prism_section_axes(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}
