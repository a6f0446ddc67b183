//! Mohr–Coulomb plasticity in principal stresses (docs/theory.md §16; de Souza Neto, Perić & Owen
//! 2008, §8.2–8.3 and Appendix A.5; Clausen, Damkilde & Andersen 2007), with an optional
//! tension cut-off and linear softening of c, φ, ψ.
//!
//! # Conventions
//! Tension positive. Principal stresses ordered σ₁ ≥ σ₂ ≥ σ₃ (σ₃ is the major compression).
//! Main yield plane and potential:
//!
//! ```text
//! f = (σ₁ − σ₃) + (σ₁ + σ₃) sin φ − 2 c cos φ,   g = (σ₁ − σ₃) + (σ₁ + σ₃) sin ψ
//! ```
//!
//! (with compression-positive stresses σ'₁ = −σ₃ ≥ σ'₃ = −σ₁ this is the textbook
//! σ'₁ − σ'₃ = 2c cos φ + (σ'₁ + σ'₃) sin φ). The optional tension cut-off is the plane
//! f_t = σ₁ − σ_t (associated flow).
//!
//! # Return regions
//! Each region is a set of active constraints; the return solves them together with the
//! flow rule σ = σ_tr − Dᵉ Σ Δγ_j ∂g_j/∂σ (Dᵉ = λ 1⊗1 + 2G I in principal space). In this
//! order, the first region whose solution is admissible (all six Mohr–Coulomb planes and all
//! three cut-off planes satisfied to 1e-11·scale) with non-negative multipliers is taken:
//!
//! | region | active | stress after return |
//! |---|---|---|
//! | [`Plane`](MohrCoulombRegion::Plane) | f₁₃ | on the main plane |
//! | [`Cutoff`](MohrCoulombRegion::Cutoff) | σ₁ = σ_t | on the cut-off plane |
//! | [`Edge12`](MohrCoulombRegion::Edge12) | f₁₃, f₂₃ | σ₁ = σ₂ (triaxial-compression meridian) |
//! | [`Edge23`](MohrCoulombRegion::Edge23) | f₁₃, f₁₂ | σ₂ = σ₃ (triaxial-extension meridian) |
//! | [`CutoffPlane`](MohrCoulombRegion::CutoffPlane) | f₁₃, σ₁ = σ_t | line where the MC plane meets the cut-off |
//! | [`CutoffEdge12`](MohrCoulombRegion::CutoffEdge12) | σ₁ = σ_t, σ₂ = σ_t | σ₁ = σ₂ = σ_t |
//! | [`CutoffCorner23`](MohrCoulombRegion::CutoffCorner23) | f₁₃, f₁₂, σ₁ = σ_t | point σ₁ = σ_t, σ₂ = σ₃ on MC |
//! | [`CutoffApex`](MohrCoulombRegion::CutoffApex) | σ_i = σ_t, i = 1..3 | σ = σ_t I |
//! | [`CutoffCorner12`](MohrCoulombRegion::CutoffCorner12) | f₁₃, f₂₃, σ₁ = σ₂ = σ_t | point σ₁ = σ₂ = σ_t on MC |
//! | [`Apex`](MohrCoulombRegion::Apex) | all MC planes | σ = c cot φ I (φ > 0 only) |
//!
//! Here f_ij = (1 + sin φ) σ_i − (1 − sin φ) σ_j − 2c cos φ, so f₁₃ is the main plane and
//! f₂₃, f₁₂ are its neighbours across the edges σ₁ = σ₂ and σ₂ = σ₃. The last two regions
//! are vertices where four or more planes meet (the flow is not fixed by as many multipliers
//! as constraints): the stress is the vertex, the plastic strain is Dᵉ⁻¹(σ_tr − σ), and the
//! return is taken when no earlier region was valid and the vertex is admissible. The normal
//! cone of the plastic potentials is still checked and reported as
//! [`MohrCoulombReturn::fallback`] when it fails. In the tests this happens only at the
//! apex with ψ = 0 (e.g. a residual ψ_res = 0): non-dilatant flow cannot reach the apex
//! from a trial state beyond it, so the apex return supplies volumetric plastic strain that
//! the potential does not (the classical treatment of the apex for non-associated flow).
//! With ψ = φ and no softening the regions partition principal stress space and `fallback`
//! is never set (property-tested). If neither a flow region nor a vertex is accepted (never
//! observed), the admissible candidate closest in the energy norm is taken with `fallback`
//! set; if none is admissible the update fails with
//! [`ConstitutiveError::ReturnMappingFailed`]. Non-associated returns are not unique in
//! general; for them this priority order *defines* the return (continuity across region
//! boundaries is property-tested).
//!
//! φ = 0 is Tresca: the apex does not exist and no expression divides by sin φ or tan φ
//! (only the apex value c cos φ / sin φ, evaluated only for sin φ > 0).
//!
//! # Softening and history
//! X(κ) = X_res + (X₀ − X_res) max(0, 1 − κ/κ_res) for X ∈ {c, φ, ψ}, where κ is the
//! accumulated equivalent deviatoric plastic strain, κ̇ = √(2/3 ė^p : ė^p) (equal to the
//! axial plastic strain of isochoric uniaxial flow, and to γ^p/√3 in simple shear). It is
//! computed from the plastic strain increment itself, Δκ = √(2/3) ‖dev Δε^p‖, so that it is
//! defined identically in every region (including the apex, where Δε^p is fixed by the
//! stress and not by multipliers) and continuous across region boundaries. Cut-off flow
//! contributes to κ like any other plastic strain.
//!
//! History slots: `[0]` κ, `[1]` accumulated volumetric plastic strain ε_v^p = Σ tr Δε^p
//! (informative only; it drives nothing).
//!
//! The multipliers and κ solve a small nonlinear system by Newton's method (residuals to
//! 1e-12 relative plus one polishing iteration, at most 50 iterations); the piecewise-linear
//! softening law is handled as in the von Mises law: solve on the softening branch, and if
//! κ ends beyond κ_res redo the return on the residual (constant) branch.
//!
//! # Tangent
//! The principal algorithmic tangent ∂σ_A/∂ε_B follows from differentiating the converged
//! local system (implicit function theorem); the full tensor is
//! D = Σ_AB ∂σ_A/∂ε_B N_A⊗N_B + Σ_{A<B} 2 (σ_A − σ_B)/(ε_A − ε_B) S_AB⊗S_AB with
//! N_A = n_A⊗n_A, S_AB = sym(n_A⊗n_B) (de Souza Neto Appendix A.5). Pairs that a region
//! forces equal (edges, vertices) get a zero spin coefficient; distinct pairs with nearly
//! equal trial strains (|Δε| ≤ 1e-8 max|ε|) take the limit ½(∂σ_A/∂ε_A − ∂σ_A/∂ε_B +
//! ∂σ_B/∂ε_B − ∂σ_B/∂ε_A) instead of dividing.

use nalgebra::{Matrix3, Matrix4, Matrix4x3, Vector3, Vector4};

use crate::frictional::{frictional_inputs, Branch, FrictionalStrength};
use crate::tensor::{flatten, spectral, Tensor4};
use crate::{
    check_finite, ConstitutiveError, ConstitutiveLaw, Elastic, MaterialState, Softening, StrengthReducible,
    StressUpdate,
};

