//! Measured runs: from raw logs to measured weave eigenvalues with standard
//! errors (thesis sections 5-7; Kooijman et al. 2008).
//!
//! Pipeline of a thesis-style run ([`process_thesis_run`]), from its
//! records ([`records`]; reading them from files is the application's,
//! `bikedyn::runs`): misalignments from the calibration run and roll/steer angles
//! ([`angles`]), speed from the reed switch ([`speed`]), clock offset of the
//! two loggers ([`sync`]), kick and free-response window ([`kicks`]), fits
//! ([`fit`]). A TU Delft log ([`process_tudelft`]) skips the first four:
//! it records roll, roll rate and speed directly. [`accept`] says which
//! fitted eigenvalues are measured weave eigenvalues (and which form is
//! reported); [`compare`] sets them against the model; [`synth`] writes
//! synthetic runs. A set of runs ([`process_set`]) shares one calibration,
//! its steer axis taken from the runs that agree on it; the runs come from
//! a [`RunSource`], read one at a time.

pub mod accept;
pub mod angles;
pub mod compare;
pub mod fit;
pub mod kicks;
pub mod records;
mod set;
pub mod speed;
pub mod sync;
pub mod synth;

use angles::{AngleMethod, Angles, Calibration};
use fit::{FitForm, FitResult};
use kicks::{Kick, KickOptions};
use records::{ThesisRun, TudelftLog};
use serde::Serialize;
use speed::SpeedProfile;
use std::path::{Path, PathBuf};
use sync::ClockOffset;

pub use set::{process_set, RunSource, MAX_MISALIGNMENT_RAD, MIN_SETTLED_S};

/// Options of the pipeline.
#[derive(Clone, Debug)]
pub struct PipelineOptions {
    /// Angle method (default [`AngleMethod::Direct`]).
    pub angle_method: AngleMethod,
    /// Kick detection and windows.
    pub kicks: KickOptions,
    /// Frame pitch at rest from the model's constraint solution (rad).
    pub frame_pitch: f64,
    /// Refine the clock offset from the data (else keep the nominal one).
    pub refine_clock: bool,
}

impl Default for PipelineOptions {
    fn default() -> Self {
        PipelineOptions {
            angle_method: AngleMethod::Direct,
            kicks: KickOptions::default(),
            // Thesis bicycle (ThesisParameters::frame_pitch).
            frame_pitch: -0.315,
            refine_clock: true,
        }
    }
}

/// Fit results of one kick.
#[derive(Clone, Debug, Serialize)]
pub struct KickFit {
    /// Run folder or log file.
    pub run: PathBuf,
    /// Kick time (s; IMU clock, or row index x 0.01 s for TU Delft logs).
    pub kick_time: f64,
    /// Fit window `[start, end]` (s).
    pub window: [f64; 2],
    /// Why the window ends.
    pub window_end: kicks::WindowEnd,
    /// Speed interval covered by the window `[low, high]` (m/s).
    pub speed_interval: [f64; 2],
    /// Mean speed over the window (m/s); NaN when the window has no usable
    /// speed sample.
    pub mean_speed: f64,
    /// Every fit that converged.
    pub fits: Vec<FitResult>,
    /// Fits that failed, with the reason.
    pub failed: Vec<(FitForm, String)>,
    /// The constant form on the primary signal: roll angle for thesis-style
    /// runs, roll rate for TU Delft logs.
    pub primary: FitForm,
    /// Index in `fits` of the reported fit: the constant form on the
    /// primary signal, or its speed-varying form where that passes
    /// [`accept::speed_form_test`] and has the smaller BIC
    /// ([`accept::choose_form`]).
    pub chosen: Option<usize>,
    /// Why a speed-varying fit that converged is not the reported one.
    pub speed_form: Option<accept::SpeedFormRejected>,
    /// Why the reported eigenvalue is not a measured weave eigenvalue
    /// (`None`: it is one; [`accept`]).
    pub rejected: Option<accept::Rejected>,
    /// Clock offset of the run (thesis-style runs).
    pub clock_offset: Option<ClockOffset>,
    /// Samples of the window (for plots): time, roll (rad), roll rate
    /// (rad/s), speed (m/s).
    #[serde(skip)]
    pub samples: Samples,
}

/// The window's samples.
#[derive(Clone, Debug, Default)]
pub struct Samples {
    /// Time (s).
    pub t: Vec<f64>,
    /// Roll (rad).
    pub roll: Vec<f64>,
    /// Roll rate (rad/s).
    pub roll_rate: Vec<f64>,
    /// Speed (m/s).
    pub speed: Vec<f64>,
}

