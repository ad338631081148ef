//! Which fitted eigenvalues are measured weave eigenvalues, and which form
//! of a kick's fit is reported.
//!
//! A fit converges to some eigenvalue on nearly any window, a noise burst
//! included (the Nyquist limit of a 100 Hz log, with r² = 0.003). A fitted
//! eigenvalue is a measured one, and enters a table, a plot or an error
//! figure, only when it passes every test below; otherwise the kick carries
//! the first test it failed, with its numbers ([`Rejected`]), for the
//! report layer to state.
//!
//! 1. It was fitted at all ([`Rejected::NoFit`]), by a form that may be
//!    reported ([`Rejected::OnlySpeedForm`]).
//! 2. The record resolves it: its frequency is at most
//!    [`MAX_NYQUIST_FRACTION`] of the Nyquist angular frequency `pi rate`
//!    (the rate from the window's own sample spacing), and the window holds
//!    at least [`MIN_PERIODS`] of its periods.
//! 3. The fit describes the window and pins the eigenvalue down: r² of at
//!    least [`MIN_R2`], each part's standard error at most
//!    [`MAX_RELATIVE_STDERR`] of the eigenvalue's modulus.
//! 4. With a model: the kick has a speed, the model an oscillatory weave at
//!    it, and the misfit to that weave is no robust outlier among the other
//!    kicks' misfits ([`robust_outliers`]).
//!
//! The speed-varying form (eigenvalue linear in speed) is reported only when
//! its slope means something ([`speed_form_test`]); otherwise the constant
//! form on the same signal is. Its bound comes from the model, which the
//! caller passes in ([`judge`]): the runtime knows the model only as a
//! [`LinearBicycle`].

use super::compare::{predicted_weave, weave_slope};
use super::fit::{FitForm, FitResult};
use super::KickFit;
use crate::eigen::LinearBicycle;
use serde::Serialize;

/// Largest fitted angular frequency, as a fraction of the Nyquist angular
/// frequency `pi rate`. At a quarter, a period spans at least eight
/// samples, so a damped cosine is drawn by its samples and not aliased; a
/// weave (2-10 rad/s) is far below it at any rate a bicycle is logged at
/// (78.5 rad/s at 100 Hz).
pub const MAX_NYQUIST_FRACTION: f64 = 0.25;

/// Fewest periods of the fitted frequency in the window. From the window's
/// start (the roll-rate peak after the kick) three quarters of a period
/// hold two zero crossings, so one half-period is seen whole; the clean,
/// heavily damped responses of the TU Delft logs decay into noise after
/// 0.76-0.95 periods with r² of 0.99 and their frequency within 2-4 %, so a
/// whole period would refuse them for no want of information. Fewer, and
/// a slow drift passes for an oscillation (1.3 rad/s over half a period).
pub const MIN_PERIODS: f64 = 0.75;

/// Smallest coefficient of determination: below it the fit explains less
/// than half of the window's variance (not a clean oscillation).
pub const MIN_R2: f64 = 0.5;

/// Largest standard error of either part of the eigenvalue, as a fraction
/// of its modulus. At a tenth, the measured eigenvalue tells apart, at two
/// standard errors, model errors of a fifth of its modulus: the size of
/// the misfits it is meant to reveal (6-34 % on the development runs).
pub const MAX_RELATIVE_STDERR: f64 = 0.1;

/// A misfit further than this many robust standard deviations (1.4826
/// median absolute deviations) from the other kicks' median, in the real or
/// the imaginary part, is not the same kind of point.
pub const OUTLIER_SIGMAS: f64 = 4.0;

/// Fewest kicks for the outlier test: the spread of fewer points is itself
/// uncertain by a third or more, so "4 standard deviations" of it would not
/// be four.
pub const MIN_FOR_OUTLIERS: usize = 8;

/// The speed-varying form's slope must differ from zero by this many
/// standard errors in its real or its imaginary part. Either part, not
/// both: the weave may change with speed in its frequency and hardly in its
/// damping, or the other way round (the thesis bicycle at 5-6 m/s: about
/// 2 rad/s and -0.5 1/s per m/s), and asking both would refuse real
/// changes. The plausibility bound and the speed change guard the rest.
pub const SLOPE_SIGMAS: f64 = 2.0;

/// The speed-varying form's slope (modulus of `d lambda / d v`) may be at
/// most this multiple of the model's own at the kick's speed. Generous: the
/// model may be off by the misfits measured (a fifth or a third) and its
/// slope changes over the window; a slope beyond three times the model's is
/// the form's two extra parameters taking up noise or an unmodelled
/// transient, not the weave changing with speed (the TU Delft logs gave
/// hundreds to 6,627 (1/s)/(m/s) against the model's 0.5-4.5).
pub const SLOPE_PLAUSIBILITY: f64 = 3.0;

