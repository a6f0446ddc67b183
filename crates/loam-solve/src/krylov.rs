//! Multigrid-preconditioned Krylov solvers (docs/theory.md §19) on faer's matrix-free
//! interface: conjugate gradients for symmetric positive definite tangents, BiCGStab for
//! the others (non-associated plasticity, follower loads, softening).
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
use crate::{BlockMatrix, LinearSolveError, LinearSolverKind, LinearSolverTimings, MatrixLayout, SystemMatrix};
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

macro_rules! real_linop {
    ($t:ty, $apply:expr) => {
        impl LinOp<f64> for $t {
            fn apply_scratch(&self, _rhs_ncols: usize, _par: Par) -> StackReq {
                StackReq::EMPTY
            }
            fn nrows(&self) -> usize {
                self.fine().num_dofs()
            }
            fn ncols(&self) -> usize {
                self.fine().num_dofs()
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

impl Operator<'_> {
    fn fine(&self) -> &BlockMatrix {
        self.0
    }
}

impl VCycle<'_> {
    fn fine(&self) -> &BlockMatrix {
        self.1
    }
}

real_linop!(Operator<'_>, |s: &Operator<'_>, x: &[f64], y: &mut [f64]| s.0.apply(x, y));
real_linop!(VCycle<'_>, |s: &VCycle<'_>, x: &[f64], y: &mut [f64]| s.0.apply(s.1, x, y));
impl Precond<f64> for VCycle<'_> {}

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
        let n = rhs.len();
        // A zero start, declared as a possibly non-zero one: with `InitialGuessStatus::Zero`
        // faer 0.24.4's CG and BiCGStab start from an uninitialised residual instead of b.
        // The price is one product.
        x.iter_mut().for_each(|v| *v = 0.0);
        let a = Operator(fine);
        let m = VCycle(&self.multigrid, fine);
        let b = MatRef::from_column_major_slice(rhs, n, 1);
        let out = MatMut::from_column_major_slice_mut(x, n, 1);
        let b_norm = dot(rhs, rhs).sqrt();
        let mut r = vec![0.0; if history.is_some() { n } else { 0 }];
        let mut hist = history;
        let callback = |xk: MatRef<'_, f64>| {
            if let Some(h) = hist.as_deref_mut() {
                let xs: Vec<f64> = xk.col(0).iter().copied().collect();
                fine.residual(rhs, &xs, &mut r);
                h.push(dot(&r, &r).sqrt() / b_norm);
            }
        };
        match self.kind {
            LinearSolverKind::Cg => {
                let params = CgParams {
                    initial_guess: InitialGuessStatus::MaybeNonZero,
                    abs_tolerance: 0.0,
                    rel_tolerance: rel_tol,
                    max_iters: self.max_iterations,
                    ..Default::default()
                };
                let mut buf = MemBuffer::new(conjugate_gradient_scratch(&m, &a, 1, Par::Seq));
                match conjugate_gradient(out, &m, &a, b, params, callback, Par::Seq, MemStack::new(&mut buf)) {
                    Ok(info) => KrylovOutcome::Converged(info.iter_count, info.rel_residual),
                    Err(CgError::NoConvergence { rel_residual, .. }) => KrylovOutcome::NotConverged(rel_residual),
                    Err(CgError::NonPositiveDefiniteOperator) => KrylovOutcome::Breakdown("the tangent"),
                    Err(CgError::NonPositiveDefinitePreconditioner) => KrylovOutcome::Breakdown("the preconditioner"),
                }
            }
            _ => {
                let params = BicgParams {
                    initial_guess: InitialGuessStatus::MaybeNonZero,
                    abs_tolerance: 0.0,
                    rel_tolerance: rel_tol,
                    max_iters: self.max_iterations,
                    ..Default::default()
                };
                let id = IdentityPrecond { dim: n };
                let mut buf = MemBuffer::new(bicgstab_scratch(id, &m, &a, 1, Par::Seq));
                match bicgstab(out, id, &m, &a, b, params, callback, Par::Seq, MemStack::new(&mut buf)) {
                    Ok(info) => KrylovOutcome::Converged(info.iter_count, info.rel_residual),
                    Err(BicgError::NoConvergence { rel_residual, .. }) => KrylovOutcome::NotConverged(rel_residual),
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

enum KrylovOutcome {
    Converged(usize, f64),
    NotConverged(f64),
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
                    Ok(LinearSolveStats { iterations, residual })
                } else {
                    Err(LinearSolveError::NonFinite)
                }
            }
            KrylovOutcome::NotConverged(reported) => {
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
mod tests {
    use super::*;
    use crate::{BlockPattern, Couplings, NodeLattice, SparseDirectSolver};

    /// The edges of an n × n node lattice as two-node elements.
    struct LatticeEdges {
        edges: Vec<[u32; 2]>,
        node_edges: Vec<Vec<(u32, u32)>>,
    }

    impl LatticeEdges {
        fn new(n: u32) -> Self {
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
    fn lattice_system(
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
