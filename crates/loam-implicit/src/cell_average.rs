//! The cell averages of B-bar and assumed strain (docs/theory.md §13): for every support
//! slot of every point, the volume-averaged gradient b̄ over the points of its averaging
//! group (cell or element), and the strain gradient c = β ∂N + (1 − β) b̄ built from it;
//! and the averaging groups themselves, which F-bar sums over at every iterate.

use loam_grid::Connectivity;
use loam_model::Model;
use nalgebra::SVector;
use rayon::prelude::*;

/// The cell averages of one step's connectivity.
#[derive(Clone, Copy)]
pub(crate) struct CellAverage<'a, const D: usize> {
    /// The volume-averaged gradient b̄ of each point's support slot over its cell
    /// (element), `stride` per point.
    pub gradients: &'a [SVector<f64, D>],
    /// β: the weight of each point's own deviatoric strain (1 for B-bar).
    pub deviatoric_weight: f64,
}

impl<'a, const D: usize> CellAverage<'a, D> {
    /// The model's cell averages over `gradients`; `None` without anti-locking.
    pub fn of(model: &Model<D>, gradients: &'a [SVector<f64, D>]) -> Option<Self> {
        model.anti_locking().deviatoric_weight().map(|deviatoric_weight| Self { gradients, deviatoric_weight })
    }

    /// The gradient c = β ∂N + (1 − β) b̄ of support slot `k` (point p, node a:
    /// k = p·stride + a) with the plain gradient `grad`. The point's strain operator is
    /// E_a,i = e_i ⊗ c_a + ⅓ (b̄_a − c_a)_i I: the cell's average strain plus β times the
    /// point's deviatoric deviation from it, with the cell's dilatation.
    #[inline]
    pub fn strain_gradient(&self, k: usize, grad: &SVector<f64, D>) -> SVector<f64, D> {
        let beta = self.deviatoric_weight;
        if beta == 1.0 {
            *grad
        } else {
            grad * beta + self.gradients[k] * (1.0 - beta)
        }
    }

    #[inline]
    pub fn average(&self, k: usize) -> &'a SVector<f64, D> {
        &self.gradients[k]
    }
}

/// The points of every averaging group (cell or element; `Model::averaging_group`), each
/// group's in ascending order, so that sums over a group run in a fixed order
/// (deterministic).
#[derive(Debug, Default)]
pub(crate) struct CellGroups {
    /// Point indices sorted by (group, point).
    order: Vec<u32>,
    /// Where each group starts in `order`, and its end last.
    starts: Vec<u32>,
    /// Each point's group, an index into `starts`.
    group_of: Vec<u32>,
}

impl CellGroups {
    /// The groups of the model's points on its current configuration.
    pub fn build<const D: usize>(&mut self, model: &Model<D>) {
        let n = model.points().len();
        let mut keyed: Vec<(usize, u32)> = (0..n).map(|p| (model.averaging_group(p), p as u32)).collect();
        keyed.sort_unstable();
        self.order.clear();
        self.starts.clear();
        self.group_of.clear();
        self.group_of.resize(n, 0);
        for (k, &(group, p)) in keyed.iter().enumerate() {
            if k == 0 || keyed[k - 1].0 != group {
                self.starts.push(k as u32);
            }
            self.group_of[p as usize] = (self.starts.len() - 1) as u32;
            self.order.push(p);
        }
        self.starts.push(n as u32);
    }

    /// How many groups there are.
    pub fn len(&self) -> usize {
        self.starts.len().saturating_sub(1)
    }

    /// The points of group `g`, in ascending order.
    pub fn group(&self, g: usize) -> &[u32] {
        &self.order[self.starts[g] as usize..self.starts[g + 1] as usize]
    }

    /// Point `p`'s group.
    pub fn group_of(&self, p: usize) -> usize {
        self.group_of[p] as usize
    }
}

/// What [`average_dilatation_operators`] averages: each point's weight (its volume), its
/// support gradients and 1 / r (axisymmetry; unread in a plane model).
pub(crate) struct PointOperators<V, G, R> {
    pub volume: V,
    pub gradients: G,
    pub inv_radius: R,
}

