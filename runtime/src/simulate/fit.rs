//! Weave eigenvalue of a simulated (or measured) roll response, from the
//! extrema of the oscillation: a robust stand-in for the thesis's fit of
//! `theta(t) = A e^(a t) cos(b t + phi) + c` (section 7.1, eq. 94).
//!
//! Between consecutive extrema `k` and `k+1` (a half period apart) the swing
//! `s_k = |theta_(k+1) - theta_k|` of `A e^(a t) cos(b t + phi) + c` decays by
//! `e^(a T/2)` whatever the offset `c`, so `a = ln(s_(k+1)/s_k) / (t_(k+2) -
//! t_(k+1))` (averaged over the swings used) and `b = pi / (half period)`.

/// Weave eigenvalue `(a, b)` (1/s, rad/s) from the roll response after
/// `t_start`, using `swings` consecutive swings (half periods). `None` if the
/// response has fewer extrema than that (e.g. a fall, or an overdamped mode).
pub fn weave_from_extrema(t: &[f64], roll: &[f64], t_start: f64, swings: usize) -> Option<(f64, f64)> {
    assert_eq!(t.len(), roll.len(), "time and roll lengths");
    // Local extrema, refined by a parabola through the three samples.
    let mut ext: Vec<(f64, f64)> = Vec::new();
    for i in 1..t.len().saturating_sub(1) {
        if t[i] <= t_start || t[i - 1] >= t[i] || t[i] >= t[i + 1] {
            continue;
        }
        let (y0, y1, y2) = (roll[i - 1], roll[i], roll[i + 1]);
        if (y1 > y0 && y1 >= y2) || (y1 < y0 && y1 <= y2) {
            let h = t[i + 1] - t[i];
            let den = y0 - 2.0 * y1 + y2;
            let (dt, y) = if den != 0.0 {
                let d = 0.5 * (y0 - y2) / den;
                (d * h, y1 - 0.25 * (y0 - y2) * d)
            } else {
                (0.0, y1)
            };
            ext.push((t[i] + dt, y));
        }
    }
    if ext.len() < swings + 2 {
        return None;
    }
    let ext = &ext[..swings + 2];
    let s: Vec<f64> = ext.windows(2).map(|w| (w[1].1 - w[0].1).abs()).collect();
    let mut a = 0.0;
    for k in 0..swings {
        a += (s[k + 1] / s[k]).ln() / (ext[k + 2].0 - ext[k + 1].0);
    }
    a /= swings as f64;
    let half = (ext[swings + 1].0 - ext[0].0) / (swings + 1) as f64;
    Some((a, std::f64::consts::PI / half))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_a_damped_cosine_with_offset() {
        let (a, b, c) = (-0.7, 6.0, 0.05);
        let t: Vec<f64> = (0..3000).map(|k| k as f64 * 0.001).collect();
        let y: Vec<f64> = t
            .iter()
            .map(|&t| 0.3 * (a * t).exp() * (b * t + 0.4).cos() + c)
            .collect();
        let (fa, fb) = weave_from_extrema(&t, &y, 0.0, 3).unwrap();
        // The swing ratio of a damped cosine is exact only for extrema half a
        // damped period apart; the bias is O((a/b)^2).
        assert!((fa - a).abs() < 0.02 && (fb - b).abs() < 0.02, "{fa} {fb}");
        assert!(weave_from_extrema(&t[..100], &y[..100], 0.0, 3).is_none());
    }
}
