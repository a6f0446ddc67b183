//! Geometric multigrid on a structured node lattice (docs/theory.md §19): the V-cycle that
//! preconditions the Krylov solve of the tangent.
//!
//! - **Hierarchy.** The nodes carry integer lattice coordinates (the background grid's
//!   node indices). A coarse level keeps every other node per axis (2:1 agglomeration of
//!   cells); a fine node takes the multilinear interpolation of its coarse neighbours, the
//!   grid's own hat functions on the coarse spacing. Levels are added until at most
//!   `COARSEST_NODES` nodes remain.
//! - **Operators.** The coarse operators are Galerkin products `A_c = Pᵀ A P`. A prolongation
//!   row is zero on a constrained fine dof, so the coarse spaces never move a support; a
//!   coarse dof that reaches no free fine dof gets a unit diagonal.
//! - **Smoother.** Chebyshev polynomials of degree `SMOOTHER_DEGREE` in the block-Jacobi
//!   preconditioned operator `D⁻¹A` (`D` the nodal `d × d` diagonal blocks, which takes care
//!   of the scaling of nearly empty nodes and of stiffness contrasts), on the interval
//!   `[0.1, 1] λ̄`, λ̄ the largest absolute row sum of `D⁻¹A`, a bound on its spectral
//!   radius. A fixed polynomial on an interval that holds the spectrum is a symmetric,
//!   convergent smoother, so the V-cycle is a symmetric positive definite preconditioner
//!   for CG.
//! - **Coarsest level.** A dense LU with partial pivoting, on one thread: faer's default
//!   parallel LU gave results that depended on the thread count.
//!
//! The structure (lattices, transfers, coarse patterns) is built when the fine pattern's
//! generation changes; the values at every `set_values`. The fine operator is the caller's
//! (the assembled tangent, not a copy): `set_values` and `apply` borrow it. Every product
//! and transfer is row-parallel with sums in a fixed order: results do not depend on the
//! thread count.

use crate::{BlockMatrix, BlockPattern};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::{Conj, Mat, MatMut, Par};
use rayon::prelude::*;
use std::sync::Mutex;

/// Coarsening stops at this many nodes (the dense LU of 3 × 400 dofs is 11 MB).
const COARSEST_NODES: usize = 400;
/// Chebyshev degree of each pre- and post-smoothing.
const SMOOTHER_DEGREE: usize = 2;
/// The Chebyshev interval, as fractions of the bound on λ_max.
const CHEBYSHEV_INTERVAL: (f64, f64) = (0.1, 1.0);

/// Per node, its coarse parents (coarse node, interpolation weight).
type Parents = Vec<Vec<(u32, f64)>>;

/// Integer lattice coordinates of nodes (unused axes zero). See the module docs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct NodeLattice {
    coords: Vec<[u32; 3]>,
}

impl NodeLattice {
    pub fn new(coords: Vec<[u32; 3]>) -> Self {
        Self { coords }
    }

    pub fn len(&self) -> usize {
        self.coords.len()
    }

    pub fn is_empty(&self) -> bool {
        self.coords.is_empty()
    }

    /// The coordinates of `node`.
    pub fn coordinates(&self, node: usize) -> [u32; 3] {
        self.coords[node]
    }

