//! The plots of a run, drawn from the CSV files it wrote (`loam plot DIR`, and `loam run`
//! at its end, whether or not the run finished): people would rather look at a
//! load–settlement curve than compute it from a reaction column.
//!
//! - `run_log.svg`: Newton iterations and cut-backs per step against the load factor or
//!   time (explicit runs: the time step);
//! - `load_displacement.svg`: each prescribed displacement's reaction against it (the
//!   footing's load–settlement curve), where the run has one;
//! - `monitors.svg`: each monitoring point's displacement against the load factor or time;
//! - `plane_forces.svg`: the force of each inclined roller and frictional plane on the
//!   material against the load factor or time (a landslide's force on a wall);
//! - `energies.svg`: kinetic, strain and total energy and the external work against time;
//! - `strength_reduction.svg`: the factor of each trial, held or failed.

use crate::output::plot::{Plot, Series};
use std::path::{Path, PathBuf};

/// The names of the plots, for the output folder's bookkeeping.
pub const PLOT_FILES: [&str; 6] = [
    "run_log.svg",
    "load_displacement.svg",
    "monitors.svg",
    "plane_forces.svg",
    "energies.svg",
    "strength_reduction.svg",
];

/// A CSV file of numbers: its header and its rows (a cell that is not a number reads NaN,
/// and NaN is not drawn).
struct Table {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Table {
    /// The table in `path`, or `None` if there is no such file.
    fn read(path: &Path) -> std::io::Result<Option<Self>> {
        let text = match std::fs::read_to_string(path) {
            Ok(text) => text,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(e),
        };
        let mut lines = text.lines();
        let header = lines.next().unwrap_or("").split(',').map(|s| s.trim().to_string()).collect();
        let parse = |line: &str| line.split(',').map(|c| c.trim().parse().unwrap_or(f64::NAN)).collect();
        Ok(Some(Self { header, rows: lines.filter(|l| !l.trim().is_empty()).map(parse).collect() }))
    }

    fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.header.iter().position(|h| h == name)?;
        Some(self.rows.iter().map(|r| r.get(k).copied().unwrap_or(f64::NAN)).collect())
    }

    /// The series `y` against `x`, by column names.
    fn series(&self, label: &str, x: &str, y: &str) -> Option<Series> {
        let points = self.column(x)?.into_iter().zip(self.column(y)?).collect();
        Some(Series::new(label, points))
    }
}

/// Draw the plots of the run in `dir` from the CSV files there, beside them; returns the
/// files written (none where there is nothing to draw).
pub fn plot_run(dir: &Path) -> std::io::Result<Vec<PathBuf>> {
    let mut plots = Vec::new();
    if let Some(log) = Table::read(&dir.join("run_log.csv"))? {
        plots.extend(steps_plot(&log).map(|p| ("run_log.svg", p)));
        plots.extend(load_displacement_plot(&log).map(|p| ("load_displacement.svg", p)));
        plots.extend(monitors_plot(&log).map(|p| ("monitors.svg", p)));
        plots.extend(plane_forces_plot(&log).map(|p| ("plane_forces.svg", p)));
    }
    if let Some(history) = Table::read(&dir.join("history.csv"))? {
        plots.extend(energies_plot(&history).map(|p| ("energies.svg", p)));
    }
    if let Some(trials) = Table::read(&dir.join("strength_reduction.csv"))? {
        plots.extend(strength_reduction_plot(&trials).map(|p| ("strength_reduction.svg", p)));
    }
    let mut written = Vec::new();
    for (name, plot) in plots {
        let path = dir.join(name);
        plot.write(&path)?;
        written.push(path);
    }
    Ok(written)
}

/// Newton iterations and cut-backs per step, or the explicit time step.
fn steps_plot(log: &Table) -> Option<Plot> {
    let newton = log.column("iterations")?.iter().any(|&n| n > 0.0);
    let quasi_static = log.column("time")? == log.column("load_factor")?;
    let x = if quasi_static { "load factor" } else { "time" };
    let mut plot = if newton {
        let mut plot = Plot::new("Newton iterations and cut-backs per step", x, "count");
        plot.series.push(log.series("Newton iterations", "time", "iterations")?);
        plot.series.push(log.series("cut-backs", "time", "cutbacks")?.dashed());
        plot
    } else {
        let mut plot = Plot::new("Time step", x, "Δt");
        plot.series.push(log.series("Δt", "time", "increment")?);
        plot
    };
    plot.log_y = !newton;
    (!log.rows.is_empty()).then_some(plot)
}

/// Each prescribed displacement's reaction against it: every column pair
/// `<name><k>_displacement_<axis>` and `<name><k>_reaction_<axis>`, labelled "name k, axis".
fn load_displacement_plot(log: &Table) -> Option<Plot> {
    let mut plot = Plot::new("Reaction against prescribed displacement", "prescribed displacement", "reaction");
    for (held, axis) in log.header.iter().filter_map(|h| h.split_once("_displacement_")) {
        let name = held.trim_end_matches(|c: char| c.is_ascii_digit());
        let label = format!("{} {}, {axis}", name.replace('_', " "), &held[name.len()..]);
        let (u, f) = (format!("{held}_displacement_{axis}"), format!("{held}_reaction_{axis}"));
        // A column that only looks like one (a monitor named so) has no pair: skip it.
        let Some(series) = log.series(&label, &u, &f) else { continue };
        plot.series.push(series);
    }
    (!plot.series.is_empty()).then_some(plot)
}

