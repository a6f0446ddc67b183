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
            LevelSpec::Plane { height, slope } => self.plane(*height, slope, gravity)?,
        };
        let water = Water::new(spec.unit_weight, level, gravity)
            .map_err(|e| self.error(&[Seg::Key("water")], format!("water: {e}")))?;
        self.check_level_in_grid(&water)?;
        Ok(Some(water))
    }

    /// An inclined plane level: D slopes, none along gravity's axis.
    fn plane<const D: usize>(
        &self,
        height: f64,
        slope: &[f64],
        gravity: &SVector<f64, D>,
    ) -> Result<PhreaticLevel, SceneError> {
        let at = [Seg::Key("water"), Seg::Key("level"), Seg::Key("slope")];
        let s = self.vector::<D>(slope, &at, "slope")?;
        if let Some(a) = (0..D).find(|&a| gravity[a] != 0.0 && s[a] != 0.0) {
            return Err(
                self.error(&at, format!("water: the plane rises along axis {a}, the axis of gravity; give 0 there"))
            );
        }
        let mut all = [0.0; 3];
        all[..D].copy_from_slice(s.as_slice());
        Ok(PhreaticLevel::Plane { height, slope: all })
    }

    /// The corners of the scene's grid (zero beyond its dimension).
    fn grid_corners(&self) -> Vec<SVector<f64, 3>> {
        let g = &self.scene.grid;
        let d = g.origin.len().min(g.cell_size.len()).min(g.cells.len()).min(3);
        (0..1usize << d)
            .map(|corner| {
                SVector::from_fn(|a, _| match a < d {
                    true if corner >> a & 1 == 1 => g.origin[a] + g.cell_size[a] * g.cells[a] as f64,
                    true => g.origin[a],
                    false => 0.0,
                })
            })
            .collect()
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
            // The plane's height over the grid's corners.
            PhreaticLevel::Plane { .. } => self.grid_corners().iter().map(|x| water.head(x)).collect(),
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
