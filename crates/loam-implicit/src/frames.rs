//! Local frames at the nodes of inclined rollers and frictional planes (docs/theory.md §5).
//! A node held by a roller on an inclined plane has its dofs in a frame whose first axis
//! is the plane's normal: the system is assembled in the global frame with those nodes
//! free, then every block touching them becomes T_iᵀ K_ij T_j and their residual Tᵀ R, the
//! normal dof is held as a grid-plane constraint's dofs are (its row and column
//! eliminated, its residual taken as the reaction), and the correction is turned back,
//! δu = T δũ. A node held by two supports (rollers, frictional planes), or by one and
//! another constraint (a grid plane's or a body's), is held in every direction.
//!
//! A node on a frictional plane is in contact (docs/theory.md §5, "Frictional planes in
//! the implicit analyses"): over a Newton solve it is open (nothing held), sticking
//! (every component of its increment held at zero: the plane does not move) or slipping
//! (the normal held, the tangential residual R_t + μ N s with N the normal reaction and s
//! the unit slip direction, its tangent row K_t + μ s K_n, and in 3D + μ N (I − s sᵀ)/|Δu_t|
//! on the node's own tangential block). The state follows the iterate, an active set:
//! after each residual a sticking node whose tangential reaction exceeds μ max(N, 0) slips
//! against it, and otherwise a closed node whose reaction pulls (N < 0) opens; before each
//! point update an open node that moves into the plane closes, slipping the way it moves
//! (sticking if it does not move along the plane), and a slipping one that moves back
//! sticks. A solve is converged only at an iterate where no state changed.

use loam_grid::ActiveNodes;
use loam_model::Model;
use loam_solve::{BlockPattern, SystemMatrix};

/// No frame at a node.
const NONE: u32 = u32::MAX;

/// The state of a node in contact with a frictional plane over an increment.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Contact {
    /// Separated from the plane, or leaving it: nothing held.
    Open,
    /// Closed and not sliding: every component held.
    Stick,
    /// Closed and sliding along the unit tangential direction `s` (the frame's axes 1..D).
    Slip([f64; 2]),
}

/// What holds a framed node.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Hold {
    /// An inclined roller: the normal.
    Roller,
    /// Two supports meet: every component.
    Everywhere,
    /// A frictional plane (its μ) in the contact state.
    Plane { friction: f64, contact: Contact },
}

/// One framed node.
#[derive(Debug, Clone)]
struct Frame {
    /// Its active node.
    node: usize,
    /// T (D × D, row-major, its columns the local axes; the first D² entries used).
    t: [f64; 9],
    hold: Hold,
    /// On a frictional plane: the normal reaction N at the last residual, and |Δu_t| at the
    /// last iterate.
    normal_force: f64,
    slip_length: f64,
}

impl Frame {
    /// The node's components of the global field `v` (D per node) in its frame, Tᵀ v_I.
    fn local<const D: usize>(&self, v: &[f64]) -> [f64; D] {
        let k = self.node * D;
        std::array::from_fn(|r| (0..D).map(|m| self.t[m * D + r] * v[k + m]).sum())
    }

    /// Write the local components `x` into the global field `v` at the node, v_I = T x.
    fn put_global<const D: usize>(&self, x: &[f64; D], v: &mut [f64]) {
        let k = self.node * D;
        for r in 0..D {
            v[k + r] = (0..D).map(|m| self.t[r * D + m] * x[m]).sum();
        }
    }

    /// Whether local component `i` is held.
    fn holds(&self, i: usize) -> bool {
        match self.hold {
            Hold::Roller => i == 0,
            Hold::Everywhere => true,
            Hold::Plane { contact: Contact::Open, .. } => false,
            Hold::Plane { contact: Contact::Stick, .. } => true,
            Hold::Plane { contact: Contact::Slip(_), .. } => i == 0,
        }
    }
}

/// The frames of one connectivity's held nodes. See the module docs.
#[derive(Debug, Default)]
pub(crate) struct LocalFrames<const D: usize> {
    /// Per active node, the index of its frame, or `NONE`.
    frame_of: Vec<u32>,
    frames: Vec<Frame>,
    /// The held local dofs (node · D + local component), ascending.
    held: Vec<usize>,
    /// The dofs assembly eliminates: the held ones but at framed nodes.
    assembly: Vec<bool>,
    /// Per roller, the nodes it holds.
    roller_nodes: Vec<Vec<usize>>,
    /// Per frictional plane, the nodes it meets.
    plane_nodes: Vec<Vec<usize>>,
    /// Whether a contact state changed at the last point update or residual.
    changed: bool,
}

