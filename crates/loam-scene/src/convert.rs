//! The one place where the schema's enums meet the domain enums they mirror: a `From`
//! impl each, so that a renamed Rust variant breaks the build here instead of silently
//! changing what a scene file means. None of these can fail; the values inside them are
//! checked by the domain constructors, whose refusals the builder parts locate.

use super::schema::{
    AntiLockingSpec, BasisSpec, KinematicsSpec, LinearSpec, MassSpec, SchemeSpec, TimeStepSpec, VtuFormatSpec,
};
use loam_explicit::{TimeStep, UpdateScheme};
use loam_format::output::VtuFormat;
use loam_grid::BasisKind;
use loam_implicit::MassMatrix;
use loam_model::{AntiLocking, Kinematics};
use loam_solve::{LinearSolverChoice, LinearSolverKind};

impl From<BasisSpec> for BasisKind {
    fn from(spec: BasisSpec) -> Self {
        match spec {
            BasisSpec::Linear => BasisKind::Linear,
            BasisSpec::Gimp => BasisKind::Gimp,
            BasisSpec::QuadraticBSpline => BasisKind::QuadraticBSpline,
        }
    }
}

impl From<VtuFormatSpec> for VtuFormat {
    fn from(spec: VtuFormatSpec) -> Self {
        match spec {
            VtuFormatSpec::Binary => VtuFormat::Binary,
            VtuFormatSpec::BinaryDouble => VtuFormat::BinaryDouble,
            VtuFormatSpec::Ascii => VtuFormat::Ascii,
        }
    }
}

impl From<KinematicsSpec> for Kinematics {
    fn from(spec: KinematicsSpec) -> Self {
        match spec {
            KinematicsSpec::SmallStrain => Kinematics::SmallStrain,
            KinematicsSpec::FiniteStrain => Kinematics::FiniteStrain,
        }
    }
}

impl From<AntiLockingSpec> for AntiLocking {
    fn from(spec: AntiLockingSpec) -> Self {
        match spec {
            AntiLockingSpec::None => AntiLocking::None,
            AntiLockingSpec::BBar => AntiLocking::BBar,
            AntiLockingSpec::AssumedStrain { stabilization } => AntiLocking::AssumedStrain { stabilization },
            AntiLockingSpec::FBar => AntiLocking::FBar,
        }
    }
}

impl From<LinearSpec> for LinearSolverChoice {
    fn from(spec: LinearSpec) -> Self {
        match spec {
            LinearSpec::Auto => LinearSolverChoice::Auto,
            LinearSpec::Direct => LinearSolverChoice::Direct,
            LinearSpec::Iterative => LinearSolverChoice::Iterative,
            LinearSpec::Cholesky => LinearSolverChoice::Forced(LinearSolverKind::Cholesky),
            LinearSpec::Lu => LinearSolverChoice::Forced(LinearSolverKind::Lu),
            LinearSpec::Cg => LinearSolverChoice::Forced(LinearSolverKind::Cg),
            LinearSpec::BiCgStab => LinearSolverChoice::Forced(LinearSolverKind::BiCgStab),
        }
    }
}

impl From<MassSpec> for MassMatrix {
    fn from(spec: MassSpec) -> Self {
        match spec {
            MassSpec::Lumped => MassMatrix::Lumped,
            MassSpec::Consistent => MassMatrix::Consistent,
        }
    }
}

impl From<SchemeSpec> for UpdateScheme {
    fn from(spec: SchemeSpec) -> Self {
        match spec {
            SchemeSpec::Usf => UpdateScheme::Usf,
            SchemeSpec::Usl => UpdateScheme::Usl,
            SchemeSpec::Musl => UpdateScheme::Musl,
        }
    }
}

impl From<&TimeStepSpec> for TimeStep {
    fn from(spec: &TimeStepSpec) -> Self {
        match *spec {
            TimeStepSpec::Cfl(safety) => TimeStep::Cfl { safety },
            TimeStepSpec::Fixed { dt, allow_above_critical } => TimeStep::Fixed { dt, allow_above_critical },
        }
    }
}
