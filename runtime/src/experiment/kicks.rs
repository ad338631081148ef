//! Finding the kicks and the free-response window after each, from the data.
//!
//! A kick is a short lateral impulse: the roll rate jumps within a few tens
//! of milliseconds, far faster than the weave oscillation changes it. The
//! detector is the second difference of the (lightly smoothed) roll rate at
//! the kick's time scale, which cancels the response's own slope; its noise
//! level is the robust spread over the whole record (kicks are rare), and a
//! kick is where it exceeds [`KickOptions::threshold_sigmas`] of that spread.
//!
//! The window starts when the forcing is over and ends at the first of: the
//! next kick, a gap in the record, the end of the record, a fall (roll beyond
//! [`KickOptions::fall_angle`]), a steer stop (steer at the extreme of the
//! record and not moving), and the end of the oscillation (the last
//! half-cycle whose roll-rate peak stands above both the noise and
//! [`KickOptions::min_relative_amplitude`] of the first peak, with half
//! periods consistent with the first ones; after it, drift or capsize
//! dominates).

use super::angles::{median, robust_sigma};
use super::records::Gap;

/// Options of the kick detector and window selection. Physical time scales,
/// not tuned to a file.
#[derive(Clone, Debug, serde::Serialize)]
pub struct KickOptions {
    /// Rise time of a kick (s): the scale of the second difference.
    pub rise_time: f64,
    /// Smoothing of the roll rate (s, moving average; ~ a 10 Hz low-pass
    /// at 0.05 s, as Kooijman et al. filter).
    pub smoothing: f64,
    /// Detection threshold in robust standard deviations of the detector.
    pub threshold_sigmas: f64,
    /// Roll angle beyond which the linear response is over (rad).
    pub fall_angle: f64,
    /// Half-cycles with a roll-rate peak below this fraction of the first
    /// peak end the window.
    pub min_relative_amplitude: f64,
    /// Keep only the strongest kick (thesis-style runs have one).
    pub single: bool,
    /// Largest relative change of speed over a window: beyond it even the
    /// eigenvalue linear in speed is a poor description (the weave
    /// frequency of the thesis bicycle grows from 3.7 to 10 rad/s between
    /// 3.4 and 6.4 m/s). Shorter windows cost more in precision than the
    /// speed change costs in bias on `shared/data/dev`.
    pub max_speed_change: f64,
}

impl Default for KickOptions {
    fn default() -> Self {
        KickOptions {
            rise_time: 0.06,
            smoothing: 0.05,
            threshold_sigmas: 10.0,
            fall_angle: 0.5,
            min_relative_amplitude: 0.15,
            single: false,
            max_speed_change: 0.3,
        }
    }
}

/// Why a window ends.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WindowEnd {
    /// The oscillation decayed into noise or drift.
    Decayed,
    /// The next kick.
    NextKick,
    /// A gap in the record.
    Gap,
    /// End of the record.
    RecordEnd,
    /// Roll beyond the fall angle.
    Fall,
    /// Steer at its stop.
    SteerStop,
    /// The roll rate stopped oscillating (capsize drift).
    Drift,
    /// The speed changed by more than [`KickOptions::max_speed_change`].
    SpeedChange,
}

/// One detected kick and its free-response window (sample indices, end
/// exclusive).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Kick {
    /// Time of the roll-rate jump (s).
    pub time: f64,
    /// Index of the kick.
    pub index: usize,
    /// Roll-rate jump (rad/s).
    pub jump: f64,
    /// Window start index.
    pub start: usize,
    /// Window end index (exclusive).
    pub end: usize,
    /// Why it ends.
    pub end_reason: WindowEnd,
    /// Number of oscillation half-cycles in the window.
    pub half_cycles: usize,
}

