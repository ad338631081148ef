//! Whether what the identified model leaves in the time series follows the
//! motion (issue 37, item 1): a force the model lacks acts through the
//! states, so its residual correlates with them, while sensor noise does
//! not. Each channel's residual (measured minus simulated, roll and steer,
//! every sample of every kick) is regressed on the simulated states: the
//! roll channel and its rate, the steer angle and its rate (rates by
//! central differences of the simulated channels). An F test with the
//! effective sample size of correlated samples (`n (1 - rho) / (1 + rho)`,
//! `rho` the lag-1 autocorrelation of the regression's residual within
//! kicks) asks whether the states explain more of it than chance would.
//! The residual's own lag-1 autocorrelation is reported as its whiteness:
//! white sensor noise gives about zero, a missing force's smooth error
//! close to one.

use nalgebra::{DMatrix, DVector};
use serde::Serialize;
use statrs::distribution::{ContinuousCDF, FisherSnedecor};

/// A measured channel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Channel {
    /// The roll channel (the roll angle, or the roll rate of a log).
    Roll,
    Steer,
}

/// A regressor: a simulated state.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StateSignal {
    Roll,
    RollRate,
    Steer,
    SteerRate,
}

/// One kick's channels at its sample times (s): measured and simulated
/// with the identified model, roll channel then steer.
pub struct KickSeries<'a> {
    pub t: &'a [f64],
    pub measured: [&'a [f64]; 2],
    pub simulated: [&'a [f64]; 2],
}

/// The regression of one channel's residual on the states.
#[derive(Clone, Debug, Serialize)]
pub struct StateCorrelation {
    pub channel: Channel,
    /// Samples pooled over the kicks, and their effective number.
    pub samples: usize,
    pub effective_samples: f64,
    /// Share of the residual's variance the states explain.
    pub r_squared: f64,
    pub f: f64,
    pub dof: (f64, f64),
    pub p_value: f64,
    /// At the 1 % level.
    pub significant: bool,
    /// Each state's coefficient per standard deviation of the state, in
    /// the channel's unit (rad or rad/s), with its standard error (from
    /// the effective sample size), largest magnitude first. Within one
    /// kick the states of a single decaying mode are nearly collinear, so
    /// the states are told apart only across kicks of different mode
    /// shapes (speeds): the standard errors say how far.
    pub coefficients: Vec<(StateSignal, f64, f64)>,
    /// Lag-1 autocorrelation of the residual itself, within kicks.
    pub whiteness_lag1: f64,
}

/// The F test's level.
pub const LEVEL: f64 = 0.01;

/// Central differences (one-sided at the ends).
fn rate(t: &[f64], x: &[f64]) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            if b > a && t[b] > t[a] {
                (x[b] - x[a]) / (t[b] - t[a])
            } else {
                0.0
            }
        })
        .collect()
}

