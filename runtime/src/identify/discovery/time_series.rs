//! Discovery in the time series: the dictionary's terms that the derived
//! models carry as parameters (a constant bias, Coulomb-like torques, and
//! angles and rates times 1, v or v^2 on the roll and steer equations),
//! fitted through the nonlinear simulation of every kick with the same
//! exact sensitivities and per-kick nuisances as the library's effects.
//!
//! The search continues the library's: its selection stays in the model
//! and is refitted beside each term, and every term is a candidate of one
//! parameter that passes the same tests as a library effect (the criterion,
//! the held-out error of the same folds of runs, a gain consistent run by
//! run, a physical sign for a dissipative term), step by step
//! ([`Search::step`]: screening orders the terms and skips those whose
//! linearised fit cannot win; when the best fails the next is tried). A
//! table of weave eigenvalues cannot see a bias or a friction, and tells
//! few of the other terms apart over a narrow range of speeds; the time
//! series see the mode shapes and the amplitude too.

use super::super::criterion::{farthest_from_prior, with_priors_on_the_data_scale, PLAUSIBLE_PRIOR_SDS};
use super::super::cross_validation::held_out_standard_error;
use super::super::selection::{family_wise_sigmas, pair_sigmas, Identification, MemberCheck, Search, Step};
use super::super::{Candidate, CandidateFit, Factory, IdentifyError, IdentifyOptions, Segment};
use crate::model::MultibodyModel;
use serde::Serialize;

/// What the search in the time series found.
#[derive(Clone, Debug, Serialize)]
pub struct TimeSeriesDiscovery {
    /// Every step, each term tried with its fit and verdict.
    pub steps: Vec<Step>,
    /// The terms added, in order (candidate names: the runtime's term
    /// names).
    pub selected: Vec<String>,
    /// Members removed by the backward check after the terms entered (the
    /// library's selection included), in order.
    pub removed: Vec<String>,
    /// The backward check: each member tested against the model without
    /// it once terms were added.
    pub final_check: Vec<MemberCheck>,
    /// The fit with the library's selection (less what the check removed)
    /// and the terms added (the library's fit when none is).
    pub after: CandidateFit,
    /// Simulations run (both starts').
    pub simulations: usize,
    /// The second start, made when the library took corrections beyond
    /// their plausible range (`None`: it took none, and one start was
    /// made).
    pub second_start: Option<SecondStart>,
}

/// A library correction left out of the second start: its candidate, its
/// parameter's symbol and value as the library fitted it, and the distance
/// from its stated prior in prior standard deviations.
#[derive(Clone, Debug, Serialize)]
pub struct LeftOut {
    pub candidate: String,
    pub symbol: String,
    pub value: f64,
    pub prior_sds: f64,
}

/// The search's second start, from the library's selection without the
/// corrections it took beyond their plausible range, and which start's
/// model was kept.
#[derive(Clone, Debug, Serialize)]
pub struct SecondStart {
    /// The corrections left out.
    pub left_out: Vec<LeftOut>,
    /// Held-out error of each start's final model.
    pub cv_first: f64,
    pub cv_second: f64,
    /// One standard error of the first start's held-out error (kicks as
    /// units).
    pub standard_error: f64,
    /// Whether the second start's model was kept: it predicts the held-out
    /// runs better than the first's by more than `standard_error`.
    pub kept_second: bool,
    /// The start not kept: the terms it added, the members it removed, its
    /// steps and simulations. (The kept start's are the discovery's own.)
    pub other_selected: Vec<String>,
    pub other_removed: Vec<String>,
    pub other_steps: Vec<Step>,
    pub other_simulations: usize,
    /// Simulations of the kept start.
    pub kept_simulations: usize,
}

/// Why the search did not run.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum NotSearched {
    /// The library's selection is fitted with a model of its own (the
    /// tyre model), which does not carry the dictionary.
    AlternativeModel(String),
    /// The model carries none of the dictionary's terms.
    NoTerms,
}

/// The time series' budget of term fits per step beyond the contenders.
pub const TERM_FITS_PER_STEP: usize = 8;

