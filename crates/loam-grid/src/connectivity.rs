//! Point–node connectivity of one step: the basis values and gradients of every point at
//! the start of the step, the active nodes (those some point's basis touches — the only
//! unknowns of the step) and, per active node, the points that touch it.
//!
//! Per-point data is stored struct-of-arrays with a fixed stride (`BasisKind::max_support`)
//! so that the hot loops index flat buffers, and buffers are reused from step to step.
//! The node → point adjacency lets every node *gather* its contributions in a fixed point
//! order, which makes parallel assembly deterministic without atomics or colouring; the
//! points' bands ([`BandScatter`]) let the transfers scatter them to the active nodes,
//! equally deterministic.

use crate::{BandScatter, BasisError, BasisKind, ElementError, FeMesh, Grid};
use nalgebra::SVector;
use rayon::prelude::*;

/// Marker for a grid node that no point touches.
pub const INACTIVE: u32 = u32::MAX;

/// Numbering of the active nodes, ascending in grid node index.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ActiveNodes {
    /// Active index of each grid node, or `INACTIVE`.
    pub grid_to_active: Vec<u32>,
    /// Grid node index of each active node.
    pub active_to_grid: Vec<u32>,
}

impl ActiveNodes {
    /// Every one of `n` nodes active, numbered as they are.
    pub fn all(n: usize) -> Self {
        let n = u32::try_from(n).expect("grid node indices are u32");
        Self { grid_to_active: (0..n).collect(), active_to_grid: (0..n).collect() }
    }

    /// Renumber to the nodes `0..n` for which `active(node)` holds, ascending; the buffers
    /// are reused.
    pub fn fill_from(&mut self, n: usize, active: impl Fn(usize) -> bool) {
        self.grid_to_active.clear();
        self.active_to_grid.clear();
        for g in 0..n {
            if active(g) {
                self.grid_to_active.push(self.active_to_grid.len() as u32);
                self.active_to_grid.push(g as u32);
            } else {
                self.grid_to_active.push(INACTIVE);
            }
        }
    }

    pub fn len(&self) -> usize {
        self.active_to_grid.len()
    }

    pub fn is_empty(&self) -> bool {
        self.active_to_grid.is_empty()
    }
}

/// For each active node, the (point, local support slot) pairs touching it, ascending in
/// point index.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct NodePointAdjacency {
    pub offsets: Vec<usize>,
    pub entries: Vec<(u32, u32)>,
}

impl NodePointAdjacency {
    pub fn of(&self, node: usize) -> &[(u32, u32)] {
        &self.entries[self.offsets[node]..self.offsets[node + 1]]
    }
}

/// Point–node connectivity at the start of a step. See the module docs.
#[derive(Debug, Clone)]
pub struct Connectivity<const D: usize> {
    basis: BasisKind,
    stride: usize,
    count: Vec<u32>,
    grid_nodes: Vec<u32>,
    active: Vec<u32>,
    values: Vec<f64>,
    gradients: Vec<SVector<f64, D>>,
    active_nodes: ActiveNodes,
    node_points: NodePointAdjacency,
    bands: BandScatter,
}

/// A point whose basis could not be evaluated, with the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("material point {point} at {position:?}: {source}")]
pub struct PointBasisError {
    pub point: usize,
    pub position: Vec<f64>,
    pub source: BasisError,
}

/// Weight below which, together with a gradient below `NEGLIGIBLE_GRADIENT / h`, a node
/// is left out of a point's support.
const NEGLIGIBLE_WEIGHT: f64 = 1e-14;
const NEGLIGIBLE_GRADIENT: f64 = 1e-8;

impl<const D: usize> Connectivity<D> {
    pub fn new(basis: BasisKind) -> Self {
        Self {
            basis,
            stride: basis.max_support(D),
            count: Vec::new(),
            grid_nodes: Vec::new(),
            active: Vec::new(),
            values: Vec::new(),
            gradients: Vec::new(),
            active_nodes: ActiveNodes::default(),
            node_points: NodePointAdjacency::default(),
            bands: BandScatter::default(),
        }
    }

    pub fn basis(&self) -> BasisKind {
        self.basis
    }

    /// Buffer stride per point.
    pub fn stride(&self) -> usize {
        self.stride
    }

    pub fn num_points(&self) -> usize {
        self.count.len()
    }

    pub fn active_nodes(&self) -> &ActiveNodes {
        &self.active_nodes
    }

    pub fn node_points(&self) -> &NodePointAdjacency {
        &self.node_points
    }

    /// The points grouped to scatter to the active nodes (their output numbering).
    pub fn bands(&self) -> &BandScatter {
        &self.bands
    }

