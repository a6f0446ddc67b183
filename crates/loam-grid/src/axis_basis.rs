//! The grid bases of every point as products of their 1D factors: per point and axis, the
//! first node along the axis, how many nodes follow it and the 1D values and derivatives.
//!
//! Every basis of a uniform grid (linear, GIMP, quadratic B-spline, docs/theory.md §4) is a
//! tensor product N_I(x) = Π_a φ_a(x_a), so a point's D × (at most 4) factors give all of
//! its (at most 4^D) node values and gradients. Storing the factors instead of the
//! products and their node numbers (`Connectivity`) takes 138 instead of 292 bytes per
//! point in 2D and 207 instead of 1 084 in 3D (2 points per cell); the products are
//! formed where a transfer uses them ([`AxisBasis::for_each_node`]), in the order and with
//! the operations of [`BasisKind::evaluate`], so the values and gradients are the same to
//! the last bit. The explicit step reads the basis three times a step and gains most.
//!
//! GIMP factors are evaluated eight points at a time, stage by stage across the points
//! (`gimp_axis_lanes`): one point's chain of divisions, conversions and weights leaves the
//! processor waiting, eight side by side keep it busy (the explicit step 7 % faster in 3D
//! and 10 % in 2D on one thread). A point off GIMP's common path (at a face, in the linear
//! limit, outside the grid) is evaluated alone, as every point of the other bases is.

use crate::basis::gimp_axis_lanes;
use crate::{BasisKind, Grid, PointBasisError};
use nalgebra::SVector;
use rayon::prelude::*;

/// The basis of every point as 1D factors (module docs). Buffers are reused from step to
/// step.
#[derive(Debug, Clone)]
pub struct AxisBasis<const D: usize> {
    basis: BasisKind,
    /// Nodes per axis of the grid the basis was computed on.
    nodes_per_axis: [usize; D],
    /// First node of each point along each axis.
    first: Vec<[u32; D]>,
    /// Nodes of each point along each axis (at most `BasisKind::max_support_1d`).
    count: Vec<[u8; D]>,
    /// 1D values, `D * WIDTH` per point, axis-major.
    values: Vec<f64>,
    /// 1D derivatives (per unit length), laid out like `values`.
    derivatives: Vec<f64>,
}

/// Slots per point and axis: the widest 1D support of any basis.
const WIDTH: usize = 4;

impl<const D: usize> AxisBasis<D> {
    pub fn new(basis: BasisKind) -> Self {
        Self {
            basis,
            nodes_per_axis: [0; D],
            first: Vec::new(),
            count: Vec::new(),
            values: Vec::new(),
            derivatives: Vec::new(),
        }
    }

    pub fn basis(&self) -> BasisKind {
        self.basis
    }

    pub fn num_points(&self) -> usize {
        self.first.len()
    }

    /// The first node of point `p` along each axis.
    #[inline]
    pub fn first(&self, p: usize) -> [u32; D] {
        self.first[p]
    }

    /// How many nodes point `p` touches along each axis.
    #[inline]
    pub fn count(&self, p: usize) -> [u8; D] {
        self.count[p]
    }

    /// Evaluate the factors of every point, in parallel. On failure, the error names the
    /// first point (lowest index) whose basis left the grid.
    pub fn compute(
        &mut self,
        grid: &Grid<D>,
        positions: &[SVector<f64, D>],
        half_lengths: &[SVector<f64, D>],
    ) -> Result<(), PointBasisError> {
        assert_eq!(positions.len(), half_lengths.len());
        let n = positions.len();
        self.nodes_per_axis = grid.nodes_per_axis();
        self.first.resize(n, [0; D]);
        self.count.resize(n, [0; D]);
        self.values.resize(n * D * WIDTH, 0.0);
        self.derivatives.resize(n * D * WIDTH, 0.0);
        let basis = self.basis;
        let failure = (
            self.first.par_chunks_mut(LANES),
            self.count.par_chunks_mut(LANES),
            self.values.par_chunks_mut(LANES * D * WIDTH),
            self.derivatives.par_chunks_mut(LANES * D * WIDTH),
        )
            .into_par_iter()
            .enumerate()
            .filter_map(|(chunk, (first, count, w, dw))| {
                let (p0, full) = (chunk * LANES, first.len() == LANES);
                let ahead = if basis == BasisKind::Gimp && full {
                    gimp_lanes(grid, &positions[p0..p0 + LANES], &half_lengths[p0..p0 + LANES], first, count, w, dw)
                } else {
                    [false; LANES]
                };
                (0..first.len()).filter(|&k| !ahead[k]).find_map(|k| {
                    let (w, dw) = (&mut w[k * D * WIDTH..][..D * WIDTH], &mut dw[k * D * WIDTH..][..D * WIDTH]);
                    let (x, l) = (&positions[p0 + k], &half_lengths[p0 + k]);
                    evaluate_point(basis, grid, x, l, &mut first[k], &mut count[k], w, dw)
                        .err()
                        .map(|source| PointBasisError { point: p0 + k, position: x.iter().copied().collect(), source })
                })
            })
            .min_by_key(|e| e.point);
        failure.map_or(Ok(()), Err)
    }

