//! The inertial terms of a Newmark / Bossak step (docs/theory.md §9). With the predictor
//! increment Δũ = Δt vₙ + Δt² (½ − β) aₙ the new nodal acceleration is
//! a_{n+1} = (Δu − Δũ) / (β Δt²), and the residual gains M [(1 − α_B) a_{n+1} + α_B aₙ]:
//! with x = c (Δu − Δũ) + α_B aₙ and c = (1 − α_B) / (β Δt²), the force M x and the
//! tangent c M.

use loam_grid::Connectivity;
use loam_kernels::{interpolate, scatter_nodal};
use rayon::prelude::*;

/// The nodal state and scratch of the inertial terms, owned by the dynamic analysis and
/// lent to its Newton solve.
#[derive(Debug, Default)]
pub(crate) struct Inertia {
    /// Consistent mass M_IJ = Σ_p m_p N_I N_J (times the identity per node) instead of the
    /// lumped row sums.
    pub consistent: bool,
    /// Lumped nodal masses m_I = Σ_p m_p N_I, one per active node.
    pub nodal_mass: Vec<f64>,
    /// c = (1 − α_B) / (β Δt²).
    pub factor: f64,
    /// Δũ per dof.
    pub predictor: Vec<f64>,
    /// α_B aₙ per dof (zero for plain Newmark).
    pub bossak_term: Vec<f64>,
    /// Nodal velocity vₙ per dof and the step Δt: the momentum force m vₙ / Δt is the
    /// floor of the residual's reference.
    pub velocity: Vec<f64>,
    pub time_step: f64,
    /// Scratch: x per dof, x interpolated to points, consistent inertial force per dof.
    x: Vec<f64>,
    point_x: Vec<f64>,
    force: Vec<f64>,
}

impl Inertia {
    /// No nodal state yet, with the consistent or lumped mass matrix.
    pub fn new(consistent: bool) -> Self {
        Self { consistent, ..Self::default() }
    }

    /// The inertial force M x at the increment `du`, into `self.force`.
    fn inertial_force<const D: usize>(&mut self, conn: &Connectivity<D>, mass: &[f64], du: &[f64]) {
        let c = self.factor;
        self.x.clear();
        self.x.extend(du.iter().zip(&self.predictor).zip(&self.bossak_term).map(|((u, p), b)| c * (u - p) + b));
        self.force.resize(du.len(), 0.0);
        if !self.consistent {
            for (k, (f, x)) in self.force.iter_mut().zip(self.x.iter()).enumerate() {
                *f = self.nodal_mass[k / D] * x;
            }
            return;
        }
        // (M x)_I = Σ_p m_p N_I x_p with x_p = Σ_J N_J x_J: interpolate, then scatter.
        let x = &*self.x;
        self.point_x.resize(conn.num_points() * D, 0.0);
        self.point_x.par_chunks_mut(D).enumerate().for_each(|(p, xp)| {
            xp.copy_from_slice(interpolate(conn, p, x).as_slice());
        });
        let point_x = &*self.point_x;
        scatter_nodal(conn, D, &mut self.force, |p, a, out| {
            let w = mass[p] * conn.support_values(p)[a];
            for i in 0..D {
                out[i] += w * point_x[p * D + i];
            }
        });
    }

    /// Add M x to the residual `r` on the free dofs, and return the inertial part of the
    /// squared reference force: r², (M x)² and the momentum force (m_I v_I / Δt)² per free
    /// dof — bodies in free flight have no external or internal force, and their round-off
    /// residual must not count as an error.
    pub fn add_to_residual<const D: usize>(
        &mut self,
        conn: &Connectivity<D>,
        mass: &[f64],
        du: &[f64],
        constrained: &[bool],
        r: &mut [f64],
    ) -> f64 {
        self.inertial_force(conn, mass, du);
        let mut reference = 0.0;
        for (k, ((ri, &fi), &fixed)) in r.iter_mut().zip(self.force.iter()).zip(constrained).enumerate() {
            if !fixed {
                let momentum = self.nodal_mass[k / D] * self.velocity[k] / self.time_step;
                reference += *ri * *ri + fi * fi + momentum * momentum;
                *ri += fi;
            }
        }
        reference
    }

    /// The tangent's inertial coefficient between support slots `a` and `b` of point `p`
    /// (on every component): c m_p N_a N_b (consistent) or c m_p N_a on the diagonal
    /// block (lumped: the row sum).
    #[inline]
    pub fn tangent_coefficient<const D: usize>(
        &self,
        conn: &Connectivity<D>,
        mass: &[f64],
        p: usize,
        a: usize,
        b: usize,
    ) -> f64 {
        let n = conn.support_values(p);
        self.factor
            * mass[p]
            * if self.consistent {
                n[a] * n[b]
            } else if a == b {
                n[a]
            } else {
                0.0
            }
    }
}
