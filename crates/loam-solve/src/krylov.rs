//! Multigrid-preconditioned Krylov solvers (docs/theory.md §19) on faer's matrix-free
//! interface: conjugate gradients for symmetric positive definite tangents, BiCGStab for
//! the others (non-associated plasticity, follower loads, softening). And GMRES, for a
//! non-symmetric tangent preconditioned by the factor of its symmetric part (the direct
//! solver's, `linear.rs`): a preconditioner that close to the inverse needs few
//! iterations, so GMRES's vector per iteration costs little, and it applies the
//! preconditioner once per iteration where BiCGStab does twice.
//!
//! BiCGStab rather than GMRES: faer provides it, its memory is a fixed handful of vectors
//! (GMRES keeps one per iteration up to a restart length, which then has to be chosen and
//! can stall), and it costs two operator and two preconditioner applications per
//! iteration. The operator is the tangent in block compressed-row storage; the
//! preconditioner one V-cycle of the geometric multigrid. faer's vector updates run on one
//! thread (`Par::Seq`) so its reductions have a fixed order; the products and the cycle
//! are row-parallel. Results are therefore the same for any thread count.
//!
//! A solve that does not reach its tolerance is an error carrying the residual history
//! (recomputed, iteration by iteration, only then), never a result.

use crate::linear::{KrylovFailure, LinearSolveStats, LinearSolver, LinearSystem};
use crate::multigrid::{dot, Multigrid};
use crate::{
    BlockMatrix, LinearSolveError, LinearSolverKind, LinearSolverTimings, MatrixLayout, SparseDirectSolver,
    SystemMatrix,
};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::matrix_free::bicgstab::{bicgstab, bicgstab_scratch, BicgError, BicgParams};
use faer::matrix_free::conjugate_gradient::{conjugate_gradient, conjugate_gradient_scratch, CgError, CgParams};
use faer::matrix_free::{IdentityPrecond, InitialGuessStatus, LinOp, Precond};
use faer::{MatMut, MatRef, Par};
use std::time::Instant;

/// Most Krylov iterations per solve, by default.
const MAX_ITERATIONS: usize = 400;

/// The tangent as a faer operator.
#[derive(Debug)]
struct Operator<'a>(&'a BlockMatrix);

/// One V-cycle on a fine operator as a faer preconditioner.
#[derive(Debug)]
struct VCycle<'a>(&'a Multigrid, &'a BlockMatrix);

/// Apply `f(x, y)` to every column of `rhs` into `out`, through contiguous copies where a
/// column is strided.
fn columns(out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, f: impl Fn(&[f64], &mut [f64])) {
    let mut out = out;
    let n = rhs.nrows();
    let (mut x, mut y) = (vec![0.0; n], vec![0.0; n]);
    for j in 0..rhs.ncols() {
        x.iter_mut().zip(rhs.col(j).iter()).for_each(|(a, b)| *a = *b);
        f(&x, &mut y);
        out.as_mut().col_mut(j).iter_mut().zip(&y).for_each(|(a, b)| *a = *b);
    }
}

/// `LinOp` for `$t`, square of size `$size(self)`, applying `$apply(self, x, y)`.
macro_rules! real_linop {
    ($t:ty, $size:expr, $apply:expr) => {
        impl LinOp<f64> for $t {
            fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
                StackReq::EMPTY
            }
            fn nrows(&self) -> usize {
                $size(self)
            }
            fn ncols(&self) -> usize {
                $size(self)
            }
            fn apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, _par: Par, _stack: &mut MemStack) {
                columns(out, rhs, |x, y| $apply(self, x, y));
            }
            fn conj_apply(&self, out: MatMut<'_, f64>, rhs: MatRef<'_, f64>, par: Par, stack: &mut MemStack) {
                self.apply(out, rhs, par, stack);
            }
        }
    };
}

/// An assembled system, in either layout, as a faer operator.
#[derive(Debug)]
pub(crate) struct SystemOperator<'a>(pub &'a LinearSystem<'a>);

/// A direct solver's factor (of the tangent's symmetric part) as a faer preconditioner.
pub(crate) struct FactorPrecond<'a>(pub &'a SparseDirectSolver);