    /// The coarse lattice — the nodes of this one at even coordinates, halved — and, per
    /// node of this one, its coarse parents with their interpolation weights, and per coarse
    /// node the node of this one it sits on.
    ///
    /// A coarse node exists only where a fine node does, so every column of P holds a 1 on
    /// a row no other column touches: P has full column rank and PᵀKP is positive definite
    /// with K. (Coarse nodes placed wherever a fine node had a parent can, at the edges of
    /// the material, share their only fine node: identical columns, a singular coarse
    /// operator.) Where a parent is
    /// missing (beyond the material), the weights of those present are scaled to sum to 1,
    /// so constants are still interpolated.
    fn coarsen(&self) -> (NodeLattice, Parents, Vec<u32>) {
        // Coarse nodes in lexicographic order, last axis slowest, as the grid numbers them.
        let key = |c: &[u32; 3]| [c[2], c[1], c[0]];
        let mut coarse: Vec<([u32; 3], u32)> = (self.coords.iter().enumerate())
            .filter(|(_, c)| c.iter().all(|x| x % 2 == 0))
            .map(|(f, c)| (key(&c.map(|x| x / 2)), f as u32))
            .collect();
        coarse.par_sort_unstable();
        let parents_of = |c: &[u32; 3]| -> Vec<(u32, f64)> {
            let mut out = vec![([0u32; 3], 1.0)];
            for (axis, &x) in c.iter().enumerate() {
                let options: &[(u32, f64)] =
                    if x % 2 == 0 { &[(x / 2, 1.0)] } else { &[(x / 2, 0.5), (x / 2 + 1, 0.5)] };
                out = out
                    .iter()
                    .flat_map(|(p, w)| {
                        options.iter().map(move |&(o, wo)| {
                            let mut q = *p;
                            q[axis] = o;
                            (q, w * wo)
                        })
                    })
                    .collect();
            }
            let present: Vec<(u32, f64)> = out
                .iter()
                .filter_map(|(q, w)| coarse.binary_search_by(|e| e.0.cmp(&key(q))).ok().map(|i| (i as u32, *w)))
                .collect();
            let total: f64 = present.iter().map(|p| p.1).sum();
            present.into_iter().map(|(i, w)| (i, w / total)).collect()
        };
        let parents = self.coords.par_iter().map(parents_of).collect();
        let own = coarse.iter().map(|e| e.1).collect();
        let coords = coarse.into_iter().map(|(k, _)| [k[2], k[1], k[0]]).collect();
        (NodeLattice { coords }, parents, own)
    }
}

/// The transfer between a level and the next coarser one: P by rows (parents of each fine
/// node) and by columns (children of each coarse node, ascending).
#[derive(Debug, Clone)]
struct Transfer {
    parents: Parents,
    children: Vec<Vec<(u32, f64)>>,
    /// The fine node each coarse node sits on.
    own: Vec<u32>,
}

impl Transfer {
    fn new(parents: Parents, own: Vec<u32>) -> Self {
        let mut children = vec![Vec::new(); own.len()];
        for (f, ps) in parents.iter().enumerate() {
            for &(c, w) in ps {
                children[c as usize].push((f as u32, w));
            }
        }
        Self { parents, children, own }
    }

    /// 1 where coarse dof (c, r) is kept: its own fine dof is free. A coarse function on a
    /// constrained node would move it.
    #[inline]
    fn coarse_free(&self, d: usize, free: &[f64], c: usize, r: usize) -> f64 {
        free[self.own[c] as usize * d + r]
    }

    /// The coarse operator's node graph: I ~ J when a child of I couples to a child of J.
    fn coarse_structure(&self, fine: &impl NodeGraph) -> Vec<Vec<u32>> {
        self.children
            .par_iter()
            .map(|kids| {
                let mut cols: Vec<u32> = kids
                    .iter()
                    .flat_map(|&(f, _)| fine.row_cols(f as usize))
                    .flat_map(|&g| self.parents[g as usize].iter().map(|&(c, _)| c))
                    .collect();
                cols.sort_unstable();
                cols.dedup();
                cols
            })
            .collect()
    }