/// Return region of a Mohr–Coulomb update (see the module documentation for the table).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum MohrCoulombRegion {
    /// Trial state admissible: returned unchanged.
    Elastic,
    /// Main plane f₁₃ = 0 (one multiplier).
    Plane,
    /// Edge σ₁ = σ₂ (planes f₁₃ and f₂₃; triaxial-compression meridian in the
    /// tension-positive convention: the major compression σ₃ is the distinct one).
    Edge12,
    /// Edge σ₂ = σ₃ (planes f₁₃ and f₁₂; triaxial-extension meridian).
    Edge23,
    /// Apex σ = c cot φ I (φ > 0 only).
    Apex,
    /// Tension cut-off plane σ₁ = σ_t.
    Cutoff,
    /// Cut-off edge σ₁ = σ₂ = σ_t (two cut-off planes).
    CutoffEdge12,
    /// Line where the main MC plane meets the cut-off plane.
    CutoffPlane,
    /// Vertex σ₁ = σ_t, σ₂ = σ₃ on the MC surface.
    CutoffCorner23,
    /// Vertex σ₁ = σ₂ = σ_t on the MC surface.
    CutoffCorner12,
    /// Cut-off apex σ = σ_t I.
    CutoffApex,
}

impl MohrCoulombRegion {
    /// Principal pairs (0,1), (0,2), (1,2) that the region forces equal.
    fn tied(self) -> [bool; 3] {
        use MohrCoulombRegion::*;
        match self {
            Edge12 | CutoffEdge12 | CutoffCorner12 => [true, false, false],
            Edge23 | CutoffCorner23 => [false, false, true],
            Apex | CutoffApex => [true, true, true],
            Elastic | Plane | Cutoff | CutoffPlane => [false; 3],
        }
    }
}

/// Diagnostics of one update (see [`MohrCoulomb::update_with_info`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MohrCoulombReturn {
    pub region: MohrCoulombRegion,
    /// The accepted return did not satisfy the flow rule's sign conditions (only possible
    /// at the vertices, e.g. the apex with ψ < φ; see the module documentation).
    pub fallback: bool,
    /// Softening enabled and κ_{n+1} ≥ κ_res (the residual strength branch).
    pub residual_branch: bool,
}

/// Mohr–Coulomb with optional tension cut-off and linear softening (see module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MohrCoulomb {
    pub elastic: Elastic,
    /// Peak cohesion c ≥ 0.
    pub cohesion: f64,
    /// Peak friction angle φ in [0, π/2) (radians).
    pub friction: f64,
    /// Peak dilation angle ψ in [0, φ] (radians).
    pub dilation: f64,
    /// Tension cut-off σ_t (σ₁ ≤ σ_t), at most the peak apex value c cot φ.
    pub tension_cutoff: Option<f64>,
    pub softening: Option<Softening>,
}

/// Strength parameters at some κ on a branch, with their κ-derivatives.
#[derive(Debug, Clone, Copy)]
struct Params {
    c: f64,
    sphi: f64,
    cphi: f64,
    spsi: f64,
    cpsi: f64,
    dc: f64,
    dphi: f64,
    dpsi: f64,
}

/// A plane in ordered principal space.
#[derive(Debug, Clone, Copy)]
enum Surface {
    /// f_ij = (1 + sin φ) σ_i − (1 − sin φ) σ_j − 2c cos φ.
    Mc(usize, usize),
    /// σ_i − σ_t.
    Cut(usize),
}

fn unit(i: usize) -> Vector3<f64> {
    let mut v = Vector3::zeros();
    v[i] = 1.0;
    v
}

fn dev3(v: &Vector3<f64>) -> Vector3<f64> {
    v - Vector3::repeat(v.sum() / 3.0)
}

impl Surface {
    fn f(self, sig: &Vector3<f64>, p: &Params, t: f64) -> f64 {
        match self {
            Surface::Mc(i, j) => (1.0 + p.sphi) * sig[i] - (1.0 - p.sphi) * sig[j] - 2.0 * p.c * p.cphi,
            Surface::Cut(i) => sig[i] - t,
        }
    }
    /// ∂f/∂σ.
    fn a(self, p: &Params) -> Vector3<f64> {
        match self {
            Surface::Mc(i, j) => unit(i) * (1.0 + p.sphi) - unit(j) * (1.0 - p.sphi),
            Surface::Cut(i) => unit(i),
        }
    }
    /// ∂g/∂σ (flow direction).
    fn b(self, p: &Params) -> Vector3<f64> {
        match self {
            Surface::Mc(i, j) => unit(i) * (1.0 + p.spsi) - unit(j) * (1.0 - p.spsi),
            Surface::Cut(i) => unit(i),
        }
    }
    /// ∂b/∂κ.
    fn db(self, p: &Params) -> Vector3<f64> {
        match self {
            Surface::Mc(i, j) => (unit(i) + unit(j)) * (p.cpsi * p.dpsi),
            Surface::Cut(_) => Vector3::zeros(),
        }
    }
    /// ∂f/∂κ at fixed σ.
    fn df(self, sig: &Vector3<f64>, p: &Params) -> f64 {
        match self {
            Surface::Mc(i, j) => {
                p.cphi * p.dphi * (sig[i] + sig[j]) - 2.0 * p.dc * p.cphi + 2.0 * p.c * p.sphi * p.dphi
            }
            Surface::Cut(_) => 0.0,
        }
    }
}

use MohrCoulombRegion as R;
use Surface::{Cut, Mc};

/// Flow regions in priority order (the vertex regions CutoffCorner12 and Apex follow).
const FLOW_REGIONS: [(MohrCoulombRegion, &[Surface], bool); 8] = [
    (R::Plane, &[Mc(0, 2)], false),
    (R::Cutoff, &[Cut(0)], true),
    (R::Edge12, &[Mc(0, 2), Mc(1, 2)], false),
    (R::Edge23, &[Mc(0, 2), Mc(0, 1)], false),
    (R::CutoffPlane, &[Mc(0, 2), Cut(0)], true),
    (R::CutoffEdge12, &[Cut(0), Cut(1)], true),
    (R::CutoffCorner23, &[Mc(0, 2), Mc(0, 1), Cut(0)], true),
    (R::CutoffApex, &[Cut(0), Cut(1), Cut(2)], true),
];

/// √(2/3): Δκ = √(2/3) ‖dev Δε^p‖.
fn alpha() -> f64 {
    (2.0f64 / 3.0).sqrt()
}
/// Elastic trial states with f ≤ ELASTIC_TOL·scale are returned unchanged.
const ELASTIC_TOL: f64 = 1e-12;
/// A candidate is admissible when every plane is satisfied to ADMISSIBLE_TOL·scale.
const ADMISSIBLE_TOL: f64 = 1e-11;
/// Newton residual tolerance (relative).
const NEWTON_TOL: f64 = 1e-12;
const MAX_ITERATIONS: usize = 50;

/// Trial data shared by the candidate solvers.
struct Trial {
    e: Vector3<f64>,
    sig: Vector3<f64>,
    kappa_n: f64,
    de: Matrix3<f64>,
    de_inv: Matrix3<f64>,
    g: f64,
    scale: f64,
}

