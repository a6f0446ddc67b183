//! The elastic block under gravity that sizes the solvers (docs/theory.md §19): `n` cells
//! a side in 2D or 3D, two points per cell and axis, GIMP, on [1, n+1]^(D−1) × [0, n] in a
//! grid with an empty cell beside and above it, rollers on its vertical sides and a base
//! that is either fixed or a roller. With the roller base it is laterally confined:
//! σ_v = −ρ g (H − z), σ_h = ν/(1−ν) σ_v in small strain.

use loam_constitutive::Elastic;
use loam_grid::{BasisKind, Grid};
use loam_model::{Kinematics, Model, PlaneConstraint};
use loam_points::{PointStore, Shape};
use nalgebra::SVector;
use std::sync::Arc;

/// The block's density, gravity (along the last axis, downwards), Young's modulus and
/// Poisson's ratio (SI: kg/m³, m/s², Pa; cells of 1 m).
pub const BLOCK_DENSITY: f64 = 2000.0;
pub const BLOCK_GRAVITY: f64 = 10.0;
pub const BLOCK_YOUNG: f64 = 1e7;
pub const BLOCK_POISSON: f64 = 0.3;

/// The block of `n` cells a side; `fixed_base` holds the base in every direction, else
/// only vertically.
pub fn elastic_block<const D: usize>(n: usize, kinematics: Kinematics, fixed_base: bool) -> Model<D> {
    layered_block(n, kinematics, fixed_base, 1.0)
}

/// [`elastic_block`] with its lower half `contrast` times softer (the stiffness-contrast
/// hard case in a block: docs/verification.md §H); `contrast` 1 is the uniform block.
pub fn layered_block<const D: usize>(n: usize, kinematics: Kinematics, fixed_base: bool, contrast: f64) -> Model<D> {
    block_model(n, kinematics, fixed_base, contrast, 0.0)
}

/// The small-cut hard case in a block (docs/verification.md §H, in 2D or 3D): the uniform
/// block, small strain, fixed base, lifted by `overlap` of a cell, so that its top face
/// lies that far into the next layer of cells (GIMP point domains reach those cells by the
/// overlap), and with the ghost penalty γ = `ghost` if given.
pub fn cut_block<const D: usize>(n: usize, overlap: f64, ghost: Option<f64>) -> Model<D> {
    let model = block_model(n, Kinematics::SmallStrain, true, 1.0, overlap);
    match ghost {
        Some(gamma) => model.with_ghost_penalty(gamma).expect("valid ghost penalty"),
        None => model,
    }
}

/// The block, its points placed at the sub-cell centres of its own cells, which are the
/// grid's lifted by `lift` along the last axis.
fn block_model<const D: usize>(
    n: usize,
    kinematics: Kinematics,
    fixed_base: bool,
    contrast: f64,
    lift: f64,
) -> Model<D> {
    let grid = Grid::new(SVector::zeros(), SVector::repeat(1.0), [n + 2; D]).expect("valid block grid");
    let v = D - 1;
    let offset = SVector::<f64, D>::from_fn(|a, _| if a == v { lift } else { 0.0 });
    let cells = Grid::new(offset, SVector::repeat(1.0), [n + 2; D]).expect("valid block cells");
    let mut points = PointStore::new();
    let min = SVector::<f64, D>::from_fn(|a, _| if a == v { 0.0 } else { 1.0 }) + offset;
    let max = SVector::<f64, D>::from_fn(|a, _| if a == v { n as f64 } else { n as f64 + 1.0 }) + offset;
    let layered = contrast != 1.0;
    let mut middle = max;
    middle[v] = (n / 2) as f64 + lift;
    let mut upper = min;
    upper[v] = (n / 2) as f64 + lift;
    if layered {
        points.fill(&cells, &Shape::Box { min, max: middle }, 2, BLOCK_DENSITY, 1).expect("the layer lies in its grid");
        points.fill(&cells, &Shape::Box { min: upper, max }, 2, BLOCK_DENSITY, 0).expect("the layer lies in its grid");
    } else {
        points.fill(&cells, &Shape::Box { min, max }, 2, BLOCK_DENSITY, 0).expect("the block lies in its grid");
    }
    let mut base = [fixed_base; 3];
    base[v] = true;
    let mut constraints = vec![PlaneConstraint::new(v, 0, base)];
    for a in 0..v {
        let mut roller = [false; 3];
        roller[a] = true;
        constraints.push(PlaneConstraint::new(a, 1, roller));
        constraints.push(PlaneConstraint::new(a, n + 1, roller));
    }
    let law = Elastic::new(BLOCK_YOUNG, BLOCK_POISSON).expect("valid elastic constants");
    let mut laws: Vec<Arc<dyn loam_constitutive::ConstitutiveLaw>> = vec![Arc::new(law)];
    if layered {
        laws.push(Arc::new(Elastic::new(BLOCK_YOUNG / contrast, BLOCK_POISSON).expect("valid soft layer")));
    }
    let gravity = SVector::<f64, D>::from_fn(|a, _| if a == v { -BLOCK_GRAVITY } else { 0.0 });
    Model::new(grid, BasisKind::Gimp, kinematics, points, laws, constraints, gravity).expect("valid block model")
}
