//! The rigid-body motions no constraint resists, body by body: what makes a quasi-static
//! tangent singular before any material is asked (Model::free_rigid_bodies).
//!
//! A body is a set of active nodes coupled through the points' supports (a component of
//! the node graph); two bodies apart share no point and are held, or not, each on its own.
//! A rigid motion of a body about its centre c, u(x) = t + ω × (x − c) / L (L its size,
//! so that every parameter has the units of a displacement), is resisted by a held
//! component i at node x when u_i(x) ≠ 0: each held component is a row of a linear map
//! from the D + (1 or 3) parameters, and the free motions are the null space of
//! G = Σ rows ⊗ rows, found from its eigenvalues (a few parameters: a 3 × 3 or 6 × 6
//! matrix per body). An inclined roller holds the component along its normal, a row the
//! same way; a frictional plane its normal, and every component where it has friction.
//! Free translations are the axes no node of the body holds; the rest of the null space
//! is rotations, named by axis (a coordinate axis where one is free) and a
//! point the axis passes through.

use crate::Model;
use loam_grid::Connectivity;
use nalgebra::{DMatrix, DVector, Vector3};

/// A rigid-body motion of a body that no constraint resists.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RigidMode {
    /// Translation along a coordinate axis.
    Translation(usize),
    /// Rotation about the unit `axis` (the z axis in 2D) through the point `through`.
    Rotation { axis: [f64; 3], through: [f64; 3] },
}

/// A body and the rigid motions no constraint resists.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeBody {
    pub points: usize,
    /// The centre of its nodes.
    pub centre: [f64; 3],
    /// Whether it is the only body of the model.
    pub alone: bool,
    pub modes: Vec<RigidMode>,
}

const AXES: [&str; 3] = ["x", "y", "z"];

/// Up to 4 significant digits, without trailing zeros ("2", "0.3125", "-1.5e-05").
fn short(x: f64) -> String {
    let x = if x.abs() < 1e-12 { 0.0 } else { x };
    let s = format!("{:.4}", x);
    let s = if s.contains('.') { s.trim_end_matches('0').trim_end_matches('.').to_string() } else { s };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

fn point(x: &[f64; 3], dim: usize) -> String {
    format!("({})", x[..dim].iter().map(|&v| short(v)).collect::<Vec<_>>().join(", "))
}

impl RigidMode {
    /// The mode in words, for a `dim`-dimensional model.
    pub fn describe(&self, dim: usize) -> String {
        match *self {
            RigidMode::Translation(a) => format!("translation along {}", AXES[a]),
            RigidMode::Rotation { through, .. } if dim == 2 => format!("rotation about {}", point(&through, 2)),
            RigidMode::Rotation { axis, through } => {
                let name = match axis.iter().position(|&c| (c.abs() - 1.0).abs() < 1e-9) {
                    Some(k) => format!("the {} axis", AXES[k]),
                    None => format!("the axis {}", point(&axis, 3)),
                };
                format!("rotation about {name} through {}", point(&through, 3))
            }
        }
    }
}

impl FreeBody {
    /// The body and its free modes in words, for a `dim`-dimensional model.
    pub fn describe(&self, dim: usize) -> String {
        let body = if self.alone {
            "the body".to_string()
        } else {
            format!("the body of {} points around {}", self.points, point(&self.centre, dim))
        };
        let modes: Vec<String> = self.modes.iter().map(|m| m.describe(dim)).collect();
        format!("{body} against {}", modes.join(", "))
    }
}

/// The body (component of the node graph) of every active node, and their number.
fn bodies<const D: usize>(conn: &Connectivity<D>) -> (Vec<usize>, usize) {
    let n = conn.active_nodes().active_to_grid.len();
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut a: usize) -> usize {
        while parent[a] != a {
            parent[a] = parent[parent[a]];
            a = parent[a];
        }
        a
    }
    for p in 0..conn.num_points() {
        let nodes = conn.support_nodes(p);
        for &b in nodes.iter().skip(1) {
            let (ra, rb) = (root(&mut parent, nodes[0] as usize), root(&mut parent, b as usize));
            parent[ra.max(rb)] = ra.min(rb);
        }
    }
    let mut id = vec![usize::MAX; n];
    let mut count = 0;
    let body: Vec<usize> = (0..n)
        .map(|a| {
            let r = root(&mut parent, a);
            if id[r] == usize::MAX {
                id[r] = count;
                count += 1;
            }
            id[r]
        })
        .collect();
    (body, count)
}

