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

    /// Read block (i, j) into `block` (row-major), change it by `change`, and write it back;
    /// nothing where the nodes are not coupled.
    fn with_block(
        &mut self,
        pattern: &BlockPattern,
        i: usize,
        j: usize,
        block: &mut [f64],
        change: impl FnOnce(&mut [f64]),
    ) {
        let d = pattern.dofs_per_node();
        match self {
            SystemMatrix::Columns(values) => {
                let Some((start, stride)) = pattern.block_position(i, j) else { return };
                for r in 0..d {
                    for k in 0..d {
                        block[r * d + k] = values[start + k * stride + r];
                    }
                }
                change(block);
                for r in 0..d {
                    for k in 0..d {
                        values[start + k * stride + r] = block[r * d + k];
                    }
                }
            }
            SystemMatrix::Rows(matrix) => {
                if let Some(b) = matrix.block_mut(i, j) {
                    change(b);
                }
            }
        }
    }

    /// Put the dofs of the nodes with a frame in their local frame: every block (i, j)
    /// becomes T_iᵀ B T_j, with `frame(node)` the node's d × d transform T (row-major,
    /// columns the local axes in global components; the identity for `None`). A local
    /// frame at the nodes of an inclined support, whose normal dof is then held
    /// ([`SystemMatrix::eliminate`]).
    pub fn transform_blocks<'a>(&mut self, pattern: &BlockPattern, frame: impl Fn(usize) -> Option<&'a [f64]>) {
        let d = pattern.dofs_per_node();
        let (mut block, mut tmp) = (vec![0.0; d * d], vec![0.0; d * d]);
        for j in 0..pattern.num_nodes() {
            for &i in pattern.neighbours(j) {
                let (ti, tj) = (frame(i as usize), frame(j));
                if ti.is_none() && tj.is_none() {
                    continue;
                }
                self.with_block(pattern, i as usize, j, &mut block, |b| {
                    // tmp = B T_j, then b = T_iᵀ tmp.
                    for r in 0..d {
                        for k in 0..d {
                            tmp[r * d + k] =
                                tj.map_or(b[r * d + k], |t| (0..d).map(|m| b[r * d + m] * t[m * d + k]).sum());
                        }
                    }
                    for r in 0..d {
                        for k in 0..d {
                            b[r * d + k] =
                                ti.map_or(tmp[r * d + k], |t| (0..d).map(|m| t[m * d + r] * tmp[m * d + k]).sum());
                        }
                    }
                });
            }
        }
    }

    /// Change block (i, j) (row-major) by `change`; nothing where the nodes are not coupled.
    pub fn change_block(&mut self, pattern: &BlockPattern, i: usize, j: usize, change: impl FnOnce(&mut [f64])) {
        let d = pattern.dofs_per_node();
        self.with_block(pattern, i, j, &mut vec![0.0; d * d], change);
    }

    /// Row operations on node `node`'s block row: for each `(target, source, factor)`,
    /// row `target` of every block (node, j) gains `factor` times row `source` (a
    /// frictional contact's tangential row taking μ s times its normal row).
    pub fn add_row_multiples(&mut self, pattern: &BlockPattern, node: usize, rows: &[(usize, usize, f64)]) {
        let d = pattern.dofs_per_node();
        let mut block = vec![0.0; d * d];
        for &j in pattern.neighbours(node) {
            self.with_block(pattern, node, j as usize, &mut block, |b| {
                for &(target, source, factor) in rows {
                    for k in 0..d {
                        b[target * d + k] += factor * b[source * d + k];
                    }
                }
            });
        }
    }

    /// Hold `dofs` (node · d + component): their rows and columns zero but for the
    /// diagonal, which keeps its value, as assembly does for the constrained dofs it is
    /// given.
    pub fn eliminate(&mut self, pattern: &BlockPattern, dofs: &[usize]) {
        let d = pattern.dofs_per_node();
        let mut block = vec![0.0; d * d];
        for &dof in dofs {
            let (f, c) = (dof / d, dof % d);
            for &j in pattern.neighbours(f) {
                let j = j as usize;
                self.with_block(pattern, f, j, &mut block, |b| {
                    (0..d).filter(|&k| !(j == f && k == c)).for_each(|k| b[c * d + k] = 0.0)
                });
                self.with_block(pattern, j, f, &mut block, |b| {
                    (0..d).filter(|&r| !(j == f && r == c)).for_each(|r| b[r * d + c] = 0.0)
                });
            }
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

    /// A local frame at one node (a rotation by 30° at node 1 of a chain of 2-dof nodes)
    /// gives Tᵀ K T in both layouts, T block-diagonal with the rotation at node 1, checked
    /// entry by entry against the dense product; holding its local normal dof then zeroes
    /// that row and column but for the diagonal.
    #[test]
    fn local_frames_transform_and_hold_in_both_layouts() {
        let chain = Chain::new(2);
        let mut pattern = BlockPattern::new(2);
        pattern.update(&chain);
        let (c, s) = (30f64.to_radians().cos(), 30f64.to_radians().sin());
        let rotation = [c, -s, s, c];
        let block = |e: usize, a: usize, b: usize, out: &mut [f64]| {
            let k = 1.0 + e as f64;
            let sign = if a == b { 1.0 } else { -1.0 };
            out.copy_from_slice(&[2.0 * k * sign, 0.5 * k, 0.5 * k, 3.0 * k * sign]);
        };
        let dense = |m: &SystemMatrix| -> Vec<Vec<f64>> {
            (0..6)
                .map(|col| {
                    let x: Vec<f64> = (0..6).map(|i| f64::from(u8::from(i == col))).collect();
                    let mut y = vec![0.0; 6];
                    m.mul_vec(&pattern, &x, &mut y);
                    y
                })
                .collect()
        };
        let mut t = vec![vec![0.0; 6]; 6];
        (0..6).for_each(|i| t[i][i] = 1.0);
        for r in 0..2 {
            for k in 0..2 {
                t[2 + r][2 + k] = rotation[r * 2 + k];
            }
        }
        for layout in [MatrixLayout::Columns, MatrixLayout::Rows] {
            let mut m = SystemMatrix::new(layout);
            m.assemble(&pattern, &chain, &[false; 6], block);
            let k = dense(&m);
            m.transform_blocks(&pattern, |node| (node == 1).then_some(&rotation[..]));
            let kt = dense(&m);
            for col in 0..6 {
                for row in 0..6 {
                    // (Tᵀ K T)[row][col], K[row][col] = k[col][row] (k holds columns).
                    let want: f64 = (0..6)
                        .flat_map(|a| (0..6).map(move |b| (a, b)))
                        .map(|(a, b)| t[a][row] * k[b][a] * t[b][col])
                        .sum();
                    assert!((kt[col][row] - want).abs() < 1e-14, "{layout:?} ({row}, {col})");
                }
            }
            m.eliminate(&pattern, &[2]);
            let held = dense(&m);
            for i in (0..6).filter(|&i| i != 2) {
                assert_eq!((held[2][i], held[i][2]), (0.0, 0.0), "{layout:?}: row and column of dof 2");
            }
            assert_eq!(held[2][2], kt[2][2], "the diagonal keeps its value");
        }
    }
}
