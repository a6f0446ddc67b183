//! Points to nodes as a deterministic parallel *scatter*: each point adds its
//! contributions to the nodes of its support, in one pass over the points and with no
//! node → point adjacency. Every analysis maps its points to the nodes this way: the
//! explicit step into a field over the whole grid, the implicit analyses (through
//! [`Connectivity::bands`](crate::Connectivity::bands)) into one over the active nodes.
//!
//! Two points of one thread's work may share a node, two of different threads' must not.
//! The nodes, in their numbering, are cut into *bands* of `W` consecutive node indices,
//! `W` at least the span of any point's support (its last node less its first, plus one);
//! each point belongs to the band of its first node, so the points of band b write only
//! nodes [bW, (b + 2)W) and bands two apart never share a node. On a grid numbered with
//! the last axis slowest, bands of [`ROWS_PER_BAND`] node rows hold every support (at most
//! 4 rows, `BasisKind::max_support_1d`). The even bands scatter in parallel, then the odd
//! ones, each band's points in ascending index. Every node therefore sums its
//! contributions in one fixed order, whatever the number of threads: bitwise identical
//! results on 1 or N threads (docs/theory.md §7), with no atomics and no per-thread copies
//! of the field.
//!
//! The output may be numbered more sparsely than the bands (the active nodes of a step,
//! ascending in grid index): band b's window is then the output nodes whose band index
//! lies in [bW, (b + 2)W), still one contiguous range.

use crate::{AxisBasis, Grid};
use rayon::prelude::*;

/// Node rows per band of a grid: at least the widest 1D support (4 nodes) less one, so that
/// bands of one colour are disjoint.
pub const ROWS_PER_BAND: usize = 3;

/// The points grouped by band for [`BandScatter::scatter`] (module docs). Buffers are
/// reused from step to step.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BandScatter {
    /// `band << 32 | point`, ascending: the points of each band, ascending.
    keys: Vec<u64>,
    /// Per band, its first key; one more entry at the end.
    starts: Vec<usize>,
    /// Per band, the first output node of its window; one more entry at the end, the number
    /// of output nodes.
    bounds: Vec<usize>,
}

/// The nodes a band's points may write: `width` values per node from node `first_node`.
pub struct NodeWindow<'a> {
    values: &'a mut [f64],
    first_node: usize,
    width: usize,
}

impl NodeWindow<'_> {
    /// The values of output node `node`, to add to.
    #[inline]
    pub fn node(&mut self, node: usize) -> &mut [f64] {
        let s = (node - self.first_node) * self.width;
        &mut self.values[s..s + self.width]
    }
}

impl BandScatter {
    /// Group the points of `basis` (computed on `grid`) by bands of [`ROWS_PER_BAND`] node
    /// rows, to scatter into a field over every node of `grid`. Points are at most 2³² (a
    /// key holds the band above the point index's 32 bits).
    pub fn group<const D: usize>(&mut self, grid: &Grid<D>, basis: &AxisBasis<D>) {
        let nodes = grid.nodes_per_axis();
        let row_len: usize = nodes[..D - 1].iter().product();
        let num_nodes = nodes[D - 1] * row_len;
        let band_nodes = ROWS_PER_BAND * row_len;
        self.group_by(basis.num_points(), num_nodes.div_ceil(band_nodes), |p| {
            basis.first(p)[D - 1] as usize / ROWS_PER_BAND
        });
        self.set_bounds(|b| (b * band_nodes).min(num_nodes));
    }

    /// Group `n` points into `bands` bands, point `p` into band `band_of(p)`.
    pub(crate) fn group_by(&mut self, n: usize, bands: usize, band_of: impl Fn(usize) -> usize + Sync) {
        assert!(n as u64 <= 1 << 32, "a point index fits the key's low 32 bits");
        self.keys.resize(n, 0);
        self.keys.par_iter_mut().enumerate().for_each(|(p, key)| *key = (band_of(p) as u64) << 32 | p as u64);
        // The keys are distinct, so the order is unique. Points numbered in band order that
        // keep their bands keep the keys sorted, which the sort detects in one pass.
        self.keys.par_sort_unstable();
        self.starts.clear();
        self.starts.extend((0..=bands).map(|b| self.keys.partition_point(|&k| ((k >> 32) as usize) < b)));
        assert_eq!(self.starts[bands], n, "every point's band is below {bands}");
    }

    /// Place every band's window: `first_output_node(b)` for b in 0..=bands, non-decreasing,
    /// the last the number of output nodes.
    pub(crate) fn set_bounds(&mut self, first_output_node: impl Fn(usize) -> usize) {
        let bands = self.starts.len() - 1;
        self.bounds.clear();
        self.bounds.extend((0..=bands).map(first_output_node));
    }

    /// The number of output nodes the scatter fills.
    pub fn num_nodes(&self) -> usize {
        self.bounds.last().copied().unwrap_or(0)
    }

    /// Zero `out` (`width` values per output node) and add every point's contributions:
    /// `contrib(p, window)` adds point `p`'s to the nodes of its support through `window`.
    pub fn scatter(&self, width: usize, out: &mut [f64], contrib: impl Fn(usize, &mut NodeWindow) + Sync) {
        assert_eq!(out.len(), self.num_nodes() * width, "a field over the grouped nodes");
        out.par_iter_mut().for_each(|v| *v = 0.0);
        let bands = self.starts.len().saturating_sub(1);
        for colour in 0..2.min(bands) {
            let of_colour = (bands - colour).div_ceil(2);
            let first = self.bounds[colour];
            self.scatter_bands(colour, 0..of_colour, width, &mut out[first * width..], first, &contrib);
        }
    }