impl<const D: usize> LocalFrames<D> {
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The frames of `model`'s inclined rollers and frictional planes on `active` (none
    /// without them), the planes' nodes sticking. `constrained` holds the grid planes' and
    /// bodies' dofs on entry and every held dof, in the nodes' frames, on return.
    pub fn connect(&mut self, model: &Model<D>, active: &ActiveNodes, constrained: &mut [bool]) {
        self.frame_of.clear();
        self.frame_of.resize(active.len(), NONE);
        self.frames.clear();
        let rollers: Vec<Vec<usize>> =
            (0..model.inclined_rollers().len()).map(|k| model.inclined_roller_nodes(active, k)).collect();
        let planes: Vec<Vec<usize>> =
            (model.frictional_planes().iter()).map(|p| model.plane_nodes(active, p.plane())).collect();
        for (k, nodes) in rollers.iter().enumerate() {
            let t = model.inclined_rollers()[k].frame();
            for &a in nodes {
                self.add(a, |r, c| t[(r, c)], Hold::Roller, constrained);
            }
        }
        for (p, nodes) in model.frictional_planes().iter().zip(&planes) {
            let t = p.plane().frame();
            let hold = Hold::Plane { friction: p.friction(), contact: Contact::Stick };
            for &a in nodes {
                self.add(a, |r, c| t[(r, c)], hold, constrained);
            }
        }
        (self.roller_nodes, self.plane_nodes) = (rollers, planes);
        self.assembly.clear();
        self.assembly.extend_from_slice(constrained);
        for f in &self.frames {
            (0..D).for_each(|i| self.assembly[f.node * D + i] = false);
        }
        self.hold_dofs(constrained);
        self.changed = false;
    }

    /// A frame at node `a` with transform `t(row, column)` held by `hold`; a node framed
    /// already, or held by another constraint, is held in every direction.
    fn add(&mut self, a: usize, t: impl Fn(usize, usize) -> f64, hold: Hold, constrained: &[bool]) {
        if self.frame_of[a] != NONE {
            self.frames[self.frame_of[a] as usize].hold = Hold::Everywhere;
            return;
        }
        let hold = if (0..D).any(|i| constrained[a * D + i]) { Hold::Everywhere } else { hold };
        self.frame_of[a] = self.frames.len() as u32;
        let mut m = [0.0; 9];
        (0..D * D).for_each(|rc| m[rc] = t(rc / D, rc % D));
        self.frames.push(Frame { node: a, t: m, hold, normal_force: 0.0, slip_length: 0.0 });
    }

    /// `constrained` and `held` at the framed nodes from their holds.
    fn hold_dofs(&mut self, constrained: &mut [bool]) {
        self.held.clear();
        for f in &self.frames {
            for i in 0..D {
                constrained[f.node * D + i] = f.holds(i);
            }
        }
        let framed = |dof: usize| self.frame_of[dof / D] != NONE;
        self.held.extend((0..constrained.len()).filter(|&dof| constrained[dof] && framed(dof)));
    }

    /// Every node on a frictional plane sticking again (the start of a Newton solve).
    pub fn reset_contacts(&mut self, constrained: &mut [bool]) {
        let mut any = false;
        for f in &mut self.frames {
            if let Hold::Plane { contact, .. } = &mut f.hold {
                *contact = Contact::Stick;
                any = true;
            }
        }
        if any {
            self.hold_dofs(constrained);
        }
        self.changed = false;
    }

    /// How many nodes slip.
    #[cfg(test)]
    pub fn slipping(&self) -> usize {
        self.frames.iter().filter(|f| matches!(f.hold, Hold::Plane { contact: Contact::Slip(_), .. })).count()
    }

    /// Whether a contact state changed at the last point update or residual: the iterate
    /// is not converged then.
    pub fn contact_changed(&self) -> bool {
        self.changed
    }

