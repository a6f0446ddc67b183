//! Body-fitted finite-element mesh for the updated Lagrangian FEM reference (the seed
//! paper compares its implicit MPM with an updated Lagrangian FEM; docs/theory.md §12).
//!
//! Elements are isoparametric bilinear quadrilaterals (D = 2) or trilinear hexahedra
//! (D = 3) on structured blocks. The material points of an FEM run are the elements' Gauss
//! points: their reference coordinates ξ never change, the nodes move with the body and the
//! mesh is never reset, so N_I(ξ_g) is fixed and only the gradients ∂N_I/∂x = J⁻ᵀ ∂N_I/∂ξ
//! change with the current node positions. Everything downstream (laws, assembly, Newton,
//! Newmark) is shared with the MPM through [`Connectivity`](crate::Connectivity).

use crate::index::cell_corner;
use crate::GaussLegendre;
use crate::{lexicographic_coords, lexicographic_index};
use nalgebra::{Matrix3, SVector};

/// Errors in building or evaluating a mesh.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    #[error("mesh block needs at least one element per axis, got {0:?}")]
    NoElements(Vec<usize>),
    #[error("mesh block bounds along axis {axis} are [{min}, {max}]; they must be finite with min < max")]
    Bounds { axis: usize, min: f64, max: f64 },
    #[error("Gauss order {0} is not supported; valid are 1, 2 and 3 points per axis")]
    GaussOrder(usize),
    #[error("blocks with Gauss order {first} and {second} cannot share one mesh")]
    MixedGaussOrder { first: usize, second: usize },
    #[error("mesh block of {elements:?} elements has more nodes than the supported {max}")]
    TooLarge { elements: Vec<usize>, max: usize },
}

/// Why a Gauss point's shape functions could not be evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElementError {
    #[error("element {element} is inverted or degenerate at Gauss point {gauss} (det J = {det:.3e})")]
    Inverted { element: usize, gauss: usize, det: f64 },
}

/// A mesh of structured blocks of bilinear / trilinear elements. Node `k` of an element
/// is its corner with bits `k & 1 << a` set along axis `a` (the grid's lexicographic order),
/// so element node lists are ascending and the tangent pattern matches the MPM's.
#[derive(Debug, Clone, PartialEq)]
pub struct FeMesh<const D: usize> {
    reference: Vec<SVector<f64, D>>,
    position: Vec<SVector<f64, D>>,
    /// 2^D node indices per element.
    elements: Vec<u32>,
    /// Block index of each element.
    block: Vec<u32>,
    gauss_order: usize,
}

impl<const D: usize> FeMesh<D> {
    pub const NODES_PER_ELEMENT: usize = 1 << D;

    /// One block: the box [min, max] cut into `elements[a]` equal elements along axis a,
    /// with `gauss_order` Gauss points per axis and element.
    pub fn block(
        min: SVector<f64, D>,
        max: SVector<f64, D>,
        elements: [usize; D],
        gauss_order: usize,
    ) -> Result<Self, MeshError> {
        if !(1..=3).contains(&gauss_order) {
            return Err(MeshError::GaussOrder(gauss_order));
        }
        if elements.contains(&0) {
            return Err(MeshError::NoElements(elements.to_vec()));
        }
        if let Some(axis) = (0..D).find(|&a| !(min[a].is_finite() && max[a].is_finite() && min[a] < max[a])) {
            return Err(MeshError::Bounds { axis, min: min[axis], max: max[axis] });
        }
        let nodes_per_axis: [usize; D] = std::array::from_fn(|a| elements[a].saturating_add(1));
        let num_nodes = nodes_per_axis.iter().try_fold(1usize, |n, &k| n.checked_mul(k));
        let Some(num_nodes) = num_nodes.filter(|&n| n < u32::MAX as usize) else {
            return Err(MeshError::TooLarge { elements: elements.to_vec(), max: u32::MAX as usize - 1 });
        };
        let reference: Vec<SVector<f64, D>> = (0..num_nodes)
            .map(|n| {
                let ijk = lexicographic_coords(n, nodes_per_axis);
                SVector::from_fn(|a, _| min[a] + (max[a] - min[a]) * ijk[a] as f64 / elements[a] as f64)
            })
            .collect();
        let num_elements: usize = elements.iter().product();
        let mut conn = Vec::with_capacity(num_elements * Self::NODES_PER_ELEMENT);
        for e in 0..num_elements {
            let base = lexicographic_coords(e, elements);
            for k in 0..Self::NODES_PER_ELEMENT {
                conn.push(lexicographic_index(cell_corner(base, k), nodes_per_axis) as u32);
            }
        }
        Ok(Self { position: reference.clone(), reference, elements: conn, block: vec![0; num_elements], gauss_order })
    }

