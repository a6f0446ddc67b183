//! Block compressed-row matrices: a `d × d` block (row-major) per coupled node pair, the
//! column nodes of each row ascending, indexed by `u32`. This is the storage of the
//! iterative solver's operators (docs/theory.md §19): one index per block instead of one
//! per scalar, and a row-parallel product `y = A x` in which each row's sum runs in a fixed
//! order, so the result does not depend on the number of threads.

use crate::BlockPattern;
use rayon::prelude::*;

/// Rows below this many are not worth a task of their own.
const MIN_ROWS_PER_TASK: usize = 256;

/// A block compressed-row matrix. See the module docs.
#[derive(Debug, Clone, Default)]
pub struct BlockMatrix {
    d: usize,
    row_ptr: Vec<usize>,
    cols: Vec<u32>,
    values: Vec<f64>,
}

impl BlockMatrix {
    /// An all-zero matrix with `d × d` blocks on the node graph `rows` (each row's column
    /// nodes ascending and below `rows.len()`).
    pub fn with_structure(d: usize, rows: &[Vec<u32>]) -> Self {
        assert!(d >= 1, "a block has at least one dof a node");
        let mut row_ptr = Vec::with_capacity(rows.len() + 1);
        row_ptr.push(0);
        for r in rows {
            debug_assert!(r.windows(2).all(|w| w[0] < w[1]), "row columns must ascend");
            assert!(r.iter().all(|&c| (c as usize) < rows.len()), "column node out of range");
            row_ptr.push(row_ptr.last().unwrap() + r.len());
        }
        let cols = rows.concat();
        let values = vec![0.0; cols.len() * d * d];
        Self { d, row_ptr, cols, values }
    }

    /// The structure of `pattern` (its node graph) with zero values.
    pub fn structure_of(pattern: &BlockPattern) -> Self {
        let rows: Vec<Vec<u32>> = (0..pattern.num_nodes()).map(|j| pattern.neighbours(j).to_vec()).collect();
        Self::with_structure(pattern.dofs_per_node(), &rows)
    }

    pub fn block_size(&self) -> usize {
        self.d
    }

    pub fn num_nodes(&self) -> usize {
        self.row_ptr.len() - 1
    }

    pub fn num_dofs(&self) -> usize {
        self.num_nodes() * self.d
    }

    pub fn num_blocks(&self) -> usize {
        self.cols.len()
    }

    /// Whether this matrix has the node graph of `pattern`.
    pub fn has_structure_of(&self, pattern: &BlockPattern) -> bool {
        self.d == pattern.dofs_per_node()
            && self.num_nodes() == pattern.num_nodes()
            && (0..self.num_nodes()).all(|i| self.row_cols(i) == pattern.neighbours(i))
    }

    /// All values, row after row.
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Add the d×d `block` (row-major) coupling node `i` (rows) to node `j` (columns),
    /// eliminating constrained dofs as assembly does. The pair must be coupled.
    pub fn add_block(&mut self, constrained: &[bool], i: usize, j: usize, block: &[f64]) {
        let d = self.d;
        let q = self
            .row_cols(i)
            .binary_search(&(j as u32))
            .unwrap_or_else(|_| panic!("add_block: nodes {i} and {j} are not coupled"));
        let start = (self.row_ptr[i] + q) * d * d;
        for r in 0..d {
            for k in 0..d {
                if (i == j && r == k) || !(constrained[i * d + r] || constrained[j * d + k]) {
                    self.values[start + r * d + k] += block[r * d + k];
                }
            }
        }
    }

    /// Block (i, j), row-major, if the nodes are coupled.
    pub fn block_mut(&mut self, i: usize, j: usize) -> Option<&mut [f64]> {
        let dd = self.d * self.d;
        let q = self.row_cols(i).binary_search(&(j as u32)).ok()?;
        let start = (self.row_ptr[i] + q) * dd;
        Some(&mut self.values[start..start + dd])
    }

    /// Entry (i·d + r, j·d + k), zero where the nodes are not coupled.
    pub fn entry(&self, i: usize, r: usize, j: usize, k: usize) -> f64 {
        let d = self.d;
        match self.row_cols(i).binary_search(&(j as u32)) {
            Ok(q) => self.row_values(i)[q * d * d + r * d + k],
            Err(_) => 0.0,
        }
    }

