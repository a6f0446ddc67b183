//! Basis functions tying a material point to grid nodes, as tensor products of 1D functions.
//!
//! - `Linear`: the standard MPM tent function N(d) = 1 − |d|/h. Its gradient jumps at cell
//!   faces, the source of cell-crossing noise; it does not converge on the self-weight column.
//! - `Gimp`: the uniform GIMP function of Bardenhagen & Kober (2004): the tent averaged over
//!   the point's domain [x_p − l_p, x_p + l_p], S(d) = (M(d + l) − M(d − l)) / (2l) with M the
//!   antiderivative of the tent. For l ≤ h/2 this is exactly the five-piece table of
//!   docs/theory.md §4; written as a difference of antiderivatives it also holds for l up to h,
//!   which iGIMP domains reach when stretched (Charlton et al. 2017).
//! - `QuadraticBSpline`: node-centred quadratic B-splines (Steffen, Kirby & Berzins 2008),
//!   C¹ across cells, so a point crossing a face sees no jump in its gradient. Each grid
//!   node carries one function. Along an axis of n cells the knot vector is
//!   [0, 0, 0, 1.5, 2.5, …, n − 1.5, n, n, n] (in cells): the interior functions are the
//!   uniform ones centred on their nodes, and the open (repeated) knots at the grid faces
//!   are the boundary treatment — the basis stays a partition of unity up to the face and
//!   interpolates there (only the face node is non-zero on the face), so a constraint on a
//!   grid face fixes the displacement itself. Inside the grid the nodal values are control
//!   values, not displacements: a constraint on an interior plane acts on them, and the
//!   nodes next to a face reproduce linear fields from their Greville points
//!   ([`bspline_greville`], 0.75 cells from the face) rather than their positions; the
//!   space still holds every linear field, which is what the patch test needs. An axis of
//!   a single cell falls back to the tent (degree is at most the number of cells there).
//!
//! Face rule, used by every function here: along each axis a cell owns `[x_i, x_{i+1})`.
//! A point exactly on a face belongs to the cell above it, so the linear basis picks one
//! gradient consistently and rigid motion creates no stress.

use crate::Grid;
use nalgebra::SVector;

/// Which basis functions a run uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BasisKind {
    Linear,
    Gimp,
    QuadraticBSpline,
}

/// A point whose basis support leaves the grid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BasisError {
    #[error("position component {axis} = {coordinate} lies outside the grid [{min}, {max})")]
    OutsideGrid { axis: usize, coordinate: f64, min: f64, max: f64 },
    #[error("position or domain half-length along axis {axis} is not finite")]
    NonFinite { axis: usize },
}

/// Half-lengths below this fraction of a cell use the linear limit of GIMP (l → 0).
const MIN_HALF_LENGTH: f64 = 1e-9;
/// Half-lengths are capped at one cell: beyond that the support would exceed four nodes
/// per axis. The cap keeps the partition of unity; it only limits how far a stretched
/// domain reaches.
const MAX_HALF_LENGTH: f64 = 1.0;
/// Nodes whose weight and gradient would both be below this (in cell units) are dropped.
const SUPPORT_EPS: f64 = 1e-12;

impl BasisKind {
    /// Largest number of nodes the basis touches along one axis.
    pub const fn max_support_1d(self) -> usize {
        match self {
            BasisKind::Linear => 2,
            BasisKind::Gimp => 4,
            BasisKind::QuadraticBSpline => 3,
        }
    }

    /// Most nodes the basis touches along one axis for a domain of half-length at most
    /// `half_length` cells (GIMP: the integers strictly within 1 + l of the point, at most
    /// ⌈2 + 2l⌉, so 3 for the l ≤ ½ of two or more points per cell; the others ignore it).
    pub fn support_bound_1d(self, half_length: f64) -> usize {
        match self {
            BasisKind::Gimp if half_length.is_finite() => {
                let l = half_length.clamp(0.0, MAX_HALF_LENGTH);
                ((2.0 + 2.0 * (l - SUPPORT_EPS)).ceil() as usize).clamp(2, 4)
            }
            _ => self.max_support_1d(),
        }
    }

    /// Largest number of nodes the basis touches in `dim` dimensions: the stride of
    /// per-point support buffers.
    pub fn max_support(self, dim: usize) -> usize {
        self.max_support_1d().pow(dim as u32)
    }

