//! Parallel sweeps of the canonical linear bicycle: over forward speed, over one
//! design parameter, and over a two-parameter grid (a [`StabilityMap`]).
//!
//! * [`speed_sweep`] wraps [`eigen_sweep`] (mode labels are tracked
//!   continuously along the speed list, so it runs serially).
//! * [`parameter_sweep`] and [`stability_map`] evaluate, per parameter value or
//!   grid cell, a caller-supplied mapping `parameter(s) -> CanonicalMatrices`
//!   (this is where a generated model is linearized) and then
//!   [`critical_speeds`] over `[speed_min, speed_max]`. Cells run in parallel
//!   with rayon; results are returned in input order, independent of the
//!   number of threads. A failing cell (mapping error, eigen error or a panic
//!   in the mapping) is recorded as a [`CellError`] in that cell; it never
//!   aborts the sweep and never produces NaN.
//!
//! Progress goes through a plain callback ([`OnCellDone`]: cells done, cells
//! in all), called from the worker threads after each cell; the runtime never
//! draws on a terminal (the command line turns the callback into a bar).

use std::fmt::Display;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};

use rayon::prelude::*;
use serde::Serialize;

use crate::canonical::CanonicalMatrices;
use crate::eigen::{critical_speeds_of, eigen_sweep, CriticalSpeeds, EigenError, EigenSweep, LinearBicycle};

/// Options shared by the parameter sweeps.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepOptions {
    /// Lower end of the forward-speed range searched for critical speeds (m/s).
    /// Default `0.0`.
    pub speed_min: f64,
    /// Upper end of the forward-speed range (m/s). Default `10.0` (the range of
    /// Meijaard et al. 2007, Fig. 3).
    pub speed_max: f64,
    /// Speed (m/s) at which every cell also records the real part of its
    /// least stable eigenvalue ([`StabilitySummary::least_stable_real_part`],
    /// [`MapQuantity::LeastStableRealPart`]). Default `None`.
    pub probe_speed: Option<f64>,
}

impl Default for SweepOptions {
    fn default() -> Self {
        Self {
            speed_min: 0.0,
            speed_max: 10.0,
            probe_speed: None,
        }
    }
}

impl SweepOptions {
    /// Options with the speed range `[speed_min, speed_max]` and other fields default.
    pub fn with_speed_range(speed_min: f64, speed_max: f64) -> Self {
        Self {
            speed_min,
            speed_max,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<(), SweepError> {
        if !(self.speed_min.is_finite() && self.speed_max.is_finite()) || self.speed_min >= self.speed_max {
            return Err(SweepError::InvalidSpeedRange {
                speed_min: self.speed_min,
                speed_max: self.speed_max,
            });
        }
        Ok(())
    }
}

/// Errors that reject a whole sweep (per-cell failures are [`CellError`]s).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SweepError {
    /// `speed_min`/`speed_max` not finite or not increasing.
    #[error("invalid speed range [{speed_min}, {speed_max}] (need finite speed_min < speed_max)")]
    InvalidSpeedRange {
        /// Requested lower end.
        speed_min: f64,
        /// Requested upper end.
        speed_max: f64,
    },
    /// The speed sweep itself failed.
    #[error(transparent)]
    Eigen(#[from] EigenError),
}

/// Where a cell failed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CellStage {
    /// The caller's mapping `parameter -> CanonicalMatrices` returned an error.
    Model,
    /// The caller's mapping panicked (the panic was caught).
    Panic,
    /// [`critical_speeds`] failed.
    Eigen,
}

/// Recorded failure of one parameter value or grid cell.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{} failed: {message}", match stage { CellStage::Model => "model mapping", CellStage::Panic => "model mapping (panic)", CellStage::Eigen => "eigen analysis" })]
pub struct CellError {
    /// Which step failed.
    pub stage: CellStage,
    /// The error's message.
    pub message: String,
}

/// Self-stability summary of one bicycle over `[speed_min, speed_max]`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StabilitySummary {
    /// `v_w`, weave (Hopf) speed, if in range (m/s).
    pub weave_speed: Option<f64>,
    /// `v_c`, capsize speed, if in range (m/s).
    pub capsize_speed: Option<f64>,
    /// `v_d`, speed where the real weave roots merge into a complex pair (m/s).
    pub weave_real_pair_merge: Option<f64>,
    /// Maximal self-stable intervals `[lo, hi]` within the speed range (m/s).
    pub stable_intervals: Vec<[f64; 2]>,
    /// Total length of the stable intervals (m/s); `0` if never stable.
    /// A lower bound of the true width when [`Self::open_ended`] is set.
    pub stable_width: f64,
    /// The last stable interval reaches `speed_max` (stable at the end of the range).
    pub open_ended: bool,
    /// Largest real part of the eigenvalues at [`SweepOptions::probe_speed`]
    /// (1/s), when a probe speed was given.
    pub least_stable_real_part: Option<f64>,
}

