//! The monitoring points' columns of `run_log.csv`: per named point, its displacement and
//! stress after every step, found by the point's stable id (NaN once the point has been
//! excavated).

use crate::point_fields::stress_columns;
use loam_format::output::CsvCell;
use loam_model::Model;
use loam_scene::Monitor;

const AXES: [&str; 3] = ["x", "y", "z"];

/// The monitoring points of a run and where each point was last found.
pub(crate) struct MonitorColumns {
    monitors: Vec<Monitor>,
    index: Vec<Found>,
}

/// Where a monitor's point was last found.
#[derive(Debug, Clone, Copy)]
enum Found {
    /// Not looked up yet.
    Unknown,
    /// At this index (checked against its id before use).
    At(usize),
    /// Removed: ids are never given again, so it is not looked for again.
    Gone,
}

impl MonitorColumns {
    pub fn new(monitors: Vec<Monitor>) -> Self {
        let index = vec![Found::Unknown; monitors.len()];
        Self { monitors, index }
    }

    /// Per monitor `monitor_<name>_u<axis>` for each axis, then its stress components.
    pub fn header(&self, dim: usize) -> Vec<String> {
        let mut header = Vec::new();
        for m in &self.monitors {
            header.extend(AXES[..dim].iter().map(|a| format!("monitor_{}_u{a}", m.name)));
            header.extend(stress_columns(dim).iter().map(|(s, _, _)| format!("monitor_{}_{s}", m.name)));
        }
        header
    }

    /// The cells of the header's columns for the state of `model`.
    pub fn cells<const D: usize>(&mut self, model: &Model<D>) -> Vec<CsvCell<'static>> {
        let pts = model.points();
        let mut cells = Vec::new();
        for (m, index) in self.monitors.iter().zip(&mut self.index) {
            // The index holds until points are removed or reordered; then one search.
            let stale = match *index {
                Found::Unknown => true,
                Found::At(p) => pts.id().get(p) != Some(&m.point),
                Found::Gone => false,
            };
            if stale {
                *index = pts.id().iter().position(|&id| id == m.point).map_or(Found::Gone, Found::At);
            }
            let Found::At(p) = *index else {
                cells.extend((0..D + stress_columns(D).len()).map(|_| CsvCell::Float(f64::NAN)));
                continue;
            };
            let u = pts.position()[p] - pts.position0()[p];
            cells.extend(u.iter().map(|&v| CsvCell::Float(v)));
            let stress = &pts.stress()[p];
            cells.extend(stress_columns(D).iter().map(|&(_, i, j)| CsvCell::Float(stress[(i, j)])));
        }
        cells
    }
}