/// Lag-1 autocorrelation of `r`, pooled within the groups `starts..ends`.
fn lag1(r: &[f64], bounds: &[(usize, usize)]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for &(a, b) in bounds {
        let m = r[a..b].iter().sum::<f64>() / (b - a).max(1) as f64;
        for k in a..b {
            den += (r[k] - m).powi(2);
            if k > a {
                num += (r[k] - m) * (r[k - 1] - m);
            }
        }
    }
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// The regression of each channel's residual on the states; `None` for a
/// channel with fewer than 20 finite samples.
pub fn state_correlation(kicks: &[KickSeries]) -> Vec<StateCorrelation> {
    let signals = [
        StateSignal::Roll,
        StateSignal::RollRate,
        StateSignal::Steer,
        StateSignal::SteerRate,
    ];
    let mut out = Vec::new();
    for (c, channel) in [(0, Channel::Roll), (1, Channel::Steer)] {
        let mut y = Vec::new();
        let mut x: Vec<[f64; 4]> = Vec::new();
        let mut bounds = Vec::new();
        for k in kicks {
            let rates = [rate(k.t, k.simulated[0]), rate(k.t, k.simulated[1])];
            let start = y.len();
            for i in 0..k
                .t
                .len()
                .min(k.measured[c].len())
                .min(k.simulated[0].len())
                .min(k.simulated[1].len())
            {
                let row = [k.simulated[0][i], rates[0][i], k.simulated[1][i], rates[1][i]];
                let e = k.measured[c][i] - k.simulated[c][i];
                if e.is_finite() && row.iter().all(|v| v.is_finite()) {
                    y.push(e);
                    x.push(row);
                }
            }
            if y.len() > start {
                bounds.push((start, y.len()));
            }
        }
        let n = y.len();
        if n < 20 {
            continue;
        }
        // Standardized states and a constant.
        let mut design = DMatrix::zeros(n, 5);
        let mut scale = [1.0; 4];
        for j in 0..4 {
            let m = x.iter().map(|r| r[j]).sum::<f64>() / n as f64;
            let sd = (x.iter().map(|r| (r[j] - m).powi(2)).sum::<f64>() / n as f64).sqrt();
            scale[j] = if sd > 0.0 { sd } else { 1.0 };
            for i in 0..n {
                design[(i, j)] = (x[i][j] - m) / scale[j];
            }
        }
        for i in 0..n {
            design[(i, 4)] = 1.0;
        }
        let yv = DVector::from_vec(y.clone());
        let ata = design.tr_mul(&design);
        let Some(inv) = ata.clone().try_inverse() else {
            continue;
        };
        let beta = &inv * design.tr_mul(&yv);
        let resid = &yv - &design * &beta;
        let mean = yv.mean();
        let sst = yv.iter().map(|v| (v - mean).powi(2)).sum::<f64>();
        let sse = resid.norm_squared();
        let r2 = if sst > 0.0 { 1.0 - sse / sst } else { 0.0 };
        let rho = lag1(resid.as_slice(), &bounds).clamp(0.0, 0.999);
        let n_eff = (n as f64 * (1.0 - rho) / (1.0 + rho)).max(6.0);
        let (p, dof2) = (4.0, (n_eff - 5.0).max(1.0));
        let f = (r2 / p) / ((1.0 - r2).max(1e-300) / dof2);
        let p_value = FisherSnedecor::new(p, dof2).map_or(f64::NAN, |d| d.sf(f));
        let s2 = sse / dof2;
        let mut coefficients: Vec<(StateSignal, f64, f64)> = (0..4)
            .map(|j| (signals[j], beta[j], (inv[(j, j)] * s2 * n as f64 / n_eff).sqrt()))
            .collect();
        coefficients.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        out.push(StateCorrelation {
            channel,
            samples: n,
            effective_samples: n_eff,
            r_squared: r2,
            f,
            dof: (p, dof2),
            p_value,
            significant: p_value < LEVEL,
            coefficients,
            whiteness_lag1: lag1(&y, &bounds),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A decaying weave-like oscillation sampled at 100 Hz for 3 s.
    fn motion() -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..300).map(|k| k as f64 * 0.01).collect();
        let roll = t.iter().map(|&t| 0.05 * (-0.5 * t).exp() * (6.0 * t).sin()).collect();
        let steer = t
            .iter()
            .map(|&t| 0.03 * (-0.5 * t).exp() * (6.0 * t + 1.0).sin())
            .collect();
        (t, roll, steer)
    }

    fn noise(n: usize, seed: u64, sd: f64) -> Vec<f64> {
        let mut s = seed | 1;
        (0..n)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                sd * 12f64.sqrt() * ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
            })
            .collect()
    }

    #[test]
    fn a_residual_following_the_motion_correlates_with_the_states_and_white_noise_does_not() {
        let (t, roll, steer) = motion();
        let steer_rate = rate(&t, &steer);
        let noisy =
            |x: &[f64], seed| -> Vec<f64> { x.iter().zip(noise(x.len(), seed, 0.002)).map(|(a, b)| a + b).collect() };
        // The measured roll lags what the model gives by a force from the
        // steer rate; the steer is measured as simulated, plus noise.
        let roll_missing: Vec<f64> = roll.iter().zip(&steer_rate).map(|(r, d)| r + 0.02 * d).collect();
        let (m_roll, m_steer) = (noisy(&roll_missing, 3), noisy(&steer, 5));
        let kick = KickSeries {
            t: &t,
            measured: [&m_roll, &m_steer],
            simulated: [&roll, &steer],
        };
        let c = state_correlation(&[kick]);
        let (roll_c, steer_c) = (&c[0], &c[1]);
        assert_eq!(roll_c.channel, Channel::Roll);
        assert!(roll_c.significant && roll_c.r_squared > 0.2, "{roll_c:?}");
        assert!(roll_c.whiteness_lag1 > 0.2, "{roll_c:?}");
        // White noise alone: no correlation, lag-1 autocorrelation near 0.
        assert!(!steer_c.significant, "{steer_c:?}");
        assert!(steer_c.whiteness_lag1.abs() < 0.2, "{steer_c:?}");
    }
}