    /// Before a point update, the kinematic changes of state at the increment `du`
    /// (global): an open node moving into its plane closes, slipping the way it moves
    /// along the plane (sticking if it does not), a slipping one that moves against its
    /// slip direction sticks, a slipping one in 3D takes the direction it moves in; then
    /// the held components of `du` are put to zero (the planes do not move).
    pub fn settle(&mut self, du: &mut [f64], constrained: &mut [bool]) {
        let mut changed = false;
        for f in self.frames.iter_mut() {
            // The increment in the node's frame, and the way it moves along the plane.
            let mut x: [f64; D] = f.local(du);
            let length = x[1..].iter().map(|v| v * v).sum::<f64>().sqrt();
            let along = if length > 0.0 { [x[1] / length, if D == 3 { x[2] / length } else { 0.0 }] } else { [0.0; 2] };
            let Hold::Plane { contact, .. } = &mut f.hold else { continue };
            match *contact {
                // Closing, it keeps sliding the way it moves (a node that friction holds
                // turns back, and sticks, at the next iterate).
                Contact::Open if x[0] < 0.0 => {
                    (*contact, changed) = (if length > 0.0 { Contact::Slip(along) } else { Contact::Stick }, true)
                }
                Contact::Slip(s) if (1..D).map(|j| x[j] * s[j - 1]).sum::<f64>() < 0.0 => {
                    (*contact, changed) = (Contact::Stick, true)
                }
                Contact::Slip(_) if D == 3 && length > 0.0 => *contact = Contact::Slip(along),
                _ => {}
            }
            if f.holds(0) {
                (0..D).filter(|&i| f.holds(i)).for_each(|i| x[i] = 0.0);
                f.put_global(&x, du);
            }
            f.slip_length = if f.holds(1) { 0.0 } else { length };
        }
        if changed {
            self.hold_dofs(constrained);
        }
        self.changed = changed;
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
        (f != NONE).then(|| &self.frames[f as usize].t[..D * D])
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
        for f in &self.frames {
            let a = f.node;
            let x: [f64; D] = std::array::from_fn(|i| v[a * D + i]);
            for r in 0..D {
                v[a * D + r] = (0..D).map(|m| entry(&f.t, r, m) * x[m]).sum();
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
    /// nodes (a dynamic step's starting velocity and acceleration, which a roller stops
    /// along its normal): v_I ← T Π Tᵀ v_I, Π zeroing the held local dofs; at a node on a
    /// frictional plane only a normal component into the plane, the contact's state being
    /// decided by the step's own iterates.
    pub fn hold_in_field(&self, v: &mut [f64]) {
        self.to_local(v);
        for f in &self.frames {
            let a = f.node;
            match f.hold {
                Hold::Plane { .. } => v[a * D] = v[a * D].max(0.0),
                _ => (0..D).filter(|&i| f.holds(i)).for_each(|i| v[a * D + i] = 0.0),
            }
        }
        self.to_global(v);
    }

    /// At the end of an implicit dynamic step, the new nodal accelerations `a_new` (global,
    /// D per active node) at the components a frictional plane holds, set so that the node
    /// ends the step at rest there, v + Δt ((1 − γ) a + γ a_new) = 0 (`v`, `a` the nodal
    /// velocity and acceleration the step started from). Newmark's relation would give a
    /// held node that started moving the opposite velocity (−v with the trapezoidal rule);
    /// with a lumped mass the held components' inertia enters only their reactions.
    pub fn stop_held_motion(&self, a_new: &mut [f64], v: &[f64], a: &[f64], dt: f64, gamma: f64) {
        for f in self.frames.iter().filter(|f| matches!(f.hold, Hold::Plane { .. })) {
            let (mut an, vl, al): ([f64; D], [f64; D], [f64; D]) = (f.local(a_new), f.local(v), f.local(a));
            for i in (0..D).filter(|&i| f.holds(i)) {
                an[i] = -(vl[i] + dt * (1.0 - gamma) * al[i]) / (gamma * dt);
            }
            f.put_global(&an, a_new);
        }
    }

    /// The tangent at the framed nodes in their frames: a slipping node's tangential rows
    /// take the friction's terms (the module docs), then the held dofs are eliminated.
    pub fn hold_in_matrix(&self, pattern: &BlockPattern, matrix: &mut SystemMatrix) {
        matrix.transform_blocks(pattern, |a| self.frame(a));
        for f in &self.frames {
            let Hold::Plane { friction, contact: Contact::Slip(s), .. } = f.hold else { continue };
            // A pulling node (it opens at the next iterate) has no friction.
            let n = f.normal_force;
            if n <= 0.0 {
                continue;
            }
            // Row j of the node's blocks += μ s_j row 0 (the normal's).
            let rows: Vec<(usize, usize, f64)> = (1..D).map(|j| (j, 0, friction * s[j - 1])).collect();
            matrix.add_row_multiples(pattern, f.node, &rows);
            if D == 3 && f.slip_length > 0.0 {
                // d(μ N s)/dΔu_t = μ N (I − s sᵀ) / |Δu_t| on the tangential block.
                matrix.change_block(pattern, f.node, f.node, |b| {
                    for j in 1..D {
                        for k in 1..D {
                            let delta = if j == k { 1.0 } else { 0.0 };
                            b[j * D + k] += friction * n * (delta - s[j - 1] * s[k - 1]) / f.slip_length;
                        }
                    }
                });
            }
        }
        matrix.eliminate(pattern, &self.held);
    }

    /// The residual `r` (f_int − f_ext at the framed nodes, global) in the nodes' frames:
    /// the changes of contact state the forces make (a pulling node opens, an overloaded
    /// sticking one slips), a slipping node's friction μ N s added to its tangential
    /// residual, the held dofs' values taken as their reactions (`reaction`, turned back to
    /// the global frame with the friction forces) and zeroed. Returns the sum of the
    /// reactions' squares, for the reference force.
    pub fn hold_in_residual(&mut self, r: &mut [f64], reaction: &mut [f64], constrained: &mut [bool]) -> f64 {
        self.to_local(r);
        let changed = self.contacts_from_forces(r);
        if changed {
            self.hold_dofs(constrained);
        }
        self.changed |= changed;
        let mut squares = 0.0;
        for f in &self.frames {
            let a = f.node;
            (0..D).for_each(|i| reaction[a * D + i] = 0.0);
            if let Hold::Plane { friction, contact: Contact::Slip(s), .. } = f.hold {
                for j in 1..D {
                    let force = friction * f.normal_force.max(0.0) * s[j - 1];
                    r[a * D + j] += force;
                    reaction[a * D + j] = -force;
                    squares += force * force;
                }
            }
        }
        for &dof in &self.held {
            reaction[dof] = r[dof];
            squares += r[dof] * r[dof];
            r[dof] = 0.0;
        }
        self.to_global(reaction);
        squares
    }

    /// The changes of state the local residual `r` makes at the nodes on frictional
    /// planes (the module docs), and their normal reactions kept; whether one changed.
    fn contacts_from_forces(&mut self, r: &[f64]) -> bool {
        let mut changed = false;
        for f in &mut self.frames {
            let Hold::Plane { friction, contact, .. } = &mut f.hold else { continue };
            let a = f.node;
            let n = r[a * D];
            let tangential = r[a * D + 1..(a + 1) * D].iter().map(|v| v * v).sum::<f64>().sqrt();
            f.normal_force = n;
            match *contact {
                // A sticking node whose tangential force exceeds the friction slips first,
                // even while it pulls: it is the tangential hold that may be pulling it.
                Contact::Stick if tangential > *friction * n.max(0.0) && tangential > 0.0 => {
                    let mut s = [0.0; 2];
                    (1..D).for_each(|j| s[j - 1] = -r[a * D + j] / tangential);
                    (*contact, changed) = (Contact::Slip(s), true);
                }
                Contact::Stick | Contact::Slip(_) if n < 0.0 => (*contact, changed) = (Contact::Open, true),
                _ => {}
            }
        }
        changed
    }

    /// Per roller, the sum of the (global) reactions at its nodes.
    pub fn roller_reactions(&self, reaction: &[f64]) -> Vec<[f64; 3]> {
        Self::sums(&self.roller_nodes, reaction)
    }

    /// Per frictional plane, the sum of the (global) forces it exerts on the material at
    /// its nodes.
    pub fn plane_reactions(&self, reaction: &[f64]) -> Vec<[f64; 3]> {
        Self::sums(&self.plane_nodes, reaction)
    }

    /// Per node set, the sum of `reaction` (D per node) over its nodes.
    fn sums(sets: &[Vec<usize>], reaction: &[f64]) -> Vec<[f64; 3]> {
        (sets.iter())
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