    /// `coarse = Pᵀ A P`, P masked by `free` (1 on the free fine dofs, 0 on constrained
    /// ones) in its rows and, through the coarse nodes' own fine dofs, in its columns; a
    /// dropped coarse dof (zero diagonal) gets 1.
    fn galerkin(&self, fine: &BlockMatrix, free: &[f64], coarse: &mut BlockMatrix) {
        let d = fine.block_size();
        let dd = d * d;
        coarse.rows_mut().with_min_len(16).for_each(|(i, cols, out)| {
            out.iter_mut().for_each(|v| *v = 0.0);
            for &(f, w1) in &self.children[i] {
                let f = f as usize;
                let row: [f64; 3] = std::array::from_fn(|r| {
                    if r < d {
                        w1 * free[f * d + r] * self.coarse_free(d, free, i, r)
                    } else {
                        0.0
                    }
                });
                for (blk, &g) in fine.row_values(f).chunks_exact(dd).zip(fine.row_cols(f)) {
                    let g = g as usize;
                    for &(j, w2) in &self.parents[g] {
                        let q = cols.binary_search(&j).expect("coarse structure holds every coupling");
                        let o = &mut out[q * dd..(q + 1) * dd];
                        for k in 0..d {
                            let col = w2 * free[g * d + k] * self.coarse_free(d, free, j as usize, k);
                            for r in 0..d {
                                o[r * d + k] += row[r] * col * blk[r * d + k];
                            }
                        }
                    }
                }
            }
            let q = cols.binary_search(&(i as u32)).expect("every coarse node couples to itself");
            for r in 0..d {
                let diag = &mut out[q * dd + r * d + r];
                if *diag == 0.0 {
                    *diag = 1.0;
                }
            }
        });
    }

    /// `coarse = Pᵀ fine` (masked).
    fn restrict(&self, d: usize, free: &[f64], fine: &[f64], coarse: &mut [f64]) {
        coarse.par_chunks_mut(d).with_min_len(64).enumerate().for_each(|(i, out)| {
            out.iter_mut().for_each(|v| *v = 0.0);
            for &(f, w) in &self.children[i] {
                let f = f as usize;
                for r in 0..d {
                    out[r] += w * free[f * d + r] * fine[f * d + r];
                }
            }
            for (r, o) in out.iter_mut().enumerate() {
                *o *= self.coarse_free(d, free, i, r);
            }
        });
    }

    /// `fine += P coarse` (masked).
    fn prolong_add(&self, d: usize, free: &[f64], coarse: &[f64], fine: &mut [f64]) {
        fine.par_chunks_mut(d).with_min_len(256).enumerate().for_each(|(f, out)| {
            for &(c, w) in &self.parents[f] {
                for r in 0..d {
                    out[r] +=
                        w * free[f * d + r] * self.coarse_free(d, free, c as usize, r) * coarse[c as usize * d + r];
                }
            }
        });
    }
}

/// A node graph: the column nodes of each row.
trait NodeGraph: Sync {
    fn row_cols(&self, i: usize) -> &[u32];
}

impl NodeGraph for BlockMatrix {
    fn row_cols(&self, i: usize) -> &[u32] {
        BlockMatrix::row_cols(self, i)
    }
}

impl NodeGraph for BlockPattern {
    fn row_cols(&self, i: usize) -> &[u32] {
        self.neighbours(i)
    }
}

/// One level: its operator (empty on the finest, whose operator the caller holds),
/// block-Jacobi inverse, λ_max(D⁻¹A), and the transfer to the next coarser level (none on
/// the coarsest).
#[derive(Debug, Clone)]
struct Level {
    /// Dofs per node.
    d: usize,
    a: BlockMatrix,
    inv_diag: Vec<f64>,
    lambda_max: f64,
    /// Per dof of this level, 1 where the coarser level's prolongation reaches, 0 where a
    /// constraint holds it.
    free: Vec<f64>,
    transfer: Option<Transfer>,
}

/// Scratch vectors of one level's cycle.
#[derive(Debug, Clone, Default)]
struct Scratch {
    r: Vec<f64>,
    dir: Vec<f64>,
    tmp: Vec<f64>,
    bc: Vec<f64>,
    xc: Vec<f64>,
}

