//! The load stiffness of follower pressures (docs/theory.md §17): a pressure on the current
//! facets changes with the increment, so the residual R = f_int − f_ext − f_p(Δu) has the
//! extra tangent −∂f_p/∂Δu, without which Newton would lose its quadratic rate.
//!
//! Vertex v's force is f_v = −s Σ_{e∋v} (p_v / D) a_e (s the load's factor, a_e the facet's
//! area vector); on a surface of revolution (axisymmetry) the share p_v / D is the ring's
//! p_v 2π (2 r_v + r_w) / 6, which moves with the radii, so the block below gains
//! a_e ⊗ ∂share/∂x_w (`Load::portion_gradient`). A vertex carried by point p sits at x_w = x_p + u_p + diag(ΔF_p F_p) R_w
//! with R_w = X_w − X_p, so ∂x_w,k/∂Δu_I,k = c_wI,k = N_I(x_p) + (Σ_l ∂N_I/∂x_l F_lk) R_w,k.
//! In 2D a_e = R (x_1 − x_0), R the rotation by −90°, so ∂a_e/∂x_1 = R = −∂a_e/∂x_0; in 3D
//! ∂a_e/∂x_k = ½ [x_{k+2} − x_{k+1}]_× (cyclic). The block coupling the force at node J
//! (weight ω_vJ of v) to the increment at node I is
//! s ω_vJ [share ∂a_e/∂x_w + a_e ⊗ ∂share/∂x_w] ∂x_w/∂Δu_I, the last diag(c_wI) without
//! anti-locking; B-bar, assumed strain and F-bar put the cell's dilatation into ΔF, which
//! couples the components ([`Carry::derivative`]).

use crate::cell_average::CellAverage;
use crate::points::TrialState;
use loam_grid::Connectivity;
use loam_kernels::{trial_vertices, LoadSupports};
use loam_model::{Load, LoadKind, LoadLevel, Model};
use loam_points::area_vector;
use loam_solve::{BlockPattern, SystemMatrix};
use nalgebra::{SMatrix, SVector};

/// The node couplings the follower loads add to the pattern: every node a vertex's force
/// reaches with every node that moves a vertex of its facets (lists are extended).
pub(crate) fn follower_couplings<const D: usize>(
    model: &Model<D>,
    conn: &Connectivity<D>,
    supports: &LoadSupports,
    couplings: &mut [Vec<u32>],
) {
    for (k, load) in model.loads().iter().enumerate().filter(|(_, l)| l.is_follower()) {
        for facet in &load.surface().facets {
            let moving: Vec<u32> = facet
                .iter()
                .flat_map(|&w| conn.support_nodes(load.carriers()[w as usize] as usize).iter().copied())
                .collect();
            for &v in facet {
                for &j in supports.support(k, v as usize).0 {
                    couplings[j as usize].extend_from_slice(&moving);
                    for &i in &moving {
                        couplings[i as usize].push(j);
                    }
                }
            }
        }
    }
}

/// What the load stiffness reads: the connectivity, the load vertices' supports, the
/// committed positions, the trial increment and increments of deformation, and the cell
/// averages of B-bar or assumed strain (which enter ΔF, and so the vertices' places).
pub(crate) struct FollowerInputs<'a, const D: usize> {
    pub model: &'a Model<D>,
    pub conn: &'a Connectivity<D>,
    pub supports: &'a LoadSupports,
    pub level: LoadLevel,
    pub du: &'a [f64],
    pub delta_f: &'a [nalgebra::Matrix3<f64>],
    pub average: Option<CellAverage<'a, D>>,
    /// With F-bar, the trial state, whose ΔF̄ carries the vertices.
    pub fbar: Option<&'a TrialState<D>>,
}