    /// Evaluate the basis at `x` for a point of domain half-lengths `half_length` (ignored
    /// by `Linear`). Writes node indices (ascending), values and gradients with respect to
    /// position into the buffers, which must hold the product over the axes of
    /// `support_bound_1d` of the half-length in cells (at most `max_support(D)`), and returns
    /// how many were written.
    pub fn evaluate<const D: usize>(
        self,
        grid: &Grid<D>,
        x: &SVector<f64, D>,
        half_length: &SVector<f64, D>,
        nodes: &mut [u32],
        values: &mut [f64],
        gradients: &mut [SVector<f64, D>],
    ) -> Result<usize, BasisError> {
        let mut idx = [[0usize; 4]; D];
        let mut w = [[0f64; 4]; D];
        let mut dw = [[0f64; 4]; D];
        let mut count = [0usize; D];
        for a in 0..D {
            count[a] = self.evaluate_axis(grid, x, half_length, a, &mut idx[a], &mut w[a], &mut dw[a])?;
        }
        // Tensor product with axis 0 fastest: node indices come out ascending.
        // An odometer over the per-axis supports (the lexicographic order of
        // `lexicographic_coords`, counted up without a division per node).
        let total: usize = count.iter().product();
        let mut odo = [0usize; D];
        for k in 0..total {
            let ijk: [usize; D] = std::array::from_fn(|a| idx[a][odo[a]]);
            let mut value = 1.0;
            for a in 0..D {
                value *= w[a][odo[a]];
            }
            let mut grad = SVector::<f64, D>::zeros();
            for a in 0..D {
                let mut g = dw[a][odo[a]];
                for b in 0..D {
                    if b != a {
                        g *= w[b][odo[b]];
                    }
                }
                grad[a] = g;
            }
            nodes[k] = grid.node_index(ijk) as u32;
            values[k] = value;
            gradients[k] = grad;
            for a in 0..D {
                odo[a] += 1;
                if odo[a] < count[a] {
                    break;
                }
                odo[a] = 0;
            }
        }
        Ok(total)
    }

    /// The 1D functions along axis `a` at `x`: node indices, values and derivatives (per
    /// unit length) into `idx`, `w`, `dw`; returns how many.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(crate) fn evaluate_axis<const D: usize>(
        self,
        grid: &Grid<D>,
        x: &SVector<f64, D>,
        half_length: &SVector<f64, D>,
        a: usize,
        idx: &mut [usize; 4],
        w: &mut [f64; 4],
        dw: &mut [f64; 4],
    ) -> Result<usize, BasisError> {
        let h = grid.cell_size()[a];
        let xi = (x[a] - grid.origin()[a]) / h;
        let l = half_length[a] / h;
        if !xi.is_finite() || !l.is_finite() {
            return Err(BasisError::NonFinite { axis: a });
        }
        let n_cells = grid.cells()[a];
        // A domain is clipped at the grid faces: material cannot lie beyond the grid, and a
        // point resting on a constrained grid face would otherwise need a node outside it
        // after any rounding of its stretched domain. GIMP remains a partition of unity for
        // any half-length, so clipping costs no consistency.
        let l = clipped_half_length(xi, l, n_cells as f64);
        let outside = || BasisError::OutsideGrid {
            axis: a,
            coordinate: x[a],
            min: grid.origin()[a],
            max: grid.origin()[a] + h * n_cells as f64,
        };
        let count = match self {
            BasisKind::Linear => linear_1d(xi, n_cells, idx, w, dw),
            BasisKind::QuadraticBSpline if n_cells == 1 => linear_1d(xi, n_cells, idx, w, dw),
            BasisKind::QuadraticBSpline => bspline_1d(xi, n_cells, idx, w, dw),
            BasisKind::Gimp if !gimp_on_common_path(xi, l, n_cells as f64) => linear_1d(xi, n_cells, idx, w, dw),
            BasisKind::Gimp => gimp_1d(xi, l.min(MAX_HALF_LENGTH), n_cells, idx, w, dw),
        }
        .ok_or_else(outside)?;
        let inv_h = 1.0 / h;
        for v in dw[..count].iter_mut() {
            *v *= inv_h;
        }
        Ok(count)
    }
}

