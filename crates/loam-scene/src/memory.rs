//! The memory a scene will take, estimated before anything large is allocated, and the
//! refusal of a scene above the limit (`loam run --max-memory`). A 2000 × 2000-cell body
//! at 8 × 8 points per cell (256 million points) used to take more than 8 GiB within
//! seconds of `loam check` before anything said so.
//!
//! The estimate is per material point and per grid node, from the peaks of measured runs
//! (docs/scene-format.md, "Memory"). It covers the points, their connectivity, the analysis's
//! per-point scratch and, for the implicit analyses, the tangent with the iterative solver;
//! a sparse factorisation in 3D takes more (its fill grows faster than the points).

use super::bodies::fem_elements;
use super::{AnalysisSpec, LoadedScene, MethodSpec, SceneError, Seg};
use loam_grid::Grid;
use loam_points::{fill_count, Shape};

/// Peak bytes per material point: (dimension, explicit analysis).
fn bytes_per_point(dimension: usize, explicit: bool) -> u64 {
    match (dimension, explicit) {
        // The 48³ elastic block, multigrid CG: 3.62 GB for 884 736 points.
        (3, false) => 4100,
        // The 3D run-out example, 1 057 760 points: 1.26 GB at its peak (1 218 B a point).
        (3, true) => 1250,
        // The run-out slope, one quasi-static step, 4 and 8 points per cell and axis.
        (_, false) => 1800,
        // The same, explicit.
        (_, true) => 900,
    }
}

/// Bytes per node of the whole background grid, active or not: the implicit
/// connectivity's map from grid node to active node (`u32`; a 20 000² grid takes 1.6 GB
/// for it), and the explicit step's dense nodal fields, 1 + 6D values and D held flags.
fn bytes_per_grid_node(dimension: usize, explicit: bool) -> u64 {
    if explicit {
        8 * (1 + 6 * dimension as u64) + dimension as u64
    } else {
        4
    }
}

/// The limit when neither the user nor the machine says: 16 GiB.
const FALLBACK_LIMIT: u64 = 16 << 30;

/// What a scene will take.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MemoryEstimate {
    /// Material points (at most, when the estimate is a bound).
    pub points: u64,
    pub grid_nodes: u64,
    pub bytes: u64,
}

/// The default limit: the machine's physical memory where it can be read (Linux), else
/// 16 GiB; and the words that say which.
pub fn default_memory_limit() -> (u64, &'static str) {
    let total = std::fs::read_to_string("/proc/meminfo").ok().and_then(|text| {
        let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
        line.split_whitespace().nth(1)?.parse::<u64>().ok().map(|kib| kib * 1024)
    });
    match total {
        Some(bytes) => (bytes, "this machine's memory"),
        None => (FALLBACK_LIMIT, "the default, 16 GiB"),
    }
}

impl LoadedScene {
    /// Peak bytes per material point of this scene's analysis in `D` dimensions.
    fn bytes_per_point<const D: usize>(&self) -> u64 {
        bytes_per_point(D, self.is_explicit())
    }

    /// Bytes per background node of this scene's analysis in `D` dimensions.
    fn bytes_per_grid_node<const D: usize>(&self) -> u64 {
        bytes_per_grid_node(D, self.is_explicit())
    }

    fn is_explicit(&self) -> bool {
        matches!(self.scene.analysis, AnalysisSpec::Explicit { .. })
    }

    /// The memory the scene will take on `grid`: with `exact_up_to` the points of each body
    /// are counted up to that many (every sub-cell centre tested, as long as a fill's loop
    /// but allocation-free), else bounded by the bodies' bounding boxes (instant). A body
    /// the fill or the mesher would refuse (its points per cell, its shape) counts none
    /// here: they say why, with its place.
    pub fn memory_estimate<const D: usize>(
        &self,
        grid: &Grid<D>,
        exact_up_to: Option<u64>,
    ) -> Result<MemoryEstimate, SceneError> {
        let mut points = 0u64;
        for (i, b) in self.scene.bodies.iter().enumerate() {
            let shape = self.shape::<D>(i, b)?;
            let ppc = b.points_per_cell;
            let count = match (self.scene.method, &shape) {
                (MethodSpec::Mpm, _) => fill_count(grid, &shape, ppc, exact_up_to).unwrap_or(0),
                // The FEM reference's Gauss points: elements of about a cell, ppc^D each.
                (MethodSpec::UpdatedLagrangianFem, Shape::Box { min, max }) if (1..=3).contains(&ppc) => {
                    let elements = fem_elements(min, max, grid).iter().product::<f64>();
                    (elements * (ppc as f64).powi(D as i32)).min(u64::MAX as f64) as u64
                }
                (MethodSpec::UpdatedLagrangianFem, _) => 0,
            };
            points = points.saturating_add(count);
        }
        let grid_nodes = grid.num_nodes() as u64;
        let bytes = points
            .saturating_mul(self.bytes_per_point::<D>())
            .saturating_add(grid_nodes.saturating_mul(self.bytes_per_grid_node::<D>()));
        Ok(MemoryEstimate { points, grid_nodes, bytes })
    }

    /// Refuse a scene whose estimate exceeds the limit (`memory_limit`, else the machine's
    /// memory), before its points are made. The bound is tried first; only a scene above
    /// the limit by its bound has its points counted.
    pub(super) fn check_memory<const D: usize>(&self, grid: &Grid<D>) -> Result<(), SceneError> {
        let (limit, which) = match self.memory_limit {
            Some(limit) => (limit, "the limit given"),
            None => default_memory_limit(),
        };
        if self.memory_estimate(grid, None)?.bytes <= limit {
            return Ok(());
        }
        // Counting stops once the points alone pass the limit.
        let estimate = self.memory_estimate(grid, Some(limit / self.bytes_per_point::<D>() + 1))?;
        if estimate.bytes <= limit {
            return Ok(());
        }
        Err(self.error(
            &[Seg::Key("bodies")],
            format!(
                "the scene would take about {} ({} material points, {} grid nodes), above {} ({which}); \
                 use fewer points per cell, larger cells or a grid that ends closer to the bodies, or raise the \
                 limit with --max-memory",
                human(estimate.bytes),
                estimate.points,
                estimate.grid_nodes,
                human(limit)
            ),
        ))
    }
}

/// Bytes in MB below a GB, else in GB.
fn human(bytes: u64) -> String {
    if bytes < 1_000_000_000 {
        format!("{:.1} MB", bytes as f64 / 1e6)
    } else {
        format!("{:.1} GB", bytes as f64 / 1e9)
    }
}