/// One body's nodes: their places and the directions they are held in (coordinate axes
/// of grid-plane and body constraints, normals of inclined rollers).
struct BodyNodes {
    x: Vec<Vector3<f64>>,
    held: Vec<Vec<Vector3<f64>>>,
    points: usize,
}

impl<const D: usize> Model<D> {
    /// The bodies with rigid-body motions that no constraint on the active nodes of `conn`
    /// resists (the module docs); a quasi-static tangent with one is singular.
    pub fn free_rigid_bodies(&self, conn: &Connectivity<D>) -> Vec<FreeBody> {
        let active = conn.active_nodes();
        let (body, count) = bodies(conn);
        let mut nodes: Vec<BodyNodes> =
            (0..count).map(|_| BodyNodes { x: Vec::new(), held: Vec::new(), points: 0 }).collect();
        let mut body_held = vec![[false; 3]; active.len()];
        for (k, c) in self.body_constraints().iter().enumerate() {
            for a in self.body_constraint_nodes(conn, k) {
                (0..D).for_each(|i| body_held[a][i] |= c.fixed[i]);
            }
        }
        for (a, &g) in active.active_to_grid.iter().enumerate() {
            let x = self.background().node_reference_position(g as usize);
            let mut axes = body_held[a];
            // A body of revolution has one rigid motion, along its axis: a radial
            // translation or an in-plane rotation strains its rings (u_r / r ≠ 0), so in
            // axisymmetry every node counts as held radially.
            axes[0] |= self.axisymmetric();
            for c in self.constraints().iter().filter(|c| self.node_on_plane(g as usize, c)) {
                (0..D).for_each(|i| axes[i] |= c.fixed[i]);
            }
            let mut held: Vec<Vector3<f64>> = (0..D).filter(|&i| axes[i]).map(|i| Vector3::ith(i, 1.0)).collect();
            for roller in self.inclined_rollers().iter().filter(|r| self.roller_holds(r, g as usize)) {
                held.push(Vector3::from_fn(|i, _| if i < D { roller.normal()[i] } else { 0.0 }));
            }
            // A frictional plane holds its normal, and while the node sticks every
            // direction: friction is what keeps a block on an incline.
            for plane in self.frictional_planes().iter().filter(|p| self.roller_holds(p.plane(), g as usize)) {
                match plane.friction() > 0.0 {
                    true => held.extend((0..D).map(|i| Vector3::ith(i, 1.0))),
                    false => held.push(Vector3::from_fn(|i, _| if i < D { plane.plane().normal()[i] } else { 0.0 })),
                }
            }
            let b = &mut nodes[body[a]];
            b.x.push(Vector3::from_fn(|i, _| if i < D { x[i] } else { 0.0 }));
            b.held.push(held);
        }
        for p in 0..conn.num_points() {
            if let Some(&a) = conn.support_nodes(p).first() {
                nodes[body[a as usize]].points += 1;
            }
        }
        (nodes.iter())
            .filter_map(|b| {
                let (centre, modes) = free_modes::<D>(b);
                (!modes.is_empty()).then_some(FreeBody { points: b.points, centre, alone: count == 1, modes })
            })
            .collect()
    }
}

/// The rotation axes of a `D`-dimensional model: z in 2D, x, y and z in 3D.
fn rotation_axes<const D: usize>() -> &'static [usize] {
    if D == 2 {
        &[2]
    } else {
        &[0, 1, 2]
    }
}

