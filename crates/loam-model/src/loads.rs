//! Loads beside gravity (docs/theory.md §17): forces at points, and tractions and pressures
//! on the material's surface. A load lives on the material, not on grid planes: its
//! vertices start on the boundary of a body, each carried by its nearest material point p
//! at x_v = x_p + diag(F_p) (X_v − X_p), so the surface moves and stretches with the points' own
//! motion and deformation (on a GIMP point's domain face the vertex stays on that face);
//! each vertex carries its share of the facets around it, which the analyses spread to
//! the nodes through the basis at its place.
//!
//! A load follows the load factor of a quasi-static analysis and its [`TimeFunction`] in
//! dynamic and explicit ones. Dead loads keep the force of the initial configuration; a
//! follower pressure acts on the current facets (it turns and stretches with the surface).

use loam_grid::Grid;
use loam_points::{area_vector, Surface};
use nalgebra::{Matrix3, SVector};

/// How a load's magnitude varies in time (dynamic and explicit analyses): the factor that
/// multiplies its full value.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum TimeFunction {
    /// In full from t = 0.
    #[default]
    Constant,
    /// Linearly from 0 at t = 0 to 1 at t = `duration`, then held.
    Ramp { duration: f64 },
    /// Piecewise linear through (time, factor) pairs, times increasing; held before the
    /// first time and after the last.
    Table(Vec<(f64, f64)>),
}

impl TimeFunction {
    /// Why the function is not valid, if it is not.
    pub fn check(&self) -> Result<(), String> {
        match self {
            TimeFunction::Constant => Ok(()),
            TimeFunction::Ramp { duration } if duration.is_finite() && *duration > 0.0 => Ok(()),
            TimeFunction::Ramp { duration } => Err(format!("ramp duration {duration}; it must be a positive number")),
            TimeFunction::Table(rows) => {
                if rows.is_empty() {
                    return Err("a table needs at least one (time, factor) pair".into());
                }
                if let Some(k) = rows.iter().position(|(t, f)| !(t.is_finite() && f.is_finite())) {
                    return Err(format!("pair {k} is not finite"));
                }
                match rows.windows(2).position(|w| w[1].0 <= w[0].0) {
                    Some(k) => Err(format!(
                        "times must increase: pair {} has time {} after {}",
                        k + 1,
                        rows[k + 1].0,
                        rows[k].0
                    )),
                    None => Ok(()),
                }
            }
        }
    }

    /// The factor at time `t`.
    pub fn at(&self, t: f64) -> f64 {
        match self {
            TimeFunction::Constant => 1.0,
            TimeFunction::Ramp { duration } => (t / duration).clamp(0.0, 1.0),
            TimeFunction::Table(rows) => piecewise_linear(rows, t).0,
        }
    }

    /// ∫₀ᵗ f(s) ds for t ≥ 0: what a velocity scaled by the function has moved by t.
    pub fn integral(&self, t: f64) -> f64 {
        match self {
            TimeFunction::Constant => t,
            TimeFunction::Ramp { duration } if t <= *duration => 0.5 * t * t / duration,
            TimeFunction::Ramp { duration } => t - 0.5 * duration,
            TimeFunction::Table(rows) => {
                // The trapezoids of the pieces up to t, with f held before the first time.
                let mut knots = vec![(0.0, piecewise_linear(rows, 0.0).0)];
                knots.extend(rows.iter().copied().filter(|&(s, _)| s > 0.0 && s < t));
                knots.push((t, piecewise_linear(rows, t).0));
                knots.windows(2).map(|w| 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0)).sum()
            }
        }
    }

    /// The least and greatest of ∫₀ᵗ f over 0 ≤ t ≤ `end`: the integral is extreme at the
    /// ends, at a table's times and where f changes sign between them (f is linear there).
    pub fn integral_range(&self, end: f64) -> (f64, f64) {
        let mut times = vec![0.0, end.max(0.0)];
        if let TimeFunction::Table(rows) = self {
            times.extend(rows.iter().map(|&(t, _)| t).filter(|&t| t > 0.0 && t < end));
            for w in rows.windows(2) {
                let ((t0, f0), (t1, f1)) = (w[0], w[1]);
                if f0 * f1 < 0.0 {
                    times.push(t0 + (t1 - t0) * f0 / (f0 - f1));
                }
            }
        }
        let values = times.iter().filter(|&&t| t <= end.max(0.0)).map(|&t| self.integral(t));
        values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| (lo.min(v), hi.max(v)))
    }
}

