//! The boundary of a shape as a surface of facets, on which surface loads act: segments in
//! 2D, triangles in 3D, each oriented so that its area vector points out of the shape
//! (docs/theory.md §17). The shape's edges are cut into pieces at most `spacing` long (a
//! triangle's diagonal is up to √2 times that, a cube-sphere's arcs up to about 1.3 times),
//! so a load sampled at the vertices resolves the grid the way the material points do.

use crate::{PointsError, Shape};
use nalgebra::{SVector, Vector2, Vector3};

/// A surface: vertices and facets of D vertex indices each (2D: segment a → b with the
/// outside on its right; 3D: triangle a, b, c counter-clockwise seen from outside).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Surface<const D: usize> {
    pub vertices: Vec<SVector<f64, D>>,
    pub facets: Vec<[u32; D]>,
}

/// The area vector of the facet with vertices `x` (length: its length in 2D, per unit
/// thickness, or its area in 3D; direction: its outward normal).
pub fn area_vector<const D: usize>(x: &[SVector<f64, D>; D]) -> SVector<f64, D> {
    match D {
        2 => {
            let e = x[1] - x[0];
            SVector::from_fn(|i, _| if i == 0 { e[1] } else { -e[0] })
        }
        3 => {
            let (a, b) = (x[1] - x[0], x[2] - x[0]);
            let c = Vector3::new(a[0], a[1], a[2]).cross(&Vector3::new(b[0], b[1], b[2])) * 0.5;
            SVector::from_fn(|i, _| c[i])
        }
        _ => unreachable!("surfaces exist in 2D and 3D"),
    }
}

impl<const D: usize> Surface<D> {
    /// The facets whose centroid satisfies `keep`, with only the vertices they use.
    pub fn select(&self, keep: impl Fn(&SVector<f64, D>) -> bool) -> Surface<D> {
        let mut map = vec![u32::MAX; self.vertices.len()];
        let mut out = Surface::default();
        for f in &self.facets {
            let centroid = f.iter().map(|&v| self.vertices[v as usize]).sum::<SVector<f64, D>>() / D as f64;
            if !keep(&centroid) {
                continue;
            }
            out.facets.push(f.map(|v| {
                if map[v as usize] == u32::MAX {
                    map[v as usize] = out.vertices.len() as u32;
                    out.vertices.push(self.vertices[v as usize]);
                }
                map[v as usize]
            }));
        }
        out
    }

    /// The vertices of facet `f`.
    pub fn facet(&self, f: usize) -> [SVector<f64, D>; D] {
        self.facets[f].map(|v| self.vertices[v as usize])
    }

    /// Σ of the facets' area vectors (zero for a closed surface).
    pub fn total_area_vector(&self) -> SVector<f64, D> {
        (0..self.facets.len()).map(|f| area_vector(&self.facet(f))).sum()
    }

    /// Append a chain of straight 2D edges through `corners` (closed when `closed`), each
    /// edge cut into pieces at most `spacing` long.
    fn push_chain(&mut self, corners: &[SVector<f64, D>], closed: bool, spacing: f64) {
        let first = self.vertices.len() as u32;
        let edges = if closed { corners.len() } else { corners.len() - 1 };
        for e in 0..edges {
            let (a, b) = (corners[e], corners[(e + 1) % corners.len()]);
            let n = pieces((b - a).norm(), spacing);
            for k in 0..n {
                self.vertices.push(a + (b - a) * (k as f64 / n as f64));
            }
        }
        if !closed {
            self.vertices.push(corners[corners.len() - 1]);
        }
        let count = self.vertices.len() as u32 - first;
        let segments = if closed { count } else { count - 1 };
        for k in 0..segments {
            let (a, b) = (first + k, first + (k + 1) % count);
            self.facets.push(std::array::from_fn(|i| if i == 0 { a } else { b }));
        }
    }

    /// Append the 3D quadrilateral patch x(s, t) = map(s, t), s, t ∈ [0, 1], cut into
    /// `n[0]` × `n[1]` quads of two triangles each, oriented by ∂x/∂s × ∂x/∂t.
    fn push_patch(&mut self, n: [usize; 2], map: impl Fn(f64, f64) -> SVector<f64, D>) {
        let first = self.vertices.len() as u32;
        for j in 0..=n[1] {
            for i in 0..=n[0] {
                self.vertices.push(map(i as f64 / n[0] as f64, j as f64 / n[1] as f64));
            }
        }
        let at = |i: usize, j: usize| first + (j * (n[0] + 1) + i) as u32;
        for j in 0..n[1] {
            for i in 0..n[0] {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                self.facets.push(std::array::from_fn(|k| [a, b, c][k]));
                self.facets.push(std::array::from_fn(|k| [a, c, d][k]));
            }
        }
    }
}

/// Pieces of at most `spacing` along a length (at least one).
fn pieces(length: f64, spacing: f64) -> usize {
    ((length / spacing) * (1.0 - 1e-12)).ceil().max(1.0) as usize
}

