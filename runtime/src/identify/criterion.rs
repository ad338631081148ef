//! The criteria the selection weighs a fit by: the information criterion
//! with effective sample sizes, the candidates' priors on the data's scale,
//! and how far a fitted correction lies from its measured value.

use super::candidate::Candidate;
pub use super::candidate::PLAUSIBLE_PRIOR_SDS;
use super::fitted::CandidateFit;

/// The variance of one weighted sample that the search's likelihood
/// assumes: the base model's weighted sum of squares per sample, inflated by
/// `(1 + rho) / (1 - rho)` for its residuals' mean lag-1 autocorrelation
/// `rho`. The weighted sum of squares counts every sample as independent
/// with variance one, but the residuals of a smooth response are strongly
/// autocorrelated and their level is not the weight: the information the
/// data carry is that sum divided by `s2` (the inflation the standard errors
/// use). The candidates' priors ([`with_priors_on_the_data_scale`]) and the
/// information criterion ([`bic`]) both use it, so that they and every fit
/// (which minimises the weighted sum with the priors) weigh the data alike.
/// At least one: a base model that fits to within the weights is not taken
/// to carry more information than the weights state.
pub(super) fn data_variance(reference: &CandidateFit) -> f64 {
    let n: usize = reference.errors.iter().flat_map(|e| e.channel_n).sum();
    let rho = reference.errors.iter().map(|e| e.rho).sum::<f64>() / reference.errors.len().max(1) as f64;
    let s2 = reference.chi2 / n.max(1) as f64 * (1.0 + rho) / (1.0 - rho);
    if s2.is_finite() {
        s2.max(1.0)
    } else {
        1.0
    }
}

