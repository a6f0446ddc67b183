//! The assembled matrix of a linear system in the layout its solver reads
//! (docs/theory.md §19): scalar compressed columns for faer's factorisations, block
//! compressed rows for the Krylov solvers. Assembling straight into the solver's layout
//! keeps one copy of the tangent: the rows of a 3D tangent hold 8 bytes per non-zero and
//! 4 per block, where the columns with their row indices and a row copy for the operator
//! held 24 per non-zero.

use crate::{BlockMatrix, BlockPattern, Couplings};
use std::borrow::Cow;

/// How a solver wants its matrix stored.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MatrixLayout {
    /// Scalar compressed columns on the pattern (faer's sparse factorisations).
    Columns,
    /// Block compressed rows (the Krylov solvers' operator).
    Rows,
}

/// A matrix on a [`BlockPattern`], in one of the two layouts. See the module docs.
#[derive(Debug, Clone)]
pub enum SystemMatrix {
    Columns(Vec<f64>),
    Rows(BlockMatrix),
}

impl SystemMatrix {
    /// An empty matrix in `layout`.
    pub fn new(layout: MatrixLayout) -> Self {
        match layout {
            MatrixLayout::Columns => SystemMatrix::Columns(Vec::new()),
            MatrixLayout::Rows => SystemMatrix::Rows(BlockMatrix::default()),
        }
    }

    pub fn layout(&self) -> MatrixLayout {
        match self {
            SystemMatrix::Columns(_) => MatrixLayout::Columns,
            SystemMatrix::Rows(_) => MatrixLayout::Rows,
        }
    }

    /// Assemble on `pattern` (see [`BlockPattern::assemble`]), replacing the values.
    pub fn assemble<C, F>(&mut self, pattern: &BlockPattern, couplings: &C, constrained: &[bool], block: F)
    where
        C: Couplings,
        F: Fn(usize, usize, usize, &mut [f64]) + Sync,
    {
        match self {
            SystemMatrix::Columns(values) => pattern.assemble(couplings, constrained, values, block),
            SystemMatrix::Rows(matrix) => pattern.assemble_rows(couplings, constrained, matrix, block),
        }
    }

    /// Add the d×d `block` (row-major) coupling node `i` (rows) to node `j` (columns),
    /// eliminating constrained dofs as assembly does.
    pub fn add_block(&mut self, pattern: &BlockPattern, constrained: &[bool], i: usize, j: usize, block: &[f64]) {
        match self {
            SystemMatrix::Columns(values) => pattern.add_block(values, constrained, i, j, block),
            SystemMatrix::Rows(matrix) => matrix.add_block(constrained, i, j, block),
        }
    }

    /// The values in the compressed-column layout of `pattern` (copied from rows).
    pub fn to_columns(&self, pattern: &BlockPattern) -> Cow<'_, [f64]> {
        match self {
            SystemMatrix::Columns(values) => Cow::Borrowed(values),
            SystemMatrix::Rows(matrix) => Cow::Owned(matrix.to_columns(pattern)),
        }
    }

    /// `y = A x`.
    pub fn mul_vec(&self, pattern: &BlockPattern, x: &[f64], y: &mut [f64]) {
        match self {
            SystemMatrix::Columns(values) => pattern.mul_vec(values, x, y),
            SystemMatrix::Rows(matrix) => matrix.apply(x, y),
        }
    }

    /// Largest |A_ij − A_ji| relative to the largest |A_ij|: zero for a symmetric matrix.
    pub fn asymmetry(&self, pattern: &BlockPattern) -> f64 {
        match self {
            SystemMatrix::Columns(values) => pattern.asymmetry(values),
            SystemMatrix::Rows(matrix) => matrix.asymmetry(),
        }
    }

    /// Bytes held by the values (and, in rows, their block indices).
    pub fn bytes(&self) -> usize {
        match self {
            SystemMatrix::Columns(values) => values.len() * 8,
            SystemMatrix::Rows(matrix) => matrix.bytes(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::tests::Chain;

    /// Both layouts assemble the same matrix, bit for bit, with constrained dofs eliminated
    /// alike, and added blocks land in the same entries.
    #[test]
    fn rows_and_columns_hold_the_same_matrix() {
        let chain = Chain::new(5);
        let mut pattern = BlockPattern::new(2);
        pattern.update(&chain);
        let constrained: Vec<bool> = (0..12).map(|dof| dof == 1 || dof == 7).collect();
        // A non-symmetric block, so a transposed layout would show.
        let block = |e: usize, a: usize, b: usize, out: &mut [f64]| {
            for (n, o) in out.iter_mut().enumerate() {
                *o += (1.0 + e as f64) * (1.0 + n as f64 * 0.3) * if a == b { 1.0 } else { -0.7 - a as f64 };
            }
        };
        let mut cols = SystemMatrix::new(MatrixLayout::Columns);
        let mut rows = SystemMatrix::new(MatrixLayout::Rows);
        for m in [&mut cols, &mut rows] {
            m.assemble(&pattern, &chain, &constrained, block);
            m.add_block(&pattern, &constrained, 4, 3, &[0.25, 0.5, 1.0, 2.0]);
        }
        assert_eq!(rows.to_columns(&pattern), cols.to_columns(&pattern));
        assert!(rows.asymmetry(&pattern) > 0.1);
        assert_eq!(rows.asymmetry(&pattern), cols.asymmetry(&pattern));
        let x: Vec<f64> = (0..12).map(|i| 1.0 + i as f64 * 0.37).collect();
        let (mut y, mut z) = (vec![0.0; 12], vec![0.0; 12]);
        rows.mul_vec(&pattern, &x, &mut y);
        cols.mul_vec(&pattern, &x, &mut z);
        for (a, b) in y.iter().zip(&z) {
            assert!((a - b).abs() <= 1e-14 * b.abs().max(1.0), "{y:?} against {z:?}");
        }
    }
}
