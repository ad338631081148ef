//! The `sweep` job: a bicycle's stability over one parameter (the weave and
//! capsize speeds and the self-stable speeds at each value, with their
//! standard deviations from the file's other `+/-` values) or a stability
//! map over two, every design through one model.
//!
//! The command line calls [`sweep`] and prints, writes or plots the typed
//! result; its JSON is the serialization of [`SweepReport`]. The command
//! line and Python choose the model of a sweep with [`sweep_model`].

use crate::bicycle::{Bicycle, BicycleError};
use crate::registry::ModelRegistry;
use crate::sensitivity::{speed_spread_over, SensitivityOptions, SweepSpread};
/// The quantity a stability map shows in each cell.
pub use bikedyn_runtime::sweep::MapQuantity;
use bikedyn_runtime::sweep::{
    parameter_sweep, stability_map, CellResult, CellStage, OnCellDone, ParamAxis, ParameterSweep, StabilityMap,
    SweepOptions as SpeedRange,
};
use serde::Serialize;

/// One swept parameter and its values.
#[derive(Clone, Debug, PartialEq)]
pub struct SweptParameter {
    /// The parameter's symbol (thesis: `Rt`, `x4`, ...; benchmark: `c`,
    /// `lam`, `w`, ...; or an effect parameter such as `c_steer`).
    pub symbol: String,
    /// Its values, in the parameter's unit (m, kg, rad, ...).
    pub values: Vec<f64>,
}

impl SweptParameter {
    /// `symbol` at `values`.
    pub fn new(symbol: impl Into<String>, values: Vec<f64>) -> Self {
        Self {
            symbol: symbol.into(),
            values,
        }
    }

    /// The value the model is chosen at: the first non-zero one (a sweep of
    /// `c_steer` from 0 runs wholly through the model with steer damping),
    /// or the first.
    fn representative(&self) -> Option<f64> {
        self.values
            .iter()
            .copied()
            .find(|&v| v != 0.0)
            .or(self.values.first().copied())
    }
}

/// What the `sweep` job computes. [`SweepOptions::new`] gives the
/// defaults of the fields other than the parameter.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOptions {
    /// The model (default: the model that represents the bicycle with the
    /// swept parameters at their first non-zero values, [`sweep_model`]).
    pub model: Option<String>,
    /// The swept parameter.
    pub parameter: SweptParameter,
    /// A second parameter, for a stability map (default: none).
    pub second: Option<SweptParameter>,
    /// Upper end of the speeds searched for the critical speeds (m/s;
    /// default 10, the range of Meijaard et al. 2007, Fig. 3); the lower
    /// end is 0.
    pub speed_max: f64,
    /// A speed (m/s) at which each design's least stable real part is
    /// given too (default: none).
    pub at_speed: Option<f64>,
    /// Whether a one-parameter sweep gives the critical speeds' standard
    /// deviations from the file's `+/-` values (default: yes; nothing is
    /// computed for a bicycle without them).
    pub standard_deviations: bool,
}

impl SweepOptions {
    /// A sweep of `symbol` over `values` with the other fields at their
    /// defaults.
    pub fn new(symbol: impl Into<String>, values: Vec<f64>) -> Self {
        Self {
            model: None,
            parameter: SweptParameter::new(symbol, values),
            second: None,
            speed_max: 10.0,
            at_speed: None,
            standard_deviations: true,
        }
    }
}

/// Why a design failed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CellFailure {
    /// What failed.
    pub message: String,
    /// Where: `model` (building or linearizing the design), `panic`, or
    /// `eigen` (the eigenvalues).
    pub stage: CellStage,
}

