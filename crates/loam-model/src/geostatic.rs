//! The geostatic (K0) initial stress of level or layered ground.

use crate::{Kinematics, Model, ModelError};
use nalgebra::Matrix3;

impl<const D: usize> Model<D> {
    /// Put the points in a geostatic initial stress: the vertical effective stress is the
    /// weight of the material above each point in its grid column, σ′_v = −Σ (|g| m − γ_w V)
    /// / A (A the column's horizontal area, a ring's in axisymmetry; points at the same height count half; the
    /// buoyancy γ_w V only below the water table), the horizontal ones K0 σ′_v,
    /// with the elastic strain that carries it (small strain ε^e = C⁻¹σ, finite strain
    /// b^e = exp(2 C⁻¹σ)). Gravity then acts in full from the start
    /// (`gravity_preloaded`). K0 applies to level or layered ground; a slope is brought to
    /// equilibrium by gravity loading instead. The points of rigid bodies are left out: they
    /// carry no stress and weigh on no column (their motion is prescribed). Fails if gravity
    /// is not along one axis, a law has no elasticity that carries it, or the state lies
    /// outside a yield surface.
    pub fn geostatic_stress(&mut self, k0: f64) -> Result<(), ModelError> {
        if !(k0.is_finite() && k0 > 0.0) {
            return Err(ModelError::Geostatic(format!("K0 is {k0}; it must be a positive number")));
        }
        let vertical = (0..D).max_by(|&a, &b| self.gravity[a].abs().total_cmp(&self.gravity[b].abs())).unwrap_or(0);
        let g = self.gravity[vertical];
        if g == 0.0 || (0..D).any(|a| a != vertical && self.gravity[a] != 0.0) {
            return Err(ModelError::Geostatic("a geostatic stress needs gravity along one axis".into()));
        }
        let sigma_v = self.overburden(vertical, g);
        let stresses: Vec<Matrix3<f64>> = (sigma_v.iter())
            .map(|&sv| {
                let mut sigma = Matrix3::identity() * (k0 * sv);
                sigma[(vertical, vertical)] = sv;
                sigma
            })
            .collect();
        // Every law's history from the point's initial stress (at F = I the Kirchhoff stress
        // is the Cauchy stress), kept aside until every point's state is admissible.
        let hs = self.points.history_stride();
        let mut history = self.points.history_values().to_vec();
        if hs > 0 {
            for (p, h) in history.chunks_mut(hs).enumerate().filter(|&(p, _)| !self.is_rigid_point(p)) {
                h.iter_mut().for_each(|v| *v = 0.0);
                self.law(p).init_history(h, &stresses[p]);
            }
        }
        let mut h_out = vec![0.0; hs];
        let mut strains = self.points.elastic_strain().to_vec();
        for (p, (sigma, &sv)) in stresses.iter().zip(&sigma_v).enumerate().filter(|&(p, _)| !self.is_rigid_point(p)) {
            let h = self.law(p).own_history(&history[p * hs..][..hs]);
            strains[p] = self.carrying_strain(p, sigma, h, (k0, sv), &mut h_out[..h.len()])?;
        }
        let view = self.points.view_mut();
        view.elastic_strain.copy_from_slice(&strains);
        view.stress.copy_from_slice(&stresses);
        view.history.copy_from_slice(&history);
        self.gravity_preloaded = true;
        Ok(())
    }