    /// The values in the compressed-column layout of `pattern` (whose node graph this
    /// matrix has), for a factorisation.
    pub fn to_columns(&self, pattern: &BlockPattern) -> Vec<f64> {
        let d = self.d;
        assert!(self.has_structure_of(pattern), "to_columns: another node graph");
        let mut values = vec![0.0; pattern.nnz()];
        let mut chunks: Vec<&mut [f64]> = Vec::with_capacity(self.num_nodes());
        let mut rest: &mut [f64] = &mut values;
        for j in 0..self.num_nodes() {
            let (head, tail) = rest.split_at_mut(pattern.neighbours(j).len() * d * d);
            chunks.push(head);
            rest = tail;
        }
        chunks.into_par_iter().enumerate().with_min_len(MIN_ROWS_PER_TASK).for_each(|(j, out)| {
            let nb = pattern.neighbours(j);
            for k in 0..d {
                for (q, &i) in nb.iter().enumerate() {
                    for r in 0..d {
                        out[k * nb.len() * d + q * d + r] = self.entry(i as usize, r, j, k);
                    }
                }
            }
        });
        values
    }

    /// Largest |A_ij − A_ji| relative to the largest |A_ij|: zero for a symmetric matrix.
    pub fn asymmetry(&self) -> f64 {
        let d = self.d;
        let (mut max_diff, mut max_abs) = (0.0f64, 0.0f64);
        for i in 0..self.num_nodes() {
            for &j in self.row_cols(i) {
                for r in 0..d {
                    for k in 0..d {
                        let a = self.entry(i, r, j as usize, k);
                        max_diff = max_diff.max((a - self.entry(j as usize, k, i, r)).abs());
                        max_abs = max_abs.max(a.abs());
                    }
                }
            }
        }
        if max_abs > 0.0 {
            max_diff / max_abs
        } else {
            0.0
        }
    }

    /// Bytes held by the values and indices.
    pub fn bytes(&self) -> usize {
        self.values.len() * 8 + self.cols.len() * 4 + self.row_ptr.len() * 8
    }

    /// Column nodes of node row `i`.
    pub fn row_cols(&self, i: usize) -> &[u32] {
        &self.cols[self.row_ptr[i]..self.row_ptr[i + 1]]
    }

    /// Blocks of node row `i`, `d²` values each, in the order of `row_cols(i)`.
    pub fn row_values(&self, i: usize) -> &[f64] {
        let dd = self.d * self.d;
        &self.values[self.row_ptr[i] * dd..self.row_ptr[i + 1] * dd]
    }

    /// The diagonal block of row `i` (row-major), zero if the row has none; blocks of up to
    /// 3 dofs (the multigrid smoother's; `IterativeSolver` refuses larger ones).
    pub fn diagonal_block(&self, i: usize) -> [f64; 9] {
        assert!(self.d <= 3, "diagonal_block: blocks of up to 3 dofs");
        let dd = self.d * self.d;
        let mut out = [0.0; 9];
        if let Ok(q) = self.row_cols(i).binary_search(&(i as u32)) {
            out[..dd].copy_from_slice(&self.row_values(i)[q * dd..(q + 1) * dd]);
        }
        out
    }

