//! The file formats of a run, knowing no loam crate: the output writers (`output`: VTU
//! frames, the PVD collection, CSV tables and logs, SVG plots), the output folder's
//! bookkeeping (`output_dir`), the plots drawn from a run's CSV files (`run_plots`) and the
//! checkpoint container (`checkpoint`: named arrays of numbers and text, checksummed). What
//! goes into them is the runner's (`loam-run`).

pub mod checkpoint;
pub mod output;
pub mod output_dir;
pub mod run_plots;

pub use output_dir::{clear_output_dir, prepare_output_dir, OutputDirError};
pub use run_plots::plot_run;
