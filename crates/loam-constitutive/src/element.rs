//! Element tests: one material point of a law driven along a path of mixed strain and
//! stress control in small strain — triaxial compression (drained and undrained),
//! oedometric compression and simple shear — to see what a law does before it is used in a
//! scene (docs/theory.md §16).
//!
//! Each step holds each of the six components (xx, yy, zz, xy, yz, xz) either by its strain
//! increment or by its stress value; the strain increments of the stress-held components are
//! found by Newton's method with the law's consistent tangent. The axial direction is z and
//! stress is tension-positive, as everywhere in loam; the path's outputs (p′, q, the axial
//! and volumetric strains) are compression-positive, as geotechnical plots are.

use nalgebra::{DMatrix, DVector, Matrix3};

use crate::tensor::idx;
use crate::{ConstitutiveError, ConstitutiveLaw};

/// The six independent components of a symmetric tensor: xx, yy, zz, xy, yz, xz.
const COMPONENTS: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (0, 2)];

/// How a component is held during a step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Held {
    /// The strain component grows by this increment (for a shear component, ε_ij = γ_ij/2).
    Strain(f64),
    /// The stress component is held at this value at the end of the step.
    Stress(f64),
}

/// A standard laboratory path, axial direction z, all compression-positive in its
/// parameters: each step compresses by `increment` (an axial strain, or for simple shear
/// an engineering shear strain γ_xz).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ElementPath {
    /// Axial compression with the lateral stresses held at their starting values.
    TriaxialDrained,
    /// Axial compression at constant volume (the lateral strains −½ the axial).
    TriaxialUndrained,
    /// Axial compression with no lateral strain.
    Oedometer,
    /// Shear γ_xz with the normal stress σ_zz held and no other strain.
    SimpleShear,
}

impl ElementPath {
    /// What each component does in a step of `increment`, from the state with stress `start`.
    pub fn held(self, increment: f64, start: &Matrix3<f64>) -> [Held; 6] {
        use Held::{Strain, Stress};
        let zero = Strain(0.0);
        match self {
            ElementPath::TriaxialDrained => {
                [Stress(start[(0, 0)]), Stress(start[(1, 1)]), Strain(-increment), zero, zero, zero]
            }
            ElementPath::TriaxialUndrained => {
                [Strain(0.5 * increment), Strain(0.5 * increment), Strain(-increment), zero, zero, zero]
            }
            ElementPath::Oedometer => [zero, zero, Strain(-increment), zero, zero, zero],
            ElementPath::SimpleShear => [zero, zero, Stress(start[(2, 2)]), zero, zero, Strain(0.5 * increment)],
        }
    }
}

/// One point of a law and its state along an element test.
#[derive(Debug, Clone)]
pub struct ElementTest<'a> {
    law: &'a dyn ConstitutiveLaw,
    strain: Matrix3<f64>,
    elastic_strain: Matrix3<f64>,
    stress: Matrix3<f64>,
    history: Vec<f64>,
}

/// Newton's tolerance on the held stresses, relative to the largest stress.
const TOLERANCE: f64 = 1e-10;
const MAX_ITERATIONS: usize = 25;

impl<'a> ElementTest<'a> {
    /// The point at rest under `initial_stress` (the law's history initialised from it, the
    /// elastic strain that carries it); an error where no elastic strain carries it or it
    /// lies outside the yield surface (the law's update from that strain does not return it).
    pub fn new(law: &'a dyn ConstitutiveLaw, initial_stress: Matrix3<f64>) -> Result<Self, ConstitutiveError> {
        let mut history = vec![0.0; law.history_len()];
        law.init_history(&mut history, &initial_stress);
        let elastic_strain =
            law.elastic_strain_of(&initial_stress, &history).ok_or(ConstitutiveError::InitialStress {
                why: "has no elastic strain that carries it (Cam clay needs a compressive mean stress)",
            })?;
        // The law's own update from that strain must give the stress back: inside the surface.
        let mut h_out = history.clone();
        let back = law.update_stress(&elastic_strain, &history, &mut h_out)?.0;
        if (back - initial_stress).norm() > 1e-8 * initial_stress.norm().max(f64::MIN_POSITIVE) {
            return Err(ConstitutiveError::InitialStress { why: "lies outside the law's yield surface" });
        }
        Ok(Self { law, strain: Matrix3::zeros(), elastic_strain, stress: initial_stress, history })
    }

    /// Total strain since the start (small strain).
    pub fn strain(&self) -> &Matrix3<f64> {
        &self.strain
    }

    pub fn stress(&self) -> &Matrix3<f64> {
        &self.stress
    }

    pub fn history(&self) -> &[f64] {
        &self.history
    }

    /// p′ = −tr σ/3 (compression positive) and q = √(3 J₂).
    pub fn p_q(&self) -> (f64, f64) {
        let p = -self.stress.trace() / 3.0;
        let s = self.stress + Matrix3::identity() * p;
        (p, (1.5 * s.norm_squared()).sqrt())
    }

