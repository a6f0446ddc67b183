//! What a verification bound is: a limit on one measured figure, which side of it passes,
//! and where the number comes from. The bounds themselves live beside their cases
//! (`column::bounds`, `bar::bounds`, ...), so that a case, its reference and what it must
//! meet are read together, and the report writer only compares and prints.

/// Which side of the limit passes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoundKind {
    /// The figure must not exceed the limit.
    Upper,
    /// The figure must reach at least the limit.
    Lower,
}

/// A limit on one measured figure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bound {
    pub value: f64,
    pub kind: BoundKind,
    /// Where the number comes from: the issue or the spec that set it, or the measurement
    /// it was derived from.
    pub source: &'static str,
}

impl Bound {
    /// A figure that must not exceed `value`.
    pub const fn upper(value: f64, source: &'static str) -> Self {
        Self { value, kind: BoundKind::Upper, source }
    }

    /// A figure that must reach at least `value`.
    pub const fn lower(value: f64, source: &'static str) -> Self {
        Self { value, kind: BoundKind::Lower, source }
    }

    /// Whether `figure` meets the bound; a NaN figure never does, so a run that produced
    /// no number fails instead of passing silently.
    pub fn holds(&self, figure: f64) -> bool {
        match self.kind {
            BoundKind::Upper => figure <= self.value,
            BoundKind::Lower => figure >= self.value,
        }
    }

    /// `<=` or `>=`, as the report prints the bound before its value.
    pub fn relation(&self) -> &'static str {
        match self.kind {
            BoundKind::Upper => "<=",
            BoundKind::Lower => ">=",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bound_holds_on_its_side_and_at_its_value() {
        let upper = Bound::upper(1.0, "test");
        assert!(upper.holds(1.0) && upper.holds(0.5) && !upper.holds(1.5) && !upper.holds(f64::NAN));
        let lower = Bound::lower(1.0, "test");
        assert!(lower.holds(1.0) && lower.holds(1.5) && !lower.holds(0.5) && !lower.holds(f64::NAN));
        assert_eq!((upper.relation(), lower.relation()), ("<=", ">="));
    }
}
