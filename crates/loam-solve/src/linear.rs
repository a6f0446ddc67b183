//! Sparse direct solvers on faer: Cholesky (LLᵀ) for symmetric tangents, LU for
//! non-symmetric ones. The symbolic factorisation (ordering and elimination tree) is kept
//! while the pattern's generation does not change, so a Newton iteration on unchanged
//! point–node connectivity pays only for the numeric factorisation. Where the system comes
//! with its node lattice, the Cholesky family eliminates in nested-dissection order
//! (`ordering.rs`), AMD's otherwise. A non-symmetric tangent may instead be solved by
//! GMRES preconditioned by the LDLᵀ factor of its symmetric part, with its LU where that
//! fails (docs/theory.md §19, "The order and the symmetric part").
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

use crate::krylov::{FactorPrecond, Krylov, KrylovOutcome, SystemOperator};
use crate::{BlockPattern, MatrixLayout, NodeLattice, SystemMatrix};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::solvers::Solve;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, LdltRef, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::linalg::solvers::{Lu, SymbolicLu};
use faer::sparse::linalg::{LltError, LuError};
use faer::sparse::FaerError;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use rayon::prelude::*;
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
    /// The time a factorisation made during the solve took (the LU after a Krylov method
    /// that did not converge), set-up time that the solver's `prepare` did not see.
    pub factorised: std::time::Duration,
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
    /// Whether `prepare` uses the node lattice where the nodes lie on a grid (a direct
    /// solver's fill-reducing order), without needing it.
    fn uses_lattice(&self) -> bool {
        self.wants_lattice()
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
    /// The method in words (what a run's summary and log name).
    fn description(&self) -> String {
        self.kind().to_string()
    }
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

/// Where and how long GMRES on the symmetric part's factor is tried (see
/// [`SparseDirectSolver::with_symmetric_part`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SymmetricPart {
    /// Systems of fewer dofs take the LU at once.
    pub from_dofs: usize,
    /// GMRES iterations before the LU.
    pub max_iterations: usize,
}

/// The factor a [`SparseDirectSolver`] holds.
enum Factor {
    None,
    /// LLᵀ of the tangent, on `symbolic_cholesky`.
    Llt(Vec<f64>),
    /// LDLᵀ of the tangent's symmetric part, on `symbolic_cholesky`: GMRES's
    /// preconditioner for the tangent.
    SymmetricPart(Vec<f64>),
    /// LU of the tangent (boxed: faer's numeric LU is large beside a vector).
    Lu(Box<Lu<usize, f64>>),
}

/// A sparse direct solver with symbolic reuse. See the module docs.
pub struct SparseDirectSolver {
    kind: LinearSolverKind,
    /// With LU: from how many dofs the symmetric part's LDLᵀ preconditions GMRES, and the
    /// most iterations before the tangent's LU (`None`: LU at once).
    symmetric_part: Option<SymmetricPart>,
    generation: Option<u64>,
    /// The symbolic LLᵀ / LDLᵀ, in the nested-dissection order of the node lattice where
    /// the system has one, AMD's otherwise.
    symbolic_cholesky: Option<SymbolicCholesky<usize>>,
    symbolic_lu: Option<SymbolicLu<usize>>,
    factor: Factor,
    /// Dofs of the last factorised matrix.
    dofs: usize,
    /// (K + Kᵀ) / 2 on the pattern, for the symmetric-part factor.
    symmetric_values: Vec<f64>,
    timings: LinearSolverTimings,
}

impl SparseDirectSolver {
    pub fn new(kind: LinearSolverKind) -> Self {
        assert!(!kind.is_iterative(), "{kind} is not a factorisation");
        Self {
            kind,
            symmetric_part: None,
            generation: None,
            symbolic_cholesky: None,
            symbolic_lu: None,
            factor: Factor::None,
            dofs: 0,
            symmetric_values: Vec::new(),
            timings: LinearSolverTimings::default(),
        }
    }

