//! Block sparsity pattern of a nodal system and deterministic parallel assembly into it.
//!
//! "Elements" are anything that couples a set of nodes: in MPM, a material point couples
//! the nodes its basis touches. The pattern is the node–node coupling graph with a dense
//! `d × d` block per coupled pair. A matrix on it is stored in one of two layouts
//! ([`SystemMatrix`](crate::SystemMatrix)): compressed columns over degrees of freedom
//! (dof = node·d + component, the columns of one node contiguous), which faer's
//! factorisations read, or block compressed rows ([`BlockMatrix`]), which the Krylov
//! solvers read. The scalar column structure is built only when a factorisation asks
//! for it: at 3 × 3 blocks its row indices take as much memory as the values.
//!
//! Assembly *gathers*: each node's column (or row) is owned by one task, which adds the
//! blocks of the elements touching it in ascending element order. No two tasks write the
//! same value and the summation order is fixed, so the result is bitwise identical for any
//! number of threads (docs/theory.md §7), and the same in both layouts: block (i, j) sums
//! the elements shared by i and j in ascending order either way.

use crate::BlockMatrix;
use rayon::prelude::*;
use std::sync::OnceLock;

/// The most dofs a node may carry (the stack buffer of an element block in assembly holds
/// this many squared): five bodies' 3D motion and a pore pressure.
pub const MAX_DOFS_PER_NODE: usize = 16;

/// The coupling structure the pattern is built from.
pub trait Couplings: Sync {
    fn num_nodes(&self) -> usize;
    /// (element, local slot of the node in the element) for every element touching `node`,
    /// ascending in element.
    fn elements_of(&self, node: usize) -> &[(u32, u32)];
    /// Nodes of `element`, ascending.
    fn nodes_of(&self, element: usize) -> &[u32];
}

/// Node-block compressed-column sparsity pattern. See the module docs.
#[derive(Debug, Clone, Default)]
pub struct BlockPattern {
    dofs_per_node: usize,
    nbr_offsets: Vec<usize>,
    nbrs: Vec<u32>,
    /// The scalar compressed-column structure (column pointers, row indices), built on
    /// first use.
    scalar: OnceLock<(Vec<usize>, Vec<usize>)>,
    generation: u64,
}

impl BlockPattern {
    /// An empty pattern of `dofs_per_node` dofs at every node (1 to
    /// [`MAX_DOFS_PER_NODE`]: a displacement of 1–3 components, the fields of several
    /// bodies, a pore pressure).
    pub fn new(dofs_per_node: usize) -> Self {
        assert!(
            (1..=MAX_DOFS_PER_NODE).contains(&dofs_per_node),
            "a node carries 1 to {MAX_DOFS_PER_NODE} dofs, not {dofs_per_node}"
        );
        Self { dofs_per_node, ..Default::default() }
    }

    pub fn dofs_per_node(&self) -> usize {
        self.dofs_per_node
    }

    pub fn num_nodes(&self) -> usize {
        self.nbr_offsets.len().saturating_sub(1)
    }

    pub fn num_dofs(&self) -> usize {
        self.num_nodes() * self.dofs_per_node
    }

    /// Scalar non-zeros: `d²` per coupled node pair.
    pub fn nnz(&self) -> usize {
        self.nbrs.len() * self.dofs_per_node * self.dofs_per_node
    }

    /// Coupled node pairs (blocks).
    pub fn num_blocks(&self) -> usize {
        self.nbrs.len()
    }

    /// Column pointers of the scalar compressed-column structure.
    pub fn col_ptr(&self) -> &[usize] {
        &self.scalar_structure().0
    }

    /// Row indices of the scalar compressed-column structure.
    pub fn row_idx(&self) -> &[usize] {
        &self.scalar_structure().1
    }

    /// The scalar compressed-column structure, built on first use.
    fn scalar_structure(&self) -> &(Vec<usize>, Vec<usize>) {
        self.scalar.get_or_init(|| {
            let d = self.dofs_per_node;
            let mut col_ptr = Vec::with_capacity(self.num_dofs() + 1);
            let mut row_idx = Vec::with_capacity(self.nnz());
            col_ptr.push(0);
            for j in 0..self.num_nodes() {
                for _k in 0..d {
                    for &i in self.neighbours(j) {
                        row_idx.extend((0..d).map(|c| i as usize * d + c));
                    }
                    col_ptr.push(row_idx.len());
                }
            }
            (col_ptr, row_idx)
        })
    }