    /// Add the blocks of `other` as further blocks (their nodes are not merged with ours:
    /// separate bodies).
    pub fn append(&mut self, other: FeMesh<D>) -> Result<(), MeshError> {
        if other.gauss_order != self.gauss_order {
            return Err(MeshError::MixedGaussOrder { first: self.gauss_order, second: other.gauss_order });
        }
        let offset = self.reference.len() as u32;
        let blocks = self.block.iter().max().map_or(0, |b| b + 1);
        self.reference.extend(other.reference);
        self.position.extend(other.position);
        self.elements.extend(other.elements.iter().map(|n| n + offset));
        self.block.extend(other.block.iter().map(|b| b + blocks));
        Ok(())
    }

    pub fn num_nodes(&self) -> usize {
        self.reference.len()
    }

    pub fn num_elements(&self) -> usize {
        self.block.len()
    }

    pub fn gauss_order(&self) -> usize {
        self.gauss_order
    }

    pub fn gauss_per_element(&self) -> usize {
        self.gauss_order.pow(D as u32)
    }

    /// Gauss points in all: the material points of the FEM run, element-major.
    pub fn num_gauss_points(&self) -> usize {
        self.num_elements() * self.gauss_per_element()
    }

    /// Block of element `e`.
    pub fn element_block(&self, e: usize) -> usize {
        self.block[e] as usize
    }

    pub fn element_nodes(&self, e: usize) -> &[u32] {
        let n = Self::NODES_PER_ELEMENT;
        &self.elements[e * n..(e + 1) * n]
    }

    /// Initial node positions.
    pub fn reference_positions(&self) -> &[SVector<f64, D>] {
        &self.reference
    }

    /// Current node positions.
    pub fn positions(&self) -> &[SVector<f64, D>] {
        &self.position
    }

    /// Reference coordinates and weight of Gauss point `g` of an element (the tensor
    /// product of the 1D rule, axis 0 fastest).
    fn gauss_point(&self, g: usize) -> (SVector<f64, D>, f64) {
        let rule = GaussLegendre::new(self.gauss_order).expect("the block checked the Gauss order");
        let ijk = lexicographic_coords(g, [self.gauss_order; D]);
        let mut w = 1.0;
        let xi = SVector::<f64, D>::from_fn(|a, _| {
            let (x, weight) = rule.point(ijk[a]);
            w *= weight;
            x
        });
        (xi, w)
    }

    /// Shape functions and their reference gradients ∂N/∂ξ at ξ.
    fn shape(xi: &SVector<f64, D>, values: &mut [f64], grads: &mut [SVector<f64, D>]) {
        for k in 0..Self::NODES_PER_ELEMENT {
            let s: [f64; D] = std::array::from_fn(|a| if (k >> a) & 1 == 1 { 1.0 } else { -1.0 });
            let f: [f64; D] = std::array::from_fn(|a| 0.5 * (1.0 + s[a] * xi[a]));
            values[k] = f.iter().product();
            grads[k] = SVector::from_fn(|a, _| (0..D).map(|b| if b == a { 0.5 * s[a] } else { f[b] }).product());
        }
    }

    /// Jacobian ∂x/∂ξ of element `e` at ξ for the given node positions, embedded in 3×3
    /// (identity out of plane in 2D) so that one determinant and inverse serve both D.
    fn jacobian(&self, e: usize, x: &[SVector<f64, D>], grads: &[SVector<f64, D>]) -> Matrix3<f64> {
        let mut j = Matrix3::identity();
        for a in 0..D {
            for b in 0..D {
                j[(a, b)] = self.element_nodes(e).iter().zip(grads).map(|(&n, g)| x[n as usize][a] * g[b]).sum();
            }
        }
        j
    }

    /// Position and volume (det J times the weight) of every Gauss point in the reference
    /// configuration, element-major.
    pub fn gauss_points(&self) -> Vec<(SVector<f64, D>, f64)> {
        let n = Self::NODES_PER_ELEMENT;
        let mut vals = vec![0.0; n];
        let mut grads = vec![SVector::zeros(); n];
        let mut out = Vec::with_capacity(self.num_gauss_points());
        for e in 0..self.num_elements() {
            for g in 0..self.gauss_per_element() {
                let (xi, w) = self.gauss_point(g);
                Self::shape(&xi, &mut vals, &mut grads);
                let j = self.jacobian(e, &self.reference, &grads);
                let x = self.element_nodes(e).iter().zip(&vals).map(|(&n, &v)| self.reference[n as usize] * v).sum();
                out.push((x, j.determinant() * w));
            }
        }
        out
    }

    /// Shape functions of Gauss point `p` (element-major numbering) at the current node
    /// positions: node indices (ascending), values and spatial gradients ∂N/∂x. Returns how
    /// many were written (2^D).
    pub fn evaluate(
        &self,
        p: usize,
        nodes: &mut [u32],
        values: &mut [f64],
        gradients: &mut [SVector<f64, D>],
    ) -> Result<usize, ElementError> {
        let n = Self::NODES_PER_ELEMENT;
        let (e, g) = (p / self.gauss_per_element(), p % self.gauss_per_element());
        let (xi, _) = self.gauss_point(g);
        Self::shape(&xi, &mut values[..n], &mut gradients[..n]);
        let j = self.jacobian(e, &self.position, &gradients[..n]);
        let det = j.determinant();
        let inv_t = match j.try_inverse() {
            Some(inv) if det > 0.0 && det.is_finite() => inv.transpose(),
            _ => return Err(ElementError::Inverted { element: e, gauss: g, det }),
        };
        for g in &mut gradients[..n] {
            let r = *g;
            *g = SVector::from_fn(|a, _| (0..D).map(|b| inv_t[(a, b)] * r[b]).sum());
        }
        nodes[..n].copy_from_slice(self.element_nodes(e));
        Ok(n)
    }