    /// For LU, on systems of `part.from_dofs` or more: solve by GMRES preconditioned by
    /// the LDLᵀ factor of the tangent's symmetric part, (K + Kᵀ)/2, to the tolerance asked,
    /// and factorise the tangent by LU only where that factor fails or GMRES does not
    /// converge in `part.max_iterations` (docs/theory.md §19). The symmetric part's factor
    /// is several times cheaper than faer's LU, whose column ordering bounds its fill by
    /// that of KᵀK. The LDLᵀ and its solves run on one thread, so that the result is the
    /// same for any thread count.
    pub fn with_symmetric_part(mut self, part: SymmetricPart) -> Self {
        if self.kind == LinearSolverKind::Lu {
            self.symmetric_part = Some(part);
        }
        self
    }

    pub fn kind(&self) -> LinearSolverKind {
        self.kind
    }

    pub fn timings(&self) -> LinearSolverTimings {
        self.timings
    }

    /// Dofs of the factorised matrix (0 before the first factorisation).
    pub fn num_dofs(&self) -> usize {
        if matches!(self.factor, Factor::None) {
            0
        } else {
            self.dofs
        }
    }

    /// Factorise the matrix with `pattern` and `values` (Cholesky or LU as the kind says;
    /// AMD's order for Cholesky), reusing the symbolic factorisation when the pattern's
    /// generation is unchanged.
    pub fn factorize(&mut self, pattern: &BlockPattern, values: &[f64]) -> Result<(), LinearSolveError> {
        self.factorize_in_order(pattern, None, values)
    }

    /// As [`factorize`](Self::factorize), the Cholesky family in the nested-dissection
    /// order of `lattice` where there is one.
    fn factorize_in_order(
        &mut self,
        pattern: &BlockPattern,
        lattice: Option<&NodeLattice>,
        values: &[f64],
    ) -> Result<(), LinearSolveError> {
        let n = pattern.num_dofs();
        self.keep_symbolic_of(pattern);
        self.factor = Factor::None;
        self.dofs = n;
        match self.kind {
            LinearSolverKind::Cholesky => {
                self.symbolic_cholesky(pattern, lattice)?;
                let symbolic = self.symbolic_cholesky.as_ref().expect("just computed");
                let t = Instant::now();
                let l = numeric_llt(symbolic, pattern, values)
                    .map_err(|e| LinearSolveError::NotPositiveDefinite(llt_words(e, n)))?;
                self.factor = Factor::Llt(l);
                self.count_numeric(t);
            }
            _ => {
                let symbolic = self.symbolic_lu(pattern)?.clone();
                let t = Instant::now();
                let structure = SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
                let mat = SparseColMatRef::new(structure, values);
                let lu =
                    Lu::try_new_with_symbolic(symbolic, mat).map_err(|e| LinearSolveError::Singular(lu_words(e, n)))?;
                self.factor = Factor::Lu(Box::new(lu));
                self.count_numeric(t);
            }
        }
        Ok(())
    }

    /// Factorise the symmetric part of the tangent by LDLᵀ; false where a pivot vanishes
    /// (then the tangent needs its LU).
    fn factorize_symmetric_part(&mut self, system: &LinearSystem<'_>) -> Result<bool, LinearSolveError> {
        let pattern = system.pattern;
        let values = system.matrix.to_columns(pattern);
        symmetric_part(pattern, &values, &mut self.symmetric_values);
        self.keep_symbolic_of(pattern);
        self.factor = Factor::None;
        self.dofs = pattern.num_dofs();
        self.symbolic_cholesky(pattern, system.lattice)?;
        let symbolic = self.symbolic_cholesky.as_ref().expect("just computed");
        let t = Instant::now();
        let factored = numeric_ldlt(symbolic, pattern, &self.symmetric_values);
        self.count_numeric(t);
        Ok(match factored {
            Some(l) => {
                self.factor = Factor::SymmetricPart(l);
                true
            }
            None => false,
        })
    }

    /// Drop the symbolic factorisations where the pattern is another.
    fn keep_symbolic_of(&mut self, pattern: &BlockPattern) {
        if self.generation != Some(pattern.generation()) {
            self.symbolic_cholesky = None;
            self.symbolic_lu = None;
            self.generation = Some(pattern.generation());
        }
    }

    fn count_numeric(&mut self, start: Instant) {
        self.timings.numeric += start.elapsed();
        self.timings.numeric_count += 1;
    }

