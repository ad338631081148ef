//! The bar a candidate's held-out gain must clear, in standard errors of
//! the gain paired run by run: two for a single test, more for one of many
//! alike hypotheses (a family-wise rate).

/// The bar of a consistent held-out gain, in standard errors, when one of
/// `candidates` alike candidates may enter: the library's two standard
/// errors are a one-sided test at about 2.3 %; for a dictionary of many
/// terms the same family-wise rate (Bonferroni) keeps a term from entering
/// because one of many fitted the scatter best by chance (1: 2.0; 28 terms:
/// about 3.1).
pub fn family_wise_sigmas(candidates: usize) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    if candidates <= 1 {
        return 2.0;
    }
    let alpha = 1.0 - Normal::standard().cdf(2.0);
    let k = candidates.max(1) as f64;
    Normal::standard().inverse_cdf(1.0 - alpha / k).max(2.0)
}

/// The bar of a consistent held-out gain a trial must clear, in standard
/// errors, and the family it is counted in: `single_bar` for a single test,
/// raised to [`family_wise_sigmas`] of the `family` fitted so far when the
/// bar is family-wise (never below `single_bar`).
pub(in crate::identify) fn entry_bar(single_bar: f64, family_wise: bool, family: usize) -> (f64, usize) {
    let family = if family_wise { family.max(1) } else { 1 };
    (single_bar.max(family_wise_sigmas(family)), family)
}

/// The bar of a pair of `candidates` alike candidates: one of every pair
/// they can form, since the search over pairs ranges over all of them
/// (the screen ranks them by their joint linearised fit, and the best are
/// fitted).
pub fn pair_sigmas(candidates: usize) -> f64 {
    family_wise_sigmas(candidates * candidates.saturating_sub(1) / 2)
}

/// The bar of a trial before any family-wise raise: `gain_sigmas` for a
/// single candidate and for the speed loss's laws together (an expected
/// trial: every run slows), `pair_gain_sigmas` for any other pair (`None`:
/// no pair may enter).
pub(in crate::identify) fn trial_bar(
    members: usize,
    all_speed_decay: bool,
    gain_sigmas: f64,
    pair_gain_sigmas: Option<f64>,
) -> f64 {
    if members > 1 && !all_speed_decay {
        pair_gain_sigmas.unwrap_or(f64::INFINITY)
    } else {
        gain_sigmas
    }
}