    /// Move node `n` by `du[n]` (the converged increment of a step).
    /// Put every node at `positions` (a checkpoint's, one per node); `false`, and nothing
    /// changed, when the count differs.
    pub fn set_positions(&mut self, positions: &[SVector<f64, D>]) -> bool {
        if positions.len() != self.position.len() {
            return false;
        }
        self.position.copy_from_slice(positions);
        true
    }

    pub fn displace(&mut self, du: impl Fn(usize) -> SVector<f64, D>) {
        for (n, x) in self.position.iter_mut().enumerate() {
            *x += du(n);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Vector2, Vector3};

    #[test]
    fn a_block_numbers_nodes_like_the_grid_and_its_gauss_points_fill_its_volume() {
        let m = FeMesh::<2>::block(Vector2::new(1.0, 2.0), Vector2::new(3.0, 5.0), [2, 3], 2).unwrap();
        assert_eq!(m.num_nodes(), 12);
        assert_eq!(m.num_elements(), 6);
        assert_eq!(m.element_nodes(0), &[0, 1, 3, 4]);
        assert_eq!(m.element_nodes(5), &[7, 8, 10, 11]);
        let gp = m.gauss_points();
        assert_eq!(gp.len(), 24);
        let vol: f64 = gp.iter().map(|(_, v)| v).sum();
        // 2 × 3 box; exact to rounding
        assert!((vol - 6.0).abs() < 1e-12);
        let m3 = FeMesh::<3>::block(Vector3::zeros(), Vector3::new(1.0, 2.0, 3.0), [1, 2, 3], 3).unwrap();
        let vol: f64 = m3.gauss_points().iter().map(|(_, v)| v).sum();
        assert!((vol - 6.0).abs() < 1e-12);
    }

    /// Under an affine map x = A X + c the gradients of the bilinear functions reproduce A
    /// exactly: Σ x_I ⊗ ∂N_I/∂X = A at every Gauss point, and the values sum to one.
    #[test]
    fn gradients_reproduce_an_affine_deformation() {
        let mut m = FeMesh::<2>::block(Vector2::zeros(), Vector2::new(2.0, 1.0), [3, 2], 3).unwrap();
        let a = nalgebra::Matrix2::new(1.3, 0.2, -0.1, 0.8);
        let c = Vector2::new(0.5, -0.25);
        let x0: Vec<_> = m.reference_positions().to_vec();
        m.displace(|n| a * x0[n] + c - x0[n]);
        let (mut nodes, mut vals, mut grads) = ([0u32; 4], [0.0; 4], [Vector2::zeros(); 4]);
        for p in 0..m.num_gauss_points() {
            m.evaluate(p, &mut nodes, &mut vals, &mut grads).unwrap();
            assert!((vals.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            // ∂X/∂x from the current gradients must be A⁻¹.
            let mut g = nalgebra::Matrix2::zeros();
            for k in 0..4 {
                g += x0[nodes[k] as usize] * grads[k].transpose();
            }
            assert!((g * a - nalgebra::Matrix2::identity()).norm() < 1e-13, "{g}");
        }
    }

    #[test]
    fn an_inverted_element_is_reported() {
        let mut m = FeMesh::<2>::block(Vector2::zeros(), Vector2::new(1.0, 1.0), [1, 1], 2).unwrap();
        m.displace(|n| if n == 3 { Vector2::new(-2.0, -2.0) } else { Vector2::zeros() });
        let (mut nodes, mut vals, mut grads) = ([0u32; 4], [0.0; 4], [Vector2::zeros(); 4]);
        let e = (0..4).find_map(|p| m.evaluate(p, &mut nodes, &mut vals, &mut grads).err());
        assert!(matches!(e, Some(ElementError::Inverted { element: 0, .. })), "{e:?}");
    }

    #[test]
    fn bad_blocks_are_refused() {
        assert!(matches!(
            FeMesh::<2>::block(Vector2::zeros(), Vector2::new(1.0, 1.0), [0, 1], 2),
            Err(MeshError::NoElements(_))
        ));
        assert!(matches!(
            FeMesh::<2>::block(Vector2::zeros(), Vector2::new(1.0, 1.0), [1, 1], 4),
            Err(MeshError::GaussOrder(4))
        ));
        assert!(matches!(
            FeMesh::<2>::block(Vector2::zeros(), Vector2::new(-1.0, 1.0), [1, 1], 2),
            Err(MeshError::Bounds { axis: 0, .. })
        ));
    }
}