/// GIMP along axis `a` for `N` points at once, each lane bit for bit what
/// [`BasisKind::evaluate_axis`] gives it: every stage (the point in cell units, its
/// clipped half-length, the reciprocal, the first and last node, the weights) for all lanes
/// before the next, so that the lanes' chains of divisions and conversions overlap. Writes
/// the values and derivatives (per unit length) of the first nodes into `w`, `dw` and
/// returns each lane's first node and count; `None` for a lane off GIMP's common path (not
/// finite, in the linear limit, at or beyond the grid's faces), which `evaluate_axis`
/// itself must take. Slots past a lane's count hold weights of no use.
pub(crate) fn gimp_axis_lanes<const D: usize, const N: usize>(
    grid: &Grid<D>,
    x: [&SVector<f64, D>; N],
    half_length: [&SVector<f64, D>; N],
    a: usize,
    w: &mut [[f64; 4]; N],
    dw: &mut [[f64; 4]; N],
) -> [Option<(usize, usize)>; N] {
    let (h, n_cells) = (grid.cell_size()[a], grid.cells()[a]);
    let n = n_cells as f64;
    let xi: [f64; N] = std::array::from_fn(|k| (x[k][a] - grid.origin()[a]) / h);
    let l: [f64; N] = std::array::from_fn(|k| half_length[k][a] / h);
    let clipped: [f64; N] = std::array::from_fn(|k| clipped_half_length(xi[k], l[k], n));
    let common: [bool; N] =
        std::array::from_fn(|k| xi[k].is_finite() && l[k].is_finite() && gimp_on_common_path(xi[k], clipped[k], n));
    // Off the common path a lane computes from a harmless stand-in and is not used.
    let l: [f64; N] = std::array::from_fn(|k| if common[k] { clipped[k].min(MAX_HALF_LENGTH) } else { 0.5 });
    let xi: [f64; N] = std::array::from_fn(|k| if common[k] { xi[k] } else { 0.5 });
    let lanes = gimp_1d_lanes(xi, l, n_cells, w, dw);
    let inv_h = 1.0 / h;
    for (dw, lane) in dw.iter_mut().zip(&lanes) {
        for v in &mut dw[..lane.map_or(0, |(_, count)| count)] {
            *v *= inv_h;
        }
    }
    std::array::from_fn(|k| lanes[k].filter(|_| common[k]))
}

/// A domain's half-length `l` at `xi` on an axis of `n` cells (all in cells), clipped at the
/// grid's faces ([`BasisKind::evaluate_axis`] says why).
#[inline]
fn clipped_half_length(xi: f64, l: f64, n: f64) -> f64 {
    l.min(xi).min(n - xi)
}

/// Whether GIMP takes its own functions at `xi` for the clipped half-length `l` on an axis
/// of `n` cells: not in the linear limit, not on or beyond a face, where the tent serves.
#[inline]
fn gimp_on_common_path(xi: f64, l: f64, n: f64) -> bool {
    !(l < MIN_HALF_LENGTH || xi < 0.0 || xi >= n)
}

/// Tent function in cell units on the cell owning `xi` (half-open rule).
fn linear_1d(xi: f64, n_cells: usize, idx: &mut [usize; 4], w: &mut [f64; 4], dw: &mut [f64; 4]) -> Option<usize> {
    if !(0.0..n_cells as f64).contains(&xi) {
        return None;
    }
    let i = floor_int(xi) as usize;
    let f = xi - i as f64;
    idx[0] = i;
    idx[1] = i + 1;
    w[0] = 1.0 - f;
    w[1] = f;
    dw[0] = -1.0;
    dw[1] = 1.0;
    Some(2)
}

/// Knot `j` of the open node-centred quadratic knot vector of an axis of `n` ≥ 2 cells
/// (module docs): three knots at 0, the cell midpoints from 1.5 to n − 1.5, three at n.
#[inline]
fn bspline_knot(j: usize, n: usize) -> f64 {
    if j <= 2 {
        0.0
    } else if j > n {
        n as f64
    } else {
        j as f64 - 1.5
    }
}

/// The Greville abscissa of node `i` on an axis of `n` ≥ 2 cells, (t_{i+1} + t_{i+2}) / 2, in
/// cells: the control value that reproduces a linear field. It is the node itself except
/// next to a face (0.75 and n − 0.75), so nodal values are control values there.
pub fn bspline_greville(i: usize, n: usize) -> f64 {
    if n < 2 {
        // A single-cell axis uses the tent: the nodes are the control points.
        return i as f64;
    }
    0.5 * (bspline_knot(i + 1, n) + bspline_knot(i + 2, n))
}

