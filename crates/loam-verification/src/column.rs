//! V1: the self-weight column (`docs/verification.md` §V1). A column of initial height H₀
//! under its own weight, ν = 0, rollers on the sides and the base, so every cross-section
//! keeps its area and the problem is one-dimensional. Whatever the law, the vertical
//! Cauchy stress is the weight above, σ_yy = −ρ₀g(H₀ − Y). For Hencky elasticity the
//! stretch has the closed form λ = W(s)/s, s = ρ₀g(H₀ − Y)/E (W: Lambert's principal
//! branch), and the displacement is its integral; for small-strain linear elasticity it is
//! the parabola −(ρ₀g/E)(H₀Y − Y²/2). A dead surcharge q on the top face (the surcharged
//! column of §V1) adds q to the weight above at every height: σ_yy = −q − ρ₀g(H₀ − Y), and
//! the same closed forms hold with s = (q + ρ₀g(H₀ − Y))/E. The error norm e_σ is AMPLE's (Coombs & Augarde
//! 2020; Wyser et al. 2020). Also here: the layered column of the stiffness-contrast hard
//! case, whose displacement integrates σ/E layer by layer.

use crate::bound::Bound;
use loam_constitutive::{ConstitutiveLaw, Elastic};
use loam_grid::GaussLegendre;
use loam_grid::{BasisKind, FeMesh, Grid};
use loam_model::{Kinematics, Load, Model, PlaneConstraint, TimeFunction};
use loam_points::{PointStore, Shape};
use nalgebra::{SVector, Vector2};
use std::sync::Arc;

/// The bounds `cargo xtask verify` checks on the columns (`docs/verification.md` §V1,
/// "Bounds checked", and the column under sudden gravity in the dynamics section).
pub mod bounds {
    use super::Bound;

    /// Observed rate of e_σ over the finest three meshes, GIMP, V1a and V1c: peer codes
    /// measure 1.5–2 with GIMP; loam measures 1.55–1.58.
    pub const GIMP_RATE: Bound = Bound::lower(1.5, "docs/verification.md §V1: GIMP rate >= 1.5 (peers: 1.5-2)");
    /// e_σ at 64 cells, GIMP, V1a and V1c.
    pub const GIMP_E_SIGMA_64: Bound = Bound::upper(1e-3, "docs/verification.md §V1: GIMP e_sigma(64) <= 1e-3");
    /// Newton iterations per load step on V1c, every method.
    pub const V1C_NEWTON_ITERATIONS: Bound =
        Bound::upper(6.0, "docs/verification.md §V1: <= 6 Newton iterations per load step on V1c");
    /// V1a under suddenly applied gravity (implicit trapezoidal, 4 periods): e_σ of the
    /// time-averaged stress against the static closed form, which carries the static run's
    /// spatial error plus the part of the oscillation that does not average out.
    pub const SUDDEN_GRAVITY_E_SIGMA: Bound =
        Bound::upper(2e-2, "docs/verification.md §V1, the column under sudden gravity: time-averaged e_sigma");
    /// V1a under suddenly applied gravity: |largest top settlement / static − 2|, the
    /// dynamic amplification factor of a step load being 2.
    pub const SUDDEN_GRAVITY_AMPLIFICATION: Bound =
        Bound::upper(0.05, "docs/verification.md §V1, the column under sudden gravity: amplification factor 2");
}

/// Principal branch W₀ of the Lambert W function for x ≥ 0 (w e^w = x), by Halley's
/// iteration from a log-based start; converged to rounding.
pub fn lambert_w0(x: f64) -> f64 {
    assert!(x >= 0.0 && x.is_finite(), "lambert_w0 is implemented for finite x >= 0, got {x}");
    if x == 0.0 {
        return 0.0;
    }
    let mut w = if x < 1.0 {
        x / (1.0 + x)
    } else {
        (1.0 + x).ln() * (1.0 - (1.0 + (1.0 + x).ln()).ln() / (2.0 + (1.0 + x).ln()))
    };
    for _ in 0..50 {
        let ew = w.exp();
        let f = w * ew - x;
        let wp1 = w + 1.0;
        let step = f / (ew * wp1 - (w + 2.0) * f / (2.0 * wp1));
        w -= step;
        if step.abs() <= 1e-16 * w.abs().max(1e-300) {
            break;
        }
    }
    w
}

/// The self-weight column of V1: height `h0`, Young's modulus, density, gravity (ν = 0,
/// rollers on the sides so that the cross-section does not change).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Column {
    pub height: f64,
    pub young: f64,
    pub density: f64,
    pub gravity: f64,
    /// Dead pressure on the top face at full load (0: the self-weight column).
    pub surcharge: f64,
}

