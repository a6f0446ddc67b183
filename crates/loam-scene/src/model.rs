//! The model part of a scene: the grid, bodies, laws, constraints and gravity assembled
//! into one model, then its options — anti-locking, geometric linearity, the ghost penalty
//! and the initial stress — each refused at its key when it does not apply.

use super::bodies::Bodies;
use super::locate::Seg;
use super::{AnalysisSpec, InitialStressSpec, LawSpec, LoadedScene, SceneError};
use loam_constitutive::{ConstitutiveLaw, MaterialState};
use loam_grid::Grid;
use loam_model::{Load, Model, ModelError, PlaneConstraint};
use nalgebra::SVector;
use std::sync::Arc;

/// The largest stiffness or force scale a scene may have: residual norms are sums of
/// squares of nodal forces, which overflow double precision (1.8e308) beyond 1e154.
const LARGEST_SCALE: f64 = 1e150;

impl LoadedScene {
    /// Refuse a material whose stiffness per cell (P-wave modulus × cell volume / smallest
    /// cell size², the size of a tangent entry) or whose weight over the grid's height (ρ |g|
    /// × cell volume × the grid's most cells along an axis, a bound on the column of cells
    /// along gravity: the size of a nodal force) would overflow the
    /// arithmetic of the tangent and the residual norms: `young: 1e308` used to pass the
    /// check and fail in Cholesky with a pivot index.
    pub(super) fn check_scales<const D: usize>(
        &self,
        grid: &Grid<D>,
        laws: &[Arc<dyn ConstitutiveLaw>],
        gravity: &SVector<f64, D>,
    ) -> Result<(), SceneError> {
        let h = grid.cell_size();
        let volume = grid.cell_volume();
        // The most cells along any axis bounds the number along gravity, whichever it is.
        let height = (0..D).map(|a| grid.cells()[a] as f64).fold(0.0, f64::max);
        for (i, (m, law)) in self.scene.materials.iter().zip(laws).enumerate() {
            let at = |key| [Seg::Key("materials"), Seg::Index(i), Seg::Key(key)];
            let mut history = vec![0.0; law.history_len()];
            law.init_history(&mut history, &nalgebra::Matrix3::zeros());
            let at_rest = law.p_wave_modulus(&MaterialState::at_rest(&history));
            let stiffness = at_rest * volume / (h.min() * h.min());
            let weight = m.density * gravity.norm() * volume * height;
            let (scale, what, key) = if stiffness > LARGEST_SCALE {
                (stiffness, "stiffness per cell (P-wave modulus × cell volume / cell size²)", "law")
            } else if weight > LARGEST_SCALE {
                (weight, "weight over the grid's height (density × gravity × cell volume × cells)", "density")
            } else {
                continue;
            };
            return Err(self.error(
                &at(key),
                format!(
                    "material \"{}\": its {what} is {scale:.1e}, beyond {LARGEST_SCALE:.0e}, where the tangent and \
                     the residual norms overflow double precision; check the units (docs/scene-format.md, Units)",
                    m.name
                ),
            ));
        }
        Ok(())
    }

    /// The model of material points, or of the FEM reference's mesh with its initial
    /// velocities, with the scene's options.
    pub(super) fn model<const D: usize>(
        &self,
        grid: Grid<D>,
        bodies: Bodies<D>,
        laws: Vec<Arc<dyn ConstitutiveLaw>>,
        constraints: Vec<PlaneConstraint>,
        gravity: SVector<f64, D>,
    ) -> Result<Model<D>, SceneError> {
        let s = &self.scene;
        let at_bodies = |e: ModelError| self.error(&[Seg::Key("bodies")], e.to_string());
        let model = match bodies {
            Bodies::Points(points) => {
                Model::new(grid, s.basis.into(), s.kinematics.into(), *points, laws, constraints, gravity)
                    .map_err(at_bodies)?
            }
            Bodies::Mesh { mesh, density, material } => {
                let mut model = Model::updated_lagrangian_fem(
                    grid,
                    s.kinematics.into(),
                    mesh,
                    &density,
                    &material,
                    laws,
                    constraints,
                    gravity,
                )
                .map_err(at_bodies)?;
                self.fem_velocities(&mut model)?;
                model
            }
        };
        self.model_options(model)
    }

