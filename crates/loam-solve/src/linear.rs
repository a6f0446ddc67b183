//! Sparse direct solvers on faer: Cholesky (LLᵀ) for symmetric tangents, LU for
//! non-symmetric ones. The symbolic factorisation (ordering and elimination tree) is kept
//! while the pattern's generation does not change, so a Newton iteration on unchanged
//! point–node connectivity pays only for the numeric factorisation.
//!
//! A non-symmetric matrix is never handed to Cholesky: the choice is the caller's (from the
//! material's tangent symmetry) and is reported by `kind()`.

use crate::BlockPattern;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, Lu, SymbolicLlt, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{MatMut, Side};
use std::time::{Duration, Instant};

/// Which factorisation a solver uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinearSolverKind {
    /// Sparse Cholesky, for symmetric positive definite tangents.
    Cholesky,
    /// Sparse LU with partial pivoting, for non-symmetric tangents.
    Lu,
}

impl std::fmt::Display for LinearSolverKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            LinearSolverKind::Cholesky => "sparse Cholesky",
            LinearSolverKind::Lu => "sparse LU",
        })
    }
}

#[derive(Debug, Clone, thiserror::Error)]
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
}

/// Time spent in each phase, summed since creation.
#[derive(Debug, Clone, Copy, Default)]
pub struct LinearSolverTimings {
    pub symbolic: Duration,
    pub numeric: Duration,
    pub solve: Duration,
    pub symbolic_count: usize,
    pub numeric_count: usize,
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
                            .map_err(|e| LinearSolveError::Symbolic(format!("{e:?}")))?,
                    )
                }
                LinearSolverKind::Lu => {
                    self.symbolic_lu =
                        Some(SymbolicLu::try_new(symbolic).map_err(|e| LinearSolveError::Symbolic(format!("{e:?}")))?)
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
                        .map_err(|e| LinearSolveError::NotPositiveDefinite(format!("{e:?}")))?,
                );
            }
            LinearSolverKind::Lu => {
                let sym = self.symbolic_lu.clone().expect("symbolic factorisation present");
                self.lu = Some(
                    Lu::try_new_with_symbolic(sym, mat).map_err(|e| LinearSolveError::Singular(format!("{e:?}")))?,
                );
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
    }
}