impl StabilitySummary {
    /// Summary of critical speeds computed over `[speed_min, speed_max]`.
    pub fn from_critical(c: &CriticalSpeeds, speed_max: f64) -> Self {
        let stable_width = c
            .stable_intervals
            .iter()
            .map(|[lo, hi]| (hi - lo).max(0.0))
            .filter(|w| w.is_finite())
            .fold(0.0, |a, w| a + w); // not `sum()`: that gives -0.0 when empty
        let open_ended = c
            .stable_intervals
            .last()
            .is_some_and(|[_, hi]| (speed_max - hi).abs() <= 1e-9 * speed_max.abs().max(1.0));
        Self {
            weave_speed: c.weave_speed,
            capsize_speed: c.capsize_speed,
            weave_real_pair_merge: c.weave_real_pair_merge,
            stable_intervals: c.stable_intervals.clone(),
            stable_width,
            open_ended,
            least_stable_real_part: None,
        }
    }

    /// First (lowest-speed) stable interval.
    pub fn first_stable_interval(&self) -> Option<[f64; 2]> {
        self.stable_intervals.first().copied()
    }
}

/// A named parameter axis (`name` is used as CSV column header and default plot label).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParamAxis {
    /// Name, e.g. `"trail c (m)"`.
    pub name: String,
    /// Values, in the order results are reported.
    pub values: Vec<f64>,
}

impl ParamAxis {
    /// New axis.
    pub fn new(name: impl Into<String>, values: Vec<f64>) -> Self {
        Self {
            name: name.into(),
            values,
        }
    }
}

/// Result at one parameter value or grid cell.
pub type CellResult = Result<StabilitySummary, CellError>;

/// Result of a one-parameter sweep; `points[k]` belongs to `param.values[k]`.
#[derive(Clone, Debug, PartialEq)]
pub struct ParameterSweep {
    /// The swept parameter.
    pub param: ParamAxis,
    /// Speed range searched, `[speed_min, speed_max]` (m/s).
    pub speed_range: [f64; 2],
    /// One result per parameter value, in input order.
    pub points: Vec<CellResult>,
}

/// Result of a two-parameter grid. Row-major: `cells[i * y.values.len() + j]`
/// belongs to `(x.values[i], y.values[j])`.
#[derive(Clone, Debug, PartialEq)]
pub struct StabilityMap {
    /// First parameter (horizontal plot axis).
    pub x: ParamAxis,
    /// Second parameter (vertical plot axis).
    pub y: ParamAxis,
    /// Speed range searched, `[speed_min, speed_max]` (m/s).
    pub speed_range: [f64; 2],
    /// Row-major cells.
    pub cells: Vec<CellResult>,
}

impl StabilityMap {
    /// Grid shape `(nx, ny)`.
    pub fn shape(&self) -> (usize, usize) {
        (self.x.values.len(), self.y.values.len())
    }

    /// Cell at `(x.values[i], y.values[j])`.
    pub fn cell(&self, i: usize, j: usize) -> Option<&CellResult> {
        let (nx, ny) = self.shape();
        if i < nx && j < ny {
            self.cells.get(i * ny + j)
        } else {
            None
        }
    }

    /// Number of failed cells.
    pub fn failures(&self) -> usize {
        self.cells.iter().filter(|c| c.is_err()).count()
    }
}

