//! Clock offset of the speed logger (DAQ) to the IMU logger,
//! `t_imu = t_daq + offset`.
//!
//! Rolling without slip ties the frame's heading to the distance travelled:
//! for small angles `yaw' = (v steer + c steer') cos(lambda) / w` (Meijaard
//! et al. 2007, the rear frame's yaw rate; `c` trail, `w` wheelbase,
//! `lambda` steer-axis tilt). Integrated over time it reads
//!
//! `yaw(t) = a int steer ds + b steer + c s + d + e t + f roll`
//!
//! with `s(t)` the distance travelled, read from the reed switch on the DAQ
//! clock. The heading is integrated rather than the yaw rate differentiated,
//! because differencing the orientation noise swamps the signal. The other
//! terms: `c s` a residual steer offset (a steer misalignment makes a steady
//! turn per metre), `d + e t` the units' slow heading drift, and `f roll`
//! because the sensor's heading moves with roll (its x axis is pitched
//! about 18 deg up from the horizon). No geometry is needed: the
//! coefficients come from linear least squares at each trial offset, and
//! the offset minimising the residual is refined by a parabola. Its standard
//! error is `sqrt(s^2 / k)` with `k` the curvature of the residual sum of
//! squares and `s^2` the residual variance (inflated for autocorrelation).
//! Information comes from the speed changing while the bicycle steers (the
//! launch, the decay after release); when it is too weak the nominal offset
//! is kept with its stated uncertainty.

use super::angles::Angles;
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

impl ClockOffset {
    /// The nominal offset (s), not determined by the data: its standard
    /// error is that of a uniform error within the +-0.3 s bound.
    pub fn nominal(value: f64) -> Self {
        ClockOffset {
            value,
            stderr: NOMINAL_OFFSET_HALF_RANGE / 3f64.sqrt(),
            from_data: false,
        }
    }
}

/// A fall ends the usable record: the bicycle lies on the ground from the
/// first roll beyond 45 deg (FORMAT.md's criterion; rad).
const MAX_ROLL: f64 = std::f64::consts::FRAC_PI_4;

/// Estimate the offset of one run. `start` is the IMU time from which the
/// orientation output has settled.
pub fn estimate_offset(angles: &Angles, speed: &SpeedProfile, nominal: f64, start: f64) -> ClockOffset {
    let prior = ClockOffset::nominal(nominal);
    let t = &angles.t;
    let n = t.len();
    if n < 50 {
        return prior;
    }
    // Distance travelled in magnet spacings (the regression's coefficients
    // absorb the scale): the pulse count, linear between pulses, up to the
    // first gap in the switch record (pulses cannot be counted across it).
    // Before the first pulse the wheel is taken at rest (it has turned less
    // than one spacing). Spacing errors (~0.1 %) are negligible here.
    let pulses: Vec<f64> = speed
        .pulses
        .iter()
        .zip(&speed.pulse_segment)
        .take_while(|(_, &s)| s == 0)
        .map(|(&p, _)| p)
        .collect();
    if pulses.len() < 10 {
        return prior;
    }
    let distance = |x: f64| -> Option<f64> {
        if x <= pulses[0] {
            return Some(0.0);
        }
        if x.is_nan() || x > pulses[pulses.len() - 1] {
            return None;
        }
        let k = pulses.partition_point(|&y| y <= x).clamp(1, pulses.len() - 1);
        Some((k - 1) as f64 + (x - pulses[k - 1]) / (pulses[k] - pulses[k - 1]))
    };
    let dt = (t[n - 1] - t[0]) / (n - 1) as f64;
    let search = 1.5 * NOMINAL_OFFSET_HALF_RANGE;
    let step = dt.max(0.002);
    let m = (2.0 * search / step).round() as usize;
    let offsets: Vec<f64> = (0..=m).map(|i| nominal - search + i as f64 * step).collect();
    // Samples usable at every trial offset: settled, before a fall, with
    // the distance known at both ends of the search.
    let fall = (0..n)
        .find(|&k| t[k] >= start && angles.roll[k].abs() > MAX_ROLL)
        .unwrap_or(n);
    let usable: Vec<usize> = (0..fall)
        .filter(|&k| {
            t[k] >= start && distance(t[k] - nominal + search).is_some() && distance(t[k] - nominal - search).is_some()
        })
        .collect();
    if usable.len() < 50 {
        return prior;
    }
    let fit = |samples: &[usize]| profile_fit(angles, samples, &distance, &offsets);
    let Some((best, stderr)) = fit(&usable) else {
        return prior;
    };
    // Consistency. In a free response roll and steer move in one mode's
    // fixed ratio, so the heading terms are nearly collinear there and an
    // offset found from it rests on small differences that a heading drift
    // can fake. The launch (speed rising while the bicycle steers) is what
    // determines the offset: the first half of the record, which holds it,
    // must determine it on its own, or the nominal offset is kept. If the
    // second half determines it too, a disagreement between the halves
    // scales the standard error by their Birge ratio sqrt(chi^2).
    let half = usable.len() / 2;
    let Some((o1, s1)) = fit(&usable[..half]).filter(|&(_, s)| s < prior.stderr) else {
        return prior;
    };
    let birge = match fit(&usable[half..]) {
        Some((o2, s2)) => ((o1 - o2).powi(2) / (s1 * s1 + s2 * s2)).sqrt().max(1.0),
        None => 1.0,
    };
    let stderr = stderr * birge;
    if !(stderr.is_finite()) || stderr > prior.stderr || (best - nominal).abs() > search {
        return prior;
    }
    ClockOffset {
        value: best,
        stderr,
        from_data: true,
    }
}