impl Column {
    /// V1a: small deformation, E = 1e6, ρ = 80, g = 10, H = 50.
    pub const V1A: Column = Column { height: 50.0, young: 1e6, density: 80.0, gravity: 10.0, surcharge: 0.0 };
    /// V1b: large deformation, 3D, E = 1e3, ρ = 50, g = 9.81, H = 0.8.
    pub const V1B: Column = Column { height: 0.8, young: 1e3, density: 50.0, gravity: 9.81, surcharge: 0.0 };
    /// V1c: large deformation, 2D, E = 1e5, ρ = 2000, g = 10, H = 10.
    pub const V1C: Column = Column { height: 10.0, young: 1e5, density: 2000.0, gravity: 10.0, surcharge: 0.0 };

    /// The same column under a surcharge of `ratio` times its weight, q = ratio · ρ₀gH₀.
    pub const fn surcharged(self, ratio: f64) -> Column {
        Column { surcharge: ratio * self.density * self.gravity * self.height, ..self }
    }

    /// q + ρ₀ g H₀: the largest stress, the scale of the error norm.
    pub fn stress_scale(&self) -> f64 {
        self.surcharge + self.density * self.gravity * self.height
    }

    /// Vertical Cauchy stress at the point of initial height `y0`, for any law and any
    /// deformation: the surcharge and the weight above per unit (unchanged) area.
    pub fn stress_yy(&self, y0: f64) -> f64 {
        -self.surcharge - self.density * self.gravity * (self.height - y0)
    }

    /// Stretch of Hencky elasticity at initial height `y0`: λ = W(s)/s with
    /// s = (q + ρ₀g(H₀ − Y))/E (σ = E ln λ / λ = −sE, ν = 0).
    pub fn hencky_stretch(&self, y0: f64) -> f64 {
        let s = -self.stress_yy(y0) / self.young;
        if s <= 0.0 {
            1.0
        } else {
            lambert_w0(s) / s
        }
    }

    /// Vertical displacement of the material at initial height `y0`, Hencky elasticity:
    /// u(Y) = ∫₀^Y (λ(Y') − 1) dY', by 8-point Gauss–Legendre on 16 panels (the integrand
    /// is smooth; converged to ~1e-15 relative).
    pub fn hencky_displacement(&self, y0: f64) -> f64 {
        let rule = GaussLegendre::new(8).expect("the 8-point rule exists");
        rule.integrate(|y| self.hencky_stretch(y) - 1.0, 0.0, y0, 16)
    }

    /// Vertical displacement of linear small-strain elasticity (M = E for ν = 0):
    /// u(Y) = −(qY + ρ₀g(H₀Y − Y²/2))/E.
    pub fn small_strain_displacement(&self, y0: f64) -> f64 {
        -(self.surcharge * y0 + self.density * self.gravity * (self.height * y0 - 0.5 * y0 * y0)) / self.young
    }
}

/// Errors of a column run against the closed form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColumnErrors {
    /// e_σ = Σ |σ_yy,p − σ_yy(Y_p)| V⁰_p / (Σ V⁰_p · (q + ρ₀gH₀)) (AMPLE; Wyser et al.
    /// 2020, with the surcharge in the scale).
    pub stress: f64,
    /// |u_num − u_ref| / |u_ref| at the highest point.
    pub top_displacement: f64,
    /// Numerical displacement of the highest point.
    pub top_displacement_value: f64,
}

/// The V1 stress norm e_σ alone (see [`ColumnErrors::stress`]); `vertical` is the axis of
/// gravity.
pub fn column_stress_error<const D: usize>(points: &PointStore<D>, column: &Column, vertical: usize) -> f64 {
    let mut num = 0.0;
    let mut vol = 0.0;
    for p in 0..points.len() {
        let s = points.stress()[p][(vertical, vertical)];
        num += (s - column.stress_yy(points.position0()[p][vertical])).abs() * points.volume0()[p];
        vol += points.volume0()[p];
    }
    num / (vol * column.stress_scale())
}

/// Measure a finished column run. `vertical` is the axis of gravity; `reference_u` the
/// closed-form displacement at an initial height.
pub fn column_errors<const D: usize>(
    points: &PointStore<D>,
    column: &Column,
    vertical: usize,
    reference_u: impl Fn(f64) -> f64,
) -> ColumnErrors {
    // The highest point at the start; the first of equal ones.
    let mut top = 0;
    for p in 0..points.len() {
        if points.position0()[p][vertical] > points.position0()[top][vertical] {
            top = p;
        }
    }
    let y0 = points.position0()[top][vertical];
    let u = points.position()[top][vertical] - y0;
    let u_ref = reference_u(y0);
    ColumnErrors {
        stress: column_stress_error(points, column, vertical),
        top_displacement: (u - u_ref).abs() / u_ref.abs(),
        top_displacement_value: u,
    }
}

