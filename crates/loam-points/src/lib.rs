//! Material points: the struct-of-arrays store of everything a point carries between steps
//! (position, volume, mass, deformation gradient, elastic strain state, stress, GIMP domain,
//! material and history), and the generation of points from shapes.
//!
//! Points are generated at the centres of an n^D subdivision of every grid cell that the
//! shape covers (the usual MPM initialisation; Sulsky et al. 1994), each with the volume of
//! its sub-cell, so that the initial GIMP domains tile the body exactly. A shape's boundary,
//! where surface loads act, is a [`Surface`] of facets.

mod surface;

pub use surface::{area_vector, Surface};

use loam_grid::{lexicographic_coords, Grid};
use nalgebra::{Matrix3, SVector, Vector2};

/// GIMP half-lengths of a deformed point, l = l₀ ⊙ diag(U) with U = √(FᵀF) the right
/// stretch (iGIMP, Charlton et al. 2017). In plane strain F is block-diagonal, so the
/// in-plane block of the 3×3 U is the in-plane stretch, the square root of the 2 × 2
/// C = FᵀF in closed form (Cayley–Hamilton): √C = (C + s I) / √(tr C + 2s), s = √det C =
/// |det F|; in 3D in closed form too ([`right_stretch_diagonal`]).
#[inline]
pub fn stretched_half_length<const D: usize>(l0: &SVector<f64, D>, f: &Matrix3<f64>) -> SVector<f64, D> {
    let plane = D == 2 && f[(0, 2)] == 0.0 && f[(1, 2)] == 0.0 && f[(2, 0)] == 0.0 && f[(2, 1)] == 0.0;
    if plane {
        let c = f.fixed_view::<2, 2>(0, 0).transpose() * f.fixed_view::<2, 2>(0, 0);
        let s = (f[(0, 0)] * f[(1, 1)] - f[(0, 1)] * f[(1, 0)]).abs();
        let t = (c.trace() + 2.0 * s).sqrt();
        // t = 0 only for F = 0 in the plane, which no valid state reaches: U = 0 then.
        return SVector::from_fn(|i, _| if t > 0.0 { l0[i] * (c[(i, i)] + s) / t } else { 0.0 });
    }
    let u = right_stretch_diagonal(f);
    SVector::from_fn(|i, _| l0[i] * u[i])
}

/// [`stretched_half_length`] of `N` points at once, each bit for bit its own: in 3D the
/// stretches in lanes ([`right_stretch_diagonals`]), whose chains overlap.
#[inline]
pub fn stretched_half_lengths<const D: usize, const N: usize>(
    l0: [&SVector<f64, D>; N],
    f: [&Matrix3<f64>; N],
) -> [SVector<f64, D>; N] {
    if D == 2 {
        return std::array::from_fn(|k| stretched_half_length(l0[k], f[k]));
    }
    let u = right_stretch_diagonals(f);
    std::array::from_fn(|k| SVector::from_fn(|i, _| l0[k][i] * u[k][i]))
}

/// The diagonal of the right stretch U = √C, C = FᵀF, of a 3 × 3 F, in closed form. By
/// Cayley–Hamilton for U, U³ − I U² + II U − III 1 = 0, so U (C + II 1) = I C + III 1 and
/// U = (C + II 1)⁻¹ (I C + III 1) (Hoger & Carlson 1984), I, II, III the invariants of U.
/// They come from those of C, each a sum of squares and so exact to round-off —
/// I_C = |F|², II_C = |cof F|² (Cauchy–Binet), III_C = det² F — and C's largest eigenvalue
/// λ₁ (the trigonometric solution of its cubic, Smith 1961, free of cancellation for the
/// largest root): the other two have λ₂λ₃ = III_C/λ₁ and λ₂ + λ₃ = (II_C − λ₂λ₃)/λ₁, so
/// √λ₂ + √λ₃ = (λ₂ + λ₃ + 2√(λ₂λ₃))^½ and √λ₂√λ₃ = √(λ₂λ₃) without forming either, and a
/// small stretch beside a large one keeps its digits. Where λ₁ nearly equals λ₂ the
/// trigonometric λ₁ is placed only to about √ε, but the pair it implies keeps I_C to second
/// order, so the invariants do too. C + II 1 is as well conditioned as
/// (λ_max + II)/(λ_min + II), tens for a stretch ratio of 800. The diagonal agrees with that
/// of an eigen-decomposition to round-off (unit test) at a fraction of the cost of its QR
/// iterations, which were a quarter of the 3D explicit step.
#[inline]
pub fn right_stretch_diagonal(f: &Matrix3<f64>) -> [f64; 3] {
    right_stretch_diagonals([f])[0]
}