/// Search the dictionary's `terms` (candidates of one parameter each, no
/// prior) in the time series, after the library's identification
/// `library` of model `M` with base parameters `base` and candidates
/// `candidates` (those the library search was given), adding at most
/// `max_terms`.
pub fn discover_in_time_series<M: MultibodyModel>(
    base: &[f64],
    segments: &[Segment],
    library: &Identification,
    candidates: &[Candidate],
    terms: &[Candidate],
    opts: &IdentifyOptions,
    max_terms: usize,
    progress: &(dyn Fn(&str, Option<(usize, usize)>) + Sync),
) -> Result<Result<TimeSeriesDiscovery, NotSearched>, IdentifyError> {
    if terms.is_empty() {
        return Ok(Err(NotSearched::NoTerms));
    }
    // The library's candidates on the data's scale, as its search fitted
    // them (the same scaling of the same base fit), then the terms.
    let mut all: Vec<Candidate> = candidates.to_vec();
    all.extend(terms.iter().cloned());
    let scaled = with_priors_on_the_data_scale(&all, &library.before);
    let mut selected: Vec<&Candidate> = Vec::new();
    for name in &library.selected {
        let c = scaled
            .iter()
            .find(|c| &c.name == name)
            .expect("the library's selection is among its candidates");
        if c.alternative_model {
            return Ok(Err(NotSearched::AlternativeModel(name.clone())));
        }
        selected.push(c);
    }
    let main = Factory::<M>::new(base.to_vec());
    // Each term's fit is a fit of every kick's whole response, and the
    // dictionary offers some fifty: a step fits at most
    // TERM_FITS_PER_STEP beyond its contenders unless the caller set its
    // own budget (the library's search has none). What a step left unfitted
    // is in its record.
    let opts = &IdentifyOptions {
        max_fits_per_step: Some(opts.max_fits_per_step.unwrap_or(TERM_FITS_PER_STEP)),
        ..opts.clone()
    };
    let search = Search {
        main: &main,
        alternative: None,
        segments,
        weights: &library.weights,
        fold_of: &library.fold_of,
        opts,
        reference: &library.before,
        stated: &all,
        progress,
        // One of many terms entering by chance is guarded against; a pair
        // is one of n (n - 1) / 2.
        gain_sigmas: family_wise_sigmas(terms.len()),
        pair_gain_sigmas: Some(pair_sigmas(terms.len())),
        family_wise: false,
    };
    let first = search_from(
        &search,
        &scaled,
        terms,
        library.after.clone(),
        selected.clone(),
        max_terms,
    )?;
    // The library may have taken a correction beyond its plausible range,
    // for want of a plausible candidate: a missing force pushed into a
    // measured parameter. A term found beside it is judged against a model
    // that already bent that parameter toward the force, and a linearised
    // screen then sees little gain left for the force itself. So the search
    // starts a second time from the library's selection without those
    // corrections; its model is kept when it predicts the held-out runs
    // better than the first start's by more than one standard error of the
    // first's held-out error (a true error of that size, with no term to
    // stand for it, keeps the first start).
    let implausible: Vec<LeftOut> = {
        let mut offset = 0;
        let mut out = Vec::new();
        for c in &selected {
            let width = c.parameters.len();
            let values = &library.after.values[offset..offset + width];
            offset += width;
            if let Some((symbol, value, sds)) =
                farthest_from_prior(&all, &[*c], values).filter(|(_, _, sds)| *sds > PLAUSIBLE_PRIOR_SDS)
            {
                out.push(LeftOut {
                    candidate: c.name.clone(),
                    symbol,
                    value,
                    prior_sds: sds,
                });
            }
        }
        out
    };
    if implausible.is_empty() {
        return Ok(Ok(first.into_discovery(None)));
    }
    let mut start = library.after.clone();
    let mut kept_members = selected.clone();
    let mut simulations = 0;
    for gone in &implausible {
        let j = kept_members
            .iter()
            .position(|c| c.name == gone.candidate)
            .expect("a member of the selection");
        (search.progress)(
            &format!("second start of the time series without {}", gone.candidate),
            None,
        );
        let Some(fit) = search.fit_without(&start, &kept_members, j)? else {
            // The library's model without it cannot be fitted: the first
            // start stands.
            return Ok(Ok(first.into_discovery(None)));
        };
        simulations += fit.simulations;
        kept_members.remove(j);
        start = fit;
    }
    let mut second = search_from(&search, &scaled, terms, start, kept_members, max_terms)?;
    second.simulations += simulations;
    let standard_error = held_out_standard_error(&first.after, &library.weights).unwrap_or(f64::NAN);
    let keep_second = first.after.cv - second.after.cv > standard_error;
    let record = |kept: &Path, other: &Path| SecondStart {
        left_out: implausible.clone(),
        cv_first: first.after.cv,
        cv_second: second.after.cv,
        standard_error,
        kept_second: keep_second,
        other_selected: other.selected.clone(),
        other_removed: other.removed.clone(),
        other_steps: other.steps.clone(),
        other_simulations: other.simulations,
        kept_simulations: kept.simulations,
    };
    Ok(Ok(if keep_second {
        let r = record(&second, &first);
        let mut d = second.into_discovery(Some(r));
        // The library's corrections left out are members removed.
        let mut removed: Vec<String> = implausible.iter().map(|l| l.candidate.clone()).collect();
        removed.append(&mut d.removed);
        d.removed = removed;
        d.simulations += d.second_start.as_ref().map_or(0, |s| s.other_simulations);
        d
    } else {
        let r = record(&first, &second);
        let mut d = first.into_discovery(Some(r));
        d.simulations += d.second_start.as_ref().map_or(0, |s| s.other_simulations);
        d
    }))
}