/// Centered moving average over `2 h + 1` samples (shorter at the ends).
pub fn moving_average(x: &[f64], h: usize) -> Vec<f64> {
    let n = x.len();
    let mut c = vec![0.0; n + 1];
    for k in 0..n {
        c[k + 1] = c[k] + x[k];
    }
    (0..n)
        .map(|k| {
            let a = k.saturating_sub(h);
            let b = (k + h + 1).min(n);
            (c[b] - c[a]) / (b - a) as f64
        })
        .collect()
}

/// Derivative by a local linear fit over `2 h + 1` samples.
pub fn derivative(t: &[f64], x: &[f64], h: usize) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|k| {
            let a = k.saturating_sub(h);
            let b = (k + h + 1).min(n);
            let m = (b - a) as f64;
            let tm = t[a..b].iter().sum::<f64>() / m;
            let xm = x[a..b].iter().sum::<f64>() / m;
            let (mut num, mut den) = (0.0, 0.0);
            for j in a..b {
                num += (t[j] - tm) * (x[j] - xm);
                den += (t[j] - tm).powi(2);
            }
            if den > 0.0 {
                num / den
            } else {
                0.0
            }
        })
        .collect()
}

/// Detect kicks and windows. `t` in s, `roll` (rad), `roll_rate` (rad/s),
/// optional `steer` (rad), `gaps` of the record.
pub fn find_kicks(
    t: &[f64],
    roll: &[f64],
    roll_rate: &[f64],
    steer: Option<&[f64]>,
    gaps: &[Gap],
    opt: &KickOptions,
) -> Vec<Kick> {
    let n = t.len();
    if n < 10 {
        return Vec::new();
    }
    let diffs: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
    let dt = median(&diffs);
    let h = ((opt.smoothing / dt / 2.0).round() as usize).max(1);
    let r = moving_average(roll_rate, h);
    let w = ((opt.rise_time / dt).round() as usize).max(2);
    if n <= 2 * w + 2 {
        return Vec::new();
    }
    let noise = sigma_rate(&r, roll_rate);
    // Change of the smoothed roll rate over the rise time; zero where the
    // stencil crosses a gap.
    let crosses_gap = |a: usize, b: usize| gaps.iter().any(|g| g.start >= t[a] && g.end <= t[b]);
    let mut score = vec![0.0; n];
    for k in 0..n - w {
        if !crosses_gap(k, k + w) && roll[k].abs() < opt.fall_angle {
            score[k] = r[k + w] - r[k];
        }
    }
    // Noise of the score from the high-frequency noise of the rate (the
    // spread of the score itself is inflated by the responses): the
    // difference of two averages of 2h+1 samples.
    let sigma = (noise * (2.0 / (2 * h + 1) as f64).sqrt()).max(1e-12);
    let mut thr = opt.threshold_sigmas * sigma;
    // A change already under way where the record (or the search after the
    // release) begins is the launch or the hand letting go, not a kick.
    if let Some(quiet) = score.iter().position(|s| s.abs() <= thr) {
        score[..quiet].iter_mut().for_each(|s| *s = 0.0);
    }
    let detection = thr;
    if opt.single {
        // One kick: the first change of at least half the largest one (the
        // response that follows changes the rate less than the kick did).
        // The record is mostly response here, so the robust spread is
        // inflated: only ask the kick to stand out of it by a few.
        let max = score.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        if max < thr {
            return Vec::new();
        }
        thr = 0.5 * max;
    }
    let mut out = Vec::new();
    let mut pos = 0;
    // In a run of one kick, a change after which the record holds no free
    // response (not one half-cycle of the roll rate) cannot be the kick: a
    // fall (its change can exceed twice the kick's) or a launch's last
    // wobble (more than half a small kick) that decays at once. The next
    // change standing out of the noise (the detection threshold) is tried
    // instead, and the first choice is kept only if none has a response.
    let mut first_choice: Option<Kick> = None;
    while pos < n - w {
        let Some(first) = (pos..n - w).find(|&k| score[k].abs() > thr) else {
            break;
        };
        // The group of this change and its peak.
        let mut last = first;
        while last + 1 < n - w && score[last + 1].abs() > thr && score[last + 1].signum() == score[first].signum() {
            last += 1;
        }
        let peak = (first..=last)
            .max_by(|&i, &j| score[i].abs().total_cmp(&score[j].abs()))
            .unwrap_or(first);
        let jump = score[peak];
        let sign = jump.signum();
        // Onset: walk back while the change is at least half the peak's.
        let mut onset = peak;
        while onset > pos && (score[onset - 1] * sign) >= 0.5 * jump.abs() {
            onset -= 1;
        }
        // The kick: steepest rise within the change.
        let kick = (onset..(onset + 2 * w).min(n - 1))
            .max_by(|&i, &j| {
                let d = |k: usize| sign * (r[(k + 1).min(n - 1)] - r[k.saturating_sub(1)]);
                d(i).total_cmp(&d(j))
            })
            .unwrap_or(onset);
        // The forcing is over when the roll rate stops rising.
        let mut start = kick;
        while start + 1 < n && sign * (r[start + 1] - r[start]) > 0.0 && start < kick + 4 * w {
            start += 1;
        }
        let mut k = window(t, roll, &r, steer, gaps, kick, start, sigma, opt);
        k.jump = jump;
        pos = k.end.max(start + w);
        if opt.single {
            if k.half_cycles > 0 {
                out.push(k);
                break;
            }
            // No response after it: try the changes beyond the detection
            // threshold, from the record's start, other than this one.
            score[first..=last].iter_mut().for_each(|s| *s = 0.0);
            if first_choice.is_none() {
                first_choice = Some(k);
                thr = detection;
                pos = 0;
            }
            continue;
        }
        out.push(k);
    }
    if opt.single && out.is_empty() {
        out.extend(first_choice);
    }
    // A later kick bounds the window of the one before.
    for i in 1..out.len() {
        let next_onset = out[i].index.saturating_sub(w);
        if next_onset < out[i - 1].end {
            out[i - 1].end = next_onset.max(out[i - 1].start);
            out[i - 1].end_reason = WindowEnd::NextKick;
        }
    }
    out
}

