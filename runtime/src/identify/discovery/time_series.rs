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

use super::super::criterion::with_priors_on_the_data_scale;
use super::super::selection::{family_wise_sigmas, Identification, MemberCheck, Search, Step};
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
    /// Simulations run.
    pub simulations: usize,
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
        pair_gain_sigmas: Some(family_wise_sigmas(terms.len() * terms.len().saturating_sub(1) / 2)),
    };
    let is_term = |c: &&Candidate| terms.iter().any(|t| t.name == c.name);
    let mut current = library.after.clone();
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
                ..search
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
    Ok(Ok(TimeSeriesDiscovery {
        steps,
        selected: added,
        removed,
        final_check,
        after: current,
        simulations,
    }))
}