/// Why a fitted eigenvalue is not a measured weave eigenvalue: the first
/// test it failed, with the numbers of the test.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "test", rename_all = "snake_case")]
pub enum Rejected {
    /// No form converged to an oscillation.
    NoFit,
    /// Only a speed-varying form converged, and it failed its tests
    /// ([`speed_form_test`]).
    OnlySpeedForm {
        /// The test it failed.
        why: SpeedFormRejected,
    },
    /// The frequency (rad/s) is above `limit`, [`MAX_NYQUIST_FRACTION`] of
    /// the Nyquist angular frequency of the record sampled at `rate` (Hz).
    AboveNyquist {
        /// Fitted angular frequency (rad/s).
        omega: f64,
        /// Largest accepted (rad/s).
        limit: f64,
        /// Sample rate of the window (Hz).
        rate: f64,
    },
    /// The window holds `periods` periods of the fitted frequency, fewer than `min`.
    FewPeriods {
        /// Periods in the window.
        periods: f64,
        /// Fewest accepted.
        min: f64,
    },
    /// The fit's r² is below `min`.
    LowR2 {
        /// The fit's r².
        r2: f64,
        /// Smallest accepted.
        min: f64,
    },
    /// A standard error is above `max_fraction` of the eigenvalue's modulus
    /// (or not finite).
    LargeStderr {
        /// Standard errors `[real, imag]` (1/s).
        stderr: [f64; 2],
        /// Modulus of the eigenvalue (1/s).
        modulus: f64,
        /// Largest accepted fraction.
        max_fraction: f64,
    },
    /// The window has no speed record, so the eigenvalue has no speed to
    /// stand at.
    NoSpeed,
    /// The model has no oscillatory weave at the kick's speed (m/s): the
    /// fitted oscillation is another mode's or a merger's.
    NoModelWeave {
        /// Mean speed of the window (m/s).
        speed: f64,
    },
    /// The misfit to the model is `sigmas` robust standard deviations of
    /// the other kicks' misfits (its own standard error included) from
    /// their median, beyond `max`.
    Outlier {
        /// Measured eigenvalue `[real, imag]`.
        measured: [f64; 2],
        /// The model's weave at the kick's speed.
        predicted: [f64; 2],
        /// Distance from the others' misfits.
        sigmas: f64,
        /// Largest accepted.
        max: f64,
    },
}

/// Why a kick's speed-varying fit is not the reported one (the constant
/// form on the same signal is).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(tag = "test", rename_all = "snake_case")]
pub enum SpeedFormRejected {
    /// No model slope to bound it: no model given, no speed, or the model
    /// has no oscillatory weave at the kick's speed.
    NoBound,
    /// Over the window's speed change the model's weave moves by less than
    /// the eigenvalue's standard error: the form would describe a change
    /// the window cannot resolve, and its slope only trades against the
    /// reported eigenvalue.
    SmallSpeedChange {
        /// Change of the speed over the window (m/s; its straight line).
        speed_change: f64,
        /// The model's weave change over it (1/s).
        model_change: f64,
        /// Standard error of the eigenvalue (1/s, modulus of both parts).
        stderr: f64,
    },
    /// Neither part of the slope is [`SLOPE_SIGMAS`] standard errors from zero.
    NotSignificant {
        /// Slope `[real, imag]` ((1/s)/(m/s)).
        slope: [f64; 2],
        /// Its standard errors.
        stderr: [f64; 2],
        /// Sigmas asked of one part.
        min_sigmas: f64,
    },
    /// The slope's modulus is beyond `factor` times the model's.
    Implausible {
        /// Modulus of the fitted slope ((1/s)/(m/s)).
        slope: f64,
        /// Modulus of the model's `d lambda / d v` at the kick's speed.
        model: f64,
        /// The factor allowed.
        factor: f64,
    },
}

/// Sample rate (Hz) from the median spacing of `t`; NaN with fewer than
/// two samples.
pub fn sample_rate(t: &[f64]) -> f64 {
    let mut d: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).filter(|d| *d > 0.0).collect();
    if d.is_empty() {
        return f64::NAN;
    }
    d.sort_by(f64::total_cmp);
    1.0 / d[d.len() / 2]
}

