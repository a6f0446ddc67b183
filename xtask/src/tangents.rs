//! `cargo xtask tangents`: export the linear systems the multigrid-preconditioned Krylov
//! solver meets, so that another preconditioner can be tried on the very same matrices
//! (`scripts/compare_preconditioners.py` runs PyAMG's smoothed aggregation on them;
//! docs/theory.md §19 gives the figures).
//!
//! A recording solver wraps the engine's `IterativeSolver` behind the `LinearSolver` trait.
//! It writes the first system of a run, and every system whose Krylov solve fails (which
//! the engine then solves by sparse LU). Each system is written restricted to its free dofs
//! as little-endian binary arrays: the compressed columns (`NAME.colptr`, i64;
//! `NAME.rowidx`, i32; `NAME.values`, f64), the right-hand side (`NAME.rhs`, f64) and, per
//! dof, the node's grid coordinates and the component (`NAME.coords`, 4 × f64). Beside the
//! engine's own solve, the recorder solves each system again with multigrid CG or
//! BiCGStab to the relative residual 1e-8 (at most 400 iterations) and writes the figures
//! to `systems.csv`.

use anyhow::{Context, Result};
use loam::analysis::Analysis;
use loam::implicit::{Kinematics, Model, QuasiStatic, QuasiStaticSettings};
use loam::solve::{
    IterativeSolver, LinearSolveError, LinearSolveStats, LinearSolver, LinearSolverChoice, LinearSolverKind,
    LinearSolverTimings, LinearSystem, MatrixLayout,
};
use loam_verification::{cut_block, layered_block};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// The relative residual of the comparison solves.
const TOLERANCE: f64 = 1e-8;

/// What a run records: the first system, and up to `failures` failed ones.
struct Recorder {
    inner: IterativeSolver,
    name: String,
    out: PathBuf,
    failures: usize,
    solves: usize,
    written: Arc<Mutex<Vec<String>>>,
}

impl Recorder {
    fn write(&self, tag: &str, system: &LinearSystem<'_>, rhs: &[f64], engine: &str) -> Result<()> {
        let name = format!("{}_{tag}", self.name);
        let pattern = system.pattern;
        let d = pattern.dofs_per_node();
        let values = system.matrix.to_columns(pattern);
        let (col_ptr, row_idx) = (pattern.col_ptr(), pattern.row_idx());
        let free: Vec<usize> = (0..pattern.num_dofs()).filter(|&i| !system.constrained[i]).collect();
        let mut index = vec![u32::MAX; pattern.num_dofs()];
        free.iter().enumerate().for_each(|(k, &i)| index[i] = k as u32);
        let (mut ptr, mut rows, mut vals) = (vec![0i64], Vec::new(), Vec::new());
        for &c in &free {
            for e in col_ptr[c]..col_ptr[c + 1] {
                if index[row_idx[e]] != u32::MAX && values[e] != 0.0 {
                    rows.push(index[row_idx[e]] as i32);
                    vals.push(values[e]);
                }
            }
            ptr.push(rows.len() as i64);
        }
        let lattice = system.lattice.context("the recorder needs the node lattice")?;
        let coords: Vec<f64> = free
            .iter()
            .flat_map(|&i| {
                let c = lattice.coordinates(i / d);
                [c[0] as f64, c[1] as f64, c[2] as f64, (i % d) as f64]
            })
            .collect();
        let b: Vec<f64> = free.iter().map(|&i| rhs[i]).collect();
        let path = |ext: &str| self.out.join(format!("{name}.{ext}"));
        write_le(&path("colptr"), ptr.iter().flat_map(|v| v.to_le_bytes()))?;
        write_le(&path("rowidx"), rows.iter().flat_map(|v| v.to_le_bytes()))?;
        write_le(&path("values"), vals.iter().flat_map(|v| v.to_le_bytes()))?;
        write_le(&path("rhs"), b.iter().flat_map(|v| v.to_le_bytes()))?;
        write_le(&path("coords"), coords.iter().flat_map(|v| v.to_le_bytes()))?;
        let again = self.solve_again(system, rhs);
        let line = format!("{name},{},{},{},{engine},{again}", free.len(), d, self.inner.kind());
        self.written.lock().unwrap().push(line);
        Ok(())
    }

    /// The same system with a fresh solver to `TOLERANCE`: iterations, relative residual
    /// (or the failure's), set-up and solve seconds.
    fn solve_again(&self, system: &LinearSystem<'_>, rhs: &[f64]) -> String {
        let mut solver = IterativeSolver::new(self.inner.kind());
        let t = Instant::now();
        if let Err(e) = solver.prepare(system) {
            return format!("set-up failed: {e},,,");
        }
        let setup = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let mut x = vec![0.0; rhs.len()];
        let outcome = solver.solve(system, rhs, &mut x, TOLERANCE);
        let solve = t.elapsed().as_secs_f64();
        match outcome {
            Ok(s) => format!("{},{:.2e},{setup:.3},{solve:.3}", s.iterations, s.residual),
            Err(LinearSolveError::NotConverged(f)) => format!("failed,{:.2e},{setup:.3},{solve:.3}", f.residual),
            Err(e) => format!("failed: {e},,{setup:.3},{solve:.3}"),
        }
    }
}

fn write_le(path: &Path, bytes: impl Iterator<Item = u8>) -> Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).with_context(|| format!("{}", path.display()))?);
    f.write_all(&bytes.collect::<Vec<u8>>())?;
    Ok(())
}