    /// Number of nodes point `p` touches.
    #[inline]
    pub fn support_len(&self, p: usize) -> usize {
        self.count[p] as usize
    }

    /// Active node indices touched by point `p`, ascending.
    #[inline]
    pub fn support_nodes(&self, p: usize) -> &[u32] {
        let s = p * self.stride;
        &self.active[s..s + self.count[p] as usize]
    }

    /// Grid node indices touched by point `p`, ascending.
    #[inline]
    pub fn support_grid_nodes(&self, p: usize) -> &[u32] {
        let s = p * self.stride;
        &self.grid_nodes[s..s + self.count[p] as usize]
    }

    /// Basis values at point `p` for its support nodes.
    #[inline]
    pub fn support_values(&self, p: usize) -> &[f64] {
        let s = p * self.stride;
        &self.values[s..s + self.count[p] as usize]
    }

    /// Basis gradients (with respect to the start-of-step position) at point `p`.
    #[inline]
    pub fn support_gradients(&self, p: usize) -> &[SVector<f64, D>] {
        let s = p * self.stride;
        &self.gradients[s..s + self.count[p] as usize]
    }

    /// Evaluate the basis of every point, number the active nodes and build the node →
    /// point adjacency. Buffers are reused. On failure, the error names the first point
    /// (lowest index) whose basis left the grid.
    pub fn compute(
        &mut self,
        grid: &Grid<D>,
        positions: &[SVector<f64, D>],
        half_lengths: &[SVector<f64, D>],
    ) -> Result<(), PointBasisError> {
        assert_eq!(positions.len(), half_lengths.len());
        let basis = self.basis;
        let h_min = grid.cell_size().min();
        // Buffers as wide as the largest support the domains allow, not the widest GIMP
        // support: 27 instead of 64 nodes per point in 3D with two points per cell.
        self.stride = (0..D)
            .map(|a| {
                let h = grid.cell_size()[a];
                let widest = half_lengths.par_iter().map(|l| l[a] / h).reduce(|| 0.0, f64::max);
                basis.support_bound_1d(widest)
            })
            .product();
        self.fill(positions.len(), grid.num_nodes(), |p, nodes, vals, grads| {
            let c = basis.evaluate(grid, &positions[p], &half_lengths[p], nodes, vals, grads)?;
            // A node where the weight and its gradient (nearly) vanish — a point on or
            // within round-off of a grid node, linear basis — couples to nothing; kept, it
            // would be an active node with a (numerically) empty row in the tangent.
            // Dropping it changes the partition of unity by < 1e-14 and of its gradient by
            // < 1e-8 / h.
            let mut kept = 0;
            for k in 0..c {
                if vals[k] > NEGLIGIBLE_WEIGHT || grads[k].norm() * h_min > NEGLIGIBLE_GRADIENT {
                    nodes[kept] = nodes[k];
                    vals[kept] = vals[k];
                    grads[kept] = grads[k];
                    kept += 1;
                }
            }
            Ok(kept)
        })
        .map_err(|(p, source)| PointBasisError {
            point: p,
            position: positions[p].iter().copied().collect(),
            source,
        })
    }

    /// The connectivity of an updated Lagrangian FEM run: the points are the mesh's Gauss
    /// points (element-major), their supports the element nodes, the gradients those of
    /// the current node positions. The stride must hold 2^D nodes (`BasisKind::Linear`).
    pub fn compute_mesh(&mut self, mesh: &FeMesh<D>) -> Result<(), ElementError> {
        self.stride = FeMesh::<D>::NODES_PER_ELEMENT;
        self.fill(mesh.num_gauss_points(), mesh.num_nodes(), |p, nodes, vals, grads| {
            mesh.evaluate(p, nodes, vals, grads)
        })
        .map_err(|(_, e)| e)
    }

    /// Evaluate every point's support with `evaluate` (nodes ascending, in a numbering of
    /// `num_nodes` nodes), then number the active nodes and build the adjacency. The first
    /// failing point (lowest index) is returned with its error.
    fn fill<E: Send>(
        &mut self,
        n: usize,
        num_nodes: usize,
        evaluate: impl Fn(usize, &mut [u32], &mut [f64], &mut [SVector<f64, D>]) -> Result<usize, E> + Sync,
    ) -> Result<(), (usize, E)> {
        self.evaluate_supports(n, evaluate)?;
        self.number_active_nodes(num_nodes);
        self.build_adjacency();
        self.group_bands(num_nodes);
        Ok(())
    }

