//! One implicit step as a Newton system (DESIGN.md "Data flow of one implicit step").
//!
//! The unknown is the incremental nodal displacement Δu of the active nodes. For a given
//! Δu every point recomputes its kinematics and stress from its *committed* state
//! (THEORY.md §7), so iterations never compound; the residual and tangent are then
//! gathered node by node:
//!   f_int,I = Σ_p v_p σ_p ∂N_I/∂x,   K_IJ = Σ_p v_p (∂N_I/∂x)_j a_ijkl (∂N_J/∂x)_l
//! with a the spatial tangent (finite strain, THEORY.md §2) or D (small strain, §3).

use loam_constitutive::{finite_strain_update, small_strain_update, ConstitutiveError, Tensor4};
use loam_grid::{Connectivity, GhostFace};
pub(crate) use loam_model::PointCouplings;
use loam_model::{internal_force, Kinematics, Model};
use loam_solve::{gather_nodal, BlockPattern, NewtonProblem};
use nalgebra::{Matrix3, SMatrix, SVector};
use rayon::prelude::*;

/// A material point whose update failed inside a Newton iteration.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("material point {point}: {source}")]
pub struct PointUpdateError {
    pub point: usize,
    pub source: ConstitutiveError,
}

/// Trial state of every point for the current Newton iterate. Reused across iterations and
/// steps; the committed state in the model only changes when a step converges.
#[derive(Debug, Default)]
pub(crate) struct TrialState<const D: usize> {
    pub delta_f: Vec<Matrix3<f64>>,
    pub stress: Vec<Matrix3<f64>>,
    pub elastic_strain: Vec<Matrix3<f64>>,
    pub history: Vec<f64>,
    pub volume: Vec<f64>,
    /// v_p times the in-plane part of the tangent, (i·D + j, k·D + l) = v a_ijkl.
    pub tangent: Vec<SMatrix<f64, 9, 9>>,
    /// Spatial gradients ∂N/∂x, `stride` per point.
    pub grad_x: Vec<SVector<f64, D>>,
    /// B-bar only: v (I : D) and v (D : I) as 3×3, the volumetric contractions of the
    /// point's tangent that the averaged dilatation couples through (v I : D : I is the
    /// trace of the first).
    pub volumetric: Vec<(Matrix3<f64>, Matrix3<f64>)>,
}

impl<const D: usize> TrialState<D> {
    pub fn resize(&mut self, n_points: usize, stride: usize, history_stride: usize) {
        self.delta_f.resize(n_points, Matrix3::identity());
        self.stress.resize(n_points, Matrix3::zeros());
        self.elastic_strain.resize(n_points, Matrix3::zeros());
        // At least one slot per point so that every point gets its own chunk.
        self.history.resize(n_points * history_stride.max(1), 0.0);
        self.volume.resize(n_points, 0.0);
        self.tangent.resize(n_points, SMatrix::zeros());
        self.grad_x.resize(n_points * stride, SVector::zeros());
        self.volumetric.resize(n_points, (Matrix3::zeros(), Matrix3::zeros()));
    }
}

/// The inertial terms of a Newmark / Bossak step (THEORY.md §4). With the predictor
/// increment Δũ = Δt vₙ + Δt² (½ − β) aₙ the new nodal acceleration is
/// a_{n+1} = (Δu − Δũ) / (β Δt²), and the residual gains M [(1 − α_B) a_{n+1} + α_B aₙ]:
/// with x = c (Δu − Δũ) + α_B aₙ and c = (1 − α_B) / (β Δt²), the force M x and the
/// tangent c M.
pub(crate) struct Inertia<'a> {
    /// Consistent mass M_IJ = Σ_p m_p N_I N_J (times the identity per node) instead of the
    /// lumped row sums.
    pub consistent: bool,
    /// Lumped nodal masses m_I = Σ_p m_p N_I, one per active node.
    pub nodal_mass: &'a [f64],
    /// c = (1 − α_B) / (β Δt²).
    pub factor: f64,
    /// Δũ per dof.
    pub predictor: &'a [f64],
    /// α_B aₙ per dof (zero for plain Newmark).
    pub bossak_term: &'a [f64],
    /// Nodal velocity vₙ per dof and the step Δt: the momentum force m vₙ / Δt is the
    /// floor of the residual's reference.
    pub velocity: &'a [f64],
    pub time_step: f64,
    /// Scratch: x per dof, x interpolated to points, consistent inertial force per dof.
    pub x: &'a mut Vec<f64>,
    pub point_x: &'a mut Vec<f64>,
    pub force: &'a mut Vec<f64>,
}