impl KickFit {
    /// The reported fit, accepted or not.
    pub fn chosen_fit(&self) -> Option<&FitResult> {
        self.chosen.map(|i| &self.fits[i])
    }
    /// The reported fit if its eigenvalue is a measured weave eigenvalue
    /// (it passed every test of [`accept`]): what tables, plots and error
    /// figures may show.
    pub fn measured_weave(&self) -> Option<&FitResult> {
        self.chosen_fit().filter(|_| self.rejected.is_none())
    }
}

/// The note of a run or log in which no kick was found (followed by the
/// reason).
pub const NO_KICK: &str = "no kick found";

/// Start of the note on a run whose own steer axis lies far from the set's
/// ([`angles::RunAxisVerdict::Inconsistent`]): it is left out of the set's
/// steer axis and fitted, with this warning.
pub const STEER_AXIS_APART: &str = "steer axis apart";

/// Result of one run or log.
#[derive(Clone, Debug, Serialize)]
pub struct RunReport {
    /// Run folder or log file.
    pub run: PathBuf,
    /// Kicks found, with their fits.
    pub kicks: Vec<KickFit>,
    /// Quaternions normalised (frame, handlebar).
    pub renormalised: [usize; 2],
    /// Gaps in the records (reported, never interpolated across).
    pub gaps: Vec<String>,
    /// Clock offset.
    pub clock_offset: Option<ClockOffset>,
    /// Magnet spacing (fractions of the circumference) with standard errors.
    pub magnet_spacing: Option<(Vec<f64>, Vec<f64>)>,
    /// Reed-switch bounces merged.
    pub bounces: usize,
    /// Notes (e.g. no kick found).
    pub notes: Vec<String>,
    /// Angles on the IMU clock (thesis runs), for plots.
    #[serde(skip)]
    pub angles: Option<Angles>,
    /// Speed profile (DAQ clock), for plots.
    #[serde(skip)]
    pub speed: Option<SpeedProfile>,
    /// The series of a TU Delft log (one clock), for identification.
    #[serde(skip)]
    pub log: Option<TudelftLog>,
}

/// Why a set's calibration or one of its runs fails the pipeline's own
/// checks (reading it is the source's: [`RunSource::Error`]).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The calibration run's bicycle moved: its mounting misalignments
    /// would carry the motion into every angle.
    #[error(
        "{}: the calibration run is not at rest: its frame sensor tilts by {:.2} deg and its handlebar sensor by {:.2} deg \
         against gravity between half-second averages over the settled record (rates up to {:.1} and {:.1} deg/s); at rest \
         they stay within {:.0} deg (the sensors wander a few tenths; their drift in heading is not counted), and a roll \
         tilts both, a steer the handlebar's; record it with the bicycle held still, or give another with --calibration",
        run.display(),
        motion.frame_tilt_range.to_degrees(),
        motion.handlebar_tilt_range.to_degrees(),
        motion.frame_tilt_rate.to_degrees(),
        motion.handlebar_tilt_rate.to_degrees(),
        Calibration::AT_REST_LIMIT.to_degrees()
    )]
    NotAtRest {
        /// The calibration run.
        run: PathBuf,
        /// How it moved.
        motion: angles::CalibrationMotion,
    },
    /// The calibration record settles for too short a time to show
    /// whether the bicycle was at rest ([`Calibration::motion`] needs four
    /// half-second blocks): a record cut short.
    #[error(
        "{}: the calibration record is settled for {settled:.2} s only ({samples} samples); at least {:.0} s at rest are needed to tell the mounting from motion and noise: record the bicycle at rest for a few seconds, or give another with --calibration",
        run.display(),
        MIN_SETTLED_S
    )]
    CalibrationTooShort {
        /// The calibration run.
        run: PathBuf,
        /// Length of its settled part (s).
        settled: f64,
        /// Samples in the record.
        samples: usize,
    },
    /// A sensor's estimated mounting misalignment is far beyond the few
    /// degrees of a sensor fixed along the body axes: the calibration or the
    /// runs are of sensors mounted otherwise (rotated, swapped), or of
    /// another bicycle.
    #[error(
        "{}: the {sensor} sensor's mounting misalignment comes out at {:.1} deg (about x y z: {:+.1} {:+.1} {:+.1}); sensors fixed along the body axes are off by a few degrees (at most {:.0}): check that the calibration record belongs to these runs, is not rotated, and that the two sensors' files are not swapped",
        run.display(),
        angle.to_degrees(),
        euler[0].to_degrees(),
        euler[1].to_degrees(),
        euler[2].to_degrees(),
        MAX_MISALIGNMENT_RAD.to_degrees()
    )]
    ImplausibleMisalignment {
        /// The calibration run.
        run: PathBuf,
        /// "frame" or "handlebar".
        sensor: &'static str,
        /// Rotation angle of the misalignment (rad).
        angle: f64,
        /// Its angles about x, y, z (rad).
        euler: [f64; 3],
    },
    /// The run's frame and handlebar files are swapped: its handlebar
    /// sensor turns about an axis of its own (not the set's steer axis),
    /// and each file's tilt against gravity matches the calibration's other
    /// sensor. It is set aside: its angles would be wrong, and the set's
    /// results are those of the set without it.
    #[error(
        "{}: set aside: its frame and handlebar files look swapped: its handlebar sensor turns about an axis {:.1} deg from the steer axis the set's other runs share (beyond {:.1} deg), and the tilts against gravity its two files show lie {:.1} deg from the calibration's handlebar and frame sensors but {:.1} deg from its frame and handlebar sensors; swap them back (imu_files in run.toml) to use the run",
        run.display(),
        angle.to_degrees(),
        limit.to_degrees(),
        as_swapped.to_degrees(),
        as_named.to_degrees()
    )]
    SensorsSwapped {
        /// The run.
        run: PathBuf,
        /// Its steer axis's angle from the set's (rad).
        angle: f64,
        /// The largest angle accepted (rad).
        limit: f64,
        /// Sum of the two files' tilt distances from the calibration's
        /// other sensor (rad).
        as_swapped: f64,
        /// The same from the calibration's sensor of the same name (rad).
        as_named: f64,
    },
}

