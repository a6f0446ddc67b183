//! The background the points are connected to: the Cartesian grid of the MPM, reset every
//! step, or the body-fitted mesh of the updated Lagrangian FEM reference (docs/theory.md
//! §12), whose nodes move with the body and persist. One type, so that what an analysis
//! asks of its background — connect the points, group them for cell averages, find the
//! nodes on a plane, move with the body — is answered here and no analysis branches on
//! which background it has.

use crate::{ActiveNodes, BasisKind, Connectivity, ElementError, FeMesh, Grid, PointBasisError, INACTIVE};
use nalgebra::SVector;

/// Why the points could not be connected to the background.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LocateError {
    /// A point's basis reaches outside the grid.
    #[error(transparent)]
    OutsideGrid(#[from] PointBasisError),
    /// An element of the body-fitted mesh is inverted.
    #[error(transparent)]
    Element(#[from] ElementError),
}

/// The grid of an MPM run, or the mesh of the FEM reference on the grid's planes. See the
/// module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct Background<const D: usize> {
    /// The Cartesian grid; for the FEM reference it only places the constraint planes.
    grid: Grid<D>,
    basis: BasisKind,
    /// The body-fitted mesh, whose Gauss points are the points.
    mesh: Option<FeMesh<D>>,
}

impl<const D: usize> Background<D> {
    /// The MPM background: `grid` with `basis`, reset every step.
    pub fn on_grid(grid: Grid<D>, basis: BasisKind) -> Self {
        Self { grid, basis, mesh: None }
    }

    /// The FEM reference: `mesh`, whose Gauss points are the points, with constraint planes
    /// placed on `grid`. Its element functions are the bilinear (trilinear) products of the
    /// linear basis, whose support size the connectivity buffers take.
    pub fn body_fitted(grid: Grid<D>, mesh: FeMesh<D>) -> Self {
        Self { grid, basis: BasisKind::Linear, mesh: Some(mesh) }
    }

    /// The grid: the whole background of an MPM run, the planes of an FEM one.
    pub fn grid(&self) -> &Grid<D> {
        &self.grid
    }

    pub fn basis(&self) -> BasisKind {
        self.basis
    }

    /// The body-fitted mesh of the FEM reference; `None` for the MPM.
    pub fn mesh(&self) -> Option<&FeMesh<D>> {
        self.mesh.as_ref()
    }

    /// Whether the nodes move with the body and keep their state from step to step (the
    /// FEM reference), rather than being reset every step (the MPM).
    pub fn moves_with_body(&self) -> bool {
        self.mesh.is_some()
    }

    /// Whether all points of an averaging group share the same nodes, as cell averages
    /// (B-bar, assumed strain) need: the linear basis on the grid, or the mesh's elements.
    pub fn groups_share_nodes(&self) -> bool {
        self.mesh.is_some() || self.basis == BasisKind::Linear
    }

    /// The lattice coordinates (grid node indices per axis) of background node `node`, as
    /// geometric multigrid coarsens them; `None` on a body-fitted mesh.
    pub fn lattice_coordinates(&self, node: usize) -> Option<[usize; D]> {
        if self.mesh.is_some() {
            return None;
        }
        let dims = self.grid.cells().map(|c| c + 1);
        Some(crate::index::lexicographic_coords(node, dims))
    }

    /// Number of nodes: grid nodes, or mesh nodes.
    pub fn num_nodes(&self) -> usize {
        self.mesh.as_ref().map_or(self.grid.num_nodes(), |m| m.num_nodes())
    }

    /// Connect the points at `positions` (with GIMP half-lengths `half_lengths`) to the
    /// background: the grid's basis, or the mesh's elements at its current node positions
    /// (whose Gauss points the points are, whatever their positions say).
    pub fn connect(
        &self,
        conn: &mut Connectivity<D>,
        positions: &[SVector<f64, D>],
        half_lengths: &[SVector<f64, D>],
    ) -> Result<(), LocateError> {
        match &self.mesh {
            None => conn.compute(&self.grid, positions, half_lengths)?,
            Some(mesh) => conn.compute_mesh(mesh)?,
        }
        Ok(())
    }

    /// The averaging group of point `p` at `x` (cell averages): its grid cell, each cell
    /// owning [x_i, x_{i+1}), or its element.
    pub fn averaging_group(&self, p: usize, x: &SVector<f64, D>) -> usize {
        match &self.mesh {
            None => self.grid.cell_index(self.grid.cell_coords(x)),
            Some(mesh) => p / mesh.gauss_per_element(),
        }
    }

    /// Where node `node` is for the constraints: a grid node's position, a mesh node's
    /// starting position.
    pub fn node_reference_position(&self, node: usize) -> SVector<f64, D> {
        match &self.mesh {
            None => self.grid.node_position(node),
            Some(mesh) => mesh.reference_positions()[node],
        }
    }

    /// Whether node `node` lies on node plane `plane` of `axis` — a grid node on it, or a
    /// mesh node that started on it (within 1e-9 of a cell) — and, if `within` is given,
    /// inside that box on the other axes (to within 1e-9 of a cell).
    pub fn node_on_plane(&self, node: usize, axis: usize, plane: usize, within: Option<&([f64; 3], [f64; 3])>) -> bool {
        let h = self.grid.cell_size();
        let x = self.node_reference_position(node);
        let on_plane = match &self.mesh {
            None => self.grid.node_coords(node)[axis] == plane,
            Some(_) => (x[axis] - (self.grid.origin()[axis] + plane as f64 * h[axis])).abs() <= 1e-9 * h[axis],
        };
        on_plane && within.is_none_or(|bounds| self.in_box(&x, bounds, Some(axis)))
    }

    /// Whether `x` lies in the box `(min, max)` on every axis but `skip`, to within 1e-9 of
    /// a cell (a box drawn through nodes or points takes them).
    pub fn in_box(&self, x: &SVector<f64, D>, (lo, hi): &([f64; 3], [f64; 3]), skip: Option<usize>) -> bool {
        let h = self.grid.cell_size();
        (0..D).all(|a| Some(a) == skip || (x[a] >= lo[a] - 1e-9 * h[a] && x[a] <= hi[a] + 1e-9 * h[a]))
    }

    /// Move the nodes that move with the body by the converged increment of a step, `du`
    /// (D values per active node of `active`); the grid, reset every step, stays where it
    /// is. Every mesh node belongs to an element, so every one is active.
    /// Put the nodes of a body-fitted mesh at `positions` (a checkpoint's): `false`, and
    /// nothing changed, without a mesh or with another number of nodes.
    pub fn set_mesh_positions(&mut self, positions: &[SVector<f64, D>]) -> bool {
        self.mesh.as_mut().is_some_and(|mesh| mesh.set_positions(positions))
    }

    pub fn displace(&mut self, active: &ActiveNodes, du: &[f64]) {
        if let Some(mesh) = &mut self.mesh {
            let g2a = &active.grid_to_active;
            mesh.displace(|n| {
                let a = g2a[n];
                assert_ne!(a, INACTIVE, "mesh node {n} belongs to no element");
                SVector::from_fn(|i, _| du[a as usize * D + i])
            });
        }
    }
}