    /// Group the points in bands of node indices as wide as the widest support's span, so
    /// that they scatter to the active nodes (module docs of [`BandScatter`]).
    fn group_bands(&mut self, num_nodes: usize) {
        let (stride, count, nodes) = (self.stride, &self.count, &self.grid_nodes);
        let support = |p: usize| &nodes[p * stride..p * stride + count[p] as usize];
        let span = (0..count.len())
            .into_par_iter()
            .map(|p| support(p).last().map_or(0, |&last| (last - support(p)[0]) as usize))
            .max()
            .unwrap_or(0);
        debug_assert!((0..count.len()).all(|p| support(p).windows(2).all(|w| w[0] < w[1])), "supports ascend");
        // Without points, one band over every node rather than one per node.
        let width = if count.is_empty() { num_nodes.max(1) } else { span + 1 };
        let first_node = |p: usize| support(p).first().map_or(0, |&g| g as usize);
        self.bands.group_by(count.len(), num_nodes.div_ceil(width).max(1), |p| first_node(p) / width);
        let active = &self.active_nodes.active_to_grid;
        self.bands.set_bounds(|b| active.partition_point(|&g| (g as usize) < b * width));
    }

    /// Every point's support nodes, values and gradients, in parallel.
    fn evaluate_supports<E: Send>(
        &mut self,
        n: usize,
        evaluate: impl Fn(usize, &mut [u32], &mut [f64], &mut [SVector<f64, D>]) -> Result<usize, E> + Sync,
    ) -> Result<(), (usize, E)> {
        let stride = self.stride;
        self.count.resize(n, 0);
        self.grid_nodes.resize(n * stride, 0);
        self.active.resize(n * stride, 0);
        self.values.resize(n * stride, 0.0);
        self.gradients.resize(n * stride, SVector::zeros());
        let first_error = self
            .grid_nodes
            .par_chunks_mut(stride)
            .zip(self.values.par_chunks_mut(stride))
            .zip(self.gradients.par_chunks_mut(stride))
            .zip(self.count.par_iter_mut())
            .enumerate()
            .filter_map(|(p, (((nodes, vals), grads), count))| match evaluate(p, nodes, vals, grads) {
                Ok(c) => {
                    *count = c as u32;
                    None
                }
                Err(e) => {
                    *count = 0;
                    Some((p, e))
                }
            })
            .min_by_key(|(p, _)| *p);
        first_error.map_or(Ok(()), Err)
    }

    /// Number the active nodes ascending in grid index, so that supports stay sorted, and
    /// renumber every support to them.
    fn number_active_nodes(&mut self, num_nodes: usize) {
        let stride = self.stride;
        let an = &mut self.active_nodes;
        an.grid_to_active.clear();
        an.grid_to_active.resize(num_nodes, INACTIVE);
        for p in 0..self.count.len() {
            let s = p * stride;
            for &g in &self.grid_nodes[s..s + self.count[p] as usize] {
                an.grid_to_active[g as usize] = 0;
            }
        }
        an.active_to_grid.clear();
        for (g, a) in an.grid_to_active.iter_mut().enumerate() {
            if *a != INACTIVE {
                *a = an.active_to_grid.len() as u32;
                an.active_to_grid.push(g as u32);
            }
        }
        let g2a = &an.grid_to_active;
        self.active.par_chunks_mut(stride).zip(self.grid_nodes.par_chunks(stride)).zip(self.count.par_iter()).for_each(
            |((act, grid_nodes), &c)| {
                for k in 0..c as usize {
                    act[k] = g2a[grid_nodes[k] as usize];
                }
            },
        );
    }