/// The multigrid hierarchy and its V-cycle. See the module docs.
pub struct Multigrid {
    levels: Vec<Level>,
    coarsest: Option<DenseLu>,
    generation: Option<u64>,
    scratch: Mutex<Vec<Scratch>>,
}

impl std::fmt::Debug for Multigrid {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Multigrid").field("levels", &self.level_sizes()).finish()
    }
}

impl Default for Multigrid {
    fn default() -> Self {
        Self::new()
    }
}

impl Multigrid {
    pub fn new() -> Self {
        Self { levels: Vec::new(), coarsest: None, generation: None, scratch: Mutex::new(Vec::new()) }
    }

    /// Nodes per level, finest first.
    pub fn level_sizes(&self) -> Vec<usize> {
        self.levels.iter().map(|l| l.free.len() / l.d.max(1)).collect()
    }

    /// Bytes held by the hierarchy (the coarse operators, smoothers and masks; the fine
    /// operator is the caller's).
    pub fn bytes(&self) -> usize {
        self.levels.iter().map(|l| l.a.bytes() + l.inv_diag.len() * 8 + l.free.len() * 8).sum()
    }

    /// The operator of level `l`, `fine` on the finest.
    fn operator<'a>(&'a self, l: usize, fine: &'a BlockMatrix) -> &'a BlockMatrix {
        if l == 0 {
            fine
        } else {
            &self.levels[l].a
        }
    }

    /// Build the structure for `pattern` on `lattice` when the pattern's generation
    /// changed; true if it was rebuilt.
    pub fn set_structure(&mut self, pattern: &BlockPattern, lattice: &NodeLattice) -> bool {
        if self.generation == Some(pattern.generation()) {
            return false;
        }
        assert_eq!(lattice.len(), pattern.num_nodes(), "one lattice coordinate per node");
        let d = pattern.dofs_per_node();
        let mut levels = Vec::new();
        // The finest operator is the caller's: its level holds an empty one.
        let mut a = BlockMatrix::default();
        let mut nodes = pattern.num_nodes();
        let mut lattice = lattice.clone();
        while nodes > COARSEST_NODES {
            let (coarse_lattice, parents, own) = lattice.coarsen();
            if coarse_lattice.len() >= nodes || coarse_lattice.is_empty() {
                break;
            }
            let transfer = Transfer::new(parents, own);
            let structure =
                if levels.is_empty() { transfer.coarse_structure(pattern) } else { transfer.coarse_structure(&a) };
            let coarse = BlockMatrix::with_structure(d, &structure);
            levels.push(Level::new(d, nodes, std::mem::replace(&mut a, coarse), Some(transfer)));
            nodes = coarse_lattice.len();
            lattice = coarse_lattice;
        }
        levels.push(Level::new(d, nodes, a, None));
        self.levels = levels;
        self.generation = Some(pattern.generation());
        let scratch = self.levels.windows(2).map(|w| Scratch::sized(w[0].free.len(), w[1].free.len())).collect();
        *self.scratch.get_mut().unwrap() = scratch;
        true
    }

    /// Recompute every level from the fine operator `fine` (assembled on the pattern of
    /// `set_structure`, with the dofs flagged in `constrained` eliminated).
    pub fn set_values(&mut self, fine: &BlockMatrix, constrained: &[bool]) -> Result<(), String> {
        assert!(self.generation.is_some(), "set_values before set_structure");
        assert_eq!(fine.num_dofs(), self.levels[0].free.len(), "set_values on a stale structure");
        self.levels[0].free = constrained.iter().map(|&c| if c { 0.0 } else { 1.0 }).collect();
        for l in 0..self.levels.len() {
            let (head, tail) = self.levels.split_at_mut(l + 1);
            let level = &mut head[l];
            let a = if l == 0 { fine } else { &level.a };
            let (inv_diag, lambda_max) = smoother_of(a);
            if let (Some(t), Some(next)) = (&level.transfer, tail.first_mut()) {
                t.galerkin(a, &level.free, &mut next.a);
                next.free = vec![1.0; next.a.num_dofs()];
            }
            (level.inv_diag, level.lambda_max) = (inv_diag, lambda_max);
        }
        let lu = DenseLu::new(self.operator(self.levels.len() - 1, fine));
        let mut check = vec![1.0; lu.dim()];
        lu.solve(&mut check);
        if check.iter().any(|v| !v.is_finite()) {
            return Err(format!("the coarsest operator ({} dofs) is singular", lu.dim()));
        }
        self.coarsest = Some(lu);
        Ok(())
    }