/// Why [`find_kicks`] found no kick in a record, in words a user can act
/// on: too short a record for the detector's stencil, a roll rate that
/// never changes (a frozen sensor), or no jump standing out of the noise
/// (a record of noise alone, or a rate or time unit that makes the kick's
/// time scale wrong).
pub fn no_kick_reason(t: &[f64], roll_rate: &[f64], opt: &KickOptions) -> String {
    let n = t.len();
    let span = match (t.first(), t.last()) {
        (Some(a), Some(b)) => b - a,
        _ => 0.0,
    };
    if n >= 2 {
        let diffs: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        let dt = median(&diffs);
        let w = ((opt.rise_time / dt).round() as usize).max(2);
        if n < 10 || n <= 2 * w + 2 {
            return format!(
                "the record holds {n} samples over {span:.3} s, too few to tell a kick (a rise of {} s) from the response after it",
                opt.rise_time
            );
        }
    } else {
        return format!("the record holds {n} sample(s): nothing to find a kick in");
    }
    // Below a micro-radian per second the rate is rounding, not motion.
    let (lo, hi) = roll_rate
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &x| {
            (lo.min(x), hi.max(x))
        });
    if !(hi - lo > 1e-6) {
        return "the roll rate never changes (a frozen sensor, or a run at rest)".to_string();
    }
    format!(
        "no jump of the roll rate stands {} noise levels out of the record ({span:.1} s, {n} samples): a record of noise alone, no kick given, or times in other units than seconds",
        opt.threshold_sigmas
    )
}

/// Noise of the roll rate: robust spread of raw minus smoothed.
fn sigma_rate(smooth: &[f64], raw: &[f64]) -> f64 {
    let d: Vec<f64> = raw.iter().zip(smooth).map(|(a, b)| a - b).collect();
    robust_sigma(&d).max(1e-12)
}