/// Each monitoring point's displacement components (`monitor_<name>_u<axis>`) against
/// the load factor or time: a footing's load–settlement curve at its centre.
fn monitors_plot(log: &Table) -> Option<Plot> {
    let quasi_static = log.column("time")? == log.column("load_factor")?;
    let x = if quasi_static { "load factor" } else { "time" };
    let mut plot = Plot::new("Displacement of the monitoring points", x, "displacement");
    for column in log.header.iter().filter(|h| h.starts_with("monitor_")) {
        let Some((name, axis)) = column["monitor_".len()..].rsplit_once("_u") else { continue };
        if !["x", "y", "z"].contains(&axis) {
            continue;
        }
        plot.series.push(log.series(&format!("{name}, u{axis}"), "time", column)?);
    }
    (!plot.series.is_empty() && !log.rows.is_empty()).then_some(plot)
}

/// Each inclined roller's, frictional plane's and rigid body's force on the material
/// (`incline<k>_reaction_<axis>`, `frictional_plane<k>_reaction_<axis>`,
/// `rigid<k>_reaction_<axis>`) against the load factor or time.
fn plane_forces_plot(log: &Table) -> Option<Plot> {
    let quasi_static = log.column("time")? == log.column("load_factor")?;
    let x = if quasi_static { "load factor" } else { "time" };
    let mut plot = Plot::new("Force of the rigid planes and bodies on the material", x, "force");
    let rigid = |h: &str| h.starts_with("incline") || h.starts_with("frictional_plane") || h.starts_with("rigid");
    let planes = log.header.iter().filter(|h| rigid(h) && h.contains("_reaction_"));
    for column in planes {
        let Some((plane, axis)) = column.split_once("_reaction_") else { continue };
        let name = plane.trim_end_matches(|c: char| c.is_ascii_digit());
        let label = format!("{} {}, {axis}", name.replace('_', " "), &plane[name.len()..]);
        plot.series.push(log.series(&label, "time", column)?);
    }
    (!plot.series.is_empty() && !log.rows.is_empty()).then_some(plot)
}

/// The energy balance against time.
fn energies_plot(history: &Table) -> Option<Plot> {
    let mut plot = Plot::new("Energies", "time", "energy");
    for (label, column) in [
        ("kinetic", "kinetic_energy"),
        ("strain", "strain_energy"),
        ("external work", "external_work"),
        ("total (kinetic + strain − work)", "total_energy"),
    ] {
        plot.series.push(history.series(label, "time", column)?);
    }
    plot.series[2].dashed = true;
    (history.rows.len() > 1).then_some(plot)
}

/// The factor of each trial, those that held apart from those that failed.
fn strength_reduction_plot(trials: &Table) -> Option<Plot> {
    let (factor, stable) = (trials.column("factor")?, trials.column("stable")?);
    let trial = |held: bool| -> Vec<(f64, f64)> {
        (factor.iter().zip(&stable).enumerate())
            .filter(|(_, (_, &s))| (s == 1.0) == held)
            .map(|(k, (&f, _))| ((k + 1) as f64, f))
            .collect()
    };
    let mut plot = Plot::new("Strength reduction: the factor of each trial", "trial", "F");
    plot.series.push(Series::new("holds", trial(true)));
    plot.series.push(Series::new("fails", trial(false)).dashed());
    (!factor.is_empty()).then_some(plot)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// From hand-written logs: the plots that have something to draw are written, with
    /// the series named after what they show; a folder without logs gets none.
    #[test]
    fn the_plots_of_a_run_come_from_its_csv_files() {
        let dir = tempfile::tempdir().unwrap();
        let log =
            "step,time,load_factor,increment,iterations,cutbacks,constraint0_displacement_y,constraint0_reaction_y\n\
                   1,0.5,0.5,0.5,3,0,-0.05,-40.0\n2,1,1,0.5,4,1,-0.1,-51.0\n";
        std::fs::write(dir.path().join("run_log.csv"), log).unwrap();
        let trials = "factor,stable,load_factor\n1.0,1,1\n2.0,0,0.6\n1.5,1,1\n";
        std::fs::write(dir.path().join("strength_reduction.csv"), trials).unwrap();
        let written = plot_run(dir.path()).unwrap();
        let names: Vec<_> = written.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
        assert_eq!(names, ["run_log.svg", "load_displacement.svg", "strength_reduction.svg"]);
        let curve = std::fs::read_to_string(dir.path().join("load_displacement.svg")).unwrap();
        assert!(curve.contains("constraint 0, y") && curve.contains("<svg"));
        let empty = tempfile::tempdir().unwrap();
        assert!(plot_run(empty.path()).unwrap().is_empty());
    }
}
