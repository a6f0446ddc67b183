//! Running a scene end to end with its outputs: a VTU frame per output step collected in a
//! PVD file, a run log (one CSV row per load step, flushed as it goes) and
//! `points_final.csv` after the last step. A run that fails mid-way keeps every file
//! written so far; the error says which step failed and why.

use crate::output::{write_csv_table, write_vtu, CsvCell, CsvWriter, OutputError, PointCloud, PvdWriter};
use crate::scene::{LoadedScene, SceneError};
use loam_implicit::{Model, QuasiStatic, RunError, StepError, StepReport};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Why a run stopped.
#[derive(Debug, thiserror::Error)]
pub enum RunFailure {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Analysis(#[from] StepError),
    #[error("output: {0}")]
    Output(#[from] OutputError),
    #[error("cannot create the output folder {}: {source}", path.display())]
    OutputDir { path: PathBuf, source: std::io::Error },
}

/// What a finished run did.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub steps: usize,
    pub points: usize,
    pub newton_iterations: usize,
    pub max_iterations_per_step: usize,
    pub cutbacks: usize,
    pub wall_time: Duration,
    pub solver: String,
    pub output_dir: PathBuf,
}

/// Run a scene, writing its outputs into `out_dir`; `progress` is called after each step.
pub fn run_scene(
    scene: &LoadedScene,
    out_dir: &Path,
    progress: &mut dyn FnMut(&StepReport, usize),
) -> Result<RunSummary, RunFailure> {
    match scene.scene.dimension {
        3 => run_dim::<3>(scene, out_dir, progress),
        _ => run_dim::<2>(scene, out_dir, progress),
    }
}

fn run_dim<const D: usize>(
    scene: &LoadedScene,
    out_dir: &Path,
    progress: &mut dyn FnMut(&StepReport, usize),
) -> Result<RunSummary, RunFailure> {
    let start = Instant::now();
    let mut analysis: QuasiStatic<D> = scene.build::<D>()?;
    std::fs::create_dir_all(out_dir).map_err(|source| RunFailure::OutputDir { path: out_dir.to_owned(), source })?;
    let out = &scene.scene.output;
    let total = analysis.settings().load_steps;
    let mut log = CsvWriter::create(
        &out_dir.join("run_log.csv"),
        &[
            "step",
            "load_factor",
            "substeps",
            "cutbacks",
            "iterations",
            "final_residual",
            "active_nodes",
            "dofs",
            "wall_time_s",
        ],
    )?;
    let mut pvd = if out.vtu_every > 0 { Some(PvdWriter::create(&out_dir.join("points.pvd"))?) } else { None };
    if let Some(pvd) = pvd.as_mut() {
        write_frame(analysis.model(), out_dir, pvd, 0, 0.0)?;
    }
    let (mut iterations, mut max_its, mut cutbacks) = (0, 0, 0);
    let result = analysis.run(|r, model| -> Result<(), OutputError> {
        iterations += r.iterations;
        max_its = max_its.max(r.iterations);
        cutbacks += r.cutbacks;
        log.row_mixed(&[
            CsvCell::Int(r.step as i64),
            CsvCell::Float(r.load_factor),
            CsvCell::Int(r.substeps as i64),
            CsvCell::Int(r.cutbacks as i64),
            CsvCell::Int(r.iterations as i64),
            CsvCell::Float(r.final_residual()),
            CsvCell::Int(r.active_nodes as i64),
            CsvCell::Int(r.dofs as i64),
            CsvCell::Float(r.wall_time.as_secs_f64()),
        ])?;
        if let Some(pvd) = pvd.as_mut() {
            if r.step % out.vtu_every == 0 || r.step == total {
                write_frame(model, out_dir, pvd, r.step, r.load_factor)?;
            }
        }
        progress(r, total);
        Ok(())
    });
    match result {
        Ok(()) => {}
        Err(RunError::Step(e)) => return Err(e.into()),
        Err(RunError::Observer(e)) => return Err(e.into()),
    }
    if out.final_csv {
        write_points_csv(analysis.model(), &out_dir.join("points_final.csv"))?;
    }
    Ok(RunSummary {
        steps: analysis.steps_done(),
        points: analysis.model().points.len(),
        newton_iterations: iterations,
        max_iterations_per_step: max_its,
        cutbacks,
        wall_time: start.elapsed(),
        solver: analysis.linear_solver_kind().to_string(),
        output_dir: out_dir.to_owned(),
    })
}

/// Flattened per-point fields shared by the VTU and CSV writers.
struct Fields {
    position: Vec<f64>,
    displacement: Vec<f64>,
    stress: Vec<f64>,
}

fn fields<const D: usize>(model: &Model<D>) -> Fields {
    let pts = &model.points;
    let flat = |v: &[nalgebra::SVector<f64, D>]| v.iter().flat_map(|x| x.iter().copied()).collect::<Vec<f64>>();
    let position = flat(&pts.position);
    let position0 = flat(&pts.position0);
    let displacement = position.iter().zip(&position0).map(|(x, x0)| x - x0).collect();
    let stress = pts
        .stress
        .iter()
        .flat_map(|s| [s[(0, 0)], s[(1, 1)], s[(2, 2)], s[(0, 1)], s[(1, 2)], s[(0, 2)]])
        .collect();
    Fields { position, displacement, stress }
}

fn write_frame<const D: usize>(
    model: &Model<D>,
    out_dir: &Path,
    pvd: &mut PvdWriter,
    step: usize,
    load_factor: f64,
) -> Result<(), OutputError> {
    let f = fields(model);
    let material: Vec<f64> = model.points.material.iter().map(|&m| m as f64).collect();
    let cloud = PointCloud::new(D, &f.position)
        .with_scalar("volume", &model.points.volume)
        .with_scalar("mass", &model.points.mass)
        .with_scalar("material", &material)
        .with_vector("displacement", &f.displacement)
        .with_tensor("stress", &f.stress);
    let name = format!("points_{step:05}.vtu");
    write_vtu(&out_dir.join(&name), &cloud)?;
    pvd.add(load_factor, &name)
}

/// `points_final.csv`: one row per point with initial and current position, stress
/// (xx, yy, zz, xy[, yz, xz]), initial and current volume, and mass.
pub fn write_points_csv<const D: usize>(model: &Model<D>, path: &Path) -> Result<(), OutputError> {
    let pts = &model.points;
    let n = pts.len();
    let axes = ["x", "y", "z"];
    let mut header: Vec<String> = Vec::new();
    let mut columns: Vec<Vec<f64>> = Vec::new();
    for a in 0..D {
        header.push(format!("{}0", axes[a]));
        columns.push(pts.position0.iter().map(|x| x[a]).collect());
    }
    for a in 0..D {
        header.push(axes[a].to_string());
        columns.push(pts.position.iter().map(|x| x[a]).collect());
    }
    let mut comps = vec![("sxx", 0, 0), ("syy", 1, 1), ("szz", 2, 2), ("sxy", 0, 1)];
    if D == 3 {
        comps.extend([("syz", 1, 2), ("sxz", 0, 2)]);
    }
    for (name, i, j) in comps {
        header.push(name.to_string());
        columns.push(pts.stress.iter().map(|s| s[(i, j)]).collect());
    }
    header.extend(["volume0", "volume", "mass"].map(String::from));
    columns.push(pts.volume0.clone());
    columns.push(pts.volume.clone());
    columns.push(pts.mass.clone());
    debug_assert!(columns.iter().all(|c| c.len() == n));
    let header_refs: Vec<&str> = header.iter().map(|s| s.as_str()).collect();
    let column_refs: Vec<&[f64]> = columns.iter().map(|c| c.as_slice()).collect();
    write_csv_table(path, &header_refs, &column_refs)
}
