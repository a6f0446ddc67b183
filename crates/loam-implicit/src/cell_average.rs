//! The cell averages of B-bar and assumed strain (docs/theory.md §13): for every support
//! slot of every point, the volume-averaged gradient b̄ over the points of its averaging
//! group (cell or element), and the strain gradient c = β ∂N + (1 − β) b̄ built from it.

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

/// B-bar's b̄ of every point's support slot: Σ_q v_q ∂N_a(x_q) / Σ_q v_q over the points q
/// of its averaging group (in axisymmetry the dilatation operator ∂N_a + (N_a / r) e_r in
/// place of ∂N_a, docs/theory.md §20), `stride` per point, into `out`. Points are grouped by sorting on
/// the group, so the sums run in a fixed order (deterministic).
pub(crate) fn cell_averaged_gradients<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
    out: &mut Vec<SVector<f64, D>>,
) {
    let pts = model.points();
    let n = pts.len();
    let stride = conn.stride();
    let mut order: Vec<(usize, usize)> = (0..n).map(|p| (model.averaging_group(p), p)).collect();
    order.sort_unstable();
    out.clear();
    out.resize(n * stride, SVector::zeros());
    let mut sums: Vec<(u32, SVector<f64, D>)> = Vec::new();
    let axisymmetric = model.axisymmetric();
    for group in order.chunk_by(|a, b| a.0 == b.0) {
        sums.clear();
        let mut volume = 0.0;
        for &(_, p) in group {
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
        for &(_, p) in group {
            for (k, node) in conn.support_nodes(p).iter().enumerate() {
                // Every support node of the group's points was summed above.
                let s = sums.iter().find(|(m, _)| m == node).expect("a node of the group").1;
                out[p * stride + k] = s / volume;
            }
        }
    }
}
