//! Which measured eigenvalues count in the weave figures, and the pooled
//! eigenvalue errors over them.
//!
//! A kick's fitted eigenvalue counts only when `fit` accepted it as a
//! measured weave eigenvalue (`bikedyn_runtime::experiment::accept`: the
//! record resolves it, the fit is clean and determined, the model has a
//! weave at its speed and it is no robust outlier) and the identification's
//! base model predicts a weave there. One bad point otherwise sets the
//! pooled figure: a low-speed response where the weave merges with the slow
//! modes fitted as -5.4 + 4.9i against -0.05 + 3.7i predicted, or a noise
//! burst fitted at 95 rad/s. Such kicks are listed with the reason and kept
//! out of the pooled figures; their time series still take part in the fits.

use bikedyn_runtime::experiment::accept::Rejected;
use bikedyn_runtime::identify::Segment;

/// A kick kept out of the pooled eigenvalue figures.
#[derive(Clone, Debug)]
pub struct Excluded {
    /// Index of the segment.
    pub kick: usize,
    /// Run (or log) of the kick.
    pub run: String,
    /// Window start (s).
    pub window_start: f64,
    /// Why (the report layer states it).
    pub rejected: Rejected,
}

/// Which kicks' measured eigenvalues count as a weave: those `fit` accepted
/// (`rejected`: its verdict per segment) that the base model's predictions
/// `predicted` have a weave for.
pub fn weave_kicks(
    segs: &[Segment],
    rejected: &[Option<Rejected>],
    predicted: &[Option<[f64; 2]>],
) -> (Vec<bool>, Vec<Excluded>) {
    let mut keep = vec![false; segs.len()];
    let mut excluded = Vec::new();
    for (i, s) in segs.iter().enumerate() {
        let why = match (
            rejected.get(i).copied().flatten(),
            s.weave,
            predicted.get(i).copied().flatten(),
        ) {
            (Some(r), _, _) => r,
            (None, None, _) => Rejected::NoFit,
            (None, Some(_), None) => Rejected::NoModelWeave { speed: s.mean_speed },
            (None, Some(_), Some(_)) => {
                keep[i] = true;
                continue;
            }
        };
        excluded.push(Excluded {
            kick: i,
            run: s.run.clone(),
            window_start: s.t0,
            rejected: why,
        });
    }
    (keep, excluded)
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