/// A converged candidate return in principal space.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    region: MohrCoulombRegion,
    sig: Vector3<f64>,
    deps_p: Vector3<f64>,
    kappa: f64,
    branch: Branch,
    /// ∂σ_A/∂ε_tr,B.
    jp: Matrix3<f64>,
    /// Multipliers non-negative (flow regions) / plastic strain in the normal cone of the
    /// potentials (vertices).
    flow_ok: bool,
}

/// The local system of a flow return at one iterate (see `MohrCoulomb::flow_system`).
struct FlowSystem {
    p: Params,
    /// The plastic flow directions b_j of the planes.
    bs: [Vector3<f64>; 3],
    eps_p: Vector3<f64>,
    /// Σ Δγ_j ∂b_j/∂κ.
    dbsum: Vector3<f64>,
    sig: Vector3<f64>,
    r: Vector4<f64>,
    jm: Matrix4<f64>,
}

/// The principal tangent ∂σ_A/∂ε_tr,B of a converged flow return: dx/dσ_tr = −J⁻¹ ∂R/∂σ_tr
/// with ∂r_j/∂σ_tr = a_j, ∂r_κ/∂σ_tr = 0.
fn flow_tangent(set: &[Surface], tr: &Trial, sys: &FlowSystem, jinv: &Matrix4<f64>) -> Matrix3<f64> {
    let mut rs = Matrix4x3::zeros();
    for (j, surf) in set.iter().enumerate() {
        rs.set_row(j, &surf.a(&sys.p).transpose());
    }
    let dx = -(jinv * rs);
    let mut dsig = Matrix3::identity();
    for (i, b) in sys.bs.iter().enumerate().take(set.len()) {
        dsig -= (tr.de * b) * dx.row(i);
    }
    dsig -= (tr.de * sys.dbsum) * dx.row(3);
    dsig * tr.de
}

impl MohrCoulomb {
    /// Angles in radians. Validates c ≥ 0, 0 ≤ φ < π/2, 0 ≤ ψ ≤ φ (all finite).
    pub fn new(elastic: Elastic, cohesion: f64, friction: f64, dilation: f64) -> Result<Self, ConstitutiveError> {
        let law = Self { elastic, cohesion, friction, dilation, tension_cutoff: None, softening: None };
        law.validate()?;
        Ok(law)
    }

    /// Angles in degrees.
    pub fn from_degrees(
        elastic: Elastic,
        cohesion: f64,
        friction_deg: f64,
        dilation_deg: f64,
    ) -> Result<Self, ConstitutiveError> {
        Self::new(elastic, cohesion, friction_deg.to_radians(), dilation_deg.to_radians())
    }

    /// Adds the cut-off plane σ₁ ≤ σ_t; σ_t must be finite and, for φ > 0, at most the peak
    /// apex value c cot φ.
    pub fn with_tension_cutoff(mut self, tension: f64) -> Result<Self, ConstitutiveError> {
        self.tension_cutoff = Some(tension);
        self.validate()?;
        Ok(self)
    }

    /// Linear softening to residual values (angles in degrees) at κ = κ_res > 0. Requires
    /// 0 ≤ c_res ≤ c, 0 ≤ φ_res ≤ φ, 0 ≤ ψ_res ≤ min(ψ, φ_res).
    pub fn with_softening(
        mut self,
        cohesion_res: f64,
        friction_res_deg: f64,
        dilation_res_deg: f64,
        kappa_res: f64,
    ) -> Result<Self, ConstitutiveError> {
        self.softening = Some(Softening {
            cohesion: cohesion_res,
            friction: friction_res_deg.to_radians(),
            dilation: dilation_res_deg.to_radians(),
            kappa: kappa_res,
        });
        self.validate()?;
        Ok(self)
    }

    fn validate(&self) -> Result<(), ConstitutiveError> {
        let bad = |name: &'static str, value: f64| Err(ConstitutiveError::InvalidParameter { name, value });
        Elastic::new(self.elastic.young, self.elastic.poisson)?;
        self.frictional().validate_peak()?;
        if let Some(t) = self.tension_cutoff {
            if !t.is_finite() {
                return bad("tension_cutoff", t);
            }
            if self.friction > 0.0 {
                let apex = self.cohesion * self.friction.cos() / self.friction.sin();
                if t > apex + 1e-12 * apex.abs() {
                    return bad("tension_cutoff", t);
                }
            }
        }
        self.frictional().validate_softening()
    }

    /// The peak strength and its softening, as the frictional laws share them.
    fn frictional(&self) -> FrictionalStrength {
        FrictionalStrength {
            cohesion: self.cohesion,
            friction: self.friction,
            dilation: self.dilation,
            softening: self.softening,
        }
    }

    /// True when the softening law makes c, φ or ψ vary.
    fn softens(&self) -> bool {
        self.frictional().softens()
    }

    /// (c, φ, ψ) at accumulated plastic strain κ (angles in radians).
    pub fn strength(&self, kappa: f64) -> (f64, f64, f64) {
        self.frictional().at(kappa)
    }

    fn branch_at(&self, kappa: f64) -> Branch {
        self.frictional().branch_at(kappa)
    }

    fn params(&self, kappa: f64, branch: Branch) -> Params {
        let s = self.frictional().on_branch(kappa, branch);
        Params {
            c: s.c,
            sphi: s.phi.sin(),
            cphi: s.phi.cos(),
            spsi: s.psi.sin(),
            cpsi: s.psi.cos(),
            dc: s.dc,
            dphi: s.dphi,
            dpsi: s.dpsi,
        }
    }

    /// (f_MC, f_t) of principal stresses in any order: f_MC = max over the six planes, f_t =
    /// max σ_i − σ_t (−∞ without cut-off).
    fn yield_principal(&self, sig: &Vector3<f64>, p: &Params) -> (f64, f64) {
        let (mx, mn) = (sig.max(), sig.min());
        let f = (1.0 + p.sphi) * mx - (1.0 - p.sphi) * mn - 2.0 * p.c * p.cphi;
        let ft = self.tension_cutoff.map_or(f64::NEG_INFINITY, |t| mx - t);
        (f, ft)
    }

    /// Yield function values (f_MC, f_t) of a stress tensor at accumulated plastic strain κ
    /// (f_t = None without cut-off). f_MC is the Mohr–Coulomb function of the ordered
    /// principal stresses, f_t = σ₁ − σ_t.
    pub fn yield_function(&self, stress: &Matrix3<f64>, kappa: f64) -> Result<(f64, Option<f64>), ConstitutiveError> {
        let s = spectral(stress)?;
        let p = self.params(kappa, self.branch_at(kappa));
        let (f, ft) = self.yield_principal(&s.values, &p);
        Ok((f, self.tension_cutoff.map(|_| ft)))
    }

    fn admissible(&self, sig: &Vector3<f64>, p: &Params, scale: f64) -> bool {
        let (f, ft) = self.yield_principal(sig, p);
        let tol = ADMISSIBLE_TOL * scale;
        f <= tol && ft <= tol
    }