/// Quantity of a [`StabilitySummary`] shown in tables and maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum MapQuantity {
    /// Width of the self-stable speed range (m/s); `None` when never stable.
    #[default]
    StableWidth,
    /// Weave speed `v_w` (m/s).
    WeaveSpeed,
    /// Capsize speed `v_c` (m/s).
    CapsizeSpeed,
    /// Real part of the least stable eigenvalue at
    /// [`SweepOptions::probe_speed`] (1/s; negative means stable there).
    LeastStableRealPart,
}

impl MapQuantity {
    /// Value for a cell; `None` for failed cells and when the quantity does not exist.
    pub fn value(&self, cell: &CellResult) -> Option<f64> {
        let s = cell.as_ref().ok()?;
        match self {
            MapQuantity::StableWidth => (s.stable_width > 0.0).then_some(s.stable_width),
            MapQuantity::WeaveSpeed => s.weave_speed,
            MapQuantity::CapsizeSpeed => s.capsize_speed,
            MapQuantity::LeastStableRealPart => s.least_stable_real_part,
        }
    }

    /// Axis/colour-bar label with unit.
    pub fn label(&self) -> &'static str {
        match self {
            MapQuantity::StableWidth => "self-stable speed range width (m/s)",
            MapQuantity::WeaveSpeed => "weave speed (m/s)",
            MapQuantity::CapsizeSpeed => "capsize speed (m/s)",
            MapQuantity::LeastStableRealPart => "real part of the least stable eigenvalue (1/s)",
        }
    }
}

/// `n` evenly spaced values from `start` to `end` inclusive (`n = 1` gives `[start]`).
pub fn linspace(start: f64, end: f64, n: usize) -> Vec<f64> {
    match n {
        0 => Vec::new(),
        1 => vec![start],
        _ => (0..n)
            .map(|k| {
                if k + 1 == n {
                    end
                } else {
                    start + (end - start) * (k as f64) / ((n - 1) as f64)
                }
            })
            .collect(),
    }
}

/// Eigenvalues and mode labels at each speed (serial; wraps [`eigen_sweep`]).
pub fn speed_sweep(c: &CanonicalMatrices, speeds: &[f64]) -> Result<EigenSweep, EigenError> {
    eigen_sweep(c, speeds)
}

/// Progress of a sweep: `(cells done, cells in all)`, called once after each
/// cell from whichever worker thread finished it. Calls from different
/// threads may arrive out of order, so a display counts the calls (or keeps
/// the largest `done`); exactly one call has `done == total`.
pub type OnCellDone<'a> = &'a (dyn Fn(usize, usize) + Sync);

/// A progress callback that ignores every report.
pub fn no_progress(_done: usize, _total: usize) {}

/// Counts finished cells and reports each to the callback.
struct CellCounter<'a> {
    done: AtomicUsize,
    total: usize,
    on_cell_done: OnCellDone<'a>,
}

impl<'a> CellCounter<'a> {
    fn new(total: usize, on_cell_done: OnCellDone<'a>) -> Self {
        Self {
            done: AtomicUsize::new(0),
            total,
            on_cell_done,
        }
    }

    fn cell_done(&self) {
        let done = self.done.fetch_add(1, Ordering::Relaxed) + 1;
        (self.on_cell_done)(done, self.total);
    }
}

/// Critical speeds of the bicycle returned by `map(value)`, for each value, in parallel.
///
/// `map` is where the caller linearizes its model at the parameter value. Its
/// errors (and panics) are recorded per value, as are eigen-analysis errors.
/// Fails as a whole only for an invalid speed range. `on_cell_done` hears of
/// each finished value ([`no_progress`] to ignore it).
pub fn parameter_sweep<F, L, E>(
    param: ParamAxis,
    map: F,
    opts: &SweepOptions,
    on_cell_done: OnCellDone<'_>,
) -> Result<ParameterSweep, SweepError>
where
    F: Fn(f64) -> Result<L, E> + Sync,
    L: LinearBicycle,
    E: Display,
{
    opts.validate()?;
    let counter = CellCounter::new(param.values.len(), on_cell_done);
    let points = param
        .values
        .par_iter()
        .map(|&p| {
            let r = evaluate_cell(|| map(p), opts);
            counter.cell_done();
            r
        })
        .collect();
    Ok(ParameterSweep {
        param,
        speed_range: [opts.speed_min, opts.speed_max],
        points,
    })
}

