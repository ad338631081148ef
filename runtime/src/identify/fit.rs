//! Fitting one candidate model: Levenberg-Marquardt over the effect
//! parameters and every kick's nuisances together (a [`Problem`] says which
//! are free), the standard errors inflated for autocorrelated residuals,
//! and the check that dissipative parameters stay positive; then the
//! held-out half of judging it ([`cross_validate`]) or its criterion
//! against a reference ([`bic`]). What a fit gives is in
//! [`fitted`](super::fitted).

use super::criterion::bic;
use super::cross_validation::cross_validate;
use super::fitted::{CandidateFit, IdentifyOptions, SegmentError};
use super::levenberg_marquardt::lm_fit;
use super::normal::Normal;
use super::problem::{Free, Problem};
use super::{IdentifyError, Setup, NUISANCE};
use std::sync::atomic::Ordering;

/// Fit a model with the setup's effect parameters free, starting from `g0`
/// and the initial states `x0`, then cross-validate it. `fold_of[s]` is the
/// fold of segment `s`.
pub fn fit_candidate(
    setup: &Setup<'_>,
    effects: Vec<String>,
    g0: &[f64],
    x0: &[[f64; NUISANCE]],
    fold_of: &[usize],
    opts: &IdentifyOptions,
    reference: Option<&CandidateFit>,
) -> Result<CandidateFit, IdentifyError> {
    fit_trial(setup, effects, g0, x0, fold_of, opts, reference, 0..0)
}

/// [`fit_candidate`] for a trial of the search: `own` are the indices of
/// the trial's own parameters (those after the current model's; empty for
/// any other fit), and a fit that holds one of its dissipative ones on its
/// floor while the cost no longer falls ends there, not physical (see
/// [`lm_fit`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn fit_trial(
    setup: &Setup<'_>,
    effects: Vec<String>,
    g0: &[f64],
    x0: &[[f64; NUISANCE]],
    fold_of: &[usize],
    opts: &IdentifyOptions,
    reference: Option<&CandidateFit>,
    own: std::ops::Range<usize>,
) -> Result<CandidateFit, IdentifyError> {
    let nseg = setup.segments.len();
    if nseg == 0 {
        return Err(IdentifyError::NoData);
    }
    let sims_before = setup.simulations.load(Ordering::Relaxed);
    let all: Vec<usize> = (0..nseg).collect();
    // A fit where every segment's initial state moves: effect parameters
    // and states together (the base model: states alone).
    let free = if setup.k() == 0 { Free::Nuisance } else { Free::All };
    let mut problem = Problem::new(setup, all.clone(), free, g0.to_vec(), x0.to_vec());
    problem.from_measured_speed = true;
    problem.settled_on_floor = own
        .filter(|&j| setup.parameters.get(j).is_some_and(|q| q.dissipative))
        .collect();
    let full = lm_fit(problem, opts.patience);
    let simulations = || setup.simulations.load(Ordering::Relaxed) - sims_before;
    let res = full.all_residuals().ok_or_else(|| IdentifyError::Simulation {
        run: setup.segments[0].run.clone(),
        message: "the fitted model does not simulate every segment".into(),
    })?;
    let errors: Vec<SegmentError> = res
        .iter()
        .zip(setup.segments)
        .zip(&setup.weights)
        .map(|((r, s), w)| SegmentError::of(r, s, *w))
        .collect();
    // The weighted sum of squares at the search's scales: the fit's
    // objective (prior rows aside), what fits compare by and the
    // criterion weighs.
    let chi2: f64 = res.iter().flatten().map(|x| x * x).sum();
    // Values beyond a parameter's floor or ceiling were simulated at it.
    let g: Vec<f64> = full
        .g
        .iter()
        .zip(&setup.parameters)
        .map(|(&v, p)| p.simulated(v))
        .collect();
    let nuisance = full.x0.clone();

    // Standard errors of the effect parameters from the Jacobian at the
    // fit: the shared block of (J^T J)^-1 is the inverse of the reduced
    // matrix of the normal equations without damping.
    let mut stderr = vec![f64::NAN; setup.k()];
    if setup.k() > 0 {
        if let (Some(blocks), Some(res)) = (full.jacobian_blocks(), full.all_residuals()) {
            let n: usize = res.iter().map(Vec::len).sum::<usize>() + full.prior_rows().len();
            let p = full.n_free() as f64;
            let rho = errors.iter().map(|e| e.rho).sum::<f64>() / errors.len() as f64;
            let s2 = chi2 / (n as f64 - p).max(1.0) * (1.0 + rho) / (1.0 - rho);
            let prior: Vec<(usize, f64, f64)> = full
                .prior_normal_rows()
                .into_iter()
                .map(|(j, sd, _)| (j, sd, 0.0))
                .collect();
            if let Some(inv) = Normal::new(&blocks, &res, &prior, setup.k(), 0.0).and_then(|nm| nm.s.try_inverse()) {
                for (i, s) in stderr.iter_mut().enumerate() {
                    *s = (inv[(i, i)] * s2).sqrt();
                }
            }
        }
    }
    let physical = setup
        .parameters
        .iter()
        .zip(&full.g)
        .all(|(p, v)| !p.dissipative || *v > p.lower.unwrap_or(0.0));
    let mut fit = CandidateFit {
        effects,
        parameters: setup.parameters.clone(),
        values: g.clone(),
        stderr,
        nuisance: nuisance.clone(),
        errors,
        held_out: vec![SegmentError::default(); nseg],
        fold_values: Vec::new(),
        bic: f64::NAN,
        cv: f64::NAN,
        chi2,
        simulations: 0,
        physical,
    };
    // Cross-validation is the costly half: a candidate is cross-validated
    // apart ([`cross_validate`]), only when selection needs its held-out
    // error (not when the information criterion or physics rejects it).
    match reference {
        Some(r) => fit.bic = bic(&fit, r),
        None => cross_validate(setup, &mut fit, fold_of, opts),
    }
    fit.simulations = simulations();
    Ok(fit)
}