/// [`right_stretch_diagonal`] of `N` deformation gradients at once, each lane bit for bit
/// the one-lane result (the one-lane case *is* that function). Every stage is computed for
/// all lanes before the next, so that the lanes' chains of roots, divisions, arc cosine and
/// cosine overlap: one stretch alone leaves the processor waiting on each link.
#[inline]
pub fn right_stretch_diagonals<const N: usize>(f: [&Matrix3<f64>; N]) -> [[f64; 3]; N] {
    let c: [Matrix3<f64>; N] = std::array::from_fn(|k| f[k].transpose() * f[k]);
    let i_c = lanes::<N>(|k| f[k].norm_squared());
    let cofactor: [Matrix3<f64>; N] = std::array::from_fn(|k| {
        Matrix3::from_fn(|i, j| {
            let (r0, r1) = ((i + 1) % 3, (i + 2) % 3);
            let (c0, c1) = ((j + 1) % 3, (j + 2) % 3);
            f[k][(r0, c0)] * f[k][(r1, c1)] - f[k][(r0, c1)] * f[k][(r1, c0)]
        })
    });
    let ii_c = lanes::<N>(|k| cofactor[k].norm_squared());
    // det F by the cofactors of its first row, already formed for II_C.
    let det = lanes::<N>(|k| f[k].row(0).dot(&cofactor[k].row(0)).abs());
    let q = lanes::<N>(|k| i_c[k] / 3.0);
    let p = lanes::<N>(|k| {
        let c = &c[k];
        let off = c[(0, 1)] * c[(0, 1)] + c[(0, 2)] * c[(0, 2)] + c[(1, 2)] * c[(1, 2)];
        let dev = |i: usize| c[(i, i)] - q[k];
        ((dev(0) * dev(0) + dev(1) * dev(1) + dev(2) * dev(2) + 2.0 * off) / 6.0).sqrt()
    });
    let half_det_b = lanes::<N>(|k| {
        let b = (c[k] - Matrix3::from_diagonal_element(q[k])) * (1.0 / p[k]);
        (0.5 * b.determinant()).clamp(-1.0, 1.0)
    });
    let angle = lanes::<N>(|k| half_det_b[k].acos() / 3.0);
    let l1 = lanes::<N>(|k| if p[k] > 0.0 { q[k] + 2.0 * p[k] * angle[k].cos() } else { q[k] });
    std::array::from_fn(|k| {
        // λ₁ = 0 only for F = 0, which no valid state reaches: U's diagonal is then 0 (as
        // the plane form takes it).
        if l1[k] <= 0.0 {
            return [0.0; 3];
        }
        let product = det[k] * det[k] / l1[k];
        let sum = ((ii_c[k] - product) / l1[k]).max(0.0);
        let (s1, s23) = (l1[k].sqrt(), product.sqrt());
        let s2_plus_s3 = (sum + 2.0 * s23).sqrt();
        let (i_u, ii_u) = (s1 + s2_plus_s3, s1 * s2_plus_s3 + s23);
        // C + II 1 is singular only for II = 0, F of rank ≤ 1 (as above).
        let Some(inverse) = (c[k] + Matrix3::from_diagonal_element(ii_u)).try_inverse() else {
            return [0.0; 3];
        };
        let n = c[k] * i_u + Matrix3::from_diagonal_element(det[k]);
        std::array::from_fn(|i| inverse.row(i).dot(&n.column(i).transpose()))
    })
}

/// One number per lane.
#[inline(always)]
fn lanes<const N: usize>(value: impl FnMut(usize) -> f64) -> [f64; N] {
    std::array::from_fn(value)
}