/// The piecewise-linear function through `rows` (abscissae increasing) at `x`, held level
/// before the first and after the last: its value and slope.
pub(crate) fn piecewise_linear(rows: &[(f64, f64)], x: f64) -> (f64, f64) {
    let k = rows.partition_point(|(xi, _)| *xi <= x);
    match k {
        0 => (rows[0].1, 0.0),
        k if k == rows.len() => (rows[k - 1].1, 0.0),
        k => {
            let ((x0, y0), (x1, y1)) = (rows[k - 1], rows[k]);
            let slope = (y1 - y0) / (x1 - x0);
            (y0 + slope * (x - x0), slope)
        }
    }
}

/// Where an analysis stands when it asks for its loads: a quasi-static load factor, or the
/// time of a dynamic or explicit analysis (gravity and point forces then act in full).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LoadLevel {
    Factor(f64),
    Time(f64),
}

impl LoadLevel {
    /// The factor on gravity and the per-point forces.
    pub fn body_factor(&self) -> f64 {
        match *self {
            LoadLevel::Factor(lambda) => lambda,
            LoadLevel::Time(_) => 1.0,
        }
    }

    /// The factor on a load with time function `time`.
    pub fn factor(&self, time: &TimeFunction) -> f64 {
        match *self {
            LoadLevel::Factor(lambda) => lambda,
            LoadLevel::Time(t) => time.at(t),
        }
    }
}

/// What a load applies at full value.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadKind<const D: usize> {
    /// A force at a single vertex.
    Force(SVector<f64, D>),
    /// A traction per unit initial area on every facet, dead.
    Traction(SVector<f64, D>),
    /// A pressure (positive pushes into the body) given at every vertex, on the initial
    /// facets (dead) or the current ones (`follower`, finite strain).
    Pressure { values: Vec<f64>, follower: bool },
}

/// One load: its surface (a single vertex and no facet for a force), the vertices' current
/// places, what it applies and its time function.
#[derive(Debug, Clone, PartialEq)]
pub struct Load<const D: usize> {
    surface: Surface<D>,
    position: Vec<SVector<f64, D>>,
    kind: LoadKind<D>,
    time: TimeFunction,
    /// Per vertex, the force at full value on the initial facets.
    dead: Vec<SVector<f64, D>>,
    /// Per vertex, the material point that carries it and X_v − X_p (set when the load is
    /// put on a model).
    carrier: Vec<u32>,
    offset: Vec<SVector<f64, D>>,
    /// Whether the surface is the meridian of a surface of revolution (an axisymmetric
    /// model's, [`Load::revolve`]).
    revolved: bool,
}

impl<const D: usize> Load<D> {
    /// A force at `at`.
    pub fn force(at: SVector<f64, D>, force: SVector<f64, D>, time: TimeFunction) -> Result<Self, String> {
        let surface = Surface { vertices: vec![at], facets: Vec::new() };
        Self::new(surface, LoadKind::Force(force), time)
    }

    /// A dead traction `traction` per unit area on `surface`.
    pub fn traction(surface: Surface<D>, traction: SVector<f64, D>, time: TimeFunction) -> Result<Self, String> {
        Self::new(surface, LoadKind::Traction(traction), time)
    }