    /// Call `f(node, value, gradient)` for every node of point `p`'s support, nodes
    /// ascending (axis 0 fastest): the products of [`BasisKind::evaluate`], bit for bit
    /// (value (w₀w₁)w₂; gradient component a the derivative along a times the other
    /// factors in ascending order). In 2D and 3D by loops nested over the axes, the factors
    /// of the outer axes and the row's first node hoisted out of the inner loop.
    #[inline]
    pub fn for_each_node(&self, p: usize, mut f: impl FnMut(usize, f64, SVector<f64, D>)) {
        let (first, count) = (self.first[p], self.count[p]);
        let w = &self.values[p * D * WIDTH..(p + 1) * D * WIDTH];
        let dw = &self.derivatives[p * D * WIDTH..(p + 1) * D * WIDTH];
        let axis = |a: usize| {
            let n = (count[a] as usize).min(WIDTH);
            (&w[a * WIDTH..a * WIDTH + n], &dw[a * WIDTH..a * WIDTH + n])
        };
        let row = self.nodes_per_axis[0];
        if D == 2 {
            let ((wx, dx), (wy, dy)) = (axis(0), axis(1));
            let mut start = first[1] as usize * row + first[0] as usize;
            for j in 0..wy.len() {
                let (wj, dj) = (wy[j], dy[j]);
                for i in 0..wx.len() {
                    let (wi, di) = (wx[i], dx[i]);
                    let grad = [di * wj, dj * wi];
                    f(start + i, wi * wj, SVector::from_fn(|a, _| grad[a]));
                }
                start += row;
            }
        } else if D == 3 {
            let ((wx, dx), (wy, dy), (wz, dz)) = (axis(0), axis(1), axis(2));
            let plane = row * self.nodes_per_axis[1];
            let mut layer = first[2] as usize * plane + first[1] as usize * row + first[0] as usize;
            for k in 0..wz.len() {
                let (wk, dk) = (wz[k], dz[k]);
                let mut start = layer;
                for j in 0..wy.len() {
                    let (wj, dj) = (wy[j], dy[j]);
                    for i in 0..wx.len() {
                        let (wi, di) = (wx[i], dx[i]);
                        let grad = [di * wj * wk, dj * wi * wk, dk * wi * wj];
                        f(start + i, wi * wj * wk, SVector::from_fn(|a, _| grad[a]));
                    }
                    start += row;
                }
                layer += plane;
            }
        } else {
            self.for_each_node_any(p, f);
        }
    }

    /// [`Self::for_each_node`] in any dimension, by an odometer over the axes.
    #[inline]
    fn for_each_node_any(&self, p: usize, mut f: impl FnMut(usize, f64, SVector<f64, D>)) {
        let (first, count) = (self.first[p], self.count[p]);
        let w = &self.values[p * D * WIDTH..(p + 1) * D * WIDTH];
        let dw = &self.derivatives[p * D * WIDTH..(p + 1) * D * WIDTH];
        let mut stride = [1usize; D];
        for a in 1..D {
            stride[a] = stride[a - 1] * self.nodes_per_axis[a - 1];
        }
        let mut odo = [0usize; D];
        loop {
            let mut node = 0;
            let mut value = 1.0;
            for a in 0..D {
                node += (first[a] as usize + odo[a]) * stride[a];
                value *= w[a * WIDTH + odo[a]];
            }
            let grad = SVector::<f64, D>::from_fn(|a, _| {
                let mut g = dw[a * WIDTH + odo[a]];
                for b in 0..D {
                    if b != a {
                        g *= w[b * WIDTH + odo[b]];
                    }
                }
                g
            });
            f(node, value, grad);
            let mut a = 0;
            loop {
                odo[a] += 1;
                if odo[a] < count[a] as usize {
                    break;
                }
                odo[a] = 0;
                a += 1;
                if a == D {
                    return;
                }
            }
        }
    }
}

/// Points whose GIMP factors are evaluated together ([`gimp_axis_lanes`]).
const LANES: usize = 8;

