//! Static groundwater (docs/theory.md §18): a phreatic level and the water's unit weight
//! give every point below the level its pore pressure p_w = γ_w (h(x) − z), z the point's
//! height against gravity and h the level above its horizontal place. The laws see the
//! effective stress σ′ (the points' stress); the total stress is σ = σ′ − p_w I (tension
//! positive). Drained and static: no consolidation and no flow — the pore pressure follows
//! the points' places and the load factor, nothing else.

use crate::loads::piecewise_linear;
use nalgebra::SVector;

/// The phreatic level: the height of the water table above each horizontal place.
#[derive(Debug, Clone, PartialEq)]
pub enum PhreaticLevel {
    /// A level water table at this height.
    Horizontal(f64),
    /// 2D: a polyline of (horizontal coordinate, height) pairs, horizontal coordinates
    /// increasing, held level beyond its ends.
    Polyline(Vec<(f64, f64)>),
    /// A plane (2D: a line): height `height` above the origin of the horizontal axes,
    /// rising by `slope[a]` per unit along each horizontal axis a (the vertical entry is
    /// ignored).
    Plane { height: f64, slope: [f64; 3] },
}

/// Static water: its unit weight γ_w and phreatic level; `vertical` is the axis of gravity.
#[derive(Debug, Clone, PartialEq)]
pub struct Water {
    unit_weight: f64,
    level: PhreaticLevel,
    vertical: usize,
    /// +1 when "up" is the positive direction of the vertical axis, −1 otherwise.
    up: f64,
}

impl Water {
    /// Water of unit weight `unit_weight` under gravity `gravity`, which must act along one
    /// axis (its direction decides "up").
    pub fn new<const D: usize>(
        unit_weight: f64,
        level: PhreaticLevel,
        gravity: &SVector<f64, D>,
    ) -> Result<Self, String> {
        if !(unit_weight.is_finite() && unit_weight > 0.0) {
            return Err(format!("the water's unit weight is {unit_weight}; it must be a positive number"));
        }
        let vertical = (0..D).max_by(|&a, &b| gravity[a].abs().total_cmp(&gravity[b].abs())).unwrap_or(0);
        if gravity[vertical] == 0.0 || (0..D).any(|a| a != vertical && gravity[a] != 0.0) {
            return Err("water needs gravity along one axis (its direction says which way is up)".into());
        }
        match &level {
            PhreaticLevel::Horizontal(h) if !h.is_finite() => return Err(format!("the level {h} is not finite")),
            PhreaticLevel::Polyline(_) if D != 2 => return Err("a polyline level is 2D only".into()),
            PhreaticLevel::Polyline(v) if v.len() < 2 => {
                return Err(format!("a polyline level needs at least 2 points, got {}", v.len()))
            }
            PhreaticLevel::Polyline(v) if v.iter().any(|(x, h)| !(x.is_finite() && h.is_finite())) => {
                return Err("the level's points must be finite".into())
            }
            PhreaticLevel::Polyline(v) if v.windows(2).any(|w| w[1].0 <= w[0].0) => {
                return Err("the level's horizontal coordinates must increase".into())
            }
            PhreaticLevel::Plane { height, slope } if !(height.is_finite() && slope.iter().all(|s| s.is_finite())) => {
                return Err("the plane's height and slopes must be finite".into())
            }
            _ => {}
        }
        Ok(Self { unit_weight, level, vertical, up: -gravity[vertical].signum() })
    }

    pub fn unit_weight(&self) -> f64 {
        self.unit_weight
    }

    pub fn level(&self) -> &PhreaticLevel {
        &self.level
    }

    /// The axis of gravity.
    pub fn vertical(&self) -> usize {
        self.vertical
    }

    /// The height of the water table above the horizontal place of `x`.
    pub fn head<const D: usize>(&self, x: &SVector<f64, D>) -> f64 {
        self.head_and_slope(x).0
    }

    /// The level's height above the horizontal place of `x` and its slope there (zero on
    /// the vertical axis; a polyline's segment slope, held level beyond its ends).
    fn head_and_slope<const D: usize>(&self, x: &SVector<f64, D>) -> (f64, SVector<f64, D>) {
        let mut slope = SVector::zeros();
        let head = match &self.level {
            PhreaticLevel::Horizontal(h) => *h,
            PhreaticLevel::Plane { height, slope: s } => {
                let horizontal = (0..D).filter(|&a| a != self.vertical);
                horizontal
                    .map(|a| {
                        slope[a] = s[a];
                        s[a] * x[a]
                    })
                    .sum::<f64>()
                    + height
            }
            PhreaticLevel::Polyline(v) => {
                let h = 1 - self.vertical.min(1);
                let (head, s) = piecewise_linear(v, x[h]);
                slope[h] = s;
                head
            }
        };
        (head, slope)
    }