/// Critical speeds over the grid `x.values x y.values` (row-major, `x` outer), in parallel.
///
/// Same error policy and progress as [`parameter_sweep`].
pub fn stability_map<F, L, E>(
    x: ParamAxis,
    y: ParamAxis,
    map: F,
    opts: &SweepOptions,
    on_cell_done: OnCellDone<'_>,
) -> Result<StabilityMap, SweepError>
where
    F: Fn(f64, f64) -> Result<L, E> + Sync,
    L: LinearBicycle,
    E: Display,
{
    opts.validate()?;
    let (nx, ny) = (x.values.len(), y.values.len());
    let counter = CellCounter::new(nx * ny, on_cell_done);
    let cells = (0..nx * ny)
        .into_par_iter()
        .map(|k| {
            let (px, py) = (x.values[k / ny], y.values[k % ny]);
            let r = evaluate_cell(|| map(px, py), opts);
            counter.cell_done();
            r
        })
        .collect();
    Ok(StabilityMap {
        x,
        y,
        speed_range: [opts.speed_min, opts.speed_max],
        cells,
    })
}

fn evaluate_cell<L: LinearBicycle, E: Display>(map: impl FnOnce() -> Result<L, E>, opts: &SweepOptions) -> CellResult {
    let c = match catch_unwind(AssertUnwindSafe(map)) {
        Ok(Ok(c)) => c,
        Ok(Err(e)) => {
            return Err(CellError {
                stage: CellStage::Model,
                message: e.to_string(),
            })
        }
        Err(payload) => {
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".to_string());
            return Err(CellError {
                stage: CellStage::Panic,
                message,
            });
        }
    };
    let eigen_error = |e: EigenError| CellError {
        stage: CellStage::Eigen,
        message: e.to_string(),
    };
    let mut summary = critical_speeds_of(&c, opts.speed_min, opts.speed_max)
        .map(|cs| StabilitySummary::from_critical(&cs, opts.speed_max))
        .map_err(eigen_error)?;
    if let Some(v) = opts.probe_speed {
        let z = crate::eigen::eigenvalues_of(&c, v).map_err(eigen_error)?;
        summary.least_stable_real_part = Some(z.iter().map(|s| s.re).fold(f64::NEG_INFINITY, f64::max));
    }
    Ok(summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sweep_linspace_endpoints_exact() {
        assert!(linspace(0.0, 1.0, 0).is_empty());
        assert_eq!(linspace(2.0, 3.0, 1), vec![2.0]);
        let v = linspace(0.0, 10.0, 101);
        assert_eq!(v.len(), 101);
        assert_eq!(v[0], 0.0);
        assert_eq!(v[100], 10.0);
        assert!((v[43] - 4.3).abs() < 1e-12);
    }

    #[test]
    fn sweep_summary_width_and_open_end() {
        let c = CriticalSpeeds {
            weave_speed: Some(4.0),
            capsize_speed: Some(6.0),
            stable_intervals: vec![[4.0, 6.0], [8.0, 10.0]],
            ..CriticalSpeeds::default()
        };
        let s = StabilitySummary::from_critical(&c, 10.0);
        assert_eq!(s.stable_width, 4.0);
        assert!(s.open_ended);
        assert_eq!(s.first_stable_interval(), Some([4.0, 6.0]));
        let s = StabilitySummary::from_critical(&CriticalSpeeds::default(), 10.0);
        assert_eq!((s.stable_width, s.open_ended), (0.0, false));
        assert!(s.stable_width.is_sign_positive(), "no -0.0 in outputs");
        assert_eq!(MapQuantity::StableWidth.value(&Ok(s)), None);
    }

    #[test]
    fn sweep_invalid_options_rejected() {
        let o = SweepOptions {
            speed_min: f64::NAN,
            ..SweepOptions::default()
        };
        assert!(o.validate().is_err());
        assert!(SweepOptions::with_speed_range(3.0, 3.0).validate().is_err());
        assert!(SweepOptions::default().validate().is_ok());
    }
}
