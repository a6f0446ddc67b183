//! Axisymmetric models (docs/theory.md §20): a 2D model read as the meridian plane of a
//! body of revolution about the y axis — x is the radius r, y the axial coordinate z, and
//! the out-of-plane direction the hoop direction θ. A point is the ring it sweeps (mass
//! and volume 2π r times its area), a load's facet a ring (`Load::revolve`), a force the
//! total of its ring; the analyses add the hoop strain u_r / r to the point's strain as
//! its out-of-plane (zz) component and the hoop stress's force σ_θθ N_I / r to the
//! radial internal force. The axis is the grid's x = 0 plane, held radially.

use crate::{AntiLocking, Model, ModelError, PlaneConstraint};

impl<const D: usize> Model<D> {
    /// Read the model as axisymmetric (module docs): 2D, on a grid whose origin lies on the
    /// axis (x = 0), with gravity along the axis (y), before any point has moved; the
    /// points become rings and the nodes on the axis are held radially
    /// (`Model::constrained_dofs`). Not with a body-fitted FEM mesh or assumed strain (not
    /// implemented in axisymmetry); B-bar averages the dilatation with its hoop part, the
    /// ghost penalty acts on rings, a follower pressure acts on the current rings.
    pub fn with_axisymmetry(mut self) -> Result<Self, ModelError> {
        let fail = |what: String| Err(ModelError::Axisymmetry(what));
        if D != 2 {
            return fail(format!("a {D}D model cannot be axisymmetric; give a 2D model (x the radius, y the axis)"));
        }
        if self.axisymmetric {
            return Ok(self);
        }
        if self.background.moves_with_body() {
            return fail("the updated Lagrangian FEM reference is plane strain only; use the MPM".into());
        }
        let x0 = self.grid().origin()[0];
        if x0 != 0.0 {
            return fail(format!("the grid starts at x = {x0}; an axisymmetric grid starts on the axis, x = 0"));
        }
        if let Some(unsupported) = self.unsupported_in_axisymmetry() {
            return fail(unsupported);
        }
        if self.gravity[0] != 0.0 {
            return fail(format!(
                "gravity has a radial (x) component {}; a body of revolution's gravity acts along its axis, y",
                self.gravity[0]
            ));
        }
        let pts = &self.points;
        if let Some(p) = (0..pts.len()).find(|&p| pts.position()[p] != pts.position0()[p]) {
            return fail(format!("point {p} has moved; a model is made axisymmetric before it is analysed"));
        }
        if let Some(p) = (0..pts.len()).find(|&p| pts.position()[p][0] <= 0.0) {
            return fail(format!("point {p} lies at radius {} ≤ 0; the points lie at x > 0", pts.position()[p][0]));
        }
        self.points.revolve();
        self.loads.iter_mut().for_each(|l| l.revolve(true));
        self.update_load_vertices();
        self.axisymmetric = true;
        Ok(self)
    }

    /// Whether the model is axisymmetric (x the radius, y the axis).
    pub fn axisymmetric(&self) -> bool {
        self.axisymmetric
    }

    /// `self`, or the refusal of an option just set that axisymmetry does not take.
    pub(crate) fn still_axisymmetric(self, error: impl Fn(String) -> ModelError) -> Result<Self, ModelError> {
        match self.axisymmetric.then(|| self.unsupported_in_axisymmetry()).flatten() {
            Some(why) => Err(error(why)),
            None => Ok(self),
        }
    }

    /// Why the model's options do not go with axisymmetry, if they do not.
    pub(crate) fn unsupported_in_axisymmetry(&self) -> Option<String> {
        if let AntiLocking::AssumedStrain { .. } = self.anti_locking {
            return Some(
                "assumed strain is not implemented in axisymmetry (its averaged strain has no hoop part); use BBar"
                    .into(),
            );
        }
        None
    }
}

/// The roller that holds the nodes on the axis radially: not one of the model's
/// constraints (a ring around a bore reaches no node on the axis, and none is missing).
pub(crate) fn axis_roller() -> PlaneConstraint {
    PlaneConstraint::new(0, 0, [true, false, false])
}
