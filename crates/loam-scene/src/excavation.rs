//! The excavation part of a scene: stages that remove the points of a region after a given
//! step (`loam_model::Model::remove_points_in`).

use super::locate::Seg;
use super::{AnalysisSpec, ControlSpec, LoadedScene, MethodSpec, SceneError};
use loam_points::Shape;

/// One excavation stage, checked: after step `after_step`, remove the points in `region`.
#[derive(Debug, Clone)]
pub struct Excavation<const D: usize> {
    pub after_step: usize,
    pub region: Shape<D>,
}

impl LoadedScene {
    /// The scene's excavation stages, each checked at its place in the file: a step of the
    /// run (a quasi-static run has `load_steps`), a valid region, on material points (the
    /// FEM reference's points are its Gauss points) and without strength reduction (whose
    /// trials would each need the stages).
    pub fn excavations<const D: usize>(&self) -> Result<Vec<Excavation<D>>, SceneError> {
        let s = &self.scene;
        let mut stages = Vec::with_capacity(s.excavation.len());
        for (k, stage) in s.excavation.iter().enumerate() {
            let at = |key| [Seg::Key("excavation"), Seg::Index(k), Seg::Key(key)];
            if s.method == MethodSpec::UpdatedLagrangianFem {
                return Err(self.error(&at("region"), "excavation removes material points; the updated Lagrangian FEM reference has Gauss points in a mesh instead"));
            }
            if stage.after_step == 0 {
                return Err(self.error(&at("after_step"), "after_step is 0; a stage comes after step 1 or later"));
            }
            if let AnalysisSpec::QuasiStatic { load_steps, strength_reduction, control, .. } = &s.analysis {
                if strength_reduction.is_some() {
                    return Err(self.error(&at("region"), "excavation stages and strength reduction cannot be combined yet: run the excavation, then a strength-reduction scene of the excavated ground"));
                }
                if matches!(control, ControlSpec::ArcLength { .. }) {
                    return Err(self.error(&at("region"), "excavation stages and arc-length control cannot be combined: an excavation at a fixed load leaves an out-of-balance force that the arc would answer by changing the load; excavate under control: LoadFactor"));
                }
                if stage.after_step > *load_steps {
                    let message = format!(
                        "after_step is {}, but the run has {load_steps} load steps: the stage would never happen",
                        stage.after_step
                    );
                    return Err(self.error(&at("after_step"), message));
                }
            }
            let region: Shape<D> = self.shape_at(&stage.region, &at("region"))?;
            region.bounds().map_err(|e| self.error(&at("region"), format!("excavation {k}: {e}")))?;
            stages.push(Excavation { after_step: stage.after_step, region });
        }
        Ok(stages)
    }
}