    /// The symbolic LLᵀ of the pattern, computed once per generation.
    fn symbolic_cholesky(
        &mut self,
        pattern: &BlockPattern,
        lattice: Option<&NodeLattice>,
    ) -> Result<(), LinearSolveError> {
        if self.symbolic_cholesky.is_none() {
            let t = Instant::now();
            let n = pattern.num_dofs();
            let structure = SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
            let order = lattice.and_then(|l| crate::ordering::nested_dissection(pattern, l));
            let inverse = order.as_ref().map(|o| crate::ordering::inverse(o));
            let ordering = match (&order, &inverse) {
                (Some(o), Some(i)) => SymmetricOrdering::Custom(PermRef::new_checked(o, i, n)),
                _ => SymmetricOrdering::Amd,
            };
            let symbolic = factorize_symbolic_cholesky(structure, Side::Lower, ordering, Default::default())
                .map_err(|e| LinearSolveError::Symbolic(generic_words(e)))?;
            self.symbolic_cholesky = Some(symbolic);
            self.timings.symbolic += t.elapsed();
            self.timings.symbolic_count += 1;
        }
        Ok(())
    }

    /// The symbolic LU of the pattern (COLAMD), computed once per generation.
    fn symbolic_lu(&mut self, pattern: &BlockPattern) -> Result<&SymbolicLu<usize>, LinearSolveError> {
        if self.symbolic_lu.is_none() {
            let t = Instant::now();
            let n = pattern.num_dofs();
            let structure = SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
            self.symbolic_lu =
                Some(SymbolicLu::try_new(structure).map_err(|e| LinearSolveError::Symbolic(generic_words(e)))?);
            self.timings.symbolic += t.elapsed();
            self.timings.symbolic_count += 1;
        }
        Ok(self.symbolic_lu.as_ref().expect("just computed"))
    }

    /// Solve A x = rhs in place with the last factorisation (of A itself: a factor of its
    /// symmetric part only preconditions, `LinearSolver::solve`).
    pub fn solve_in_place(&mut self, rhs: &mut [f64]) -> Result<(), LinearSolveError> {
        let t = Instant::now();
        if matches!(self.factor, Factor::SymmetricPart(_)) || !self.apply_factor(rhs) {
            return Err(LinearSolveError::NotFactorised);
        }
        self.timings.solve += t.elapsed();
        if rhs.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(LinearSolveError::NonFinite)
        }
    }

    /// `x ← F⁻¹ x` with the factor F held (the tangent's, or its symmetric part's); false
    /// when there is none.
    pub(crate) fn apply_factor(&self, x: &mut [f64]) -> bool {
        let n = x.len();
        let mat = MatMut::from_column_major_slice_mut(x, n, 1);
        let par = faer::get_global_parallelism();
        match (&self.factor, &self.symbolic_cholesky) {
            (Factor::Lu(lu), _) => lu.solve_in_place(mat),
            (Factor::Llt(l), Some(symbolic)) => {
                let mut buf = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, par));
                LltRef::new(symbolic, l).solve_in_place_with_conj(Conj::No, mat, par, MemStack::new(&mut buf));
            }
            (Factor::SymmetricPart(l), Some(symbolic)) => {
                let mut buf = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
                LdltRef::new(symbolic, l).solve_in_place_with_conj(Conj::No, mat, Par::Seq, MemStack::new(&mut buf));
            }
            _ => return false,
        }
        true
    }

    /// GMRES on the tangent preconditioned by its symmetric part's factor (see
    /// [`with_symmetric_part`](Self::with_symmetric_part)); where it does not reach
    /// `rel_tol`, factorise the tangent by LU and solve directly.
    fn solve_on_symmetric_part(
        &mut self,
        system: &LinearSystem<'_>,
        rhs: &[f64],
        x: &mut [f64],
        rel_tol: f64,
    ) -> Result<LinearSolveStats, LinearSolveError> {
        let max_iterations = self.symmetric_part.expect("the symmetric part preconditions").max_iterations;
        let t = Instant::now();
        let method = Krylov { kind: LinearSolverKind::Lu, rel_tol, max_iterations };
        let outcome = method.solve(&SystemOperator(system), &FactorPrecond(self), rhs, x, |_| {});
        self.timings.solve += t.elapsed();
        match outcome {
            KrylovOutcome::Converged(iterations, residual) if x.iter().all(|v| v.is_finite()) => {
                self.timings.iterations += iterations;
                Ok(LinearSolveStats { iterations, residual, ..Default::default() })
            }
            outcome => {
                let iterations = match outcome {
                    KrylovOutcome::Converged(n, _) | KrylovOutcome::NotConverged(n, _) => n,
                    KrylovOutcome::Breakdown(_) => max_iterations,
                };
                tracing::debug!(iterations, "GMRES on the symmetric part's factor did not converge; LU");
                self.timings.iterations += iterations;
                let t = Instant::now();
                self.factorize_tangent(system)?;
                let factorised = t.elapsed();
                x.copy_from_slice(rhs);
                self.solve_in_place(x)?;
                Ok(LinearSolveStats { iterations, residual: 0.0, factorised })
            }
        }
    }

    /// Factorise the tangent itself (Cholesky or LU as the kind says).
    fn factorize_tangent(&mut self, system: &LinearSystem<'_>) -> Result<(), LinearSolveError> {
        self.factorize_in_order(system.pattern, system.lattice, &system.matrix.to_columns(system.pattern))
    }
}