    /// One step holding each component as `held` says: Newton on the strain increments of
    /// the stress-held components. An error where the law fails or Newton does not
    /// converge (the state is then unchanged).
    pub fn step(&mut self, held: [Held; 6]) -> Result<(), ConstitutiveError> {
        let free: Vec<usize> = (0..6).filter(|&a| matches!(held[a], Held::Stress(_))).collect();
        let mut d = Matrix3::zeros();
        for (a, &(i, j)) in COMPONENTS.iter().enumerate() {
            if let Held::Strain(de) = held[a] {
                d[(i, j)] = de;
                d[(j, i)] = de;
            }
        }
        // The held stresses' scale: the largest stress now or held (a stress-free start
        // that holds nothing is held to round-off of the law's own stresses).
        let held_scale = held.iter().fold(0.0f64, |m, h| if let Held::Stress(s) = h { m.max(s.abs()) } else { m });
        let mut h_out = vec![0.0; self.history.len()];
        let mut residual = f64::NAN;
        for iteration in 0..MAX_ITERATIONS {
            let up = self.law.update(&(self.elastic_strain + d), &self.history, &mut h_out)?;
            let r = DVector::from_iterator(
                free.len(),
                free.iter().map(|&a| {
                    let (i, j) = COMPONENTS[a];
                    up.stress[(i, j)] - if let Held::Stress(s) = held[a] { s } else { 0.0 }
                }),
            );
            let scale = self.stress.amax().max(held_scale).max(up.stress.amax()).max(f64::MIN_POSITIVE);
            residual = r.amax() / scale;
            if residual <= TOLERANCE {
                self.strain += d;
                self.elastic_strain = up.elastic_strain;
                self.stress = up.stress;
                self.history.copy_from_slice(&h_out);
                return Ok(());
            }
            // ∂σ_b/∂ε_a for a symmetric strain component a (both ε_ij and ε_ji move).
            let jacobian = DMatrix::from_fn(free.len(), free.len(), |r, c| {
                let ((k, l), (i, j)) = (COMPONENTS[free[r]], COMPONENTS[free[c]]);
                let mut v = up.tangent[(idx(k, l), idx(i, j))];
                if i != j {
                    v += up.tangent[(idx(k, l), idx(j, i))];
                }
                v
            });
            let delta = jacobian.lu().solve(&(-r)).ok_or(ConstitutiveError::ReturnMappingFailed {
                law: "element test's Newton on the held stresses (singular tangent)",
                iterations: iteration,
                residual,
            })?;
            for (n, &a) in free.iter().enumerate() {
                let (i, j) = COMPONENTS[a];
                d[(i, j)] += delta[n];
                d[(j, i)] = d[(i, j)];
            }
        }
        Err(ConstitutiveError::ReturnMappingFailed {
            law: "element test's Newton on the held stresses",
            iterations: MAX_ITERATIONS,
            residual,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{ConeFit, DruckerPrager, Elastic, MohrCoulomb};

    fn el() -> Elastic {
        Elastic::new(1.0e4, 0.3).unwrap()
    }

    /// Drained triaxial compression of an elastic point: q/ε_a = E (to round-off), and
    /// the lateral stress stays where it was held.
    #[test]
    fn drained_triaxial_of_an_elastic_point_gives_young() {
        let law = el();
        let start = Matrix3::identity() * -100.0;
        let mut t = ElementTest::new(&law, start).unwrap();
        for _ in 0..10 {
            t.step(ElementPath::TriaxialDrained.held(1e-4, &start)).unwrap();
        }
        let (_, q) = t.p_q();
        assert!((q / 1e-3 - 1.0e4).abs() < 1e-6 * 1.0e4);
        assert!((t.stress()[(0, 0)] + 100.0).abs() < 1e-8);
        // ε_lateral = −ν ε_axial.
        assert!((t.strain()[(0, 0)] - 0.3e-3).abs() < 1e-12);
    }

    /// Drained triaxial compression of Mohr–Coulomb (c = 0) ends at its strength:
    /// σ₁/σ₃ = (1 + sin φ)/(1 − sin φ) in compression, and the compression-fitted
    /// Drucker–Prager cone, which passes through that meridian, at the same q.
    #[test]
    fn drained_triaxial_reaches_the_compression_meridian() {
        let start = Matrix3::identity() * -100.0;
        let sf = 30f64.to_radians().sin();
        let expected = 100.0 * ((1.0 + sf) / (1.0 - sf) - 1.0);
        let mc = MohrCoulomb::from_degrees(el(), 0.0, 30.0, 0.0).unwrap();
        let dp = DruckerPrager::from_degrees(el(), 0.0, 30.0, 0.0, ConeFit::Compression).unwrap();
        for law in [&mc as &dyn ConstitutiveLaw, &dp] {
            let mut t = ElementTest::new(law, start).unwrap();
            for _ in 0..200 {
                t.step(ElementPath::TriaxialDrained.held(5e-4, &start)).unwrap();
            }
            let (_, q) = t.p_q();
            assert!((q - expected).abs() < 1e-8 * expected, "{}: q = {q}, expected {expected}", law.name());
        }
    }

    /// Oedometric and simple-shear steps hold what they say: no lateral strain; σ_zz fixed.
    #[test]
    fn oedometer_and_simple_shear_hold_their_components() {
        let law = DruckerPrager::from_degrees(el(), 5.0, 30.0, 10.0, ConeFit::PlaneStrain).unwrap();
        let start = Matrix3::identity() * -50.0;
        let mut t = ElementTest::new(&law, start).unwrap();
        for _ in 0..20 {
            t.step(ElementPath::Oedometer.held(1e-3, &start)).unwrap();
        }
        assert_eq!(t.strain()[(0, 0)], 0.0);
        assert!((t.strain()[(2, 2)] + 0.02).abs() < 1e-15);
        let now = *t.stress();
        for _ in 0..20 {
            t.step(ElementPath::SimpleShear.held(1e-3, &now)).unwrap();
        }
        assert!((t.stress()[(2, 2)] - now[(2, 2)]).abs() < 1e-8 * now.amax());
        assert!((t.strain()[(0, 2)] - (0.01 + 0.0)).abs() < 1e-15);
    }
}