/// One start of the search: forward over the terms from the model `current`
/// of the members `selected`, then the backward check.
struct Path {
    steps: Vec<Step>,
    selected: Vec<String>,
    removed: Vec<String>,
    final_check: Vec<MemberCheck>,
    after: CandidateFit,
    simulations: usize,
}

impl Path {
    fn into_discovery(self, second_start: Option<SecondStart>) -> TimeSeriesDiscovery {
        TimeSeriesDiscovery {
            steps: self.steps,
            selected: self.selected,
            removed: self.removed,
            final_check: self.final_check,
            after: self.after,
            simulations: self.simulations,
            second_start,
        }
    }
}

fn search_from<'c>(
    search: &Search<'_>,
    scaled: &'c [Candidate],
    terms: &[Candidate],
    mut current: CandidateFit,
    mut selected: Vec<&'c Candidate>,
    max_terms: usize,
) -> Result<Path, IdentifyError> {
    let is_term = |c: &&Candidate| terms.iter().any(|t| t.name == c.name);
    let mut steps = Vec::new();
    let mut added: Vec<String> = Vec::new();
    let mut final_check = Vec::new();
    let mut removed: Vec<String> = Vec::new();
    let mut simulations = 0;
    // Forward, then the backward check of every member (the library's
    // included: a correction the library took for want of the missing
    // force gives way when a term explains the data better without it, or
    // when beside the term its gain is within the held-out error's scatter);
    // after a removal the forward search resumes once, as the library's
    // does.
    for _round in 0..2 {
        while added.len() < max_terms {
            let remaining: Vec<&Candidate> = scaled
                .iter()
                .filter(is_term)
                .filter(|c| !added.contains(&c.name) && !removed.contains(&c.name))
                .collect();
            if remaining.is_empty() {
                break;
            }
            // A pair only where two places are left.
            let step_search = Search {
                pair_gain_sigmas: search.pair_gain_sigmas.filter(|_| added.len() + 2 <= max_terms),
                ..*search
            };
            let (step, fit, sims) = step_search.step(&current, &selected, &remaining)?;
            simulations += sims;
            let names = step.added.clone();
            steps.push(step);
            let Some(fit) = fit else { break };
            for name in names {
                selected.push(scaled.iter().find(|c| c.name == name).expect("added term"));
                added.push(name);
            }
            current = fit;
        }
        if added.is_empty() {
            break;
        }
        // Every member entered a model without the term added last; beside
        // it, of the models the held-out error does not tell apart (within
        // one standard error) the simplest is kept (the one-standard-error
        // rule, see `eliminate`).
        let checks = search.eliminate(&mut current, &mut selected, &mut simulations, true)?;
        let gone: Vec<String> = checks.iter().filter(|c| c.removed).map(|c| c.name.clone()).collect();
        final_check.extend(checks);
        if gone.is_empty() {
            break;
        }
        added.retain(|a| !gone.contains(a));
        removed.extend(gone);
    }
    Ok(Path {
        steps,
        selected: added,
        removed,
        final_check,
        after: current,
        simulations,
    })
}
