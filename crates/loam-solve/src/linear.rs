//! Sparse direct solvers on faer: Cholesky (LLᵀ) for symmetric tangents, LU for
//! non-symmetric ones. The symbolic factorisation (ordering and elimination tree) is kept
//! while the pattern's generation does not change, so a Newton iteration on unchanged
//! point–node connectivity pays only for the numeric factorisation.
//!
//! A non-symmetric matrix is never handed to Cholesky: the choice is the caller's (from the
//! material's tangent symmetry) and is reported by `kind()`.
//!
//! Every solver sits behind [`LinearSolver`]: prepare for a matrix (factorise, or build a
//! preconditioner), then solve to a relative tolerance (which a direct solver exceeds).
//! The interface passes the system as its node graph, values, constrained dofs and node
//! lattice, and vectors as plain slices over the dofs this process holds: a distributed
//! backend (PETSc's KSP over MPI) would hold a contiguous range of node rows and implement
//! the same two calls (docs/theory.md §19).

use crate::{BlockPattern, MatrixLayout, NodeLattice, SystemMatrix};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::linalg::{LltError, LuError};
use faer::sparse::FaerError;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{MatMut, Side};
use std::time::{Duration, Instant};

/// Which method a solver uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinearSolverKind {
    /// Sparse Cholesky, for symmetric positive definite tangents.
    Cholesky,
    /// Sparse LU with partial pivoting, for non-symmetric tangents.
    Lu,
    /// Conjugate gradients preconditioned by geometric multigrid, for symmetric positive
    /// definite tangents.
    Cg,
    /// BiCGStab preconditioned by geometric multigrid, for the others.
    BiCgStab,
}

impl LinearSolverKind {
    pub fn is_iterative(self) -> bool {
        matches!(self, LinearSolverKind::Cg | LinearSolverKind::BiCgStab)
    }

    /// The method of this family (direct or iterative) for a tangent that is (or is not)
    /// symmetric positive definite.
    pub fn for_tangent(iterative: bool, symmetric_definite: bool) -> Self {
        match (iterative, symmetric_definite) {
            (false, true) => LinearSolverKind::Cholesky,
            (false, false) => LinearSolverKind::Lu,
            (true, true) => LinearSolverKind::Cg,
            (true, false) => LinearSolverKind::BiCgStab,
        }
    }

    /// A solver of this kind.
    pub fn solver(self) -> Box<dyn LinearSolver> {
        if self.is_iterative() {
            Box::new(crate::IterativeSolver::new(self))
        } else {
            Box::new(SparseDirectSolver::new(self))
        }
    }
}

impl std::fmt::Display for LinearSolverKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LinearSolverKind::Cholesky => "sparse Cholesky",
            LinearSolverKind::Lu => "sparse LU",
            LinearSolverKind::Cg => "multigrid-preconditioned CG",
            LinearSolverKind::BiCgStab => "multigrid-preconditioned BiCGStab",
        })
    }
}

/// What the settings ask of the linear solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LinearSolverChoice {
    /// Direct below a size, iterative above it (and where the background is a grid), the
    /// method from the tangent's symmetry.
    #[default]
    Auto,
    /// A direct solver, Cholesky or LU from the tangent's symmetry.
    Direct,
    /// An iterative solver, CG or BiCGStab from the tangent's symmetry.
    Iterative,
    /// This method, whatever the tangent.
    Forced(LinearSolverKind),
}

/// A linear system as the solvers see it: the node graph, the matrix assembled on it (in
/// the layout the solver asks for, or converted), the constrained dofs (rows and columns
/// eliminated but for the diagonal) and, where the nodes lie on a grid, their lattice
/// coordinates (for multigrid).
#[derive(Debug, Clone, Copy)]
pub struct LinearSystem<'a> {
    pub pattern: &'a BlockPattern,
    pub matrix: &'a SystemMatrix,
    pub constrained: &'a [bool],
    pub lattice: Option<&'a NodeLattice>,
}

/// What one solve did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LinearSolveStats {
    /// Krylov iterations (0 for a direct solve).
    pub iterations: usize,
    /// ‖b − A x‖ / ‖b‖ reached (0 for a direct solve, which does not compute it).
    pub residual: f64,
}

