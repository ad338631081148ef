//! Measured against predicted weave eigenvalues (driven-speed linearization:
//! the canonical matrices at constant forward speed).

use crate::eigen::{eigen_sweep_of, LinearBicycle, Mode};
use serde::Serialize;

/// The model's weave eigenvalue `[real, imag]` (imag > 0) at speed `v`
/// (m/s); `None` below the speed where the weave roots become complex.
pub fn predicted_weave(c: &dyn LinearBicycle, v: f64) -> Option<[f64; 2]> {
    let sweep = eigen_sweep_of(c, &[v]).ok()?;
    let p = sweep.points.first()?;
    (0..4)
        .filter(|&k| p.modes[k] == Mode::Weave && p.eigenvalues[k].im > 0.0)
        .map(|k| [p.eigenvalues[k].re, p.eigenvalues[k].im])
        .next()
}

/// The model's `d lambda / d v` of the weave `[real, imag]` ((1/s)/(m/s))
/// at speed `v`, by central differences over 0.01 m/s (one-sided where
/// the weave stops being oscillatory on one side); `None` where the model
/// has no oscillatory weave at `v`.
pub fn weave_slope(c: &dyn LinearBicycle, v: f64) -> Option<[f64; 2]> {
    const H: f64 = 0.01;
    let at = predicted_weave(c, v)?;
    let (lo, hi) = (predicted_weave(c, v - H), predicted_weave(c, v + H));
    let (a, b, dv) = match (lo, hi) {
        (Some(l), Some(h)) => (l, h, 2.0 * H),
        (None, Some(h)) => (at, h, H),
        (Some(l), None) => (l, at, H),
        (None, None) => return None,
    };
    Some([(b[0] - a[0]) / dv, (b[1] - a[1]) / dv])
}

/// Prediction over a speed interval.
#[derive(Clone, Debug, Serialize)]
pub struct Prediction {
    /// Weave eigenvalue at the mean speed.
    pub at_mean_speed: [f64; 2],
    /// Range of the real part over the interval `[low, high]`.
    pub real_range: [f64; 2],
    /// Range of the imaginary part over the interval.
    pub imag_range: [f64; 2],
}

/// Prediction at `mean` and over `[lo, hi]` (m/s).
pub fn predict(c: &dyn LinearBicycle, mean: f64, lo: f64, hi: f64) -> Option<Prediction> {
    let at = predicted_weave(c, mean)?;
    let speeds: Vec<f64> = (0..=10).map(|i| lo + (hi - lo) * i as f64 / 10.0).collect();
    let sweep = eigen_sweep_of(c, &speeds).ok()?;
    let mut re = [f64::INFINITY, f64::NEG_INFINITY];
    let mut im = re;
    for p in &sweep.points {
        for k in 0..4 {
            if p.modes[k] == Mode::Weave && p.eigenvalues[k].im > 0.0 {
                re = [re[0].min(p.eigenvalues[k].re), re[1].max(p.eigenvalues[k].re)];
                im = [im[0].min(p.eigenvalues[k].im), im[1].max(p.eigenvalues[k].im)];
            }
        }
    }
    if !re[0].is_finite() {
        re = [at[0], at[0]];
        im = [at[1], at[1]];
    }
    Some(Prediction {
        at_mean_speed: at,
        real_range: re,
        imag_range: im,
    })
}

/// One row of the residual table.
#[derive(Clone, Debug, Serialize)]
pub struct Residual {
    /// Run (path) and kick time (s).
    pub run: String,
    /// Kick time (s).
    pub kick_time: f64,
    /// Mean speed (m/s).
    pub mean_speed: f64,
    /// Measured `[re, im]`.
    pub measured: [f64; 2],
    /// Standard errors.
    pub stderr: [f64; 2],
    /// Predicted at the mean speed.
    pub predicted: [f64; 2],
    /// `(measured - predicted) / stderr` for real and imaginary parts.
    pub z: [f64; 2],
}
