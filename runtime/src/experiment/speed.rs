//! Forward speed from the rear-wheel reed switch.
//!
//! Edges by hysteresis between two thresholds set from the record's own open
//! and closed levels; contact bounce (a short opening right after closing)
//! is merged; each pulse is placed at its centre (magnet nearest the switch).
//! Between consecutive pulses the wheel turns one magnet spacing; spacing
//! errors repeat every wheel turn and are estimated over the run; a local
//! linear fit over two wheel turns gives the smoothed speed `v(t)` and its
//! standard error. Times are on the DAQ clock.

use super::angles::{median, robust_sigma};
use super::records::{RunMeta, SwitchRecord};

/// Speed record of one run.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SpeedProfile {
    /// Pulse centres (s, DAQ clock).
    pub pulses: Vec<f64>,
    /// Segment of each pulse (a gap in the record starts a new one).
    pub pulse_segment: Vec<usize>,
    /// Mid-times of the magnet-to-magnet intervals (s).
    pub t: Vec<f64>,
    /// Per-interval speed with the estimated magnet spacing (m/s).
    pub v_interval: Vec<f64>,
    /// Smoothed speed at `t` (m/s).
    pub v: Vec<f64>,
    /// Standard error of `v` (m/s).
    pub v_stderr: Vec<f64>,
    /// Magnet spacing as a fraction of the circumference (sums to 1), from
    /// the pulse after magnet k to the next.
    pub spacing: Vec<f64>,
    /// Standard error of each spacing fraction.
    pub spacing_stderr: Vec<f64>,
    /// Switch thresholds (V): opening, closing.
    pub thresholds: (f64, f64),
    /// Bounces merged into their pulse.
    pub bounces: usize,
    /// Whether interval `k` follows a gap in the record (not used for speed).
    pub segment_start: Vec<bool>,
}

impl SpeedProfile {
    /// Smoothed speed and its standard error at DAQ time `t` (linear between
    /// interval mid-times; `None` outside the record or across a gap).
    pub fn at(&self, t: f64) -> Option<(f64, f64)> {
        let n = self.t.len();
        if n == 0 || t < self.t[0] || t > self.t[n - 1] {
            return None;
        }
        let k = self.t.partition_point(|&x| x <= t);
        if k == 0 {
            return Some((self.v[0], self.v_stderr[0]));
        }
        if k >= n {
            return Some((self.v[n - 1], self.v_stderr[n - 1]));
        }
        if self.segment_start[k] {
            return None;
        }
        let w = (t - self.t[k - 1]) / (self.t[k] - self.t[k - 1]);
        Some((
            self.v[k - 1] + w * (self.v[k] - self.v[k - 1]),
            self.v_stderr[k - 1].max(self.v_stderr[k]),
        ))
    }
}

