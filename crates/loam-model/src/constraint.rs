//! Constraints on the nodes of a plane of the background grid.

/// A constraint on the nodes of a grid plane: the listed displacement components are
/// prescribed — zero (a roller fixes the component normal to the plane, a fixed plane all
/// of them), or `displacement` at full load, applied in proportion to the load factor
/// (a footing pushed into the ground). `within` limits it to the nodes of the plane inside
/// a box (all axes; the plane's own axis is ignored).
#[derive(Debug, Clone, PartialEq)]
pub struct PlaneConstraint {
    /// Axis normal to the plane.
    pub axis: usize,
    /// Index of the node plane along `axis`.
    pub plane: usize,
    /// Which displacement components are prescribed (first D entries used).
    pub fixed: [bool; 3],
    /// Prescribed displacement of the fixed components at full load (zero: held).
    pub displacement: [f64; 3],
    /// Only nodes with min ≤ x ≤ max (per axis, to within 1e-9 of a cell), if given.
    pub within: Option<([f64; 3], [f64; 3])>,
}

impl PlaneConstraint {
    /// Hold the `fixed` components of every node of the plane at zero.
    pub fn new(axis: usize, plane: usize, fixed: [bool; 3]) -> Self {
        Self { axis, plane, fixed, displacement: [0.0; 3], within: None }
    }

    /// Prescribe `displacement` (at full load) on the fixed components instead of zero.
    pub fn displaced(mut self, displacement: [f64; 3]) -> Self {
        self.displacement = displacement;
        self
    }

    /// Only the nodes of the plane inside the box [min, max].
    pub fn within(mut self, min: [f64; 3], max: [f64; 3]) -> Self {
        self.within = Some((min, max));
        self
    }

    /// Whether the constraint prescribes a non-zero displacement.
    pub fn is_displaced(&self) -> bool {
        self.displacement.iter().zip(&self.fixed).any(|(d, &f)| f && *d != 0.0)
    }
}