/// Whether the speed-varying fit `varying` may be reported instead of the
/// constant form `constant` (same signal; `None` when it did not converge):
/// a model slope to bound it (`model_slope`, `d lambda / d v` at the kick's
/// speed), a speed change over the window (`span`, s) across which the
/// model's weave moves by at least the eigenvalue's standard error, a slope
/// significant in one part ([`SLOPE_SIGMAS`]) and within
/// [`SLOPE_PLAUSIBILITY`] times the model's.
pub fn speed_form_test(
    varying: &FitResult,
    constant: Option<&FitResult>,
    span: f64,
    model_slope: Option<[f64; 2]>,
) -> Result<(), SpeedFormRejected> {
    let model = model_slope
        .map(|m| m[0].hypot(m[1]))
        .filter(|m| m.is_finite())
        .ok_or(SpeedFormRejected::NoBound)?;
    let speed_change = varying.speed_line.map_or(0.0, |l| (l[1] * span).abs());
    let se = constant.unwrap_or(varying).eigenvalue_stderr;
    let stderr = se[0].hypot(se[1]);
    let model_change = model * speed_change;
    // Written so that a NaN fails.
    if !(model_change >= stderr) {
        return Err(SpeedFormRejected::SmallSpeedChange {
            speed_change,
            model_change,
            stderr,
        });
    }
    let (slope, slope_se) = (
        varying.slope.unwrap_or([0.0; 2]),
        varying.slope_stderr.unwrap_or([f64::INFINITY; 2]),
    );
    let sigmas = |c: usize| slope[c].abs() / slope_se[c];
    if !(sigmas(0) > SLOPE_SIGMAS || sigmas(1) > SLOPE_SIGMAS) {
        return Err(SpeedFormRejected::NotSignificant {
            slope,
            stderr: slope_se,
            min_sigmas: SLOPE_SIGMAS,
        });
    }
    let modulus = slope[0].hypot(slope[1]);
    if !(modulus <= SLOPE_PLAUSIBILITY * model) {
        return Err(SpeedFormRejected::Implausible {
            slope: modulus,
            model,
            factor: SLOPE_PLAUSIBILITY,
        });
    }
    Ok(())
}

/// The constant and the speed-varying form on one signal.
fn signal(constant: FitForm) -> [FitForm; 2] {
    match constant {
        FitForm::RollAngle | FitForm::SpeedVaryingRollAngle => [FitForm::RollAngle, FitForm::SpeedVaryingRollAngle],
        FitForm::RollRate | FitForm::SpeedVaryingRollRate => [FitForm::RollRate, FitForm::SpeedVaryingRollRate],
    }
}

/// The reported fit of a kick (index in `k.fits`) and, where a
/// speed-varying fit converged but is not reported, why: on the primary
/// signal (or the other, if no form converged on it), the constant form, or
/// the speed-varying one where it passes [`speed_form_test`] and has the
/// smaller BIC. `model_slope`: the model's `d lambda / d v` at the kick's
/// speed (`None`: no model, and so the constant form).
pub fn choose_form(k: &KickFit, model_slope: Option<[f64; 2]>) -> (Option<usize>, Option<SpeedFormRejected>) {
    let other = match k.primary {
        FitForm::RollAngle | FitForm::SpeedVaryingRollAngle => FitForm::RollRate,
        _ => FitForm::RollAngle,
    };
    let span = k.window[1] - k.window[0];
    // Where no form is reported, the primary signal's refusal says why its
    // speed-varying fit was not.
    let mut first = None;
    for [constant, varying] in [signal(k.primary), signal(other)] {
        let pick = |f: FitForm| k.fits.iter().position(|x| x.form == f);
        let (c, v) = (pick(constant), pick(varying));
        let refused = v
            .map(|v| speed_form_test(&k.fits[v], c.map(|c| &k.fits[c]), span, model_slope))
            .and_then(Result::err);
        let v = v.filter(|_| refused.is_none());
        let chosen = match (c, v) {
            (Some(c), Some(v)) => Some(if k.fits[v].bic < k.fits[c].bic { v } else { c }),
            (c, v) => c.or(v),
        };
        if chosen.is_some() {
            return (chosen, refused);
        }
        first = first.or(refused);
    }
    (None, first)
}

/// Tests 1-3 of the module docs on the reported fit of `k`: it exists, the
/// record resolves it, it fits and is determined.
pub fn check_fit(k: &KickFit) -> Result<(), Rejected> {
    let f = k.chosen_fit().ok_or(match k.speed_form {
        Some(why) => Rejected::OnlySpeedForm { why },
        None => Rejected::NoFit,
    })?;
    let [sigma, omega] = f.eigenvalue;
    let rate = sample_rate(&k.samples.t);
    let limit = MAX_NYQUIST_FRACTION * std::f64::consts::PI * rate;
    if !(omega <= limit) {
        return Err(Rejected::AboveNyquist { omega, limit, rate });
    }
    let periods = omega * (k.window[1] - k.window[0]) / std::f64::consts::TAU;
    if !(periods >= MIN_PERIODS) {
        return Err(Rejected::FewPeriods {
            periods,
            min: MIN_PERIODS,
        });
    }
    if !(f.r2 >= MIN_R2) {
        return Err(Rejected::LowR2 { r2: f.r2, min: MIN_R2 });
    }
    let modulus = sigma.hypot(omega);
    let se = f.eigenvalue_stderr;
    if !(se[0].max(se[1]) <= MAX_RELATIVE_STDERR * modulus) || se.iter().any(|s| !s.is_finite()) {
        return Err(Rejected::LargeStderr {
            stderr: se,
            modulus,
            max_fraction: MAX_RELATIVE_STDERR,
        });
    }
    Ok(())
}

