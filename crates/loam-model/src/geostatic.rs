//! The geostatic (K0) initial stress of level or layered ground (docs/theory.md §5).

use crate::{Kinematics, Model, ModelError};
use nalgebra::Matrix3;

impl<const D: usize> Model<D> {
    /// Put the points in a geostatic initial stress: the vertical stress is the weight of
    /// the material above each point in its grid column, σ_v = −|g| Σ m / A (A the column's
    /// horizontal area; points at the same height count half), the horizontal ones K0 σ_v,
    /// with the elastic strain that carries it (small strain ε^e = C⁻¹σ, finite strain
    /// b^e = exp(2 C⁻¹σ)). Gravity then acts in full from the start
    /// (`gravity_preloaded`). K0 applies to level or layered ground; a slope is brought to
    /// equilibrium by gravity loading instead. Fails if gravity is not along one axis, a
    /// law has no isotropic elasticity, or the state lies outside a yield surface.
    pub fn geostatic_stress(&mut self, k0: f64) -> Result<(), ModelError> {
        if !(k0.is_finite() && k0 > 0.0) {
            return Err(ModelError::Geostatic(format!("K0 is {k0}; it must be a positive number")));
        }
        let vertical = (0..D).max_by(|&a, &b| self.gravity[a].abs().total_cmp(&self.gravity[b].abs())).unwrap_or(0);
        let g = self.gravity[vertical];
        if g == 0.0 || (0..D).any(|a| a != vertical && self.gravity[a] != 0.0) {
            return Err(ModelError::Geostatic("a geostatic stress needs gravity along one axis".into()));
        }
        // Down is the direction of gravity; "above" is against it.
        let up = -g.signum();
        let h = self.grid().cell_size();
        let area: f64 = (0..D).filter(|&a| a != vertical).map(|a| h[a]).product();
        let pts = &self.points;
        let n = pts.len();
        // The column of a point: its cell's coordinates across gravity (the vertical one
        // zeroed), so points sort by column, then from the top down.
        let column = |p: usize| {
            let mut ijk = self.grid().cell_coords(&pts.position[p]);
            ijk[vertical] = 0;
            ijk
        };
        let mut order: Vec<([usize; D], usize)> = (0..n).map(|p| (column(p), p)).collect();
        order.sort_by(|(ca, a), (cb, b)| {
            ca.cmp(cb).then((up * pts.position[*b][vertical]).total_cmp(&(up * pts.position[*a][vertical])))
        });
        let tol = 1e-9 * h[vertical];
        let mut sigma_v = vec![0.0; n];
        for col in order.chunk_by(|a, b| a.0 == b.0) {
            let mut above = 0.0;
            // The rows of the column: points at the same height, top down.
            for row in
                col.chunk_by(|&(_, a), &(_, b)| (pts.position[a][vertical] - pts.position[b][vertical]).abs() <= tol)
            {
                let row_mass: f64 = row.iter().map(|&(_, q)| pts.mass[q]).sum();
                for &(_, q) in row {
                    sigma_v[q] = -g.abs() * (above + 0.5 * row_mass) / area;
                }
                above += row_mass;
            }
        }
        let hs = pts.history_stride();
        let mut h_out = vec![0.0; hs];
        let mut strains = Vec::with_capacity(n);
        let mut stresses = Vec::with_capacity(n);
        for (p, &sv) in sigma_v.iter().enumerate() {
            let law = &self.materials[pts.material[p] as usize];
            let Some(elastic) = law.elasticity() else {
                return Err(ModelError::Geostatic(format!(
                    "material {} ({}) has no isotropic elasticity to carry an initial stress",
                    pts.material[p],
                    law.name()
                )));
            };
            let mut sigma = Matrix3::identity() * (k0 * sv);
            sigma[(vertical, vertical)] = sv;
            let eps = elastic.strain(&sigma);
            // Admissible: the law's own update from that elastic strain returns the stress.
            let upd = law
                .update(&eps, pts.history(p), &mut h_out)
                .map_err(|e| ModelError::Geostatic(format!("point {p}: {e}")))?;
            if (upd.stress - sigma).norm() > 1e-8 * sigma.norm().max(f64::MIN_POSITIVE) {
                return Err(ModelError::Geostatic(format!(
                    "point {p} at {:?}: the K0 = {k0} stress (σ_v = {:.4e}) lies outside the yield surface of material {} ({}); use a K0 inside it or gravity loading",
                    pts.position[p].as_slice(), sv, pts.material[p], law.name()
                )));
            }
            let be = match self.kinematics {
                Kinematics::SmallStrain => eps,
                Kinematics::FiniteStrain => loam_constitutive::tensor::sym_exp(&(eps * 2.0))
                    .map_err(|e| ModelError::Geostatic(format!("point {p}: {e}")))?,
            };
            strains.push(be);
            stresses.push(sigma);
        }
        self.points.elastic_strain = strains;
        self.points.stress = stresses;
        self.gravity_preloaded = true;
        Ok(())
    }
}