impl std::fmt::Debug for FactorPrecond<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "the factor of {} dofs", self.0.num_dofs())
    }
}

real_linop!(Operator<'_>, |s: &Operator<'_>| s.0.num_dofs(), |s: &Operator<'_>, x: &[f64], y: &mut [f64]| s
    .0
    .apply(x, y));
real_linop!(VCycle<'_>, |s: &VCycle<'_>| s.1.num_dofs(), |s: &VCycle<'_>, x: &[f64], y: &mut [f64]| s
    .0
    .apply(s.1, x, y));
impl Precond<f64> for VCycle<'_> {}
real_linop!(
    SystemOperator<'_>,
    |s: &SystemOperator<'_>| s.0.pattern.num_dofs(),
    |s: &SystemOperator<'_>, x: &[f64], y: &mut [f64]| s.0.matrix.mul_vec(s.0.pattern, x, y)
);
real_linop!(
    FactorPrecond<'_>,
    |s: &FactorPrecond<'_>| s.0.num_dofs(),
    |s: &FactorPrecond<'_>, x: &[f64], y: &mut [f64]| {
        y.copy_from_slice(x);
        s.0.apply_factor(y);
    }
);
impl Precond<f64> for FactorPrecond<'_> {}

/// A multigrid-preconditioned Krylov solver. See the module docs.
#[derive(Debug)]
pub struct IterativeSolver {
    kind: LinearSolverKind,
    multigrid: Multigrid,
    /// The operator in rows, where the system came in columns (a copy).
    converted: BlockMatrix,
    max_iterations: usize,
    timings: LinearSolverTimings,
}

impl IterativeSolver {
    /// `kind` is `Cg` or `BiCgStab`.
    pub fn new(kind: LinearSolverKind) -> Self {
        assert!(kind.is_iterative(), "{kind} is not a Krylov method");
        Self {
            kind,
            multigrid: Multigrid::new(),
            converted: BlockMatrix::default(),
            max_iterations: MAX_ITERATIONS,
            timings: LinearSolverTimings::default(),
        }
    }

    /// At most `n` Krylov iterations per solve (default 400).
    pub fn with_max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }

    /// Nodes per multigrid level, finest first (empty before the first `prepare`).
    pub fn level_sizes(&self) -> Vec<usize> {
        self.multigrid.level_sizes()
    }

    /// One Krylov solve from a zero guess; `history` asks for the relative residual of
    /// every iterate (one extra product per iteration).
    fn krylov(
        &self,
        fine: &BlockMatrix,
        rhs: &[f64],
        x: &mut [f64],
        rel_tol: f64,
        history: Option<&mut Vec<f64>>,
    ) -> KrylovOutcome {
        let b_norm = dot(rhs, rhs).sqrt();
        let mut r = vec![0.0; if history.is_some() { rhs.len() } else { 0 }];
        let mut hist = history;
        let on_iterate = |xk: MatRef<'_, f64>| {
            if let Some(h) = hist.as_deref_mut() {
                let xs: Vec<f64> = xk.col(0).iter().copied().collect();
                fine.residual(rhs, &xs, &mut r);
                h.push(dot(&r, &r).sqrt() / b_norm);
            }
        };
        let method = Krylov { kind: self.kind, rel_tol, max_iterations: self.max_iterations };
        method.solve(&Operator(fine), &VCycle(&self.multigrid, fine), rhs, x, on_iterate)
    }
}

/// A Krylov method with its stopping rule: CG for `LinearSolverKind::Cg`, GMRES for `Lu`
/// (the LDLᵀ of the symmetric part preconditioning a non-symmetric tangent), BiCGStab for
/// the others.
pub(crate) struct Krylov {
    pub kind: LinearSolverKind,
    pub rel_tol: f64,
    pub max_iterations: usize,
}