/// A linear solver. See the module docs.
pub trait LinearSolver: Send {
    fn kind(&self) -> LinearSolverKind;
    /// The layout to assemble the matrix in (another is converted, at the cost of a copy).
    fn layout(&self) -> MatrixLayout {
        MatrixLayout::Columns
    }
    /// Whether `prepare` needs the node lattice.
    fn wants_lattice(&self) -> bool {
        false
    }
    /// Prepare for the matrix of `system`: factorise it, or build the preconditioner.
    fn prepare(&mut self, system: &LinearSystem<'_>) -> Result<(), LinearSolveError>;
    /// Solve A x = rhs into `x` to the relative residual `rel_tol` (a direct solver does
    /// better), `system` the one of the last `prepare`.
    fn solve(
        &mut self,
        system: &LinearSystem<'_>,
        rhs: &[f64],
        x: &mut [f64],
        rel_tol: f64,
    ) -> Result<LinearSolveStats, LinearSolveError>;
    fn timings(&self) -> LinearSolverTimings;
    /// Bytes the solver holds beyond the assembled system (a factor, a hierarchy); 0 where
    /// it is not known.
    fn bytes(&self) -> usize {
        0
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinearSolveError {
    #[error("symbolic factorisation failed: {0}")]
    Symbolic(String),
    #[error("the tangent is not positive definite (Cholesky failed): {0}")]
    NotPositiveDefinite(String),
    #[error("the tangent is singular (LU failed): {0}")]
    Singular(String),
    #[error("solve called before a successful factorisation")]
    NotFactorised,
    #[error("the solution contains NaN or infinity")]
    NonFinite,
    #[error("multigrid needs the nodes' grid coordinates, and a body-fitted mesh (the FEM reference) has none: use a direct solver")]
    NoLattice,
    #[error(transparent)]
    NotConverged(Box<KrylovFailure>),
    #[error("the multigrid smoother takes blocks of 1 to 3 dofs a node, and this system has {0}: use a direct solver")]
    BlockSize(usize),
    /// A failure its caller traced to a cause in the model (which this crate cannot see).
    #[error("{source}; here {cause}")]
    Traced { source: Box<LinearSolveError>, cause: String },
}

/// A Krylov solve that did not reach its tolerance, with the true relative residual of
/// each iterate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{method} did not reach the relative residual {tolerance:.1e} in {iterations} iterations (reached {residual:.2e}; residuals {})", history_summary(.history))]
pub struct KrylovFailure {
    pub method: LinearSolverKind,
    pub iterations: usize,
    pub residual: f64,
    pub tolerance: f64,
    pub history: Vec<f64>,
}

/// A residual history in a line: the first few, then every tenth, then the last.
fn history_summary(history: &[f64]) -> String {
    let picked: Vec<String> = history
        .iter()
        .enumerate()
        .filter(|(i, _)| *i < 3 || i % 10 == 9 || *i + 1 == history.len())
        .map(|(i, r)| format!("{}: {r:.2e}", i + 1))
        .collect();
    picked.join(", ")
}

/// Time spent in each phase, summed since creation: for a direct solver the symbolic and
/// numeric factorisations; for an iterative one the multigrid structure and its values
/// (Galerkin products, smoothers, coarsest factorisation).
#[derive(Debug, Clone, Copy, Default)]
pub struct LinearSolverTimings {
    pub symbolic: Duration,
    pub numeric: Duration,
    pub solve: Duration,
    pub symbolic_count: usize,
    pub numeric_count: usize,
    /// Krylov iterations over all solves.
    pub iterations: usize,
}

/// A sparse direct solver with symbolic reuse. See the module docs.
pub struct SparseDirectSolver {
    kind: LinearSolverKind,
    generation: Option<u64>,
    symbolic_llt: Option<SymbolicLlt<usize>>,
    symbolic_lu: Option<SymbolicLu<usize>>,
    llt: Option<Llt<usize, f64>>,
    lu: Option<Lu<usize, f64>>,
    timings: LinearSolverTimings,
}

impl SparseDirectSolver {
    pub fn new(kind: LinearSolverKind) -> Self {
        assert!(!kind.is_iterative(), "{kind} is not a factorisation");
        Self {
            kind,
            generation: None,
            symbolic_llt: None,
            symbolic_lu: None,
            llt: None,
            lu: None,
            timings: LinearSolverTimings::default(),
        }
    }

    pub fn kind(&self) -> LinearSolverKind {
        self.kind
    }

    pub fn timings(&self) -> LinearSolverTimings {
        self.timings
    }

    /// Factorise the matrix with `pattern` and `values`, reusing the symbolic factorisation
    /// when the pattern's generation is unchanged.
    pub fn factorize(&mut self, pattern: &BlockPattern, values: &[f64]) -> Result<(), LinearSolveError> {
        let n = pattern.num_dofs();
        let symbolic = SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
        let mat = SparseColMatRef::new(symbolic, values);
        if self.generation != Some(pattern.generation()) {
            let t = Instant::now();
            match self.kind {
                LinearSolverKind::Cholesky => {
                    self.symbolic_llt = Some(
                        SymbolicLlt::try_new(symbolic, Side::Lower)
                            .map_err(|e| LinearSolveError::Symbolic(generic_words(e)))?,
                    )
                }
                _ => {
                    self.symbolic_lu =
                        Some(SymbolicLu::try_new(symbolic).map_err(|e| LinearSolveError::Symbolic(generic_words(e)))?)
                }
            }
            self.generation = Some(pattern.generation());
            self.timings.symbolic += t.elapsed();
            self.timings.symbolic_count += 1;
        }
        let t = Instant::now();
        self.llt = None;
        self.lu = None;
        match self.kind {
            LinearSolverKind::Cholesky => {
                let sym = self.symbolic_llt.clone().expect("symbolic factorisation present");
                self.llt = Some(
                    Llt::try_new_with_symbolic(sym, mat, Side::Lower)
                        .map_err(|e| LinearSolveError::NotPositiveDefinite(llt_words(e, n)))?,
                );
            }
            _ => {
                let sym = self.symbolic_lu.clone().expect("symbolic factorisation present");
                self.lu =
                    Some(Lu::try_new_with_symbolic(sym, mat).map_err(|e| LinearSolveError::Singular(lu_words(e, n)))?);
            }
        }
        self.timings.numeric += t.elapsed();
        self.timings.numeric_count += 1;
        Ok(())
    }

    /// Solve A x = rhs in place with the last factorisation.
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<(), LinearSolveError> {
        let t = Instant::now();
        let n = rhs.len();
        let mat = MatMut::from_column_major_slice_mut(rhs, n, 1);
        match (&self.llt, &self.lu) {
            (Some(llt), _) => llt.solve_in_place(mat),
            (None, Some(lu)) => lu.solve_in_place(mat),
            _ => return Err(LinearSolveError::NotFactorised),
        }
        self.timings.solve += t.elapsed();
        if rhs.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(LinearSolveError::NonFinite)
        }
    }
}

impl LinearSolver for SparseDirectSolver {
    fn kind(&self) -> LinearSolverKind {
        self.kind
    }

    fn prepare(&mut self, system: &LinearSystem<'_>) -> Result<(), LinearSolveError> {
        self.factorize(system.pattern, &system.matrix.to_columns(system.pattern))
    }

    fn solve(
        &mut self,
        _system: &LinearSystem<'_>,
        rhs: &[f64],
        x: &mut [f64],
        _rel_tol: f64,
    ) -> Result<LinearSolveStats, LinearSolveError> {
        x.copy_from_slice(rhs);
        self.solve_in_place(x)?;
        Ok(LinearSolveStats::default())
    }

    fn timings(&self) -> LinearSolverTimings {
        self.timings
    }
}

/// Why a tangent that was positive definite or regular before stops being so.
const SINGULAR_CAUSE: &str = "a part of the body is free to move or the material has lost its stiffness";

/// What a failed Cholesky factorisation of an `n`-dof tangent means, in words (faer's
/// errors print as Rust debug text).
fn llt_words(e: LltError, n: usize) -> String {
    match e {
        LltError::Numeric(faer::linalg::cholesky::llt::factor::LltError::NonPositivePivot { index }) => format!(
            "pivot {index} of {n} (in the fill-reducing order) is not positive: the tangent is singular or \
             indefinite, because {SINGULAR_CAUSE}"
        ),
        LltError::Generic(e) => generic_words(e),
    }
}

/// What a failed LU factorisation of an `n`-dof tangent means, in words.
fn lu_words(e: LuError, n: usize) -> String {
    match e {
        LuError::SymbolicSingular { index } => {
            format!("no pivot at step {index} of {n}: the tangent is singular, because {SINGULAR_CAUSE}")
        }
        LuError::Generic(e) => generic_words(e),
    }
}

/// faer's errors that are not about the numbers.
fn generic_words(e: impl Into<FaerError>) -> String {
    match e.into() {
        FaerError::OutOfMemory => {
            "out of memory: the factor does not fit in this machine; the iterative solver needs far less".into()
        }
        FaerError::IndexOverflow => "the factor has more entries than its index type can count".into(),
        other => format!("{other:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::tests::assemble_chain;

    #[test]
    fn cholesky_and_lu_solve_a_chain_with_a_fixed_end() {
        // Bar of 3 elements, stiffness 1,2,3, node 0 fixed, unit load at node 3:
        // displacements are cumulative flexibilities 1, 1 + 1/2, 1 + 1/2 + 1/3.
        let fixed = [true, false, false, false];
        let (p, v) = assemble_chain(3, 1, &fixed);
        for kind in [LinearSolverKind::Cholesky, LinearSolverKind::Lu] {
            let mut s = SparseDirectSolver::new(kind);
            s.factorize(&p, &v).unwrap();
            let mut x = vec![0.0, 0.0, 0.0, 1.0];
            s.solve_in_place(&mut x).unwrap();
            let exact = [0.0, 1.0, 1.5, 1.0 + 0.5 + 1.0 / 3.0];
            for (a, b) in x.iter().zip(exact) {
                assert!((a - b).abs() < 1e-14, "{kind}: {x:?}");
            }
            // Second factorisation on the same pattern reuses the symbolic part.
            s.factorize(&p, &v).unwrap();
            assert_eq!(s.timings().symbolic_count, 1);
            assert_eq!(s.timings().numeric_count, 2);
        }
    }

    /// Blocks of 4 dofs a node (a 3D displacement and a pore pressure): the chain of three
    /// elements with the coupling block k M per element, M symmetric positive definite
    /// with every dof coupled, node 0 held; assembled in both layouts (the same product)
    /// and solved by Cholesky and LU for the right-hand side of a chosen solution, which
    /// comes back to round-off.
    #[test]
    fn four_dofs_a_node_assemble_and_solve() {
        use crate::pattern::tests::Chain;
        use crate::BlockMatrix;
        let d = 4;
        let m = |r: usize, c: usize| if r == c { 2.0 + r as f64 } else { 0.5 };
        let chain = Chain::new(3);
        let mut p = BlockPattern::new(d);
        p.update(&chain);
        let fixed: Vec<bool> = (0..16).map(|dof| dof < 4).collect();
        let block = |e: usize, a: usize, b: usize, out: &mut [f64]| {
            let k = (1.0 + e as f64) * if a == b { 1.0 } else { -1.0 };
            (0..d * d).for_each(|rc| out[rc] += k * m(rc / d, rc % d));
        };
        let mut values = Vec::new();
        p.assemble(&chain, &fixed, &mut values, block);
        let mut rows = BlockMatrix::default();
        p.assemble_rows(&chain, &fixed, &mut rows, block);
        let exact: Vec<f64> = (0..16).map(|dof| if dof < 4 { 0.0 } else { 1.0 + 0.1 * dof as f64 }).collect();
        let (mut f, mut g) = (vec![0.0; 16], vec![0.0; 16]);
        p.mul_vec(&values, &exact, &mut f);
        rows.apply(&exact, &mut g);
        assert_eq!(f, g, "both layouts hold the same matrix");
        assert_eq!(p.asymmetry(&values), 0.0);
        for kind in [LinearSolverKind::Cholesky, LinearSolverKind::Lu] {
            let mut s = SparseDirectSolver::new(kind);
            s.factorize(&p, &values).unwrap();
            let mut x = f.clone();
            s.solve_in_place(&mut x).unwrap();
            for (a, b) in x.iter().zip(&exact) {
                assert!((a - b).abs() < 1e-13, "{kind}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn an_unconstrained_bar_is_not_positive_definite() {
        let (p, v) = assemble_chain(3, 1, &[false; 4]);
        let mut s = SparseDirectSolver::new(LinearSolverKind::Cholesky);
        // Singular (rigid-body mode): Cholesky either fails or yields a non-finite solve.
        let res = s.factorize(&p, &v).and_then(|_| {
            let mut x = vec![1.0, 0.0, 0.0, -1.0];
            s.solve_in_place(&mut x)
        });
        assert!(res.is_err());
        if let Err(e @ LinearSolveError::NotPositiveDefinite(_)) = res {
            assert!(e.to_string().contains("free to move") && !e.to_string().contains("Numeric("), "{e}");
        }
    }

    /// faer's factorisation errors read as what they mean, not as Rust debug text.
    #[test]
    fn factorisation_failures_are_said_in_words() {
        use faer::linalg::cholesky::llt::factor::LltError as Pivot;
        let words = llt_words(LltError::Numeric(Pivot::NonPositivePivot { index: 4 }), 10);
        assert!(words.starts_with("pivot 4 of 10") && words.contains("free to move"), "{words}");
        assert!(lu_words(LuError::SymbolicSingular { index: 2 }, 9).starts_with("no pivot at step 2 of 9"));
        assert!(generic_words(FaerError::OutOfMemory).contains("iterative solver"));
    }
}
