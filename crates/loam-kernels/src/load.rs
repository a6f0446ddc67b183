//! The loads' share of a step (docs/theory.md §17): each load vertex connected to the
//! active nodes, its force spread to them, and the places of follower loads' vertices in a
//! trial state.
//!
//! A vertex is a point of the surface, not of the body's volume: its nodal weights are the
//! grid's shape functions at its place (GIMP's tent, the B-spline), the consistent nodal
//! load of the basis. A weight on a node no material point reaches (the linear basis where
//! the surface and the points next to it lie in different cells) would load a node with no
//! stiffness; it is moved to the vertex's other nodes in proportion to their weights, which
//! keeps the resultant and moves the load by at most one cell. The work is serial over the
//! vertices, which grow with the surface, not the volume, and fixes the summation order.

use crate::interpolate;
use crate::ConnectError;
use loam_grid::{ActiveNodes, Connectivity, Grid, INACTIVE};
use loam_model::{Load, LoadLevel, Model};
use loam_points::PointStore;
use nalgebra::{Matrix3, SVector};

/// `x`, brought onto the grid where it lies on a grid face or within half a cell beyond it:
/// a cell owns [x_i, x_{i+1}), so the upper faces belong to no cell (they are taken 1e-12
/// of a cell inside), yet a loaded boundary may end on one (a column as wide as its grid),
/// and a vertex carried by a point next to a fixed grid face may be extrapolated a little
/// past it. Farther out, `x` is returned as it is (and refused by the basis).
fn onto_grid<const D: usize>(grid: &Grid<D>, x: &SVector<f64, D>) -> SVector<f64, D> {
    let (lo, hi, h) = (grid.origin(), grid.extent_max(), grid.cell_size());
    SVector::from_fn(|a, _| {
        if x[a] < lo[a] && lo[a] - x[a] <= 0.5 * h[a] {
            lo[a]
        } else if x[a] >= hi[a] - 1e-9 * h[a] && x[a] - hi[a] <= 0.5 * h[a] {
            hi[a] - 1e-12 * h[a]
        } else {
            x[a]
        }
    })
}

/// Every load vertex's support: active nodes and weights (summing to 1).
#[derive(Debug, Clone, Default)]
pub struct LoadSupports {
    /// Per load, the index of its first vertex; one more entry at the end.
    first_vertex: Vec<usize>,
    /// Per vertex (all loads in order), the start of its entries; one more at the end.
    first_entry: Vec<usize>,
    node: Vec<u32>,
    weight: Vec<f64>,
}

impl LoadSupports {
    /// Connect the vertices of `model`'s loads (at the configuration the mechanics is
    /// written on) to the active nodes `active`. A vertex that touches no active node
    /// (the load is not on the material) is an error naming the load and the place.
    pub fn connect<const D: usize>(
        &mut self,
        model: &Model<D>,
        active: &ActiveNodes,
        step: usize,
    ) -> Result<(), ConnectError> {
        let (grid, basis) = (model.grid(), model.basis());
        let mut nodes = vec![0u32; basis.max_support(D)];
        let mut values = vec![0.0; nodes.len()];
        let mut gradients = vec![SVector::<f64, D>::zeros(); nodes.len()];
        self.first_vertex.clear();
        self.first_entry.clear();
        self.node.clear();
        self.weight.clear();
        for (k, load) in model.loads().iter().enumerate() {
            self.first_vertex.push(self.first_entry.len());
            let places = if model.geometrically_linear() { &load.surface().vertices[..] } else { load.positions() };
            for (v, x) in places.iter().enumerate() {
                self.first_entry.push(self.node.len());
                let off =
                    || ConnectError::LoadOffMaterial { step, load: k, vertex: v, position: x.as_slice().to_vec() };
                let count = basis
                    .evaluate(grid, &onto_grid(grid, x), &SVector::zeros(), &mut nodes, &mut values, &mut gradients)
                    .map_err(|_| off())?;
                let start = self.node.len();
                for (&g, &w) in nodes[..count].iter().zip(&values[..count]) {
                    let a = active.grid_to_active[g as usize];
                    if a != INACTIVE && w > 0.0 {
                        self.node.push(a);
                        self.weight.push(w);
                    }
                }
                let total: f64 = self.weight[start..].iter().sum();
                if total < 1e-9 {
                    return Err(off());
                }
                self.weight[start..].iter_mut().for_each(|w| *w /= total);
            }
        }
        self.first_vertex.push(self.first_entry.len());
        self.first_entry.push(self.node.len());
        Ok(())
    }

    /// Active nodes and weights of vertex `v` of load `k`.
    pub fn support(&self, k: usize, v: usize) -> (&[u32], &[f64]) {
        let i = self.first_vertex[k] + v;
        let range = self.first_entry[i]..self.first_entry[i + 1];
        (&self.node[range.clone()], &self.weight[range])
    }

    /// Add the nodal forces of `model`'s dead loads at `level` to `out` (D per active node).
    pub fn add_dead<const D: usize>(&self, model: &Model<D>, level: LoadLevel, out: &mut [f64]) {
        for (k, load) in model.loads().iter().enumerate().filter(|(_, l)| !l.is_follower()) {
            self.spread(k, load.dead_forces(), model.load_scale(k, level), out);
        }
    }

    /// Add the nodal forces of the follower loads at `level` to `out`, each on the vertex
    /// places `places(k, load)` (its committed ones, or those of a trial state).
    pub fn add_follower<const D: usize>(
        &self,
        model: &Model<D>,
        level: LoadLevel,
        places: impl Fn(usize, &Load<D>) -> Vec<SVector<f64, D>>,
        out: &mut [f64],
    ) {
        let mut forces = Vec::new();
        for (k, load) in model.loads().iter().enumerate().filter(|(_, l)| l.is_follower()) {
            load.forces_on(&places(k, load), &mut forces);
            self.spread(k, &forces, model.load_scale(k, level), out);
        }
    }

    /// Add Σ_v N_I(x_v) f_v · scale for load `k` to `out`.
    fn spread<const D: usize>(&self, k: usize, forces: &[SVector<f64, D>], scale: f64, out: &mut [f64]) {
        for (v, f) in forces.iter().enumerate() {
            let (nodes, weights) = self.support(k, v);
            for (&a, &w) in nodes.iter().zip(weights) {
                for i in 0..D {
                    out[a as usize * D + i] += w * scale * f[i];
                }
            }
        }
    }
}

/// The vertices of `load` in a trial state: each carried by its point (committed place
/// and deformation gradient in `points`), moved by the nodal increment `du`
/// (u_p = Σ N_I(x_p) Δu_I) and stretched by its trial gradient ΔF_p F_p:
/// x_v = x_p + u_p + diag(ΔF_p F_p) (X_v − X_p) (`Load::carried`).
pub fn trial_vertices<const D: usize>(
    conn: &Connectivity<D>,
    load: &Load<D>,
    points: &PointStore<D>,
    du: &[f64],
    delta_f: &[Matrix3<f64>],
) -> Vec<SVector<f64, D>> {
    (0..load.positions().len())
        .map(|v| {
            let p = load.carriers()[v] as usize;
            let moved = points.position()[p] + interpolate(conn, p, du);
            load.carried(v, &moved, &(delta_f[p] * points.deformation_gradient()[p]))
        })
        .collect()
}
