//! Material points: the struct-of-arrays store of everything a point carries between steps
//! (position, volume, mass, deformation gradient, elastic strain state, stress, GIMP domain,
//! material and history), and the generation of points from shapes.
//!
//! Points are generated at the centres of an n^D subdivision of every grid cell that the
//! shape covers (the usual MPM initialisation; Sulsky et al. 1994), each with the volume of
//! its sub-cell, so that the initial GIMP domains tile the body exactly. A shape's boundary,
//! where surface loads act, is a [`Surface`] of facets.

mod fill;
mod shape;
mod store;
mod stretch;
mod surface;

pub use fill::fill_count;
pub use shape::Shape;
pub use store::{Column, PointId, PointStore, PointsMut, Renumbering, StateFields};
pub use stretch::{right_stretch_diagonal, right_stretch_diagonals, stretched_half_length, stretched_half_lengths};
pub use surface::{area_vector, Surface};

/// Errors in generating points.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PointsError {
    #[error("points_per_cell is {0}; it must be between 1 and 8")]
    PointsPerCell(usize),
    #[error("density is {0}; it must be a positive finite number")]
    Density(f64),
    #[error("the shape contains no point centre: it is empty or thinner than a sub-cell ({0})")]
    EmptyRegion(String),
    #[error("the shape reaches outside the grid: a point would sit at {position:?}, grid spans {min:?} to {max:?}")]
    OutsideGrid { position: Vec<f64>, min: Vec<f64>, max: Vec<f64> },
    #[error("the shape reaches outside the grid: its bounds are {lo:?} to {hi:?}, the grid spans {min:?} to {max:?}")]
    BeyondGrid { lo: Vec<f64>, hi: Vec<f64>, min: Vec<f64>, max: Vec<f64> },
    #[error("a polygon needs at least 3 vertices, got {0}")]
    Polygon(usize),
    #[error("a ball's radius is {0}; it must be a positive number")]
    Radius(f64),
    #[error("the spacing of a surface's facets is {0}; it must be a positive number")]
    Spacing(f64),
    #[error("a polygon is only defined in 2D")]
    PolygonDimension,
    #[error("a prism is only defined in 3D, extruded along axis 0, 1 or 2 (got {axis}) from a coordinate below the one it goes to (got {from} to {to})")]
    Prism { axis: usize, from: f64, to: f64 },
    #[error("a cut box needs a finite point and a finite, non-zero normal")]
    CutPlane,
    #[error("surfaces (for loads) are not available on a {0} yet: give the loaded part its own Box body")]
    NoSurface(&'static str),
    #[error("the boundary would need about {facets:.1e} facets of at most {spacing} (more than 1e7): is a vertex or size mistyped?")]
    TooManyFacets { facets: f64, spacing: f64 },
    #[error("box min {min:?} is not below max {max:?} on every axis")]
    BoxOrder { min: Vec<f64>, max: Vec<f64> },
    #[error("the store holds {points} points but {found} values of `{field}`; every field needs one per point")]
    FieldLength { field: &'static str, points: usize, found: usize },
    #[error("point {point}: {what}")]
    Point { point: usize, what: String },
    #[error("a checkpoint's point field `{field}`: {what}")]
    Column { field: &'static str, what: String },
    #[error("a reordering of {0} points must name each of them once")]
    Reorder(usize),
    #[error("the points added keep {found} history values each, the store {expected}")]
    HistoryStride { found: usize, expected: usize },
}