/// The stability of one design of a one-parameter sweep. Fields are in
/// alphabetical order, as `bikedyn sweep --format json` has always
/// written them; all but `value` and `error` are `null` for a failed
/// design.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepPoint {
    /// `v_c`, the capsize speed (m/s), if in range.
    pub capsize_speed: Option<f64>,
    /// Standard deviation of `v_c` (m/s), when asked and the file gives
    /// `+/-` values.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub capsize_speed_sd: Option<Option<f64>>,
    /// Why the design failed, if it did.
    pub error: Option<CellFailure>,
    /// Largest real part of the eigenvalues at the options' `at_speed`
    /// (1/s), when given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub least_stable_real_part: Option<f64>,
    /// Whether the last stable interval reaches the top of the speed range.
    pub open_ended: Option<bool>,
    /// Maximal self-stable speed intervals `[lo, hi]` (m/s).
    pub stable_intervals: Option<Vec<[f64; 2]>>,
    /// Total length of the stable intervals (m/s).
    pub stable_width: Option<f64>,
    /// The parameter's value.
    pub value: f64,
    /// `v_d`, where the real weave roots merge into the weave pair (m/s).
    pub weave_real_pair_merge: Option<f64>,
    /// `v_w`, the weave speed (m/s), if in range.
    pub weave_speed: Option<f64>,
    /// Standard deviation of `v_w` (m/s), likewise.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weave_speed_sd: Option<Option<f64>>,
}

/// The stability of one design of a stability map, at `(x.values[i],
/// y.values[j])`; fields as [`SweepPoint`]'s, in alphabetical order.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MapCell {
    /// `v_c` (m/s).
    pub capsize_speed: Option<f64>,
    /// Why the design failed, if it did.
    pub error: Option<CellFailure>,
    /// Index of the first parameter's value.
    pub i: usize,
    /// Index of the second parameter's value.
    pub j: usize,
    /// Largest real part at `at_speed` (1/s), when given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub least_stable_real_part: Option<f64>,
    /// Whether the last stable interval reaches the top of the speed range.
    pub open_ended: Option<bool>,
    /// Self-stable speed intervals (m/s).
    pub stable_intervals: Option<Vec<[f64; 2]>>,
    /// Their total length (m/s).
    pub stable_width: Option<f64>,
    /// `v_d` (m/s).
    pub weave_real_pair_merge: Option<f64>,
    /// `v_w` (m/s).
    pub weave_speed: Option<f64>,
    /// The first parameter's value.
    pub x: f64,
    /// The second parameter's value.
    pub y: f64,
}

/// The fields a design's result gives, failed or not.
struct Fields {
    capsize_speed: Option<f64>,
    error: Option<CellFailure>,
    least_stable_real_part: Option<f64>,
    open_ended: Option<bool>,
    stable_intervals: Option<Vec<[f64; 2]>>,
    stable_width: Option<f64>,
    weave_real_pair_merge: Option<f64>,
    weave_speed: Option<f64>,
}

impl Fields {
    fn of(c: &CellResult) -> Self {
        match c {
            Ok(s) => Fields {
                capsize_speed: s.capsize_speed,
                error: None,
                least_stable_real_part: s.least_stable_real_part,
                open_ended: Some(s.open_ended),
                stable_intervals: Some(s.stable_intervals.clone()),
                stable_width: Some(s.stable_width),
                weave_real_pair_merge: s.weave_real_pair_merge,
                weave_speed: s.weave_speed,
            },
            Err(e) => Fields {
                capsize_speed: None,
                error: Some(CellFailure {
                    message: e.message.clone(),
                    stage: e.stage,
                }),
                least_stable_real_part: None,
                open_ended: None,
                stable_intervals: None,
                stable_width: None,
                weave_real_pair_merge: None,
                weave_speed: None,
            },
        }
    }
}

