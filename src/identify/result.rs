//! The identification's result as data: one schema for measured runs, logs
//! and tables of measured weave eigenvalues (`bikedyn identify --json`,
//! `report.json`, Python's `IdentifyResult`). These types are the schema:
//! the JSON is their derived serialization, and
//! `tests/identification/result_schema.rs` checks it against the committed
//! `tests/data/identify_schema.json`.
//!
//! The keys every source has come first (`source`, the selection, the
//! fitted parameters, every candidate tried with its verdict, the errors
//! before and after, what the library leaves, what discovery found); what
//! only one source has follows in [`Details`]. A key a source cannot fill
//! is `null` (a table has no time series, so no roll error), never absent.

use super::discovery::DiscoveryOutcome;
use super::time_series::TimeSeriesOutcome;
use super::weave_errors::Excluded;
use super::words::verdict_text;
use bikedyn_runtime::identify::confounding::Design;
use bikedyn_runtime::identify::remaining::Remaining;
use bikedyn_runtime::identify::state_correlation::StateCorrelation;
use bikedyn_runtime::identify::{Bound, EffectParameter, Verdict, Weights};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::PathBuf;

/// The two-sided 95 % point of the normal distribution, as the reports
/// print it: a parameter's interval is `value +- 1.96 stderr`.
pub const Z_95: f64 = 1.96;

/// One row of a measured eigenvalue table.
#[derive(Clone, Debug, Serialize)]
pub struct EigenPoint {
    /// Line of the file.
    pub line: usize,
    /// Forward speed (m/s).
    pub speed: f64,
    /// Measured weave eigenvalue `[re, im]` (1/s).
    pub eigenvalue: [f64; 2],
    /// Its standard errors, if the table gives them.
    pub stderr: Option<[f64; 2]>,
}

/// What was identified from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    /// Measured runs or logs (time series of kicks).
    Runs,
    /// A table of measured weave eigenvalues.
    EigenvalueTable,
}

/// The identification's result.
#[derive(Clone, Debug, Serialize)]
pub struct IdentifyResult {
    pub source: Source,
    /// The selected effects and corrections, in the order they were added
    /// (` (speed decay)` after an effect that explains only the speed's
    /// fall).
    pub selected_effects: Vec<String>,
    /// Each fitted symbol of the selection.
    pub parameters: BTreeMap<String, Estimate>,
    /// Every candidate of every step, with its fit and verdict.
    pub candidates: Vec<CandidateTrial>,
    /// The base model's errors.
    pub error_before: Errors,
    /// The errors with the selection.
    pub error_after: Errors,
    /// The driven-speed model of the weave predictions.
    pub driven_model: &'static str,
    /// What the library leaves in the weave eigenvalues: a pattern beyond
    /// their scatter, or none (`null`: too few kicks or rows to test).
    pub remaining: Option<Remaining>,
    /// What the dictionary of generalized forces found on the weave
    /// eigenvalues beyond the library (`null`: not requested).
    pub discovery: Option<DiscoveryOutcome>,
    /// What only this source has.
    #[serde(flatten)]
    pub details: Details,
}

/// What only one source has.
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum Details {
    Runs(Box<RunDetails>),
    Table(TableDetails),
}

/// What only runs and logs have.
#[derive(Clone, Debug, Serialize)]
pub struct RunDetails {
    /// The free-speed model fitted.
    pub model: &'static str,
    /// What the runs' roll channel measures: `"angle"` or `"rate"`.
    pub roll_channel: bikedyn_runtime::identify::RollChannel,
    /// The model's speed was imposed (logs of a motor-held speed).
    pub speed_imposed: bool,
    /// Kicks fitted.
    pub kicks: usize,
    /// Runs and kicks left out, each with the reason.
    pub skipped: Vec<String>,
    /// Kicks kept out of the eigenvalue figures, with the test they failed.
    pub eigen_excluded: Vec<ExcludedKick>,
    /// The residual diagnosis of the base model.
    pub findings: Vec<super::diagnosis::Finding>,
    /// Whether each channel's residual after identification follows the
    /// simulated states.
    pub state_correlation: Vec<StateCorrelation>,
    /// What the dictionary's terms found in the time series (`null`: not
    /// requested).
    pub time_series_discovery: Option<TimeSeriesOutcome>,
    /// The backward check of every member of the final model.
    pub final_check: Vec<MemberCheck>,
    /// Pairs of candidates the runs do not separate.
    pub confounded: Vec<Confounded>,
    /// Each kick's channel weights.
    pub weights: Vec<Weights>,
    /// Folds of the cross-validation (whole runs or logs held out).
    pub folds: usize,
    /// Simulations run.
    pub simulations: usize,
    /// Wall-clock time (s).
    pub seconds: f64,
}