/// K += −∂f_p/∂Δu for every follower load, facet by facet in a fixed order.
pub(crate) fn add_follower_tangent<const D: usize>(
    inputs: &FollowerInputs<D>,
    pattern: &BlockPattern,
    constrained: &[bool],
    matrix: &mut SystemMatrix,
) {
    let FollowerInputs { model, conn, supports, level, du, delta_f, average, fbar } = *inputs;
    let points = model.points();
    for (k, load) in model.loads().iter().enumerate().filter(|(_, l)| l.is_follower()) {
        let LoadKind::Pressure { values: pressure, .. } = load.kind() else { continue };
        let scale = model.load_scale(k, level);
        let x = trial_vertices(conn, load, points, du, delta_f);
        for facet in &load.surface().facets {
            let corners = facet.map(|v| x[v as usize]);
            let a = area_vector(&corners);
            for (slot, &w) in facet.iter().enumerate() {
                let da = area_derivative(&corners, slot);
                let p = load.carriers()[w as usize] as usize;
                let offset = *load.offset(w as usize);
                let carry = Carry {
                    p,
                    offset,
                    f: points.deformation_gradient()[p],
                    average,
                    inv_radius: model.axisymmetric().then(|| 1.0 / model.configuration()[p][0]),
                    fbar: fbar.map(|trial| FBarCarry::new(model, trial, p, &offset)),
                };
                for (at, &v) in facet.iter().enumerate() {
                    let amount = scale * pressure[v as usize];
                    let share = load.portion(amount, facet, at, &x);
                    let block = da * share + a * load.portion_gradient(amount, at, slot).transpose();
                    let (nodes_j, weights) = supports.support(k, v as usize);
                    for (&j, &omega) in nodes_j.iter().zip(weights) {
                        add_moving_blocks(conn, &carry, &(block * omega), j, pattern, constrained, matrix);
                    }
                }
            }
        }
    }
}

/// A vertex's carrier: point `p`, the offset X_v − X_p, the committed F_p, the cell
/// averages (with B-bar or assumed strain), 1 / r_p (axisymmetry) and F-bar's terms.
struct Carry<'a, const D: usize> {
    p: usize,
    offset: SVector<f64, D>,
    f: nalgebra::Matrix3<f64>,
    average: Option<CellAverage<'a, D>>,
    inv_radius: Option<f64>,
    fbar: Option<FBarCarry<'a, D>>,
}

/// With F-bar the vertex moves with ΔF̄ = s ΔF, s = (ΔJ̄ / ΔJ)^{1/m}, and δΔF̄ =
/// s δΔF + (1/m) (tr l̄ − tr l) ΔF̄ (crate::fbar): the carrier's trial state, s, and the
/// lever (ΔF̄ F)_kk R_k / m of the dilatation's part.
struct FBarCarry<'a, const D: usize> {
    trial: &'a TrialState<D>,
    scale: f64,
    lever: SVector<f64, D>,
    axisymmetric: bool,
}

impl<'a, const D: usize> FBarCarry<'a, D> {
    fn new(model: &Model<D>, trial: &'a TrialState<D>, p: usize, offset: &SVector<f64, D>) -> Self {
        let m = if D == 2 && !model.axisymmetric() { 2.0 } else { 3.0 };
        let ratio = trial.volume[p] / model.points().volume()[p] / trial.jacobian[p];
        let moved = trial.delta_f[p] * model.points().deformation_gradient()[p];
        let lever = SVector::from_fn(|k, _| moved[(k, k)] * offset[k] / m);
        Self { trial, scale: ratio.powf(1.0 / m), lever, axisymmetric: model.axisymmetric() }
    }

    /// The dilatation's part of ∂x_v,k/∂Δu_I,j, lever_k (b̄_I − ∂N_I/∂x − N_I / r e_r)_j, for
    /// support slot `slot` (value `n`) of carrier `p`.
    fn dilatation(&self, slot: usize, n: f64, p: usize) -> SMatrix<f64, D, D> {
        let mut extra = self.trial.average_x[slot] - self.trial.grad_x[slot];
        if self.axisymmetric {
            extra[0] -= n * self.trial.inv_radius[p];
        }
        self.lever * extra.transpose()
    }
}

