//! Frequency responses of a bicycle at a speed: the transfer functions from
//! the roll and steer torques to the roll and steer angles over a
//! log-spaced frequency grid (`bikedyn bode`; issue 36, item 3). The
//! numerics are `bikedyn_runtime::frequency`.
//!
//! Any bicycle with second-order roll-steer equations works, effects
//! included (the model linearized at the speed). The inputs are the two
//! torques of the equations' input matrix; a lateral force at the saddle is
//! not among the model's inputs, so it is not offered. A model with extra
//! first-order states (tyre forces) has no torque input matrix formed and is
//! refused.

use crate::bicycle::{Bicycle, BicycleError};
use crate::registry::ModelRegistry;
use bikedyn_runtime::eigen::LinearBicycle;
/// The transfer functions at each frequency (the numerics' own result type).
pub use bikedyn_runtime::frequency::FrequencyResponse;
use bikedyn_runtime::frequency::{frequency_response as response_of, log_grid, FrequencyError};
use serde::Serialize;
use thiserror::Error;

/// Most frequencies of one response.
pub const MAX_POINTS: usize = 1_000_000;

/// What [`frequency_response`] computes.
#[derive(Clone, Debug, PartialEq)]
pub struct FrequencyOptions {
    /// Generated model (`None`: the bicycle's default model).
    pub model: Option<String>,
    /// Forward speed (m/s).
    pub speed: f64,
    /// Lowest angular frequency (rad/s).
    pub omega_min: f64,
    /// Highest angular frequency (rad/s).
    pub omega_max: f64,
    /// Number of frequencies, evenly spaced in logarithm.
    pub points: usize,
}

impl Default for FrequencyOptions {
    fn default() -> Self {
        FrequencyOptions {
            model: None,
            speed: 5.0,
            omega_min: 0.1,
            omega_max: 100.0,
            points: 200,
        }
    }
}

/// The frequency response of a bicycle.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Bode {
    /// The bicycle (built-in name or file).
    pub bike: String,
    /// The generated model of the equations.
    pub model: &'static str,
    /// Units of `G`.
    pub units: &'static str,
    #[serde(flatten)]
    pub response: FrequencyResponse,
}

/// Errors of [`frequency_response`].
#[derive(Debug, Error)]
pub enum FrequencyResponseError {
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    #[error("speed {speed}: must be a finite forward speed (m/s)")]
    NonFiniteSpeed { speed: f64 },
    #[error("{points} frequencies: between 2 and {MAX_POINTS} are allowed")]
    Points { points: usize },
    #[error("{bike}: {source}")]
    Frequency { bike: String, source: FrequencyError },
}

/// The transfer functions of `bike` at `options.speed` over the frequency
/// grid of `options`.
pub fn frequency_response<R: ModelRegistry>(
    bike: &Bicycle<R>,
    options: &FrequencyOptions,
) -> Result<Bode, FrequencyResponseError> {
    if !options.speed.is_finite() {
        return Err(FrequencyResponseError::NonFiniteSpeed { speed: options.speed });
    }
    if !(2..=MAX_POINTS).contains(&options.points) {
        return Err(FrequencyResponseError::Points { points: options.points });
    }
    let err = |source| FrequencyResponseError::Frequency {
        bike: bike.name.clone(),
        source,
    };
    let omega = log_grid(options.omega_min, options.omega_max, options.points).map_err(err)?;
    let lin = bike.linear_with(options.model.as_deref())?;
    if lin.first_order().is_some() {
        return Err(err(FrequencyError::FirstOrder {
            model: lin.model.to_string(),
        }));
    }
    let response = response_of(&lin, options.speed, &omega).map_err(err)?;
    Ok(Bode {
        bike: bike.name.clone(),
        model: lin.model,
        units: "G in rad/(N m); magnitude_db re 1 rad/(N m); phase in degrees; omega in rad/s",
        response,
    })
}
