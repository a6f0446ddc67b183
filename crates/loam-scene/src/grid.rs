//! The grid part of a scene: its dimension and the background grid.

use super::locate::Seg;
use super::{LoadedScene, SceneError};
use loam_grid::{Grid, GridError};

impl LoadedScene {
    /// The scene's `dimension` must be the `D` it is built in.
    pub(super) fn check_dimension<const D: usize>(&self) -> Result<(), SceneError> {
        let dimension = self.scene.dimension;
        if dimension != D {
            return Err(self.error(
                &[Seg::Key("dimension")],
                format!("dimension is {dimension}; loam runs 2 (plane strain) or 3"),
            ));
        }
        Ok(())
    }

    /// The background grid: origin, cell size and cell counts, each with `D` components;
    /// what the grid itself refuses is reported at the key it concerns.
    pub(super) fn grid<const D: usize>(&self) -> Result<Grid<D>, SceneError> {
        let g = &self.scene.grid;
        let origin = self.vector(&g.origin, &[Seg::Key("grid"), Seg::Key("origin")], "grid.origin")?;
        let cell = self.vector(&g.cell_size, &[Seg::Key("grid"), Seg::Key("cell_size")], "grid.cell_size")?;
        if g.cells.len() != D {
            return Err(self.error(
                &[Seg::Key("grid"), Seg::Key("cells")],
                format!("grid.cells has {} entries; a {D}D scene needs {D}", g.cells.len()),
            ));
        }
        let mut cells = [0usize; D];
        cells.copy_from_slice(&g.cells);
        Grid::new(origin, cell, cells).map_err(|e| {
            let key = match e {
                GridError::CellSize { .. } => "cell_size",
                GridError::CellCount { .. } | GridError::TooLarge { .. } => "cells",
                GridError::Origin { .. } => "origin",
            };
            self.error(&[Seg::Key("grid"), Seg::Key(key)], e.to_string())
        })
    }
}