/// What only a table has.
#[derive(Clone, Debug, Serialize)]
pub struct TableDetails {
    /// The table read.
    pub table: PathBuf,
    /// Its rows.
    pub points: Vec<EigenPoint>,
    /// Candidates not tried, each `[name, reason]`.
    pub not_tried: Vec<(String, String)>,
    /// The weave eigenvalue `[re (1/s), im (rad/s)]` of each row with the
    /// base model and with the selection.
    pub predicted_before: Vec<Option<[f64; 2]>>,
    pub predicted_after: Vec<Option<[f64; 2]>>,
}

/// A fitted parameter.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Estimate {
    /// The fitted value (`unit`).
    pub value: f64,
    /// The 95 % interval `value -+ 1.96 stderr`.
    pub low: f64,
    pub high: f64,
    /// One standard error.
    pub stderr: f64,
    /// SI unit.
    pub unit: String,
    /// Symbols that take this one's value.
    pub tied: Vec<String>,
    /// The stated prior of a correction (the bicycle file's `+/-`, or the
    /// model's default for its kind).
    pub prior: Option<Prior>,
    /// The value's distance from the prior's mean, in prior standard
    /// deviations.
    pub prior_sds: Option<f64>,
    /// A value on its floor or ceiling: a limit, not an estimate.
    pub on_bound: Option<OnBound>,
}

/// A Gaussian prior: mean and standard deviation.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Prior {
    pub mean: f64,
    pub sd: f64,
}

/// Which bound a value sits on (`{"floor": x}` or `{"ceiling": x}`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum OnBound {
    Floor(f64),
    Ceiling(f64),
}

impl Estimate {
    /// The estimate of parameter `p` at `value` with standard error
    /// `stderr`.
    pub fn of(p: &EffectParameter, value: f64, stderr: f64) -> Self {
        Estimate {
            value,
            low: value - Z_95 * stderr,
            high: value + Z_95 * stderr,
            stderr,
            unit: p.unit.clone(),
            tied: p.tied.clone(),
            prior: p.prior.map(|(mean, sd)| Prior { mean, sd }),
            prior_sds: p.prior.map(|(mean, sd)| (value - mean) / sd),
            on_bound: p.on_bound(value).map(|b| match b {
                Bound::Floor(lo) => OnBound::Floor(lo),
                Bound::Ceiling(hi) => OnBound::Ceiling(hi),
            }),
        }
    }
}

/// `parameters` fitted to `values` with `stderr` (one of each per
/// parameter, in order), by symbol.
pub fn estimates<'a>(
    parameters: impl IntoIterator<Item = &'a EffectParameter>,
    values: &[f64],
    stderr: &[f64],
) -> BTreeMap<String, Estimate> {
    parameters
        .into_iter()
        .zip(values.iter().zip(stderr))
        .map(|(p, (&v, &se))| (p.symbol.clone(), Estimate::of(p, v, se)))
        .collect()
}

/// A fitted value of a candidate's fit.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FittedValue {
    pub symbol: String,
    pub value: f64,
    /// One standard error.
    pub stderr: f64,
}

/// One candidate tried at one step.
#[derive(Clone, Debug, Serialize)]
pub struct CandidateTrial {
    /// The step (from 1).
    pub step: usize,
    pub name: String,
    /// The effects and corrections it adds (two for a pair).
    pub members: Vec<String>,
    /// The step's base selection it extends.
    pub extends: Vec<String>,
    /// The criterion's change against the step's base (BIC; negative:
    /// better), when fitted.
    pub score: Option<f64>,
    /// The score test's prediction of that change, when made.
    pub predicted_score: Option<f64>,
    /// Held-out error (runs: the folds of runs; a table: leave one speed
    /// out), when cross-validated.
    pub cv: Option<f64>,
    /// The step base's held-out error.
    pub base_cv: f64,
    /// The fit's values (its base's parameters included), when fitted.
    pub values: Option<Vec<FittedValue>>,
    /// Whether it was added.
    pub selected: bool,
    /// The verdict with its numbers.
    pub outcome: Verdict,
    /// The verdict in words.
    pub verdict: String,
}