    /// A pressure of `values` (one per vertex of `surface`), dead or follower.
    pub fn pressure(surface: Surface<D>, values: Vec<f64>, follower: bool, time: TimeFunction) -> Result<Self, String> {
        if values.len() != surface.vertices.len() {
            return Err(format!("{} pressures for {} vertices", values.len(), surface.vertices.len()));
        }
        Self::new(surface, LoadKind::Pressure { values, follower }, time)
    }

    fn new(surface: Surface<D>, kind: LoadKind<D>, time: TimeFunction) -> Result<Self, String> {
        time.check()?;
        if surface.vertices.is_empty() {
            return Err("the load has no vertex".into());
        }
        if !matches!(kind, LoadKind::Force(_)) && surface.facets.is_empty() {
            return Err("the load's surface has no facet".into());
        }
        let finite = match &kind {
            LoadKind::Force(f) | LoadKind::Traction(f) => f.iter().all(|v| v.is_finite()),
            LoadKind::Pressure { values, .. } => values.iter().all(|v| v.is_finite()),
        };
        if !finite || !surface.vertices.iter().flatten().all(|x| x.is_finite()) {
            return Err("its magnitude and vertices must be finite".into());
        }
        let mut load = Self {
            position: surface.vertices.clone(),
            surface,
            kind,
            time,
            dead: Vec::new(),
            carrier: Vec::new(),
            offset: Vec::new(),
            revolved: false,
        };
        let mut dead = Vec::new();
        load.forces_on(&load.surface.vertices, &mut dead);
        load.dead = dead;
        Ok(load)
    }

    /// The initial vertices and the facets.
    pub fn surface(&self) -> &Surface<D> {
        &self.surface
    }

    /// The vertices' current places.
    pub fn positions(&self) -> &[SVector<f64, D>] {
        &self.position
    }

    pub fn kind(&self) -> &LoadKind<D> {
        &self.kind
    }

    pub fn time_function(&self) -> &TimeFunction {
        &self.time
    }

    /// Whether the force depends on the vertices' current places.
    pub fn is_follower(&self) -> bool {
        matches!(self.kind, LoadKind::Pressure { follower: true, .. })
    }

    /// Per vertex, the force at full value on the initial configuration.
    pub fn dead_forces(&self) -> &[SVector<f64, D>] {
        &self.dead
    }

    /// Per vertex, the force at full value with the vertices at `x`: a traction's facet load
    /// shared equally among the facet's vertices; a pressure's vertex v takes p_v a_e / D of
    /// each facet e around it (the lumped load of a linearly varying pressure: the
    /// resultant exact, the moment to the facet size). On a surface of revolution
    /// ([`Load::revolve`]) a facet is a ring of area 2π r̄ a_e, and vertex v takes
    /// 2π (2 r_v + r_w) / 6 of a_e, r_w the radius of the facet's other vertex: the
    /// consistent load of a uniform traction, whose resultant is exact. Dead loads ignore
    /// `x`.
    pub fn forces_on(&self, x: &[SVector<f64, D>], out: &mut Vec<SVector<f64, D>>) {
        out.clear();
        out.resize(self.surface.vertices.len(), SVector::zeros());
        let x = if self.is_follower() { x } else { &self.surface.vertices };
        match &self.kind {
            LoadKind::Force(f) => out[0] = *f,
            LoadKind::Traction(t) => {
                for facet in &self.surface.facets {
                    let area = area_vector(&facet.map(|v| x[v as usize])).norm();
                    for (k, &v) in facet.iter().enumerate() {
                        out[v as usize] += t * self.portion(area, facet, k, x);
                    }
                }
            }
            LoadKind::Pressure { values, .. } => {
                for facet in &self.surface.facets {
                    let a = area_vector(&facet.map(|v| x[v as usize]));
                    for (k, &v) in facet.iter().enumerate() {
                        out[v as usize] -= a * self.portion(values[v as usize], facet, k, x);
                    }
                }
            }
        }
    }