    /// The bands `2k + colour` for k in `range`, whose windows tile `values` (output nodes
    /// from `first_node` on), split in halves across rayon's threads.
    fn scatter_bands(
        &self,
        colour: usize,
        range: std::ops::Range<usize>,
        width: usize,
        values: &mut [f64],
        first_node: usize,
        contrib: &(impl Fn(usize, &mut NodeWindow) + Sync),
    ) {
        if range.len() > 1 {
            let mid = range.start + range.len() / 2;
            let split = self.bounds[2 * mid + colour];
            let (lo, hi) = values.split_at_mut((split - first_node) * width);
            rayon::join(
                || self.scatter_bands(colour, range.start..mid, width, lo, first_node, contrib),
                || self.scatter_bands(colour, mid..range.end, width, hi, split, contrib),
            );
            return;
        }
        let band = 2 * range.start + colour;
        let mut window = NodeWindow { values, first_node, width };
        for &key in &self.keys[self.starts[band]..self.starts[band + 1]] {
            contrib(key as u32 as usize, &mut window);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BasisKind;
    use nalgebra::{SVector, Vector2};
    use proptest::prelude::*;

    /// Scatter the basis values of `x` (domains of half-length `l` cells) on 1 and 3
    /// threads and serially: the threaded results are bitwise equal, the serial one equal
    /// to round-off, and the shares sum to the points (partition of unity).
    fn scatter_agrees<const D: usize>(grid: &Grid<D>, kind: BasisKind, x: &[SVector<f64, D>], l: f64) {
        let half = vec![grid.cell_size() * l; x.len()];
        let mut basis = AxisBasis::new(kind);
        basis.compute(grid, x, &half).unwrap();
        let mut bands = BandScatter::default();
        bands.group(grid, &basis);
        let run = |threads: usize| {
            let mut out = vec![0.0; grid.num_nodes()];
            rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
                bands.scatter(1, &mut out, |p, w| {
                    basis.for_each_node(p, |node, n, _| w.node(node)[0] += n * (1.0 + p as f64))
                })
            });
            out
        };
        let one = run(1);
        assert_eq!(one, run(3));
        let mut serial = vec![0.0; grid.num_nodes()];
        for p in 0..x.len() {
            basis.for_each_node(p, |node, n, _| serial[node] += n * (1.0 + p as f64));
        }
        for (a, b) in one.iter().zip(&serial) {
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} vs {b}");
        }
        let total: f64 = one.iter().sum();
        let expected: f64 = (0..x.len()).map(|p| 1.0 + p as f64).sum();
        assert!((total - expected).abs() <= 1e-10 * expected, "{total} vs {expected}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        /// Any basis, 2D and 3D, grids of 1 to 12 cells along the banded axis (fewer rows
        /// than a band, one band, several), GIMP domains up to a whole cell (supports of 4
        /// rows): no write leaves its band's window (the windows are bounds-checked
        /// slices) and the result is the same on any number of threads.
        #[test]
        fn any_support_scatters_in_one_order(
            kind in prop_oneof![Just(BasisKind::Linear), Just(BasisKind::Gimp), Just(BasisKind::QuadraticBSpline)],
            rows in 1usize..12,
            l in 0.0f64..1.0,
            unit in proptest::collection::vec(0.0f64..1.0, 3 * 40),
        ) {
            let g2 = Grid::new(Vector2::zeros(), Vector2::new(0.5, 0.25), [5, rows]).unwrap();
            let x2: Vec<_> = unit.chunks(3).map(|u| Vector2::new(2.5 * u[0], 0.25 * rows as f64 * u[1] * 0.999)).collect();
            scatter_agrees(&g2, kind, &x2, l);
            let g3 = Grid::new(SVector::<f64, 3>::zeros(), SVector::<f64, 3>::repeat(1.0), [3, 4, rows]).unwrap();
            let x3: Vec<_> = unit.chunks(3).map(|u| SVector::<f64, 3>::new(3.0 * u[0], 4.0 * u[1], rows as f64 * u[2] * 0.999)).collect();
            scatter_agrees(&g3, kind, &x3, l);
        }
    }

    /// The scatter of the basis values and of m N (mass) gives every node the sum over the
    /// points of their shares, the same as a serial loop to round-off, and bitwise the same
    /// on 1 and 3 threads; the shares sum to the number of points (partition of unity).
    #[test]
    fn scatter_sums_every_share_in_a_fixed_order() {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(0.5, 0.5), [9, 20]).unwrap();
        let x: Vec<_> = (0..400).map(|i| Vector2::new(0.3 + 0.01 * i as f64, 0.2 + 0.023 * i as f64)).collect();
        let l = vec![Vector2::repeat(0.125); x.len()];
        let mut basis = AxisBasis::new(BasisKind::Gimp);
        basis.compute(&grid, &x, &l).unwrap();
        let mut bands = BandScatter::default();
        bands.group(&grid, &basis);
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            let mut out = vec![1.0; grid.num_nodes() * 2];
            pool.install(|| {
                bands.scatter(2, &mut out, |p, w| {
                    basis.for_each_node(p, |node, n, _| {
                        let v = w.node(node);
                        v[0] += n;
                        v[1] += n * (1.0 + p as f64);
                    })
                })
            });
            out
        };
        let one = run(1);
        assert_eq!(one, run(3));
        let mut serial = vec![0.0; grid.num_nodes() * 2];
        for p in 0..x.len() {
            basis.for_each_node(p, |node, n, _| {
                serial[2 * node] += n;
                serial[2 * node + 1] += n * (1.0 + p as f64);
            });
        }
        for (a, b) in one.iter().zip(&serial) {
            assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} vs {b}");
        }
        let total: f64 = one.iter().step_by(2).sum();
        assert!((total - x.len() as f64).abs() < 1e-10, "{total}");
    }
}