    /// Runs `solve` on the branch(es) the softening law needs (see module docs).
    fn on_branches(
        &self,
        kappa_n: f64,
        solve: impl Fn(Branch) -> Result<Option<Candidate>, ConstitutiveError>,
    ) -> Result<Option<Candidate>, ConstitutiveError> {
        self.frictional().on_branches(kappa_n, |c: &Candidate| c.kappa, solve)
    }

    /// Return to the planes `set` (1–3 of them) with as many multipliers, by Newton on the
    /// local system ([`flow_system`](Self::flow_system)), polished by one iteration past
    /// convergence. `Ok(None)` when the local system is singular (the region does not
    /// exist for these parameters).
    fn solve_flow(
        &self,
        region: MohrCoulombRegion,
        set: &[Surface],
        tr: &Trial,
        branch: Branch,
    ) -> Result<Option<Candidate>, ConstitutiveError> {
        let m = set.len();
        let mut dg = [0.0f64; 3];
        let mut kappa = tr.kappa_n;
        let mut polished = false;
        let mut last = f64::NAN;
        for _ in 0..MAX_ITERATIONS {
            let sys = self.flow_system(set, tr, branch, &dg, kappa);
            let (r, jm) = (&sys.r, &sys.jm);
            if !(r.iter().all(|v| v.is_finite()) && jm.iter().all(|v| v.is_finite())) {
                return Err(ConstitutiveError::ReturnMappingFailed {
                    law: "mohr-coulomb",
                    iterations: MAX_ITERATIONS,
                    residual: f64::NAN,
                });
            }
            let rf = (0..m).map(|j| r[j].abs()).fold(0.0, f64::max);
            last = rf / tr.scale;
            // κ residual relative to κ or, for κ ≈ 0, to the plastic strain it comes from.
            let conv = rf <= NEWTON_TOL * tr.scale && r[3].abs() <= NEWTON_TOL * kappa.abs().max(sys.eps_p.norm());
            // Singular local system: Hadamard ratio |det| / Π ‖row‖.
            let hadamard: f64 = jm.row_iter().map(|row| row.norm()).product();
            let det = determinant4(jm);
            // jm is finite here, but its minors may overflow and make det NaN, which
            // counts as singular.
            if det.is_nan() || det.abs() <= 1e-12 * hadamard {
                return Ok(None);
            }
            let Some(jinv) = jm.try_inverse() else {
                return Ok(None);
            };
            if conv && polished {
                let jp = flow_tangent(set, tr, &sys, &jinv);
                let gmax = dg[..m].iter().fold(0.0f64, |a, &v| a.max(v.abs()));
                let flow_ok = dg[..m].iter().all(|&v| v >= -1e-12 * gmax);
                return Ok(Some(Candidate { region, sig: sys.sig, deps_p: sys.eps_p, kappa, branch, jp, flow_ok }));
            }
            if conv {
                polished = true;
            }
            let delta = -(jinv * r);
            for j in 0..m {
                dg[j] += delta[j];
            }
            kappa = (kappa + delta[3]).max(tr.kappa_n);
        }
        Err(ConstitutiveError::ReturnMappingFailed { law: "mohr-coulomb", iterations: MAX_ITERATIONS, residual: last })
    }

    /// The local system of a return to the planes `set` at multipliers `dg` and κ: the
    /// plastic strain Σ Δγ_j b_j, the stress, the residual (one yield function per plane,
    /// then κ − κ_n − α ‖dev Δε^p‖) and its Jacobian in (Δγ, κ).
    fn flow_system(&self, set: &[Surface], tr: &Trial, branch: Branch, dg: &[f64; 3], kappa: f64) -> FlowSystem {
        let m = set.len();
        let t = self.tension_cutoff.unwrap_or(f64::INFINITY);
        let al = alpha();
        let p = self.params(kappa, branch);
        let bs: [Vector3<f64>; 3] = std::array::from_fn(|j| set.get(j).map_or(Vector3::zeros(), |s| s.b(&p)));
        let mut eps_p = Vector3::zeros();
        let mut dbsum = Vector3::zeros();
        for j in 0..m {
            eps_p += bs[j] * dg[j];
            dbsum += set[j].db(&p) * dg[j];
        }
        let sig = tr.sig - tr.de * eps_p;
        let w = dev3(&eps_p);
        let nw = w.norm();
        // ‖dev Δε^p‖ is not differentiable at 0 (e.g. hydrostatic flow at the cut-off
        // apex): below round-off level use the zero subgradient.
        let what = if nw > 1e-14 * eps_p.norm() { w / nw } else { Vector3::zeros() };
        let mut r = Vector4::zeros();
        let mut jm = Matrix4::identity();
        for j in 0..m {
            r[j] = set[j].f(&sig, &p, t);
            let a = set[j].a(&p);
            for i in 0..m {
                jm[(j, i)] = -a.dot(&(tr.de * bs[i]));
            }
            jm[(j, 3)] = -a.dot(&(tr.de * dbsum)) + set[j].df(&sig, &p);
        }
        r[3] = kappa - tr.kappa_n - al * nw;
        for i in 0..m {
            jm[(3, i)] = -al * what.dot(&bs[i]);
        }
        jm[(3, 3)] = 1.0 - al * what.dot(&dbsum);
        FlowSystem { p, bs, eps_p, dbsum, sig, r, jm }
    }

    /// Vertex σ₁ = σ₂ = σ_t on the MC surface: σ₃ = ((1 + sin φ) σ_t − 2c cos φ)/(1 − sin φ),
    /// with κ from the scalar equation κ = κ_n + √(2/3)/(2G) ‖dev(σ_tr − σ_V(κ))‖.
    fn solve_corner12(&self, tr: &Trial, branch: Branch) -> Result<Option<Candidate>, ConstitutiveError> {
        let Some(t) = self.tension_cutoff else {
            return Ok(None);
        };
        let beta = alpha() / (2.0 * tr.g);
        let mut kappa = tr.kappa_n;
        let mut polished = false;
        let mut last = f64::NAN;
        for _ in 0..MAX_ITERATIONS {
            let p = self.params(kappa, branch);
            let den = 1.0 - p.sphi;
            let num = (1.0 + p.sphi) * t - 2.0 * p.c * p.cphi;
            let s3 = num / den;
            let dnum = p.cphi * p.dphi * t - 2.0 * p.dc * p.cphi + 2.0 * p.c * p.sphi * p.dphi;
            let ds3 = (dnum + s3 * p.cphi * p.dphi) / den;
            let sigv = Vector3::new(t, t, s3);
            let dsigv = Vector3::new(0.0, 0.0, ds3);
            let u = dev3(&(tr.sig - sigv));
            let nu = u.norm();
            let uhat = if nu > 1e-14 * tr.sig.norm() { u / nu } else { Vector3::zeros() };
            let r = kappa - tr.kappa_n - beta * nu;
            let dr = 1.0 + beta * uhat.dot(&dsigv);
            if !(r.is_finite() && dr.is_finite()) || dr.abs() < 1e-12 {
                return Err(ConstitutiveError::ReturnMappingFailed {
                    law: "mohr-coulomb",
                    iterations: MAX_ITERATIONS,
                    residual: r,
                });
            }
            last = r;
            let conv = r.abs() <= NEWTON_TOL * kappa.abs().max(beta * u.norm());
            if conv && polished {
                // dκ/dσ_tr = β û / dr; dσ/dσ_tr = σ_V' ⊗ dκ/dσ_tr; Dᵉ û = 2G û (û deviatoric).
                let jp = dsigv * (uhat * (alpha() / dr)).transpose();
                let deps_p = tr.de_inv * (tr.sig - sigv);
                let gens = [Mc(0, 2).b(&p), Mc(1, 2).b(&p), unit(0), unit(1)];
                return Ok(Some(Candidate {
                    region: R::CutoffCorner12,
                    sig: sigv,
                    deps_p,
                    kappa,
                    branch,
                    jp,
                    flow_ok: in_cone(&deps_p, &gens),
                }));
            }
            if conv {
                polished = true;
            }
            kappa = (kappa - r / dr).max(tr.kappa_n);
        }
        Err(ConstitutiveError::ReturnMappingFailed { law: "mohr-coulomb", iterations: MAX_ITERATIONS, residual: last })
    }

