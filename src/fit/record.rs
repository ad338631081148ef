//! A fit's results as data: one record per kick, as `bikedyn fit --json`
//! prints them ([`KickRecord`]), and the whole fit as Python's `FitResult`
//! and its `kicks.json` get it ([`FitRecord`]). These types are the
//! schema: the JSON is
//! their derived serialization (described in docs/measured-runs.md,
//! "Output"), and `tests/measured_runs/result_schema.rs` checks its shape
//! against the committed `tests/data/fit_schema.json`.
//!
//! A key a kick cannot fill is `null` (no measured weave, no prediction),
//! except `clock_offset` (thesis-style runs only) and `no_prediction` (a
//! kick without a speed only), which are absent otherwise: readers of the
//! JSON (python/bikedyn/results.py, the tests of TU Delft logs) rely on
//! that. A number that is not finite (the mean speed of a window without a
//! speed record) is `null`, as serde_json writes it.

use super::{calibration_text, FitOutcome, NO_SPEED};
use bikedyn_runtime::eigen::LinearBicycle;
use bikedyn_runtime::experiment::accept::{Rejected, SpeedFormRejected};
use bikedyn_runtime::experiment::compare::{self, Prediction};
use bikedyn_runtime::experiment::fit::FitResult;
use bikedyn_runtime::experiment::kicks::WindowEnd;
use bikedyn_runtime::experiment::sync::ClockOffset;
use bikedyn_runtime::experiment::KickFit;
use serde::Serialize;

/// A whole fit as Python's `bikedyn.fit` returns it (`FitResult`,
/// python/bikedyn/results.py reads it): the kicks as `bikedyn fit --json`
/// prints them, and what the command line says on standard error.
#[derive(Clone, Debug, Serialize)]
pub struct FitRecord {
    /// One record per kick.
    pub kicks: Vec<KickRecord>,
    /// Runs, logs and kicks left out, each with the reason.
    pub skipped: Vec<String>,
    /// Notes on the runs, each after its run's path.
    pub notes: Vec<String>,
    /// Each set's calibration in words (misalignment, noise at rest).
    pub calibration: String,
    /// The generated model that predicts each kick's weave.
    pub prediction_model: &'static str,
}

impl FitRecord {
    /// The record of a fit's outcome.
    pub fn of(out: &FitOutcome) -> FitRecord {
        let linear = &out.linear as &dyn LinearBicycle;
        FitRecord {
            kicks: out
                .reports
                .iter()
                .flat_map(|r| r.kicks.iter())
                .map(|k| KickRecord::of(k, linear))
                .collect(),
            skipped: out.errors.clone(),
            notes: out
                .reports
                .iter()
                .flat_map(|r| r.notes.iter().map(move |n| format!("{}: {n}", r.run.display())))
                .collect(),
            calibration: calibration_text(out),
            prediction_model: out.linear.model,
        }
    }
}

/// One kick: its window, every fit, the verdict on the reported one and
/// the bicycle's prediction.
#[derive(Clone, Debug, Serialize)]
pub struct KickRecord {
    /// Run folder or log file.
    pub run: String,
    /// Kick time (s; IMU clock, or data-row index x 0.01 s for a TU Delft log).
    pub kick_time: f64,
    /// Free-response window fitted, `[start, end]` (s).
    pub window: [f64; 2],
    /// Why the window ends (`decayed`, `next_kick`, `gap`, `record_end`,
    /// `fall`, `steer_stop`, `drift`, `speed_change`).
    pub window_end: WindowEnd,
    /// Speed interval over the window, `[low, high]` (m/s).
    pub speed_interval: [f64; 2],
    /// Mean speed over the window (m/s); `null` without a usable speed record.
    pub mean_speed: f64,
    /// Every form that converged.
    pub fits: Vec<FormFit>,
    /// Every form that did not, with the reason.
    pub failed_fits: Vec<FailedFit>,
    /// The measured weave eigenvalue `[real, imag]` (1/s, rad/s); `null`
    /// when the reported fit is no measured weave eigenvalue (`refused`).
    pub weave: Option<[f64; 2]>,
    /// Its standard errors `[real, imag]` (1/s, rad/s), or `null`.
    pub weave_stderr: Option<[f64; 2]>,
    /// r² of the measured weave's fit, or `null`.
    pub r2: Option<f64>,
    /// Form of the measured weave's fit (as in `fits[].form`), or `null`.
    pub form: Option<&'static str>,
    /// The test the reported fit failed, or `null` when it is a measured
    /// weave eigenvalue.
    pub refused: Option<Refusal<Rejected>>,
    /// Why a speed-varying fit that converged is not the reported one, or
    /// `null`.
    pub speed_varying_refused: Option<Refusal<SpeedFormRejected>>,
    /// Clock offset of the speed record (thesis-style runs; absent for a
    /// TU Delft log).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub clock_offset: Option<ClockOffset>,
    /// The bicycle's weave at the mean speed and its range over the speed
    /// interval (1/s, rad/s); `null` without a speed, or where the model has
    /// no oscillatory weave.
    pub predicted_weave: Option<Prediction>,
    /// Why there is no prediction: present only for a kick without a speed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub no_prediction: Option<&'static str>,
}