impl Krylov {
    /// Solve `a x = rhs` from a zero guess, preconditioned by `m`; `on_iterate` sees every
    /// iterate of CG and BiCGStab (GMRES forms its iterate only at the end).
    pub fn solve(
        &self,
        a: &impl LinOp<f64>,
        m: &impl Precond<f64>,
        rhs: &[f64],
        x: &mut [f64],
        on_iterate: impl FnMut(MatRef<'_, f64>),
    ) -> KrylovOutcome {
        let n = rhs.len();
        // A zero start, declared as a possibly non-zero one: with `InitialGuessStatus::Zero`
        // faer 0.24.4's CG and BiCGStab start from an uninitialised residual instead of b.
        // The price is one product.
        x.iter_mut().for_each(|v| *v = 0.0);
        let b = MatRef::from_column_major_slice(rhs, n, 1);
        let out = MatMut::from_column_major_slice_mut(x, n, 1);
        let (rel_tolerance, max_iters) = (self.rel_tol, self.max_iterations);
        if self.kind == LinearSolverKind::Lu {
            return gmres(a, m, rhs, x, rel_tolerance, max_iters);
        }
        if self.kind == LinearSolverKind::Cg {
            let params = CgParams {
                initial_guess: InitialGuessStatus::MaybeNonZero,
                abs_tolerance: 0.0,
                rel_tolerance,
                max_iters,
                ..Default::default()
            };
            let mut buf = MemBuffer::new(conjugate_gradient_scratch(m, a, 1, Par::Seq));
            match conjugate_gradient(out, m, a, b, params, on_iterate, Par::Seq, MemStack::new(&mut buf)) {
                Ok(info) => KrylovOutcome::Converged(info.iter_count, info.rel_residual),
                Err(CgError::NoConvergence { rel_residual, .. }) => {
                    KrylovOutcome::NotConverged(max_iters, rel_residual)
                }
                Err(CgError::NonPositiveDefiniteOperator) => KrylovOutcome::Breakdown("the tangent"),
                Err(CgError::NonPositiveDefinitePreconditioner) => KrylovOutcome::Breakdown("the preconditioner"),
            }
        } else {
            let params = BicgParams {
                initial_guess: InitialGuessStatus::MaybeNonZero,
                abs_tolerance: 0.0,
                rel_tolerance,
                max_iters,
                ..Default::default()
            };
            let id = IdentityPrecond { dim: n };
            let mut buf = MemBuffer::new(bicgstab_scratch(id, m, a, 1, Par::Seq));
            match bicgstab(out, id, m, a, b, params, on_iterate, Par::Seq, MemStack::new(&mut buf)) {
                Ok(info) => KrylovOutcome::Converged(info.iter_count, info.rel_residual),
                Err(BicgError::NoConvergence { rel_residual, .. }) => {
                    KrylovOutcome::NotConverged(max_iters, rel_residual)
                }
            }
        }
    }
}

/// The system's operator in rows: its own, or `converted`, the copy `prepare` made.
fn operator<'a>(converted: &'a BlockMatrix, system: &'a LinearSystem<'_>) -> &'a BlockMatrix {
    match system.matrix {
        SystemMatrix::Rows(m) => m,
        SystemMatrix::Columns(_) => converted,
    }
}

/// `y = op x` for an operator that needs no scratch (all of this module's).
fn apply(op: &impl LinOp<f64>, x: &[f64], y: &mut [f64]) {
    let n = x.len();
    let out = MatMut::from_column_major_slice_mut(y, n, 1);
    let mut none: [std::mem::MaybeUninit<u8>; 0] = [];
    op.apply(out, MatRef::from_column_major_slice(x, n, 1), Par::Seq, MemStack::new(&mut none));
}