/// The GIMP factors of `LANES` points, axis by axis in lanes, into their slots; whether
/// each lane is done (every axis on GIMP's common path), else [`evaluate_point`] takes it.
#[allow(clippy::too_many_arguments)]
fn gimp_lanes<const D: usize>(
    grid: &Grid<D>,
    x: &[SVector<f64, D>],
    l: &[SVector<f64, D>],
    first: &mut [[u32; D]],
    count: &mut [[u8; D]],
    w: &mut [f64],
    dw: &mut [f64],
) -> [bool; LANES] {
    let mut done = [true; LANES];
    for a in 0..D {
        let (mut wa, mut dwa) = ([[0.0; WIDTH]; LANES], [[0.0; WIDTH]; LANES]);
        let axis =
            gimp_axis_lanes(grid, std::array::from_fn(|k| &x[k]), std::array::from_fn(|k| &l[k]), a, &mut wa, &mut dwa);
        for (k, lane) in axis.iter().enumerate() {
            let Some((first_node, nodes)) = *lane else {
                done[k] = false;
                continue;
            };
            first[k][a] = first_node as u32;
            count[k][a] = nodes as u8;
            let slots = (k * D + a) * WIDTH;
            w[slots..slots + WIDTH].copy_from_slice(&wa[k]);
            dw[slots..slots + WIDTH].copy_from_slice(&dwa[k]);
        }
    }
    done
}