    /// σ_v of every point: the (effective) weight of the material above it in its grid
    /// column over the column's area (its ring's in axisymmetry), points at the same height (within 1e-9 of a cell)
    /// counting half. Gravity `g` acts along axis `vertical`; "above" is against it.
    fn overburden(&self, vertical: usize, g: f64) -> Vec<f64> {
        let up = -g.signum();
        let h = self.grid().cell_size();
        let area: f64 = (0..D).filter(|&a| a != vertical).map(|a| h[a]).product();
        let pts = &self.points;
        // The column of a point: its cell's coordinates across gravity (the vertical one
        // zeroed), so points sort by column, then from the top down.
        let column = |p: usize| {
            let mut ijk = self.grid().cell_coords(&pts.position()[p]);
            ijk[vertical] = 0;
            ijk
        };
        let mut order: Vec<([usize; D], usize)> =
            (0..pts.len()).filter(|&p| !self.is_rigid_point(p)).map(|p| (column(p), p)).collect();
        order.sort_by(|(ca, a), (cb, b)| {
            ca.cmp(cb).then((up * pts.position()[*b][vertical]).total_cmp(&(up * pts.position()[*a][vertical])))
        });
        let tol = 1e-9 * h[vertical];
        let mut sigma_v = vec![0.0; pts.len()];
        for col in order.chunk_by(|a, b| a.0 == b.0) {
            // In axisymmetry the column is a ring of radius r_c (its cells' centre), whose
            // points' weights are those of their rings (docs/theory.md §20).
            let area = if self.axisymmetric() {
                let origin = self.grid().origin()[0];
                std::f64::consts::TAU * (origin + (col[0].0[0] as f64 + 0.5) * h[0]) * area
            } else {
                area
            };
            let mut above = 0.0;
            // The rows of the column: points at the same height, top down.
            for row in col
                .chunk_by(|&(_, a), &(_, b)| (pts.position()[a][vertical] - pts.position()[b][vertical]).abs() <= tol)
            {
                let row_weight: f64 = row.iter().map(|&(_, q)| self.effective_weight(q, g)).sum();
                for &(_, q) in row {
                    sigma_v[q] = -(above + 0.5 * row_weight) / area;
                }
                above += row_weight;
            }
        }
        sigma_v
    }

    /// The weight of point `q` that its column's effective stress carries: m |g|, less the
    /// buoyancy on the submerged part of its domain (the water's force of the balance,
    /// [`Model::water_force`] in full, so the state starts in equilibrium).
    fn effective_weight(&self, q: usize, g: f64) -> f64 {
        let pts = &self.points;
        let buoyancy = self.water.as_ref().map_or(0.0, |w| {
            let half = pts.half_length()[q][w.vertical()];
            w.force_density(&pts.position()[q], half)[w.vertical()].abs()
        });
        g.abs() * pts.mass()[q] - buoyancy * pts.volume()[q]
    }

    /// The elastic strain state that carries `sigma` (K0 and σ_v given for the message) at
    /// point `p` with history `history` (the law's inverse of its elasticity, ε^e = C⁻¹σ for
    /// linear elasticity; b^e = exp(2 ε^e) in finite strain), checked admissible: the law's own update from it returns the stress.
    fn carrying_strain(
        &self,
        p: usize,
        sigma: &Matrix3<f64>,
        history: &[f64],
        (k0, sv): (f64, f64),
        h_out: &mut [f64],
    ) -> Result<Matrix3<f64>, ModelError> {
        let pts = &self.points;
        let law = self.law(p);
        let Some(eps) = law.elastic_strain_of(sigma, history) else {
            return Err(ModelError::Geostatic(format!(
                "material {} ({}) has no elasticity that carries the initial stress at point {p} (σ_v = {sv:.4e})",
                pts.material()[p],
                law.name()
            )));
        };
        let upd = law.update(&eps, history, h_out).map_err(|e| ModelError::Geostatic(format!("point {p}: {e}")))?;
        if (upd.stress - sigma).norm() > 1e-8 * sigma.norm().max(f64::MIN_POSITIVE) {
            return Err(ModelError::Geostatic(format!(
                "point {p} at {:?}: the K0 = {k0} stress (σ_v = {:.4e}) lies outside the yield surface of material {} ({}); use a K0 inside it or gravity loading",
                pts.position()[p].as_slice(), sv, pts.material()[p], law.name()
            )));
        }
        match self.kinematics {
            Kinematics::SmallStrain => Ok(eps),
            Kinematics::FiniteStrain => loam_constitutive::tensor::sym_exp(&(eps * 2.0))
                .map_err(|e| ModelError::Geostatic(format!("point {p}: {e}"))),
        }
    }
}