impl<const D: usize> Carry<'_, D> {
    /// ∂x_v,k/∂Δu_I,j for support slot `a` of the carrier (value `n`, gradient `g`):
    /// x_v,k = x_p,k + u_p,k + (ΔF F)_kk R_k with ΔF = I + Σ_I Δu_I ⊗ c_I, c_I the strain
    /// gradient, gives δ_kj [N_I + (Σ_m c_I,m F_mk) R_k]; with anti-locking ΔF also carries
    /// (θ̄ − θ)/3 I, θ̄ = Σ Δu_I · b̄_I the cell's dilatation and θ = Σ Δu_I · (c_I + N_I/r e_r)
    /// the point's, adding F_kk R_k (b̄_I − c_I − N_I/r e_r)_j / 3.
    fn derivative(&self, conn: &Connectivity<D>, a: usize, n: f64, g: &SVector<f64, D>) -> SMatrix<f64, D, D> {
        let slot = self.p * conn.stride() + a;
        let c = self.average.map_or(*g, |avg| avg.strain_gradient(slot, g));
        let s = self.fbar.as_ref().map_or(1.0, |fbar| fbar.scale);
        let mut d = SMatrix::<f64, D, D>::from_fn(|k, j| {
            if k == j {
                n + s * (0..D).map(|m| c[m] * self.f[(m, k)]).sum::<f64>() * self.offset[k]
            } else {
                0.0
            }
        });
        if let Some(fbar) = &self.fbar {
            d += fbar.dilatation(slot, n, self.p);
        }
        if let Some(avg) = self.average {
            let mut own = c;
            if let Some(inv_r) = self.inv_radius {
                own[0] += n * inv_r;
            }
            let extra = (avg.average(slot) - own) / 3.0;
            for k in 0..D {
                let lever = self.f[(k, k)] * self.offset[k];
                for j in 0..D {
                    d[(k, j)] += lever * extra[j];
                }
            }
        }
        d
    }
}

/// Add `block` · C_I to the coupling of node `j` with every node I of the carrier's
/// support, C_I = ∂x_v/∂Δu_I ([`Carry::derivative`]).
fn add_moving_blocks<const D: usize>(
    conn: &Connectivity<D>,
    carry: &Carry<D>,
    block: &SMatrix<f64, D, D>,
    j: u32,
    pattern: &BlockPattern,
    constrained: &[bool],
    matrix: &mut SystemMatrix,
) {
    let p = carry.p;
    let mut flat = [0.0; 9];
    let supports = conn.support_nodes(p).iter().zip(conn.support_values(p)).zip(conn.support_gradients(p));
    for (a, ((&i, &n), g)) in supports.enumerate() {
        let coupling = block * carry.derivative(conn, a, n, g);
        for r in 0..D {
            for c in 0..D {
                flat[r * D + c] = coupling[(r, c)];
            }
        }
        matrix.add_block(pattern, constrained, j as usize, i as usize, &flat[..D * D]);
    }
}

/// ∂a/∂x_slot of the facet with corners `x` (module docs).
fn area_derivative<const D: usize>(x: &[SVector<f64, D>; D], slot: usize) -> SMatrix<f64, D, D> {
    match D {
        2 => {
            let sign = if slot == 1 { 1.0 } else { -1.0 };
            SMatrix::from_fn(|i, j| sign * [[0.0, 1.0], [-1.0, 0.0]][i][j])
        }
        3 => {
            let e = (x[(slot + 2) % 3] - x[(slot + 1) % 3]) * 0.5;
            // [e]_× δ = e × δ
            let m = [[0.0, -e[2], e[1]], [e[2], 0.0, -e[0]], [-e[1], e[0], 0.0]];
            SMatrix::from_fn(|i, j| m[i][j])
        }
        _ => unreachable!("loads exist in 2D and 3D"),
    }
}

/// Whether the model has a follower load (and so a load stiffness and its couplings).
pub(crate) fn has_follower<const D: usize>(loads: &[Load<D>]) -> bool {
    loads.iter().any(|l| l.is_follower())
}
