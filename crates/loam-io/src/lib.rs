//! Everything that knows a file format: the RON scene schema and its validation
//! (`scene`), the output writers (`output`: VTU, PVD, CSV, SVG plots), the output folder's
//! bookkeeping (`output_dir`), the plots of a run (`run_plots`), the checkpoint file format
//! (`checkpoint`) and what a checkpoint holds of a run (`restart`), and the runner that ties
//! a scene to an analysis and its outputs (`runner`), over the three analyses behind one
//! stepping interface (`loam_analysis`).

pub mod checkpoint;
pub mod output;
pub mod output_dir;
mod point_fields;
pub mod restart;
pub mod run_plots;
pub mod runner;
pub mod scene;

pub use loam_analysis::{Analysis, AnalysisError, Progress};
pub use output_dir::{clear_output_dir, prepare_output_dir, OutputDirError};
pub use point_fields::write_points_csv;
pub use restart::{checkpoint_interval, checkpoint_scene, CheckpointEvery, CheckpointWritten, CHECKPOINT_FILE};
pub use run_plots::plot_run;
pub use runner::{resume_scene, run_scene, run_scene_with, RunEvent, RunFailure, RunOptions, RunSummary};
pub use scene::{LoadedScene, Scene, SceneError};