/// Right-preconditioned GMRES without restart (Saad & Schultz 1986; Saad, Iterative
/// Methods for Sparse Linear Systems, 2003, §6.5 and §9.3.2) from a zero guess: the
/// Arnoldi basis by modified Gram–Schmidt, the least-squares problem by Givens rotations,
/// whose last entry is the residual's norm ‖b − A x‖. The preconditioned directions
/// z_j = M⁻¹ v_j are kept (flexible GMRES's form), so that the iterate x = Σ y_j z_j costs
/// no further preconditioner application. Sequential reductions: the same result for any
/// thread count.
fn gmres(
    a: &impl LinOp<f64>,
    m: &impl LinOp<f64>,
    rhs: &[f64],
    x: &mut [f64],
    rel_tol: f64,
    max_iterations: usize,
) -> KrylovOutcome {
    let beta = dot(rhs, rhs).sqrt();
    if beta == 0.0 {
        return KrylovOutcome::Converged(0, 0.0);
    }
    let mut basis: Vec<Vec<f64>> = vec![rhs.iter().map(|b| b / beta).collect()];
    let mut directions: Vec<Vec<f64>> = Vec::new();
    // Column j of the Hessenberg matrix, rotated: `h[j]` holds its j + 1 upper entries.
    let mut h: Vec<Vec<f64>> = Vec::new();
    let (mut cs, mut sn, mut g): (Vec<f64>, Vec<f64>, _) = (Vec::new(), Vec::new(), vec![beta]);
    let mut w = vec![0.0; rhs.len()];
    for j in 0..max_iterations {
        let mut z = vec![0.0; rhs.len()];
        apply(m, &basis[j], &mut z);
        apply(a, &z, &mut w);
        directions.push(z);
        let mut column: Vec<f64> = Vec::with_capacity(j + 2);
        for v in &basis {
            let hij = dot(&w, v);
            w.iter_mut().zip(v).for_each(|(w, v)| *w -= hij * v);
            column.push(hij);
        }
        let next = dot(&w, &w).sqrt();
        for i in 0..j {
            let (a, b) = (column[i], column[i + 1]);
            column[i] = cs[i] * a + sn[i] * b;
            column[i + 1] = -sn[i] * a + cs[i] * b;
        }
        let r = column[j].hypot(next);
        if !(r.is_finite() && r > 0.0) {
            return KrylovOutcome::NotConverged(j, g[j].abs() / beta);
        }
        let (c, s) = (column[j] / r, next / r);
        column[j] = r;
        g.push(-s * g[j]);
        g[j] *= c;
        cs.push(c);
        sn.push(s);
        h.push(column);
        let residual = g[j + 1].abs() / beta;
        if residual <= rel_tol || next == 0.0 {
            combine(&h, &g, &directions, x);
            return KrylovOutcome::Converged(j + 1, residual);
        }
        basis.push(w.iter().map(|w| w / next).collect());
    }
    KrylovOutcome::NotConverged(max_iterations, g[max_iterations].abs() / beta)
}

/// x = Σ y_j z_j with R y = g, R the rotated Hessenberg matrix (upper triangular; column j
/// is `h[j]`).
fn combine(h: &[Vec<f64>], g: &[f64], directions: &[Vec<f64>], x: &mut [f64]) {
    let k = h.len();
    let mut y = g[..k].to_vec();
    for i in (0..k).rev() {
        let yi = y[i] / h[i][i];
        y[i] = yi;
        for (l, yl) in y.iter_mut().enumerate().take(i) {
            *yl -= h[i][l] * yi;
        }
    }
    x.iter_mut().for_each(|v| *v = 0.0);
    for (yj, z) in y.iter().zip(directions) {
        x.iter_mut().zip(z).for_each(|(x, z)| *x += yj * z);
    }
}

pub(crate) enum KrylovOutcome {
    Converged(usize, f64),
    /// Stopped after this many iterations (a breakdown, or the most allowed) at this
    /// relative residual.
    NotConverged(usize, f64),
    /// CG met a direction of non-positive curvature in the named operator.
    Breakdown(&'static str),
}

impl LinearSolver for IterativeSolver {
    fn kind(&self) -> LinearSolverKind {
        self.kind
    }

    fn wants_lattice(&self) -> bool {
        true
    }

    fn layout(&self) -> MatrixLayout {
        MatrixLayout::Rows
    }

    fn prepare(&mut self, system: &LinearSystem<'_>) -> Result<(), LinearSolveError> {
        let lattice = system.lattice.ok_or(LinearSolveError::NoLattice)?;
        let d = system.pattern.dofs_per_node();
        if d > 3 {
            return Err(LinearSolveError::BlockSize(d));
        }
        let t = Instant::now();
        if self.multigrid.set_structure(system.pattern, lattice) {
            self.timings.symbolic += t.elapsed();
            self.timings.symbolic_count += 1;
        }
        let t = Instant::now();
        if let SystemMatrix::Columns(values) = system.matrix {
            if !self.converted.has_structure_of(system.pattern) {
                self.converted = BlockMatrix::structure_of(system.pattern);
            }
            self.converted.copy_from_pattern(system.pattern, values);
        }
        let fine = operator(&self.converted, system);
        self.multigrid.set_values(fine, system.constrained).map_err(LinearSolveError::Singular)?;
        self.timings.numeric += t.elapsed();
        self.timings.numeric_count += 1;
        Ok(())
    }