    /// Node → point adjacency by counting sort (points ascending within each node).
    fn build_adjacency(&mut self) {
        let (stride, n) = (self.stride, self.count.len());
        let n_active = self.active_nodes.active_to_grid.len();
        let adj = &mut self.node_points;
        adj.offsets.clear();
        adj.offsets.resize(n_active + 1, 0);
        for p in 0..n {
            let s = p * stride;
            for &a in &self.active[s..s + self.count[p] as usize] {
                adj.offsets[a as usize + 1] += 1;
            }
        }
        for i in 0..n_active {
            adj.offsets[i + 1] += adj.offsets[i];
        }
        adj.entries.clear();
        adj.entries.resize(adj.offsets[n_active], (0, 0));
        let mut fill = adj.offsets.clone();
        for p in 0..n {
            let s = p * stride;
            for (k, &a) in self.active[s..s + self.count[p] as usize].iter().enumerate() {
                let slot = &mut fill[a as usize];
                adj.entries[*slot] = (p as u32, k as u32);
                *slot += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    #[test]
    fn active_nodes_and_adjacency_of_two_points() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [4, 4]).unwrap();
        let mut c = Connectivity::<2>::new(BasisKind::Linear);
        let pos = [Vector2::new(0.5, 0.5), Vector2::new(1.5, 0.5)];
        c.compute(&g, &pos, &[Vector2::zeros(); 2]).unwrap();
        // Cells (0,0) and (1,0): grid nodes 0,1,2 and 5,6,7 are active.
        assert_eq!(c.active_nodes().active_to_grid, vec![0, 1, 2, 5, 6, 7]);
        assert_eq!(c.support_nodes(0), &[0, 1, 3, 4]);
        assert_eq!(c.support_nodes(1), &[1, 2, 4, 5]);
        // Active node 1 (grid 1) is touched by point 0 (slot 1) and point 1 (slot 0).
        assert_eq!(c.node_points().of(1), &[(0, 1), (1, 0)]);
        assert_eq!(c.node_points().of(0), &[(0, 0)]);
    }

    #[test]
    fn first_failing_point_is_named() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [2, 2]).unwrap();
        let mut c = Connectivity::<2>::new(BasisKind::Linear);
        let pos = [Vector2::new(0.5, 0.5), Vector2::new(2.5, 0.5), Vector2::new(-1.0, 0.5)];
        let e = c.compute(&g, &pos, &[Vector2::zeros(); 3]).unwrap_err();
        assert_eq!(e.point, 1);
    }

    /// A point exactly on a grid node (linear basis) touches four nodes of which one has
    /// zero weight and zero gradient: that node is not part of the support, so it is not an
    /// active node and the tangent has no empty row.
    #[test]
    fn nodes_with_no_weight_and_no_gradient_are_dropped() {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [4, 4]).unwrap();
        let mut conn = Connectivity::new(BasisKind::Linear);
        conn.compute(&grid, &[Vector2::new(2.0, 2.0)], &[Vector2::new(0.25, 0.25)]).unwrap();
        // Nodes (2,2) with N = 1, and (3,2), (2,3) with N = 0 but gradient ±1 along one axis.
        assert_eq!(conn.support_len(0), 3);
        assert_eq!(conn.active_nodes().len(), 3);
        assert!(conn.support_values(0).iter().sum::<f64>() == 1.0);
        let g: Vector2<f64> = conn.support_gradients(0).iter().sum();
        assert_eq!(g, Vector2::zeros());
    }

    /// The points' bands scatter to the active nodes: each node gets the sum of its points'
    /// shares, as a serial loop gives to round-off and bitwise the same on 1 and 3 threads,
    /// for every basis on a grid and on a mesh of two blocks (nodes not one lattice).
    #[test]
    fn bands_scatter_to_the_active_nodes_in_one_order() {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(0.5, 0.25), [12, 30]).unwrap();
        let x: Vec<_> = (0..500)
            .map(|i| Vector2::new(0.3 + 5.2 * ((i * 37 % 101) as f64 / 101.0), 0.4 + 0.013 * i as f64))
            .collect();
        let l = vec![Vector2::new(0.1, 0.06); x.len()];
        let mut mesh = FeMesh::block(Vector2::zeros(), Vector2::new(1.0, 1.0), [6, 5], 2).unwrap();
        mesh.append(FeMesh::block(Vector2::new(0.0, 1.0), Vector2::new(0.5, 1.5), [7, 3], 2).unwrap()).unwrap();
        let mut cases = Vec::new();
        for kind in [BasisKind::Linear, BasisKind::Gimp, BasisKind::QuadraticBSpline] {
            let mut conn = Connectivity::new(kind);
            conn.compute(&grid, &x, &l).unwrap();
            cases.push(conn);
        }
        let mut conn = Connectivity::new(BasisKind::Linear);
        conn.compute_mesh(&mesh).unwrap();
        cases.push(conn);
        for conn in &cases {
            let n = conn.active_nodes().len();
            let run = |threads: usize| {
                let mut out = vec![1.0; 2 * n];
                rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| {
                    conn.bands().scatter(2, &mut out, |p, w| {
                        for (k, &a) in conn.support_nodes(p).iter().enumerate() {
                            let v = w.node(a as usize);
                            v[0] += conn.support_values(p)[k];
                            v[1] += conn.support_values(p)[k] * (1.0 + p as f64);
                        }
                    })
                });
                out
            };
            let one = run(1);
            assert_eq!(one, run(3));
            let mut serial = vec![0.0; 2 * n];
            for p in 0..conn.num_points() {
                for (k, &a) in conn.support_nodes(p).iter().enumerate() {
                    serial[2 * a as usize] += conn.support_values(p)[k];
                    serial[2 * a as usize + 1] += conn.support_values(p)[k] * (1.0 + p as f64);
                }
            }
            for (a, b) in one.iter().zip(&serial) {
                assert!((a - b).abs() <= 1e-12 * b.abs().max(1.0), "{a} vs {b}");
            }
            let total: f64 = one.iter().step_by(2).sum();
            assert!((total - conn.num_points() as f64).abs() < 1e-9, "{total}");
        }
    }
}