    /// The part of `amount` (a facet's area, or a pressure on it) that the facet's vertex
    /// `k` takes: amount / D, or amount 2π (2 r_v + r_w) / 6 on a surface of revolution
    /// ([`Load::forces_on`]).
    #[inline]
    pub fn portion(&self, amount: f64, facet: &[u32; D], k: usize, x: &[SVector<f64, D>]) -> f64 {
        if !self.revolved {
            return amount / D as f64;
        }
        let (r_v, r_w) = (x[facet[k] as usize][0], x[facet[1 - k] as usize][0]);
        amount * std::f64::consts::TAU * (2.0 * r_v + r_w) / 6.0
    }

    /// ∂/∂x of [`Load::portion`] with respect to the place of the facet's vertex `slot`:
    /// zero on a plane surface; on a surface of revolution amount 2π · 2/6 (`slot` = `k`,
    /// the vertex's own radius) or 2π/6 (the other vertex's), along the radius.
    #[inline]
    pub fn portion_gradient(&self, amount: f64, k: usize, slot: usize) -> SVector<f64, D> {
        let mut g = SVector::zeros();
        if self.revolved {
            let weight = if slot == k { 2.0 } else { 1.0 };
            g[0] = amount * std::f64::consts::TAU * weight / 6.0;
        }
        g
    }

    /// Read the surface as the meridian of a surface of revolution about the y axis (an
    /// axisymmetric model's, x the radius), each facet a ring (2D only), or, `revolved`
    /// false, as a plane surface again.
    pub(crate) fn revolve(&mut self, revolved: bool) {
        debug_assert!(D == 2 || !revolved, "a surface of revolution has a 2D meridian");
        if revolved == self.revolved {
            // The dead forces are those the constructor (or the last call) computed.
            return;
        }
        self.revolved = revolved;
        let mut dead = Vec::new();
        self.forces_on(&self.surface.vertices, &mut dead);
        self.dead = dead;
    }

    /// The load's resultant on the current vertices at `scale` times its full value.
    pub fn resultant(&self, scale: f64) -> SVector<f64, D> {
        let mut f = Vec::new();
        self.forces_on(&self.position, &mut f);
        f.iter().sum::<SVector<f64, D>>() * scale
    }

    /// The point carrying each vertex.
    pub fn carriers(&self) -> &[u32] {
        &self.carrier
    }

    /// Where vertex `v` is when its carrier is at `x_p` with deformation gradient `f_p`:
    /// x_p + diag(F_p) (X_v − X_p), each axis of the offset stretched as the carrier's
    /// iGIMP domain is, without the shear, which would couple a vertex's height to its
    /// carrier's shear through a horizontal offset (docs/theory.md §17).
    #[inline]
    pub fn carried(&self, v: usize, x_p: &SVector<f64, D>, f_p: &Matrix3<f64>) -> SVector<f64, D> {
        let r = &self.offset[v];
        x_p + SVector::from_fn(|i, _| f_p[(i, i)] * r[i])
    }

    /// X_v − X_p of vertex `v`.
    pub fn offset(&self, v: usize) -> &SVector<f64, D> {
        &self.offset[v]
    }

    /// Attach every vertex to its nearest point of `positions` (the initial ones).
    pub(crate) fn attach(&mut self, grid: &Grid<D>, positions: &[SVector<f64, D>]) {
        self.carrier = nearest_points(grid, positions, &self.surface.vertices);
        self.offset =
            (self.surface.vertices.iter().zip(&self.carrier)).map(|(x, &p)| x - positions[p as usize]).collect();
    }

    /// Put the vertices at `positions` (a checkpoint's, one per vertex); `false`, and
    /// nothing changed, when the count differs.
    pub(crate) fn set_positions(&mut self, positions: &[SVector<f64, D>]) -> bool {
        if positions.len() != self.position.len() {
            return false;
        }
        self.position.copy_from_slice(positions);
        true
    }