    fn solve(
        &mut self,
        system: &LinearSystem<'_>,
        rhs: &[f64],
        x: &mut [f64],
        rel_tol: f64,
    ) -> Result<LinearSolveStats, LinearSolveError> {
        let t = Instant::now();
        let outcome = self.krylov(operator(&self.converted, system), rhs, x, rel_tol, None);
        self.timings.solve += t.elapsed();
        match outcome {
            KrylovOutcome::Converged(iterations, residual) => {
                self.timings.iterations += iterations;
                if x.iter().all(|v| v.is_finite()) {
                    Ok(LinearSolveStats { iterations, residual, ..Default::default() })
                } else {
                    Err(LinearSolveError::NonFinite)
                }
            }
            KrylovOutcome::NotConverged(_, reported) => {
                // faer reports no usable residual on failure (1.0 in 0.24.4): the history's
                // last entry is the true one.
                let mut history = Vec::new();
                self.krylov(operator(&self.converted, system), rhs, x, rel_tol, Some(&mut history));
                let residual = history.last().copied().unwrap_or(reported);
                Err(LinearSolveError::NotConverged(Box::new(KrylovFailure {
                    method: self.kind,
                    iterations: self.max_iterations,
                    residual,
                    tolerance: rel_tol,
                    history,
                })))
            }
            KrylovOutcome::Breakdown(what) => Err(LinearSolveError::NotPositiveDefinite(format!(
                "conjugate gradients met a direction of non-positive curvature in {what}"
            ))),
        }
    }

    fn timings(&self) -> LinearSolverTimings {
        self.timings
    }

    fn bytes(&self) -> usize {
        self.multigrid.bytes()
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::{BlockPattern, Couplings, NodeLattice, SparseDirectSolver};

    /// The edges of an n × n node lattice as two-node elements.
    pub(crate) struct LatticeEdges {
        edges: Vec<[u32; 2]>,
        node_edges: Vec<Vec<(u32, u32)>>,
    }

    impl LatticeEdges {
        pub(crate) fn new(n: u32) -> Self {
            let mut edges = Vec::new();
            for y in 0..n {
                for x in 0..n {
                    let i = y * n + x;
                    if x + 1 < n {
                        edges.push([i, i + 1]);
                    }
                    if y + 1 < n {
                        edges.push([i, i + n]);
                    }
                }
            }
            let mut node_edges = vec![Vec::new(); (n * n) as usize];
            for (e, nodes) in edges.iter().enumerate() {
                for (a, &v) in nodes.iter().enumerate() {
                    node_edges[v as usize].push((e as u32, a as u32));
                }
            }
            Self { edges, node_edges }
        }
    }

    impl Couplings for LatticeEdges {
        fn num_nodes(&self) -> usize {
            self.node_edges.len()
        }
        fn elements_of(&self, node: usize) -> &[(u32, u32)] {
            &self.node_edges[node]
        }
        fn nodes_of(&self, element: usize) -> &[u32] {
            &self.edges[element]
        }
    }

    /// A graph Laplacian on an n × n lattice times the 2 × 2 block `k`, the bottom row of
    /// nodes held, with a stiffness that jumps by `contrast` across the middle: the system,
    /// its lattice and a load.
    pub(crate) fn lattice_system(
        n: u32,
        k: [f64; 4],
        contrast: f64,
    ) -> (BlockPattern, SystemMatrix, Vec<bool>, NodeLattice, Vec<f64>) {
        let mesh = LatticeEdges::new(n);
        let mut pattern = BlockPattern::new(2);
        pattern.update(&mesh);
        let constrained: Vec<bool> = (0..n * n * 2).map(|dof| dof / 2 < n).collect();
        let mut values = SystemMatrix::new(MatrixLayout::Rows);
        values.assemble(&pattern, &mesh, &constrained, |e, a, b, out| {
            let y = mesh.edges[e][0] / n;
            let s = if a == b { 1.0 } else { -1.0 } * if y >= n / 2 { contrast } else { 1.0 };
            out.iter_mut().zip(k).for_each(|(o, kv)| *o += s * kv);
        });
        let lattice = NodeLattice::new((0..n * n).map(|i| [i % n, i / n, 0]).collect());
        let rhs =
            (0..n * n * 2).map(|dof| if constrained[dof as usize] { 0.0 } else { 1.0 + (dof % 3) as f64 }).collect();
        (pattern, values, constrained, lattice, rhs)
    }

    /// Iterations to reach `tol`, and the largest difference from the direct solution
    /// relative to its largest value.
    fn against_direct(kind: LinearSolverKind, n: u32, k: [f64; 4], contrast: f64, tol: f64) -> (usize, f64) {
        let (pattern, values, constrained, lattice, rhs) = lattice_system(n, k, contrast);
        let system =
            LinearSystem { pattern: &pattern, matrix: &values, constrained: &constrained, lattice: Some(&lattice) };
        let mut direct = SparseDirectSolver::new(LinearSolverKind::Lu);
        direct.prepare(&system).unwrap();
        let mut exact = vec![0.0; rhs.len()];
        LinearSolver::solve(&mut direct, &system, &rhs, &mut exact, 0.0).unwrap();
        let mut iterative = IterativeSolver::new(kind);
        iterative.prepare(&system).unwrap();
        let mut x = vec![0.0; rhs.len()];
        let stats = iterative.solve(&system, &rhs, &mut x, tol).unwrap();
        let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let err = x.iter().zip(&exact).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())) / scale;
        (stats.iterations, err)
    }

