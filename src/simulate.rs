//! Nonlinear simulation of a bicycle through a generated model (`bikedyn
//! simulate`, Python `simulate`): the job ([`SimulateRequest`] ->
//! [`SimulationOutcome`], [`simulate`]), the model choice and the run; the
//! inputs (initial conditions, kicks, torque pulses) and integration
//! options are the runtime's plain structs.

use crate::bicycle::{Bicycle, BicycleError};
use bikedyn_runtime::linearize::{parameter_vector, LinearizeError};
use bikedyn_runtime::registry::{ModelInfo, ModelRegistry, ModelVisitor};
use bikedyn_runtime::simulate::simulate as integrate;
/// The job's vocabulary: initial state, inputs, integration options and
/// the simulated run (the runtime's plain structs).
pub use bikedyn_runtime::simulate::{
    Events, InitialConditions, Inputs, Kick, Method, PulseShape, PulseTarget, SimOptions, SimulateError, Simulation,
    TorquePulse, MIN_RTOL,
};
use bikedyn_runtime::MultibodyModel;
use serde::Serialize;
use thiserror::Error;

/// A simulation job: which model, from what state, with what inputs, for
/// how long, how accurately. Angles in rad, rates in rad/s, speeds in m/s,
/// times in s (the thesis's signs: steer positive to the left).
#[derive(Clone, Debug)]
pub struct SimulateRequest {
    /// The model by name (`None`, the default: the smallest driven-speed
    /// model that has every parameter the bicycle sets).
    pub model: Option<String>,
    /// Run the model's free-speed variant, the speed a state of the motion
    /// (default false: the speed is imposed).
    pub free_speed: bool,
    /// The state at t = 0 (default upright, straight ahead, 4.5 m/s).
    pub initial: InitialConditions,
    /// Kicks and torque pulses (default none).
    pub inputs: Inputs,
    /// Simulated time (s, default 5).
    pub duration: f64,
    /// Tolerances, method, output interval and stop events (the runtime's
    /// defaults: rtol 1e-8, atol 1e-10, DOP853, 0.01 s, stops at 1 rad of
    /// roll and 1.4 rad of steer).
    pub options: SimOptions,
}

impl Default for SimulateRequest {
    fn default() -> Self {
        Self {
            model: None,
            free_speed: false,
            initial: InitialConditions::default(),
            inputs: Inputs::default(),
            duration: 5.0,
            options: SimOptions::default(),
        }
    }
}

/// What a simulation job gives: the model run and the motion.
#[derive(Clone, Debug)]
pub struct SimulationOutcome {
    /// The model run (the free-speed variant when asked).
    pub model: &'static ModelInfo,
    /// The motion, sample by sample, and the integrator's statistics.
    pub simulation: Simulation,
    /// Wall-clock time of the integration (s; NaN in WebAssembly, which has
    /// no clock).
    pub wall_seconds: f64,
}

/// A simulation's figures of merit, as `simulate --json`-style output and
/// Python's `stats` give them.
#[derive(Clone, Debug, Serialize)]
pub struct SimulationSummary {
    /// The model run.
    pub model: String,
    /// Whether the speed was free (a state) or imposed.
    pub free_speed: bool,
    /// Why the run ended (the duration, or a stop event).
    pub stop: String,
    /// Simulated time (s).
    pub simulated_seconds: f64,
    /// Wall-clock time of the integration (s; `null` in WebAssembly).
    pub wall_seconds: f64,
    /// Right-hand-side evaluations of the integrator.
    pub rhs_evaluations: u64,
    /// Accepted steps.
    pub accepted_steps: u64,
    /// Rejected steps.
    pub rejected_steps: u64,
    /// Largest residual of the holonomic constraints over the run (m).
    pub max_constraint_residual: f64,
    /// Largest residual of the velocity constraints (m/s).
    pub max_velocity_residual: f64,
    /// Relative change of the total energy over the run (a conservative
    /// model's accuracy check).
    pub relative_energy_change: f64,
}

impl SimulationOutcome {
    /// The run's figures of merit.
    pub fn summary(&self) -> SimulationSummary {
        let sim = &self.simulation;
        SimulationSummary {
            model: sim.model.to_string(),
            free_speed: self.model.free_speed,
            stop: sim.stop.to_string(),
            simulated_seconds: sim.t.last().copied().unwrap_or(0.0),
            wall_seconds: self.wall_seconds,
            rhs_evaluations: sim.stats.rhs_evaluations,
            accepted_steps: sim.stats.accepted_steps,
            rejected_steps: sim.stats.rejected_steps,
            max_constraint_residual: sim.max_constraint_residual(),
            max_velocity_residual: sim.max_velocity_residual(),
            relative_energy_change: sim.relative_energy_drift(),
        }
    }
}

/// Run a simulation job for `bike` (the one call behind `bikedyn simulate`
/// and Python's `simulate`): choose the model, form its parameters, and
/// integrate. The runtime refuses invalid inputs (a non-finite state, a
/// tolerance below [`bikedyn_runtime::simulate::MIN_RTOL`], a
/// non-positive duration or output interval) with an error that says which.
pub fn simulate<R: ModelRegistry>(
    bike: &Bicycle<R>,
    request: &SimulateRequest,
) -> Result<SimulationOutcome, SimulationError> {
    let model = choose_model(bike, request.model.as_deref(), request.free_speed)?;
    let (simulation, wall_seconds) = timed(|| {
        run(
            bike,
            model,
            &request.initial,
            &request.inputs,
            request.duration,
            &request.options,
        )
    });
    Ok(SimulationOutcome {
        model,
        simulation: simulation?,
        wall_seconds,
    })
}

/// `f`'s result and the wall-clock seconds it took.
#[cfg(not(target_arch = "wasm32"))]
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let start = std::time::Instant::now();
    let out = f();
    (out, start.elapsed().as_secs_f64())
}

/// In WebAssembly there is no clock in `std` (`Instant::now` would abort
/// the module): the time is NaN (`null` in JSON), and the browser page
/// times the call itself.
#[cfg(target_arch = "wasm32")]
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    (f(), f64::NAN)
}

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
    let lookup = bike.lookup()?;
    // The bicycle's controller acts through the whole run, whatever the
    // request's perturbations.
    let closed_loop = Inputs {
        feedback: bike.feedback.clone(),
        ..inputs.clone()
    };
    R::with_model(
        model.name,
        RunSimulation {
            lookup: &lookup,
            ic: initial,
            inputs: &closed_loop,
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
        Ok(integrate::<M>(&param, self.ic, self.inputs, self.duration, self.opts)?)
    }
}