/// A one-parameter sweep's result.
#[derive(Clone, Debug, Serialize)]
pub struct ParameterSweepReport {
    /// The generated model every design went through (not serialized: the
    /// command line names it on standard error).
    #[serde(skip)]
    pub model: String,
    /// The parameter's symbol.
    pub parameter: String,
    /// One entry per value, in the order given.
    pub points: Vec<SweepPoint>,
    /// The speeds searched, `[0, speed_max]` (m/s).
    pub speed_range: [f64; 2],
    /// The critical speeds' standard deviations at each value, when given.
    #[serde(skip)]
    pub standard_deviations: Option<SweepSpread>,
    /// Whether they were asked for a file with `+/-` values and could not
    /// be given: setting the parameter converts the file to another form.
    #[serde(skip)]
    pub standard_deviations_missing: bool,
    /// The sweep as computed, for tables, CSV and figures.
    #[serde(skip)]
    pub sweep: ParameterSweep,
}

/// How a map's cells are laid out, as its JSON says.
pub const MAP_LAYOUT: &str = "row-major: cells[i * len(y.values) + j] is (x.values[i], y.values[j])";

/// A stability map's result.
#[derive(Clone, Debug, Serialize)]
pub struct StabilityMapReport {
    /// The generated model every design went through (not serialized).
    #[serde(skip)]
    pub model: String,
    /// One entry per design, row-major.
    pub cells: Vec<MapCell>,
    /// [`MAP_LAYOUT`].
    pub layout: &'static str,
    /// The speeds searched, `[0, speed_max]` (m/s).
    pub speed_range: [f64; 2],
    /// The first parameter: `name` (symbol) and `values`.
    pub x: ParamAxis,
    /// The second parameter.
    pub y: ParamAxis,
    /// The map as computed, for tables, CSV and figures.
    #[serde(skip)]
    pub map: StabilityMap,
}

/// The result of the `sweep` job.
#[derive(Clone, Debug, Serialize)]
#[serde(untagged)]
pub enum SweepReport {
    /// Over one parameter.
    Parameter(ParameterSweepReport),
    /// Over two.
    Map(StabilityMapReport),
}

/// A design that failed: the parameters' values and why.
#[derive(Clone, Debug, PartialEq)]
pub struct FailedDesign {
    /// `(symbol, value)` of each swept parameter.
    pub at: Vec<(String, f64)>,
    /// Why.
    pub message: String,
}

/// At most this many failed designs are listed in the error.
const FAILURES_SHOWN: usize = 10;

fn failed_text(failed: &[FailedDesign]) -> String {
    let mut s = String::new();
    for (k, f) in failed.iter().take(FAILURES_SHOWN).enumerate() {
        let at: Vec<String> = f.at.iter().map(|(p, v)| format!("{p} = {v}")).collect();
        if k > 0 {
            s.push('\n');
        }
        s += &format!("  {}: {}", at.join(", "), f.message);
    }
    if failed.len() > FAILURES_SHOWN {
        s += &format!("\n  ... and {} more", failed.len() - FAILURES_SHOWN);
    }
    s
}