    /// One V-cycle from a zero guess: `x ≈ A⁻¹ b`, `fine` the operator of `set_values`.
    pub fn apply(&self, fine: &BlockMatrix, b: &[f64], x: &mut [f64]) {
        let mut scratch = self.scratch.lock().unwrap_or_else(|e| e.into_inner());
        self.cycle(0, fine, b, x, &mut scratch);
    }

    fn cycle(&self, l: usize, fine: &BlockMatrix, b: &[f64], x: &mut [f64], scratch: &mut [Scratch]) {
        let level = &self.levels[l];
        let Some(transfer) = &level.transfer else {
            x.copy_from_slice(b);
            self.coarsest.as_ref().expect("values set before a cycle").solve(x);
            return;
        };
        let (s, rest) = scratch.split_first_mut().expect("scratch per level");
        let a = self.operator(l, fine);
        x.iter_mut().for_each(|v| *v = 0.0);
        level.smooth(a, b, x, true, s);
        a.residual(b, x, &mut s.r);
        transfer.restrict(level.d, &level.free, &s.r, &mut s.bc);
        self.cycle(l + 1, fine, &s.bc, &mut s.xc, rest);
        transfer.prolong_add(level.d, &level.free, &s.xc, x);
        level.smooth(a, b, x, false, s);
    }
}

/// A dense LU factorisation with partial pivoting, computed and applied on one thread.
struct DenseLu {
    lu: Mat<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
}

impl DenseLu {
    fn new(a: &BlockMatrix) -> Self {
        let dense = a.to_dense();
        let n = dense.len();
        let mut lu = Mat::from_fn(n, n, |i, j| dense[i][j]);
        let (mut perm, mut perm_inv) = (vec![0usize; n], vec![0usize; n]);
        let req = factor::lu_in_place_scratch::<usize, f64>(n, n, Par::Seq, Default::default());
        factor::lu_in_place(
            lu.as_mut(),
            &mut perm,
            &mut perm_inv,
            Par::Seq,
            MemStack::new(&mut MemBuffer::new(req)),
            Default::default(),
        );
        Self { lu, perm, perm_inv }
    }

    fn dim(&self) -> usize {
        self.perm.len()
    }

    /// `x ← A⁻¹ x`.
    fn solve(&self, x: &mut [f64]) {
        let n = self.dim();
        let perm = PermRef::new_checked(&self.perm, &self.perm_inv, n);
        let rhs = MatMut::from_column_major_slice_mut(x, n, 1);
        let req = solve::solve_in_place_scratch::<usize, f64>(n, 1, Par::Seq);
        let lu = self.lu.as_ref();
        solve::solve_in_place_with_conj(lu, lu, perm, Conj::No, rhs, Par::Seq, MemStack::new(&mut MemBuffer::new(req)));
    }
}

impl Scratch {
    fn sized(fine: usize, coarse: usize) -> Self {
        Self {
            r: vec![0.0; fine],
            dir: vec![0.0; fine],
            tmp: vec![0.0; fine],
            bc: vec![0.0; coarse],
            xc: vec![0.0; coarse],
        }
    }
}

impl Level {
    /// A level of `nodes` nodes; `free` is sized (all free) until values come.
    fn new(d: usize, nodes: usize, a: BlockMatrix, transfer: Option<Transfer>) -> Self {
        Self { d, a, inv_diag: Vec::new(), lambda_max: 0.0, free: vec![1.0; nodes * d], transfer }
    }