    /// The first vertex whose carrier `new_index` drops (gives `None` for), if any.
    pub(crate) fn dropped_carrier(&self, new_index: impl Fn(usize) -> Option<usize>) -> Option<usize> {
        self.carrier.iter().position(|&p| new_index(p as usize).is_none())
    }

    /// Give every vertex's carrier its index in `new_index` (which keeps every carrier:
    /// [`Load::dropped_carrier`] first).
    pub(crate) fn renumber_carriers(&mut self, new_index: impl Fn(usize) -> Option<usize>) {
        for c in &mut self.carrier {
            *c = new_index(*c as usize).expect("checked: every carrier is kept") as u32;
        }
    }

    /// Put every vertex where its carrier now puts it.
    pub(crate) fn follow(&mut self, positions: &[SVector<f64, D>], f: &[Matrix3<f64>]) {
        for v in 0..self.position.len() {
            let p = self.carrier[v] as usize;
            self.position[v] = self.carried(v, &positions[p], &f[p]);
        }
    }
}

/// For each of `targets`, the index of the nearest of `points` (the lowest index among
/// equally near ones), searched cell ring by cell ring over the grid.
fn nearest_points<const D: usize>(grid: &Grid<D>, points: &[SVector<f64, D>], targets: &[SVector<f64, D>]) -> Vec<u32> {
    let cell_of = |x: &SVector<f64, D>| grid.cell_index(grid.cell_coords(x));
    let mut by_cell: Vec<(usize, u32)> = points.iter().enumerate().map(|(p, x)| (cell_of(x), p as u32)).collect();
    by_cell.sort_unstable();
    let cells = grid.cells();
    targets
        .iter()
        .map(|x| {
            let centre = grid.cell_coords(x);
            let mut best: Option<(f64, u32)> = None;
            let reach = *cells.iter().max().unwrap_or(&1);
            for ring in 0..=reach {
                // A point in ring r is at least (r − 1) cells away: stop one ring after a find.
                if let Some((d, _)) = best {
                    let h_min = grid.cell_size().min();
                    if d.sqrt() < (ring as f64 - 1.0) * h_min {
                        break;
                    }
                }
                for_ring(centre, ring, cells, |ijk| {
                    let c = grid.cell_index(ijk);
                    let start = by_cell.partition_point(|&(cell, _)| cell < c);
                    for &(_, p) in by_cell[start..].iter().take_while(|&&(cell, _)| cell == c) {
                        let d = (points[p as usize] - x).norm_squared();
                        if best.is_none_or(|(bd, bp)| d < bd || (d == bd && p < bp)) {
                            best = Some((d, p));
                        }
                    }
                });
            }
            best.expect("a model has points").1
        })
        .collect()
}