impl<const D: usize> Shape<D> {
    /// The boundary of the shape, facets at most `spacing` on a side, area vectors outward.
    /// A polygon's vertices may run either way round.
    pub fn boundary(&self, spacing: f64) -> Result<Surface<D>, PointsError> {
        let (lo, hi) = self.bounds()?;
        if !(spacing.is_finite() && spacing > 0.0) {
            return Err(PointsError::Spacing(spacing));
        }
        let facets = self.facet_estimate(&lo, &hi, spacing);
        if facets.is_nan() || facets > MAX_FACETS {
            return Err(PointsError::TooManyFacets { facets, spacing });
        }
        let mut s = Surface::default();
        match (self, D) {
            (Shape::Box { .. }, 2) => {
                let c = |x: f64, y: f64| SVector::from_fn(|i, _| if i == 0 { x } else { y });
                s.push_chain(&[c(lo[0], lo[1]), c(hi[0], lo[1]), c(hi[0], hi[1]), c(lo[0], hi[1])], true, spacing);
            }
            (Shape::Box { .. }, _) => box_faces(&mut s, &lo, &hi, spacing),
            (Shape::Polygon(v), _) => {
                let mut corners: Vec<SVector<f64, D>> = v.iter().map(|p| SVector::from_fn(|i, _| p[i])).collect();
                if signed_area(v) < 0.0 {
                    corners.reverse(); // walk counter-clockwise: the outside on the right
                }
                s.push_chain(&corners, true, spacing);
            }
            (Shape::Ball { centre, radius }, 2) => {
                let n = pieces(2.0 * std::f64::consts::PI * radius, spacing).max(8);
                let corners: Vec<SVector<f64, D>> = (0..n)
                    .map(|k| {
                        let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
                        centre + SVector::from_fn(|i, _| radius * if i == 0 { t.cos() } else { t.sin() })
                    })
                    .collect();
                s.push_chain(&corners, true, spacing);
            }
            (Shape::Prism { .. }, _) => return Err(PointsError::NoSurface("Prism")),
            (Shape::CutBox { .. }, _) => return Err(PointsError::NoSurface("CutBox")),
            (Shape::Ball { centre, radius }, _) => {
                // The cube's faces pushed out onto the sphere (a cube-sphere), the cube cut
                // finely enough that the arcs are at most `spacing`.
                let n = pieces(std::f64::consts::FRAC_PI_2 * radius, spacing);
                let mut cube = Surface::<D>::default();
                box_faces(&mut cube, &SVector::repeat(-1.0), &SVector::repeat(1.0), 2.0 / n as f64);
                for x in &mut cube.vertices {
                    *x = centre + *x * (*radius / x.norm());
                }
                s = cube;
            }
        }
        Ok(s)
    }
}

impl<const D: usize> Shape<D> {
    /// About how many facets of at most `spacing` the boundary takes, for a shape with the
    /// bounds `lo`, `hi` (before any is made: a mistyped vertex at 1e9 used to make
    /// `loam check` cut a billion-long edge into pieces).
    fn facet_estimate(&self, lo: &SVector<f64, D>, hi: &SVector<f64, D>, spacing: f64) -> f64 {
        let e = hi - lo;
        match (self, D) {
            (Shape::Box { .. }, 2) => 2.0 * (e[0] + e[1]) / spacing,
            (Shape::Box { .. }, _) => 4.0 * (e[0] * e[1] + e[1] * e[2] + e[2] * e[0]) / (spacing * spacing),
            (Shape::Polygon(v), _) => (0..v.len()).map(|i| (v[(i + 1) % v.len()] - v[i]).norm()).sum::<f64>() / spacing,
            (Shape::Ball { radius, .. }, 2) => 2.0 * std::f64::consts::PI * radius / spacing,
            (Shape::Ball { radius, .. }, _) => 12.0 * (std::f64::consts::FRAC_PI_2 * radius / spacing).powi(2),
            (Shape::Prism { .. } | Shape::CutBox { .. }, _) => 0.0,
        }
    }
}

/// The most facets a boundary may have (about 0.6 GB of them).
const MAX_FACETS: f64 = 1e7;

/// Twice the signed area of a polygon (positive counter-clockwise).
fn signed_area(v: &[Vector2<f64>]) -> f64 {
    (0..v.len()).map(|i| v[i].perp(&v[(i + 1) % v.len()])).sum()
}