/// Errors of the job.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// The bicycle, a parameter or the model.
    #[error(transparent)]
    Bicycle(#[from] BicycleError),
    /// The sweep as a whole.
    #[error(transparent)]
    Sweep(#[from] bikedyn_runtime::sweep::SweepError),
    /// `parameter` or `second` has no values.
    #[error("{0}: no values given")]
    NoValues(&'static str),
    /// `parameter` and `second` name the same parameter.
    #[error("parameter and second both name `{0}`: a map needs two different parameters")]
    SameParameter(String),
    /// `speed_max` is not a positive finite speed.
    #[error("speed_max {0}: the upper end of the searched speeds must be a positive finite speed (m/s)")]
    SpeedMax(f64),
    /// `at_speed` is not a finite speed.
    #[error("at_speed must be a finite speed, found {0:?}")]
    AtSpeed(f64),
    /// Designs failed: a sweep with failed designs is an error listing
    /// them (at most ten), never a table with messages in it.
    #[error("{} of the sweep's designs failed, no table written:\n{}", .0.len(), failed_text(.0))]
    FailedDesigns(Vec<FailedDesign>),
}

fn check(opts: &SweepOptions) -> Result<(), SweepError> {
    if opts.parameter.values.is_empty() {
        return Err(SweepError::NoValues("parameter"));
    }
    if let Some(p2) = &opts.second {
        if p2.symbol.trim() == opts.parameter.symbol.trim() {
            // The second value would overwrite the first in every design.
            return Err(SweepError::SameParameter(p2.symbol.clone()));
        }
        if p2.values.is_empty() {
            return Err(SweepError::NoValues("second"));
        }
    }
    if !(opts.speed_max.is_finite() && opts.speed_max > 0.0) {
        return Err(SweepError::SpeedMax(opts.speed_max));
    }
    if let Some(v) = opts.at_speed.filter(|v| !v.is_finite()) {
        return Err(SweepError::AtSpeed(v));
    }
    Ok(())
}

/// `bike` with the swept parameters at `x` and `y`.
fn design<R: ModelRegistry>(
    bike: &Bicycle<R>,
    opts: &SweepOptions,
    x: f64,
    y: Option<f64>,
) -> Result<Bicycle<R>, BicycleError> {
    let b = bike.with_parameter(&opts.parameter.symbol, x)?;
    match (&opts.second, y) {
        (Some(p2), Some(y)) => b.with_parameter(&p2.symbol, y),
        _ => Ok(b),
    }
}

/// The model of a sweep: the options' model, or the one that represents
/// `bike` with the swept parameters at their first non-zero values (a
/// sweep of `c_steer` from 0 runs wholly through the model with steer
/// damping). Every design of the sweep goes through it.
pub fn sweep_model<R: ModelRegistry>(bike: &Bicycle<R>, opts: &SweepOptions) -> Result<String, SweepError> {
    if let Some(m) = &opts.model {
        return Ok(m.clone());
    }
    let x = opts
        .parameter
        .representative()
        .ok_or(SweepError::NoValues("parameter"))?;
    let y = match &opts.second {
        Some(p2) => Some(p2.representative().ok_or(SweepError::NoValues("second"))?),
        None => None,
    };
    Ok(design(bike, opts, x, y)?.model(None)?.name.to_string())
}

/// The `sweep` job: the stability of `bike` at every value of the swept
/// parameter (or every pair of values of the two), each design through
/// the one model [`sweep_model`] chooses. `on_cell_done` hears of each
/// finished design (`bikedyn::runtime::sweep::no_progress` to ignore it).
pub fn sweep<R: ModelRegistry>(
    bike: &Bicycle<R>,
    opts: &SweepOptions,
    on_cell_done: OnCellDone<'_>,
) -> Result<SweepReport, SweepError>
where
    Bicycle<R>: Sync,
{
    check(opts)?;
    // An unknown parameter fails here, once, rather than in every design.
    design(
        bike,
        opts,
        opts.parameter.values[0],
        opts.second.as_ref().map(|p| p.values[0]),
    )?;
    compute(bike, opts, on_cell_done)
}

/// Row `i` of the stability map of `opts` (which has a second parameter):
/// the designs at the first parameter's value `i` and each of the
/// second's, for a map given a row at a time. Its cells' `i` are 0.
pub fn stability_map_row<R: ModelRegistry>(
    bike: &Bicycle<R>,
    opts: &SweepOptions,
    i: usize,
    on_cell_done: OnCellDone<'_>,
) -> Result<StabilityMapReport, SweepError>
where
    Bicycle<R>: Sync,
{
    check(opts)?;
    let x = *opts.parameter.values.get(i).ok_or(SweepError::NoValues("parameter"))?;
    if opts.second.is_none() {
        return Err(SweepError::NoValues("second"));
    }
    let row = SweepOptions {
        parameter: SweptParameter::new(opts.parameter.symbol.clone(), vec![x]),
        ..opts.clone()
    };
    match compute(bike, &row, on_cell_done)? {
        SweepReport::Map(m) => Ok(m),
        SweepReport::Parameter(_) => unreachable!("a sweep with a second parameter is a map"),
    }
}

fn compute<R: ModelRegistry>(
    bike: &Bicycle<R>,
    opts: &SweepOptions,
    on_cell_done: OnCellDone<'_>,
) -> Result<SweepReport, SweepError>
where
    Bicycle<R>: Sync,
{
    let model = sweep_model(bike, opts)?;
    let range = SpeedRange {
        probe_speed: opts.at_speed,
        ..SpeedRange::with_speed_range(0.0, opts.speed_max)
    };
    let p1 = &opts.parameter;
    let linear = |x: f64, y: Option<f64>| design(bike, opts, x, y).and_then(|b| b.linear_with(Some(&model)));
    match &opts.second {
        Some(p2) => {
            // The designs of one value of the first parameter (a row of the
            // map, the browser's request) share the bicycle with that value
            // set: made once per value, not once per design; where it
            // cannot be made, each design fails as `design` fails.
            let firsts: Vec<Option<Bicycle<R>>> = p1
                .values
                .iter()
                .map(|&x| bike.with_parameter(&p1.symbol, x).ok())
                .collect();
            let map = stability_map(
                ParamAxis::new(p1.symbol.clone(), p1.values.clone()),
                ParamAxis::new(p2.symbol.clone(), p2.values.clone()),
                |x, y| {
                    let first = p1
                        .values
                        .iter()
                        .position(|v| v.to_bits() == x.to_bits())
                        .and_then(|i| firsts[i].as_ref());
                    match first {
                        Some(b) => b
                            .with_parameter(&p2.symbol, y)
                            .and_then(|b| b.linear_with(Some(&model))),
                        None => linear(x, Some(y)),
                    }
                },
                &range,
                on_cell_done,
            )?;
            let ny = map.y.values.len();
            refuse_failures(map.cells.iter().enumerate().map(|(k, c)| {
                let at = vec![
                    (p1.symbol.clone(), map.x.values[k / ny]),
                    (p2.symbol.clone(), map.y.values[k % ny]),
                ];
                (at, c)
            }))?;
            let cells = map
                .cells
                .iter()
                .enumerate()
                .map(|(k, c)| {
                    let (i, j) = (k / ny, k % ny);
                    let f = Fields::of(c);
                    MapCell {
                        capsize_speed: f.capsize_speed,
                        error: f.error,
                        i,
                        j,
                        least_stable_real_part: f.least_stable_real_part,
                        open_ended: f.open_ended,
                        stable_intervals: f.stable_intervals,
                        stable_width: f.stable_width,
                        weave_real_pair_merge: f.weave_real_pair_merge,
                        weave_speed: f.weave_speed,
                        x: map.x.values[i],
                        y: map.y.values[j],
                    }
                })
                .collect();
            Ok(SweepReport::Map(StabilityMapReport {
                model,
                cells,
                layout: MAP_LAYOUT,
                speed_range: map.speed_range,
                x: map.x.clone(),
                y: map.y.clone(),
                map,
            }))
        }
        None => {
            let s = parameter_sweep(
                ParamAxis::new(p1.symbol.clone(), p1.values.clone()),
                |x| linear(x, None),
                &range,
                on_cell_done,
            )?;
            refuse_failures(
                s.points
                    .iter()
                    .zip(&s.param.values)
                    .map(|(c, &x)| (vec![(p1.symbol.clone(), x)], c)),
            )?;
            // The critical speeds' standard deviations at each value from
            // the file's other +/- values (the swept parameter is set, so
            // its own is left out).
            let (spread, missing) = if opts.standard_deviations && !bike.uncertainties.is_empty() {
                let options = SensitivityOptions {
                    model: Some(model.clone()),
                    speed_max: opts.speed_max,
                    ..SensitivityOptions::default()
                };
                let u = speed_spread_over(bike, &p1.symbol, &s.param.values, &options);
                let missing = u.is_none();
                (u, missing)
            } else {
                (None, false)
            };
            let points = s
                .points
                .iter()
                .zip(&s.param.values)
                .enumerate()
                .map(|(k, (c, &value))| {
                    let f = Fields::of(c);
                    let sd = |v: &Vec<Option<f64>>| v.get(k).copied().flatten();
                    SweepPoint {
                        capsize_speed: f.capsize_speed,
                        capsize_speed_sd: spread.as_ref().map(|u| sd(&u.capsize_speed)),
                        error: f.error,
                        least_stable_real_part: f.least_stable_real_part,
                        open_ended: f.open_ended,
                        stable_intervals: f.stable_intervals,
                        stable_width: f.stable_width,
                        value,
                        weave_real_pair_merge: f.weave_real_pair_merge,
                        weave_speed: f.weave_speed,
                        weave_speed_sd: spread.as_ref().map(|u| sd(&u.weave_speed)),
                    }
                })
                .collect();
            Ok(SweepReport::Parameter(ParameterSweepReport {
                model,
                parameter: s.param.name.clone(),
                points,
                speed_range: s.speed_range,
                standard_deviations: spread,
                standard_deviations_missing: missing,
                sweep: s,
            }))
        }
    }
}

fn refuse_failures<'a>(cells: impl Iterator<Item = (Vec<(String, f64)>, &'a CellResult)>) -> Result<(), SweepError> {
    let failed: Vec<FailedDesign> = cells
        .filter_map(|(at, c)| {
            c.as_ref().err().map(|e| FailedDesign {
                at,
                message: e.message.clone(),
            })
        })
        .collect();
    if failed.is_empty() {
        Ok(())
    } else {
        Err(SweepError::FailedDesigns(failed))
    }
}