/// Call `visit` for every cell of the grid at Chebyshev distance exactly `ring` from `centre`.
fn for_ring<const D: usize>(centre: [usize; D], ring: usize, cells: [usize; D], mut visit: impl FnMut([usize; D])) {
    let lo: [usize; D] = std::array::from_fn(|a| centre[a].saturating_sub(ring));
    let hi: [usize; D] = std::array::from_fn(|a| (centre[a] + ring).min(cells[a] - 1));
    let dims: [usize; D] = std::array::from_fn(|a| hi[a] - lo[a] + 1);
    for k in 0..dims.iter().product() {
        let off = loam_grid::lexicographic_coords(k, dims);
        let ijk: [usize; D] = std::array::from_fn(|a| lo[a] + off[a]);
        if (0..D).any(|a| ijk[a].abs_diff(centre[a]) == ring) {
            visit(ijk);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use loam_points::Shape;
    use nalgebra::Vector2;

    #[test]
    fn time_functions_interpolate_and_refuse_bad_tables() {
        assert_eq!(TimeFunction::Constant.at(-1.0), 1.0);
        assert_eq!(TimeFunction::Ramp { duration: 2.0 }.at(0.5), 0.25);
        assert_eq!(TimeFunction::Ramp { duration: 2.0 }.at(3.0), 1.0);
        let table = TimeFunction::Table(vec![(0.0, 0.0), (1.0, 2.0), (3.0, 0.0)]);
        assert!(table.check().is_ok());
        assert_eq!(table.at(0.5), 1.0);
        assert_eq!(table.at(2.0), 1.0);
        assert_eq!(table.at(-1.0), 0.0);
        assert_eq!(table.at(4.0), 0.0);
        assert!(TimeFunction::Table(vec![(0.0, 0.0), (0.0, 1.0)]).check().unwrap_err().contains("increase"));
        assert!(TimeFunction::Table(vec![]).check().is_err());
        assert!(TimeFunction::Ramp { duration: 0.0 }.check().is_err());
        assert_eq!(LoadLevel::Factor(0.3).factor(&TimeFunction::Ramp { duration: 1.0 }), 0.3);
        assert_eq!(LoadLevel::Time(0.5).body_factor(), 1.0);
        // Integrals: the areas under each, by hand.
        assert_eq!(TimeFunction::Constant.integral(2.5), 2.5);
        assert_eq!(TimeFunction::Ramp { duration: 2.0 }.integral(1.0), 0.25);
        assert_eq!(TimeFunction::Ramp { duration: 2.0 }.integral(3.0), 2.0);
        assert_eq!(table.integral(0.5), 0.25);
        assert_eq!(table.integral(2.0), 2.5);
        assert_eq!(table.integral(4.0), 3.0);
        let late = TimeFunction::Table(vec![(1.0, 2.0), (2.0, 0.0)]);
        assert_eq!(late.integral(1.5), 2.0 + 0.75);
        // Range of the integral of a motion out (f = 1) and back (f = −1), by hand: it peaks
        // where f changes sign, at t = 1.5 (1 + ½ · 0.5 · 1 = 1.25), and is back at 0 at t = 3;
        // to t = 1.2 it only rises (1 + 0.2 (1 + 0.6)/2 = 1.16).
        let there_and_back = TimeFunction::Table(vec![(0.0, 1.0), (1.0, 1.0), (2.0, -1.0), (3.0, -1.0)]);
        assert_eq!(there_and_back.integral_range(3.0), (0.0, 1.25));
        let (lo, hi) = there_and_back.integral_range(1.2);
        assert!(lo == 0.0 && (hi - 1.16).abs() < 1e-15, "{lo} {hi}");
        assert_eq!(TimeFunction::Constant.integral_range(2.0), (0.0, 2.0));
    }

    /// A uniform pressure p on the top of a box: resultant −p × width, shared equally
    /// among interior vertices (p h) and by half at the ends; a follower pressure on a
    /// surface turned by 90° turns its resultant with it.
    #[test]
    fn pressure_shares_and_follows() {
        let top = Shape::Box { min: Vector2::new(0.0, 0.0), max: Vector2::new(2.0, 1.0) }
            .boundary(0.5)
            .unwrap()
            .select(|c| c[1] > 0.99);
        let n = top.vertices.len();
        let load = Load::pressure(top, vec![3.0; n], true, TimeFunction::Constant).unwrap();
        assert_eq!(load.resultant(0.5), Vector2::new(0.0, -3.0));
        let shares: Vec<f64> = load.dead_forces().iter().map(|f| f[1]).collect();
        assert!(shares.iter().all(|&s| s == -1.5 || s == -0.75), "{shares:?}");
        let turned: Vec<_> = load.positions().iter().map(|x| Vector2::new(-x[1], x[0])).collect();
        let mut f = Vec::new();
        load.forces_on(&turned, &mut f);
        let r: Vector2<f64> = f.iter().sum();
        assert!((r - Vector2::new(6.0, 0.0)).norm() < 1e-14, "{r}");
        assert!(Load::pressure(Surface::<2>::default(), vec![], false, TimeFunction::Constant).is_err());
        assert!(Load::force(Vector2::zeros(), Vector2::new(f64::NAN, 0.0), TimeFunction::Constant).is_err());
    }
}