/// The free rigid modes of one body, and its centre.
fn free_modes<const D: usize>(b: &BodyNodes) -> ([f64; 3], Vec<RigidMode>) {
    let n = b.x.len().max(1) as f64;
    let c: Vector3<f64> = b.x.iter().sum::<Vector3<f64>>() / n;
    let size = b.x.iter().map(|x| (x - c).norm()).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    let rot = rotation_axes::<D>();
    let m = D + rot.len();
    // G = Σ r rᵀ over the held components, r the row of u_i's derivatives.
    let mut g = DMatrix::<f64>::zeros(m, m);
    for (x, held) in b.x.iter().zip(&b.held) {
        let r = (x - c) / size;
        for e in held {
            let mut row = DVector::<f64>::zeros(m);
            (0..D).for_each(|i| row[i] = e[i]);
            for (j, &k) in rot.iter().enumerate() {
                row[D + j] = Vector3::ith(k, 1.0).cross(&r).dot(e);
            }
            g += &row * row.transpose();
        }
    }
    let eig = g.symmetric_eigen();
    let largest = eig.eigenvalues.iter().fold(0.0, |a: f64, &l| a.max(l));
    let null: Vec<DVector<f64>> = (0..m)
        .filter(|&k| eig.eigenvalues[k] <= 1e-10 * largest)
        .map(|k| eig.eigenvectors.column(k).into_owned())
        .collect();
    let free_axes: Vec<usize> = (0..D).filter(|&i| b.held.iter().flatten().all(|e| e[i] == 0.0)).collect();
    let mut modes: Vec<RigidMode> = free_axes.iter().map(|&a| RigidMode::Translation(a)).collect();
    modes.extend(rotations::<D>(&null, &free_axes, c, size));
    (c.into(), modes)
}

/// The rotations of the null space `null` (its free translations `free_axes` taken out),
/// about coordinate axes where such a rotation is free, about other axes for the rest.
fn rotations<const D: usize>(null: &[DVector<f64>], free_axes: &[usize], c: Vector3<f64>, size: f64) -> Vec<RigidMode> {
    let rot = rotation_axes::<D>();
    if null.is_empty() {
        return Vec::new();
    }
    // The rotation parts of the null basis (one column per null vector), and the
    // combination that gives a rotation ω: a = R⁺ ω.
    let n = DMatrix::from_columns(null);
    let r = n.rows(D, rot.len()).into_owned();
    // One SVD gives R's rank, its column space and its pseudo-inverse.
    let svd = r.clone().svd(true, true);
    let rank = svd.singular_values.iter().filter(|&&s| s > 1e-9).count();
    let u = svd.u.clone().expect("asked for");
    let pinv = match svd.pseudo_inverse(1e-9) {
        Ok(p) => p,
        Err(_) => return Vec::new(),
    };
    let reachable = |w: &DVector<f64>| (&r * (&pinv * w) - w).norm() < 1e-6 * w.norm().max(1.0);
    let mut axes: Vec<DVector<f64>> = Vec::new();
    for j in 0..rot.len() {
        let w = DVector::from_fn(rot.len(), |i, _| if i == j { 1.0 } else { 0.0 });
        if reachable(&w) {
            axes.push(w);
        }
    }
    // The other free rotation directions, orthogonal to the coordinate ones found.
    if axes.len() < rank {
        for k in 0..rank {
            let mut w = u.column(k).into_owned();
            for a in &axes {
                w -= a * a.dot(&w);
            }
            if w.norm() > 1e-6 && axes.len() < rank {
                axes.push(w.normalize());
            }
        }
    }
    (axes.iter())
        .map(|w| {
            let mut v = &n * (&pinv * w);
            free_axes.iter().for_each(|&a| v[a] = 0.0);
            rotation_about::<D>(&v, c, size)
        })
        .collect()
}

/// The rotation of the rigid-motion parameters `v` about its axis, through the point of
/// the axis nearest the body's centre: c + (ω × t) / |ω|².
fn rotation_about<const D: usize>(v: &DVector<f64>, c: Vector3<f64>, size: f64) -> RigidMode {
    let rot = rotation_axes::<D>();
    let t = Vector3::from_fn(|i, _| if i < D { v[i] } else { 0.0 });
    let mut omega = Vector3::zeros();
    for (j, &k) in rot.iter().enumerate() {
        omega[k] = v[D + j] / size;
    }
    let through = c + omega.cross(&t) / omega.norm_squared();
    let axis = omega.normalize();
    // One sign per axis, for a stable report: the first non-zero component positive.
    let sign = axis.iter().find(|a| a.abs() > 1e-12).map_or(1.0, |a| a.signum());
    RigidMode::Rotation { axis: (axis * sign).into(), through: through.into() }
}