/// Each design's stability at given speeds: the least stable real part at
/// each speed, and the weave and capsize speeds between the lowest and
/// the highest (NaN where there is none, or for one speed).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SweepAtSpeeds {
    /// The generated model every design went through.
    pub model: String,
    /// Number of designs: the first parameter's values times the second's
    /// (row-major, the first parameter outer).
    pub designs: usize,
    /// Largest real part of the eigenvalues (1/s), design by design, speed
    /// by speed (`designs` x speeds), extra states' included.
    pub least_stable_real_part: Vec<f64>,
    /// `v_w` of each design (m/s; NaN: none in the range).
    pub weave_speed: Vec<f64>,
    /// `v_c` of each design (m/s; NaN: none in the range).
    pub capsize_speed: Vec<f64>,
}

/// Errors of [`sweep_at_speeds`].
#[derive(Debug, thiserror::Error)]
pub enum SweepAtSpeedsError {
    /// The options, or the model choice.
    #[error(transparent)]
    Sweep(#[from] SweepError),
    /// `speeds` is empty or holds a speed that is not finite.
    #[error("speeds: {0} is not a finite speed (m/s)")]
    Speed(f64),
    /// A design could not be built or linearized.
    #[error("at {}: {source}", at_text(.at))]
    Design {
        /// `(symbol, value)` of each swept parameter.
        at: Vec<(String, f64)>,
        /// Why (boxed: the error stays small on the way up).
        source: Box<BicycleError>,
    },
    /// A design's eigenvalues.
    #[error("at {}: {source}", at_text(.at))]
    Eigen {
        /// `(symbol, value)` of each swept parameter.
        at: Vec<(String, f64)>,
        /// Why.
        source: bikedyn_runtime::eigen::EigenError,
    },
}

fn at_text(at: &[(String, f64)]) -> String {
    at.iter()
        .map(|(p, v)| format!("{p} = {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Each design's least stable real part at `speeds` (m/s) and its weave
/// and capsize speeds between the lowest and the highest of them (from 0
/// at the lowest), the designs in parallel, each through the one model
/// [`sweep_model`] chooses. `speed_max`, `at_speed` and
/// `standard_deviations` of `opts` are not used: `speeds` gives the
/// speeds.
pub fn sweep_at_speeds<R: ModelRegistry>(
    bike: &Bicycle<R>,
    opts: &SweepOptions,
    speeds: &[f64],
) -> Result<SweepAtSpeeds, SweepAtSpeedsError>
where
    Bicycle<R>: Sync,
{
    use bikedyn_runtime::eigen::{critical_speeds_of, eigen_sweep_of, eigenvalues_of, LinearBicycle};
    use rayon::prelude::*;
    check(&SweepOptions {
        speed_max: 1.0,
        at_speed: None,
        ..opts.clone()
    })?;
    match speeds.iter().find(|v| !v.is_finite()) {
        Some(&v) => return Err(SweepAtSpeedsError::Speed(v)),
        None if speeds.is_empty() => return Err(SweepAtSpeedsError::Speed(f64::NAN)),
        None => {}
    }
    let model = sweep_model(bike, opts)?;
    let (v_min, v_max) = speeds
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
    let ys: Vec<Option<f64>> = match &opts.second {
        Some(p2) => p2.values.iter().copied().map(Some).collect(),
        None => vec![None],
    };
    let cells: Vec<(f64, Option<f64>)> = opts
        .parameter
        .values
        .iter()
        .flat_map(|&x| ys.iter().map(move |&y| (x, y)))
        .collect();
    // Each design's least stable real parts, v_w and v_c.
    type Design = (Vec<f64>, f64, f64);
    let results: Vec<Result<Design, SweepAtSpeedsError>> = cells
        .par_iter()
        .map(|&(x, y)| {
            let at = || {
                let mut at = vec![(opts.parameter.symbol.clone(), x)];
                if let (Some(p2), Some(y)) = (&opts.second, y) {
                    at.push((p2.symbol.clone(), y));
                }
                at
            };
            let lin = design(bike, opts, x, y)
                .and_then(|b| b.linear_with(Some(&model)))
                .map_err(|e| SweepAtSpeedsError::Design {
                    at: at(),
                    source: Box::new(e),
                })?;
            let eig = |source| SweepAtSpeedsError::Eigen { at: at(), source };
            let mut least = Vec::with_capacity(speeds.len());
            if lin.first_order().is_some() {
                // Extra states: the sweep's spectrum, which includes them.
                let s = eigen_sweep_of(&lin, speeds).map_err(eig)?;
                for p in &s.points {
                    let m = p
                        .eigenvalues
                        .iter()
                        .chain(&p.extra_eigenvalues)
                        .map(|z| z.re)
                        .fold(f64::NEG_INFINITY, f64::max);
                    least.push(m);
                }
            } else {
                for &v in speeds {
                    let z = eigenvalues_of(&lin, v).map_err(eig)?;
                    least.push(z.iter().map(|z| z.re).fold(f64::NEG_INFINITY, f64::max));
                }
            }
            let (weave, capsize) = if v_max > v_min {
                let c = critical_speeds_of(&lin, v_min.max(0.0), v_max).map_err(eig)?;
                (c.weave_speed.unwrap_or(f64::NAN), c.capsize_speed.unwrap_or(f64::NAN))
            } else {
                (f64::NAN, f64::NAN)
            };
            Ok((least, weave, capsize))
        })
        .collect();
    let mut out = SweepAtSpeeds {
        model,
        designs: cells.len(),
        least_stable_real_part: Vec::with_capacity(cells.len() * speeds.len()),
        weave_speed: Vec::with_capacity(cells.len()),
        capsize_speed: Vec::with_capacity(cells.len()),
    };
    for r in results {
        let (l, w, c) = r?;
        out.least_stable_real_part.extend(l);
        out.weave_speed.push(w);
        out.capsize_speed.push(c);
    }
    Ok(out)
}