/// The Newton system of one load or time step.
pub(crate) struct StepSystem<'a, const D: usize> {
    pub model: &'a Model<D>,
    pub conn: &'a Connectivity<D>,
    pub pattern: &'a BlockPattern,
    pub values: &'a mut Vec<f64>,
    pub constrained: &'a [bool],
    pub f_ext: &'a [f64],
    /// f_int − f_ext on the constrained dofs at the last evaluation (the support
    /// reactions); zero on free dofs.
    pub reaction: &'a mut Vec<f64>,
    pub trial: &'a mut TrialState<D>,
    /// Inertia of a dynamic step; `None` in quasi-static analysis.
    pub inertia: Option<Inertia<'a>>,
    /// B-bar or assumed strain: the cell averages of the support gradients; `None`
    /// without anti-locking.
    pub cell_average: Option<CellAverage<'a, D>>,
    /// Ghost-penalty faces over active nodes, their matrices already scaled by γ M
    /// (docs/theory.md §15); empty without the penalty.
    pub ghost: &'a [GhostFace],
}

/// The cell averages of B-bar and assumed strain (docs/theory.md §13).
#[derive(Clone, Copy)]
pub(crate) struct CellAverage<'a, const D: usize> {
    /// The volume-averaged gradient b̄ of each point's support slot over its cell
    /// (element), `stride` per point.
    pub gradients: &'a [SVector<f64, D>],
    /// β: the weight of each point's own deviatoric strain (1 for B-bar).
    pub deviatoric_weight: f64,
}