/// What the MPM and FEM columns share: grid, body's upper corner, constraints, gravity, law.
struct ColumnParts<const D: usize> {
    grid: Grid<D>,
    max: SVector<f64, D>,
    constraints: Vec<PlaneConstraint>,
    gravity: SVector<f64, D>,
    law: Arc<dyn ConstitutiveLaw>,
}

/// The V1 column's shared parts (see [`column_model_with_spare_cells`]).
fn column_parts<const D: usize>(column: &Column, width: f64, cells_high: usize, spare_cells: usize) -> ColumnParts<D> {
    assert!(D >= 2);
    let h = column.height / cells_high as f64;
    let cell = SVector::<f64, D>::from_fn(|a, _| if a == 1 { h } else { width });
    let mut cells = [1usize; D];
    cells[1] = cells_high + spare_cells;
    let grid = Grid::new(SVector::zeros(), cell, cells).expect("valid column grid");
    let max = SVector::<f64, D>::from_fn(|a, _| if a == 1 { column.height } else { width });
    let mut constraints = Vec::new();
    for a in 0..D {
        let mut fixed = [false; 3];
        fixed[a] = true;
        constraints.push(PlaneConstraint::new(a, 0, fixed));
        if a != 1 {
            constraints.push(PlaneConstraint::new(a, 1, fixed));
        }
    }
    let mut gravity = SVector::<f64, D>::zeros();
    gravity[1] = -column.gravity;
    let law = Elastic::new(column.young, 0.0).expect("valid elastic constants");
    ColumnParts { grid, max, constraints, gravity, law: Arc::new(law) }
}

/// The V1 column as a model: one cell wide (`width`; the cell is `width` across in every
/// horizontal axis), `cells_high` cells over the column height plus one empty cell above,
/// `points_per_cell`^D points per cell, rollers on the sides and the base, ν = 0 elastic,
/// gravity along −y (axis 1) in 2D and 3D, and the surcharge as a dead pressure on the top
/// face.
pub fn column_model<const D: usize>(
    column: &Column,
    width: f64,
    cells_high: usize,
    points_per_cell: usize,
    basis: BasisKind,
    kinematics: Kinematics,
) -> Model<D> {
    column_model_with_spare_cells(column, width, cells_high, 1, points_per_cell, basis, kinematics)
}

/// [`column_model`] with `spare_cells` empty cells above the column instead of one: room
/// for a column that rises, e.g. an explicit run driven past its stability limit, which
/// must stop with a point leaving the grid and not sooner.
pub fn column_model_with_spare_cells<const D: usize>(
    column: &Column,
    width: f64,
    cells_high: usize,
    spare_cells: usize,
    points_per_cell: usize,
    basis: BasisKind,
    kinematics: Kinematics,
) -> Model<D> {
    let ColumnParts { grid, max, constraints, gravity, law } =
        column_parts::<D>(column, width, cells_high, spare_cells);
    let mut points = PointStore::new();
    points
        .fill(&grid, &Shape::Box { min: SVector::zeros(), max }, points_per_cell, column.density, 0)
        .expect("column fits the grid");
    let model =
        Model::new(grid, basis, kinematics, points, vec![law], constraints, gravity).expect("valid column model");
    if column.surcharge == 0.0 {
        return model;
    }
    let top = Shape::Box { min: SVector::zeros(), max }
        .boundary(width.min(column.height / cells_high as f64) / points_per_cell as f64)
        .expect("valid column boundary")
        .select(|c| c[1] >= column.height * (1.0 - 1e-12));
    let n = top.vertices.len();
    let load = Load::pressure(top, vec![column.surcharge; n], false, TimeFunction::Constant).expect("valid surcharge");
    model.with_loads(vec![load]).expect("the surcharge lies in the grid")
}

/// The V1 column as an updated Lagrangian FEM model: the same grid planes, constraints,
/// law and loads as [`column_model`], the body meshed by one element per grid cell with
/// `gauss_order`^D Gauss points each.
pub fn column_fem_model<const D: usize>(
    column: &Column,
    width: f64,
    cells_high: usize,
    gauss_order: usize,
    kinematics: Kinematics,
) -> Model<D> {
    assert_eq!(column.surcharge, 0.0, "the FEM reference takes no surface loads yet");
    let ColumnParts { grid, max, constraints, gravity, law } = column_parts::<D>(column, width, cells_high, 1);
    let elements = std::array::from_fn(|a| if a == 1 { cells_high } else { 1 });
    let mesh = FeMesh::block(SVector::zeros(), max, elements, gauss_order).expect("valid column mesh");
    Model::updated_lagrangian_fem(grid, kinematics, mesh, &[column.density], &[0], vec![law], constraints, gravity)
        .expect("valid column FEM model")
}

/// The V1 column in two layers, the upper half `contrast` times softer than the lower (a
/// hard case: a stiffness contrast across one cell face), small strain, ν = 0. The stress
/// is still the weight above, σ_yy = −ρg(H − Y); the displacement integrates σ/E layer by
/// layer.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LayeredColumn {
    pub column: Column,
    pub contrast: f64,
}