/// The six faces of the 3D box [lo, hi], outward.
fn box_faces<const D: usize>(s: &mut Surface<D>, lo: &SVector<f64, D>, hi: &SVector<f64, D>, spacing: f64) {
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        let n = [pieces(hi[u] - lo[u], spacing), pieces(hi[v] - lo[v], spacing)];
        for (at, outward) in [(lo[axis], false), (hi[axis], true)] {
            // (u, v, axis) is right-handed: ∂x/∂s × ∂x/∂t points along +axis; swap s and t
            // on the low face.
            s.push_patch(n, |a, b| {
                let (a, b) = if outward { (a, b) } else { (b, a) };
                let mut x = SVector::zeros();
                x[axis] = at;
                x[u] = lo[u] + a * (hi[u] - lo[u]);
                x[v] = lo[v] + b * (hi[v] - lo[v]);
                x
            });
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Vector2, Vector3};

    /// A closed surface has zero total area vector, and its outward area vectors give the
    /// enclosed volume by the divergence theorem: V = Σ_f a_f · x̄_f / D.
    fn enclosed<const D: usize>(s: &Surface<D>) -> (f64, f64) {
        let mut volume = 0.0;
        for f in 0..s.facets.len() {
            let x = s.facet(f);
            let centroid = x.iter().sum::<SVector<f64, D>>() / D as f64;
            volume += area_vector(&x).dot(&centroid) / D as f64;
        }
        (s.total_area_vector().norm(), volume)
    }

    /// A polygon with a vertex mistyped to 1e9 is refused before any facet is made; the
    /// estimate of a 2D box is its perimeter over the spacing.
    #[test]
    fn a_boundary_of_too_many_facets_is_refused() {
        let spike = Shape::<2>::Polygon(vec![Vector2::new(0.0, 0.0), Vector2::new(1e9, 0.5), Vector2::new(0.0, 1.0)]);
        match spike.boundary(0.0625) {
            Err(PointsError::TooManyFacets { facets, .. }) => assert_relative_eq!(facets, 3.2e10, max_relative = 1e-6),
            other => panic!("{other:?}"),
        }
        let b = Shape::<2>::Box { min: Vector2::zeros(), max: Vector2::new(2.0, 1.0) };
        assert_eq!(b.facet_estimate(&Vector2::zeros(), &Vector2::new(2.0, 1.0), 0.5), 12.0);
        assert_eq!(b.boundary(0.5).unwrap().facets.len(), 12);
    }

    #[test]
    fn box_boundaries_are_closed_and_outward() {
        let b2 = Shape::Box { min: Vector2::new(1.0, 2.0), max: Vector2::new(4.0, 3.0) }.boundary(0.5).unwrap();
        assert_eq!(b2.facets.len(), 2 * (6 + 2));
        let (open, volume) = enclosed(&b2);
        assert!(open < 1e-14);
        assert_relative_eq!(volume, 3.0, epsilon = 1e-12);
        // The top edge's area vectors point up, with length equal to the edge.
        let top = b2.select(|c| c[1] > 2.99);
        assert_relative_eq!(top.total_area_vector(), Vector2::new(0.0, 3.0), epsilon = 1e-14);
        let b3 =
            Shape::Box { min: Vector3::new(0.0, 0.0, 0.0), max: Vector3::new(1.0, 2.0, 0.5) }.boundary(0.3).unwrap();
        let (open, volume) = enclosed(&b3);
        assert!(open < 1e-13);
        assert_relative_eq!(volume, 1.0, epsilon = 1e-12);
        let top = b3.select(|c| c[1] > 1.99);
        assert_relative_eq!(top.total_area_vector(), Vector3::new(0.0, 0.5, 0.0), epsilon = 1e-14);
    }

    #[test]
    fn polygons_either_way_round_and_balls_point_out() {
        let ccw = vec![Vector2::new(0.0, 0.0), Vector2::new(2.0, 0.0), Vector2::new(0.0, 2.0)];
        for v in [ccw.clone(), ccw.into_iter().rev().collect()] {
            let s = Shape::<2>::Polygon(v).boundary(0.25).unwrap();
            let (open, area) = enclosed(&s);
            assert!(open < 1e-14);
            assert_relative_eq!(area, 2.0, epsilon = 1e-12);
            assert!(s.facets.iter().enumerate().all(|(f, _)| (0..2).all(|i| {
                let x = s.facet(f)[i];
                (x - Vector2::new(0.0, 0.0)).norm() <= 2.0 + 1e-12
            })));
        }
        // A disk's polygon underestimates πr² by O(h²); a sphere's cube-sphere likewise.
        let disk = Shape::Ball { centre: Vector2::new(1.0, 1.0), radius: 1.0 }.boundary(0.05).unwrap();
        let (open, area) = enclosed(&disk);
        assert!(open < 1e-12);
        assert!((area - std::f64::consts::PI).abs() < 2e-3, "area {area}");
        let ball = Shape::Ball { centre: Vector3::new(0.0, 0.0, 0.0), radius: 1.0 }.boundary(0.1).unwrap();
        let (open, volume) = enclosed(&ball);
        assert!(open < 1e-12);
        assert!((volume - 4.0 / 3.0 * std::f64::consts::PI).abs() < 0.03, "volume {volume}");
    }
}
