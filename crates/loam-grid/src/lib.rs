//! The background of the material point method: a uniform Cartesian grid in D = 2 (plane
//! strain) or D = 3 dimensions, the basis functions that tie material points to its nodes
//! (linear "standard MPM", GIMP, quadratic B-splines), the body-fitted mesh of the updated
//! Lagrangian FEM reference, both behind [`Background`], and the per-step connectivity:
//! which nodes each point's basis touches, which nodes are active, and which points touch
//! each node; and the deterministic band scatter that maps points to nodes. Also the
//! ghost-penalty faces of cut cells, the one lexicographic numbering and the one
//! Gauss–Legendre rule of the workspace.
//!
//! The grid is reset every step (updated Lagrangian MPM): it carries no state of its own.
//! See docs/theory.md §4 for the basis functions (Bardenhagen & Kober 2004; iGIMP of
//! Charlton, Coombs & Augarde 2017) and §12 for the mesh.

mod axis_basis;
mod background;
mod bands;
mod basis;
mod connectivity;
mod gauss;
mod ghost;
mod index;
mod layout;
mod mesh;

pub use axis_basis::AxisBasis;
pub use background::{Background, LocateError};
pub use bands::{BandScatter, NodeWindow, ROWS_PER_BAND};
pub use basis::{bspline_greville, BasisError, BasisKind};
pub use connectivity::{ActiveNodes, Connectivity, NodePointAdjacency, PointBasisError, INACTIVE};
pub use gauss::GaussLegendre;
pub use ghost::{ghost_faces, GhostFace, CUT_FILL};
pub use index::{lexicographic_coords, lexicographic_index};
pub use layout::{LayoutError, NodeField, NodeLayout};
pub use mesh::{ElementError, FeMesh, MeshError};

use nalgebra::SVector;

/// Errors in the definition of a grid.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum GridError {
    #[error("grid cell size along axis {axis} is {value}; it must be a positive finite number")]
    CellSize { axis: usize, value: f64 },
    #[error("grid has {value} cells along axis {axis}; it needs at least 1")]
    CellCount { axis: usize, value: usize },
    #[error("grid origin component {axis} is {value}; it must be finite")]
    Origin { axis: usize, value: f64 },
    #[error("grid has {nodes} nodes, more than the supported {max}")]
    TooLarge { nodes: usize, max: usize },
}

/// A uniform Cartesian background grid. Nodes are numbered with x fastest, then y, then z.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid<const D: usize> {
    origin: SVector<f64, D>,
    cell_size: SVector<f64, D>,
    cells: [usize; D],
}

impl<const D: usize> Grid<D> {
    /// A grid with its first node at `origin`, cells of `cell_size` per axis and `cells`
    /// cells per axis.
    pub fn new(origin: SVector<f64, D>, cell_size: SVector<f64, D>, cells: [usize; D]) -> Result<Self, GridError> {
        for axis in 0..D {
            if !origin[axis].is_finite() {
                return Err(GridError::Origin { axis, value: origin[axis] });
            }
            let h = cell_size[axis];
            if !(h.is_finite() && h > 0.0) {
                return Err(GridError::CellSize { axis, value: h });
            }
            if cells[axis] == 0 {
                return Err(GridError::CellCount { axis, value: 0 });
            }
        }
        let nodes = cells.iter().map(|c| c + 1).try_fold(1usize, |acc, n| acc.checked_mul(n));
        match nodes {
            Some(n) if n < u32::MAX as usize => {}
            _ => return Err(GridError::TooLarge { nodes: nodes.unwrap_or(usize::MAX), max: u32::MAX as usize - 1 }),
        }
        Ok(Self { origin, cell_size, cells })
    }

    pub fn origin(&self) -> &SVector<f64, D> {
        &self.origin
    }

    pub fn cell_size(&self) -> &SVector<f64, D> {
        &self.cell_size
    }

    pub fn cells(&self) -> [usize; D] {
        self.cells
    }

    /// Upper corner of the grid.
    pub fn extent_max(&self) -> SVector<f64, D> {
        SVector::from_fn(|a, _| self.origin[a] + self.cell_size[a] * self.cells[a] as f64)
    }

    pub fn nodes_per_axis(&self) -> [usize; D] {
        self.cells.map(|c| c + 1)
    }

    pub fn num_nodes(&self) -> usize {
        self.cells.iter().map(|c| c + 1).product()
    }

    pub fn cell_volume(&self) -> f64 {
        self.cell_size.iter().product()
    }

    pub fn num_cells(&self) -> usize {
        self.cells.iter().product()
    }