/// The robust outlier test on misfits (measured minus predicted, `[re,
/// im]`) with the measured eigenvalues' standard errors: for each, its
/// distance from the median misfit in robust standard deviations (1.4826
/// median absolute deviations, combined with its own standard error: a
/// short, noisy fit may miss by more without being another kind of point),
/// the larger of the two parts, when beyond [`OUTLIER_SIGMAS`]; `None` for
/// the others, and for all when there are fewer than [`MIN_FOR_OUTLIERS`].
pub fn robust_outliers(misfits: &[[f64; 2]], stderr: &[[f64; 2]]) -> Vec<Option<f64>> {
    if misfits.len() < MIN_FOR_OUTLIERS {
        return vec![None; misfits.len()];
    }
    let centre_spread = |c: usize| {
        let x: Vec<f64> = misfits.iter().map(|z| z[c]).collect();
        let m = median(&x);
        let dev: Vec<f64> = x.iter().map(|v| (v - m).abs()).collect();
        (m, 1.4826 * median(&dev))
    };
    let spread = [centre_spread(0), centre_spread(1)];
    misfits
        .iter()
        .zip(stderr)
        .map(|(d, se)| {
            let z = |c: usize| {
                let (m, s) = spread[c];
                let scale = (s * s + se[c] * se[c]).sqrt();
                if scale > 0.0 {
                    (d[c] - m).abs() / scale
                } else {
                    0.0
                }
            };
            let worst = z(0).max(z(1));
            (worst > OUTLIER_SIGMAS).then_some(worst)
        })
        .collect()
}

fn median(x: &[f64]) -> f64 {
    let mut v: Vec<f64> = x.iter().copied().filter(|a| a.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Judge every kick: choose its reported form (the speed-varying form's
/// bound from `model`), then test the reported eigenvalue (module docs),
/// setting [`KickFit::chosen`], [`KickFit::speed_form`] and
/// [`KickFit::rejected`]. Without a model only tests 1-3 apply and the
/// constant form is reported. The outlier test runs over all the kicks
/// given that pass the others.
pub fn judge<'a>(kicks: impl IntoIterator<Item = &'a mut KickFit>, model: Option<&dyn LinearBicycle>) {
    let mut kicks: Vec<&mut KickFit> = kicks.into_iter().collect();
    let mut predicted: Vec<Option<[f64; 2]>> = Vec::with_capacity(kicks.len());
    for k in kicks.iter_mut() {
        let v = k.mean_speed;
        let slope = model.filter(|_| v.is_finite()).and_then(|m| weave_slope(m, v));
        (k.chosen, k.speed_form) = choose_form(k, slope);
        let p = model.filter(|_| v.is_finite()).and_then(|m| predicted_weave(m, v));
        k.rejected = check_fit(k).err().or(if !v.is_finite() {
            Some(Rejected::NoSpeed)
        } else if model.is_some() && p.is_none() {
            Some(Rejected::NoModelWeave { speed: v })
        } else {
            None
        });
        predicted.push(p.filter(|_| k.rejected.is_none()));
    }
    let idx: Vec<usize> = (0..kicks.len()).filter(|&i| predicted[i].is_some()).collect();
    let (misfits, stderr): (Vec<[f64; 2]>, Vec<[f64; 2]>) = idx
        .iter()
        .map(|&i| {
            let f = kicks[i].chosen_fit().expect("an accepted kick has a fit");
            let p = predicted[i].expect("filtered");
            ([f.eigenvalue[0] - p[0], f.eigenvalue[1] - p[1]], f.eigenvalue_stderr)
        })
        .unzip();
    for (&i, out) in idx.iter().zip(robust_outliers(&misfits, &stderr)) {
        if let Some(sigmas) = out {
            let measured = kicks[i].chosen_fit().expect("an accepted kick has a fit").eigenvalue;
            kicks[i].rejected = Some(Rejected::Outlier {
                measured,
                predicted: predicted[i].expect("filtered"),
                sigmas,
                max: OUTLIER_SIGMAS,
            });
        }
    }
}