/// Scratch of [`average_dilatation_operators`], reused: each group's nodes (the union of
/// its points' supports, `stride` slots, unused ones `u32::MAX`), their weighted sums and
/// the group's total weight.
#[derive(Debug, Default)]
pub(crate) struct GroupSums<const D: usize> {
    nodes: Vec<u32>,
    sums: Vec<SVector<f64, D>>,
    volume: Vec<f64>,
}

/// b̄ of every point's support slot: Σ_q v_q d_a(x_q) / Σ_q v_q over the points q of its
/// averaging group, d_a = ∂N_a the dilatation operator (in axisymmetry ∂N_a + (N_a / r) e_r,
/// docs/theory.md §20), `stride` per point, into `out`. B-bar takes the start-of-step
/// volumes and gradients, F-bar the trial ones. Every group's sums are taken once, over its
/// points in order (deterministic). A group's points share its nodes (linear basis, FEM
/// mesh: `Model::with_anti_locking` asks for it), though a point may leave out one it
/// barely touches (docs/theory.md §11), so a group's nodes are the union of its points'.
pub(crate) fn average_dilatation_operators<'a, const D: usize>(
    groups: &CellGroups,
    conn: &Connectivity<D>,
    axisymmetric: bool,
    operators: PointOperators<
        impl Fn(usize) -> f64 + Sync,
        impl Fn(usize) -> &'a [SVector<f64, D>] + Sync,
        impl Fn(usize) -> f64 + Sync,
    >,
    scratch: &mut GroupSums<D>,
    out: &mut Vec<SVector<f64, D>>,
) {
    let PointOperators { volume, gradients, inv_radius } = operators;
    let stride = conn.stride();
    let GroupSums { nodes, sums, volume: group_volume } = scratch;
    nodes.clear();
    nodes.resize(groups.len() * stride, u32::MAX);
    sums.clear();
    sums.resize(groups.len() * stride, SVector::zeros());
    group_volume.resize(groups.len(), 0.0);
    let slot_of = |nodes: &[u32], node: u32| nodes.iter().position(|&m| m == node);
    let chunks = (nodes.par_chunks_mut(stride), sums.par_chunks_mut(stride), group_volume.par_iter_mut());
    chunks.into_par_iter().enumerate().for_each(|(g, (nodes, sums, total))| {
        *total = 0.0;
        for &q in groups.group(g) {
            let q = q as usize;
            let v = volume(q);
            *total += v;
            let grads = gradients(q);
            for (b, &node) in conn.support_nodes(q).iter().enumerate() {
                let mut d = grads[b];
                if axisymmetric {
                    d[0] += conn.support_values(q)[b] * inv_radius(q);
                }
                // A group has at most `stride` nodes: those of its cell (element).
                let k = slot_of(nodes, node).unwrap_or_else(|| {
                    let free = slot_of(nodes, u32::MAX).expect("a group's nodes are its cell's");
                    nodes[free] = node;
                    free
                });
                sums[k] += d * v;
            }
        }
    });
    out.resize(groups.group_of.len() * stride, SVector::zeros());
    out.par_chunks_mut(stride).enumerate().for_each(|(p, out)| {
        let g = groups.group_of(p);
        let group_nodes = &nodes[g * stride..][..stride];
        for (a, &node) in conn.support_nodes(p).iter().enumerate() {
            let k = slot_of(group_nodes, node).expect("every node of the group's points was summed");
            out[a] = sums[g * stride + k] / group_volume[g];
        }
    });
}

/// B-bar's b̄ (start-of-step volumes and gradients, [`average_dilatation_operators`]).
pub(crate) fn cell_averaged_gradients<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
    groups: &CellGroups,
    scratch: &mut GroupSums<D>,
    out: &mut Vec<SVector<f64, D>>,
) {
    let (pts, configuration) = (model.points(), model.configuration());
    let operators = PointOperators {
        volume: |q: usize| pts.volume()[q],
        gradients: |q: usize| conn.support_gradients(q),
        inv_radius: |q: usize| 1.0 / configuration[q][0],
    };
    out.clear();
    average_dilatation_operators(groups, conn, model.axisymmetric(), operators, scratch, out);
}