#[allow(clippy::too_many_arguments)]
fn fit_window(
    run: &Path,
    k: &Kick,
    t: &[f64],
    roll: &[f64],
    rate: &[f64],
    speed: &[f64],
    primary: FitForm,
    offset: Option<ClockOffset>,
) -> KickFit {
    let (a, b) = (k.start, k.end);
    let samples = Samples {
        t: t[a..b].to_vec(),
        roll: roll[a..b].to_vec(),
        roll_rate: rate[a..b].to_vec(),
        speed: speed[a..b].to_vec(),
    };
    let mut fit = fit_kick(run, k.time, k.end_reason, samples, primary);
    fit.window = [t[a], t[b.max(a + 1) - 1]];
    fit.clock_offset = offset;
    fit
}

/// Fit every form to a kick's free-response window (`samples`, the kick at
/// `kick_time`) and report the constant form on the `primary` signal
/// (roll angle or roll rate), judged without a model
/// ([`accept::check_fit`]); [`accept::judge`] judges again with one.
pub fn fit_kick(
    run: &Path,
    kick_time: f64,
    window_end: kicks::WindowEnd,
    samples: Samples,
    primary: FitForm,
) -> KickFit {
    let (ts, rs, qs, vs) = (&samples.t, &samples.roll, &samples.roll_rate, &samples.speed);
    let finite_v: Vec<f64> = vs.iter().copied().filter(|v| v.is_finite()).collect();
    let (lo, hi) = finite_v
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| (l.min(v), h.max(v)));
    // No speed sample in the window: no mean speed (NaN, null in JSON), so
    // that nothing is predicted at a made-up speed of zero.
    let mean = if finite_v.is_empty() {
        f64::NAN
    } else {
        finite_v.iter().sum::<f64>() / finite_v.len() as f64
    };
    let mut fits = Vec::new();
    let mut failed = Vec::new();
    // The speed-varying form needs a speed that changes measurably over the
    // window: a linear trend of the speed, significant at three standard
    // errors (a constant speed leaves the slopes unidentifiable).
    // The speed record may end a little before the window does (the two
    // loggers stop independently): the trend is taken over the samples with
    // a speed if they cover most of the window, and extended over the rest.
    let (tf, vf): (Vec<f64>, Vec<f64>) = ts
        .iter()
        .zip(vs)
        .filter(|(_, v)| v.is_finite())
        .map(|(t, v)| (*t, *v))
        .unzip();
    let trend = if vf.len() > 3 && 5 * vf.len() >= 4 * vs.len() {
        speed_trend(&tf, &vf).map(|(a, b, se)| (a + b * (ts[0] - tf[0]), b, se))
    } else {
        None
    };
    let speed_ok = trend.is_some();
    let v_lin: Vec<f64> = match trend {
        Some((a, b, _)) => ts.iter().map(|x| a + b * (x - ts[0])).collect(),
        None => Vec::new(),
    };
    // The grid and the constant fit are shared by both forms on a signal.
    let (roll_prep, rate_prep) = (fit::prepare(ts, rs), fit::prepare(ts, qs));
    let forms = [
        (FitForm::RollAngle, rs, false, &roll_prep),
        (FitForm::RollRate, qs, false, &rate_prep),
        (FitForm::SpeedVaryingRollAngle, rs, true, &roll_prep),
        (FitForm::SpeedVaryingRollRate, qs, true, &rate_prep),
    ];
    for (form, y, varying, prep) in forms {
        if varying && !speed_ok {
            failed.push((form, "speed not measurably changing over the window".to_string()));
            continue;
        }
        let fitted = prep
            .as_ref()
            .map_err(|e| e.clone())
            .and_then(|p| fit::fit_prepared(form, ts, y, varying.then_some(v_lin.as_slice()), p));
        match fitted {
            Ok(f) => fits.push(f),
            Err(e) => failed.push((form, e.to_string())),
        }
    }
    let window = match (ts.first(), ts.last()) {
        (Some(&a), Some(&b)) => [a, b],
        _ => [f64::NAN; 2],
    };
    let mut k = KickFit {
        run: run.to_path_buf(),
        kick_time,
        window,
        window_end,
        speed_interval: if lo.is_finite() { [lo, hi] } else { [f64::NAN, f64::NAN] },
        mean_speed: mean,
        fits,
        failed,
        primary,
        chosen: None,
        speed_form: None,
        rejected: None,
        clock_offset: None,
        samples,
    };
    accept::judge([&mut k], None);
    k
}