/// Errors in generating points.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PointsError {
    #[error("points_per_cell is {0}; it must be between 1 and 8")]
    PointsPerCell(usize),
    #[error("density is {0}; it must be a positive finite number")]
    Density(f64),
    #[error("the shape contains no point centre: it is empty or thinner than a sub-cell ({0})")]
    EmptyRegion(String),
    #[error("the shape reaches outside the grid: a point would sit at {position:?}, grid spans {min:?} to {max:?}")]
    OutsideGrid { position: Vec<f64>, min: Vec<f64>, max: Vec<f64> },
    #[error("the shape reaches outside the grid: its bounds are {lo:?} to {hi:?}, the grid spans {min:?} to {max:?}")]
    BeyondGrid { lo: Vec<f64>, hi: Vec<f64>, min: Vec<f64>, max: Vec<f64> },
    #[error("a polygon needs at least 3 vertices, got {0}")]
    Polygon(usize),
    #[error("a ball's radius is {0}; it must be a positive number")]
    Radius(f64),
    #[error("the spacing of a surface's facets is {0}; it must be a positive number")]
    Spacing(f64),
    #[error("a polygon is only defined in 2D")]
    PolygonDimension,
    #[error("a prism is only defined in 3D, extruded along axis 0, 1 or 2 (got {axis}) from a coordinate below the one it goes to (got {from} to {to})")]
    Prism { axis: usize, from: f64, to: f64 },
    #[error("a cut box needs a finite point and a finite, non-zero normal")]
    CutPlane,
    #[error("surfaces (for loads) are not available on a {0} yet: give the loaded part its own Box body")]
    NoSurface(&'static str),
    #[error("the boundary would need about {facets:.1e} facets of at most {spacing} (more than 1e7): is a vertex or size mistyped?")]
    TooManyFacets { facets: f64, spacing: f64 },
    #[error("box min {min:?} is not below max {max:?} on every axis")]
    BoxOrder { min: Vec<f64>, max: Vec<f64> },
    #[error("the store holds {points} points but {found} values of `{field}`; every field needs one per point")]
    FieldLength { field: &'static str, points: usize, found: usize },
    #[error("point {point}: {what}")]
    Point { point: usize, what: String },
}

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
    fn bounds(&self) -> Result<(SVector<f64, D>, SVector<f64, D>), PointsError> {
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

/// Struct-of-arrays store of material points. Each field holds one entry per point.
#[derive(Debug, Clone, Default)]
pub struct PointStore<const D: usize> {
    /// Current position x_p.
    pub position: Vec<SVector<f64, D>>,
    /// Initial position X_p.
    pub position0: Vec<SVector<f64, D>>,
    /// Current volume v_p.
    pub volume: Vec<f64>,
    /// Initial volume V_p.
    pub volume0: Vec<f64>,
    /// Mass (constant).
    pub mass: Vec<f64>,
    /// Velocity v_p (dynamic analyses; zero and unused in quasi-static ones).
    pub velocity: Vec<SVector<f64, D>>,
    /// Acceleration a_p (implicit Newmark dynamics).
    pub acceleration: Vec<SVector<f64, D>>,
    /// Deformation gradient F (3×3 also in plane strain, where F_zz = 1).
    pub deformation_gradient: Vec<Matrix3<f64>>,
    /// Elastic strain state: b^e (finite strain, identity when unstrained) or ε^e (small
    /// strain, zero when unstrained). The analysis sets which when it starts.
    pub elastic_strain: Vec<Matrix3<f64>>,
    /// Cauchy stress σ (3×3; σ_zz of plane strain included). Tension positive.
    pub stress: Vec<Matrix3<f64>>,
    /// Initial GIMP domain half-lengths l_p0.
    pub half_length0: Vec<SVector<f64, D>>,
    /// Current GIMP domain half-lengths l_p = l_p0 ⊙ diag(U) (iGIMP).
    pub half_length: Vec<SVector<f64, D>>,
    /// Material index per point.
    pub material: Vec<u32>,
    /// Per-point history variables of the material, `history_stride` per point.
    pub history: Vec<f64>,
    history_stride: usize,
}

impl<const D: usize> PointStore<D> {
    pub fn new() -> Self {
        Self::default()
    }

    pub fn len(&self) -> usize {
        self.position.len()
    }

    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    pub fn history_stride(&self) -> usize {
        self.history_stride
    }

    /// History slice of point `p`.
    pub fn history(&self, p: usize) -> &[f64] {
        &self.history[p * self.history_stride..(p + 1) * self.history_stride]
    }

    /// Size the history buffer to `stride` values per point and let `init` set each
    /// point's initial history.
    pub fn init_history(&mut self, stride: usize, mut init: impl FnMut(usize, &mut [f64])) {
        self.history_stride = stride;
        self.history.clear();
        self.history.resize(stride * self.len(), 0.0);
        if stride > 0 {
            for (p, h) in self.history.chunks_mut(stride).enumerate() {
                init(p, h);
            }
        }
    }

    /// Set every point's elastic strain state (identity for b^e, zero for ε^e).
    pub fn reset_elastic_strain(&mut self, value: Matrix3<f64>) {
        self.elastic_strain.iter_mut().for_each(|e| *e = value);
    }

    /// Total mass.
    pub fn total_mass(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Linear momentum Σ m_p v_p.
    pub fn momentum(&self) -> SVector<f64, D> {
        self.mass.iter().zip(&self.velocity).map(|(m, v)| v * *m).sum()
    }

    /// The largest distance a point has moved from its initial position.
    pub fn max_displacement(&self) -> f64 {
        self.position.iter().zip(&self.position0).map(|(x, x0)| (x - x0).norm()).fold(0.0, f64::max)
    }

    /// Check what every user of the store indexes: one value of every field per point, and
    /// each point's position, volume and mass finite, volume and mass positive, velocity
    /// finite.
    pub fn check(&self) -> Result<(), PointsError> {
        let n = self.len();
        let lengths = [
            ("position0", self.position0.len()),
            ("volume", self.volume.len()),
            ("volume0", self.volume0.len()),
            ("mass", self.mass.len()),
            ("velocity", self.velocity.len()),
            ("acceleration", self.acceleration.len()),
            ("deformation_gradient", self.deformation_gradient.len()),
            ("elastic_strain", self.elastic_strain.len()),
            ("stress", self.stress.len()),
            ("half_length0", self.half_length0.len()),
            ("half_length", self.half_length.len()),
            ("material", self.material.len()),
        ];
        if let Some(&(field, found)) = lengths.iter().find(|(_, len)| *len != n) {
            return Err(PointsError::FieldLength { field, points: n, found });
        }
        let bad = |point: usize, what: String| Err(PointsError::Point { point, what });
        for p in 0..n {
            if !(self.position[p].iter().chain(self.velocity[p].iter()).all(|c| c.is_finite())) {
                return bad(p, "its position and velocity must be finite".into());
            }
            let (v, m) = (self.volume[p], self.mass[p]);
            if !(v.is_finite() && v > 0.0 && m.is_finite() && m > 0.0) {
                return bad(p, format!("volume {v} and mass {m}; both must be positive and finite"));
            }
        }
        Ok(())
    }

    /// Kinetic energy ½ Σ m_p |v_p|².
    pub fn kinetic_energy(&self) -> f64 {
        0.5 * self.mass.iter().zip(&self.velocity).map(|(m, v)| m * v.norm_squared()).sum::<f64>()
    }

    /// Add one point.
    pub fn push(&mut self, x: SVector<f64, D>, volume: f64, density: f64, half_length: SVector<f64, D>, material: u32) {
        self.position.push(x);
        self.position0.push(x);
        self.volume.push(volume);
        self.volume0.push(volume);
        self.mass.push(density * volume);
        self.velocity.push(SVector::zeros());
        self.acceleration.push(SVector::zeros());
        self.deformation_gradient.push(Matrix3::identity());
        self.elastic_strain.push(Matrix3::identity());
        self.stress.push(Matrix3::zeros());
        self.half_length0.push(half_length);
        self.half_length.push(half_length);
        self.material.push(material);
        self.history.extend(std::iter::repeat_n(0.0, self.history_stride));
    }

    /// Fill `shape` with `points_per_cell`^D points per grid cell, at the centres of the
    /// sub-cells whose centre lies inside the shape. Returns the number of points added; a
    /// failing fill leaves the store unchanged.
    pub fn fill(
        &mut self,
        grid: &Grid<D>,
        shape: &Shape<D>,
        points_per_cell: usize,
        density: f64,
        material: u32,
    ) -> Result<usize, PointsError> {
        check_points_per_cell(points_per_cell)?;
        if !(density.is_finite() && density > 0.0) {
            return Err(PointsError::Density(density));
        }
        let n = points_per_cell;
        let sub = grid.cell_size() / n as f64;
        let volume = grid.cell_volume() / (n.pow(D as u32)) as f64;
        let new_points = sub_cell_centres(grid, shape, &sub)?;
        for &x in &new_points {
            self.push(x, volume, density, sub / 2.0, material);
        }
        Ok(new_points.len())
    }
}

/// The sub-cells of size `sub` (aligned with the grid) that cover `shape`'s bounding box:
/// the index of the first along each axis and their count along each axis; an error when
/// there is none.
fn sub_cell_range<const D: usize>(
    grid: &Grid<D>,
    shape: &Shape<D>,
    sub: &SVector<f64, D>,
) -> Result<([i64; D], [usize; D]), PointsError> {
    let (lo, hi) = shape.bounds()?;
    let origin = grid.origin();
    // Sub-cell index ranges covering the shape's bounding box. A box that reaches more than
    // one sub-cell beyond the grid is refused at once (the fill refuses any centre in the
    // layer just outside): a bounding box of 1e300 cells is never walked (it used to be, by
    // `loam check` on a mistyped cell size), and a shape that reaches out between centres
    // is not cut to the grid silently.
    let sub_cells = |a: usize| ((grid.extent_max()[a] - origin[a]) / sub[a]).round() as i64;
    let first: [i64; D] = std::array::from_fn(|a| ((lo[a] - origin[a]) / sub[a] - 0.5).ceil() as i64);
    let last: [i64; D] = std::array::from_fn(|a| ((hi[a] - origin[a]) / sub[a] - 0.5).floor() as i64);
    if (0..D).any(|a| first[a] < -1 || last[a] > sub_cells(a)) {
        return Err(PointsError::BeyondGrid {
            lo: lo.iter().copied().collect(),
            hi: hi.iter().copied().collect(),
            min: origin.iter().copied().collect(),
            max: grid.extent_max().iter().copied().collect(),
        });
    }
    if (0..D).any(|a| first[a] > last[a]) {
        return Err(PointsError::EmptyRegion(format!("bounds {:?} to {:?}", lo.as_slice(), hi.as_slice())));
    }
    Ok((first, std::array::from_fn(|a| (last[a] - first[a] + 1) as usize)))
}

/// How many points [`PointStore::fill`] would add, without allocating them: at most the
/// sub-cells of the shape's bounding box (`exact_up_to` `None`, no shape test), or exactly,
/// every centre tested but the count stopped at `exact_up_to` (a memory estimate only needs
/// to know that a limit is passed). Refuses what the fill refuses about `points_per_cell`.
pub fn fill_count<const D: usize>(
    grid: &Grid<D>,
    shape: &Shape<D>,
    points_per_cell: usize,
    exact_up_to: Option<u64>,
) -> Result<u64, PointsError> {
    check_points_per_cell(points_per_cell)?;
    let sub = grid.cell_size() / points_per_cell as f64;
    let (first, dims) = sub_cell_range(grid, shape, &sub)?;
    let Some(cap) = exact_up_to else { return Ok(dims.iter().fold(1u64, |n, &d| n.saturating_mul(d as u64))) };
    Ok(centres_in(grid, shape, first, dims, sub).take(cap.min(usize::MAX as u64) as usize).count() as u64)
}

/// Points per cell and axis, 1 to 8.
fn check_points_per_cell(points_per_cell: usize) -> Result<(), PointsError> {
    if points_per_cell == 0 || points_per_cell > 8 {
        return Err(PointsError::PointsPerCell(points_per_cell));
    }
    Ok(())
}

/// The centres of the sub-cells of the range `first`, `dims` (size `sub`, axis 0 fastest)
/// that lie inside `shape`.
fn centres_in<'a, const D: usize>(
    grid: &'a Grid<D>,
    shape: &'a Shape<D>,
    first: [i64; D],
    dims: [usize; D],
    sub: SVector<f64, D>,
) -> impl Iterator<Item = SVector<f64, D>> + 'a {
    let origin = grid.origin();
    (0..dims.iter().product())
        .map(move |k| {
            let ijk = lexicographic_coords(k, dims);
            SVector::from_fn(|a, _| origin[a] + ((first[a] + ijk[a] as i64) as f64 + 0.5) * sub[a])
        })
        .filter(|x| shape.contains(x))
}

/// The centres of the sub-cells of size `sub` (aligned with the grid) that lie inside
/// `shape`, axis 0 fastest; an error when there is none or one lies outside the grid.
fn sub_cell_centres<const D: usize>(
    grid: &Grid<D>,
    shape: &Shape<D>,
    sub: &SVector<f64, D>,
) -> Result<Vec<SVector<f64, D>>, PointsError> {
    let (lo, hi) = shape.bounds()?;
    let empty = || PointsError::EmptyRegion(format!("bounds {:?} to {:?}", lo.as_slice(), hi.as_slice()));
    let origin = grid.origin();
    let (first, dims) = sub_cell_range(grid, shape, sub)?;
    let mut centres = Vec::new();
    for x in centres_in(grid, shape, first, dims, *sub) {
        if !grid.contains(&x) {
            return Err(PointsError::OutsideGrid {
                position: x.iter().copied().collect(),
                min: origin.iter().copied().collect(),
                max: grid.extent_max().iter().copied().collect(),
            });
        }
        centres.push(x);
    }
    if centres.is_empty() {
        return Err(empty());
    }
    Ok(centres)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The diagonal of √(FᵀF) by the eigen-decomposition of FᵀF (nalgebra's symmetric QR),
    /// the tests' reference, and the largest principal stretch.
    fn reference_stretch(f: &Matrix3<f64>) -> (Vector3<f64>, f64) {
        let eig = (f.transpose() * f).symmetric_eigen();
        let s = eig.eigenvalues.map(|e| e.max(0.0).sqrt());
        let u = eig.eigenvectors * Matrix3::from_diagonal(&s) * eig.eigenvectors.transpose();
        (u.diagonal(), s.max())
    }

    /// The plane-strain closed form of √(FᵀF) gives the half-lengths of the 3D
    /// eigen-decomposition (the same F seen as a 3D one) to round-off: a stretch, a
    /// rotation with a stretch, a simple shear and a compression.
    #[test]
    fn the_plane_stretch_is_that_of_the_eigen_decomposition() {
        let l0 = Vector2::new(0.25, 0.5);
        let (c, s) = (0.6f64.cos(), 0.6f64.sin());
        for f in [
            Matrix3::new(1.2, 0.0, 0.0, 0.0, 0.9, 0.0, 0.0, 0.0, 1.0),
            Matrix3::new(1.3 * c, -0.8 * s, 0.0, 1.3 * s, 0.8 * c, 0.0, 0.0, 0.0, 1.0),
            Matrix3::new(1.0, 0.7, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            Matrix3::new(0.05, 0.01, 0.0, -0.02, 0.3, 0.0, 0.0, 0.0, 1.0),
        ] {
            let plane = stretched_half_length(&l0, &f);
            let l3 = Vector3::new(0.25, 0.5, 1.0).component_mul(&reference_stretch(&f).0);
            for i in 0..2 {
                assert!((plane[i] - l3[i]).abs() <= 1e-15 * l3[i].max(1e-3), "{f}: {plane} vs {l3}");
            }
        }
    }

    /// The closed-form diagonal of U = √(FᵀF) against that of the eigen-decomposition of FᵀF
    /// (nalgebra's symmetric QR, the reference), to 1e-13 relative to U's largest stretch (a
    /// diagonal entry of U is a weighted mean of the principal stretches and its absolute
    /// error is that of the largest; 1e-13 is a few hundred ε, the round-off of either
    /// method's dozens of operations: the worst of 2 000 random F measured 2.1e-14).
    fn assert_closed_form_stretch(f: &Matrix3<f64>) {
        let (u, largest) = reference_stretch(f);
        let got = right_stretch_diagonal(f);
        for i in 0..3 {
            assert!((got[i] - u[i]).abs() <= 1e-13 * largest, "{f}: {got:?} vs {u}");
        }
    }

    /// Rotated stretches with distinct, pairwise equal, all equal and widely spread
    /// principal stretches, a near-identity F, simple shears and a compression to 1 % of
    /// the volume (random F: the property test below).
    #[test]
    fn the_closed_form_stretch_is_that_of_the_eigen_decomposition() {
        let rotation = |a: f64, b: f64, c: f64| nalgebra::Rotation3::from_euler_angles(a, b, c).into_inner();
        let stretches = [
            [1.2, 0.9, 1.05],
            [1.0, 1.0, 1.0],
            [1.3, 1.3, 0.7],
            [0.8, 1.5, 1.5],
            [1.0 + 1e-9, 1.0, 1.0 - 1e-9],
            [40.0, 0.05, 1.0],
            [0.2, 0.25, 0.2],
        ];
        for (k, st) in stretches.iter().enumerate() {
            let (r, q) = (rotation(0.3 * k as f64, -0.7, 1.1), rotation(0.2, 0.5 * k as f64, -0.4));
            // F = R V Q with V diagonal: C = Qᵀ V² Q, principal stretches V.
            assert_closed_form_stretch(&(r * Matrix3::from_diagonal(&Vector3::from(*st)) * q));
            assert_closed_form_stretch(&Matrix3::from_diagonal(&Vector3::from(*st)));
        }
        assert_closed_form_stretch(&Matrix3::new(1.0, 0.7, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0));
        assert_closed_form_stretch(&Matrix3::new(1.0, 0.1, -0.3, 0.0, 1.0, 0.2, 0.0, 0.0, 1.0));
        let near_identity = Matrix3::new(1e-7, -2e-8, 3e-8, 1e-8, -5e-8, 0.0, 2e-9, 4e-8, 1e-8);
        assert_closed_form_stretch(&(Matrix3::identity() + near_identity));
    }

    /// Eight stretches computed together are each the one computed alone, to the last bit,
    /// whatever the other lanes hold: distinct, repeated (p = 0, which skips the arc
    /// cosine) and zero F, sheared and compressed ones; and the half-lengths likewise, in
    /// 3D and in plane strain.
    #[test]
    fn stretches_in_lanes_are_each_the_one_alone() {
        let lanes: [Matrix3<f64>; 8] = [
            Matrix3::new(1.2, 0.1, -0.3, 0.05, 0.9, 0.2, 0.0, -0.1, 1.05),
            Matrix3::identity() * 2.0,
            Matrix3::zeros(),
            Matrix3::new(1.0, 0.7, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            Matrix3::from_diagonal(&Vector3::new(40.0, 0.05, 1.0)),
            Matrix3::identity() + Matrix3::new(1e-7, -2e-8, 3e-8, 1e-8, -5e-8, 0.0, 2e-9, 4e-8, 1e-8),
            Matrix3::new(0.3, -0.2, 0.1, 0.4, 0.6, -0.5, 0.2, 0.1, 0.9),
            // Rank one: C + II 1 is singular, the diagonal is taken as 0.
            Matrix3::new(1.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0),
        ];
        let together = right_stretch_diagonals::<8>(std::array::from_fn(|k| &lanes[k]));
        for (k, f) in lanes.iter().enumerate() {
            assert_eq!(together[k].map(f64::to_bits), right_stretch_diagonal(f).map(f64::to_bits), "lane {k}");
        }
        let l3: [Vector3<f64>; 8] = std::array::from_fn(|k| Vector3::new(0.25, 0.125 * (k + 1) as f64, 0.5));
        let got = stretched_half_lengths::<3, 8>(std::array::from_fn(|k| &l3[k]), std::array::from_fn(|k| &lanes[k]));
        for k in 0..8 {
            let alone = stretched_half_length(&l3[k], &lanes[k]);
            assert_eq!(got[k].map(f64::to_bits), alone.map(f64::to_bits), "3D lane {k}");
        }
        let l2: [Vector2<f64>; 8] = std::array::from_fn(|k| Vector2::new(0.25, 0.1 * (k + 1) as f64));
        let got = stretched_half_lengths::<2, 8>(std::array::from_fn(|k| &l2[k]), std::array::from_fn(|k| &lanes[k]));
        for k in 0..8 {
            assert_eq!(got[k], stretched_half_length(&l2[k], &lanes[k]), "2D lane {k}");
        }
    }

    proptest::proptest! {
        /// F = 1 + A, A's entries in (−1, 1), det F > 0.01.
        #[test]
        fn the_closed_form_stretch_of_any_f(a in proptest::array::uniform9(-1.0f64..1.0)) {
            let f = Matrix3::identity() + Matrix3::from_row_slice(&a);
            proptest::prop_assume!(f.determinant() > 0.01);
            assert_closed_form_stretch(&f);
        }
    }
    use approx::assert_relative_eq;
    use nalgebra::{Vector2, Vector3};

    #[test]
    fn box_fill_conserves_volume_and_mass() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(0.5, 0.25), [4, 8]).unwrap();
        let mut s = PointStore::<2>::new();
        let n =
            s.fill(&g, &Shape::Box { min: Vector2::new(0.0, 0.0), max: Vector2::new(1.0, 1.5) }, 2, 2000.0, 0).unwrap();
        // 2 x 6 cells, 4 points each.
        assert_eq!(n, 48);
        assert_relative_eq!(s.volume.iter().sum::<f64>(), 1.5, epsilon = 1e-12);
        assert_relative_eq!(s.total_mass(), 3000.0, epsilon = 1e-9);
        assert_eq!(s.half_length[0], Vector2::new(0.125, 0.0625));
        assert_eq!(s.position[0], Vector2::new(0.125, 0.0625));
    }

    /// The count without filling: exact equals the fill's; the bound is the bounding box's
    /// sub-cells (a disc of radius 1 at 4 points per unit cell: 64 in the box, 52 inside).
    #[test]
    fn fill_count_bounds_and_counts_the_fill() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(0.5, 0.5), [8, 8]).unwrap();
        let disc = Shape::Ball { centre: Vector2::new(2.0, 2.0), radius: 1.0 };
        let n = PointStore::<2>::new().fill(&g, &disc, 2, 1.0, 0).unwrap() as u64;
        assert_eq!(fill_count(&g, &disc, 2, Some(u64::MAX)).unwrap(), n);
        assert_eq!(fill_count(&g, &disc, 2, Some(10)).unwrap(), 10);
        assert_eq!(fill_count(&g, &disc, 2, None).unwrap(), 64);
        assert!(matches!(fill_count(&g, &disc, 9, None), Err(PointsError::PointsPerCell(9))));
        // Centres (i + ½)/4 from 1 within the unit circle about (2, 2): 52, counted by hand.
        assert_eq!(n, 52);
    }

    /// A prism of a right triangle (legs 8 and 4 in x and z) across y from 1 to 4: its
    /// points are those of the triangle's fill repeated along y, volume 16 × 3 = 48 to the
    /// staircase of the diagonal; and the same volume as a box cut by the hypotenuse's plane.
    #[test]
    fn a_prism_and_a_cut_box_fill_the_extruded_triangle() {
        let g = Grid::<3>::new(Vector3::zeros(), Vector3::new(1.0, 1.0, 1.0), [10, 6, 6]).unwrap();
        let tri = vec![Vector2::new(0.0, 0.0), Vector2::new(8.0, 0.0), Vector2::new(0.0, 4.0)];
        let mut prism = PointStore::<3>::new();
        prism.fill(&g, &Shape::Prism { section: tri.clone(), axis: 1, from: 1.0, to: 4.0 }, 2, 1.0, 0).unwrap();
        let g2 = Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [10, 6]).unwrap();
        let mut flat = PointStore::<2>::new();
        flat.fill(&g2, &Shape::Polygon(tri), 2, 1.0, 0).unwrap();
        assert_eq!(prism.len(), flat.len() * 6, "two points per cell over three cells in y");
        let volume: f64 = prism.volume.iter().sum();
        assert_relative_eq!(volume, flat.volume.iter().sum::<f64>() * 3.0, epsilon = 1e-9);
        assert!(prism.position.iter().all(|x| x[1] > 1.0 && x[1] < 4.0 && x[0] / 8.0 + x[2] / 4.0 <= 1.0));
        // The same solid: the box [0, 8] × [1, 4] × [0, 4] less the side of x/8 + z/4 > 1.
        let cut = Shape::CutBox {
            min: Vector3::new(0.0, 1.0, 0.0),
            max: Vector3::new(8.0, 4.0, 4.0),
            point: Vector3::new(8.0, 0.0, 0.0),
            normal: Vector3::new(0.5, 0.0, 1.0),
        };
        let mut boxed = PointStore::<3>::new();
        boxed.fill(&g, &cut, 2, 1.0, 0).unwrap();
        assert_eq!(boxed.position, prism.position);
        assert!(matches!(cut.boundary(0.5), Err(PointsError::NoSurface("CutBox"))));
        let flat_prism = Shape::<2>::Prism { section: vec![], axis: 1, from: 0.0, to: 1.0 };
        assert!(matches!(PointStore::<2>::new().fill(&g2, &flat_prism, 2, 1.0, 0), Err(PointsError::Prism { .. })));
    }

    #[test]
    fn polygon_fill_of_a_triangle() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [10, 10]).unwrap();
        let mut s = PointStore::<2>::new();
        let tri = vec![Vector2::new(0.0, 0.0), Vector2::new(8.0, 0.0), Vector2::new(0.0, 8.0)];
        s.fill(&g, &Shape::Polygon(tri), 4, 1.0, 0).unwrap();
        // Area 32; sub-cell sampling converges to it, off by the diagonal's half sub-cells.
        let area: f64 = s.volume.iter().sum();
        assert!((area - 32.0).abs() < 8.0 * 0.25, "area {area}");
    }

    #[test]
    fn three_dimensional_box() {
        let g = Grid::<3>::new(Vector3::zeros(), Vector3::new(0.4, 0.1, 0.4), [1, 8, 1]).unwrap();
        let mut s = PointStore::<3>::new();
        let n =
            s.fill(&g, &Shape::Box { min: Vector3::zeros(), max: Vector3::new(0.4, 0.8, 0.4) }, 2, 50.0, 0).unwrap();
        assert_eq!(n, 64);
        assert_relative_eq!(s.volume.iter().sum::<f64>(), 0.128, epsilon = 1e-12);
    }

    #[test]
    fn bad_fills_are_refused() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [2, 2]).unwrap();
        let mut s = PointStore::<2>::new();
        // Half a sub-cell out: the centre at x = 2.25 is in the shape and outside the grid.
        let b = Shape::Box { min: Vector2::new(0.0, 0.0), max: Vector2::new(2.3, 1.0) };
        assert!(matches!(s.fill(&g, &b, 2, 1.0, 0), Err(PointsError::OutsideGrid { .. })));
        // A cell out: refused by its bounds, before any centre is walked.
        let b = Shape::Box { min: Vector2::new(0.0, 0.0), max: Vector2::new(3.0, 1.0) };
        assert!(matches!(s.fill(&g, &b, 2, 1.0, 0), Err(PointsError::BeyondGrid { .. })));
        let thin = Shape::Box { min: Vector2::new(0.1, 0.1), max: Vector2::new(0.2, 0.2) };
        assert!(matches!(s.fill(&g, &thin, 2, 1.0, 0), Err(PointsError::EmptyRegion(_))));
        let ok = Shape::Box { min: Vector2::new(0.0, 0.0), max: Vector2::new(1.0, 1.0) };
        assert!(matches!(s.fill(&g, &ok, 0, 1.0, 0), Err(PointsError::PointsPerCell(0))));
        assert!(matches!(s.fill(&g, &ok, 2, -1.0, 0), Err(PointsError::Density(_))));
        assert!(s.is_empty());
    }

    /// The disk of V5 (radius 0.2 on a 20×20 unit grid, 2×2 points per cell): sub-cell
    /// sampling gives an area within one ring of sub-cells of πr² (perimeter 2πr × sub-cell
    /// width 0.025 ≈ 0.031 is a loose bound; the sampling error is far smaller on average).
    #[test]
    fn ball_fill_of_a_disk() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(0.05, 0.05), [20, 20]).unwrap();
        let mut s = PointStore::<2>::new();
        s.fill(&g, &Shape::Ball { centre: Vector2::new(0.2, 0.2), radius: 0.2 }, 2, 1000.0, 0).unwrap();
        let area: f64 = s.volume.iter().sum();
        let exact = std::f64::consts::PI * 0.04;
        assert!((area - exact).abs() < 2.0 * std::f64::consts::PI * 0.2 * 0.025, "area {area} vs {exact}");
        assert!(s.position.iter().all(|x| (x - Vector2::new(0.2, 0.2)).norm() <= 0.2));
        let bad = Shape::Ball { centre: Vector2::new(0.5, 0.5), radius: -1.0 };
        assert!(matches!(s.fill(&g, &bad, 2, 1.0, 0), Err(PointsError::Radius(_))));
    }
}
