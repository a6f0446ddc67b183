//! The cell averages of B-bar and assumed strain (docs/theory.md §13): for every support
//! slot of every point, the volume-averaged gradient b̄ over the points of its averaging
//! group (cell or element), and the strain gradient c = β ∂N + (1 − β) b̄ built from it;
//! and the averaging groups themselves, which F-bar sums over at every iterate.

use loam_grid::Connectivity;
use loam_model::Model;
use nalgebra::SVector;

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

    /// The points of each group in turn.
    pub fn groups(&self) -> impl Iterator<Item = &[u32]> {
        self.starts.windows(2).map(|w| &self.order[w[0] as usize..w[1] as usize])
    }

    /// The points of point `p`'s group (`p` among them).
    pub fn members(&self, p: usize) -> &[u32] {
        let g = self.group_of[p] as usize;
        &self.order[self.starts[g] as usize..self.starts[g + 1] as usize]
    }
}

/// B-bar's b̄ of every point's support slot: Σ_q v_q ∂N_a(x_q) / Σ_q v_q over the points q
/// of its averaging group (in axisymmetry the dilatation operator ∂N_a + (N_a / r) e_r in
/// place of ∂N_a, docs/theory.md §20), `stride` per point, into `out`.
pub(crate) fn cell_averaged_gradients<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
    groups: &CellGroups,
    out: &mut Vec<SVector<f64, D>>,
) {
    let pts = model.points();
    let n = pts.len();
    let stride = conn.stride();
    out.clear();
    out.resize(n * stride, SVector::zeros());
    let mut sums: Vec<(u32, SVector<f64, D>)> = Vec::new();
    let axisymmetric = model.axisymmetric();
    for group in groups.groups() {
        sums.clear();
        let mut volume = 0.0;
        for &p in group {
            let p = p as usize;
            let v = pts.volume()[p];
            volume += v;
            let inv_r = if axisymmetric { 1.0 / model.configuration()[p][0] } else { 0.0 };
            for (a, (&node, g)) in conn.support_nodes(p).iter().zip(conn.support_gradients(p)).enumerate() {
                // The dilatation operator: ∂N_a, and in axisymmetry (N_a / r) e_r beside it.
                let mut d = *g;
                if axisymmetric {
                    d[0] += conn.support_values(p)[a] * inv_r;
                }
                match sums.iter_mut().find(|(m, _)| *m == node) {
                    Some((_, s)) => *s += d * v,
                    None => sums.push((node, d * v)),
                }
            }
        }
        for &p in group {
            let p = p as usize;
            for (k, node) in conn.support_nodes(p).iter().enumerate() {
                // Every support node of the group's points was summed above.
                let s = sums.iter().find(|(m, _)| m == node).expect("a node of the group").1;
                out[p * stride + k] = s / volume;
            }
        }
    }
}