/// Linear trend `v = a + b (t - t0)` of the speed over a window, if its slope
/// is significant at three standard errors: `(a, b, stderr of b)`.
fn speed_trend(t: &[f64], v: &[f64]) -> Option<(f64, f64, f64)> {
    let n = t.len() as f64;
    let tm = t.iter().sum::<f64>() / n;
    let vm = v.iter().sum::<f64>() / n;
    let stt: f64 = t.iter().map(|x| (x - tm).powi(2)).sum();
    let b = t.iter().zip(v).map(|(x, y)| (x - tm) * (y - vm)).sum::<f64>() / stt;
    let a = vm + b * (t[0] - tm);
    let ss: f64 = t.iter().zip(v).map(|(x, y)| (y - a - b * (x - t[0])).powi(2)).sum();
    // Neighbouring speed samples are correlated (smoothing, sample-and-hold
    // between magnet passes): count at most ten independent samples.
    let n_ind = n.min(10.0);
    let se = (ss / (n - 2.0) / stt * n / n_ind).sqrt();
    (b.abs() > 3.0 * se).then_some((a, b, se))
}

/// Process one thesis-style run with the set's calibration.
pub fn process_thesis_run(run: &ThesisRun, cal: &Calibration, opt: &PipelineOptions) -> RunReport {
    let ang = angles::angles(run, cal, opt.angle_method);
    let sp = speed::speed_profile(&run.switch, &run.meta);
    let offset = if opt.refine_clock {
        sync::estimate_offset(&ang, &sp, run.meta.nominal_offset_s, cal.settled_from.max(ang.t[0]))
    } else {
        ClockOffset::nominal(run.meta.nominal_offset_s)
    };
    let t = &ang.t;
    let dt = (t[t.len() - 1] - t[0]) / (t.len().max(2) - 1) as f64;
    let h = ((opt.kicks.smoothing / dt / 2.0).round() as usize).max(1);
    let rate = kicks::derivative(t, &ang.roll, h);
    let v: Vec<f64> = t
        .iter()
        .map(|&x| sp.at(x - offset.value).map(|s| s.0).unwrap_or(f64::NAN))
        .collect();
    let mut ko = opt.kicks.clone();
    ko.single = true;
    // Before the settled time the orientation is not trustworthy, and the
    // kick comes after the release, which ends the launch at the highest
    // speed (FORMAT.md: launch, release, then the kick).
    // The release ends the launch: the first time after the launch's peak
    // acceleration that the acceleration falls below half of that peak. (The
    // highest speed is no mark: with little rolling loss the speed after the
    // release is a plateau whose maximum falls anywhere on it.) The
    // acceleration is a central difference over RELEASE_SPAN, short against
    // a hand launch (seconds) and long against the magnet-to-magnet noise.
    const RELEASE_SPAN: f64 = 0.2;
    let accel: Vec<f64> =
        sp.t.iter()
            .map(|&x| match (sp.at(x - RELEASE_SPAN), sp.at(x + RELEASE_SPAN)) {
                (Some(a), Some(b)) => (b.0 - a.0) / (2.0 * RELEASE_SPAN),
                _ => f64::NAN,
            })
            .collect();
    let release = accel
        .iter()
        .enumerate()
        .filter(|(_, a)| a.is_finite())
        .max_by(|a, b| a.1.total_cmp(b.1))
        .filter(|(_, &amax)| amax > 0.0)
        .and_then(|(imax, &amax)| (imax..accel.len()).find(|&i| accel[i] < 0.5 * amax))
        .map(|i| sp.t[i] + offset.value);
    let k0 = t.partition_point(|&x| x < cal.settled_from.max(release.unwrap_or(f64::NEG_INFINITY)));
    let found = kicks::find_kicks(
        &t[k0..],
        &ang.roll[k0..],
        &rate[k0..],
        Some(&ang.steer[k0..]),
        &run.frame.gaps,
        &ko,
    );
    let mut notes = Vec::new();
    if found.is_empty() {
        let why = kicks::no_kick_reason(&t[k0..], &rate[k0..], &ko);
        notes.push(format!("{NO_KICK}: {why}"));
    }
    let kicks = found
        .into_iter()
        .map(|mut k| {
            k.start += k0;
            k.end += k0;
            k.index += k0;
            limit_speed_change(&mut k, &v, opt.kicks.max_speed_change);
            fit_window(&run.dir, &k, t, &ang.roll, &rate, &v, FitForm::RollAngle, Some(offset))
        })
        .collect();
    let mut gaps: Vec<String> = Vec::new();
    for (rec, g) in [(&run.frame.path, &run.frame.gaps), (&run.switch.path, &run.switch.gaps)] {
        for x in g {
            gaps.push(format!(
                "{}:{}: gap {:.4}-{:.4} s",
                rec.display(),
                x.line,
                x.start,
                x.end
            ));
        }
    }
    RunReport {
        run: run.dir.clone(),
        kicks,
        renormalised: [run.frame.renormalised, run.handlebar.renormalised],
        gaps,
        clock_offset: Some(offset),
        magnet_spacing: Some((sp.spacing.clone(), sp.spacing_stderr.clone())),
        bounces: sp.bounces,
        notes,
        angles: Some(ang),
        speed: Some(sp),
        log: None,
    }
}