    /// Mutable rows, one `(row, columns, blocks)` per node, for filling in parallel.
    pub fn rows_mut(&mut self) -> impl IndexedParallelIterator<Item = (usize, &[u32], &mut [f64])> + '_ {
        let dd = self.d * self.d;
        let mut chunks: Vec<&mut [f64]> = Vec::with_capacity(self.num_nodes());
        let mut rest: &mut [f64] = &mut self.values;
        for w in self.row_ptr.windows(2) {
            let (head, tail) = rest.split_at_mut((w[1] - w[0]) * dd);
            chunks.push(head);
            rest = tail;
        }
        let (row_ptr, cols) = (&self.row_ptr, &self.cols);
        chunks.into_par_iter().enumerate().map(move |(i, v)| (i, &cols[row_ptr[i]..row_ptr[i + 1]], v))
    }

    /// Copy the values of a matrix assembled on `pattern` (whose node graph this matrix
    /// has): the pattern stores columns, this matrix rows.
    pub fn copy_from_pattern(&mut self, pattern: &BlockPattern, values: &[f64]) {
        let d = self.d;
        assert!(self.has_structure_of(pattern), "copy_from_pattern: another node graph");
        self.rows_mut().with_min_len(MIN_ROWS_PER_TASK).for_each(|(i, cols, out)| {
            for (p, &j) in cols.iter().enumerate() {
                for r in 0..d {
                    for k in 0..d {
                        out[p * d * d + r * d + k] = pattern.entry(values, i, r, j as usize, k);
                    }
                }
            }
        });
    }

    /// `y = A x`, each row summed in column order (deterministic). Blocks of 1–3 dofs run
    /// with the block size known to the compiler (the Krylov solvers' hot loop); larger ones
    /// sum the same way in place.
    pub fn apply(&self, x: &[f64], y: &mut [f64]) {
        assert_eq!(x.len(), self.num_dofs(), "apply: x has one value per dof");
        assert_eq!(y.len(), self.num_dofs(), "apply: y has one value per dof");
        match self.d {
            1 => self.apply_blocks_of::<1>(x, y),
            2 => self.apply_blocks_of::<2>(x, y),
            3 => self.apply_blocks_of::<3>(x, y),
            d => y.par_chunks_mut(d).with_min_len(MIN_ROWS_PER_TASK).enumerate().for_each(|(i, yi)| {
                yi.iter_mut().for_each(|v| *v = 0.0);
                for (b, &j) in self.row_values(i).chunks_exact(d * d).zip(self.row_cols(i)) {
                    let xj = &x[j as usize * d..j as usize * d + d];
                    for r in 0..d {
                        for k in 0..d {
                            yi[r] += b[r * d + k] * xj[k];
                        }
                    }
                }
            }),
        }
    }

    /// [`BlockMatrix::apply`] for blocks of `N` dofs.
    fn apply_blocks_of<const N: usize>(&self, x: &[f64], y: &mut [f64]) {
        y.par_chunks_mut(N).with_min_len(MIN_ROWS_PER_TASK).enumerate().for_each(|(i, yi)| {
            let mut acc = [0.0; N];
            for (b, &j) in self.row_values(i).chunks_exact(N * N).zip(self.row_cols(i)) {
                let xj = &x[j as usize * N..j as usize * N + N];
                for r in 0..N {
                    for k in 0..N {
                        acc[r] += b[r * N + k] * xj[k];
                    }
                }
            }
            yi.copy_from_slice(&acc);
        });
    }

    /// `r = b − A x`.
    pub fn residual(&self, b: &[f64], x: &[f64], r: &mut [f64]) {
        self.apply(x, r);
        r.par_iter_mut().zip(b.par_iter()).with_min_len(MIN_ROWS_PER_TASK * 3).for_each(|(ri, bi)| *ri = bi - *ri);
    }

    /// The matrix as dense rows (for the coarsest level and for tests).
    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let d = self.d;
        let n = self.num_dofs();
        let mut a = vec![vec![0.0; n]; n];
        for i in 0..self.num_nodes() {
            for (b, &j) in self.row_values(i).chunks_exact(d * d).zip(self.row_cols(i)) {
                for r in 0..d {
                    for k in 0..d {
                        a[i * d + r][j as usize * d + k] = b[r * d + k];
                    }
                }
            }
        }
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::tests::assemble_chain;

    #[test]
    fn rows_copied_from_a_pattern_give_its_product() {
        let fixed = [true, true, false, false, false, false, false, false, false, false];
        let (p, mut v) = assemble_chain(4, 2, &fixed);
        // A non-symmetric block, so that a transposed copy would show.
        p.add_block(&mut v, &fixed, 2, 1, &[1.0, 2.0, 3.0, 4.0]);
        let mut m = BlockMatrix::structure_of(&p);
        m.copy_from_pattern(&p, &v);
        let x: Vec<f64> = (0..10).map(|i| 1.0 + i as f64 * 0.37).collect();
        let (mut y, mut z) = (vec![0.0; 10], vec![0.0; 10]);
        m.apply(&x, &mut y);
        p.mul_vec(&v, &x, &mut z);
        assert_eq!(y, z);
        let mut r = vec![0.0; 10];
        m.residual(&z, &x, &mut r);
        assert!(r.iter().all(|&v| v == 0.0));
    }
}