    /// Apex σ = c cot φ I. Δε^p = ε_tr − Dᵉ⁻¹σ has deviatoric part dev ε_tr, so κ is
    /// explicit: κ = κ_n + √(2/3) ‖dev ε_tr‖. `None` when φ(κ) = 0 (no apex).
    fn solve_apex(&self, tr: &Trial) -> Option<Candidate> {
        let de = dev3(&tr.e);
        let nde = de.norm();
        // Zero subgradient of ‖dev ε_tr‖ for a (round-off) hydrostatic trial, which is what
        // a symmetric difference quotient sees.
        let what = if nde > 1e-14 * tr.e.norm() { de / nde } else { Vector3::zeros() };
        let kappa = tr.kappa_n + alpha() * nde;
        let branch = self.branch_at(kappa);
        let p = self.params(kappa, branch);
        if p.sphi <= 0.0 {
            return None;
        }
        let pa = p.c * p.cphi / p.sphi;
        // d(c cot φ)/dκ = c' cot φ − c φ'/sin²φ.
        let dpa = p.dc * p.cphi / p.sphi - p.c * p.dphi / (p.sphi * p.sphi);
        let sig = Vector3::repeat(pa);
        let jp = Vector3::repeat(1.0) * (what * (dpa * alpha())).transpose();
        let deps_p = tr.de_inv * (tr.sig - sig);
        let gens = [Mc(0, 2).b(&p), Mc(1, 2).b(&p), Mc(0, 1).b(&p), Mc(2, 0).b(&p), Mc(2, 1).b(&p), Mc(1, 0).b(&p)];
        if !(sig.iter().chain(jp.iter()).all(|v| v.is_finite())) {
            return None;
        }
        Some(Candidate { region: R::Apex, sig, deps_p, kappa, branch, jp, flow_ok: in_cone(&deps_p, &gens) })
    }