/// Quadratic B-splines in cell units on the knot span holding `xi` (half-open, like the
/// cells): the three non-zero functions, which belong to nodes k − 2, k − 1, k of span
/// [t_k, t_{k+1}), by the Cox–de Boor recursion; derivatives from the degree-1 functions
/// (Piegl & Tiller, The NURBS Book, A2.2 and eq. 2.9). Needs n ≥ 2.
fn bspline_1d(xi: f64, n_cells: usize, idx: &mut [usize; 4], w: &mut [f64; 4], dw: &mut [f64; 4]) -> Option<usize> {
    let n = n_cells;
    if !(0.0..n as f64).contains(&xi) {
        return None;
    }
    // Span k ∈ [2, n]: t_k ≤ xi < t_{k+1}.
    let k = if xi < 1.5 { 2 } else { (floor_int(xi + 1.5) as usize).min(n) };
    let t = |j: usize| bspline_knot(j, n);
    // Degree 1 on the span: N_{k−1,1} and N_{k,1}.
    let (t_km1, t_k, t_k1, t_k2) = (t(k - 1), t(k), t(k + 1), t(k + 2));
    let n1_left = (t_k1 - xi) / (t_k1 - t_k);
    let n1_right = (xi - t_k) / (t_k1 - t_k);
    // Degree 2: N_{k−2,2}, N_{k−1,2}, N_{k,2}.
    let a = n1_left / (t_k1 - t_km1);
    let b = n1_right / (t_k2 - t_k);
    w[0] = (t_k1 - xi) * a;
    w[1] = (xi - t_km1) * a + (t_k2 - xi) * b;
    w[2] = (xi - t_k) * b;
    dw[0] = -2.0 * a;
    dw[1] = 2.0 * (a - b);
    dw[2] = 2.0 * b;
    idx[0] = k - 2;
    idx[1] = k - 1;
    idx[2] = k;
    Some(3)
}

/// The tent N(s) = max(0, 1 − |s|) in cell units.
#[inline]
fn tent(s: f64) -> f64 {
    max(1.0 - s.abs(), 0.0)
}

/// min and max of numbers known not to be NaN (the basis checks its inputs are finite):
/// one instruction each, where `f64::min`/`max` add the handling of a NaN operand; the
/// GIMP weights take eight per node.
#[inline]
fn min(a: f64, b: f64) -> f64 {
    if a < b {
        a
    } else {
        b
    }
}

#[inline]
fn max(a: f64, b: f64) -> f64 {
    if a > b {
        a
    } else {
        b
    }
}

/// GIMP weight and its derivative in cell units: the average of the tent over the domain
/// [d − l, d + l], S = (1/2l) ∫ N, and dS/dd = (N(d + l) − N(d − l)) / (2l).
///
/// The tent is linear on [−1, 0] (slope +1) and [0, 1] (slope −1), so the integral is the
/// sum over those pieces of (length × tent at the piece's midpoint). Lengths are measured
/// in the coordinate t = s − d ∈ [−l, l], so for a small domain they are exact multiples of
/// l and nothing cancels: the difference of antiderivatives, M(d + l) − M(d − l), loses
/// all digits of l below 1e-16 · M and breaks the partition of unity for small l.
/// `inv_2l` is 1 / (2l), computed once per point and axis.
#[inline]
fn gimp_weight(d: f64, l: f64, inv_2l: f64) -> (f64, f64) {
    // Rising piece [−1, 0] and falling piece [0, 1], shifted to t = s − d.
    let (rise_lo, rise_hi) = (max(-l, -1.0 - d), min(l, -d));
    let (fall_lo, fall_hi) = (max(-l, -d), min(l, 1.0 - d));
    let rise = max(rise_hi - rise_lo, 0.0);
    let fall = max(fall_hi - fall_lo, 0.0);
    // A piece of length 0 adds exactly +0 (its tent is finite), so both are summed without
    // a branch: the sum is the same to the last bit as adding only the pieces of positive
    // length, and the step's basis evaluation, a branch the predictor misses at random per
    // point, is faster.
    let s = rise * tent(d + 0.5 * (rise_lo + rise_hi)) + fall * tent(d + 0.5 * (fall_lo + fall_hi));
    (s * inv_2l, (rise - fall) * inv_2l)
}

/// ⌊x⌋ of a finite |x| < 2⁵³ as an integer, by truncation: without SSE4.1 in the default
/// target, `f64::floor` is a library call. Every 1D basis finds its nodes with it, each
/// for a coordinate already checked to lie within a few cells of its grid.
#[inline]
fn floor_int(x: f64) -> i64 {
    let t = x as i64;
    t - i64::from(t as f64 > x)
}