/// End a window where the speed has changed by more than `frac` from its
/// value at the start.
fn limit_speed_change(k: &mut Kick, v: &[f64], frac: f64) {
    let v0 = v[k.start];
    if !v0.is_finite() {
        return;
    }
    if let Some(j) = (k.start..k.end).find(|&j| (v[j] - v0).abs() > frac * v0.abs()) {
        k.end = j;
        k.end_reason = kicks::WindowEnd::SpeedChange;
    }
}

/// Process one TU Delft log (many kicks).
pub fn process_tudelft(log: &TudelftLog, opt: &PipelineOptions) -> RunReport {
    let mut ko = opt.kicks.clone();
    ko.single = false;
    let found = kicks::find_kicks(&log.t, &log.roll, &log.roll_rate, Some(&log.steer), &[], &ko);
    let mut notes = Vec::new();
    if found.is_empty() {
        let why = kicks::no_kick_reason(&log.t, &log.roll_rate, &ko);
        notes.push(format!("{NO_KICK}: {why}"));
    }
    let kicks = found
        .iter()
        .map(|k| {
            let mut k = k.clone();
            limit_speed_change(&mut k, &log.speed, opt.kicks.max_speed_change);
            fit_window(
                &log.path,
                &k,
                &log.t,
                &log.roll,
                &log.roll_rate,
                &log.speed,
                FitForm::RollRate,
                None,
            )
        })
        .collect();
    RunReport {
        run: log.path.clone(),
        kicks,
        renormalised: [0, 0],
        gaps: Vec::new(),
        clock_offset: None,
        magnet_spacing: None,
        bounces: 0,
        notes,
        angles: None,
        speed: None,
        log: Some(log.clone()),
    }
}