impl LinearSolver for Recorder {
    fn kind(&self) -> LinearSolverKind {
        self.inner.kind()
    }
    fn layout(&self) -> MatrixLayout {
        self.inner.layout()
    }
    fn wants_lattice(&self) -> bool {
        true
    }
    fn prepare(&mut self, system: &LinearSystem<'_>) -> Result<(), LinearSolveError> {
        self.inner.prepare(system)
    }
    fn solve(
        &mut self,
        system: &LinearSystem<'_>,
        rhs: &[f64],
        x: &mut [f64],
        rel_tol: f64,
    ) -> Result<LinearSolveStats, LinearSolveError> {
        self.solves += 1;
        let result = self.inner.solve(system, rhs, x, rel_tol);
        let engine = match &result {
            Ok(s) => format!("{} its to {rel_tol:.0e}", s.iterations),
            Err(_) => format!("failed at {rel_tol:.0e}"),
        };
        let tag = match &result {
            _ if self.solves == 1 => Some("first".to_string()),
            Err(_) if self.failures > 0 => {
                self.failures -= 1;
                Some(format!("failed{}", self.solves))
            }
            _ => None,
        };
        if let Some(tag) = tag {
            if let Err(e) = self.write(&tag, system, rhs, &engine) {
                eprintln!("{}: could not write the system: {e:#}", self.name);
            }
        }
        result
    }
    fn timings(&self) -> LinearSolverTimings {
        self.inner.timings()
    }
}

/// A block case: its name, how to build its model, and whether the direct solver runs it
/// too.
type BlockCase = (String, Box<dyn Fn() -> Model<3>>, bool);

/// The elastic blocks at three sizes, the layered blocks at a contrast of 10⁶ and the cut
/// block at three cuts with and without the ghost penalty.
fn block_cases() -> Vec<BlockCase> {
    let mut cases: Vec<BlockCase> = Vec::new();
    for n in [16, 24, 32] {
        let model = move || layered_block(n, Kinematics::FiniteStrain, true, 1.0);
        cases.push((format!("block{n}"), Box::new(model), false));
    }
    for n in [16, 24] {
        let model = move || layered_block(n, Kinematics::SmallStrain, true, 1e6);
        cases.push((format!("layered{n}_1e6"), Box::new(model), true));
    }
    for overlap in [1e-2, 1e-4, 1e-6] {
        for ghost in [None, Some(0.1)] {
            let name = format!("cut16_{overlap:.0e}{}", if ghost.is_some() { "_ghost" } else { "" });
            cases.push((name, Box::new(move || cut_block(16, overlap, ghost)), true));
        }
    }
    cases
}

/// One load step of `model` with `recorder` as its solver, and with the direct solver if
/// `with_direct`: the `steps.csv` row after the name.
fn one_step(model: &dyn Fn() -> Model<3>, with_direct: bool, recorder: Recorder) -> String {
    let settings = QuasiStaticSettings { load_steps: 1, ..Default::default() };
    let mut qs = QuasiStatic::new(model(), settings.clone());
    qs.set_linear_solver(Box::new(recorder));
    let iterative = match qs.step() {
        Ok(r) => format!("{},{},{}", r.iterations, r.linear_iterations, r.direct_fallbacks),
        Err(e) => format!("failed: {e},,"),
    };
    let direct = if with_direct {
        let settings = QuasiStaticSettings { linear_solver: LinearSolverChoice::Direct, ..settings };
        QuasiStatic::new(model(), settings).step().map_or_else(|e| format!("failed: {e}"), |r| r.iterations.to_string())
    } else {
        String::new()
    };
    format!("{iterative},{direct}")
}

/// Export the systems of the elastic 3D blocks, the layered block at a contrast of 10⁶, the
/// block with a small cut (with and without the ghost penalty) and the von Mises footing
/// near its mechanism into `out`; run one step of each block with the iterative solver (and
/// of the hard cases with the direct one too) into `steps.csv`.
pub fn run(out: &Path) -> Result<()> {
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let written = Arc::new(Mutex::new(Vec::new()));
    let recorder = |name: &str, kind, failures| Recorder {
        inner: IterativeSolver::new(kind),
        name: name.to_string(),
        out: out.to_path_buf(),
        failures,
        solves: 0,
        written: written.clone(),
    };
    let mut steps = String::from("system,iterative: Newton iterations,Krylov,fallbacks,direct: Newton iterations\n");
    for (name, model, with_direct) in block_cases() {
        let row = one_step(&model, with_direct, recorder(&name, LinearSolverKind::Cg, 0));
        println!("{name}: one step, {row}");
        steps += &format!("{name},{row}\n");
    }
    std::fs::write(out.join("steps.csv"), &steps)?;
    let path = Path::new("examples/footing_von_mises.ron");
    let scene = loam::scene::LoadedScene::parse(path, std::fs::read_to_string(path)?)?;
    let Analysis::QuasiStatic(mut qs) = scene.build::<2>()? else { anyhow::bail!("the footing is quasi-static") };
    qs.set_linear_solver(Box::new(recorder("footing_vm", LinearSolverKind::Cg, 3)));
    for _ in 0..3 {
        if let Err(e) = qs.step() {
            println!("footing_vm: {e}");
        }
    }
    let mut csv = String::from(
        "system,free dofs,dofs per node,method,engine's solve,iterations to 1e-8,residual,set-up s,solve s\n",
    );
    for line in written.lock().unwrap().iter() {
        csv += line;
        csv.push('\n');
    }
    std::fs::write(out.join("systems.csv"), &csv)?;
    print!("{csv}");
    Ok(())
}
