//! Nonlinear simulation of a bicycle through a generated model (`bikedyn
//! simulate`): the model choice and the run; the inputs (initial
//! conditions, kicks, torque pulses) and integration options are the
//! runtime's plain structs.

use crate::bicycle::{Bicycle, BicycleError};
use bikedyn_runtime::linearize::{parameter_vector, LinearizeError};
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry, ModelVisitor};
use bikedyn_runtime::simulate::{simulate, InitialConditions, Inputs, SimOptions, SimulateError, Simulation};
use bikedyn_runtime::MultibodyModel;
use thiserror::Error;

/// Why a simulation could not run.
#[derive(Debug, Error)]
pub enum SimulationError {
    /// The bicycle lacks a parameter or the named model cannot represent it.
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    /// Free speed was asked of a model without a free-speed variant.
    #[error("model `{model}` has no free-speed variant (see `bikedyn models`)")]
    NoFreeSpeedVariant { model: &'static str },
    /// The parameter vector of the model could not be formed.
    #[error(transparent)]
    Linearize(#[from] LinearizeError),
    /// The integration failed or its inputs are invalid.
    #[error(transparent)]
    Simulate(#[from] SimulateError),
}

/// The model a bicycle is simulated with: `model` by name, or the one that
/// fits the bicycle; its free-speed variant when `free_speed` (among the
/// models of the bicycle's registry).
pub fn choose_model<R: ModelRegistry>(
    bike: &Bicycle<R>,
    model: Option<&str>,
    free_speed: bool,
) -> Result<&'static ModelInfo, SimulationError> {
    let info = bike.model(model)?;
    if !free_speed {
        return Ok(info);
    }
    crate::models::free_speed_variant_in::<R>(info).ok_or(SimulationError::NoFreeSpeedVariant { model: info.name })
}

/// Simulate `bike` through `model` from `initial` with `inputs` for
/// `duration` (s).
pub fn run<R: ModelRegistry>(
    bike: &Bicycle<R>,
    model: &ModelInfo,
    initial: &InitialConditions,
    inputs: &Inputs,
    duration: f64,
    options: &SimOptions,
) -> Result<Simulation, SimulationError> {
    bike.refuse_feedback("simulate")?;
    let lookup = bike.lookup()?;
    R::with_model(
        model.name,
        RunSimulation {
            lookup: &lookup,
            ic: initial,
            inputs,
            duration,
            opts: options,
        },
    )
    .expect("registered model")
}

struct RunSimulation<'a, F: Fn(&str) -> Option<f64>> {
    lookup: &'a F,
    ic: &'a InitialConditions,
    inputs: &'a Inputs,
    duration: f64,
    opts: &'a SimOptions,
}

impl<F: Fn(&str) -> Option<f64>> ModelVisitor for RunSimulation<'_, F> {
    type Output = Result<Simulation, SimulationError>;
    fn visit<M: MultibodyModel>(self) -> Self::Output {
        let param = parameter_vector::<M>(self.lookup, self.ic.speed)?;
        Ok(simulate::<M>(&param, self.ic, self.inputs, self.duration, self.opts)?)
    }
}