#[allow(clippy::too_many_arguments)]
fn window(
    t: &[f64],
    roll: &[f64],
    r: &[f64],
    steer: Option<&[f64]>,
    gaps: &[Gap],
    kick: usize,
    start: usize,
    noise: f64,
    opt: &KickOptions,
) -> Kick {
    let n = t.len();
    let m = ((opt.rise_time / (t[1] - t[0]).max(1e-9)).round() as usize).max(2);
    let mut lim = (n, WindowEnd::RecordEnd);
    fn bound(lim: &mut (usize, WindowEnd), idx: usize, why: WindowEnd) {
        if idx < lim.0 {
            *lim = (idx, why);
        }
    }
    if let Some(g) = gaps.iter().find(|g| g.end > t[start]) {
        bound(&mut lim, t.partition_point(|&x| x <= g.start), WindowEnd::Gap);
    }
    if let Some(k) = (start..n).find(|&k| roll[k].abs() > opt.fall_angle) {
        bound(&mut lim, k, WindowEnd::Fall);
    }
    if let Some(s) = steer {
        // Steer stop: within 2 % of the largest steer of the record (and
        // beyond 20 deg, far outside a weave response), pinned for three
        // rise times (a smooth extreme of an oscillation turns back sooner).
        let ext = s.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let pinned = |k: usize| s[k].abs() > 0.98 * ext;
        if ext > 0.35 {
            if let Some(k) = (start..n.saturating_sub(3 * m)).find(|&k| (k..k + 3 * m).all(pinned)) {
                bound(&mut lim, k, WindowEnd::SteerStop);
            }
        }
    }
    let (mut end, mut reason) = lim;
    // Half-cycles of the roll rate after the start: zero crossings with
    // hysteresis (the rate must leave a band of two noise levels on the
    // other side), so noise near zero does not split a half-cycle.
    let band = 2.0 * noise;
    let mut crossings = vec![start];
    let mut state = r[start].signum();
    let mut last_zero = start;
    for k in start + 1..end {
        if r[k - 1].signum() != r[k].signum() {
            last_zero = k;
        }
        if state != 0.0 && r[k] * state < -band {
            crossings.push(last_zero);
            state = -state;
        }
    }
    let mut half_cycles = 0;
    let mut first_peak = 0.0f64;
    let mut prev_peak = 0.0f64;
    let mut first_half = 0.0;
    let mut last_good = start;
    let mut stopped = false;
    for c in crossings.windows(2) {
        let (c0, c1) = (c[0], c[1]);
        let pk = r[c0..c1].iter().fold(0.0f64, |x, y| x.max(y.abs()));
        let half = t[c1] - t[c0];
        if half_cycles == 0 {
            first_peak = pk;
        } else if half_cycles == 1 {
            first_half = half;
        } else if first_half > 0.0 && !(half > 0.5 * first_half && half < 2.0 * first_half) {
            stopped = true;
            break;
        }
        // Decayed into noise or below a fraction of the first peak; or
        // forced again (a peak twice the one before).
        if pk < (3.0 * noise).max(opt.min_relative_amplitude * first_peak) || (half_cycles > 0 && pk > 2.0 * prev_peak)
        {
            stopped = true;
            break;
        }
        prev_peak = pk;
        half_cycles += 1;
        last_good = c1;
    }
    if !stopped && half_cycles >= 2 {
        // No crossing for long after the last one: drift dominates.
        let tail = crossings.last().copied().unwrap_or(start);
        if first_half > 0.0 && t[end - 1] - t[tail] > 2.0 * first_half {
            end = last_good;
            reason = WindowEnd::Drift;
        }
    }
    if stopped && last_good < end {
        end = last_good;
        reason = WindowEnd::Decayed;
    }
    Kick {
        time: t[kick],
        index: kick,
        jump: 0.0,
        start,
        end: end.max(start),
        end_reason: reason,
        half_cycles,
    }
}
