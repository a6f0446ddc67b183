//! Gauss–Legendre quadrature on [−1, 1]: the one rule behind the Gauss points of the
//! body-fitted mesh, the face integrals of the ghost penalty and the closed-form integrals
//! of the verification references (Abramowitz & Stegun, table 25.4).
//!
//! A rule is stored as its non-negative half (the rules are symmetric), so that the
//! nodes and weights of either sign are exactly the same numbers.

/// An n-point Gauss–Legendre rule, n in 1, 2, 3 or 8.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaussLegendre {
    /// Positive nodes, ascending; the centre node 0 of an odd rule is not among them.
    positive: &'static [f64],
    /// Weights of the positive nodes.
    weights: &'static [f64],
    /// Weight of the centre node of an odd rule (0 for an even one).
    centre: f64,
}

const X8: [f64; 4] = [0.183_434_642_495_649_8, 0.525_532_409_916_329, 0.796_666_477_413_626_7, 0.960_289_856_497_536_3];
const W8: [f64; 4] = [0.362_683_783_378_362, 0.313_706_645_877_887_3, 0.222_381_034_453_374_5, 0.101_228_536_290_376_3];

impl GaussLegendre {
    /// The n-point rule, exact for polynomials of degree 2n − 1; `None` for an order this
    /// module does not hold (1, 2, 3 and 8 are).
    pub fn new(points: usize) -> Option<Self> {
        Some(match points {
            1 => Self { positive: &[], weights: &[], centre: 2.0 },
            2 => Self { positive: &[0.577_350_269_189_625_8], weights: &[1.0], centre: 0.0 },
            3 => Self { positive: &[0.774_596_669_241_483_4], weights: &[5.0 / 9.0], centre: 8.0 / 9.0 },
            8 => Self { positive: &X8, weights: &W8, centre: 0.0 },
            _ => return None,
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        2 * self.positive.len() + usize::from(self.centre != 0.0)
    }

    /// Always false: every rule has at least one point.
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Node and weight of point `i`, nodes ascending from −1 to 1.
    pub fn point(&self, i: usize) -> (f64, f64) {
        let half = self.positive.len();
        let odd = usize::from(self.centre != 0.0);
        if i < half {
            (-self.positive[half - 1 - i], self.weights[half - 1 - i])
        } else if i < half + odd {
            (0.0, self.centre)
        } else {
            (self.positive[i - half - odd], self.weights[i - half - odd])
        }
    }

    /// ∫_a^b f over `panels` equal panels, each by this rule, the two nodes of a
    /// symmetric pair summed before weighting.
    pub fn integrate(&self, f: impl Fn(f64) -> f64, a: f64, b: f64, panels: usize) -> f64 {
        let h = (b - a) / panels as f64;
        let mut sum = 0.0;
        for k in 0..panels {
            let c = a + (k as f64 + 0.5) * h;
            if self.centre != 0.0 {
                sum += self.centre * f(c);
            }
            for (x, w) in self.positive.iter().zip(self.weights) {
                sum += w * (f(c - 0.5 * h * x) + f(c + 0.5 * h * x));
            }
        }
        sum * 0.5 * h
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An n-point rule integrates x^k exactly on [−1, 1] for k ≤ 2n − 1 (to rounding).
    #[test]
    fn rules_are_exact_to_their_degree() {
        for n in [1, 2, 3, 8] {
            let rule = GaussLegendre::new(n).unwrap();
            assert_eq!(rule.len(), n);
            for k in 0..2 * n {
                let exact = if k % 2 == 1 { 0.0 } else { 2.0 / (k as f64 + 1.0) };
                let sum: f64 = (0..n).map(|i| rule.point(i)).map(|(x, w)| w * x.powi(k as i32)).sum();
                assert!((sum - exact).abs() < 1e-14, "n = {n}, x^{k}: {sum} vs {exact}");
                let panels = rule.integrate(|x| x.powi(k as i32), -1.0, 1.0, 3);
                assert!((panels - exact).abs() < 1e-14, "n = {n}, x^{k} on panels: {panels}");
            }
        }
        assert!(GaussLegendre::new(4).is_none());
    }

    #[test]
    fn nodes_ascend_and_mirror() {
        let rule = GaussLegendre::new(3).unwrap();
        let nodes: Vec<f64> = (0..3).map(|i| rule.point(i).0).collect();
        assert_eq!(nodes, vec![-0.774_596_669_241_483_4, 0.0, 0.774_596_669_241_483_4]);
        assert_eq!((0..3).map(|i| rule.point(i).1).collect::<Vec<_>>(), vec![5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0]);
    }
}