    /// Where node `j`'s columns start in the compressed-column values.
    fn column_start(&self, j: usize) -> usize {
        self.nbr_offsets[j] * self.dofs_per_node * self.dofs_per_node
    }

    /// Changes whenever `update` finds a different structure: a linear solver keeps its
    /// symbolic factorisation while this stays the same.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Nodes coupled to `node` (itself included), ascending.
    pub fn neighbours(&self, node: usize) -> &[u32] {
        &self.nbrs[self.nbr_offsets[node]..self.nbr_offsets[node + 1]]
    }

    /// Rebuild the pattern for `couplings`. Returns true when the structure changed (and
    /// the generation advanced), false when it is the same as before and nothing was
    /// rebuilt.
    pub fn update<C: Couplings>(&mut self, couplings: &C) -> bool {
        self.update_with(couplings, &[])
    }

    /// As [`update`](Self::update), with couplings beyond the elements': `extra[node]` lists
    /// nodes tied to `node` by something else (the faces of a ghost penalty); an empty
    /// slice adds none.
    pub fn update_with<C: Couplings>(&mut self, couplings: &C, extra: &[Vec<u32>]) -> bool {
        let n = couplings.num_nodes();
        let lists: Vec<Vec<u32>> = (0..n)
            .into_par_iter()
            .map(|j| {
                let mut v: Vec<u32> = couplings
                    .elements_of(j)
                    .iter()
                    .flat_map(|&(e, _)| couplings.nodes_of(e as usize).iter().copied())
                    .chain(extra.get(j).into_iter().flatten().copied())
                    .collect();
                v.sort_unstable();
                v.dedup();
                v
            })
            .collect();
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0);
        for l in &lists {
            offsets.push(offsets.last().unwrap() + l.len());
        }
        let same =
            offsets == self.nbr_offsets && lists.iter().enumerate().all(|(j, l)| l.as_slice() == self.neighbours(j));
        if same {
            return false;
        }
        self.nbr_offsets = offsets;
        self.nbrs = lists.concat();
        self.scalar = OnceLock::new();
        self.generation += 1;
        true
    }

    /// For every node `j` in parallel, with `out` the values `chunk(j)` long that
    /// `values` holds from `start(j)`: `visit(j, out, e, slot_j, i, q, slot_i)` for each
    /// element `e` touching `j` (ascending) and each node `i` of it, `q` the place of `i`
    /// among `j`'s neighbours. The one gather loop of both layouts.
    fn gather<C, F>(&self, couplings: &C, values: &mut [f64], visit: F)
    where
        C: Couplings,
        F: Fn(usize, &mut [f64], usize, usize, usize, usize, usize) + Sync,
    {
        let dd = self.dofs_per_node * self.dofs_per_node;
        let mut chunks: Vec<&mut [f64]> = Vec::with_capacity(self.num_nodes());
        let mut rest: &mut [f64] = values;
        for j in 0..self.num_nodes() {
            let (head, tail) = rest.split_at_mut(self.neighbours(j).len() * dd);
            chunks.push(head);
            rest = tail;
        }
        chunks.into_par_iter().enumerate().for_each(|(j, out)| {
            let nb = self.neighbours(j);
            for &(e, b) in couplings.elements_of(j) {
                let nodes = couplings.nodes_of(e as usize);
                let mut q = 0;
                for (a, &i) in nodes.iter().enumerate() {
                    while nb[q] != i {
                        q += 1;
                    }
                    visit(j, out, e as usize, b as usize, i as usize, q, a);
                }
            }
        });
    }

    /// Assemble a matrix with this pattern into `values` (resized to `nnz`), in the
    /// compressed-column layout.
    ///
    /// `block(element, a, b, out)` adds the d×d block coupling local node `a` (rows) and
    /// local node `b` (columns) of `element` into `out` (row-major, `out[i*d + k]`).
    /// Dofs flagged in `constrained` are eliminated: their rows and columns are zero but
    /// for the diagonal, which keeps its assembled value so the system stays well scaled.
    pub fn assemble<C, F>(&self, couplings: &C, constrained: &[bool], values: &mut Vec<f64>, block: F)
    where
        C: Couplings,
        F: Fn(usize, usize, usize, &mut [f64]) + Sync,
    {
        match self.dofs_per_node {
            1..=3 => self.assemble_columns::<9, _, _>(couplings, constrained, values, block),
            4..=8 => self.assemble_columns::<64, _, _>(couplings, constrained, values, block),
            _ => self.assemble_columns::<{ MAX_DOFS_PER_NODE * MAX_DOFS_PER_NODE }, _, _>(
                couplings,
                constrained,
                values,
                block,
            ),
        }
    }

    /// [`BlockPattern::assemble`] with each element block on the stack, in `N` ≥ d² values:
    /// the smallest that fits, since the buffer is zeroed for every block.
    fn assemble_columns<const N: usize, C, F>(
        &self,
        couplings: &C,
        constrained: &[bool],
        values: &mut Vec<f64>,
        block: F,
    ) where
        C: Couplings,
        F: Fn(usize, usize, usize, &mut [f64]) + Sync,
    {
        let d = self.dofs_per_node;
        values.clear();
        values.resize(self.nnz(), 0.0);
        self.gather(couplings, values, |j, out, e, b, i, q, a| {
            let col_len = self.neighbours(j).len() * d;
            let mut buf = [0.0f64; N];
            block(e, a, b, &mut buf[..d * d]);
            for k in 0..d {
                for r in 0..d {
                    if kept(constrained, d, i, r, j, k) {
                        out[k * col_len + q * d + r] += buf[r * d + k];
                    }
                }
            }
        });
    }

    /// As [`assemble`](Self::assemble), into the block rows of `matrix` (given this
    /// pattern's structure if it has another): node `j`'s task fills row `j`.
    pub fn assemble_rows<C, F>(&self, couplings: &C, constrained: &[bool], matrix: &mut BlockMatrix, block: F)
    where
        C: Couplings,
        F: Fn(usize, usize, usize, &mut [f64]) + Sync,
    {
        if !matrix.has_structure_of(self) {
            *matrix = BlockMatrix::structure_of(self);
        }
        match self.dofs_per_node {
            1..=3 => self.assemble_block_rows::<9, _, _>(couplings, constrained, matrix, block),
            4..=8 => self.assemble_block_rows::<64, _, _>(couplings, constrained, matrix, block),
            _ => self.assemble_block_rows::<{ MAX_DOFS_PER_NODE * MAX_DOFS_PER_NODE }, _, _>(
                couplings,
                constrained,
                matrix,
                block,
            ),
        }
    }

    /// [`BlockPattern::assemble_rows`] with each element block on the stack (as
    /// [`BlockPattern::assemble_columns`]).
    fn assemble_block_rows<const N: usize, C, F>(
        &self,
        couplings: &C,
        constrained: &[bool],
        matrix: &mut BlockMatrix,
        block: F,
    ) where
        C: Couplings,
        F: Fn(usize, usize, usize, &mut [f64]) + Sync,
    {
        let d = self.dofs_per_node;
        let values = matrix.values_mut();
        values.iter_mut().for_each(|v| *v = 0.0);
        self.gather(couplings, values, |j, out, e, b, i, q, a| {
            let mut buf = [0.0f64; N];
            // Block (j, i): node j's slot gives the rows.
            block(e, b, a, &mut buf[..d * d]);
            for r in 0..d {
                for k in 0..d {
                    if kept(constrained, d, j, r, i, k) {
                        out[q * d * d + r * d + k] += buf[r * d + k];
                    }
                }
            }
        });
    }

    /// Add the d×d `block` (row-major) coupling node `i` (rows) to node `j` (columns) into
    /// `values`, eliminating constrained dofs as [`assemble`](Self::assemble) does. The pair
    /// must be in the pattern. Sequential: callers adding many blocks do so in a fixed order.
    pub fn add_block(&self, values: &mut [f64], constrained: &[bool], i: usize, j: usize, block: &[f64]) {
        let d = self.dofs_per_node;
        let nb = self.neighbours(j);
        let q = nb
            .binary_search(&(i as u32))
            .unwrap_or_else(|_| panic!("add_block: nodes {i} and {j} are not coupled in the pattern"));
        let col_len = nb.len() * d;
        let start = self.column_start(j);
        for k in 0..d {
            for r in 0..d {
                if kept(constrained, d, i, r, j, k) {
                    values[start + k * col_len + q * d + r] += block[r * d + k];
                }
            }
        }
    }

    /// Where block (i, j) lies in the compressed-column values: entry (r, k) of the block is
    /// at `start + k · stride + r`; `None` where the nodes are not coupled.
    pub fn block_position(&self, i: usize, j: usize) -> Option<(usize, usize)> {
        let nb = self.neighbours(j);
        let q = nb.binary_search(&(i as u32)).ok()?;
        Some((self.column_start(j) + q * self.dofs_per_node, nb.len() * self.dofs_per_node))
    }

    /// Entry (i·d + r, j·d + k) of the compressed-column `values`.
    pub fn entry(&self, values: &[f64], i: usize, r: usize, j: usize, k: usize) -> f64 {
        let d = self.dofs_per_node;
        let nb = self.neighbours(j);
        match nb.binary_search(&(i as u32)) {
            Ok(q) => values[self.column_start(j) + k * nb.len() * d + q * d + r],
            Err(_) => 0.0,
        }
    }

    /// `y = A x` for a matrix with this pattern.
    pub fn mul_vec(&self, values: &[f64], x: &[f64], y: &mut [f64]) {
        assert_eq!(x.len(), self.num_dofs(), "mul_vec: x has one value per dof");
        let (col_ptr, row_idx) = self.scalar_structure();
        y.iter_mut().for_each(|v| *v = 0.0);
        for (c, xc) in x.iter().enumerate() {
            for idx in col_ptr[c]..col_ptr[c + 1] {
                y[row_idx[idx]] += values[idx] * xc;
            }
        }
    }

    /// Largest |A_ij − A_ji| relative to the largest |A_ij|: zero for a symmetric matrix.
    pub fn asymmetry(&self, values: &[f64]) -> f64 {
        let d = self.dofs_per_node;
        let mut max_diff: f64 = 0.0;
        let mut max_abs: f64 = 0.0;
        for j in 0..self.num_nodes() {
            let nb = self.neighbours(j);
            for (q, &i) in nb.iter().enumerate() {
                let i = i as usize;
                // position of j among the neighbours of i (the pattern is symmetric)
                let p = self.neighbours(i).binary_search(&(j as u32)).expect("symmetric pattern");
                let len_j = nb.len() * d;
                let len_i = self.neighbours(i).len() * d;
                for k in 0..d {
                    for r in 0..d {
                        let a = values[self.column_start(j) + k * len_j + q * d + r];
                        let at = values[self.column_start(i) + r * len_i + p * d + k];
                        max_diff = max_diff.max((a - at).abs());
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
}

/// Whether entry (i·d + r, j·d + k) survives the elimination of the constrained dofs: a
/// constrained row or column keeps only its diagonal.
#[inline]
fn kept(constrained: &[bool], d: usize, i: usize, r: usize, j: usize, k: usize) -> bool {
    (i == j && r == k) || !(constrained[i * d + r] || constrained[j * d + k])
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A 1D chain of two-node elements: nodes 0–1–2–3.
    pub struct Chain {
        pub elems: Vec<[u32; 2]>,
        pub node_elems: Vec<Vec<(u32, u32)>>,
    }

    impl Chain {
        pub fn new(n_elems: usize) -> Self {
            let elems: Vec<[u32; 2]> = (0..n_elems as u32).map(|e| [e, e + 1]).collect();
            let mut node_elems = vec![Vec::new(); n_elems + 1];
            for (e, nodes) in elems.iter().enumerate() {
                for (a, &n) in nodes.iter().enumerate() {
                    node_elems[n as usize].push((e as u32, a as u32));
                }
            }
            Self { elems, node_elems }
        }
    }

    impl Couplings for Chain {
        fn num_nodes(&self) -> usize {
            self.node_elems.len()
        }
        fn elements_of(&self, node: usize) -> &[(u32, u32)] {
            &self.node_elems[node]
        }
        fn nodes_of(&self, element: usize) -> &[u32] {
            &self.elems[element]
        }
    }

    /// 1D bar stiffness k [1 -1; -1 1] per element, as a dense matrix for comparison.
    pub fn assemble_chain(n: usize, d: usize, constrained: &[bool]) -> (BlockPattern, Vec<f64>) {
        let chain = Chain::new(n);
        let mut p = BlockPattern::new(d);
        assert!(p.update(&chain));
        let mut v = Vec::new();
        p.assemble(&chain, constrained, &mut v, |e, a, b, out| {
            let k = 1.0 + e as f64;
            let s = if a == b { k } else { -k };
            for i in 0..d {
                out[i * d + i] += s * (i + 1) as f64;
            }
        });
        (p, v)
    }

    /// Extra couplings enter the pattern, and `add_block` adds into exactly the coupled
    /// pair (checked through A x), skipping constrained rows and columns off the diagonal.
    #[test]
    fn extra_couplings_and_added_blocks() {
        let chain = Chain::new(2); // nodes 0–1–2; 0 and 2 share no element
        let mut p = BlockPattern::new(1);
        p.update_with(&chain, &[vec![2], vec![], vec![0]]);
        assert_eq!(p.neighbours(0), &[0, 1, 2]);
        let mut values = vec![0.0; p.nnz()];
        p.add_block(&mut values, &[false; 3], 0, 2, &[3.0]);
        p.add_block(&mut values, &[false; 3], 2, 0, &[3.0]);
        let mut y = vec![0.0; 3];
        p.mul_vec(&values, &[1.0, 10.0, 100.0], &mut y);
        assert_eq!(y, vec![300.0, 0.0, 3.0]);
        let mut values = vec![0.0; p.nnz()];
        p.add_block(&mut values, &[true, false, false], 0, 2, &[3.0]);
        p.add_block(&mut values, &[true, false, false], 0, 0, &[5.0]);
        p.mul_vec(&values, &[1.0, 10.0, 100.0], &mut y);
        assert_eq!(y, vec![5.0, 0.0, 0.0]);
    }

    #[test]
    fn chain_assembles_the_tridiagonal_matrix() {
        let (p, v) = assemble_chain(3, 1, &[false; 4]);
        assert_eq!(p.col_ptr(), &[0, 2, 5, 8, 10]);
        assert_eq!(p.row_idx(), &[0, 1, 0, 1, 2, 1, 2, 3, 2, 3]);
        assert_eq!(v, vec![1.0, -1.0, -1.0, 3.0, -2.0, -2.0, 5.0, -3.0, -3.0, 3.0]);
        assert_eq!(p.asymmetry(&v), 0.0);
        let chain = Chain::new(3);
        let mut p2 = p.clone();
        assert!(!p2.update(&chain), "same structure must not advance the generation");
        assert_eq!(p2.generation(), p.generation());
    }

    #[test]
    fn constrained_dofs_are_eliminated_keeping_the_diagonal() {
        let (_, v) = assemble_chain(3, 1, &[true, false, false, false]);
        assert_eq!(v, vec![1.0, 0.0, 0.0, 3.0, -2.0, -2.0, 5.0, -3.0, -3.0, 3.0]);
    }

    #[test]
    fn blocks_and_matvec() {
        let (p, v) = assemble_chain(2, 2, &[false; 6]);
        let x = [1.0, 1.0, 2.0, 2.0, 4.0, 4.0];
        let mut y = [0.0; 6];
        p.mul_vec(&v, &x, &mut y);
        // component 0: K = [1 -1 0; -1 3 -2; 0 -2 2] (times 1), component 1: times 2
        assert_eq!(y, [-1.0, -2.0, -3.0, -6.0, 4.0, 8.0]);
    }
}