    /// Linear index of the cell with integer coordinates `ijk` (axis 0 fastest, like nodes).
    #[inline]
    pub fn cell_index(&self, ijk: [usize; D]) -> usize {
        lexicographic_index(ijk, self.cells)
    }

    /// Integer coordinates of cell `idx` (the inverse of [`cell_index`](Self::cell_index)).
    #[inline]
    pub fn cell_ijk(&self, idx: usize) -> [usize; D] {
        lexicographic_coords(idx, self.cells)
    }

    /// Linear node index of the node with integer coordinates `ijk`.
    #[inline]
    pub fn node_index(&self, ijk: [usize; D]) -> usize {
        lexicographic_index(ijk, self.nodes_per_axis())
    }

    /// Integer coordinates of node `idx`.
    #[inline]
    pub fn node_coords(&self, idx: usize) -> [usize; D] {
        lexicographic_coords(idx, self.nodes_per_axis())
    }

    pub fn node_position(&self, idx: usize) -> SVector<f64, D> {
        let ijk = self.node_coords(idx);
        SVector::from_fn(|a, _| self.origin[a] + self.cell_size[a] * ijk[a] as f64)
    }

    /// Whether `x` lies in the grid, with the half-open rule used everywhere in loam:
    /// each cell owns `[x_i, x_{i+1})` along every axis, so the upper faces of the grid
    /// belong to no cell.
    pub fn contains(&self, x: &SVector<f64, D>) -> bool {
        (0..D).all(|a| {
            let xi = (x[a] - self.origin[a]) / self.cell_size[a];
            xi >= 0.0 && xi < self.cells[a] as f64
        })
    }

    /// Integer coordinates of the cell that owns `x` (each cell owns `[x_i, x_{i+1})`),
    /// clamped to the grid: points on or beyond its faces count to the nearest cell.
    pub fn cell_coords(&self, x: &SVector<f64, D>) -> [usize; D] {
        std::array::from_fn(|a| {
            let xi = ((x[a] - self.origin[a]) / self.cell_size[a]).floor().max(0.0) as usize;
            xi.min(self.cells[a] - 1)
        })
    }

    /// The index of the grid plane of nodes normal to `axis` at `coordinate`, if a plane of
    /// nodes lies there (within 1e-9 of a cell).
    pub fn node_plane(&self, axis: usize, coordinate: f64) -> Option<usize> {
        let xi = (coordinate - self.origin[axis]) / self.cell_size[axis];
        let i = xi.round();
        if (xi - i).abs() <= 1e-9 && i >= 0.0 && i <= self.cells[axis] as f64 {
            Some(i as usize)
        } else {
            None
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    #[test]
    fn node_numbering_round_trips() {
        let g = Grid::<3>::new(nalgebra::Vector3::zeros(), nalgebra::Vector3::new(1.0, 2.0, 0.5), [3, 4, 5]).unwrap();
        assert_eq!(g.num_nodes(), 4 * 5 * 6);
        for idx in 0..g.num_nodes() {
            assert_eq!(g.node_index(g.node_coords(idx)), idx);
        }
        assert_eq!(g.node_index([1, 0, 0]), 1);
        assert_eq!(g.node_index([0, 1, 0]), 4);
        let p = g.node_position(g.node_index([1, 2, 3]));
        assert_eq!(p, nalgebra::Vector3::new(1.0, 4.0, 1.5));
    }

    #[test]
    fn invalid_grids_are_refused() {
        assert!(matches!(
            Grid::<2>::new(Vector2::zeros(), Vector2::new(0.0, 1.0), [1, 1]),
            Err(GridError::CellSize { axis: 0, .. })
        ));
        assert!(matches!(
            Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [1, 0]),
            Err(GridError::CellCount { axis: 1, .. })
        ));
    }

    #[test]
    fn cells_own_their_lower_faces_and_clamp_at_the_grid() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 0.5), [3, 2]).unwrap();
        assert_eq!(g.cell_coords(&Vector2::new(1.0, 0.49)), [1, 0]);
        assert_eq!(g.cell_coords(&Vector2::new(0.99, 0.5)), [0, 1]);
        assert_eq!(g.cell_coords(&Vector2::new(3.0, 1.0)), [2, 1]);
        assert_eq!(g.cell_coords(&Vector2::new(-0.1, -5.0)), [0, 0]);
    }

    #[test]
    fn half_open_containment_and_planes() {
        let g = Grid::<2>::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [2, 2]).unwrap();
        assert!(g.contains(&Vector2::new(0.0, 0.0)));
        assert!(!g.contains(&Vector2::new(2.0, 1.0)));
        assert_eq!(g.node_plane(0, 1.0), Some(1));
        assert_eq!(g.node_plane(0, 0.5), None);
        assert_eq!(g.node_plane(1, 3.0), None);
    }
}
