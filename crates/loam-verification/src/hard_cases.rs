//! The hard cases (docs/verification.md §H): where implicit MPM
//! usually breaks, shown rather than hidden. Most have no closed form and are reported as
//! figures; what is bounded is that the method copes: a 10⁶ stiffness contrast converges
//! (the layered column, `column::LayeredColumn`), a point leaving the grid is reported with
//! the last converged state kept, and the face ghost penalty keeps small cuts conditioned.
//! The fixtures here are the softening specimen and the block translated through the grid.

use crate::bound::Bound;
use loam_constitutive::{ConstitutiveLaw, Elastic, VonMises};
use loam_grid::{BasisKind, Grid};
use loam_model::{AntiLocking, Kinematics, Model, PlaneConstraint};
use loam_points::{PointStore, Shape};
use nalgebra::Vector2;
use std::sync::Arc;

/// The bounds `cargo xtask verify` checks on the hard cases (`docs/verification.md`,
/// "Hard cases", "Checked: ...").
pub mod bounds {
    use super::Bound;

    /// H1: Newton iterations of the one load step of the layered column at a 10⁶ contrast
    ///.
    pub const CONTRAST_NEWTON_ITERATIONS: Bound =
        Bound::upper(2.0, "docs/verification.md §H: a 1e6 stiffness contrast converges in <= 2 Newton iterations");
    /// H4: a point leaving the grid is reported as such, with the last converged state and
    /// every point kept (1 = yes).
    pub const POINT_LEAVING_THE_GRID_REPORTED: Bound =
        Bound::lower(1.0, "docs/verification.md §H: a point leaving the grid is reported, the last state kept");
    /// H5: Newton failures of the translated block with the ghost penalty, over every
    /// overlap and both penalties.
    pub const GHOST_NEWTON_FAILURES: Bound =
        Bound::upper(0.0, "docs/verification.md §H: with the ghost penalty Newton converges at every overlap");
    /// H5: the largest condition number with the ghost penalty (γ = 0.1) over the well-cut
    /// block's.
    pub const GHOST_CONDITION_RATIO: Bound = Bound::upper(
        1.5,
        "docs/verification.md §H: with the ghost penalty the condition stays within 1.5x of the well-cut block's",
    );
}

/// A hard case: plane-strain compression of a softening von Mises specimen (1 × 2, quarter
/// model: rollers on the left and the base), the top pushed down by `shortening` with the
/// load factor. σ_y = 100 softening at H = −500 (E = 1e4, ν = 0.3) to 30; a 0.25 × 0.25
/// weaker corner (σ_y = 90) at the origin seeds the shear band. Linear basis, B-bar,
/// `cells_across` cells over the width; the grid reaches `margin` widths beyond the right
/// side, where the specimen bulges.
pub fn softening_specimen(cells_across: usize, margin: f64, shortening: f64) -> Model<2> {
    let n = cells_across;
    let h = 1.0 / n as f64;
    let extra = (margin * n as f64).ceil() as usize;
    let grid = Grid::new(Vector2::zeros(), Vector2::new(h, h), [n + extra, 2 * n + 1]).expect("valid specimen grid");
    let elastic = Elastic::new(1e4, 0.3).expect("valid elasticity");
    let law = |yield_stress: f64| -> Arc<dyn ConstitutiveLaw> {
        Arc::new(
            VonMises::new(elastic, yield_stress, -500.0)
                .and_then(|l| l.with_residual_yield_stress(0.3 * yield_stress))
                .expect("valid softening law"),
        )
    };
    let w = 0.25;
    let mut points = PointStore::new();
    let outline = [(w, 0.0), (1.0, 0.0), (1.0, 2.0), (0.0, 2.0), (0.0, w), (w, w)].map(|(x, y)| Vector2::new(x, y));
    points.fill(&grid, &Shape::Polygon(outline.to_vec()), 2, 1.0, 0).expect("specimen fits the grid");
    points
        .fill(&grid, &Shape::Box { min: Vector2::zeros(), max: Vector2::new(w, w) }, 2, 1.0, 1)
        .expect("weak corner fits");
    let constraints = vec![
        PlaneConstraint::new(1, 2 * n, [false, true, false]).displaced([0.0, -shortening, 0.0]),
        PlaneConstraint::new(1, 0, [false, true, false]),
        PlaneConstraint::new(0, 0, [true, false, false]),
    ];
    Model::new(
        grid,
        BasisKind::Linear,
        Kinematics::SmallStrain,
        points,
        vec![law(100.0), law(90.0)],
        constraints,
        Vector2::zeros(),
    )
    .and_then(|m| m.with_anti_locking(AntiLocking::BBar))
    .expect("valid specimen")
}

/// A hard case for small cuts: a 4 h × 4 h elastic block (E = 1e3, ν = 0.3, unit density)
/// on a fixed base under gravity 10, shifted along x so that its right face lies
/// `overlap` of a cell into the next cell (h = 1, 10 × 6 cells), small strain. With GIMP
/// the rightmost point domains reach that cell by `overlap` h, and its far nodes get
/// weights ~ overlap² and stiffness ~ overlap².
pub fn translated_block(overlap: f64, basis: BasisKind, ghost_penalty: Option<f64>) -> Model<2> {
    let grid = Grid::new(Vector2::zeros(), Vector2::new(1.0, 1.0), [10, 6]).expect("valid grid");
    // Points at the sub-cell centres of the block's own cells, not of the grid's.
    let shift = 2.0 + overlap;
    let block_cells = Grid::new(Vector2::new(shift, 0.0), Vector2::new(1.0, 1.0), [4, 4]).expect("valid block cells");
    let mut points = PointStore::new();
    points
        .fill(
            &block_cells,
            &Shape::Box { min: Vector2::new(shift, 0.0), max: Vector2::new(shift + 4.0, 4.0) },
            2,
            1.0,
            0,
        )
        .expect("block fits");
    let law = Arc::new(Elastic::new(1e3, 0.3).expect("valid elasticity"));
    let model = Model::new(
        grid,
        basis,
        Kinematics::SmallStrain,
        points,
        vec![law],
        vec![PlaneConstraint::new(1, 0, [true, true, false])],
        Vector2::new(0.0, -10.0),
    )
    .expect("valid block");
    match ghost_penalty {
        Some(gamma) => model.with_ghost_penalty(gamma).expect("valid ghost penalty"),
        None => model,
    }
}