    /// The model with the scene's loads, each refused at its place in `loads`.
    pub(super) fn with_loads<const D: usize>(
        &self,
        model: Model<D>,
        loads: Vec<Load<D>>,
    ) -> Result<Model<D>, SceneError> {
        model.with_loads(loads).map_err(|e| match e {
            ModelError::Load { index, .. } => self.error(&[Seg::Key("loads"), Seg::Index(index)], e.to_string()),
            e => self.error(&[Seg::Key("loads")], e.to_string()),
        })
    }

    /// Axisymmetry, anti-locking, geometric linearity (implicit only), the ghost penalty
    /// (implicit only) and the groundwater (implicit only), in that order.
    fn model_options<const D: usize>(&self, mut model: Model<D>) -> Result<Model<D>, SceneError> {
        let s = &self.scene;
        let explicit = matches!(s.analysis, AnalysisSpec::Explicit { .. });
        let refused = |key: &'static str| move |e: ModelError| self.error(&[Seg::Key(key)], e.to_string());
        if s.axisymmetric {
            model = model.with_axisymmetry().map_err(refused("axisymmetric"))?;
        }
        let mut model = model.with_anti_locking(s.anti_locking.into()).map_err(refused("anti_locking"))?;
        if s.geometrically_linear {
            if explicit {
                return Err(self.error(&[Seg::Key("geometrically_linear")], "explicit analysis moves its points by their velocities; set geometrically_linear: false or use an implicit analysis"));
            }
            model = model.with_geometrically_linear().map_err(refused("geometrically_linear"))?;
        }
        if let Some(gamma) = s.ghost_penalty {
            if explicit {
                return Err(self.error(
                    &[Seg::Key("ghost_penalty")],
                    "the ghost penalty stabilises the implicit tangent; an Explicit analysis has none (remove the key)",
                ));
            }
            model = model.with_ghost_penalty(gamma).map_err(refused("ghost_penalty"))?;
        }
        if let Some(water) = self.water(&model.gravity().clone())? {
            if explicit {
                return Err(self.error(
                    &[Seg::Key("water")],
                    "pore pressures are implemented in the implicit analyses; use QuasiStatic or ImplicitDynamic",
                ));
            }
            model = model.with_water(water).map_err(refused("water"))?;
        }
        self.check_cam_clay_starts_stressed()?;
        Ok(model)
    }

    /// The model in its initial stress: the geostatic one where the scene asks for it, set
    /// once the rigid bodies are known (their points carry none).
    pub(super) fn with_initial_stress<const D: usize>(&self, mut model: Model<D>) -> Result<Model<D>, SceneError> {
        if let InitialStressSpec::Geostatic { k0 } = self.scene.initial_stress {
            model.geostatic_stress(k0).map_err(|e| self.error(&[Seg::Key("initial_stress")], e.to_string()))?;
        }
        Ok(model)
    }

    /// Modified Cam clay has no stiffness and no yield surface without a mean pressure:
    /// a scene that uses it must start from a geostatic stress.
    fn check_cam_clay_starts_stressed(&self) -> Result<(), SceneError> {
        if matches!(self.scene.initial_stress, InitialStressSpec::Geostatic { .. }) {
            return Ok(());
        }
        let materials = &self.scene.materials;
        let Some(i) = materials.iter().position(|m| matches!(m.law, LawSpec::ModifiedCamClay { .. })) else {
            return Ok(());
        };
        Err(self.error(
            &[Seg::Key("materials"), Seg::Index(i), Seg::Key("law")],
            format!(
                "material \"{}\": ModifiedCamClay has no stiffness and no yield surface at zero pressure; start \
                 the scene from a stress with `initial_stress: Geostatic(k0: ...)`",
                materials[i].name
            ),
        ))
    }
}
