//! The `stability` job: a bicycle's weave and capsize speeds, every
//! crossing of a real part through zero and the self-stable speed
//! intervals over a speed range, with the standard deviations of the two
//! speeds that the parameter file's `+/-` values imply (first order, exact
//! derivatives) and, when asked, a Monte Carlo check of them.
//!
//! The command line and Python call [`stability`] and print or convert the
//! typed result; its JSON is the serialization of [`StabilityReport`].

use crate::bicycle::{Bicycle, BicycleError};
use crate::monte_carlo::{monte_carlo_speeds, MonteCarloOptions, MonteCarloSpeeds};
use crate::registry::ModelRegistry;
use crate::sensitivity::{speed_uncertainties, SensitivityError, SensitivityOptions, StabilityUncertainty};
use bikedyn_runtime::eigen::{critical_speeds_of, EigenError};
/// The weave and capsize speeds and each crossing of the eigenvalues.
pub use bikedyn_runtime::eigen::{CriticalSpeeds, CrossingDirection, CrossingKind};
use serde::Serialize;

/// What the `stability` job computes.
#[derive(Clone, Debug)]
pub struct StabilityOptions {
    /// The model (default: the bicycle's default model).
    pub model: Option<String>,
    /// Lower end of the speed range (m/s); the standard deviations of the
    /// speeds are given only from 0.
    pub speed_min: f64,
    /// Upper end of the speed range (m/s).
    pub speed_max: f64,
    /// A Monte Carlo check: this many bicycles drawn about the file's
    /// values with its `+/-` standard deviations, from this seed.
    pub monte_carlo: Option<(usize, u64)>,
    /// The bicycle's name in the report (default: its own name; the
    /// command line gives the name or path as typed).
    pub label: Option<String>,
}

impl Default for StabilityOptions {
    fn default() -> Self {
        Self {
            model: None,
            speed_min: 0.0,
            speed_max: 10.0,
            monte_carlo: None,
            label: None,
        }
    }
}

/// One speed where a real part crosses zero.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CrossingReport {
    /// Speed (m/s).
    pub speed: f64,
    /// The mode: `weave`, `capsize`, `castering`, or a merged pair's name.
    pub mode: &'static str,
    /// `destabilizing` or `stabilizing`, with increasing speed.
    pub direction: String,
    /// `complex_pair` or `real_root`.
    pub kind: &'static str,
    /// Imaginary part at the crossing (rad/s; 0 for a real root).
    pub frequency: f64,
}

/// The result of the `stability` job.
#[derive(Clone, Debug, Serialize)]
pub struct StabilityReport {
    /// The bicycle as named (built-in name or file).
    pub bike: String,
    /// The generated model.
    pub model: String,
    /// `v_w`: the weave speed (m/s), where the weave becomes stable.
    pub weave_speed: Option<f64>,
    /// `v_c`: the capsize speed (m/s), where the capsize mode becomes
    /// unstable.
    pub capsize_speed: Option<f64>,
    /// `v_d`: where the two real weave roots merge into the weave pair
    /// (m/s).
    #[serde(rename = "weave_real_pair_merge_speed")]
    pub weave_real_pair_merge: Option<f64>,
    /// Maximal speed intervals `[lo, hi]` (m/s) where every real part is
    /// negative.
    pub stable_intervals: Vec<[f64; 2]>,
    /// Every crossing in the range, ascending.
    pub crossings: Vec<CrossingReport>,
    /// Standard deviation of `v_w` (m/s), when the file gives `+/-` values.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weave_speed_sd: Option<Option<f64>>,
    /// Standard deviation of `v_c` (m/s), likewise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub capsize_speed_sd: Option<Option<f64>>,
    /// The first-order propagation in full (shares of the variance).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub uncertainty: Option<StabilityUncertainty>,
    /// The Monte Carlo check, when asked.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub monte_carlo: Option<MonteCarloSpeeds>,
    /// Why the standard deviations could not be computed although the file
    /// gives `+/-` values (a note for the reader; not serialized).
    #[serde(skip)]
    pub uncertainty_missing: Option<String>,
    /// The critical speeds as computed, for text output.
    #[serde(skip)]
    pub critical: CriticalSpeeds,
}

