//! Cross-validation by run. A fit's effect parameters are fitted again
//! without each fold, and the held-out kicks are judged at those values
//! with only their initial states fitted. The folds are whole runs (or
//! logs), so a held-out error is that of data the effect never saw, and a
//! selection step compares two models run by run ([`paired_gain`]).

use super::fitted::{CandidateFit, IdentifyOptions, SegmentError};
use super::levenberg_marquardt::lm_fit;
use super::problem::{Free, Problem};
use super::{Segment, Setup, Weights};
use std::sync::atomic::Ordering;

/// Cross-validate a fit of `setup`: for each fold, the effect parameters
/// from the other segments (their initial states held at the full fit),
/// then only the held-out segments' initial states fitted with those effect
/// values. Fills the fit's held-out errors, `cv` and fold values.
pub fn cross_validate(setup: &Setup<'_>, fit: &mut CandidateFit, fold_of: &[usize], opts: &IdentifyOptions) {
    let sims_before = setup.simulations.load(Ordering::Relaxed);
    let nseg = setup.segments.len();
    let nfold = fold_of.iter().copied().max().map_or(0, |m| m + 1);
    // With no shared parameter each segment's fit is its own: fitting the
    // held-out segments' initial states again gives the full fit's.
    if setup.k() == 0 {
        let n: usize = fit.errors.iter().map(|e| e.channel_n.iter().sum::<usize>()).sum();
        fit.cv = fit.chi2 / n.max(1) as f64;
        fit.held_out = fit.errors.clone();
        fit.fold_values = vec![Vec::new(); nfold];
        return;
    }
    let all: Vec<usize> = (0..nseg).collect();
    let g = fit.values.clone();
    let nuisance = fit.nuisance.clone();
    let mut held_out = vec![SegmentError::default(); nseg];
    let mut held_res: Vec<Vec<f64>> = vec![Vec::new(); nseg];
    let mut fold_values = vec![g.clone(); nfold];
    for (f, fold_g) in fold_values.iter_mut().enumerate() {
        let test: Vec<usize> = all.iter().copied().filter(|&s| fold_of[s] == f).collect();
        let train: Vec<usize> = all.iter().copied().filter(|&s| fold_of[s] != f).collect();
        if test.is_empty() {
            continue;
        }
        let gf = if setup.k() > 0 && !train.is_empty() {
            let p = lm_fit(
                Problem::new(setup, train, Free::Shared, g.clone(), nuisance.clone()),
                opts.patience,
            );
            p.g.clone()
        } else {
            g.clone()
        };
        let p = lm_fit(
            Problem::new(setup, test.clone(), Free::Nuisance, gf.clone(), nuisance.clone()),
            opts.patience,
        );
        if let Some(r) = p.all_residuals() {
            for (i, &s) in test.iter().enumerate() {
                held_out[s] = SegmentError::of(&r[i], &setup.segments[s], setup.weights[s]);
                held_res[s] = r[i].clone();
            }
        }
        *fold_g = gf;
    }
    let n_cv: usize = held_res.iter().map(Vec::len).sum();
    fit.cv = held_res.iter().flatten().map(|x| x * x).sum::<f64>() / n_cv.max(1) as f64;
    fit.held_out = held_out;
    fit.fold_values = fold_values;
    fit.simulations += setup.simulations.load(Ordering::Relaxed) - sims_before;
}

/// The folds of the cross-validation: by run, so that a held-out error is
/// that of runs (or logs, with many kicks each) the fit never saw; runs are
/// dealt to `folds` folds in their order. With a single run the folds are
/// by kick.
pub fn folds_by_run(segments: &[Segment], folds: usize) -> (usize, Vec<usize>) {
    let mut runs: Vec<&str> = Vec::new();
    for s in segments {
        if !runs.contains(&s.run.as_str()) {
            runs.push(&s.run);
        }
    }
    if runs.len() < 2 {
        let folds = folds.clamp(2, segments.len().max(2));
        return (folds, (0..segments.len()).map(|s| s % folds).collect());
    }
    let folds = folds.clamp(2, runs.len());
    let fold_of = segments
        .iter()
        .map(|s| runs.iter().position(|r| *r == s.run).unwrap_or(0) % folds)
        .collect();
    (folds, fold_of)
}

/// A segment's weighted sum of squares over its channels (the residuals
/// divided by the channel scales `w`, as the fit weighs them) and its
/// number of samples.
fn weighted_ss(e: &SegmentError, w: &Weights) -> (f64, f64) {
    let ss = e.channel_ss[0] / (w.roll * w.roll)
        + e.channel_ss[1] / (w.steer * w.steer)
        + e.channel_ss[2] / (w.speed * w.speed);
    (ss, e.channel_n.iter().sum::<usize>() as f64)
}

/// Standard error of a fit's held-out error `cv` (the pooled mean square
/// of the weighted held-out residuals), with the segments (kicks) as the
/// units: the ratio estimator's `sqrt(m / (m - 1) sum (ss_i - cv n_i)^2) / N`
/// over `m` segments of `n_i` samples and weighted sum of squares `ss_i`
/// (`N` samples in all). `None` with fewer than two segments.
pub fn held_out_standard_error(fit: &CandidateFit, w: &[Weights]) -> Option<f64> {
    let parts: Vec<(f64, f64)> = fit.held_out.iter().zip(w).map(|(e, w)| weighted_ss(e, w)).collect();
    let m = parts.len() as f64;
    let total: f64 = parts.iter().map(|p| p.1).sum();
    if m < 2.0 || !(total > 0.0) {
        return None;
    }
    let cv = parts.iter().map(|p| p.0).sum::<f64>() / total;
    let spread: f64 = parts.iter().map(|(ss, n)| (ss - cv * n).powi(2)).sum();
    Some((m / (m - 1.0) * spread).sqrt() / total)
}

/// Paired comparison of the held-out errors of two models, run by run:
/// mean gain (weighted mean square, `base - candidate`) and its standard
/// error. Selection asks the gain to exceed two standard errors, so an
/// effect that improves the held-out error only on average over a few runs
/// (an artefact of one run, noise) is not added.
pub fn paired_gain(base: &CandidateFit, cand: &CandidateFit, w: &[Weights]) -> Option<(f64, f64)> {
    let mse = |e: &SegmentError, w: &Weights| {
        let (ss, n) = weighted_ss(e, w);
        ss / n.max(1.0)
    };
    let d: Vec<f64> = base
        .held_out
        .iter()
        .zip(&cand.held_out)
        .zip(w)
        .map(|((a, b), w)| mse(a, w) - mse(b, w))
        .collect();
    let n = d.len() as f64;
    if n < 2.0 {
        return None;
    }
    let m = d.iter().sum::<f64>() / n;
    let var = d.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    Some((m, (var / n).sqrt()))
}
