//! The Monte Carlo check of the critical speeds' standard deviations: the
//! weave and capsize speeds of bicycles drawn about a parameter file's
//! values with its `+/-` standard deviations.
//!
//! [`speed_uncertainties`](crate::sensitivity::speed_uncertainties)
//! propagates the file's standard deviations to first order with exact
//! derivatives; this draws the bicycles instead, so the two agree where the
//! speeds are about linear over a standard deviation of each parameter, and
//! where they do not, the draws are the answer.

use crate::bicycle::Bicycle;
use crate::registry::ModelRegistry;
use crate::sensitivity::SensitivityError;
use bikedyn_runtime::eigen::critical_speeds_of;
use bikedyn_runtime::random::SplitMix64;
use rayon::prelude::*;
use serde::Serialize;

/// Options of [`monte_carlo_speeds`].
#[derive(Clone, Debug, PartialEq)]
pub struct MonteCarloOptions {
    /// Number of drawn bicycles (at least 2).
    pub draws: usize,
    /// Seed of the draws: the same seed gives the same draws on any
    /// number of threads.
    pub seed: u64,
    /// Generated model (default: the bicycle's own choice).
    pub model: Option<String>,
    /// Upper end of the searched speeds (m/s).
    pub speed_max: f64,
}

impl Default for MonteCarloOptions {
    fn default() -> Self {
        MonteCarloOptions {
            draws: 1000,
            seed: 1,
            model: None,
            speed_max: 10.0,
        }
    }
}

/// One critical speed over the draws that have it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SampledSpeed {
    /// Mean (m/s).
    pub mean: f64,
    /// Sample standard deviation (m/s).
    pub standard_deviation: f64,
    /// Standard error of that standard deviation (m/s), `sd / sqrt(2 (n -
    /// 1))` (normal draws): how far from the distribution's own the
    /// sample's may lie.
    pub standard_error_of_sd: f64,
    /// Draws that have the speed in the searched range.
    pub draws: usize,
}

/// The critical speeds of the drawn bicycles.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MonteCarloSpeeds {
    /// Bicycles drawn.
    pub draws: usize,
    /// Their seed.
    pub seed: u64,
    /// Draws whose parameters are no bicycle (a negative mass, an inertia
    /// that breaks the triangle inequality ...), left out.
    pub not_a_bicycle: usize,
    pub weave_speed: Option<SampledSpeed>,
    pub capsize_speed: Option<SampledSpeed>,
}

/// The weave and capsize speeds of `options.draws` bicycles, each with
/// every parameter that `bike`'s file gives a standard deviation drawn from
/// a normal distribution about its value with that deviation, independently
/// (what the files' `+/-` values are: each parameter's measurement error).
/// `None` when the file gives no standard deviations. The deviates are
/// drawn in one sequence from the seed before the bicycles are evaluated in
/// parallel, so the result does not depend on the threads.
pub fn monte_carlo_speeds<R: ModelRegistry>(
    bike: &Bicycle<R>,
    options: &MonteCarloOptions,
) -> Result<Option<MonteCarloSpeeds>, SensitivityError> {
    if bike.uncertainties.is_empty() {
        return Ok(None);
    }
    if !(options.speed_max.is_finite() && options.speed_max > 0.0) {
        return Err(SensitivityError::BadSpeedMax {
            speed_max: options.speed_max,
        });
    }
    let nominal = |symbol: &str| {
        bike.parameters
            .get(symbol)
            .or_else(|| bike.effects.get(symbol).copied())
    };
    let parameters: Vec<(&str, f64, f64)> = bike
        .uncertainties
        .iter()
        .filter_map(|(s, sd)| Some((s.as_str(), nominal(s)?, *sd)))
        .collect();
    // The nominal bicycle must be one the model takes (its errors are the
    // caller's to see, not a draw's).
    bike.linear_with(options.model.as_deref())?;
    let draws = options.draws.max(2);
    let mut rng = SplitMix64::new(options.seed);
    let deviates: Vec<Vec<f64>> = (0..draws)
        .map(|_| parameters.iter().map(|_| rng.normal()).collect())
        .collect();
    let speeds: Vec<Option<(Option<f64>, Option<f64>)>> = deviates
        .par_iter()
        .map(|z| {
            let mut b = bike.clone();
            for ((symbol, value, sd), z) in parameters.iter().zip(z) {
                b = b.with_parameter(symbol, value + sd * z).ok()?;
            }
            let lin = b.linear_with(options.model.as_deref()).ok()?;
            let crit = critical_speeds_of(&lin, 0.0, options.speed_max).ok()?;
            Some((crit.weave_speed, crit.capsize_speed))
        })
        .collect();
    let sampled = |pick: fn(&(Option<f64>, Option<f64>)) -> Option<f64>| {
        let x: Vec<f64> = speeds.iter().flatten().filter_map(pick).collect();
        let n = x.len();
        if n < 2 {
            return None;
        }
        let mean = x.iter().sum::<f64>() / n as f64;
        let sd = (x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / (n - 1) as f64).sqrt();
        Some(SampledSpeed {
            mean,
            standard_deviation: sd,
            standard_error_of_sd: sd / (2.0 * (n - 1) as f64).sqrt(),
            draws: n,
        })
    };
    Ok(Some(MonteCarloSpeeds {
        draws,
        seed: options.seed,
        not_a_bicycle: speeds.iter().filter(|s| s.is_none()).count(),
        weave_speed: sampled(|s| s.0),
        capsize_speed: sampled(|s| s.1),
    }))
}