    /// The depth of `x` below the water table (negative above it).
    pub fn depth<const D: usize>(&self, x: &SVector<f64, D>) -> f64 {
        self.up * (self.head(x) - x[self.vertical])
    }

    /// The pore pressure at `x` at full load: γ_w times the depth below the table, zero
    /// above it (no suction).
    pub fn pore_pressure<const D: usize>(&self, x: &SVector<f64, D>) -> f64 {
        self.unit_weight * self.depth(x).max(0.0)
    }

    /// The water's force per unit volume at full load on a point at `x` whose domain
    /// reaches `half_height` above and below it: −∇p_w = γ_w (up − the level's slope along
    /// a polyline), times the fraction of the domain below the level (so a point the level
    /// cuts carries the buoyancy of its submerged part, and the force does not jump as the
    /// level passes a point centre).
    pub fn force_density<const D: usize>(&self, x: &SVector<f64, D>, half_height: f64) -> SVector<f64, D> {
        let depth = self.depth(x);
        let fraction = if half_height > 0.0 {
            ((depth + half_height) / (2.0 * half_height)).clamp(0.0, 1.0)
        } else if depth > 0.0 {
            1.0
        } else {
            0.0
        };
        if fraction == 0.0 {
            return SVector::zeros();
        }
        // −∇p_w = −γ_w ∇depth, depth = up (h(x) − x_v): γ_w up (e_v − ∇h).
        let mut b = -self.head_and_slope(x).1;
        b[self.vertical] = 1.0;
        b * (self.up * self.unit_weight * fraction)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector2;

    #[test]
    fn pore_pressure_below_a_level_and_a_polyline() {
        let g = Vector2::new(0.0, -10.0);
        let w = Water::new(10.0, PhreaticLevel::Horizontal(5.0), &g).unwrap();
        assert_eq!(w.pore_pressure(&Vector2::new(3.0, 2.0)), 30.0);
        assert_eq!(w.pore_pressure(&Vector2::new(3.0, 6.0)), 0.0);
        let line = Water::new(10.0, PhreaticLevel::Polyline(vec![(0.0, 4.0), (10.0, 2.0)]), &g).unwrap();
        assert!((line.pore_pressure(&Vector2::new(5.0, 0.0)) - 30.0).abs() < 1e-12);
        assert_eq!(line.pore_pressure(&Vector2::new(-1.0, 0.0)), 40.0);
        assert_eq!(line.pore_pressure(&Vector2::new(20.0, 0.0)), 20.0);
        assert!(Water::new(10.0, PhreaticLevel::Horizontal(1.0), &Vector2::new(1.0, -10.0)).is_err());
        assert!(Water::new(-1.0, PhreaticLevel::Horizontal(1.0), &g).is_err());
        assert!(Water::new(1.0, PhreaticLevel::Polyline(vec![(1.0, 0.0), (1.0, 2.0)]), &g).is_err());
        // A plane rising 1 in 10 along x: head 4.5 at x = 5; the buoyancy tilts against
        // the slope (−γ_w ∇h horizontally), and the same as a polyline along it.
        let plane = Water::new(10.0, PhreaticLevel::Plane { height: 4.0, slope: [0.1, 0.0, 0.0] }, &g).unwrap();
        let on_line = Water::new(10.0, PhreaticLevel::Polyline(vec![(0.0, 4.0), (10.0, 5.0)]), &g).unwrap();
        let x = Vector2::new(5.0, 1.0);
        assert!((plane.pore_pressure(&x) - 35.0).abs() < 1e-12);
        assert!((plane.force_density(&x, 0.0) - Vector2::new(-1.0, 10.0)).norm() < 1e-12);
        assert!((plane.force_density(&x, 0.0) - on_line.force_density(&x, 0.0)).norm() < 1e-12);
        // A point the level cuts at its centre carries half the buoyancy.
        assert_eq!(w.force_density(&Vector2::new(0.0, 5.0), 0.25), Vector2::new(0.0, 5.0));
        // Gravity along +y: up is −y.
        let down = Water::new(10.0, PhreaticLevel::Horizontal(5.0), &Vector2::new(0.0, 10.0)).unwrap();
        assert_eq!(down.pore_pressure(&Vector2::new(0.0, 7.0)), 20.0);
    }
}