/// One form fitted to a kick.
#[derive(Clone, Debug, Serialize)]
pub struct FormFit {
    /// The form (`eq94_roll_angle`, `kooijman_roll_rate`,
    /// `speed_varying_roll_angle`, `speed_varying_roll_rate`).
    pub form: &'static str,
    /// Eigenvalue `[real, imag]` (1/s, rad/s).
    pub eigenvalue: [f64; 2],
    /// Its standard errors (1/s, rad/s).
    pub stderr: [f64; 2],
    /// d(eigenvalue)/d(speed) `[real, imag]` ((1/s)/(m/s)) of a
    /// speed-varying form, else `null`.
    pub slope_per_mps: Option<[f64; 2]>,
    /// Its standard errors, or `null`.
    pub slope_stderr: Option<[f64; 2]>,
    /// Coefficient of determination.
    pub r2: f64,
    /// Residual root mean square (rad for roll angle, rad/s for roll rate).
    pub rms: f64,
    /// Akaike information criterion (Gaussian likelihood).
    pub aic: f64,
    /// Bayesian information criterion.
    pub bic: f64,
    /// Number of samples fitted.
    pub n: usize,
}

impl From<&FitResult> for FormFit {
    fn from(f: &FitResult) -> Self {
        FormFit {
            form: f.form.name(),
            eigenvalue: f.eigenvalue,
            stderr: f.eigenvalue_stderr,
            slope_per_mps: f.slope,
            slope_stderr: f.slope_stderr,
            r2: f.r2,
            rms: f.rms,
            aic: f.aic,
            bic: f.bic,
            n: f.n,
        }
    }
}

/// A form that could not be fitted.
#[derive(Clone, Debug, Serialize)]
pub struct FailedFit {
    /// The form (as in [`FormFit::form`]).
    pub form: &'static str,
    /// Why, in words.
    pub error: String,
}

/// A verdict against a fit: the test (`test`) and its numbers, flattened
/// from the verdict's own type, its sentence, and for the reported fit the
/// fit itself.
#[derive(Clone, Debug, Serialize)]
pub struct Refusal<T> {
    /// The test and its numbers (keys of the verdict's variant).
    #[serde(flatten)]
    pub verdict: T,
    /// The same in words, with the numbers.
    pub reason: String,
    /// The refused fit (the reported one's refusal only; absent otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fit: Option<RefusedFit>,
}

/// The fit a refusal is about.
#[derive(Clone, Debug, Serialize)]
pub struct RefusedFit {
    /// The form (as in [`FormFit::form`]).
    pub form: &'static str,
    /// Eigenvalue `[real, imag]` (1/s, rad/s).
    pub eigenvalue: [f64; 2],
    /// Its standard errors (1/s, rad/s).
    pub stderr: [f64; 2],
    /// Coefficient of determination.
    pub r2: f64,
}

impl KickRecord {
    /// The record of kick `k`, its weave predicted by `linear` (the
    /// bicycle's model) at the kick's mean speed.
    pub fn of(k: &KickFit, linear: &dyn LinearBicycle) -> KickRecord {
        use bikedyn_report::experiment::accept::{rejected_text, speed_form_text};
        let measured = k.measured_weave();
        let [lo, hi] = k.speed_interval;
        let speed_known = k.mean_speed.is_finite();
        KickRecord {
            run: k.run.display().to_string(),
            kick_time: k.kick_time,
            window: k.window,
            window_end: k.window_end,
            speed_interval: k.speed_interval,
            mean_speed: k.mean_speed,
            fits: k.fits.iter().map(FormFit::from).collect(),
            failed_fits: k
                .failed
                .iter()
                .map(|(f, e)| FailedFit {
                    form: f.name(),
                    error: e.clone(),
                })
                .collect(),
            weave: measured.map(|f| f.eigenvalue),
            weave_stderr: measured.map(|f| f.eigenvalue_stderr),
            r2: measured.map(|f| f.r2),
            form: measured.map(|f| f.form.name()),
            refused: k.rejected.map(|r| Refusal {
                verdict: r,
                reason: rejected_text(&r),
                fit: k.chosen_fit().map(|f| RefusedFit {
                    form: f.form.name(),
                    eigenvalue: f.eigenvalue,
                    stderr: f.eigenvalue_stderr,
                    r2: f.r2,
                }),
            }),
            speed_varying_refused: k.speed_form.map(|r| Refusal {
                verdict: r,
                reason: speed_form_text(&r),
                fit: None,
            }),
            clock_offset: k.clock_offset,
            predicted_weave: speed_known
                .then(|| compare::predict(linear, k.mean_speed, lo, hi))
                .flatten(),
            no_prediction: (!speed_known).then_some(NO_SPEED),
        }
    }
}