/// ⌈x⌉ of a finite |x| < 2⁵³ as an integer ([`floor_int`]).
#[inline]
fn ceil_int(x: f64) -> i64 {
    let t = x as i64;
    t + i64::from((t as f64) < x)
}

/// GIMP in cell units: nodes i with |xi − i| < 1 + l. A node beyond the grid that would
/// carry weight means the point's domain leaves the grid. The one-lane case of
/// [`gimp_1d_lanes`].
#[inline]
fn gimp_1d(
    xi: f64,
    l: f64,
    n_cells: usize,
    idx: &mut [usize; 4],
    w: &mut [f64; 4],
    dw: &mut [f64; 4],
) -> Option<usize> {
    let [lane] = gimp_1d_lanes([xi], [l], n_cells, std::array::from_mut(w), std::array::from_mut(dw));
    let (first, count) = lane?;
    for (k, i) in idx[..count].iter_mut().enumerate() {
        *i = first + k;
    }
    Some(count)
}

/// [`gimp_1d`] for `N` points at once, each lane's nodes and weights computed stage by
/// stage beside the others' ([`gimp_axis_lanes`]): each lane's first node and count, `None`
/// where its domain leaves the grid; slots past a lane's count hold weights of no use.
///
/// The nodes are the integers from ⌈xi − reach⌉ to ⌊xi + reach⌋ less an end lying exactly
/// at the reach (xi − i is exact for the integers near xi, so only the ends can): no test
/// per node.
#[inline]
fn gimp_1d_lanes<const N: usize>(
    xi: [f64; N],
    l: [f64; N],
    n_cells: usize,
    w: &mut [[f64; 4]; N],
    dw: &mut [[f64; 4]; N],
) -> [Option<(usize, usize)>; N] {
    let reach: [f64; N] = std::array::from_fn(|k| 1.0 + l[k] - SUPPORT_EPS);
    let inv_2l: [f64; N] = std::array::from_fn(|k| 0.5 / l[k]);
    let first: [i64; N] = std::array::from_fn(|k| {
        let first = ceil_int(xi[k] - reach[k]);
        first + i64::from(xi[k] - first as f64 >= reach[k])
    });
    let last: [i64; N] = std::array::from_fn(|k| {
        let last = floor_int(xi[k] + reach[k]);
        last - i64::from(last as f64 - xi[k] >= reach[k])
    });
    let count: [usize; N] = std::array::from_fn(|k| (last[k] - first[k] + 1).clamp(0, 4) as usize);
    let widest = count.iter().copied().max().unwrap_or(0);
    for j in 0..widest {
        for k in 0..N {
            (w[k][j], dw[k][j]) = gimp_weight(xi[k] - (first[k] + j as i64) as f64, l[k], inv_2l[k]);
        }
    }
    std::array::from_fn(|k| (first[k] >= 0 && last[k] <= n_cells as i64).then(|| (first[k] as usize, count[k])))
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use nalgebra::{Vector2, Vector3};
    use proptest::prelude::*;

    /// five-piece table of Bardenhagen & Kober (2004), h = 1, valid for l ≤ 1/2.
    fn gimp_table(d: f64, l: f64) -> (f64, f64) {
        if d <= -1.0 - l || d > 1.0 + l {
            (0.0, 0.0)
        } else if d <= -1.0 + l {
            ((1.0 + l + d).powi(2) / (4.0 * l), (1.0 + l + d) / (2.0 * l))
        } else if d <= -l {
            (1.0 + d, 1.0)
        } else if d <= l {
            (1.0 - (d * d + l * l) / (2.0 * l), -d / l)
        } else if d <= 1.0 - l {
            (1.0 - d, -1.0)
        } else {
            ((1.0 + l - d).powi(2) / (4.0 * l), -(1.0 + l - d) / (2.0 * l))
        }
    }

    fn grid2(n: usize) -> Grid<2> {
        Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [n, n]).unwrap()
    }

    fn eval2(kind: BasisKind, g: &Grid<2>, x: Vector2<f64>, l: f64) -> Vec<(u32, f64, Vector2<f64>)> {
        let m = kind.max_support(2);
        let (mut nodes, mut n, mut dn) = (vec![0; m], vec![0.0; m], vec![Vector2::zeros(); m]);
        let c = kind.evaluate(g, &x, &Vector2::repeat(l), &mut nodes, &mut n, &mut dn).unwrap();
        (0..c).map(|k| (nodes[k], n[k], dn[k])).collect()
    }

    #[test]
    fn gimp_matches_the_published_table() {
        for &l in &[0.25, 0.125, 0.5] {
            for k in 0..400 {
                let d = -1.6 + 3.2 * k as f64 / 399.0;
                let (s, ds) = gimp_table(d, l);
                let (s2, ds2) = gimp_weight(d, l, 0.5 / l);
                // Both are closed forms of the same function: equal to rounding.
                assert!((s - s2).abs() < 1e-14, "S at d={d}, l={l}: {s} vs {s2}");
                assert!((ds - ds2).abs() < 1e-12, "dS at d={d}, l={l}: {ds} vs {ds2}");
            }
        }
    }

    proptest! {
        /// Partition of unity and of its gradient (Σ N = 1, Σ ∇N = 0) and linear
        /// completeness (Σ N x_I = x), which every basis here must reproduce exactly.
        #[test]
        fn partition_of_unity_and_linear_reproduction(
            x in 0.0f64..7.999, y in 0.0f64..7.999, l in 0.0f64..1.0, kind in 0usize..3
        ) {
            let kind = [BasisKind::Linear, BasisKind::Gimp, BasisKind::QuadraticBSpline][kind];
            // GIMP domains are clipped at the faces, which is tested on its own below.
            let (x, y) = if kind == BasisKind::Gimp { (x.clamp(1.3, 6.7), y.clamp(1.3, 6.7)) } else { (x, y) };
            let g = grid2(8);
            let p = Vector2::new(x, y);
            let s = eval2(kind, &g, p, l);
            let sum: f64 = s.iter().map(|t| t.1).sum();
            let gsum: Vector2<f64> = s.iter().map(|t| t.2).sum();
            // Linear fields are reproduced from the control values at the Greville points
            // (the nodes themselves for the interpolating bases).
            let control = |node: u32| {
                let c = g.node_coords(node as usize);
                Vector2::from_fn(|a, _| if kind == BasisKind::QuadraticBSpline { bspline_greville(c[a], 8) } else { c[a] as f64 })
            };
            let xr: Vector2<f64> = s.iter().map(|t| control(t.0) * t.1).sum();
            let grad_x: nalgebra::Matrix2<f64> = s.iter().map(|t| control(t.0) * t.2.transpose()).sum();
            prop_assert!((sum - 1.0).abs() < 1e-13);
            prop_assert!(gsum.norm() < 1e-12);
            prop_assert!((xr - p).norm() < 1e-12);
            prop_assert!((grad_x - nalgebra::Matrix2::identity()).norm() < 1e-12);
            let mut sorted: Vec<u32> = s.iter().map(|t| t.0).collect();
            sorted.sort();
            prop_assert_eq!(sorted, s.iter().map(|t| t.0).collect::<Vec<_>>());
        }

        /// Gradients are the derivatives of the values (central differences, step 1e-6:
        /// truncation O(1e-12) for the C¹ GIMP away from its kinks).
        #[test]
        fn gimp_gradient_is_the_derivative(x in 2.0f64..5.0, y in 2.0f64..5.0, l in 0.05f64..0.9) {
            let g = grid2(8);
            let p = Vector2::new(x, y);
            let base = eval2(BasisKind::Gimp, &g, p, l);
            let eps = 1e-6;
            for axis in 0..2 {
                let mut dp = Vector2::zeros();
                dp[axis] = eps;
                let plus = eval2(BasisKind::Gimp, &g, p + dp, l);
                let minus = eval2(BasisKind::Gimp, &g, p - dp, l);
                let at = |v: &Vec<(u32, f64, Vector2<f64>)>, node: u32| {
                    v.iter().find(|t| t.0 == node).map_or(0.0, |t| t.1)
                };
                for t in &base {
                    let fd = (at(&plus, t.0) - at(&minus, t.0)) / (2.0 * eps);
                    prop_assert!((fd - t.2[axis]).abs() < 1e-6, "node {} axis {axis}: {fd} vs {}", t.0, t.2[axis]);
                }
            }
        }
    }

    /// The closed form of the uniform node-centred quadratic B-spline (Steffen et al. 2008,
    /// eq. 17), in cell units: 3/4 − d² for |d| ≤ 1/2, (3/2 − |d|)²/2 for 1/2 ≤ |d| ≤ 3/2.
    fn uniform_bspline(d: f64) -> (f64, f64) {
        let a = d.abs();
        if a <= 0.5 {
            (0.75 - d * d, -2.0 * d)
        } else if a <= 1.5 {
            (0.5 * (1.5 - a).powi(2), -(1.5 - a) * d.signum())
        } else {
            (0.0, 0.0)
        }
    }

    proptest! {
        /// The support bound the connectivity sizes its buffers by holds every GIMP
        /// support: for any position and any half-length up to the one it is asked for.
        #[test]
        fn gimp_supports_stay_within_the_bound(x in 0.0f64..7.999, l in 0.0f64..1.2, f in 0.0f64..=1.0) {
            let g = grid2(8);
            let bound = BasisKind::Gimp.support_bound_1d(l);
            let s = eval2(BasisKind::Gimp, &g, Vector2::new(x, 4.0), l * f);
            prop_assert!(s.len() <= bound * bound, "{} nodes, bound {bound} per axis", s.len());
        }
    }

    proptest! {
        /// From 3.5 cells off one face to 2.5 off the other (where every function in the
        /// support has simple knots) the open knot vector gives the uniform functions:
        /// the recursion and the closed form agree to rounding.
        #[test]
        fn interior_bsplines_are_the_uniform_ones(x in 3.5f64..5.5, y in 3.5f64..5.5) {
            let g = grid2(8);
            for (node, n, dn) in eval2(BasisKind::QuadraticBSpline, &g, Vector2::new(x, y), 0.0) {
                let c = g.node_coords(node as usize);
                let (wx, dwx) = uniform_bspline(x - c[0] as f64);
                let (wy, dwy) = uniform_bspline(y - c[1] as f64);
                prop_assert!((n - wx * wy).abs() < 1e-14);
                prop_assert!((dn - Vector2::new(dwx * wy, wx * dwy)).norm() < 1e-13);
            }
        }

        /// B-spline gradients are the derivatives of the values, near the faces as well
        /// (central differences, step 1e-6; the functions are C¹, piecewise quadratic, so
        /// the truncation error is O(1e-12) except within 1e-6 of a knot, O(1e-6) there).
        #[test]
        fn bspline_gradient_is_the_derivative(x in 0.01f64..7.99, y in 0.01f64..7.99) {
            let g = grid2(8);
            let p = Vector2::new(x, y);
            let base = eval2(BasisKind::QuadraticBSpline, &g, p, 0.0);
            let eps = 1e-6;
            for axis in 0..2 {
                let mut dp = Vector2::zeros();
                dp[axis] = eps;
                let plus = eval2(BasisKind::QuadraticBSpline, &g, p + dp, 0.0);
                let minus = eval2(BasisKind::QuadraticBSpline, &g, p - dp, 0.0);
                let at = |v: &Vec<(u32, f64, Vector2<f64>)>, node: u32| {
                    v.iter().find(|t| t.0 == node).map_or(0.0, |t| t.1)
                };
                for t in &base {
                    let fd = (at(&plus, t.0) - at(&minus, t.0)) / (2.0 * eps);
                    prop_assert!((fd - t.2[axis]).abs() < 1e-6, "node {} axis {axis}: {fd} vs {}", t.0, t.2[axis]);
                }
            }
        }
    }

    /// The open knots make the basis interpolate at the grid faces: on a face only the
    /// face node is non-zero, so a constraint there fixes the displacement itself.
    #[test]
    fn bsplines_interpolate_at_the_grid_faces() {
        let g = grid2(8);
        let s = eval2(BasisKind::QuadraticBSpline, &g, Vector2::new(0.0, 3.0), 0.0);
        for (node, n, _) in s {
            let c = g.node_coords(node as usize);
            if c[0] == 0 {
                assert_relative_eq!(n, uniform_bspline(3.0 - c[1] as f64).0, epsilon = 1e-15);
            } else {
                assert_eq!(n, 0.0);
            }
        }
        // Near the far face (n − 1e-12) the last node carries the whole weight.
        let s = eval2(BasisKind::QuadraticBSpline, &g, Vector2::new(3.0, 8.0 - 1e-12), 0.0);
        let top: f64 = s.iter().filter(|t| g.node_coords(t.0 as usize)[1] == 8).map(|t| t.1).sum();
        assert_relative_eq!(top, 1.0, epsilon = 1e-11);
        // A single-cell axis falls back to the tent; two cells give the quadratic Bernstein
        // functions on [0, 2]: (1 − x/2)², x(1 − x/2), (x/2)².
        let g = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [2, 1]).unwrap();
        let s = eval2(BasisKind::QuadraticBSpline, &g, Vector2::new(0.5, 0.25), 0.0);
        assert_eq!(s.len(), 6);
        let along_x: Vec<f64> = s.iter().filter(|t| g.node_coords(t.0 as usize)[1] == 0).map(|t| t.1 / 0.75).collect();
        for (got, want) in along_x.iter().zip([0.5625, 0.375, 0.0625]) {
            assert_relative_eq!(*got, want, epsilon = 1e-15);
        }
    }

    /// Small domains (clipped at a grid face, or tiny by choice) keep the partition of
    /// unity to rounding: the case proptest found with the antiderivative form, where
    /// M(d + l) − M(d − l) cancelled (error ~1e-16 / l).
    #[test]
    fn small_domains_keep_the_partition_of_unity() {
        let g = grid2(8);
        for &l in &[1.425_279_387_573_835e-4, 1e-6, 2e-9] {
            let s = eval2(BasisKind::Gimp, &g, Vector2::new(1.3, 1.3), l);
            let sum: f64 = s.iter().map(|t| t.1).sum();
            let gsum: Vector2<f64> = s.iter().map(|t| t.2).sum();
            assert!((sum - 1.0).abs() < 1e-14, "l = {l}: sum {sum}");
            assert!(gsum.norm() < 1e-12, "l = {l}: gradient sum {gsum}");
        }
    }

    #[test]
    fn linear_face_rule_takes_the_cell_above() {
        let g = grid2(4);
        let s = eval2(BasisKind::Linear, &g, Vector2::new(2.0, 1.5), 0.0);
        let nodes: Vec<u32> = s.iter().map(|t| t.0).collect();
        // cell [2,3) x [1,2): nodes (2,1),(3,1),(2,2),(3,2)
        assert_eq!(nodes, vec![7, 8, 12, 13]);
        assert_relative_eq!(s[0].1, 0.5);
        assert_relative_eq!(s[0].2[0], -0.5);
    }

    #[test]
    fn gimp_support_counts() {
        let g = grid2(8);
        // l = h/4 at the centre of a quarter cell: 2 nodes per axis.
        assert_eq!(eval2(BasisKind::Gimp, &g, Vector2::new(3.25, 3.75), 0.25).len(), 4);
        // domain straddling a node: 3 nodes along that axis.
        assert_eq!(eval2(BasisKind::Gimp, &g, Vector2::new(3.1, 3.5), 0.25).len(), 6);
    }

    #[test]
    fn support_leaving_the_grid_is_an_error() {
        let g = grid2(4);
        let m = 16;
        let (mut nodes, mut n, mut dn) = (vec![0; m], vec![0.0; m], vec![Vector2::zeros(); m]);
        // A domain crossing the grid edge is clipped there: no node outside the grid is
        // needed, and the clipped basis is still a partition of unity.
        let c = BasisKind::Gimp
            .evaluate(&g, &Vector2::new(0.1, 1.5), &Vector2::repeat(0.25), &mut nodes, &mut n, &mut dn)
            .unwrap();
        assert!((n[..c].iter().sum::<f64>() - 1.0).abs() < 1e-14);
        assert!(nodes[..c].iter().all(|&k| g.node_coords(k as usize)[0] <= 2));
        // A point centre outside the grid is an error.
        let err = BasisKind::Gimp
            .evaluate(&g, &Vector2::new(-0.1, 1.5), &Vector2::repeat(0.25), &mut nodes, &mut n, &mut dn)
            .unwrap_err();
        assert!(matches!(err, BasisError::OutsideGrid { axis: 0, .. }));
        assert!(BasisKind::Linear
            .evaluate(&g, &Vector2::new(4.0, 1.0), &Vector2::zeros(), &mut nodes, &mut n, &mut dn)
            .is_err());
    }

    #[test]
    fn three_dimensional_partition_of_unity() {
        let g = Grid::<3>::new(Vector3::zeros(), Vector3::new(0.5, 1.0, 2.0), [4, 4, 4]).unwrap();
        let m = BasisKind::Gimp.max_support(3);
        let (mut nodes, mut n, mut dn) = (vec![0; m], vec![0.0; m], vec![Vector3::zeros(); m]);
        let c = BasisKind::Gimp
            .evaluate(&g, &Vector3::new(1.01, 2.3, 4.4), &Vector3::new(0.1, 0.3, 0.6), &mut nodes, &mut n, &mut dn)
            .unwrap();
        let sum: f64 = n[..c].iter().sum();
        assert_relative_eq!(sum, 1.0, epsilon = 1e-14);
    }
}