/// How far the model's predictions are from the measurements at one stage.
#[derive(Clone, Debug, Serialize)]
pub struct Errors {
    /// RMS |measured - predicted| weave eigenvalue over the kicks (or
    /// rows) whose eigenvalue counts as a weave (1/s).
    pub eigen_rms: f64,
    /// The same with each kick weighted by the inverse variance of its
    /// measured eigenvalue (1/s; `null` for a table).
    pub eigen_weighted_rms: Option<f64>,
    /// Median over the runs of each run's roll and steer RMS (rad, or
    /// rad/s for a roll-rate channel; `null` for a table).
    pub median_run_roll_rms: Option<f64>,
    pub median_run_steer_rms: Option<f64>,
    /// Pooled RMS roll (rad or rad/s), steer (rad) and speed (m/s)
    /// residuals of the simulated kicks (`null` for a table).
    pub roll_rms: Option<f64>,
    pub steer_rms: Option<f64>,
    pub speed_rms: Option<f64>,
    /// The same with each run (or table row) predicted by values fitted
    /// without it; before identification, the base model's.
    pub held_out: HeldOutErrors,
    /// Each kick (empty for a table).
    pub per_run: Vec<KickErrors>,
}

/// [`Errors`] held out.
#[derive(Clone, Debug, Serialize)]
pub struct HeldOutErrors {
    pub eigen_rms: f64,
    pub eigen_weighted_rms: Option<f64>,
    pub roll_rms: Option<f64>,
    pub steer_rms: Option<f64>,
    pub speed_rms: Option<f64>,
}

/// One kick's errors.
#[derive(Clone, Debug, Serialize)]
pub struct KickErrors {
    /// Its run or log.
    pub run: String,
    /// Start of its window (s).
    pub window_start: f64,
    /// RMS roll (rad or rad/s), steer (rad), speed (m/s) residuals.
    pub roll_rms: f64,
    pub steer_rms: f64,
    pub speed_rms: f64,
    /// Roll RMS with its run held out.
    pub held_out_roll_rms: f64,
    /// Measured and predicted weave `[re (1/s), im (rad/s)]`.
    pub measured_weave: Option<[f64; 2]>,
    /// Whether the measured eigenvalue counts as a weave.
    pub weave_counted: bool,
    pub predicted_weave: Option<[f64; 2]>,
}

/// A kick kept out of the eigenvalue figures.
#[derive(Clone, Debug, Serialize)]
pub struct ExcludedKick {
    pub kick: usize,
    pub run: String,
    pub window_start: f64,
    /// The test it failed, with its numbers.
    pub rejected: bikedyn_runtime::experiment::accept::Rejected,
    /// Why, in words.
    pub reason: String,
}

impl From<&Excluded> for ExcludedKick {
    fn from(e: &Excluded) -> Self {
        ExcludedKick {
            kick: e.kick,
            run: e.run.clone(),
            window_start: e.window_start,
            rejected: e.rejected,
            reason: bikedyn_report::experiment::accept::rejected_text(&e.rejected),
        }
    }
}

/// A member of the final model tested against the model without it.
#[derive(Clone, Debug, Serialize)]
pub struct MemberCheck {
    pub name: String,
    /// The model it was tested in.
    pub model: Vec<String>,
    pub removed: bool,
    /// The criterion's change on removing it (`null`: not fitted).
    pub bic_change: Option<f64>,
    /// Held-out errors with and without it.
    pub cv_with: Option<f64>,
    pub cv_without: Option<f64>,
    pub outcome: Verdict,
    pub verdict: String,
    /// Kept because the model without it puts a correction beyond the
    /// plausible prior deviations: which (symbol, value, prior standard
    /// deviations from the measured value).
    pub without_implausible: Option<(String, f64, f64)>,
}

impl From<&bikedyn_runtime::identify::MemberCheck> for MemberCheck {
    fn from(c: &bikedyn_runtime::identify::MemberCheck) -> Self {
        let finite = |x: f64| Some(x).filter(|x| x.is_finite());
        MemberCheck {
            name: c.name.clone(),
            model: c.model.clone(),
            removed: c.removed,
            bic_change: finite(c.bic_change),
            cv_with: finite(c.cv_with),
            cv_without: finite(c.cv_without),
            outcome: c.verdict.clone(),
            verdict: match &c.without_implausible {
                Some((symbol, value, sds)) => super::words::kept_as_no_plausible_rival(symbol, *value, *sds),
                None => verdict_text(&c.verdict),
            },
            without_implausible: c.without_implausible.clone(),
        }
    }
}

/// A selected candidate and a rival the runs do not separate from it.
#[derive(Clone, Debug, Serialize)]
pub struct Confounded {
    pub step: usize,
    pub chosen: String,
    pub rival: String,
    /// Correlation of their estimates.
    pub correlation: f64,
    /// The rival's paired held-out gain over the chosen one, with its
    /// standard error.
    pub held_out_gain: Option<f64>,
    pub held_out_gain_stderr: Option<f64>,
    /// Neither predicts the held-out runs consistently better.
    pub predicts_alike: bool,
    /// Not separated by these runs (alike, or correlated at 0.9 or more).
    pub confounded: bool,
    /// Kicks that would separate them.
    pub designs: Vec<Design>,
}