    /// `out = D⁻¹ r`.
    fn jacobi(&self, r: &[f64], out: &mut [f64]) {
        let d = self.d;
        out.par_chunks_mut(d).with_min_len(256).enumerate().for_each(|(i, o)| {
            let inv = &self.inv_diag[i * d * d..(i + 1) * d * d];
            for a in 0..d {
                o[a] = (0..d).map(|b| inv[a * d + b] * r[i * d + b]).sum();
            }
        });
    }

    /// Chebyshev smoothing of `a x = b` (Saad, Iterative Methods, Alg. 12.1, with the
    /// block-Jacobi preconditioner); `zero` says `x` is zero on entry.
    fn smooth(&self, a: &BlockMatrix, b: &[f64], x: &mut [f64], zero: bool, s: &mut Scratch) {
        let (lo, hi) = (CHEBYSHEV_INTERVAL.0 * self.lambda_max, CHEBYSHEV_INTERVAL.1 * self.lambda_max);
        if hi <= 0.0 || !hi.is_finite() {
            return;
        }
        let (theta, delta) = ((hi + lo) / 2.0, (hi - lo) / 2.0);
        let sigma = theta / delta;
        let mut rho = 1.0 / sigma;
        if zero {
            s.r.copy_from_slice(b);
        } else {
            a.residual(b, x, &mut s.r);
        }
        self.jacobi(&s.r, &mut s.dir);
        s.dir.iter_mut().for_each(|v| *v /= theta);
        for k in 0..SMOOTHER_DEGREE {
            x.par_iter_mut().zip(s.dir.par_iter()).with_min_len(1024).for_each(|(xi, di)| *xi += di);
            if k + 1 == SMOOTHER_DEGREE {
                break;
            }
            a.apply(&s.dir, &mut s.tmp);
            s.r.par_iter_mut().zip(s.tmp.par_iter()).with_min_len(1024).for_each(|(ri, ti)| *ri -= ti);
            let rho_new = 1.0 / (2.0 * sigma - rho);
            self.jacobi(&s.r, &mut s.tmp);
            let (c1, c2) = (rho_new * rho, 2.0 * rho_new / delta);
            s.dir.par_iter_mut().zip(s.tmp.par_iter()).with_min_len(1024).for_each(|(di, ti)| *di = c1 * *di + c2 * ti);
            rho = rho_new;
        }
    }
}

/// The block-Jacobi inverse of `a` and the bound on λ_max(D⁻¹A) its smoother uses.
fn smoother_of(a: &BlockMatrix) -> (Vec<f64>, f64) {
    let d = a.block_size();
    let mut inv_diag = vec![0.0; a.num_nodes() * d * d];
    inv_diag.par_chunks_mut(d * d).enumerate().for_each(|(i, out)| invert_block(d, &a.diagonal_block(i), out));
    let lambda_max = estimate_lambda_max(a, &inv_diag);
    (inv_diag, lambda_max)
}

/// An upper bound of the spectral radius of D⁻¹A: its largest absolute row sum (every
/// induced norm bounds the spectral radius). Chebyshev smoothing is only safe with an
/// interval that reaches λ_max: a power-iteration estimate from below left the
/// preconditioner indefinite (CG broke down) unless run for some forty products.
fn estimate_lambda_max(a: &BlockMatrix, inv_diag: &[f64]) -> f64 {
    let d = a.block_size();
    let dd = d * d;
    (0..a.num_nodes())
        .into_par_iter()
        .with_min_len(256)
        .map(|i| {
            let inv = &inv_diag[i * dd..(i + 1) * dd];
            let mut sums = [0.0f64; 3];
            for blk in a.row_values(i).chunks_exact(dd) {
                for r in 0..d {
                    for k in 0..d {
                        let v: f64 = (0..d).map(|m| inv[r * d + m] * blk[m * d + k]).sum();
                        sums[r] += v.abs();
                    }
                }
            }
            sums[..d].iter().fold(0.0f64, |m, &v| m.max(v))
        })
        .reduce(|| 0.0, f64::max)
}