/// `out` ← (K + Kᵀ) / 2 on `pattern` (structurally symmetric, rows ascending in a column).
fn symmetric_part(pattern: &BlockPattern, values: &[f64], out: &mut Vec<f64>) {
    let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
    out.resize(values.len(), 0.0);
    out.par_iter_mut().enumerate().for_each(|(e, s)| {
        // The column of entry e, then the place of its transpose.
        let c = col_ptr.partition_point(|&start| start <= e) - 1;
        let r = row_idx[e];
        let t = col_ptr[r] + row_idx[col_ptr[r]..col_ptr[r + 1]].binary_search(&c).expect("symmetric pattern");
        *s = 0.5 * (values[e] + values[t]);
    });
}

/// The numeric LLᵀ of `values` on `symbolic`.
fn numeric_llt(
    symbolic: &SymbolicCholesky<usize>,
    pattern: &BlockPattern,
    values: &[f64],
) -> Result<Vec<f64>, LltError> {
    let n = pattern.num_dofs();
    let structure = SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
    let par = faer::get_global_parallelism();
    let mut l = vec![0.0; symbolic.len_val()];
    let mut buf = MemBuffer::try_new(symbolic.factorize_numeric_llt_scratch::<f64>(par, Default::default()))
        .map_err(|_| LltError::Generic(FaerError::OutOfMemory))?;
    symbolic.factorize_numeric_llt::<f64>(
        &mut l,
        SparseColMatRef::new(structure, values),
        Side::Lower,
        Default::default(),
        par,
        MemStack::new(&mut buf),
        Default::default(),
    )?;
    Ok(l)
}

/// The numeric LDLᵀ of `values` on `symbolic`; `None` where a pivot vanishes or the
/// factor is not finite.
fn numeric_ldlt(symbolic: &SymbolicCholesky<usize>, pattern: &BlockPattern, values: &[f64]) -> Option<Vec<f64>> {
    let n = pattern.num_dofs();
    let structure = SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
    let par = Par::Seq;
    let mut l = vec![0.0; symbolic.len_val()];
    let mut buf = MemBuffer::try_new(symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default())).ok()?;
    symbolic
        .factorize_numeric_ldlt::<f64>(
            &mut l,
            SparseColMatRef::new(structure, values),
            Side::Lower,
            Default::default(),
            par,
            MemStack::new(&mut buf),
            Default::default(),
        )
        .ok()?;
    l.iter().all(|v| v.is_finite()).then_some(l)
}

impl LinearSolver for SparseDirectSolver {
    fn kind(&self) -> LinearSolverKind {
        self.kind
    }

    /// Cholesky and the symmetric part's LDLᵀ order by nested dissection on the lattice;
    /// faer's LU orders its columns itself.
    fn uses_lattice(&self) -> bool {
        self.kind == LinearSolverKind::Cholesky || self.symmetric_part.is_some()
    }

    fn description(&self) -> String {
        const GMRES: &str = "GMRES preconditioned by the symmetric part's LDLᵀ";
        match self.symmetric_part {
            // Before the first factorisation the size is not known.
            Some(part) if self.dofs == 0 => format!("sparse LU, or from {} dofs {GMRES}", part.from_dofs),
            Some(part) if self.dofs >= part.from_dofs => format!("{GMRES} (sparse LU where that fails)"),
            _ => self.kind.to_string(),
        }
    }

