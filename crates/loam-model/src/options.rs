//! Which analyses accept which options of a model, in one table: each analysis checks a
//! model against it when it is made, and the scene reports a refusal at its key.

use crate::Model;

/// The analyses a model can be given to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AnalysisKind {
    QuasiStatic,
    Dynamic,
    Explicit,
}

impl AnalysisKind {
    fn column(self) -> usize {
        match self {
            AnalysisKind::QuasiStatic => 0,
            AnalysisKind::Dynamic => 1,
            AnalysisKind::Explicit => 2,
        }
    }
}

/// An option of a model that not every analysis accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ModelOption {
    /// The updated Lagrangian FEM reference's body-fitted mesh.
    BodyFittedMesh,
    /// A ghost penalty on cut cells.
    GhostPenalty,
    /// Equilibrium on the initial configuration.
    GeometricallyLinear,
    /// Static groundwater.
    Water,
    /// An anti-locking treatment (B-bar, assumed strain, F-bar).
    AntiLocking,
    /// A plane constraint that prescribes a non-zero displacement.
    DisplacedConstraint { index: usize },
    /// A roller on an inclined plane.
    InclinedRoller { index: usize },
    /// A rigid plane with Coulomb friction.
    FrictionalPlane { index: usize },
    /// Bodies in contact, a velocity field each.
    BodyContact,
    /// A body moved as a rigid whole at a prescribed velocity.
    RigidBody { index: usize },
    /// A constraint on a body that holds its nodes.
    BodyConstraint { index: usize },
    /// A constraint on a body that prescribes a non-zero displacement.
    DisplacedBodyConstraint { index: usize },
}

/// One row of the table: the options it is about, whether the quasi-static, dynamic and
/// explicit analyses accept them, and why an analysis that does not refuses them.
struct Acceptance {
    is: fn(&ModelOption) -> bool,
    by: [bool; 3],
    why: &'static str,
}

/// Which analyses accept each option (the module docs).
const ACCEPTED: [Acceptance; 12] = [
    Acceptance {
        is: |o| matches!(o, ModelOption::BodyFittedMesh),
        by: [true, true, false],
        why: "the model is an updated Lagrangian FEM mesh; explicit analysis runs MPM models only (use the implicit quasi-static or dynamic analysis for the FEM reference)",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::GhostPenalty),
        by: [true, true, false],
        why: "the model asks for a ghost penalty, which stabilises the implicit tangent; explicit analysis has none (remove it)",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::GeometricallyLinear),
        by: [true, true, false],
        why: "the model is geometrically linear (points held at their places); explicit analysis moves its points by their velocities",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::Water),
        by: [true, true, false],
        why: "the model has groundwater; pore pressures are implemented in the implicit analyses only (QuasiStatic, ImplicitDynamic)",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::AntiLocking),
        by: [true, true, false],
        why: "the model asks for anti-locking, which the implicit point update applies; explicit analysis has none (remove it)",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::DisplacedConstraint { .. }),
        by: [true, false, false],
        why: "prescribes a non-zero displacement; only quasi-static implicit analysis applies displacements (with the load factor)",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::InclinedRoller { .. }),
        by: [true, true, true],
        why: "",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::FrictionalPlane { .. }),
        by: [true, true, true],
        why: "",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::BodyContact),
        by: [false, false, true],
        why: "the model's bodies are in contact, a velocity field each; only the explicit analysis has contact between bodies yet",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::RigidBody { .. }),
        by: [false, false, true],
        why: "meets the material by contact at the grid nodes; only the explicit analysis has contact yet",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::BodyConstraint { .. }),
        by: [true, true, true],
        why: "",
    },
    Acceptance {
        is: |o| matches!(o, ModelOption::DisplacedBodyConstraint { .. }),
        by: [true, false, false],
        why: "prescribes a non-zero displacement; only quasi-static implicit analysis applies displacements (with the load factor); the dynamic and explicit analyses hold a body (Fixed, or Displacement with Some(0.0))",
    },
];

/// An option the analysis does not accept, and why.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", self.message())]
pub struct Unaccepted {
    pub option: ModelOption,
    pub analysis: AnalysisKind,
    why: &'static str,
}

impl Unaccepted {
    fn message(&self) -> String {
        match self.option {
            ModelOption::DisplacedConstraint { index } => format!("constraint {index} {}", self.why),
            ModelOption::InclinedRoller { index } => format!("inclined roller {index} {}", self.why),
            ModelOption::FrictionalPlane { index } => format!("frictional plane {index} {}", self.why),
            ModelOption::RigidBody { index } => format!("rigid body {index} {}", self.why),
            ModelOption::BodyConstraint { index } | ModelOption::DisplacedBodyConstraint { index } => {
                format!("body constraint {index} {}", self.why)
            }
            _ => self.why.to_string(),
        }
    }
}

impl<const D: usize> Model<D> {
    /// The options this model uses beyond points, laws, grid-plane constraints and loads.
    pub fn options(&self) -> Vec<ModelOption> {
        let mut options = Vec::new();
        if self.background.moves_with_body() {
            options.push(ModelOption::BodyFittedMesh);
        }
        if self.ghost_penalty.is_some() {
            options.push(ModelOption::GhostPenalty);
        }
        if self.geometrically_linear {
            options.push(ModelOption::GeometricallyLinear);
        }
        if self.water.is_some() {
            options.push(ModelOption::Water);
        }
        if self.anti_locking != crate::AntiLocking::None {
            options.push(ModelOption::AntiLocking);
        }
        let displaced = self.constraints.iter().enumerate().filter(|(_, c)| c.is_displaced());
        options.extend(displaced.map(|(index, _)| ModelOption::DisplacedConstraint { index }));
        options.extend((0..self.inclined.len()).map(|index| ModelOption::InclinedRoller { index }));
        options.extend((0..self.frictional.len()).map(|index| ModelOption::FrictionalPlane { index }));
        options.extend(self.body_contact.map(|_| ModelOption::BodyContact));
        options.extend((0..self.rigid_bodies().len()).map(|index| ModelOption::RigidBody { index }));
        options.extend((self.body_constraints().iter().enumerate()).map(|(index, c)| match c.is_displaced() {
            true => ModelOption::DisplacedBodyConstraint { index },
            false => ModelOption::BodyConstraint { index },
        }));
        options
    }

    /// The first option of this model `analysis` does not accept (the table above).
    pub fn check_accepted_by(&self, analysis: AnalysisKind) -> Result<(), Unaccepted> {
        for option in self.options() {
            let row = ACCEPTED.iter().find(|row| (row.is)(&option)).expect("every option is in the table");
            if !row.by[analysis.column()] {
                return Err(Unaccepted { option, analysis, why: row.why });
            }
        }
        Ok(())
    }
}