/// Pulses and bounce count from a voltage record.
fn detect_pulses(sw: &SwitchRecord) -> (Vec<(usize, usize)>, (f64, f64), usize) {
    // The open level is the record's usual one (magnets pass the switch a
    // small part of each turn), its median; unless the wheel stopped with a
    // magnet at the switch and the logger went on: the record then sits
    // mostly closed, its median is the closed level, and the open one is
    // the median of the samples below the middle of the record's span. The
    // span runs from the tenth lowest to the tenth highest sample: levels
    // the switch held (a pulse lasts several samples, and a run has
    // hundreds), not a spike, however long the wheel rested.
    let mut sorted: Vec<f64> = sw.volts.iter().copied().filter(|v| v.is_finite()).collect();
    sorted.sort_by(|a, b| a.total_cmp(b));
    if sorted.is_empty() {
        return (Vec::new(), (f64::NAN, f64::NAN), 0);
    }
    let k = 9.min(sorted.len() / 2);
    let (bottom, top) = (sorted[k], sorted[sorted.len() - 1 - k]);
    let middle = 0.5 * (bottom + top);
    let mut open = median(&sw.volts);
    if open > middle {
        let below = sorted.partition_point(|&v| v < middle);
        open = median(&sorted[..below]);
    }
    drop(sorted);
    // A converter's record of a switch at rest can sit on one value for a
    // long time: its robust spread is then zero, and every sample a step
    // above the open level would count as closed. The noise is taken as at
    // least one step of a 10-bit converter over the record's span, so the
    // closed level is looked for well above the open one.
    let noise = robust_sigma(&sw.volts).max(1e-3 * (top - open)).max(1e-9);
    // Closed level: the median of samples far above the open level.
    let high: Vec<f64> = sw.volts.iter().copied().filter(|&v| v > open + 10.0 * noise).collect();
    if high.len() < 2 {
        return (Vec::new(), (f64::NAN, f64::NAN), 0);
    }
    let closed = median(&high);
    let (lo, hi) = (open + 0.3 * (closed - open), open + 0.6 * (closed - open));
    // Raw closed stretches by hysteresis.
    let mut raw = Vec::new();
    let mut state = false;
    let mut start = 0;
    for (k, &v) in sw.volts.iter().enumerate() {
        if !state && v > hi {
            state = true;
            start = k;
        } else if state && v < lo {
            state = false;
            raw.push((start, k));
        }
    }
    if raw.is_empty() {
        return (raw, (lo, hi), 0);
    }
    // Debounce: an opening shorter than half the typical closed time is a
    // bounce (true openings last the time of a whole magnet spacing).
    let widths: Vec<f64> = raw.iter().map(|(a, b)| (b - a) as f64).collect();
    let typical = median(&widths);
    let mut merged: Vec<(usize, usize)> = Vec::new();
    let mut bounces = 0;
    for &(a, b) in &raw {
        if let Some(last) = merged.last_mut() {
            let opening = (a - last.1) as f64;
            let no_gap = !sw.gaps.iter().any(|g| g.start >= sw.t[last.1] && g.end <= sw.t[a]);
            if no_gap && opening < (0.5 * typical).max(1.5) {
                last.1 = b;
                bounces += 1;
                continue;
            }
        }
        merged.push((a, b));
    }
    (merged, (lo, hi), bounces)
}

/// Local linear fit with tricube weights over the `half` nearest intervals
/// on each side; returns value and standard error at each point.
fn smooth(t: &[f64], y: &[f64], seg: &[usize], half: usize) -> (Vec<f64>, Vec<f64>) {
    let n = t.len();
    let mut v = vec![f64::NAN; n];
    let mut se = vec![f64::NAN; n];
    for i in 0..n {
        let lo = i.saturating_sub(half);
        let hi = (i + half + 1).min(n);
        let idx: Vec<usize> = (lo..hi).filter(|&j| seg[j] == seg[i]).collect();
        let h = idx.iter().map(|&j| (t[j] - t[i]).abs()).fold(0.0, f64::max) * 1.0001 + 1e-12;
        let (mut sw, mut st, mut sy, mut stt, mut sty) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let mut w = Vec::with_capacity(idx.len());
        for &j in &idx {
            let u = ((t[j] - t[i]) / h).abs();
            let wj = (1.0 - u * u * u).powi(3);
            let d = t[j] - t[i];
            sw += wj;
            st += wj * d;
            sy += wj * y[j];
            stt += wj * d * d;
            sty += wj * d * y[j];
            w.push(wj);
        }
        let det = sw * stt - st * st;
        let (a, b) = if idx.len() >= 3 && det.abs() > 1e-15 * sw * stt.max(1e-300) {
            ((stt * sy - st * sty) / det, (sw * sty - st * sy) / det)
        } else {
            (sy / sw, 0.0)
        };
        v[i] = a;
        // Residual spread and the effective number of points of the fit.
        let mut ss = 0.0;
        let mut sw2 = 0.0;
        for (k, &j) in idx.iter().enumerate() {
            let r = y[j] - (a + b * (t[j] - t[i]));
            ss += w[k] * r * r;
            sw2 += w[k] * w[k];
        }
        let n_eff = sw * sw / sw2.max(1e-300);
        let dof = (n_eff - 2.0).max(1.0);
        se[i] = (ss / sw * n_eff / dof / n_eff).sqrt();
    }
    (v, se)
}

