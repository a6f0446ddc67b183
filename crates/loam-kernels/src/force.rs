//! The internal force f_int,I = Σ_p v_p σ_p ∂N_I/∂x (docs/theory.md §1), with the hoop
//! stress's radial share v_p σ_θθ N_I / r_p in axisymmetry (§20): one kernel for the
//! implicit residual, the dynamic start and the explicit grid update.

use crate::scatter_nodal;
use loam_grid::Connectivity;
use nalgebra::{Matrix3, SVector};

/// Internal force of a point at one support node, v σ ∂N_a; with B-bar (b̄_a given)
/// also σ : (⅓ (b̄_a − ∂N_a) ⊗ e_i) I = v (tr σ / 3)(b̄_a − ∂N_a); in axisymmetry
/// (`hoop` = N_a / r given) also v σ_θθ N_a / r on the radial (x) component, σ_θθ the
/// out-of-plane σ_zz, and the point's dilatation operator in B-bar's term is
/// ∂N_a + (N_a / r) e_r.
#[inline]
pub fn internal_force<const D: usize>(
    volume: f64,
    stress: &Matrix3<f64>,
    grad: &SVector<f64, D>,
    bbar: Option<&SVector<f64, D>>,
    hoop: Option<f64>,
) -> SVector<f64, D> {
    let mut f = SVector::<f64, D>::from_fn(|i, _| volume * (0..D).map(|j| stress[(i, j)] * grad[j]).sum::<f64>());
    if let Some(b) = bbar {
        // b̄_a less the point's own dilatation operator, which has the hoop part too.
        let mut d = b - grad;
        if let Some(n_over_r) = hoop {
            d[0] -= n_over_r;
        }
        f += d * (volume * stress.trace() / 3.0);
    }
    if let Some(n_over_r) = hoop {
        f[0] += volume * stress[(2, 2)] * n_over_r;
    }
    f
}

/// Scatter f_int,I into `out` (D values per active node), where `force(point, slot)` is
/// the point's internal force at the node in its support slot (see [`internal_force`]).
pub fn scatter_internal_force<const D: usize>(
    conn: &Connectivity<D>,
    out: &mut [f64],
    force: impl Fn(usize, usize) -> SVector<f64, D> + Sync,
) {
    scatter_nodal(conn, D, out, |p, slot, node| {
        let f = force(p, slot);
        for i in 0..D {
            node[i] += f[i];
        }
    });
}