/// The factors of one point along every axis into its slots (`D * WIDTH` values and
/// derivatives).
#[allow(clippy::too_many_arguments)]
fn evaluate_point<const D: usize>(
    basis: BasisKind,
    grid: &Grid<D>,
    x: &SVector<f64, D>,
    l: &SVector<f64, D>,
    first: &mut [u32; D],
    count: &mut [u8; D],
    w: &mut [f64],
    dw: &mut [f64],
) -> Result<(), crate::BasisError> {
    let mut idx = [0usize; WIDTH];
    for a in 0..D {
        let (w, dw) = (&mut w[a * WIDTH..(a + 1) * WIDTH], &mut dw[a * WIDTH..(a + 1) * WIDTH]);
        let (w, dw) = (w.try_into().expect("WIDTH slots"), dw.try_into().expect("WIDTH slots"));
        let c = basis.evaluate_axis(grid, x, l, a, &mut idx, w, dw)?;
        first[a] = idx[0] as u32;
        count[a] = c as u8;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};

    /// Every basis of the points `x` with half-lengths `l` by [`AxisBasis`] is that of
    /// [`BasisKind::evaluate`] to the last bit.
    fn products_match_evaluate<const D: usize>(grid: &Grid<D>, x: &[SVector<f64, D>], l: &[SVector<f64, D>]) {
        for kind in [BasisKind::Linear, BasisKind::Gimp, BasisKind::QuadraticBSpline] {
            let mut axis = AxisBasis::new(kind);
            axis.compute(grid, x, l).unwrap();
            for p in 0..x.len() {
                let m = kind.max_support(D);
                let (mut nodes, mut n, mut dn) = (vec![0; m], vec![0.0; m], vec![SVector::zeros(); m]);
                let c = kind.evaluate(grid, &x[p], &l[p], &mut nodes, &mut n, &mut dn).unwrap();
                let mut got = Vec::new();
                axis.for_each_node(p, |node, v, g| got.push((node as u32, v, g)));
                let expected: Vec<_> = (0..c).map(|k| (nodes[k], n[k], dn[k])).collect();
                assert_eq!(got, expected, "{kind:?} point {p}");
            }
        }
    }

    /// The factors' products are [`BasisKind::evaluate`]'s nodes, values and gradients to
    /// the last bit, for every basis, in 2D and 3D, including stretched GIMP domains and
    /// points next to the grid's faces.
    #[test]
    fn products_are_the_evaluated_basis() {
        let g2 = Grid::new(Vector2::new(-1.0, 0.5), Vector2::new(0.5, 0.25), [7, 9]).unwrap();
        let x2 = [Vector2::new(0.13, 1.37), Vector2::new(-0.9, 0.55), Vector2::new(2.4, 2.7)];
        let l2 = [Vector2::new(0.125, 0.0625), Vector2::new(0.3, 0.2), Vector2::new(0.05, 0.1)];
        products_match_evaluate(&g2, &x2, &l2);
        let g3 = Grid::new(Vector3::zeros(), Vector3::new(1.0, 0.5, 2.0), [5, 6, 4]).unwrap();
        let x3 = [Vector3::new(2.3, 1.1, 3.9), Vector3::new(0.1, 2.9, 7.95)];
        let l3 = [Vector3::new(0.25, 0.125, 0.5), Vector3::new(0.6, 0.2, 0.01)];
        products_match_evaluate(&g3, &x3, &l3);
        // 1D takes the odometer of any dimension.
        let g1 = Grid::new(SVector::<f64, 1>::new(0.5), SVector::<f64, 1>::new(0.25), [6]).unwrap();
        let x1 = [SVector::<f64, 1>::new(0.6), SVector::<f64, 1>::new(1.93)];
        products_match_evaluate(&g1, &x1, &[SVector::<f64, 1>::new(0.1), SVector::<f64, 1>::new(0.0)]);
    }

    /// Points evaluated eight at a time (GIMP's lanes) give each the basis it gets alone,
    /// to the last bit: whole chunks and a ragged end, with lanes off the common path among
    /// them — a domain clipped at a face, one in the linear limit, a point on the lower
    /// face, stretched domains of four nodes — in 2D and 3D, for every basis.
    #[test]
    fn points_in_lanes_get_their_own_basis() {
        let g2 = Grid::new(Vector2::new(-1.0, 0.5), Vector2::new(0.5, 0.25), [7, 9]).unwrap();
        let g3 = Grid::new(Vector3::zeros(), Vector3::new(1.0, 0.5, 2.0), [5, 6, 4]).unwrap();
        let (mut x2, mut l2, mut x3, mut l3) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for i in 0..27 {
            let t = i as f64 / 27.0;
            let u = (7.3 * t).fract();
            x2.push(Vector2::new(-1.0 + 3.5 * u, 0.5 + 2.25 * (3.1 * t).fract()));
            l2.push(Vector2::new(0.05 + 0.4 * t, 0.02 + 0.2 * u));
            x3.push(Vector3::new(5.0 * u, 3.0 * (2.3 * t).fract(), 8.0 * t));
            l3.push(Vector3::new(0.1 + 0.8 * u, 0.05 + 0.4 * t, 0.5 * (1.7 * t).fract()));
        }
        // Off the common path, in the first and a later chunk: on the lower face, vanishing
        // domains (the linear limit) along one axis; on it, domains clipped by the upper face.
        (x2[3], l2[5], l2[14], x2[9], l2[9]) = (
            Vector2::new(-1.0, 0.5),
            Vector2::new(1e-12, 0.1),
            Vector2::new(0.2, 1e-12),
            Vector2::new(2.4, 2.7),
            Vector2::new(0.4, 0.2),
        );
        (x3[2], l3[4], l3[13], x3[10], l3[10]) = (
            Vector3::zeros(),
            Vector3::new(0.3, 1e-12, 0.5),
            Vector3::new(0.3, 0.2, 1e-12),
            Vector3::new(4.9, 2.9, 7.9),
            Vector3::new(0.6, 0.2, 1.5),
        );
        products_match_evaluate(&g2, &x2, &l2);
        products_match_evaluate(&g3, &x3, &l3);
        // One dimension takes the lanes too (nine points: a chunk and one more).
        let g1 = Grid::new(SVector::<f64, 1>::new(0.5), SVector::<f64, 1>::new(0.25), [6]).unwrap();
        let x1: Vec<_> = (0..9).map(|i| SVector::<f64, 1>::new(0.55 + 0.16 * i as f64)).collect();
        let l1: Vec<_> = (0..9).map(|i| SVector::<f64, 1>::new(0.02 + 0.01 * i as f64)).collect();
        products_match_evaluate(&g1, &x1, &l1);
    }

    /// Among points in lanes, the lowest one outside the grid is named.
    #[test]
    fn the_first_point_outside_is_named_among_lanes() {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [4, 4]).unwrap();
        let mut x = vec![Vector2::new(1.5, 1.5); 20];
        // Point 11 fails along both axes: its error is that of axis 0.
        (x[13], x[11], x[17]) = (Vector2::new(5.0, 1.0), Vector2::new(-1.0, -0.5), Vector2::new(f64::NAN, 1.0));
        let mut axis = AxisBasis::new(BasisKind::Gimp);
        let e = axis.compute(&grid, &x, &[Vector2::repeat(0.25); 20]).unwrap_err();
        assert_eq!(e.point, 11);
        assert!(matches!(e.source, crate::BasisError::OutsideGrid { axis: 0, .. }), "{:?}", e.source);
        assert_eq!(e.position, vec![-1.0, -0.5]);
    }

    /// A point outside the grid is named; of two, the lower index.
    #[test]
    fn the_first_point_outside_is_named() {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [2, 2]).unwrap();
        let x = [Vector2::new(0.5, 0.5), Vector2::new(0.5, 2.5), Vector2::new(-1.0, 0.5)];
        let mut axis = AxisBasis::new(BasisKind::Gimp);
        let e = axis.compute(&grid, &x, &[Vector2::repeat(0.25); 3]).unwrap_err();
        assert_eq!(e.point, 1);
    }
}
