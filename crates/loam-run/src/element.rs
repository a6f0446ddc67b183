//! Running an element test (`loam element FILE`): the path step by step, `element.csv`
//! written row by row (a law that fails keeps the rows before it), and the two plots of
//! the path, `element_strain.svg` (q against the path's strain) and `element_pq.svg` (the
//! stress path in p′–q).

use loam_constitutive::{ElementPath, ElementTest};
use loam_format::output::plot::{Plot, Series};
use loam_format::output::{CsvWriter, OutputError};
use loam_scene::{ElementRun, LoadedElementTest, SceneError};
use std::path::{Path, PathBuf};

/// Why an element test did not run to its end.
#[derive(Debug, thiserror::Error)]
pub enum ElementFailure {
    #[error(transparent)]
    Test(#[from] SceneError),
    #[error("output: {0}")]
    Output(#[from] OutputError),
    #[error("{0}: {1}")]
    File(PathBuf, std::io::Error),
    #[error("step {step} of {steps}: the law failed ({message}); element.csv and the plots hold the steps before it")]
    Law { step: usize, steps: usize, message: String },
}

/// What a finished element test reached: its steps and the last p′ and q.
#[derive(Debug, Clone, Copy)]
pub struct ElementSummary {
    pub steps: usize,
    pub p: f64,
    pub q: f64,
}

/// Run the element test in `test`, writing its outputs in `out_dir` (created if need be).
pub fn run_element(test: &LoadedElementTest, out_dir: &Path) -> Result<ElementSummary, ElementFailure> {
    let run = test.build()?;
    std::fs::create_dir_all(out_dir).map_err(|e| ElementFailure::File(out_dir.to_owned(), e))?;
    let mut point = ElementTest::new(run.law.as_ref(), run.initial_stress).map_err(|e| ElementFailure::Law {
        step: 0,
        steps: run.steps,
        message: e.to_string(),
    })?;
    let names = run.law.history_names();
    let strain_name = strain_column(run.path);
    let mut header =
        vec!["step", strain_name, "volumetric_strain", "p", "q", "stress_xx", "stress_yy", "stress_zz", "stress_xz"];
    header.extend(names);
    let mut csv = CsvWriter::create(out_dir.join("element.csv"), &header)?;
    let mut curve = vec![row(&point, run.path, 0)];
    csv.row(&curve[0])?;
    let mut failure = None;
    // Every step of a path holds the same: its strain increments and the starting stresses.
    let held = run.path.held(run.increment, &run.initial_stress);
    for step in 1..=run.steps {
        if let Err(e) = point.step(held) {
            failure = Some(ElementFailure::Law { step, steps: run.steps, message: e.to_string() });
            break;
        }
        curve.push(row(&point, run.path, step));
        csv.row(curve.last().expect("pushed"))?;
    }
    drop(csv);
    plots(&run, &curve, out_dir)?;
    if let Some(f) = failure {
        return Err(f);
    }
    let (p, q) = point.p_q();
    Ok(ElementSummary { steps: run.steps, p, q })
}

/// The CSV name of the strain a path is driven by.
fn strain_column(path: ElementPath) -> &'static str {
    match path {
        ElementPath::SimpleShear => "shear_strain",
        _ => "axial_strain",
    }
}

/// One row of element.csv: the step, the path's strain and the volumetric strain
/// (compression positive; 0 − x, so that no −0 is written), p′, q, the stresses, the law's
/// history.
fn row(point: &ElementTest, path: ElementPath, step: usize) -> Vec<f64> {
    let (e, s) = (point.strain(), point.stress());
    let strain = match path {
        ElementPath::SimpleShear => 2.0 * e[(0, 2)],
        _ => 0.0 - e[(2, 2)],
    };
    let (p, q) = point.p_q();
    let mut r = vec![step as f64, strain, 0.0 - e.trace(), p, q, s[(0, 0)], s[(1, 1)], s[(2, 2)], s[(0, 2)]];
    r.extend_from_slice(point.history());
    r
}

/// q against the path's strain, and the stress path in p′–q.
fn plots(run: &ElementRun, curve: &[Vec<f64>], out_dir: &Path) -> Result<(), ElementFailure> {
    let title = if run.title.is_empty() { run.law.name().to_string() } else { run.title.clone() };
    let strain = strain_column(run.path).replace('_', " ");
    let mut by_strain = Plot::new(format!("{title}: q against {strain}"), strain, "q");
    by_strain.series.push(Series::new(run.law.name(), curve.iter().map(|r| (r[1], r[4])).collect()));
    let mut stress_path = Plot::new(format!("{title}: stress path"), "p′", "q");
    stress_path.series.push(Series::new(run.law.name(), curve.iter().map(|r| (r[3], r[4])).collect()));
    for (plot, name) in [(by_strain, "element_strain.svg"), (stress_path, "element_pq.svg")] {
        let path = out_dir.join(name);
        plot.write(&path).map_err(|e| ElementFailure::File(path, e))?;
    }
    Ok(())
}
