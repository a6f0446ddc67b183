//! The monitoring points of a scene: each name resolved to the material point that starts
//! nearest its place, by the point's stable id (so that it follows that point through
//! removals and restarts).

use super::locate::Seg;
use super::{LoadedScene, SceneError};
use loam_model::Model;
use loam_points::PointId;

/// A monitoring point, resolved: its name and the id of its material point.
#[derive(Debug, Clone, PartialEq)]
pub struct Monitor {
    pub name: String,
    pub point: PointId,
}

impl LoadedScene {
    /// The scene's monitoring points on `model` (as built, before any step), each checked at
    /// its place in the file: a name of letters, digits and `_`, not used before, and a
    /// place inside or on a body's shape.
    pub fn monitors<const D: usize>(&self, model: &Model<D>) -> Result<Vec<Monitor>, SceneError> {
        let mut monitors: Vec<Monitor> = Vec::with_capacity(self.scene.monitor.len());
        for (k, m) in self.scene.monitor.iter().enumerate() {
            let at = |key| [Seg::Key("monitor"), Seg::Index(k), Seg::Key(key)];
            let valid = !m.name.is_empty() && m.name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_');
            if !valid {
                return Err(self.error(
                    &at("name"),
                    format!(
                        "monitor {k} is named {:?}; a name is letters, digits and _ (it heads run_log.csv's columns)",
                        m.name
                    ),
                ));
            }
            if monitors.iter().any(|e| e.name == m.name) {
                return Err(self.error(
                    &at("name"),
                    format!("monitor {k} is named {:?}, as an earlier one is; names must differ", m.name),
                ));
            }
            let x = self.vector::<D>(&m.at, &at("at"), "a monitoring point's place")?;
            if !self.in_some_body(&x)? {
                return Err(self.error(&at("at"), format!(
                    "monitor {k} at {:?} lies in no body; a monitoring point follows a material point, so `at` must lie inside or on a body's shape",
                    m.at
                )));
            }
            let pts = model.points();
            // Once per monitor, before the run.
            let Some(p) = pts.nearest_at_start(&x) else {
                return Err(self.error(&at("at"), "the model has no points"));
            };
            monitors.push(Monitor { name: m.name.clone(), point: pts.id()[p] });
        }
        Ok(monitors)
    }
}
