//! Clock offset of the speed logger (DAQ) to the IMU logger,
//! `t_imu = t_daq + offset`.
//!
//! The frame's yaw rate is tied to speed and steer by rolling without slip:
//! for small angles `yaw' = (v steer + c steer') cos(lambda) / w`, with `c`
//! the trail, `w` the wheelbase and `lambda` the steer-axis tilt (Meijaard et
//! al. 2007, eq. for the rear-frame yaw). With `v` read on the DAQ clock, the
//! relation holds only at the right offset. For each trial offset the
//! coefficients of `v steer` and `steer'` (plus a constant for the slow
//! heading drift of the units) are found by linear least squares, so no
//! geometry is needed; the offset minimising the residual is refined by a
//! parabola, and its standard error is `sqrt(s^2 / k)` with `k` the
//! curvature of the residual sum of squares and `s^2` the residual variance
//! (inflated for autocorrelation). Information comes from the speed changing
//! while the bicycle steers: with a nearly constant speed the profile is flat
//! and the nominal offset is kept with its stated uncertainty.

use super::angles::Angles;
use super::kicks::derivative;
use super::speed::SpeedProfile;

/// The nominal offset is good to +-0.3 s (FORMAT.md): as a uniform prior,
/// standard deviation 0.3 / sqrt(3) s.
pub const NOMINAL_OFFSET_HALF_RANGE: f64 = 0.3;

/// Estimated clock offset.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ClockOffset {
    /// `t_imu - t_daq` (s).
    pub value: f64,
    /// Standard error (s).
    pub stderr: f64,
    /// Whether the data determined it (else the nominal value is kept).
    pub from_data: bool,
}

/// Estimate the offset of one run. `start` is the IMU time from which the
/// orientation output has settled.
pub fn estimate_offset(angles: &Angles, speed: &SpeedProfile, nominal: f64, start: f64) -> ClockOffset {
    let prior = ClockOffset {
        value: nominal,
        stderr: NOMINAL_OFFSET_HALF_RANGE / 3f64.sqrt(),
        from_data: false,
    };
    let t = &angles.t;
    let n = t.len();
    if n < 50 || speed.t.len() < 10 {
        return prior;
    }
    let dt = (t[n - 1] - t[0]) / (n - 1) as f64;
    let h = ((0.05 / dt) as usize).max(1);
    let yaw_rate = derivative(t, &angles.yaw, h);
    let steer_rate = derivative(t, &angles.steer, h);
    let steer = &angles.steer;
    let search = 1.5 * NOMINAL_OFFSET_HALF_RANGE;
    let step = dt.max(0.002);
    let m = (2.0 * search / step).round() as usize;
    let offsets: Vec<f64> = (0..=m).map(|i| nominal - search + i as f64 * step).collect();
    // Samples usable at every trial offset.
    let usable: Vec<usize> = (0..n)
        .filter(|&k| {
            t[k] >= start
                && offsets
                    .iter()
                    .step_by(m.max(1))
                    .all(|o| speed.at(t[k] - o).is_some_and(|(v, _)| v > 0.5))
        })
        .filter(|&k| speed.at(t[k] - nominal).is_some())
        .collect();
    if usable.len() < 50 {
        return prior;
    }
    let ssr_at = |o: f64| -> Option<(f64, Vec<f64>)> {
        let mut a = nalgebra::Matrix3::zeros();
        let mut b = nalgebra::Vector3::zeros();
        let mut rows = Vec::with_capacity(usable.len());
        for &k in &usable {
            let (v, _) = speed.at(t[k] - o)?;
            let x = nalgebra::Vector3::new(v * steer[k], steer_rate[k], 1.0);
            a += x * x.transpose();
            b += x * yaw_rate[k];
            rows.push((x, yaw_rate[k]));
        }
        let sol = a.cholesky()?.solve(&b);
        let r: Vec<f64> = rows.iter().map(|(x, y)| y - x.dot(&sol)).collect();
        Some((r.iter().map(|e| e * e).sum(), r))
    };
    let mut prof: Vec<(f64, f64)> = Vec::new();
    for &o in &offsets {
        if let Some((s, _)) = ssr_at(o) {
            prof.push((o, s));
        }
    }
    if prof.len() < 5 {
        return prior;
    }
    let (ib, _) = prof
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .map(|(i, p)| (i, *p))
        .unwrap_or((0, (nominal, 0.0)));
    if ib == 0 || ib + 1 >= prof.len() {
        return prior;
    }
    // Parabola through a neighbourhood of the minimum.
    let w = 5.min(ib).min(prof.len() - 1 - ib);
    let pts = &prof[ib - w..=ib + w];
    let (x0, _) = prof[ib];
    let mut ata = nalgebra::Matrix3::zeros();
    let mut atb = nalgebra::Vector3::zeros();
    for &(o, s) in pts {
        let d = o - x0;
        let x = nalgebra::Vector3::new(1.0, d, d * d);
        ata += x * x.transpose();
        atb += x * s;
    }
    let Some(ch) = ata.cholesky() else { return prior };
    let c = ch.solve(&atb);
    if !(c[2] > 0.0) {
        return prior;
    }
    let best = x0 - c[1] / (2.0 * c[2]);
    let Some((ssr, r)) = ssr_at(best) else { return prior };
    let nn = r.len() as f64;
    let rho = {
        let c0: f64 = r.iter().map(|x| x * x).sum();
        let c1: f64 = r.windows(2).map(|w| w[0] * w[1]).sum();
        (c1 / c0).clamp(0.0, 0.99)
    };
    let s2 = ssr / (nn - 3.0) * (1.0 + rho) / (1.0 - rho);
    // SSR(o) ~ SSR_min + c2 (o - o*)^2; a change of s^2 is one standard error.
    let stderr = (s2 / c[2]).sqrt();
    if !(stderr.is_finite()) || stderr > prior.stderr || (best - nominal).abs() > search {
        return prior;
    }
    ClockOffset {
        value: best,
        stderr,
        from_data: true,
    }
}
