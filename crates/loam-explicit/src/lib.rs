//! Explicit material point method over the same grid, points, constitutive laws and model
//! as the implicit solver, for comparison with it (docs/theory.md §10) and for fast dynamics.
//!
//! One step, updated Lagrangian with the grid reset every step:
//!
//! 1. Connect: every point's basis at its committed position, as the 1D factors of the
//!    tensor product (`loam_grid::AxisBasis`, evaluated once and read by stages 2, 5 and
//!    6), and the points grouped into bands of grid rows for the scatter.
//! 2. Point → grid by a deterministic parallel scatter into dense nodal fields
//!    (`loam_grid::BandScatter`), one record per node, or one per body and node when the
//!    bodies are in contact (`fields`; each point to its own body's):
//!    m_I = Σ_p N_I m_p, p_I = Σ_p N_I m_p v_p, f_I = Σ_p N_I f_ext,p − Σ_p v_p σ_p ∇N_I.
//!    Nodes with m_I ≤ 1e-12 · max m_I are empty (zero velocity and acceleration);
//!    constrained dofs get zero velocity, their momentum kept for the FLIP update (5).
//! 3. Local non-viscous damping (Cundall 1987; Itasca FLAC/PFC "local damping"):
//!    f_I ← f_I − α |f_I| sign(v_I), per component.
//! 4. Grid momentum update v_I^{n+1} = (p_I + Δt f_I) / m_I, a_I = f_I / m_I at a free
//!    dof; at a held one v_I^{n+1} = 0 and a_I = −p_I / (m_I Δt). At the nodes of an
//!    inclined roller or a frictional plane the velocity is then made admissible (no
//!    approach, Coulomb slip; `contact`) and a_I = (v_I^{n+1} − p_I / m_I) / Δt; so are
//!    the velocities of bodies in contact where they meet (`body_contact`).
//! 5. Grid → point: v_p ← flip (v_p + Δt Σ N_I a_I) + (1 − flip) Σ N_I v_I^{n+1}
//!    (FLIP of Brackbill & Ruppel 1986 blended with PIC), x_p ← x_p + Δt Σ N_I v_I^{n+1},
//!    with Δt a_I = v_I^{n+1} − p_I / m_I the node's change of velocity: at a held dof
//!    −p_I / m_I, the velocity the support stopped.
//! 6. Stress update from ∇v_p = Σ_I v_I ⊗ ∇N_I: ΔF = I + Δt ∇v_p, then the finite-strain
//!    (Hencky, b^e) or small-strain driver of `loam-constitutive`. Which nodal velocity
//!    v_I, and when, is the update scheme (Bardenhagen 2002, "Energy conservation error in
//!    the material point method for solid mechanics", J. Comput. Phys. 180; Nairn 2003,
//!    "Material point method calculations with explicit cracks", CMES 4; Buzzi, Pedroso &
//!    Giacomini 2008 compare them):
//!    - USF: v_I = p_I / m_I of the start of the step, stress updated *before* the
//!      internal force is computed (with the updated stress and volume);
//!    - USL: v_I = v_I^{n+1};
//!    - MUSL (Sulsky, Zhou & Schreyer 1995): v_I re-mapped from the updated point
//!      velocities, p_I = Σ N_I m_p v_p^{n+1} (constrained dofs zeroed), v_I = p_I / m_I.
//! 7. Commit: F ← ΔF F, v_p ← det ΔF v_p, iGIMP half-lengths stretched with F, stress,
//!    elastic strain, history, velocity, position — each computed into scratch by the
//!    stage that has the point in hand (F, volume and half-lengths by the stress update of
//!    6), and exchanged with the model's at once.
//!
//! The algorithm is that of Sulsky, Chen & Schreyer (1994), "A particle method for
//! history-dependent materials", Comput. Methods Appl. Mech. Engrg. 118. The time step is
//! the CFL limit Δt_c = h_min / (max_p c_p + max_I |v_I|), c_p = √(M / ρ_p) with M the
//! P-wave modulus of the point's law and ρ_p = m_p / v_p its current density, and
//! v_I = p_I / m_I the velocity the grid carries the material at (docs/theory.md §10): a
//! lower bound of min_p h_min / (c_p + |v̄_p|) for the points' carried velocities v̄_p.
//! The step is therefore taken after stage 2.
//!
//! Everything a step computes goes into scratch buffers reused from step to step; the
//! model is changed only when the whole step has succeeded, so a failed step (a point
//! leaving the grid, a blow-up) leaves the last committed state intact. Every point → node
//! transfer sums each node's contributions in a fixed order (the bands of the scatter) and
//! every point loop is independent, so results are bitwise identical for any number of
//! threads (docs/theory.md §7).

mod body_contact;
mod contact;
mod energy;
mod error;
mod explicit;
mod fields;
mod settings;

pub use energy::LeapfrogEnergy;
pub use error::ExplicitError;
pub use explicit::{Explicit, ExplicitState, ExplicitStepReport, StepPhases};
pub use loam_kernels::{ConnectError, InvalidSetting, RunError};
pub use loam_model::{Kinematics, Model, ModelError, PlaneConstraint};
pub use settings::{ExplicitSettings, TimeStep, UpdateScheme};