    #[test]
    fn multigrid_cg_iterations_stay_bounded_under_refinement() {
        // SPD: a symmetric positive definite block times the Laplacian. The error against
        // LU is bounded by the condition number times the tolerance 1e-10; the iteration
        // counts of a working multigrid do not grow with n (geometric convergence per
        // V-cycle independent of h, e.g. Trottenberg et al., Multigrid, 2001, ch. 2).
        let k = [2.0, 0.5, 0.5, 1.0];
        let counts: Vec<usize> = [33, 65, 129]
            .iter()
            .map(|&n| {
                let (it, err) = against_direct(LinearSolverKind::Cg, n, k, 1.0, 1e-10);
                eprintln!("n = {n}: {it} iterations, error {err:.1e}");
                assert!(err < 1e-6, "n = {n}: error {err:e}");
                it
            })
            .collect();
        assert!(counts.iter().all(|&c| c <= 20), "{counts:?}");
        assert!(counts[2] <= counts[0] + 3, "{counts:?}");
    }

    #[test]
    fn multigrid_holds_a_stiffness_contrast_of_a_million() {
        let (it, err) = against_direct(LinearSolverKind::Cg, 65, [2.0, 0.5, 0.5, 1.0], 1e6, 1e-10);
        assert!(err < 1e-6 && it <= 30, "{it} iterations, error {err:e}");
    }

    #[test]
    fn bicgstab_solves_a_non_symmetric_system() {
        let (it, err) = against_direct(LinearSolverKind::BiCgStab, 65, [2.0, 0.6, 0.2, 1.0], 1.0, 1e-10);
        assert!(err < 1e-6 && it <= 20, "{it} iterations, error {err:e}");
    }

    #[test]
    fn a_solve_that_cannot_converge_is_an_error_with_its_history() {
        let (pattern, values, constrained, lattice, rhs) = lattice_system(33, [2.0, 0.5, 0.5, 1.0], 1.0);
        let system =
            LinearSystem { pattern: &pattern, matrix: &values, constrained: &constrained, lattice: Some(&lattice) };
        let mut s = IterativeSolver::new(LinearSolverKind::Cg).with_max_iterations(3);
        s.prepare(&system).unwrap();
        let mut x = vec![0.0; rhs.len()];
        let err = s.solve(&system, &rhs, &mut x, 1e-14).unwrap_err();
        let LinearSolveError::NotConverged(failure) = &err else { panic!("{err}") };
        let KrylovFailure { history, residual, .. } = failure.as_ref();
        // The history is the true residual of each iterate, decreasing, the last reported.
        assert_eq!(history.len(), 3);
        assert!(history.windows(2).all(|w| w[1] < w[0]) && history[0] < 1.0, "{err}");
        assert!(*residual == history[2] && *residual > 1e-14, "{err}");
    }