/// The candidates with their priors put on the scale of the weighted data:
/// a prior `sd` is applied as `sd / sqrt(s2)` ([`data_variance`], measured
/// on the base model's fit), never weaker than as stated; without this a
/// correction would move several prior deviations for a small gain in a sum
/// that overstates the data.
pub(super) fn with_priors_on_the_data_scale(candidates: &[Candidate], base: &CandidateFit) -> Vec<Candidate> {
    let scale = data_variance(base).sqrt();
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

/// The effective number of samples of a fit's data, with each kick's
/// autocorrelation taken from `reference` (the base model of the search):
/// a roll or steer channel of `n` samples counts `n (1 - rho) / (1 + rho)`;
/// the speed samples are sparse (one per magnet) and count as independent.
fn effective_samples(fit: &CandidateFit, reference: &CandidateFit) -> f64 {
    let mut n_eff_all = 0.0;
    for (e, r) in fit.errors.iter().zip(&reference.errors) {
        for c in 0..3 {
            let n = e.channel_n[c];
            if n == 0 {
                continue;
            }
            let rho = if c == 2 { 0.0 } else { r.rho };
            n_eff_all += n as f64 * (1.0 - rho) / (1.0 + rho);
        }
    }
    n_eff_all
}

/// Bayesian information criterion of `fit` against `reference` (the base
/// model of the search): `chi2 / s2 + k ln(n_eff)`, the weighted sum of
/// squares at the search's channel scales over the data's variance
/// ([`data_variance`]) plus the penalty of the `k` fitted effect
/// parameters on the effective sample size.
///
/// It is the fits' own objective (prior rows aside) on one fixed scale, so
/// that the fits, the score test's predictions, the priors and the
/// criterion share one likelihood: a model that holds another, fitted at
/// least as well, never scores worse than it beyond `ln(n_eff)` per added
/// parameter. A criterion with a variance of its own per kick and channel
/// (profiled out, `sum n_eff ln(SS / n)`) weighed channels by their
/// relative change, not by what the fits minimise, and a nested model
/// could score worse than its member with no fault of its fit
/// (docs/identification.md, the criterion on the fits' own sum).
pub fn bic(fit: &CandidateFit, reference: &CandidateFit) -> f64 {
    fit.chi2 / data_variance(reference) + fit.values.len() as f64 * effective_samples(fit, reference).max(1.0).ln()
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::identify::fitted::SegmentError;

    /// A fit of `k` effect parameters whose kicks have the sums of squares
    /// `ss` (roll, steer, speed; each kick 200 roll and steer samples and 4
    /// speed samples, residual autocorrelation `rho`) at unit weights.
    fn fit(ss: &[[f64; 3]], k: usize, rho: f64) -> CandidateFit {
        let errors: Vec<SegmentError> = ss
            .iter()
            .map(|&channel_ss| SegmentError {
                channel_ss,
                channel_n: [200, 200, 4],
                rho,
                ..SegmentError::default()
            })
            .collect();
        CandidateFit {
            effects: vec![],
            parameters: vec![],
            values: vec![0.0; k],
            stderr: vec![f64::NAN; k],
            nuisance: vec![],
            held_out: vec![],
            fold_values: vec![],
            bic: f64::NAN,
            cv: f64::NAN,
            chi2: ss.iter().flatten().sum(),
            errors,
            simulations: 0,
            physical: true,
        }
    }

    #[test]
    fn a_model_that_holds_another_and_fits_at_least_as_well_never_scores_worse_than_one_penalty_per_parameter() {
        let base = fit(&[[200.0, 200.0, 4.0], [200.0, 200.0, 4.0]], 0, 0.9);
        let n_eff = effective_samples(&base, &base);
        // 2 x (2 x 200 x 0.1 / 1.9 + 4) = 50.1 effective samples.
        assert!((n_eff - 2.0 * (400.0 * 0.1 / 1.9 + 4.0)).abs() < 1e-9);
        // A member that moved the speed channel's relative misfit a lot and
        // a model holding it that trades some of that for a larger absolute
        // gain in roll: the profiled criterion (a variance per channel)
        // ranked such a pair the wrong way round; this one cannot.
        let member = fit(&[[190.0, 200.0, 0.4], [190.0, 200.0, 0.4]], 1, 0.9);
        let holding = fit(&[[150.0, 200.0, 2.0], [150.0, 200.0, 2.0]], 2, 0.9);
        assert!(holding.chi2 <= member.chi2);
        let (b_member, b_holding) = (bic(&member, &base), bic(&holding, &base));
        assert!(
            b_holding <= b_member + n_eff.ln() + 1e-12,
            "{b_holding} > {b_member} + ln {n_eff}"
        );
        // And here it is better: 76.8 less weighted sum over s2 = 19 (the
        // base model fits within its weights, rho 0.9), less one penalty.
        let s2 = data_variance(&base);
        assert!((s2 - 19.0).abs() < 1e-9);
        assert!((b_member - b_holding - ((member.chi2 - holding.chi2) / s2 - n_eff.ln())).abs() < 1e-9);
    }

    #[test]
    fn the_criterion_and_the_priors_weigh_the_data_by_one_variance() {
        let base = fit(&[[400.0, 100.0, 8.0]], 0, 0.5);
        // The base model's weighted sum per sample (508 / 404) times 3.
        let s2 = 508.0 / 404.0 * 3.0;
        assert!((data_variance(&base) - s2).abs() < 1e-12);
        let c = crate::identify::selection::tests::candidate("correct I3z", "I3z", Some((1.25, 0.125)));
        let scaled = with_priors_on_the_data_scale(&[c], &base);
        let (_, sd) = scaled[0].parameters[0].prior.unwrap();
        assert!((sd - 0.125 / s2.sqrt()).abs() < 1e-15);
        // One unit of the prior's penalty in the fit's sum, (d / sd')^2 with
        // d = sd', is 1 / s2 in the criterion: a prior deviation costs what
        // one stated standard deviation costs, whatever the weights.
        let worse = fit(&[[400.0 + 1.0, 100.0, 8.0]], 0, 0.5);
        assert!((bic(&worse, &base) - bic(&base, &base) - 1.0 / s2).abs() < 1e-12);
        // A base model fitted within its weights is not taken to carry more
        // than they state.
        assert_eq!(data_variance(&fit(&[[1.0, 1.0, 0.1]], 0, 0.0)), 1.0);
    }
}