/// The offset minimising the residual of the heading relation over the IMU
/// samples `usable` (in time order), and its standard error; `None` when
/// the residual has no interior minimum over `offsets`.
fn profile_fit(
    angles: &Angles,
    usable: &[usize],
    distance: &dyn Fn(f64) -> Option<f64>,
    offsets: &[f64],
) -> Option<(f64, f64)> {
    let t = &angles.t;
    if usable.len() < 50 {
        return None;
    }
    let t_mean = usable.iter().map(|&k| t[k]).sum::<f64>() / usable.len() as f64;
    let ssr_at = |o: f64| -> Option<(f64, Vec<f64>)> {
        let mut a = nalgebra::SMatrix::<f64, 6, 6>::zeros();
        let mut b = nalgebra::SVector::<f64, 6>::zeros();
        let mut rows = Vec::with_capacity(usable.len());
        let mut int_steer = 0.0;
        let mut s_prev: Option<f64> = None;
        for &k in usable {
            let s = distance(t[k] - o)?;
            if let Some(sp) = s_prev {
                int_steer += angles.steer[k] * (s - sp);
            }
            s_prev = Some(s);
            let x =
                nalgebra::SVector::<f64, 6>::from([int_steer, angles.steer[k], s, 1.0, t[k] - t_mean, angles.roll[k]]);
            a += x * x.transpose();
            b += x * angles.yaw[k];
            rows.push((x, angles.yaw[k]));
        }
        let sol = a.cholesky()?.solve(&b);
        let r: Vec<f64> = rows.iter().map(|(x, y)| y - x.dot(&sol)).collect();
        Some((r.iter().map(|e| e * e).sum(), r))
    };
    let prof: Vec<(f64, f64)> = offsets.iter().filter_map(|&o| ssr_at(o).map(|(s, _)| (o, s))).collect();
    if prof.len() < 5 {
        return None;
    }
    let ib = prof
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .map(|(i, _)| i)?;
    if ib == 0 || ib + 1 >= prof.len() {
        return None;
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
    let c = ata.cholesky()?.solve(&atb);
    if !(c[2] > 0.0) {
        return None;
    }
    let best = x0 - c[1] / (2.0 * c[2]);
    let (ssr, r) = ssr_at(best)?;
    let nn = r.len() as f64;
    // The heading drift is a random walk, not a line: residuals stay
    // correlated over seconds, so the lag-one correlation understates it.
    // Integrated autocorrelation time `1 + 2 sum rho_k`, summed while the
    // correlations stay positive (Geyer's initial positive sequence).
    let c0: f64 = r.iter().map(|x| x * x).sum();
    let mut tau_int = 1.0;
    for lag in 1..r.len() / 4 {
        let rho = r.iter().zip(&r[lag..]).map(|(a, b)| a * b).sum::<f64>() / c0;
        if rho <= 0.0 {
            break;
        }
        tau_int += 2.0 * rho;
    }
    let s2 = ssr / (nn - 6.0) * tau_int;
    // SSR(o) ~ SSR_min + c2 (o - o*)^2; a change of s^2 is one standard error.
    let stderr = (s2 / c[2]).sqrt();
    stderr.is_finite().then_some((best, stderr))
}