    /// The stress update with its return region and diagnostics: the trial state in
    /// principal space, then either the elastic update or the return the regions admit,
    /// rotated back to the full space with its consistent tangent.
    pub fn update_with_info(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<(StressUpdate, MohrCoulombReturn), ConstitutiveError> {
        let (r, info) = self.returned(eps_trial, h_n, h_out)?;
        let tangent = match &r.flow {
            None => self.elastic.stiffness(),
            Some(flow) => flow.tangent()?,
        };
        Ok((StressUpdate { stress: r.stress, elastic_strain: r.elastic_strain, tangent }, info))
    }

    /// The trial state in principal space, then either the elastic update or the return the
    /// regions admit, rotated back to the full space, with the new history in `h_out`: all
    /// of an update but its tangent. (`update_with_info` checks the tangent after `h_out` is
    /// written; a caller drops the history of a failed update.)
    fn returned(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<(Returned, MohrCoulombReturn), ConstitutiveError> {
        let (kappa_n, evp_n) = frictional_inputs(eps_trial, h_n, h_out, "Mohr-Coulomb history")?;
        let eps = (eps_trial + eps_trial.transpose()) * 0.5;
        let (tr, n) = self.principal_trial(&eps, kappa_n)?;
        let branch_n = self.branch_at(kappa_n);
        let (f_tr, ft_tr) = self.yield_principal(&tr.sig, &self.params(kappa_n, branch_n));
        if f_tr <= ELASTIC_TOL * tr.scale && ft_tr <= ELASTIC_TOL * tr.scale {
            h_out[0] = kappa_n;
            h_out[1] = evp_n;
            let info = MohrCoulombReturn {
                region: R::Elastic,
                fallback: false,
                residual_branch: branch_n == Branch::Residual,
            };
            // Exactly the elastic law's update of the input (not of its symmetrised copy).
            let r = Returned { stress: self.elastic.stress(eps_trial), elastic_strain: *eps_trial, flow: None };
            return Ok((r, info));
        }
        let Some((mut c, fallback)) = self.select_return(&tr)? else {
            return Err(ConstitutiveError::ReturnMappingFailed { law: "mohr-coulomb", iterations: 0, residual: f_tr });
        };
        tie_equalities(&mut c);
        let (stress, elastic_strain) = full_space(&n, &eps, &c)?;
        h_out[0] = c.kappa;
        h_out[1] = evp_n + c.deps_p.sum();
        let info = MohrCoulombReturn { region: c.region, fallback, residual_branch: c.branch == Branch::Residual };
        Ok((Returned { stress, elastic_strain, flow: Some(PrincipalReturn { n, e: tr.e, c }) }, info))
    }

    /// The trial state in principal space, principal values descending (σ₁ ≥ σ₂ ≥ σ₃
    /// follows since σ_A = λ tr ε + 2G ε_A), with the principal directions as columns.
    fn principal_trial(&self, eps: &Matrix3<f64>, kappa_n: f64) -> Result<(Trial, Matrix3<f64>), ConstitutiveError> {
        let (lambda, g) = self.elastic.lame();
        let spec = spectral(eps)?;
        let mut order = [0usize, 1, 2];
        order.sort_by(|&a, &b| spec.values[b].total_cmp(&spec.values[a]));
        let e = Vector3::from_fn(|a, _| spec.values[order[a]]);
        let n = Matrix3::from_fn(|r, c| spec.vectors[(r, order[c])]);
        let de = Matrix3::repeat(lambda) + Matrix3::identity() * (2.0 * g);
        let de_inv = (Matrix3::identity() - Matrix3::repeat(lambda / (3.0 * lambda + 2.0 * g))) / (2.0 * g);
        let sig = de * e;
        if !sig.iter().all(|v| v.is_finite()) {
            return Err(ConstitutiveError::NonFinite { what: "Mohr-Coulomb trial stress" });
        }
        let scale = sig.amax().max(self.cohesion).max(self.tension_cutoff.map_or(0.0, f64::abs)).max(f64::MIN_POSITIVE);
        Ok((Trial { e, sig, kappa_n, de, de_inv, g, scale }, n))
    }

    /// The return: the first flow region whose multipliers are non-negative and whose
    /// stress is admissible, else a vertex, else (not expected, see module docs) the
    /// closest admissible candidate in the energy norm; with whether it was a fallback.
    fn select_return(&self, tr: &Trial) -> Result<Option<(Candidate, bool)>, ConstitutiveError> {
        let kappa_n = tr.kappa_n;
        let admissible = |c: &Candidate| self.admissible(&c.sig, &self.params(c.kappa, c.branch), tr.scale);
        // Rejected candidates (at most 8 flow regions + 2 vertices; no heap allocation).
        let mut seen: [Option<Candidate>; 10] = [None; 10];
        let mut n_seen = 0;
        let mut remember = |c: Candidate| {
            seen[n_seen] = Some(c);
            n_seen += 1;
        };
        for (region, set, needs_cutoff) in FLOW_REGIONS {
            if needs_cutoff && self.tension_cutoff.is_none() {
                continue;
            }
            if let Some(c) = self.on_branches(kappa_n, |b| self.solve_flow(region, set, tr, b))? {
                if c.flow_ok && admissible(&c) {
                    return Ok(Some((c, false)));
                }
                remember(c);
            }
        }
        // Vertices where more planes meet than there are constraints.
        let corner = self.on_branches(kappa_n, |b| self.solve_corner12(tr, b))?;
        for c in corner.into_iter().chain(self.solve_apex(tr)) {
            if admissible(&c) {
                return Ok(Some((c, !c.flow_ok)));
            }
            remember(c);
        }
        let energy = |c: &Candidate| c.deps_p.dot(&(tr.de * c.deps_p));
        Ok(seen
            .iter()
            .flatten()
            .filter(|c| admissible(c))
            .min_by(|a, b| energy(a).total_cmp(&energy(b)))
            .map(|c| (*c, true)))
    }
}

/// det m of a 4 × 4 by its 2 × 2 minors (Laplace along the first two rows): where nalgebra's
/// `determinant` factors a 4 × 4 by LU, a tenth of an explicit Mohr–Coulomb run (V8). Used
/// only to tell a singular local system, so its round-off need not match the LU's.
fn determinant4(m: &Matrix4<f64>) -> f64 {
    let low = |i: usize, j: usize| m[(0, i)] * m[(1, j)] - m[(0, j)] * m[(1, i)];
    let high = |i: usize, j: usize| m[(2, i)] * m[(3, j)] - m[(2, j)] * m[(3, i)];
    low(0, 1) * high(2, 3) - low(0, 2) * high(1, 3) + low(0, 3) * high(1, 2) + low(1, 2) * high(0, 3)
        - low(1, 3) * high(0, 2)
        + low(2, 3) * high(0, 1)
}

/// Enforce the equalities of principal stresses the return region implies exactly (they
/// hold to round-off).
fn tie_equalities(c: &mut Candidate) {
    let tied = c.region.tied();
    if tied == [true; 3] {
        c.sig = Vector3::repeat(c.sig.mean());
    } else if tied[0] {
        let m = 0.5 * (c.sig[0] + c.sig[1]);
        c.sig[0] = m;
        c.sig[1] = m;
    } else if tied[2] {
        let m = 0.5 * (c.sig[1] + c.sig[2]);
        c.sig[1] = m;
        c.sig[2] = m;
    }
}

/// An update's stress and elastic strain, and its return where it flowed.
struct Returned {
    stress: Matrix3<f64>,
    elastic_strain: Matrix3<f64>,
    flow: Option<PrincipalReturn>,
}

/// A return `c` from the principal trial (principal strains `e`, directions `n`).
struct PrincipalReturn {
    n: Matrix3<f64>,
    e: Vector3<f64>,
    c: Candidate,
}

impl PrincipalReturn {
    /// The consistent tangent in the full space ([`assemble`]); an error where it is not
    /// finite.
    fn tangent(&self) -> Result<Tensor4, ConstitutiveError> {
        let Self { n, e, c } = self;
        let tangent = assemble(n, e, &c.sig, &c.jp, c.region.tied());
        if !tangent.iter().all(|v| v.is_finite()) {
            return Err(ConstitutiveError::NonFinite { what: "Mohr-Coulomb tangent" });
        }
        Ok(tangent)
    }
}

/// The returned state in the full space: stress and plastic strain rotated back from the
/// principal directions `n`, and the elastic strain.
fn full_space(
    n: &Matrix3<f64>,
    eps: &Matrix3<f64>,
    c: &Candidate,
) -> Result<(Matrix3<f64>, Matrix3<f64>), ConstitutiveError> {
    let stress = n * Matrix3::from_diagonal(&c.sig) * n.transpose();
    let stress = (stress + stress.transpose()) * 0.5;
    let eps_p = n * Matrix3::from_diagonal(&c.deps_p) * n.transpose();
    let elastic_strain = eps - (eps_p + eps_p.transpose()) * 0.5;
    check_finite(&stress, "Mohr-Coulomb stress")?;
    Ok((stress, elastic_strain))
}

/// Full tangent from the principal one (de Souza Neto Appendix A.5), see module docs.
fn assemble(n: &Matrix3<f64>, e: &Vector3<f64>, sig: &Vector3<f64>, jp: &Matrix3<f64>, tied: [bool; 3]) -> Tensor4 {
    let na: [_; 3] = std::array::from_fn(|a| {
        let v = n.column(a);
        flatten(&(v * v.transpose()))
    });
    let mut d = Tensor4::zeros();
    for a in 0..3 {
        for b in 0..3 {
            d += na[a] * na[b].transpose() * jp[(a, b)];
        }
    }
    let emax = e.amax();
    for (k, (a, b)) in [(0usize, 1usize), (0, 2), (1, 2)].into_iter().enumerate() {
        let theta = if tied[k] {
            0.0
        } else if (e[a] - e[b]).abs() > 1e-8 * emax {
            (sig[a] - sig[b]) / (e[a] - e[b])
        } else {
            0.5 * ((jp[(a, a)] - jp[(a, b)]) + (jp[(b, b)] - jp[(b, a)]))
        };
        let p = n.column(a) * n.column(b).transpose();
        let s = flatten(&((p + p.transpose()) * 0.5));
        d += s * s.transpose() * (2.0 * theta);
    }
    d
}

/// Whether v lies in the cone spanned by `gens` (Carathéodory: some ≤ 3 of them with
/// non-negative coefficients), to a relative tolerance of 1e-9.
fn in_cone(v: &Vector3<f64>, gens: &[Vector3<f64>]) -> bool {
    let nv = v.norm();
    if nv == 0.0 {
        return true;
    }
    let tol = 1e-9;
    let k = gens.len();
    for i in 0..k {
        for j in (i + 1)..k {
            for l in (j + 1)..k {
                let m = Matrix3::from_columns(&[gens[i], gens[j], gens[l]]);
                let scale = gens[i].norm() * gens[j].norm() * gens[l].norm();
                if m.determinant().abs() <= 1e-10 * scale {
                    continue;
                }
                if let Some(inv) = m.try_inverse() {
                    let x = inv * v;
                    if (0..3).all(|q| x[q] * m.column(q).norm() >= -tol * nv) {
                        return true;
                    }
                }
            }
        }
    }
    // Rank-deficient generator sets: pairs and singles by least squares.
    for i in 0..k {
        for j in i..k {
            let (gi, gj) = (gens[i], gens[j]);
            let (x, y) = if i == j {
                (gi.dot(v) / gi.norm_squared(), 0.0)
            } else {
                let (a11, a12, a22) = (gi.norm_squared(), gi.dot(&gj), gj.norm_squared());
                let det = a11 * a22 - a12 * a12;
                if det <= 1e-12 * a11 * a22 {
                    continue;
                }
                let (b1, b2) = (gi.dot(v), gj.dot(v));
                ((a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det)
            };
            let res = (v - gi * x - gj * y).norm();
            if res <= tol * nv && x * gi.norm() >= -tol * nv && y * gj.norm() >= -tol * nv {
                return true;
            }
        }
    }
    false
}

impl StrengthReducible for MohrCoulomb {
    /// c/F, φ_F = atan(tan φ / F), ψ_F = min(ψ, φ_F) (a dilation above the reduced
    /// friction would break ψ ≤ φ), the tension cut-off over F (the apex c cot φ is
    /// unchanged) and the residual values of softening alike.
    fn with_strength_reduced(&self, factor: f64) -> Result<std::sync::Arc<dyn ConstitutiveLaw>, ConstitutiveError> {
        let reduced = self.frictional().reduced(factor)?;
        let law = Self {
            elastic: self.elastic,
            cohesion: reduced.cohesion,
            friction: reduced.friction,
            dilation: reduced.dilation,
            tension_cutoff: self.tension_cutoff.map(|t| t / factor),
            softening: reduced.softening,
        };
        law.validate().map(|()| std::sync::Arc::new(law) as std::sync::Arc<dyn ConstitutiveLaw>)
    }
}

impl ConstitutiveLaw for MohrCoulomb {
    fn elasticity(&self, _state: &MaterialState) -> Option<Elastic> {
        Some(self.elastic)
    }

    fn as_strength_reducible(&self) -> Option<&dyn StrengthReducible> {
        Some(self)
    }

    fn name(&self) -> &'static str {
        "mohr-coulomb"
    }

    fn history_len(&self) -> usize {
        2
    }

    fn history_names(&self) -> &'static [&'static str] {
        &["plastic_shear_strain", "plastic_volumetric_strain"]
    }

    fn plastic_strain(&self, h: &[f64]) -> f64 {
        h[0]
    }

    /// f_MC or f_t within 1e-6 of the strength scale max(c, |σ|) of zero.
    fn is_yielding(&self, stress: &Matrix3<f64>, h: &[f64]) -> bool {
        let Ok((f, ft)) = self.yield_function(stress, h[0]) else { return false };
        let tol = 1e-6 * self.strength(h[0]).0.max(stress.norm());
        f >= -tol || ft.is_some_and(|ft| ft >= -tol)
    }

    /// Symmetric for associated flow (ψ = φ) without softening. Softening couples the yield
    /// normals to κ (and κ to the plastic strain norm), which breaks symmetry in general.
    fn symmetric_tangent(&self) -> bool {
        self.dilation == self.friction && !self.softens()
    }

    fn can_soften(&self) -> bool {
        self.softens()
    }

    fn update(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<StressUpdate, ConstitutiveError> {
        self.update_with_info(eps_trial, h_n, h_out).map(|(u, _)| u)
    }

    /// [`MohrCoulomb::update_with_info`]'s stress and elastic strain without assembling the
    /// consistent tangent (a 9 × 9 sum of outer products), which an explicit step has no
    /// use for — nor, then, refusing a non-finite tangent, as `update` does.
    fn update_stress(
        &self,
        eps_trial: &Matrix3<f64>,
        h_n: &[f64],
        h_out: &mut [f64],
    ) -> Result<(Matrix3<f64>, Matrix3<f64>), ConstitutiveError> {
        let (r, _) = self.returned(eps_trial, h_n, h_out)?;
        Ok((r.stress, r.elastic_strain))
    }

    fn p_wave_modulus(&self, _state: &MaterialState) -> f64 {
        self.elastic.p_wave_modulus()
    }

    fn stored_energy(&self, elastic_strain: &Matrix3<f64>) -> f64 {
        self.elastic.stored_energy(elastic_strain)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tensor::idx;

    /// The minors' determinant against nalgebra's LU on matrices with an exact determinant
    /// (integers: every product and sum exact) and on a general one (round-off, 1e-13
    /// relative to the product of the row norms, Hadamard's bound).
    #[test]
    fn determinant4_agrees_with_the_lu() {
        let cases = [
            Matrix4::identity(),
            Matrix4::new(2.0, 0.0, 1.0, 3.0, 1.0, -1.0, 4.0, 0.0, 0.0, 5.0, -2.0, 1.0, 3.0, 1.0, 0.0, -4.0),
            Matrix4::new(1.0, 2.0, 3.0, 4.0, 2.0, 4.0, 6.0, 8.0, 0.0, 1.0, 0.0, 1.0, 7.0, 0.0, 2.0, 1.0),
            Matrix4::from_fn(|i, j| if (i + j) % 2 == 0 { 1.0 } else { -2.0 } * (1.0 + i as f64) / (1.0 + j as f64)),
            Matrix4::from_fn(|i, j| ((i * 7 + j * 3) as f64).sin() + if i == j { 3.0 } else { 0.0 }),
        ];
        for m in cases {
            let (ours, lu) = (determinant4(&m), m.determinant());
            let hadamard: f64 = m.row_iter().map(|r| r.norm()).product();
            assert!((ours - lu).abs() <= 1e-13 * hadamard, "{m}: {ours} against {lu}");
        }
        // An exact cofactor expansion in integers, computed apart from this code: 284.
        assert_eq!(determinant4(&cases[1]), 284.0);
        assert_eq!(determinant4(&cases[2]), 0.0);
    }

    fn el() -> Elastic {
        Elastic::new(1.0e4, 0.3).unwrap()
    }

    fn strain_for_stress(s: [f64; 3]) -> Matrix3<f64> {
        let (l, g) = el().lame();
        let tr = s.iter().sum::<f64>();
        let e = Vector3::from(s).map(|x| (x - l / (3.0 * l + 2.0 * g) * tr) / (2.0 * g));
        let q = nalgebra::Rotation3::from_scaled_axis(Vector3::new(0.3, -0.5, 0.7)).into_inner();
        q * Matrix3::from_diagonal(&e) * q.transpose()
    }

    #[test]
    fn validates_parameters_and_names_them() {
        let name_of = |r: Result<MohrCoulomb, ConstitutiveError>| match r {
            Err(ConstitutiveError::InvalidParameter { name, .. }) => name,
            other => panic!("expected InvalidParameter, got {other:?}"),
        };
        assert_eq!(name_of(MohrCoulomb::from_degrees(el(), -1.0, 30.0, 0.0)), "cohesion");
        assert_eq!(name_of(MohrCoulomb::from_degrees(el(), f64::NAN, 30.0, 0.0)), "cohesion");
        assert_eq!(name_of(MohrCoulomb::from_degrees(el(), 1.0, 90.0, 0.0)), "friction");
        assert_eq!(name_of(MohrCoulomb::from_degrees(el(), 1.0, -1.0, 0.0)), "friction");
        assert_eq!(name_of(MohrCoulomb::from_degrees(el(), 1.0, 30.0, 31.0)), "dilation");
        assert_eq!(name_of(MohrCoulomb::from_degrees(el(), 1.0, 30.0, -1.0)), "dilation");
        let law = MohrCoulomb::from_degrees(el(), 10.0, 30.0, 10.0).unwrap();
        // Apex c cot φ = 17.32: a cut-off above it is rejected, at or below it accepted.
        assert_eq!(name_of(law.with_tension_cutoff(17.4)), "tension_cutoff");
        assert_eq!(name_of(law.with_tension_cutoff(f64::INFINITY)), "tension_cutoff");
        assert!(law.with_tension_cutoff(10.0 / 30f64.to_radians().tan()).is_ok());
        assert!(law.with_tension_cutoff(-3.0).is_ok());
        // Tresca has no apex: any finite cut-off.
        assert!(MohrCoulomb::from_degrees(el(), 10.0, 0.0, 0.0).unwrap().with_tension_cutoff(1e6).is_ok());
        assert_eq!(name_of(law.with_softening(11.0, 20.0, 0.0, 0.1)), "residual cohesion");
        assert_eq!(name_of(law.with_softening(1.0, 31.0, 0.0, 0.1)), "residual friction");
        assert_eq!(name_of(law.with_softening(1.0, 20.0, 11.0, 0.1)), "residual dilation");
        assert_eq!(name_of(law.with_softening(1.0, 5.0, 6.0, 0.1)), "residual dilation");
        assert_eq!(name_of(law.with_softening(1.0, 20.0, 0.0, 0.0)), "kappa_res");
        assert!(law.with_softening(1.0, 20.0, 0.0, 0.1).is_ok());
        assert!(MohrCoulomb::from_degrees(Elastic { young: -1.0, poisson: 0.3 }, 1.0, 30.0, 0.0).is_err());
        // Angles are stored in radians.
        assert!((law.friction - 30f64.to_radians()).abs() < 1e-15);
        assert_eq!(law.history_len(), 2);
    }

    #[test]
    fn strength_reduction_divides_c_and_tan_phi() {
        // Plane-strain pure shear past yield with ψ = 0: the mean stress stays 0 and the
        // shear stress sits on the surface at τ = c cos φ (Mohr's circle through the origin
        // touching the envelope), so the reduced law must give (c/F) cos(atan(tan φ/F)).
        let law = MohrCoulomb::from_degrees(el(), 10.0, 30.0, 0.0).unwrap();
        let gamma = 0.05;
        let eps = Matrix3::new(0.0, gamma / 2.0, 0.0, gamma / 2.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for factor in [1.0, 1.4, 2.5] {
            let reduced = law.with_strength_reduced(factor).unwrap();
            let mut h = vec![0.0; reduced.history_len()];
            let h0 = h.clone();
            let tau = reduced.update(&eps, &h0, &mut h).unwrap().stress[(0, 1)];
            let phi_f = (30f64.to_radians().tan() / factor).atan();
            let want = 10.0 / factor * phi_f.cos();
            assert!((tau - want).abs() < 1e-9 * want, "F = {factor}: τ = {tau}, want {want}");
        }
        // Associated flow keeps ψ ≤ φ: ψ_F = φ_F, still associated (symmetric tangent).
        let assoc = MohrCoulomb::from_degrees(el(), 10.0, 30.0, 30.0).unwrap();
        assert!(assoc.with_strength_reduced(1.5).unwrap().symmetric_tangent());
        assert!(assoc.with_strength_reduced(0.0).is_err());
        assert!(el().as_strength_reducible().is_none());
    }

    #[test]
    fn symmetric_tangent_flag() {
        let assoc = MohrCoulomb::from_degrees(el(), 10.0, 30.0, 30.0).unwrap();
        assert!(assoc.symmetric_tangent());
        assert!(assoc.with_tension_cutoff(5.0).unwrap().symmetric_tangent());
        // Softening to the same values changes nothing.
        assert!(assoc.with_softening(10.0, 30.0, 30.0, 0.1).unwrap().symmetric_tangent());
        assert!(!MohrCoulomb::from_degrees(el(), 10.0, 30.0, 20.0).unwrap().symmetric_tangent());
        assert!(!assoc.with_softening(5.0, 30.0, 30.0, 0.1).unwrap().symmetric_tangent());
    }

    /// Why softening reports a non-symmetric tangent even for associated flow: κ is the
    /// norm of the deviatoric plastic strain, so at an edge ∂κ/∂Δγ depends on the mix of
    /// the two multipliers and the tangent loses major symmetry (cohesion softening only).
    #[test]
    fn associated_softening_edge_is_not_symmetric() {
        let law =
            MohrCoulomb::from_degrees(el(), 10.0, 30.0, 30.0).unwrap().with_softening(2.0, 30.0, 30.0, 0.05).unwrap();
        let eps = strain_for_stress([-60.0, -62.0, -250.0]);
        let (up, info) = law.update_with_info(&eps, &[0.0, 0.0], &mut [0.0; 2]).unwrap();
        assert_eq!(info.region, MohrCoulombRegion::Edge12);
        let d = up.tangent;
        assert!((d - d.transpose()).norm() > 1e-6 * d.norm());
    }

    #[test]
    fn tangent_is_minor_symmetric() {
        let law = MohrCoulomb::from_degrees(el(), 10.0, 30.0, 10.0).unwrap();
        for s in [[-50.0, -100.0, -250.0], [-60.0, -62.0, -250.0], [300.0, 200.0, -100.0]] {
            let d = law.update(&strain_for_stress(s), &[0.0, 0.0], &mut [0.0; 2]).unwrap().tangent;
            for i in 0..3 {
                for j in 0..3 {
                    for k in 0..3 {
                        for l in 0..3 {
                            let v = d[(idx(i, j), idx(k, l))];
                            // Built from symmetric dyads: equal up to round-off (1e-12 ‖D‖).
                            assert!((v - d[(idx(j, i), idx(k, l))]).abs() <= 1e-12 * d.norm());
                            assert!((v - d[(idx(i, j), idx(l, k))]).abs() <= 1e-12 * d.norm());
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn cone_membership() {
        let g = [Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 1.0, 0.0), Vector3::new(0.0, 0.0, 1.0)];
        assert!(in_cone(&Vector3::new(1.0, 2.0, 3.0), &g));
        assert!(!in_cone(&Vector3::new(1.0, -2.0, 3.0), &g));
        assert!(in_cone(&Vector3::zeros(), &g));
        // Rank-deficient generators (ψ = 0: deviatoric flow only).
        let d = [Vector3::new(1.0, 0.0, -1.0), Vector3::new(0.0, 1.0, -1.0), Vector3::new(1.0, -1.0, 0.0)];
        assert!(in_cone(&Vector3::new(2.0, 1.0, -3.0), &d));
        assert!(!in_cone(&Vector3::new(1.0, 1.0, 1.0), &d));
    }

    /// The spin coefficient for repeated principal strains uses the limit, not 0/0.
    #[test]
    fn assemble_elastic_limit_for_repeated_values() {
        let (l, g) = el().lame();
        let de = Matrix3::repeat(l) + Matrix3::identity() * (2.0 * g);
        let e = Vector3::new(1e-3, 1e-3, -2e-3);
        let sig = de * e;
        let d = assemble(&Matrix3::identity(), &e, &sig, &de, [false; 3]);
        // Exactly the isotropic tensor (round-off).
        assert!((d - el().stiffness()).norm() < 1e-12 * d.norm());
    }
}