/// Speed profile of a run (empty when the wheel never turns, as in the
/// calibration run).
pub fn speed_profile(sw: &SwitchRecord, meta: &RunMeta) -> SpeedProfile {
    let (pulses, thresholds, bounces) = detect_pulses(sw);
    let centres: Vec<f64> = pulses.iter().map(|&(a, b)| 0.5 * (sw.t[a] + sw.t[b - 1])).collect();
    let n_mag = meta.magnets;
    let step = meta.wheel_circumference_m / n_mag as f64;
    // Segments: a gap in the record breaks the pulse sequence.
    let mut seg_of_pulse = vec![0usize; centres.len()];
    for k in 1..centres.len() {
        let broken = sw.gaps.iter().any(|g| g.start >= centres[k - 1] && g.end <= centres[k]);
        seg_of_pulse[k] = seg_of_pulse[k - 1] + broken as usize;
    }
    let mut t = Vec::new();
    let mut dt = Vec::new();
    let mut seg = Vec::new();
    let mut phase = Vec::new();
    let mut count_in_seg = 0usize;
    for k in 1..centres.len() {
        if seg_of_pulse[k] != seg_of_pulse[k - 1] {
            count_in_seg = 0;
            continue;
        }
        t.push(0.5 * (centres[k] + centres[k - 1]));
        dt.push(centres[k] - centres[k - 1]);
        seg.push(seg_of_pulse[k]);
        phase.push(count_in_seg % n_mag);
        count_in_seg += 1;
    }
    let mut spacing = vec![1.0 / n_mag as f64; n_mag];
    let mut spacing_stderr = vec![f64::NAN; n_mag];
    let half = 2 * n_mag;
    let naive: Vec<f64> = dt.iter().map(|d| step / d).collect();
    let (mut v, mut se) = smooth(&t, &naive, &seg, half);
    // Spacing errors: the distance each interval really covers is v * dt;
    // averaged per magnet position over the run (only the first segment,
    // whose magnet phase is known), twice.
    if t.len() >= 3 * n_mag {
        for _ in 0..2 {
            let mut ratios: Vec<Vec<f64>> = vec![Vec::new(); n_mag];
            // Skip the start of the launch, where the speed changes too fast
            // within two wheel turns for the local linear fit.
            let vmax = v.iter().copied().filter(|x| x.is_finite()).fold(0.0, f64::max);
            for i in 0..t.len() {
                if seg[i] == seg[0] && v[i].is_finite() && v[i] > 0.5 * vmax {
                    ratios[phase[i]].push(v[i] * dt[i] / meta.wheel_circumference_m);
                }
            }
            if ratios.iter().any(|r| r.len() < 2) {
                break;
            }
            let means: Vec<f64> = ratios.iter().map(|r| r.iter().sum::<f64>() / r.len() as f64).collect();
            let total: f64 = means.iter().sum();
            for k in 0..n_mag {
                spacing[k] = means[k] / total;
                let m = means[k];
                let var = ratios[k].iter().map(|x| (x - m).powi(2)).sum::<f64>() / (ratios[k].len() - 1) as f64;
                spacing_stderr[k] = (var / ratios[k].len() as f64).sqrt() / total;
            }
            let corrected: Vec<f64> = (0..t.len())
                .map(|i| {
                    let f = if seg[i] == seg[0] {
                        spacing[phase[i]]
                    } else {
                        1.0 / n_mag as f64
                    };
                    f * meta.wheel_circumference_m / dt[i]
                })
                .collect();
            (v, se) = smooth(&t, &corrected, &seg, half);
        }
    }
    let v_interval: Vec<f64> = (0..t.len())
        .map(|i| {
            let f = if seg[i] == seg[0] {
                spacing[phase[i]]
            } else {
                1.0 / n_mag as f64
            };
            f * meta.wheel_circumference_m / dt[i]
        })
        .collect();
    let segment_start = (0..t.len()).map(|i| i > 0 && seg[i] != seg[i - 1]).collect();
    SpeedProfile {
        pulses: centres,
        pulse_segment: seg_of_pulse,
        t,
        v_interval,
        v,
        v_stderr: se,
        spacing,
        spacing_stderr,
        thresholds,
        bounces,
        segment_start,
    }
}