/// Errors of the job.
#[derive(Debug, thiserror::Error)]
pub enum StabilityError {
    /// The bicycle or model.
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    /// The eigenvalues over the range.
    #[error(transparent)]
    Eigen(#[from] EigenError),
    /// The Monte Carlo draws.
    #[error(transparent)]
    Sensitivity(#[from] SensitivityError),
    /// A speed range that is not `0 <= min < max`, finite.
    #[error("speed range [{0}, {1}] m/s: expected 0 <= minimum < maximum, finite")]
    SpeedRange(f64, f64),
    /// Fewer than two Monte Carlo draws.
    #[error("{0} Monte Carlo draws: at least 2 are needed for a spread")]
    TooFewDraws(usize),
    /// A Monte Carlo check of a bicycle without `+/-` values.
    #[error("Monte Carlo draws are made about the file's +/- standard deviations, and `{0}` gives none")]
    NoUncertainties(String),
}

/// The `stability` job.
pub fn stability<R: ModelRegistry>(
    bike: &Bicycle<R>,
    opts: &StabilityOptions,
) -> Result<StabilityReport, StabilityError> {
    let (lo, hi) = (opts.speed_min, opts.speed_max);
    if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && hi > lo) {
        return Err(StabilityError::SpeedRange(lo, hi));
    }
    let lin = bike.linear_with(opts.model.as_deref())?;
    let crit = critical_speeds_of(&lin, lo, hi)?;
    // The speeds' standard deviations (none for a file without `+/-`, or
    // for a range that does not start at rest, where the crossings found
    // may not be the bicycle's v_w and v_c).
    let (uncertainty, uncertainty_missing) = if lo == 0.0 {
        match speed_uncertainties(
            bike,
            &SensitivityOptions {
                model: opts.model.clone(),
                speed_max: hi,
                ..SensitivityOptions::default()
            },
        ) {
            Ok(u) => (u, None),
            Err(SensitivityError::NoCrossing { .. }) => (None, None),
            Err(e) => (None, Some(e.to_string())),
        }
    } else {
        (None, None)
    };
    let monte_carlo = match opts.monte_carlo {
        None => None,
        Some((draws, _)) if draws < 2 => return Err(StabilityError::TooFewDraws(draws)),
        Some((draws, seed)) => Some(
            monte_carlo_speeds(
                bike,
                &MonteCarloOptions {
                    draws,
                    seed,
                    model: opts.model.clone(),
                    speed_max: hi,
                },
            )?
            .ok_or_else(|| StabilityError::NoUncertainties(bike.name.clone()))?,
        ),
    };
    Ok(StabilityReport {
        bike: opts.label.clone().unwrap_or_else(|| bike.name.clone()),
        model: lin.model.to_string(),
        weave_speed: crit.weave_speed,
        capsize_speed: crit.capsize_speed,
        weave_real_pair_merge: crit.weave_real_pair_merge,
        stable_intervals: crit.stable_intervals.clone(),
        crossings: crit
            .crossings
            .iter()
            .map(|x| CrossingReport {
                speed: x.speed,
                mode: x.mode.name(),
                direction: format!("{:?}", x.direction).to_lowercase(),
                kind: match x.kind {
                    CrossingKind::RealRoot => "real_root",
                    CrossingKind::ComplexPair => "complex_pair",
                },
                frequency: x.frequency,
            })
            .collect(),
        weave_speed_sd: uncertainty
            .as_ref()
            .map(|u| u.weave_speed.as_ref().map(|x| x.standard_deviation)),
        capsize_speed_sd: uncertainty
            .as_ref()
            .map(|u| u.capsize_speed.as_ref().map(|x| x.standard_deviation)),
        uncertainty,
        monte_carlo,
        uncertainty_missing,
        critical: crit,
    })
}