impl<'a, const D: usize> CellAverage<'a, D> {
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

/// r += G Δu for every ghost face, component by component, faces in a fixed order.
fn add_ghost_force<const D: usize>(ghost: &[GhostFace], du: &[f64], r: &mut [f64]) {
    for face in ghost {
        let n = face.nodes.len();
        for (a, &na) in face.nodes.iter().enumerate() {
            for (b, &nb) in face.nodes.iter().enumerate() {
                let g = face.matrix[a * n + b];
                for i in 0..D {
                    r[na as usize * D + i] += g * du[nb as usize * D + i];
                }
            }
        }
    }
}

/// Embed the in-plane displacement-increment gradient in 3×3 (plane strain: zero out of plane).
#[inline]
fn embed<const D: usize>(g: &SMatrix<f64, D, D>) -> Matrix3<f64> {
    let mut m = Matrix3::zeros();
    for i in 0..D {
        for j in 0..D {
            m[(i, j)] = g[(i, j)];
        }
    }
    m
}

/// In-plane block (i·D + j, k·D + l) of a full 9×9 tensor, scaled; unused entries zero.
#[inline]
fn in_plane<const D: usize>(a: &Tensor4, scale: f64) -> SMatrix<f64, 9, 9> {
    if D == 3 {
        return a * scale;
    }
    let mut out = SMatrix::<f64, 9, 9>::zeros();
    for i in 0..D {
        for j in 0..D {
            for k in 0..D {
                for l in 0..D {
                    out[(i * D + j, k * D + l)] = scale * a[(3 * i + j, 3 * k + l)];
                }
            }
        }
    }
    out
}

impl<const D: usize> StepSystem<'_, D> {
    /// Update every point's trial state for the increment `du`.
    fn update_points(&mut self, du: &[f64]) -> Result<(), PointUpdateError> {
        let model = self.model;
        let conn = self.conn;
        let pts = &model.points;
        let hs = pts.history_stride();
        let stride = conn.stride();
        let kin = model.kinematics;
        let average = self.cell_average;
        let t = &mut *self.trial;
        let hist_chunks = t.history.par_chunks_mut(hs.max(1));
        let first_error = (
            t.delta_f.par_iter_mut(),
            t.stress.par_iter_mut(),
            t.elastic_strain.par_iter_mut(),
            t.volume.par_iter_mut(),
            t.tangent.par_iter_mut(),
            t.grad_x.par_chunks_mut(stride),
        )
            .into_par_iter()
            .zip(hist_chunks.zip(t.volumetric.par_iter_mut()))
            .enumerate()
            .filter_map(|(p, ((df, stress, elastic, volume, tangent, grad_x), (h_out, vol_terms)))| {
                let nodes = conn.support_nodes(p);
                let grads = conn.support_gradients(p);
                // With cell averaging (small strain only, Model::with_anti_locking) the
                // strain gradients c_a go to grad_x now, and the increment gradient is
                // Σ Δu_a ⊗ c_a.
                let strain_grads: &[SVector<f64, D>] = match average {
                    Some(avg) => {
                        for (a, c) in grad_x[..nodes.len()].iter_mut().enumerate() {
                            *c = avg.strain_gradient(p * stride + a, &grads[a]);
                        }
                        &grad_x[..nodes.len()]
                    }
                    None => grads,
                };
                let mut g = SMatrix::<f64, D, D>::zeros();
                for (a, &node) in nodes.iter().enumerate() {
                    let u = SVector::<f64, D>::from_fn(|i, _| du[node as usize * D + i]);
                    g += u * strain_grads[a].transpose();
                }
                let law = &*model.materials[pts.material[p] as usize];
                let h_n = pts.history(p);
                let h_out = &mut h_out[..hs];
                match kin {
                    Kinematics::FiniteStrain => {
                        let dfd = SMatrix::<f64, D, D>::identity() + g;
                        let f3 = Matrix3::identity() + embed(&g);
                        let det_df = f3.determinant();
                        let j_total = det_df * pts.deformation_gradient[p].determinant();
                        let upd = match finite_strain_update(law, &f3, &pts.elastic_strain[p], j_total, h_n, h_out) {
                            Ok(u) => u,
                            Err(source) => return Some(PointUpdateError { point: p, source }),
                        };
                        // det ΔF > 0 was checked by the update, so ΔF is invertible.
                        let inv = dfd.try_inverse().unwrap_or_else(SMatrix::identity);
                        for a in 0..nodes.len() {
                            grad_x[a] = inv.transpose() * grads[a];
                        }
                        *df = f3;
                        *stress = upd.cauchy;
                        *elastic = upd.be;
                        *volume = det_df * pts.volume[p];
                        *tangent = in_plane::<D>(&upd.spatial_tangent, *volume);
                    }
                    Kinematics::SmallStrain => {
                        let mut g3 = embed(&g);
                        if let Some(avg) = average {
                            // ε̄ = ε + (θ̄ − θ)/3 I with θ̄ = Σ_a u_a · b̄_a (Hughes 1980).
                            let theta_bar: f64 = nodes
                                .iter()
                                .enumerate()
                                .map(|(a, &node)| {
                                    (0..D)
                                        .map(|i| du[node as usize * D + i] * avg.average(p * stride + a)[i])
                                        .sum::<f64>()
                                })
                                .sum();
                            let theta = g.trace();
                            g3 += Matrix3::identity() * ((theta_bar - theta) / 3.0);
                        }
                        let upd = match small_strain_update(law, &g3, &pts.elastic_strain[p], h_n, h_out) {
                            Ok(u) => u,
                            Err(source) => return Some(PointUpdateError { point: p, source }),
                        };
                        if average.is_none() {
                            grad_x[..nodes.len()].copy_from_slice(grads);
                        }
                        *df = Matrix3::identity() + g3;
                        *stress = upd.stress;
                        *elastic = upd.elastic_strain;
                        *volume = pts.volume[p];
                        *tangent = in_plane::<D>(&upd.tangent, *volume);
                        if average.is_some() {
                            let a = &upd.tangent;
                            let v = *volume;
                            let id = Matrix3::from_fn(|k, l| v * (0..3).map(|m| a[(4 * m, 3 * k + l)]).sum::<f64>());
                            let di = Matrix3::from_fn(|i, j| v * (0..3).map(|m| a[(3 * i + j, 4 * m)]).sum::<f64>());
                            *vol_terms = (id, di);
                        }
                    }
                }
                None
            })
            .min_by_key(|e| e.point);
        match first_error {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

impl Inertia<'_> {
    /// The inertial force M x at the increment `du`, into `self.force`.
    fn inertial_force<const D: usize>(&mut self, conn: &Connectivity<D>, mass: &[f64], du: &[f64]) {
        let c = self.factor;
        self.x.clear();
        self.x.extend(du.iter().zip(self.predictor).zip(self.bossak_term).map(|((u, p), b)| c * (u - p) + b));
        self.force.resize(du.len(), 0.0);
        if !self.consistent {
            for (k, (f, x)) in self.force.iter_mut().zip(self.x.iter()).enumerate() {
                *f = self.nodal_mass[k / D] * x;
            }
            return;
        }
        // (M x)_I = Σ_p m_p N_I x_p with x_p = Σ_J N_J x_J: interpolate, then gather.
        let x = &*self.x;
        self.point_x.resize(conn.num_points() * D, 0.0);
        self.point_x.par_chunks_mut(D).enumerate().for_each(|(p, xp)| {
            xp.iter_mut().for_each(|v| *v = 0.0);
            for (&node, &n) in conn.support_nodes(p).iter().zip(conn.support_values(p)) {
                for i in 0..D {
                    xp[i] += n * x[node as usize * D + i];
                }
            }
        });
        let point_x = &*self.point_x;
        gather_nodal(&PointCouplings(conn), D, self.force, |p, a, out| {
            let w = mass[p] * conn.support_values(p)[a];
            for i in 0..D {
                out[i] += w * point_x[p * D + i];
            }
        });
    }
}

impl<const D: usize> NewtonProblem for StepSystem<'_, D> {
    type Error = PointUpdateError;

    fn num_dofs(&self) -> usize {
        self.conn.active_nodes().len() * D
    }

    fn evaluate(&mut self, du: &[f64], r: &mut [f64]) -> Result<f64, PointUpdateError> {
        self.update_points(du)?;
        let trial = &*self.trial;
        let conn = self.conn;
        let stride = conn.stride();
        let average = self.cell_average;
        gather_nodal(&PointCouplings(conn), D, r, |p, a, out| {
            let k = p * stride + a;
            let f = internal_force(trial.volume[p], &trial.stress[p], &trial.grad_x[k], average.map(|c| c.average(k)));
            for i in 0..D {
                out[i] += f[i];
            }
        });
        add_ghost_force::<D>(self.ghost, du, r);
        // r = M x + f_int − f_ext; the reference is the external and inertial force on
        // free dofs plus the support reactions (= f_int) on constrained ones (THEORY.md §7):
        // a free vibration has no external force, and must not be judged against zero.
        // In dynamics the internal and inertial forces join the reference, with the
        // momentum force m_I v_I / Δt as a floor: bodies in free flight have no external
        // or internal force, and their round-off residual must not count as an error.
        let mut reference = 0.0;
        if let Some(inertia) = self.inertia.as_mut() {
            inertia.inertial_force::<D>(self.conn, &self.model.points.mass, du);
            for (k, ((ri, &fi), &fixed)) in r.iter_mut().zip(inertia.force.iter()).zip(self.constrained).enumerate() {
                if !fixed {
                    let momentum = inertia.nodal_mass[k / D] * inertia.velocity[k] / inertia.time_step;
                    reference += *ri * *ri + fi * fi + momentum * momentum;
                    *ri += fi;
                }
            }
        }
        self.reaction.resize(r.len(), 0.0);
        for (((ri, &fe), &fixed), reaction) in
            r.iter_mut().zip(self.f_ext).zip(self.constrained).zip(self.reaction.iter_mut())
        {
            *reaction = 0.0;
            if fixed {
                reference += *ri * *ri;
                *reaction = *ri - fe;
                *ri = 0.0;
            } else {
                reference += fe * fe;
                *ri -= fe;
            }
        }
        Ok(reference.sqrt())
    }

    fn assemble(&mut self) {
        let trial = &*self.trial;
        let conn = self.conn;
        let stride = conn.stride();
        let mass = &self.model.points.mass;
        // Inertia adds c m_p N_a N_b (consistent) or c m_p N_a on the diagonal block
        // (lumped: the row sum) to every component.
        let inertia = self.inertia.as_ref().map(|i| (i.factor, i.consistent));
        let average = self.cell_average;
        self.pattern.assemble(&PointCouplings(conn), self.constrained, self.values, |p, a, b, out| {
            if let Some((c, consistent)) = inertia {
                let n = conn.support_values(p);
                let m = c
                    * mass[p]
                    * if consistent {
                        n[a] * n[b]
                    } else if a == b {
                        n[a]
                    } else {
                        0.0
                    };
                for i in 0..D {
                    out[i * D + i] += m;
                }
            }
            let ga = &trial.grad_x[p * stride + a];
            let gb = &trial.grad_x[p * stride + b];
            if let Some(avg) = average {
                // E_a,i = e_i ⊗ c_a + ⅓ d_a,i I with d = b̄ − c (c in grad_x): the cross
                // and volumetric terms of E_a,i : D : E_b,k beside the plain one below.
                let (id, di) = &trial.volumetric[p];
                let idi = id.trace();
                let da = avg.average(p * stride + a) - ga;
                let db = avg.average(p * stride + b) - gb;
                for i in 0..D {
                    for k in 0..D {
                        let mut s = idi * da[i] * db[k] / 9.0;
                        for l in 0..D {
                            s += da[i] * id[(k, l)] * gb[l] / 3.0;
                            s += db[k] * ga[l] * di[(i, l)] / 3.0;
                        }
                        out[i * D + k] += s;
                    }
                }
            }
            let t = &trial.tangent[p];
            for i in 0..D {
                for k in 0..D {
                    let mut s = 0.0;
                    for j in 0..D {
                        for l in 0..D {
                            s += ga[j] * t[(i * D + j, k * D + l)] * gb[l];
                        }
                    }
                    out[i * D + k] += s;
                }
            }
        });
        let mut block = [0.0; 9];
        for face in self.ghost {
            let n = face.nodes.len();
            for (a, &na) in face.nodes.iter().enumerate() {
                for (b, &nb) in face.nodes.iter().enumerate() {
                    for i in 0..D {
                        block[i * D + i] = face.matrix[a * n + b];
                    }
                    self.pattern.add_block(self.values, self.constrained, na as usize, nb as usize, &block[..D * D]);
                }
            }
        }
    }

    fn matrix(&self) -> (&BlockPattern, &[f64]) {
        (self.pattern, self.values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{AntiLocking, PlaneConstraint, QuasiStatic, QuasiStaticSettings};
    use loam_constitutive::{ConstitutiveLaw, Elastic, MohrCoulomb, VonMises};
    use loam_grid::{BasisKind, Grid};
    use loam_points::{PointStore, Shape};
    use nalgebra::Vector2;
    use std::sync::Arc;

    /// A 2×2-cell block on a 5×5 grid, pre-loaded by gravity to a stressed state. With a
    /// ghost penalty the block is shifted 0.3 cells along x, so that it cuts cells.
    fn stressed_block_with(
        kinematics: Kinematics,
        basis: BasisKind,
        anti_locking: AntiLocking,
        ghost: Option<f64>,
        law: Arc<dyn ConstitutiveLaw>,
    ) -> Model<2> {
        let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [5, 5]).unwrap();
        let mut points = PointStore::new();
        let shape = Shape::Box { min: Vector2::new(1.0, 0.0), max: Vector2::new(3.0, 2.0) };
        points.fill(&grid, &shape, 2, 1000.0, 0).unwrap();
        if ghost.is_some() {
            points.position.iter_mut().for_each(|x| x[0] += 0.3);
        }
        let fixed = PlaneConstraint::new(1, 0, [true, true, false]);
        let mut model = Model::new(grid, basis, kinematics, points, vec![law], vec![fixed], Vector2::new(3.0, -10.0))
            .unwrap()
            .with_anti_locking(anti_locking)
            .unwrap();
        if let Some(gamma) = ghost {
            model = model.with_ghost_penalty(gamma).unwrap();
        }
        let mut qs = QuasiStatic::new(model, QuasiStaticSettings { load_steps: 2, ..Default::default() });
        qs.step().unwrap();
        qs.step().unwrap();
        qs.into_model()
    }

    /// Deterministic pseudo-random numbers in [-1, 1) (64-bit LCG, Knuth's constants).
    fn noise(n: usize, seed: u64) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
            })
            .collect()
    }

    /// K v equals the central difference of the residual along v, on a stressed state and
    /// a finite increment: the tangent is the exact linearisation, which is what makes
    /// Newton quadratic. Relative tolerance 1e-6: central differences with step 1e-7 on a
    /// residual of magnitude ~1e3 carry truncation ~1e-10 and rounding ~1e-9 relative.
    /// The plastic cases (von Mises σ_y = 2.4e4, associated Mohr–Coulomb c = 8e3, φ = 30°,
    /// strong enough to carry the gravity preload) take a simple shear of 0.2 and nodal
    /// noise of up to 20 % of a cell, so that points return to the yield surface in it,
    /// and check that some do.
    #[test]
    fn assembled_tangent_is_the_derivative_of_the_residual() {
        let elastic = Elastic::new(1e5, 0.3).unwrap();
        let linear: Arc<dyn ConstitutiveLaw> = Arc::new(elastic);
        let von_mises: Arc<dyn ConstitutiveLaw> = Arc::new(VonMises::new(elastic, 2.4e4, 0.0).unwrap());
        let mohr_coulomb: Arc<dyn ConstitutiveLaw> =
            Arc::new(MohrCoulomb::from_degrees(elastic, 8e3, 30.0, 30.0).unwrap());
        let assumed = AntiLocking::AssumedStrain { stabilization: 0.2 };
        let cases = [
            (Kinematics::FiniteStrain, BasisKind::Gimp, AntiLocking::None, None, &linear),
            (Kinematics::SmallStrain, BasisKind::Gimp, AntiLocking::None, None, &linear),
            (Kinematics::SmallStrain, BasisKind::Linear, AntiLocking::BBar, None, &linear),
            (Kinematics::SmallStrain, BasisKind::Linear, assumed, None, &linear),
            (Kinematics::SmallStrain, BasisKind::Linear, AntiLocking::BBar, None, &von_mises),
            (Kinematics::SmallStrain, BasisKind::Linear, assumed, None, &von_mises),
            (Kinematics::SmallStrain, BasisKind::Linear, assumed, None, &mohr_coulomb),
            (Kinematics::FiniteStrain, BasisKind::Gimp, AntiLocking::None, Some(1.0), &linear),
        ];
        for (kinematics, basis, anti_locking, ghost, law) in cases {
            let plastic = !Arc::ptr_eq(law, &linear);
            let model = stressed_block_with(kinematics, basis, anti_locking, ghost, law.clone());
            let mut conn = Connectivity::new(model.basis);
            conn.compute(&model.grid, &model.points.position, &model.points.half_length).unwrap();
            let faces = ghost.map_or(Vec::new(), |gamma| crate::engine::scaled_ghost_faces(&model, &conn, gamma));
            assert_eq!(faces.is_empty(), ghost.is_none(), "the shifted block must cut cells");
            let mut couplings = Vec::new();
            crate::engine::ghost_couplings(&faces, conn.active_nodes().len(), &mut couplings);
            let mut pattern = BlockPattern::new(2);
            pattern.update_with(&PointCouplings(&conn), &couplings);
            let n = conn.active_nodes().len() * 2;
            let constrained = vec![false; n];
            let f_ext = vec![0.0; n];
            let mut values = Vec::new();
            let mut trial = TrialState::default();
            trial.resize(model.points.len(), conn.stride(), model.points.history_stride());
            let mut cell_gradients = Vec::new();
            crate::engine::cell_averaged_gradients(&model, &conn, &mut cell_gradients);
            let mut sys = StepSystem {
                model: &model,
                conn: &conn,
                pattern: &pattern,
                values: &mut values,
                constrained: &constrained,
                f_ext: &f_ext,
                reaction: &mut Vec::new(),
                trial: &mut trial,
                inertia: None,
                cell_average: crate::engine::cell_average(&model, &cell_gradients),
                ghost: &faces,
            };
            // A finite increment (up to 2 % of a cell, 20 % for the plastic laws) so that ΔF ≠ I.
            let amplitude = if plastic { 0.2 } else { 0.02 };
            let mut du: Vec<f64> = noise(n, 7).iter().map(|x| amplitude * x).collect();
            if plastic {
                // Plus a simple shear of 0.2, which survives the cell averages.
                for (a, &g) in conn.active_nodes().active_to_grid.iter().enumerate() {
                    du[a * 2] += 0.2 * model.grid.node_position(g as usize)[1];
                }
                // At Δu = 0 every point is elastic (the committed state is admissible).
                sys.evaluate(&vec![0.0; n], &mut vec![0.0; n]).unwrap();
                let elastic_tangents = sys.trial.tangent.clone();
                sys.evaluate(&du, &mut vec![0.0; n]).unwrap();
                let returned = elastic_tangents
                    .iter()
                    .zip(&sys.trial.tangent)
                    .filter(|(e, t)| (*e - *t).norm() > 1e-6 * e.norm())
                    .count();
                assert!(returned > 0, "{anti_locking:?}: no point returned to the yield surface");
            }
            let v = noise(n, 11);
            let eps = 1e-7;
            let (mut rp, mut rm, mut r) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            let plus: Vec<f64> = du.iter().zip(&v).map(|(a, b)| a + eps * b).collect();
            let minus: Vec<f64> = du.iter().zip(&v).map(|(a, b)| a - eps * b).collect();
            sys.evaluate(&plus, &mut rp).unwrap();
            sys.evaluate(&minus, &mut rm).unwrap();
            sys.evaluate(&du, &mut r).unwrap();
            sys.assemble();
            let mut kv = vec![0.0; n];
            pattern.mul_vec(sys.values, &v, &mut kv);
            let diff: f64 = kv
                .iter()
                .zip(rp.iter().zip(&rm))
                .map(|(k, (p, m))| (k - (p - m) / (2.0 * eps)).powi(2))
                .sum::<f64>()
                .sqrt();
            let scale: f64 = kv.iter().map(|k| k * k).sum::<f64>().sqrt();
            assert!(
                diff <= 1e-6 * scale,
                "{kinematics:?} {anti_locking:?} plastic {plastic}: |Kv - FD| / |Kv| = {:e}",
                diff / scale
            );
            // Hyperelastic (Hencky), linear elastic and associated tangents are symmetric
            // as a whole.
            let asym = pattern.asymmetry(sys.values);
            assert!(asym < 1e-10, "{kinematics:?}: asymmetry {asym:e}");
        }
    }
}
