//! Which measured eigenvalues count as a weave, and the pooled eigenvalue
//! errors over them.
//!
//! A kick's fitted eigenvalue is a weave only when the fit describes a clean
//! oscillation and the model has a weave to compare it with. One bad point
//! otherwise sets the pooled figure: a low-speed response where the weave
//! merges with the slow modes fitted as -5.4 + 4.9i against -0.05 + 3.7i
//! predicted, or a noise burst fitted at 95 rad/s. Such kicks are listed
//! with the reason and kept out of the pooled figures; their time series
//! still take part in the fits.

use bikedyn_runtime::identify::Segment;
use serde::Serialize;

/// Smallest coefficient of determination of a weave fit: below it the fit
/// explains less than half of the window's variance (not a clean
/// oscillation).
pub const MIN_R2: f64 = 0.5;

/// A misfit further than this many robust standard deviations (1.4826
/// median absolute deviations) from the others' median, in the real or the
/// imaginary part, is not the same kind of point.
pub const OUTLIER_SIGMAS: f64 = 4.0;

/// Fewest weave kicks for the outlier test: the spread of fewer points is
/// itself uncertain by a third or more, so "4 standard deviations" of it
/// would not be four.
const MIN_FOR_OUTLIERS: usize = 8;

/// A kick kept out of the pooled eigenvalue figures.
#[derive(Clone, Debug, Serialize)]
pub struct Excluded {
    /// Index of the segment.
    pub kick: usize,
    /// Run (or log) of the kick.
    pub run: String,
    /// Window start (s).
    pub window_start: f64,
    /// Why.
    pub reason: String,
}

/// Which kicks' measured eigenvalues count as a weave, judged against the
/// base model's predictions `predicted`.
pub fn weave_kicks(segs: &[Segment], predicted: &[Option<[f64; 2]>]) -> (Vec<bool>, Vec<Excluded>) {
    let mut keep = vec![false; segs.len()];
    let mut excluded = Vec::new();
    let mut exclude = |i: usize, reason: String| {
        excluded.push(Excluded {
            kick: i,
            run: segs[i].run.clone(),
            window_start: segs[i].t0,
            reason,
        })
    };
    for (i, s) in segs.iter().enumerate() {
        match (s.weave, predicted.get(i).copied().flatten()) {
            (None, _) => exclude(i, "no eigenvalue fit".into()),
            (Some(_), _) if s.weave_r2.is_some_and(|r2| !(r2 >= MIN_R2)) => exclude(
                i,
                format!(
                    "fit r2 {:.2} below {MIN_R2}: not a clean oscillation",
                    s.weave_r2.unwrap_or(f64::NAN)
                ),
            ),
            (Some(_), None) => exclude(
                i,
                format!(
                    "the model has no oscillatory weave at {:.2} m/s (merged with the slow modes)",
                    s.mean_speed
                ),
            ),
            (Some(_), Some(_)) => keep[i] = true,
        }
    }
    let idx: Vec<usize> = (0..segs.len()).filter(|&i| keep[i]).collect();
    if idx.len() >= MIN_FOR_OUTLIERS {
        let d: Vec<[f64; 2]> = idx
            .iter()
            .map(|&i| {
                let (m, _) = segs[i].weave.expect("kept kicks have a fit");
                let p = predicted[i].expect("kept kicks have a prediction");
                [m[0] - p[0], m[1] - p[1]]
            })
            .collect();
        let centre_spread = |c: usize| {
            let x: Vec<f64> = d.iter().map(|z| z[c]).collect();
            let m = median(&x);
            let dev: Vec<f64> = x.iter().map(|v| (v - m).abs()).collect();
            (m, 1.4826 * median(&dev))
        };
        let (re, im) = (centre_spread(0), centre_spread(1));
        for (k, &i) in idx.iter().enumerate() {
            // The kick's own standard error widens its tolerance: a short,
            // noisy fit may miss by more without being another kind of point.
            let se = segs[i].weave.map_or([0.0; 2], |w| w.1);
            let z = |c: usize, (m, s): (f64, f64)| {
                let scale = (s * s + se[c] * se[c]).sqrt();
                if scale > 0.0 {
                    (d[k][c] - m).abs() / scale
                } else {
                    0.0
                }
            };
            let worst = z(0, re).max(z(1, im));
            if worst > OUTLIER_SIGMAS {
                keep[i] = false;
                let (m, _) = segs[i].weave.expect("kept kicks have a fit");
                exclude(
                    i,
                    format!(
                        "measured {:.2}{:+.2}i misses the model by {worst:.1} robust standard deviations of the other kicks' misfits (its own standard error included; beyond {OUTLIER_SIGMAS})",
                        m[0], m[1]
                    ),
                );
            }
        }
    }
    excluded.sort_by_key(|e| e.kick);
    (keep, excluded)
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

/// RMS of |measured - predicted| weave eigenvalue (1/s) over the kicks kept.
pub fn eigen_rms(segs: &[Segment], pred: &[Option<[f64; 2]>], keep: &[bool]) -> f64 {
    let d: Vec<f64> = pairs(segs, pred, keep).map(|(d2, _)| d2).collect();
    (d.iter().sum::<f64>() / d.len().max(1) as f64).sqrt()
}

/// The same, each kick weighted by the inverse variance of its measured
/// eigenvalue (a long clean response counts more than a short noisy one).
pub fn eigen_weighted_rms(segs: &[Segment], pred: &[Option<[f64; 2]>], keep: &[bool]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (d2, w) in pairs(segs, pred, keep) {
        num += w * d2;
        den += w;
    }
    (num / den).sqrt()
}

/// Squared misfit and inverse variance of every kept kick.
fn pairs<'a>(
    segs: &'a [Segment],
    pred: &'a [Option<[f64; 2]>],
    keep: &'a [bool],
) -> impl Iterator<Item = (f64, f64)> + 'a {
    segs.iter().zip(pred).zip(keep).filter_map(|((s, p), &k)| {
        if !k {
            return None;
        }
        let (m, se) = s.weave?;
        let p = (*p)?;
        let var = se[0] * se[0] + se[1] * se[1];
        let w = if var > 0.0 && var.is_finite() { 1.0 / var } else { 0.0 };
        Some(((m[0] - p[0]).powi(2) + (m[1] - p[1]).powi(2), w))
    })
}
