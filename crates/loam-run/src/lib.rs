//! Running a scene: the runner that ties a scene (`loam-scene`) to its analysis (over the
//! three analyses behind `loam_analysis`'s one stepping interface) and its outputs
//! (`loam-format`), the per-point fields the outputs write (`point_fields`), and what a
//! checkpoint holds of a run and how a run is put back from one (`restart`).

mod element;
mod monitor;
mod point_fields;
pub mod restart;
pub mod runner;

pub use element::{run_element, ElementFailure, ElementSummary};
pub use loam_analysis::{Analysis, AnalysisError, Progress};
pub use point_fields::write_points_csv;
pub use restart::{checkpoint_interval, checkpoint_scene, CheckpointEvery, CheckpointWritten, CHECKPOINT_FILE};
pub use runner::{resume_scene, run_scene, run_scene_with, RunEvent, RunFailure, RunOptions, RunSummary};
