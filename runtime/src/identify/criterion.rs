//! The criteria the selection weighs a fit by: the information criterion
//! with effective sample sizes, the candidates' priors on the data's scale,
//! and how far a fitted correction lies from its measured value.

use super::candidate::Candidate;
pub use super::candidate::PLAUSIBLE_PRIOR_SDS;
use super::fitted::CandidateFit;

/// The candidates with their priors put on the scale of the weighted data.
/// The weighted sum of squares counts every sample as independent with
/// variance one, but the residuals of a smooth response are strongly
/// autocorrelated and their level is not the weight: the information the
/// data carry is that sum divided by `s2 = chi2 / n (1 + rho) / (1 - rho)`
/// (the inflation the standard errors use). A prior `sd` is therefore
/// applied as `sd / sqrt(s2)`, measured on the base model's fit, never
/// weaker than as stated; without this a correction would move several
/// prior deviations for a small gain in a sum that overstates the data.
pub(super) fn with_priors_on_the_data_scale(candidates: &[Candidate], base: &CandidateFit) -> Vec<Candidate> {
    let n: usize = base.errors.iter().flat_map(|e| e.channel_n).sum();
    let rho = base.errors.iter().map(|e| e.rho).sum::<f64>() / base.errors.len().max(1) as f64;
    let s2 = base.chi2 / n.max(1) as f64 * (1.0 + rho) / (1.0 - rho);
    let scale = if s2.is_finite() { s2.max(1.0).sqrt() } else { 1.0 };
    candidates
        .iter()
        .map(|c| {
            let mut c = c.clone();
            for p in &mut c.parameters {
                p.prior = p.prior.map(|(mean, sd)| (mean, sd / scale));
                // The same place in the stated units.
                p.gross_beyond *= scale;
            }
            c
        })
        .collect()
}

/// Bayesian information criterion of `fit` with the effective sample size
/// of each channel taken from `reference` (the base model of the search):
/// the profile likelihood of Gaussian residuals with one unknown variance
/// per channel of each segment (a run that the model follows badly, e.g.
/// one that diverges toward a fall, then counts by the log of its misfit
/// and cannot outweigh the others): `sum n_eff ln(SS / n) + k ln(n_eff)`.
pub fn bic(fit: &CandidateFit, reference: &CandidateFit) -> f64 {
    let mut total = 0.0;
    let mut n_eff_all = 0.0;
    for (e, r) in fit.errors.iter().zip(&reference.errors) {
        for c in 0..3 {
            let n = e.channel_n[c];
            if n == 0 || !(e.channel_ss[c] > 0.0) {
                continue;
            }
            // Speed samples are sparse (one per magnet): about independent.
            let rho = if c == 2 { 0.0 } else { r.rho };
            let n_eff = n as f64 * (1.0 - rho) / (1.0 + rho);
            total += n_eff * (e.channel_ss[c] / n as f64).ln();
            n_eff_all += n_eff;
        }
    }
    total + fit.values.len() as f64 * n_eff_all.max(1.0).ln()
}

/// Of the fitted `values` of `members` (their parameters in order), the
/// one farthest from its prior as `stated` declares it (the candidates'
/// priors before they are put on the data's scale): symbol, value and
/// distance in prior standard deviations (`None`: no parameter has a prior,
/// e.g. an effect).
pub(super) fn farthest_from_prior(
    stated: &[Candidate],
    members: &[&Candidate],
    values: &[f64],
) -> Option<(String, f64, f64)> {
    let mut out: Option<(String, f64, f64)> = None;
    let params = members.iter().flat_map(|m| {
        let declared = stated.iter().find(|c| c.name == m.name).unwrap_or(m);
        declared.parameters.iter()
    });
    for (p, &v) in params.zip(values) {
        if let Some((mean, sd)) = p.prior {
            let d = ((v - mean) / sd).abs();
            if out.as_ref().is_none_or(|o| d > o.2) {
                out = Some((p.symbol.clone(), v, d));
            }
        }
    }
    out
}
