//! V8, the granular column collapse (docs/verification.md §V8): explicit MPM run until the
//! deposit is at rest, its height, flank slope and run-out against the experiments and the
//! infinite slope, and the checks of issue 19 that points at rest stop and the CFL step
//! comes back.

use crate::report::{Report, Row};
use anyhow::Result;
use loam::explicit::{Explicit, ExplicitSettings, TimeStep};
use loam::model::Model;
use loam_verification::granular::{bounds, GranularColumn};
use std::fmt::Write as _;
use std::time::Instant;

/// Simulated time: the collapse is over within about 0.3 s; the rest lets the deposit's
/// elastic ringing decay.
const DURATION: f64 = 1.5;

/// The deposit: its height at the wall, the toe (the farthest column of cells at least a
/// cell deep), the farthest point and the mean slope of the flank between them.
struct Deposit {
    height: f64,
    toe: f64,
    farthest: f64,
    flank_slope_deg: f64,
}

/// The highest point per column of cells and what it says.
fn deposit(model: &Model<2>) -> Deposit {
    let h = model.grid().cell_size()[0];
    let nx = model.grid().cells()[0];
    let mut top = vec![0.0f64; nx];
    let mut farthest = 0.0f64;
    for x in model.points().position() {
        let i = ((x[0] / h).max(0.0) as usize).min(nx - 1);
        top[i] = top[i].max(x[1]);
        farthest = farthest.max(x[0]);
    }
    let height = top[0];
    let toe_i = (0..nx).rev().find(|&i| top[i] >= h).unwrap_or(0);
    // The flank: from the last column within a cell of the top to the toe.
    let shoulder = (0..=toe_i).rev().find(|&i| top[i] >= height - h).unwrap_or(0);
    let run = (toe_i - shoulder).max(1) as f64 * h;
    let flank_slope_deg = ((top[shoulder] - top[toe_i]) / run).atan().to_degrees();
    Deposit { height, toe: (toe_i + 1) as f64 * h, farthest, flank_slope_deg }
}

/// The critical step of the wave speeds alone at the points' current densities,
/// min_p h / c_p with c_p = √(M / ρ_p): what the CFL step comes back to at rest (a loose,
/// dilated front has a lower density and a higher c_p than the column had).
fn wave_step(model: &Model<2>) -> f64 {
    let (pts, moduli) = (model.points(), model.constant_p_wave_moduli());
    let h = model.grid().cell_size().min();
    let c_max = (0..pts.len())
        .map(|p| (model.p_wave_modulus(&moduli, p) * pts.volume()[p] / pts.mass()[p]).sqrt())
        .fold(0.0, f64::max);
    h / c_max
}

/// V8 in the report: one run at 10 (quick) or 20 cells across H₀.
pub(crate) fn verify(quick: bool, report: &mut Report) -> Result<()> {
    let column = GranularColumn::V8;
    let cells = if quick { 10 } else { 20 };
    let h = column.height / cells as f64;
    eprintln!("verify: V8 granular column collapse, {cells} cells across H0");
    let settings =
        ExplicitSettings { flip: 0.99, time_step: TimeStep::Cfl { safety: 0.5 }, ..ExplicitSettings::new(DURATION) };
    let t = Instant::now();
    let mut ex = Explicit::new(column.model(cells), settings)?;
    let (mut peak, mut last, mut steps) = (0.0f64, (0.0, 0.0), 0);
    while !ex.is_finished() {
        let r = ex.step()?;
        let speed = ex.model().points().velocity().iter().map(|v| v.norm()).fold(0.0, f64::max);
        peak = peak.max(speed);
        (last, steps) = ((speed, r.critical_dt), r.step);
    }
    let wall = t.elapsed().as_secs_f64();
    let d = deposit(ex.model());
    let elastic = wave_step(ex.model());
    let (l0, h0) = (column.width, column.height);
    let runout = (d.toe - l0) / l0;
    let points = ex.model().points().len();
    writeln!(report.md, "## V8 granular column collapse\n\nA column of cohesionless soil (Mohr–Coulomb c = 0, φ = {}°, ψ = 0, E = {:e} Pa, ρ = {} kg/m³) L₀ = {l0} m wide and H₀ = {h0} m high (a = {}) against a smooth wall, on a rough base, released under gravity and run for {DURATION} s; {cells} cells across H₀ (h = {h} m), {points} points, GIMP, finite strain, explicit MUSL, CFL 0.5, FLIP fraction 0.99. Compared against: the deposit height H∞ = H₀ of quasi-2D experiments for a < 0.65 (Lube et al. 2005; Lajeunesse et al. 2005), a flank no steeper than φ (infinite slope at rest), and the experiments' run-out (L∞ − L₀)/L₀ = 1.2 a = {:.2} (sands and beads of φ ≈ 30°: compared, not bounded, as φ = 20° runs further). Toe: the farthest column of cells at least one cell deep. Wave step: min_p h / c_p at the points' final densities, the CFL step without the velocity term.\n", column.friction_deg, column.young, column.density, column.aspect_ratio(), column.experimental_runout())?;
    writeln!(report.md, "| steps | wall [s] | H∞ [m] | toe L∞ [m] | farthest point [m] | (L∞ − L₀)/L₀ | experiments | flank slope [°] | end speed / peak | Δt_c end / wave step |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    writeln!(
        report.md,
        "| {steps} | {wall:.1} | {:.4} | {:.3} | {:.3} | {runout:.2} | {:.2} | {:.1} | {:.1e} | {:.4} |\n",
        d.height,
        d.toe,
        d.farthest,
        column.experimental_runout(),
        d.flank_slope_deg,
        last.0 / peak,
        last.1 / elastic
    )?;
    let case = format!("V8 granular collapse {cells}/H0");
    report.rows.push(Row::checked(&case, "final_height_error_cells", (d.height - h0).abs() / h, bounds::FINAL_HEIGHT));
    let slope_ratio = d.flank_slope_deg.to_radians().tan() / column.friction_deg.to_radians().tan();
    report.rows.push(Row::checked(&case, "flank_tan_over_tan_phi", slope_ratio, bounds::FLANK_SLOPE));
    report.rows.push(Row::info(&case, "end_speed_over_peak", last.0 / peak));
    report.rows.push(Row::checked(
        &case,
        "critical_dt_change_at_rest",
        (last.1 / elastic - 1.0).abs(),
        bounds::CFL_AT_REST,
    ));
    report.rows.push(Row::info(&case, "runout_over_width", runout));
    report.rows.push(Row::info(&case, "wall_time_s", wall));
    Ok(())
}