impl LayeredColumn {
    /// u(Y) = ∫₀^Y σ_yy/E(Y') dY', E = E₀ below H/2 and E₀/contrast above.
    pub fn displacement(&self, y0: f64) -> f64 {
        let c = &self.column;
        let half = 0.5 * c.height;
        let integral = |a: f64, b: f64| c.height * (b - a) - 0.5 * (b * b - a * a);
        let rg = c.density * c.gravity;
        let lower = -rg / c.young * integral(0.0, y0.min(half));
        let upper = if y0 > half { -rg * self.contrast / c.young * integral(half, y0) } else { 0.0 };
        lower + upper
    }

    /// One cell wide, `cells_high` (even) cells over the height, 2×2 points per cell, the
    /// layer interface on a cell face.
    pub fn model(&self, cells_high: usize, basis: BasisKind) -> Model<2> {
        assert!(cells_high.is_multiple_of(2), "the interface must lie on a cell face");
        let c = &self.column;
        let width = c.height / cells_high as f64;
        let ColumnParts { grid, max, constraints, gravity, law } = column_parts::<2>(c, width, cells_high, 1);
        let soft = Elastic::new(c.young / self.contrast, 0.0).expect("valid soft layer");
        let mut points = PointStore::new();
        let half = 0.5 * c.height;
        points
            .fill(&grid, &Shape::Box { min: Vector2::zeros(), max: Vector2::new(max[0], half) }, 2, c.density, 0)
            .expect("lower layer fits");
        points
            .fill(&grid, &Shape::Box { min: Vector2::new(0.0, half), max }, 2, c.density, 1)
            .expect("upper layer fits");
        Model::new(grid, basis, Kinematics::SmallStrain, points, vec![law, Arc::new(soft)], constraints, gravity)
            .expect("valid layered column")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lambert_w_satisfies_its_definition() {
        for &x in &[1e-12, 1e-3, 0.04, 0.392, 1.0, 2.0, 10.0, 1e3] {
            let w = lambert_w0(x);
            assert!((w * w.exp() - x).abs() <= 1e-14 * x.max(1.0), "x={x} w={w}");
        }
        // W(1) = Ω, the omega constant.
        assert!((lambert_w0(1.0) - 0.567_143_290_409_783_8).abs() < 1e-15);
    }

    /// The published top displacements of the three columns (the V1 table of the
    /// verification spec, quoted in `docs/verification.md` §V1), computed independently there.
    #[test]
    fn column_reference_displacements_match_the_published_table() {
        let cases = [(Column::V1A, -0.962009), (Column::V1B, -0.115671), (Column::V1C, -3.919632)];
        for (c, u) in cases {
            let got = c.hencky_displacement(c.height);
            // the table gives 6 decimals
            assert!((got - u).abs() < 5e-7, "{c:?}: {got} vs {u}");
        }
        assert!((Column::V1A.small_strain_displacement(50.0) + 1.0).abs() < 1e-12);
    }

    /// The surcharged closed forms: the small-strain displacement's slope at the base is the
    /// strain there, −(q + ρ₀gH₀)/E; the Hencky stretch at the top is W(q/E)/(q/E), and the
    /// Hencky displacement tends to the small-strain one as E grows (both by quadrature and
    /// by differentiation, not from a run).
    #[test]
    fn surcharged_closed_forms_agree_with_their_definitions() {
        let c = Column::V1A.surcharged(0.5);
        assert_eq!(c.surcharge, 0.5 * 80.0 * 10.0 * 50.0);
        let h = 1e-4;
        let slope = (c.small_strain_displacement(h) - c.small_strain_displacement(-h)) / (2.0 * h);
        assert!((slope + c.stress_scale() / c.young).abs() < 1e-10);
        let s = c.surcharge / c.young;
        assert!((c.hencky_stretch(c.height) - lambert_w0(s) / s).abs() < 1e-15);
        let stiff = Column { young: 1e10, ..c };
        let (a, b) = (stiff.hencky_displacement(50.0), stiff.small_strain_displacement(50.0));
        assert!((a - b).abs() < 1e-5 * b.abs(), "{a} vs {b}");
    }

    /// The layered column without contrast is the uniform one.
    #[test]
    fn a_layered_column_without_contrast_is_the_small_strain_column() {
        let layered = LayeredColumn { column: Column::V1A, contrast: 1.0 };
        for y in [0.0, 10.0, 25.0, 40.0, 50.0] {
            let (a, b) = (layered.displacement(y), Column::V1A.small_strain_displacement(y));
            assert!((a - b).abs() <= 1e-15 * b.abs().max(1.0), "y = {y}: {a} vs {b}");
        }
    }
}