/// The inverse of a `d × d` block (row-major) by cofactors; a block too close to singular
/// for that falls back to the reciprocals of its non-zero diagonal.
fn invert_block(d: usize, m: &[f64; 9], out: &mut [f64]) {
    let a = |r: usize, c: usize| m[r * d + c];
    let scale = m[..d * d].iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let det = match d {
        1 => a(0, 0),
        2 => a(0, 0) * a(1, 1) - a(0, 1) * a(1, 0),
        _ => {
            a(0, 0) * (a(1, 1) * a(2, 2) - a(1, 2) * a(2, 1)) - a(0, 1) * (a(1, 0) * a(2, 2) - a(1, 2) * a(2, 0))
                + a(0, 2) * (a(1, 0) * a(2, 1) - a(1, 1) * a(2, 0))
        }
    };
    if scale == 0.0 || det.abs() <= 1e-12 * scale.powi(d as i32) {
        out.iter_mut().for_each(|v| *v = 0.0);
        for r in 0..d {
            let v = a(r, r);
            out[r * d + r] = if v != 0.0 { 1.0 / v } else { 0.0 };
        }
        return;
    }
    match d {
        1 => out[0] = 1.0 / det,
        2 => {
            out.copy_from_slice(&[a(1, 1) / det, -a(0, 1) / det, -a(1, 0) / det, a(0, 0) / det]);
        }
        _ => {
            for r in 0..3 {
                for c in 0..3 {
                    // inverse[r][c] = cofactor[c][r] / det
                    let (r1, r2) = ((c + 1) % 3, (c + 2) % 3);
                    let (c1, c2) = ((r + 1) % 3, (r + 2) % 3);
                    out[r * 3 + c] = (a(r1, c1) * a(r2, c2) - a(r1, c2) * a(r2, c1)) / det;
                }
            }
        }
    }
}

/// The dot product summed in index order.
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn three_by_three_blocks_invert() {
        let m = [4.0, 1.0, 0.5, 2.0, 5.0, 1.0, 0.0, 1.0, 3.0];
        let mut inv = [0.0; 9];
        invert_block(3, &m, &mut inv);
        for r in 0..3 {
            for c in 0..3 {
                let s: f64 = (0..3).map(|k| m[r * 3 + k] * inv[k * 3 + c]).sum();
                assert!((s - if r == c { 1.0 } else { 0.0 }).abs() < 1e-14, "{s}");
            }
        }
    }

    #[test]
    fn a_lattice_coarsens_to_every_other_node_with_hat_weights() {
        // Nodes 0..=4 on a line: coarse nodes 0, 1, 2 (fine 0, 2, 4); fine 1 and 3 between.
        let lattice = NodeLattice::new((0..5).map(|x| [x, 0, 0]).collect());
        let (coarse, parents, own) = lattice.coarsen();
        assert_eq!(coarse.len(), 3);
        assert_eq!(own, vec![0, 2, 4]);
        assert_eq!(parents[0], vec![(0, 1.0)]);
        assert_eq!(parents[1], vec![(0, 0.5), (1, 0.5)]);
        assert_eq!(parents[4], vec![(2, 1.0)]);
        // In 2D a cell-centre node takes a quarter of each corner present, scaled to a
        // partition of unity over those that are: here two of four.
        let lattice = NodeLattice::new(vec![[1, 1, 0], [0, 0, 0], [2, 2, 0]]);
        let (coarse, parents, own) = lattice.coarsen();
        assert_eq!((coarse.len(), own), (2, vec![1, 2]));
        assert_eq!(parents[0], vec![(0, 0.5), (1, 0.5)]);
    }
}
