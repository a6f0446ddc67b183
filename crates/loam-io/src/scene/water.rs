//! The water part of a scene: the phreatic level and the water's unit weight
//! (docs/theory.md §18).

use super::locate::Seg;
use super::{LevelSpec, LoadedScene, SceneError};
use loam_model::{PhreaticLevel, Water};
use nalgebra::SVector;

impl LoadedScene {
    /// The scene's groundwater, if any, under `gravity`.
    pub(super) fn water<const D: usize>(&self, gravity: &SVector<f64, D>) -> Result<Option<Water>, SceneError> {
        let Some(spec) = &self.scene.water else { return Ok(None) };
        let level = match &spec.level {
            LevelSpec::Horizontal(h) => PhreaticLevel::Horizontal(*h),
            LevelSpec::Polyline(v) => PhreaticLevel::Polyline(v.clone()),
        };
        let water = Water::new(spec.unit_weight, level, gravity)
            .map_err(|e| self.error(&[Seg::Key("water")], format!("water: {e}")))?;
        self.check_level_in_grid(&water)?;
        Ok(Some(water))
    }

    /// A level outside the grid is a mistake (water above everything is given by a level
    /// above the bodies, inside the grid's height).
    fn check_level_in_grid(&self, water: &Water) -> Result<(), SceneError> {
        let g = &self.scene.grid;
        let v = water.vertical();
        let (Some(&o), Some(&h), Some(&n)) = (g.origin.get(v), g.cell_size.get(v), g.cells.get(v)) else {
            return Ok(());
        };
        let (lo, hi) = (o, o + h * n as f64);
        let heights: Vec<f64> = match water.level() {
            PhreaticLevel::Horizontal(level) => vec![*level],
            PhreaticLevel::Polyline(points) => points.iter().map(|p| p.1).collect(),
        };
        match heights.iter().find(|&&z| !(z >= lo && z <= hi)) {
            Some(z) => Err(self.error(
                &[Seg::Key("water"), Seg::Key("level")],
                format!("water: the level {z} lies outside the grid's height {lo} to {hi}; give a level inside it"),
            )),
            None => Ok(()),
        }
    }
}