    /// The LLᵀ or LDLᵀ factor's values and the symmetric part (faer does not tell an
    /// LU's size).
    fn bytes(&self) -> usize {
        match &self.factor {
            Factor::Llt(l) | Factor::SymmetricPart(l) => (l.len() + self.symmetric_values.len()) * 8,
            _ => 0,
        }
    }

    fn prepare(&mut self, system: &LinearSystem<'_>) -> Result<(), LinearSolveError> {
        let large = |part: SymmetricPart| system.pattern.num_dofs() >= part.from_dofs;
        if self.symmetric_part.is_some_and(large) && self.factorize_symmetric_part(system)? {
            return Ok(());
        }
        self.factorize_tangent(system)
    }

    fn solve(
        &mut self,
        system: &LinearSystem<'_>,
        rhs: &[f64],
        x: &mut [f64],
        rel_tol: f64,
    ) -> Result<LinearSolveStats, LinearSolveError> {
        if matches!(self.factor, Factor::SymmetricPart(_)) {
            return self.solve_on_symmetric_part(system, rhs, x, rel_tol);
        }
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

    /// The largest difference between `x` and `exact`, relative to the largest |exact|.
    fn relative_error(x: &[f64], exact: &[f64]) -> f64 {
        let scale = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        x.iter().zip(exact).fold(0.0f64, |m, (a, b)| m.max((a - b).abs())) / scale
    }

    /// A non-symmetric block Laplacian on a 24 × 24 lattice (the 2 × 2 block k has
    /// k₁₂ = 0.6, k₂₁ = −0.2): GMRES preconditioned by the symmetric part's LDLᵀ reaches the
    /// LU solution to 1e-9 (the tolerance 1e-10 times a condition number of a few) without
    /// an LU; where it may take only one iteration, the tangent's LU solves it to
    /// round-off. A symmetric one (k₁₂ = k₂₁ = 0.5) factorised by Cholesky in the lattice's
    /// nested-dissection order gives AMD's solution to round-off.
    #[test]
    fn the_symmetric_part_preconditions_a_non_symmetric_tangent() {
        use crate::krylov::tests::lattice_system;
        let (pattern, matrix, constrained, lattice, rhs) = lattice_system(24, [2.0, 0.6, -0.2, 1.0], 1.0);
        let system =
            LinearSystem { pattern: &pattern, matrix: &matrix, constrained: &constrained, lattice: Some(&lattice) };
        let mut lu = SparseDirectSolver::new(LinearSolverKind::Lu);
        lu.prepare(&system).unwrap();
        let mut exact = vec![0.0; rhs.len()];
        lu.solve(&system, &rhs, &mut exact, 0.0).unwrap();
        for (max_iterations, tolerance, factorisations) in [(40, 1e-9, 1), (1, 1e-13, 2)] {
            let part = SymmetricPart { from_dofs: 1, max_iterations };
            let mut s = SparseDirectSolver::new(LinearSolverKind::Lu).with_symmetric_part(part);
            s.prepare(&system).unwrap();
            let mut x = vec![0.0; rhs.len()];
            let stats = s.solve(&system, &rhs, &mut x, 1e-10).unwrap();
            let error = relative_error(&x, &exact);
            assert!(error < tolerance, "{max_iterations} iterations: error {error:.2e}");
            assert!(stats.iterations > 0);
            assert_eq!(s.timings().numeric_count, factorisations, "{max_iterations} iterations: {stats:?}");
        }
        let (pattern, matrix, constrained, lattice, rhs) = lattice_system(24, [2.0, 0.5, 0.5, 1.0], 1.0);
        let mut amd = SparseDirectSolver::new(LinearSolverKind::Cholesky);
        amd.factorize(&pattern, &matrix.to_columns(&pattern)).unwrap();
        let mut exact = rhs.clone();
        amd.solve_in_place(&mut exact).unwrap();
        let system =
            LinearSystem { pattern: &pattern, matrix: &matrix, constrained: &constrained, lattice: Some(&lattice) };
        let mut nd = SparseDirectSolver::new(LinearSolverKind::Cholesky);
        nd.prepare(&system).unwrap();
        let mut x = vec![0.0; rhs.len()];
        nd.solve(&system, &rhs, &mut x, 0.0).unwrap();
        assert!(relative_error(&x, &exact) < 1e-12, "{:.2e}", relative_error(&x, &exact));
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
