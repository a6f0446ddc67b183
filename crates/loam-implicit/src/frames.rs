//! Local frames at the nodes of inclined rollers (docs/theory.md §5). A node held by a
//! roller on an inclined plane has its dofs in a frame whose first axis is the plane's
//! normal: the system is assembled in the global frame with those nodes free, then every
//! block touching them becomes T_iᵀ K_ij T_j and their residual Tᵀ R, the normal dof is
//! held as a grid-plane constraint's dofs are (its row and column eliminated, its residual
//! taken as the reaction), and the correction is turned back, δu = T δũ. A node held by
//! two rollers, or by a roller and another constraint (a grid plane's or a body's), is
//! held in every direction.

use loam_grid::ActiveNodes;
use loam_model::Model;
use loam_solve::{BlockPattern, SystemMatrix};

/// No frame at a node.
const NONE: u32 = u32::MAX;

/// The frames of one connectivity's held nodes. See the module docs.
#[derive(Debug, Default)]
pub(crate) struct LocalFrames<const D: usize> {
    /// Per active node, the index of its frame, or `NONE`.
    frame_of: Vec<u32>,
    /// Per frame, its node (active index).
    nodes: Vec<usize>,
    /// Per frame, T (D × D, row-major; its columns the local axes).
    transforms: Vec<f64>,
    /// The held local dofs (node · D + local component), ascending.
    held: Vec<usize>,
    /// The dofs assembly eliminates: the held ones but at framed nodes.
    assembly: Vec<bool>,
    /// Per roller, the nodes it holds.
    roller_nodes: Vec<Vec<usize>>,
}

impl<const D: usize> LocalFrames<D> {
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The frames of `model`'s inclined rollers on `active` (none without rollers).
    /// `constrained` holds the grid planes' and bodies' dofs on entry and every held dof,
    /// in the nodes' frames, on return.
    pub fn connect(&mut self, model: &Model<D>, active: &ActiveNodes, constrained: &mut [bool]) {
        self.frame_of.clear();
        self.frame_of.resize(active.len(), NONE);
        self.nodes.clear();
        self.transforms.clear();
        self.held.clear();
        self.roller_nodes =
            (0..model.inclined_rollers().len()).map(|k| model.inclined_roller_nodes(active, k)).collect();
        let mut everywhere = vec![false; active.len()];
        for (k, nodes) in self.roller_nodes.iter().enumerate() {
            let t = model.inclined_rollers()[k].frame();
            for &a in nodes {
                if self.frame_of[a] != NONE {
                    everywhere[a] = true;
                    continue;
                }
                self.frame_of[a] = self.nodes.len() as u32;
                self.nodes.push(a);
                self.transforms.extend((0..D * D).map(|rc| t[(rc / D, rc % D)]));
                everywhere[a] |= (0..D).any(|i| constrained[a * D + i]);
            }
        }
        self.assembly.clear();
        self.assembly.extend_from_slice(constrained);
        for &a in &self.nodes {
            for i in 0..D {
                self.assembly[a * D + i] = false;
                constrained[a * D + i] = i == 0 || everywhere[a];
            }
        }
        self.held = (0..constrained.len()).filter(|&dof| constrained[dof] && self.frame_of[dof / D] != NONE).collect();
    }

    /// The dofs assembly, the residual and the predictor treat as held: `constrained` (the
    /// held dofs), but at framed nodes none, whose held dofs are eliminated in their frames
    /// afterwards (and whose global increment keeps every component).
    pub fn assembly_mask<'a>(&'a self, constrained: &'a [bool]) -> &'a [bool] {
        if self.is_empty() {
            constrained
        } else {
            &self.assembly
        }
    }

    /// Node `a`'s transform, if it has a frame.
    pub fn frame(&self, a: usize) -> Option<&[f64]> {
        let f = *self.frame_of.get(a)?;
        (f != NONE).then(|| &self.transforms[f as usize * D * D..(f as usize + 1) * D * D])
    }

    /// `v` (D per active node) at the framed nodes in their frames: v_I ← Tᵀ v_I.
    pub fn to_local(&self, v: &mut [f64]) {
        self.turn(v, |t, r, m| t[m * D + r]);
    }

    /// `v` at the framed nodes back in the global frame: v_I ← T v_I.
    pub fn to_global(&self, v: &mut [f64]) {
        self.turn(v, |t, r, m| t[r * D + m]);
    }

    /// v_I ← A v_I at every framed node, A(r, m) = `entry(T, r, m)`.
    fn turn(&self, v: &mut [f64], entry: impl Fn(&[f64], usize, usize) -> f64) {
        for (f, &a) in self.nodes.iter().enumerate() {
            let t = &self.transforms[f * D * D..(f + 1) * D * D];
            let x: [f64; D] = std::array::from_fn(|i| v[a * D + i]);
            for r in 0..D {
                v[a * D + r] = (0..D).map(|m| entry(t, r, m) * x[m]).sum();
            }
        }
    }

    /// A load vector (global) as a linear solve takes it: in the nodes' frames, its held
    /// dofs zeroed.
    pub fn hold_in_load(&self, f: &mut [f64]) {
        self.to_local(f);
        for &dof in &self.held {
            f[dof] = 0.0;
        }
    }

    /// A nodal field (global, D per active node) without its held components at the framed
    /// nodes: v_I ← T Π Tᵀ v_I, Π zeroing the held local dofs (a dynamic step's nodal
    /// velocity and acceleration, which the roller stops along its normal).
    pub fn hold_in_field(&self, v: &mut [f64]) {
        self.hold_in_load(v);
        self.to_global(v);
    }

    /// The tangent at the framed nodes in their frames, their held dofs eliminated.
    pub fn hold_in_matrix(&self, pattern: &BlockPattern, matrix: &mut SystemMatrix) {
        matrix.transform_blocks(pattern, |a| self.frame(a));
        matrix.eliminate(pattern, &self.held);
    }

    /// The residual `r` (f_int − f_ext at the framed nodes, global) in the nodes' frames,
    /// its held dofs' values taken as their reactions (`reaction`, turned back to the
    /// global frame) and zeroed; returns the sum of their squares for the reference force.
    pub fn hold_in_residual(&self, r: &mut [f64], reaction: &mut [f64]) -> f64 {
        self.to_local(r);
        let mut squares = 0.0;
        for &dof in &self.held {
            reaction[dof] = r[dof];
            squares += r[dof] * r[dof];
            r[dof] = 0.0;
        }
        self.to_global(reaction);
        squares
    }

    /// Per roller, the sum of the (global) reactions at its nodes.
    pub fn roller_reactions(&self, reaction: &[f64]) -> Vec<[f64; 3]> {
        (self.roller_nodes.iter())
            .map(|nodes| {
                let mut sum = [0.0; 3];
                for &a in nodes {
                    (0..D).for_each(|i| sum[i] += reaction[a * D + i]);
                }
                sum
            })
            .collect()
    }
}
