//! The kernels every analysis shares, implicit quasi-static, implicit dynamic and explicit
//! alike: the stages of a step that do not depend on the integrator (docs/theory.md §1).
//!
//! - [`connect`]: locate the points on the background, evaluate their basis, number the
//!   active nodes, mark the constrained dofs; [`check_constraints`] (on grid planes and
//!   inclined planes) and [`check_constraints_connected`] (bodies' too) before a first step.
//! - [`scatter_nodal`]: point → node transfer over a step's connectivity, through the
//!   points' bands (`loam_grid::BandScatter`, two colours of bands of nodes), so that the
//!   sums are bitwise the same on any number of threads. The explicit step scatters through
//!   the same bands, grouped on its tensor-product basis.
//! - [`interpolate`], [`interpolate_add`], [`interpolate_pair`]: node → point transfer,
//!   Σ_I N_I(x_p) u_I.
//! - [`internal_force`] and [`scatter_internal_force`]: f_int,I = Σ_p v_p σ_p ∂N_I/∂x.
//! - [`embed`], [`update_point`], [`advance_deformation`]: point kinematics — the
//!   increment ΔF = I + ∇Δu, the law driven in small or finite strain, and the committed
//!   F and GIMP domain.
//! - [`LoadSupports`]: the load vertices on the active nodes, their forces spread to the
//!   nodes, and the displacement that moves them.
//! - [`ConnectError`], [`InvalidSetting`] and [`RunError`]: what the analyses' errors share.
//! - [`on_pool`]: a step handed to rayon's pool once, not each of its parallel passes.

mod connect;
mod error;
mod force;
mod load;
mod point;
mod pool;
mod transfer;

pub use connect::{check_constraints, check_constraints_connected, connect};
pub use error::{ConnectError, InvalidSetting, RunError};
pub use force::{internal_force, scatter_internal_force};
pub use load::{trial_vertices, LoadSupports};
pub use point::{advance_deformation, embed, update_point, update_point_stress, Committed, PointStress, PointUpdate};
pub use pool::on_pool;
pub use transfer::{interpolate, interpolate_add, interpolate_pair, scatter_nodal};