    #[test]
    fn a_system_in_columns_is_solved_as_in_rows() {
        let (pattern, rows, constrained, lattice, rhs) = lattice_system(33, [2.0, 0.6, 0.2, 1.0], 1.0);
        let columns = SystemMatrix::Columns(rows.to_columns(&pattern).into_owned());
        let solve = |matrix: &SystemMatrix| {
            let system = LinearSystem { pattern: &pattern, matrix, constrained: &constrained, lattice: Some(&lattice) };
            let mut s = IterativeSolver::new(LinearSolverKind::BiCgStab);
            s.prepare(&system).unwrap();
            let mut x = vec![0.0; rhs.len()];
            s.solve(&system, &rhs, &mut x, 1e-8).unwrap();
            x
        };
        assert_eq!(solve(&rows), solve(&columns));
    }

    /// A dense operator, for GMRES on a system whose solution is chosen.
    #[derive(Debug)]
    struct Dense(Vec<Vec<f64>>);
    real_linop!(Dense, |s: &Dense| s.0.len(), |s: &Dense, x: &[f64], y: &mut [f64]| {
        y.iter_mut().zip(&s.0).for_each(|(y, row)| *y = dot(row, x));
    });

    /// GMRES on a non-symmetric 12 × 12 system (a convection–diffusion stencil with a
    /// strong upwind term), unpreconditioned and preconditioned by the Jacobi diagonal:
    /// the chosen solution comes back to 1e-10 within the dimension's iterations (exact
    /// arithmetic needs at most n), and the residual it reports is the true
    /// ‖b − A x‖ / ‖b‖.
    #[test]
    fn gmres_solves_a_non_symmetric_system() {
        let n = 12;
        let a: Vec<Vec<f64>> = (0..n)
            .map(|i| {
                (0..n)
                    .map(|j| match j as i64 - i as i64 {
                        0 => 2.0 + 0.1 * i as f64,
                        -1 => -1.8,
                        1 => -0.2,
                        _ => 0.0,
                    })
                    .collect()
            })
            .collect();
        let jacobi =
            Dense((0..n).map(|i| (0..n).map(|j| if i == j { 1.0 / a[i][i] } else { 0.0 }).collect()).collect());
        let identity = Dense((0..n).map(|i| (0..n).map(|j| f64::from(i == j)).collect()).collect());
        let a = Dense(a);
        let exact: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin() + 1.0).collect();
        let mut b = vec![0.0; n];
        apply(&a, &exact, &mut b);
        for m in [&identity, &jacobi] {
            let mut x = vec![0.0; n];
            let KrylovOutcome::Converged(iterations, reported) = gmres(&a, m, &b, &mut x, 1e-12, n) else {
                panic!("GMRES did not converge in n iterations");
            };
            assert!(iterations <= n);
            let error = x.iter().zip(&exact).map(|(x, e)| (x - e).abs()).fold(0.0, f64::max);
            assert!(error < 1e-10, "error {error:.2e}");
            let mut ax = vec![0.0; n];
            apply(&a, &x, &mut ax);
            let r: Vec<f64> = b.iter().zip(&ax).map(|(b, ax)| b - ax).collect();
            let true_residual = dot(&r, &r).sqrt() / dot(&b, &b).sqrt();
            assert!((true_residual - reported).abs() < 1e-13, "{true_residual:.3e} vs {reported:.3e}");
        }
    }

    #[test]
    fn same_solution_on_one_and_several_threads() {
        let (pattern, values, constrained, lattice, rhs) = lattice_system(65, [2.0, 0.6, 0.2, 1.0], 1.0);
        let system =
            LinearSystem { pattern: &pattern, matrix: &values, constrained: &constrained, lattice: Some(&lattice) };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
            pool.install(|| {
                let mut s = IterativeSolver::new(LinearSolverKind::BiCgStab);
                s.prepare(&system).unwrap();
                let mut x = vec![0.0; rhs.len()];
                s.solve(&system, &rhs, &mut x, 1e-8).unwrap();
                x
            })
        };
        assert_eq!(run(1), run(3));
    }
}
