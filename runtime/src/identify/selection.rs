//! Forward stepwise selection of the candidates: which effects and
//! corrections the data warrant, step by step, with every candidate's
//! outcome as a typed [`Verdict`].
//!
//! Each step extends the current model by the candidate that (a) lowers the
//! information criterion ([`bic`]), (b) lowers the held-out error of the
//! cross-validation by run, by more than two standard errors of the
//! run-by-run gain ([`paired_gain`]; more when the step has fitted several
//! candidates: the family-wise bar of [`entry_bar`], so that one of many
//! tries does not enter on the scatter of the runs), and (c) keeps its dissipative
//! parameters positive. The score test ([`super::screen`]) orders the
//! candidates and skips those whose linearised fit cannot lower the
//! criterion, but it never discards one because of another: the
//! candidates it ranks close to the best are fitted together (they are the
//! rivals the report compares), and when none of them passes, the next
//! ones are fitted in the order of their predicted gain until one passes
//! or none is left. Before one that passes is added, every candidate
//! predicted to gain at least half of what it gained once fitted is
//! fitted too (it could beat it), and the best of those that pass is
//! added. When no single candidate passes, pairs whose joint
//! linearised fit beats each member's alone are fitted and validated the
//! same way (a damper and an inertia error may each explain only part of
//! a misfit). The search ends when a step adds nothing, or after
//! [`IdentifyOptions::max_effects`] additions beside the speed loss, which
//! is modelled first (rolling resistance and drag, in steps of their own,
//! and together as one trial).
//!
//! Two checks keep a plausible stand-in from taking the place of the cause:
//! a winner that fitted worse than a correction beyond its prior is fitted
//! together with that correction, and gives way to it when the correction
//! explains most of what it did (the encompassing test, [`Verdict::Encompassed`]);
//! and after the forward search every candidate that a later one followed
//! is tested again against the final model without it (the backward check,
//! [`elimination`]); one that fails is removed and the forward
//! search resumes once.
//!
//! The criterion of every fit, at every step, is computed with the
//! effective sample sizes of the base model's residuals (one reference for
//! the whole search), so the steps' figures add up: a step's base is the
//! previous step's base plus the change it selected.

mod bar;
mod elimination;
mod validation;

use super::confounding::Confounding;
pub use super::criterion::{bic, PLAUSIBLE_PRIOR_SDS};
use super::criterion::{farthest_from_prior, with_priors_on_the_data_scale};
pub use super::cross_validation::{folds_by_run, paired_gain};
use super::fit::fit_trial;
use super::fitted::channel_scales;
use super::screen;
use super::search_order::{added_of, first_passing, SearchOrder};
use super::{
    fit_candidate, Candidate, CandidateFit, EffectParameter, Factory, IdentifyError, IdentifyOptions, ModelFactory,
    RollChannel, Segment, Setup, Weights, NUISANCE,
};
use crate::model::MultibodyModel;
pub(super) use bar::{entry_bar, trial_bar};
pub use bar::{family_wise_sigmas, pair_sigmas};
pub use elimination::MemberCheck;
use serde::Serialize;
use std::sync::atomic::Ordering;

pub use super::verdict::Verdict;

/// One candidate (or a pair of candidates) of a step and its outcome.
#[derive(Clone, Debug, Serialize)]
pub struct Trial {
    /// The candidate's name; a pair is `a + b`.
    pub name: String,
    /// The candidates it adds (one, or two for a pair).
    pub members: Vec<String>,
    /// The score test's predicted change of the criterion, where it applies
    /// (`None`: not screened, e.g. the tyre candidate's other model).
    pub predicted_bic_change: Option<f64>,
    /// The fit, when it was fitted.
    pub fit: Option<CandidateFit>,
    pub verdict: Verdict,
}

/// One step of the stepwise selection: the candidates tried on top of the
/// current model, in the order they were considered.
#[derive(Clone, Debug, Serialize)]
pub struct Step {
    /// Effects of the model this step extends.
    pub base: Vec<String>,
    /// Its criterion and held-out error.
    pub base_bic: f64,
    pub base_cv: f64,
    /// Every candidate of the step with its outcome.
    pub trials: Vec<Trial>,
    /// The candidates added (empty: the search ends here; two for a pair).
    pub added: Vec<String>,
    /// The candidate added against each rival that also explained the
    /// data: how far the data tell them apart ([`confounding`]).
    pub confounded: Vec<Confounding>,
}

impl Step {
    /// The trial that was added, if any.
    pub fn added_trial(&self) -> Option<&Trial> {
        self.trials.iter().find(|t| t.verdict.added())
    }
}

/// Outcome of identification.
#[derive(Clone, Debug, Serialize)]
pub struct Identification {
    /// Channel scales of each segment.
    pub weights: Vec<Weights>,
    /// The base model's fit (no effect added).
    pub before: CandidateFit,
    /// The selected model's fit (equal to `before` when nothing is warranted).
    pub after: CandidateFit,
    /// Selected candidates in order.
    pub selected: Vec<String>,
    pub steps: Vec<Step>,
    /// The backward check: each selected candidate followed by a later
    /// addition, tested against the final model without it
    /// ([`elimination`]).
    pub final_check: Vec<MemberCheck>,
    /// Folds of the cross-validation.
    pub folds: usize,
    /// Fold of each segment (all kicks of a run in one fold).
    pub fold_of: Vec<usize>,
    /// Simulations run in all.
    pub simulations: usize,
}

/// The largest number of pairs fitted in a step whose single candidates all
/// failed, best predicted first (each costs a fit and a cross-validation).
const MAX_PAIRS: usize = 3;

/// Identify which of `candidates` the data warrant, for the free-speed
/// model `M` with base parameters `base` (no effect). `progress` is called
/// after each stage (the base fit, a step's score test, each candidate's fit
/// and cross-validation) with what was done and, where the stage's size is
/// known, how far it is: `(done, total)`.
pub fn identify<M: MultibodyModel>(
    base: &[f64],
    segments: &[Segment],
    candidates: &[Candidate],
    alternative: Option<&dyn ModelFactory>,
    opts: &IdentifyOptions,
    progress: &(dyn Fn(&str, Option<(usize, usize)>) + Sync),
) -> Result<Identification, IdentifyError> {
    if segments.is_empty() {
        return Err(IdentifyError::NoData);
    }
    let (folds, fold_of) = folds_by_run(segments, opts.folds);
    let x0: Vec<[f64; NUISANCE]> = segments.iter().map(|s| s.initial).collect();
    // Channel scales: first a sensor-level guess, then each segment's own
    // residual level per channel under the base model (at least the best
    // segment's, which is about the noise), so that each segment and
    // channel weighs by how well the base model describes it: roll and
    // steer (rad) and speed (m/s) are otherwise incommensurable, and a run
    // that diverges toward a fall would otherwise dominate the fit.
    let guess = |s: &Segment| Weights {
        roll: match s.roll_channel {
            RollChannel::Angle => 0.005,
            RollChannel::Rate => 0.05,
        },
        steer: 0.01,
        speed: 0.05,
    };
    let guesses: Vec<Weights> = segments.iter().map(guess).collect();
    let setup0 = Setup::new::<M>(base, segments, &guesses, &[])?;
    // (No folds: this fit only sets the channel scales.)
    let first = fit_candidate(&setup0, vec![], &[], &x0, &[], opts, None)?;
    let weights = channel_scales(&first.errors);
    let setup0 = Setup::new::<M>(base, segments, &weights, &[])?;
    let mut before = fit_candidate(&setup0, vec![], &[], &first.nuisance, &fold_of, opts, None)?;
    before.bic = bic(&before, &before);
    progress("fitted base model", Some((1, 1)));
    let mut simulations = first.simulations + before.simulations;
    let scaled = with_priors_on_the_data_scale(candidates, &before);
    let search = Search {
        main: &Factory::<M>::new(base.to_vec()),
        alternative,
        segments,
        weights: &weights,
        fold_of: &fold_of,
        opts,
        reference: &before,
        stated: candidates,
        progress,
        gain_sigmas: 2.0,
        // A pair is one of every pair the candidates can form, and the
        // search over pairs ranges over all of them (the screen ranks them
        // by their joint linearised fit): its bar counts them, as the
        // dictionary's does (`pair_sigmas`; 36 candidates, 630
        // pairs: 3.97 standard errors). At the single test's two, on
        // oracle-sim seed base 5's `steer_friction_small`, a roll-rate
        // controller with `I5y` entered at 2.65 standard errors for a gain
        // of half a percent of the held-out error (0.2235 -> 0.2225), beside
        // the right friction: a pair of many fitting the scatter.
        pair_gain_sigmas: Some(pair_sigmas(scaled.len())),
        family_wise: opts.family_wise_bar,
    };

    let mut current = before.clone();
    let mut selected: Vec<&Candidate> = Vec::new();
    let mut steps: Vec<Step> = Vec::new();
    // Two phases: the speed loss first (rolling resistance, drag: they
    // move the speed channel and hardly the lateral motion), then every
    // candidate. Modelling the speed loss first keeps a lateral candidate
    // from being chosen for what it takes up of a missing speed loss, and
    // the speed-decay effects do not count against `max_effects` (every
    // measured run slows, so they would otherwise take the places of the
    // effects the search is for).
    let lateral = |selected: &[&Candidate]| selected.iter().filter(|c| !c.speed_decay).count();
    let mut final_check = Vec::new();
    let mut removed: Vec<String> = Vec::new();
    // Forward, then the backward check; when the check removes a
    // candidate, the forward search resumes once (without it: a removed
    // candidate does not come back).
    for round in 0..2 {
        let phases: &[bool] = if round == 0 { &[true, false] } else { &[false] };
        for &speed_phase in phases {
            while lateral(&selected) < opts.max_effects {
                let remaining: Vec<&Candidate> = scaled
                    .iter()
                    .filter(|c| !selected.iter().any(|s| s.name == c.name))
                    .filter(|c| !removed.contains(&c.name))
                    .filter(|c| !c.alternative_model || alternative.is_some())
                    .filter(|c| !speed_phase || c.speed_decay)
                    .filter(|c| speed_phase || !c.speed_decay || round == 0)
                    .collect();
                if remaining.is_empty() {
                    break;
                }
                let (step, fit, sims) = search.step(&current, &selected, &remaining)?;
                simulations += sims;
                let added = step.added.clone();
                steps.push(step);
                let Some(fit) = fit else { break };
                for name in &added {
                    selected.push(scaled.iter().find(|c| &c.name == name).expect("added candidate"));
                }
                current = fit;
            }
        }
        let checks = search.eliminate(&mut current, &mut selected, &mut simulations, false)?;
        let gone: Vec<String> = checks.iter().filter(|c| c.removed).map(|c| c.name.clone()).collect();
        final_check.extend(checks);
        if gone.is_empty() {
            break;
        }
        removed.extend(gone);
    }
    Ok(Identification {
        weights,
        before,
        after: current,
        selected: selected.iter().map(|c| c.name.clone()).collect(),
        steps,
        final_check,
        folds,
        fold_of,
        simulations,
    })
}

/// What every step of one search shares.
pub(super) struct Search<'s> {
    pub(super) main: &'s dyn ModelFactory,
    pub(super) alternative: Option<&'s dyn ModelFactory>,
    pub(super) segments: &'s [Segment],
    pub(super) weights: &'s [Weights],
    pub(super) fold_of: &'s [usize],
    pub(super) opts: &'s IdentifyOptions,
    /// The base model's fit: the effective sample sizes of every criterion.
    pub(super) reference: &'s CandidateFit,
    /// The candidates with their priors as stated (the plausibility of a
    /// rival; the fits use them on the data's scale).
    pub(super) stated: &'s [Candidate],
    pub(super) progress: &'s (dyn Fn(&str, Option<(usize, usize)>) + Sync),
    /// Standard errors by which a candidate's held-out gain, paired run by
    /// run, must exceed zero to enter (2 for the library's search).
    pub(super) gain_sigmas: f64,
    /// The same for a pair, or `None` when no pair may enter (one place
    /// left). A pair is one of many more hypotheses than a single
    /// candidate: the library's and the dictionary's bars count the pairs
    /// their candidates can form. The speed loss's two laws, fitted
    /// together as one expected trial, keep `gain_sigmas`.
    pub(super) pair_gain_sigmas: Option<f64>,
    /// Whether the bar of a step rises with the candidates it has fitted
    /// ([`family_wise_sigmas`] of them, at least `gain_sigmas`): a step that
    /// fits nine candidates gives chance nine tries at the bar of a single
    /// test. The speed-decay laws keep the single bar: every measured run
    /// slows, so they are expected rather than one hypothesis of many. The
    /// dictionary's search sets its bars for the whole dictionary instead.
    pub(super) family_wise: bool,
}

/// A trial being considered: its members (indices into the step's
/// remaining candidates) and what the step knows of it so far.
pub(super) struct Pending<'c> {
    pub(super) members: Vec<&'c Candidate>,
    pub(super) predicted: Option<f64>,
    pub(super) fit: Option<(CandidateFit, Setup<'c>)>,
    pub(super) verdict: Option<Verdict>,
}

impl<'c> Pending<'c> {
    pub(super) fn name(&self) -> String {
        self.members
            .iter()
            .map(|c| c.name.as_str())
            .collect::<Vec<_>>()
            .join(" + ")
    }
}

/// The trials of one step: each remaining candidate alone, with its
/// predicted change of the criterion (`predicted`, aligned with
/// `remaining`; `None`: not screened), and, while neither speed-loss law
/// is in the model (`selected`), the two together. Returns the trials and
/// how many of them are single candidates (the first ones).
pub(super) fn trials_of<'c>(
    remaining: &[&'c Candidate],
    selected: &[&'c Candidate],
    predicted: &[Option<f64>],
) -> (Vec<Pending<'c>>, usize) {
    // The speed loss's laws are always fitted, never screened: every run
    // slows, so they are expected rather than one hypothesis of many, and
    // the score test misjudges them beside the law already in the model
    // (on an independent set it predicted drag, beside rolling resistance,
    // to raise the criterion by 65; fitted, drag lowered it by 613 and took
    // the rolling resistance from 0.028 to 0.016, near its truth).
    let mut pending: Vec<Pending<'c>> = remaining
        .iter()
        .zip(predicted)
        .map(|(c, p)| Pending {
            members: vec![*c],
            predicted: if c.speed_decay { None } else { *p },
            fit: None,
            verdict: None,
        })
        .collect();
    // The speed loss's laws together: every run has both rolling resistance
    // and drag, and the speed record tells them apart only by how the loss
    // grows with speed; fitted one at a time, the first takes up the
    // other's part (drag at twice its value) and the second then gains too
    // little on held-out runs. The pair is fitted beside each alone (not
    // screened: always fitted), and the criterion chooses among those that
    // pass. It is fitted in every step while neither law is in the model,
    // not only in the speed phase: beside a large lateral misfit (Coulomb
    // steer friction missing, the simulated weave far from the measured
    // one) the speed record's share of the fit can drive one law below
    // zero, and once the lateral effect is in, drag alone would otherwise
    // take the whole loss (an independent set: `CdA` at twice its value, no
    // rolling resistance, and two false corrections for what that left).
    let single = pending.len();
    let speed_laws: Vec<&'c Candidate> = remaining.iter().copied().filter(|c| c.speed_decay).collect();
    if speed_laws.len() >= 2 && !selected.iter().any(|c| c.speed_decay) {
        pending.push(Pending {
            members: speed_laws,
            predicted: None,
            fit: None,
            verdict: None,
        });
    }
    (pending, single)
}

impl<'s> Search<'s> {
    /// One step on top of `current` (with the candidates `selected`): the
    /// step's record, the fit of the extended model when something was
    /// added, and the simulations run.
    pub(super) fn step(
        &self,
        current: &CandidateFit,
        selected: &[&'s Candidate],
        remaining: &[&'s Candidate],
    ) -> Result<(Step, Option<CandidateFit>, usize), IdentifyError> {
        let base_bic = bic(current, self.reference);
        let screened = screen::screen(&screen::Screen {
            main: self.main,
            alternative: self.alternative,
            segments: self.segments,
            weights: self.weights,
            selected,
            remaining,
            current,
            reference: self.reference,
        });
        let mut simulations = screened.simulations;
        (self.progress)(&format!("score test of {} candidates", remaining.len()), None);
        // Predicted changes against the step's base: the screen's reference
        // is the current fit one Gauss-Newton step further, never above it.
        let reference_bic = screened.reference.map_or(base_bic, |r| r.min(base_bic));
        let change = |p: Option<f64>| p.map(|p| p - reference_bic);
        let predicted: Vec<Option<f64>> = screened.predictions.iter().map(|p| change(*p)).collect();
        let (mut pending, single) = trials_of(remaining, selected, &predicted);
        for p in &mut pending {
            if let Some(d) = p.predicted.filter(|d| !(*d < 0.0)) {
                p.verdict = Some(Verdict::NoPredictedGain {
                    predicted_bic_change: d,
                });
            }
        }
        let predicted: Vec<Option<f64>> = pending
            .iter()
            .map(|p| {
                if p.verdict.is_some() {
                    Some(f64::INFINITY)
                } else {
                    p.predicted
                }
            })
            .collect();
        let mut plan = SearchOrder::of(&predicted);
        // The compute budget, if one is set: the contenders, or
        // `max_fits_per_step` in the order of the search if more.
        let budget = self
            .opts
            .max_fits_per_step
            .map_or(plan.order.len(), |most| plan.contenders.max(most));
        for &i in plan.order.iter().skip(budget) {
            pending[i].verdict = Some(Verdict::BeyondBudget {
                predicted_bic_change: pending[i].predicted.unwrap_or(f64::NAN),
                budget,
            });
        }
        plan.truncate(budget);
        let mut fitted = 0;
        let mut winner = first_passing(
            &mut pending,
            &plan,
            |pending, i| {
                self.fit(&mut pending[i], current, selected, base_bic)?;
                fitted += 1;
                (self.progress)(
                    &format!("fitted {}", pending[i].name()),
                    Some((fitted, plan.order.len().max(fitted))),
                );
                Ok(())
            },
            |pending| self.validate(pending, current),
            |pending, w| pending[w].fit.as_ref().map_or(f64::NAN, |(f, _)| base_bic - f.bic),
        )?;
        // No single candidate passed: pairs whose joint linearised fit
        // beats each member's alone, best predicted first.
        if winner.is_none() && self.pair_gain_sigmas.is_some() {
            let mut pairs = screened.pairs.clone();
            pairs.sort_by(|a, b| a.1.total_cmp(&b.1));
            // A pair this step has already fitted as one trial (the speed
            // loss's two laws) is not fitted again: the same fit, listed
            // twice in the report.
            let fitted_together = |a: usize, b: usize| {
                pending.iter().any(|p| {
                    p.members.len() == 2
                        && p.members.iter().any(|c| std::ptr::eq(*c, remaining[a]))
                        && p.members.iter().any(|c| std::ptr::eq(*c, remaining[b]))
                })
            };
            pairs.retain(|((a, b), p)| *p < reference_bic && !fitted_together(*a, *b));
            pairs.truncate(MAX_PAIRS);
            let count = pairs.len();
            for (n, ((a, b), p)) in pairs.into_iter().enumerate() {
                let mut pair = Pending {
                    members: vec![remaining[a], remaining[b]],
                    predicted: change(Some(p)),
                    fit: None,
                    verdict: None,
                };
                self.fit(&mut pair, current, selected, base_bic)?;
                (self.progress)(&format!("fitted pair {}", pair.name()), Some((n + 1, count)));
                pending.push(pair);
                winner = self.validate(&mut pending, current)?;
                if winner.is_some() {
                    break;
                }
            }
        }
        // Nothing plausible passed: the corrections the data pull beyond
        // their stated uncertainty are cross-validated last (a measurement
        // can be wrong by more than its stated uncertainty, a forgotten lamp
        // on the handlebar; the report gives the distance). Those not
        // reached keep their verdict.
        if winner.is_none() {
            let far: Vec<usize> = (0..pending.len())
                .filter(|&i| matches!(pending[i].verdict, Some(Verdict::ImplausibleUnderPrior { .. })))
                .collect();
            let kept: Vec<Option<Verdict>> = far.iter().map(|&i| pending[i].verdict.take()).collect();
            winner = self.validate(&mut pending, current)?;
            for (&i, v) in far.iter().zip(kept) {
                if pending[i].verdict.is_none() {
                    pending[i].verdict = v;
                }
            }
        }
        // A plausible winner that a correction beyond its prior explains
        // away (the encompassing test).
        if let Some(w) = winner.filter(|&w| w < single) {
            if let Some(x) = self.encompassed(&mut pending, w, single, current, selected, base_bic)? {
                winner = Some(x);
            }
        }
        // Those behind the winner.
        if let Some(w) = winner {
            let added = pending[w].name();
            for p in pending.iter_mut().filter(|p| p.verdict.is_none()) {
                // `validate` gives every fitted single candidate its
                // verdict; one still without is a fit the step made but
                // did not cross-validate once it had its winner.
                p.verdict = Some(match &p.fit {
                    Some((f, _)) => Verdict::CriterionAboveAdded {
                        bic_change: f.bic - base_bic,
                        added: added.clone(),
                    },
                    None => Verdict::BehindAdded {
                        predicted_bic_change: p.predicted.unwrap_or(f64::NAN),
                        added: added.clone(),
                    },
                });
            }
        }
        let confounded = match winner.filter(|&w| w < single) {
            Some(w) => self.rivals(&pending, w, selected, base_bic),
            None => Vec::new(),
        };
        let mut trials = Vec::with_capacity(pending.len());
        let mut added_fit = None;
        let mut added = Vec::new();
        for (i, p) in pending.into_iter().enumerate() {
            let name = p.name();
            let members: Vec<String> = p.members.iter().map(|c| c.name.clone()).collect();
            let fit = p.fit.map(|(mut f, setup)| {
                f.simulations = setup.simulations.load(Ordering::Relaxed);
                simulations += f.simulations;
                f
            });
            if Some(i) == winner {
                added_fit = fit.clone();
                added = members.clone();
            }
            trials.push(Trial {
                name,
                members,
                predicted_bic_change: p.predicted,
                fit,
                verdict: p.verdict.expect("every trial has a verdict"),
            });
        }
        let step = Step {
            base: current.effects.clone(),
            base_bic,
            base_cv: current.cv,
            trials,
            added,
            confounded,
        };
        Ok((step, added_fit, simulations))
    }

    /// Fit a pending trial on top of `current`; a failed fit gets its
    /// verdict, and so does a fit that is not physical or does not lower
    /// the criterion.
    pub(super) fn fit(
        &self,
        p: &mut Pending<'s>,
        current: &CandidateFit,
        selected: &[&'s Candidate],
        base_bic: f64,
    ) -> Result<(), IdentifyError> {
        let mut active: Vec<&Candidate> = selected.to_vec();
        active.extend(p.members.iter().copied());
        let setup = match self.alternative.filter(|_| active.iter().any(|a| a.alternative_model)) {
            Some(f) => f.setup(self.segments, self.weights, &active)?,
            None => self.main.setup(self.segments, self.weights, &active)?,
        };
        // A start: the current values, then each new parameter's.
        let start_with = |value: &dyn Fn(&Candidate, &EffectParameter) -> f64| -> Vec<f64> {
            let mut g = current.values.clone();
            for c in &p.members {
                g.extend(c.parameters.iter().map(|q| value(c, q)));
            }
            g
        };
        let small = |q: &EffectParameter| q.initial.unwrap_or(0.1 * q.scale);
        let g0 = start_with(&|_, q| small(q));
        let effects: Vec<String> = active.iter().flat_map(|a| a.effects.clone()).collect();
        let ks = current.values.len();
        let fit_from = |g0: &[f64]| {
            fit_trial(
                &setup,
                effects.clone(),
                g0,
                &current.nuisance,
                self.fold_of,
                self.opts,
                Some(self.reference),
                ks..g0.len(),
            )
        };
        let mut fitted = fit_from(&g0);
        // A law that is not smooth at the candidate's absence (Coulomb
        // friction: a torque large enough to stick the steer changes the
        // response in kind, not in degree) has minima a local search from
        // a small start does not cross: it is fitted from starts at its
        // scale and four times it as well, and the best by the criterion is
        // kept. The law's shape (its smoothing rate) starts from the
        // bicycle's value in the first and from the middle of its range
        // (on a log scale) in these: the criterion is not convex in the
        // shape, and a fit started on a bound can end on it at a point
        // where the data still pull it outward (a local minimum on the
        // bound) while a better one lies inside.
        if p.members.iter().any(|c| c.nonsmooth) {
            let mid_range = |q: &EffectParameter| match (q.lower, q.upper) {
                (Some(lo), Some(hi)) if lo > 0.0 && hi > lo => (lo * hi).sqrt(),
                _ => small(q),
            };
            for factor in [1.0, 4.0] {
                let start = start_with(&|c, q| match (c.nonsmooth, q.shape) {
                    (true, false) => factor * q.scale,
                    (true, true) => mid_range(q),
                    _ => small(q),
                });
                if let Ok(again) = fit_from(&start) {
                    if fitted
                        .as_ref()
                        .map_or(true, |f| again.bic < f.bic || !f.bic.is_finite())
                    {
                        fitted = Ok(again);
                    }
                }
            }
        }
        // The candidate's model holds the current one (its parameters at
        // their absence), so a fit that ends with a larger sum of squares
        // than the current model's stopped in a local minimum away from
        // it (a friction torque started at a tenth of its scale can lock a
        // damped response): fitted again from its absence, the better of
        // the two is kept.
        if let Ok(f) = &fitted {
            if f.chi2 > current.chi2 * (1.0 + 1e-9) {
                let from_absence = start_with(&|_, q| match (q.shape, q.prior) {
                    (true, _) => small(q),
                    (false, Some((mean, _))) => mean,
                    (false, None) => q.lower.unwrap_or(0.0),
                });
                if from_absence != g0 {
                    if let Ok(again) = fit_from(&from_absence) {
                        if again.chi2 < f.chi2 {
                            fitted = Ok(again);
                        }
                    }
                }
            }
        }
        match fitted {
            Ok(f) => {
                let farthest = self.farthest_from_prior(&p.members, &f.values[ks.min(f.values.len())..]);
                if !f.physical {
                    p.verdict = Some(Verdict::NotPhysical);
                } else if !(f.bic < base_bic) {
                    p.verdict = Some(Verdict::NoCriterionGain {
                        bic_change: f.bic - base_bic,
                    });
                } else if let Some((symbol, value, prior_sds)) =
                    farthest.filter(|(_, _, sds)| *sds > PLAUSIBLE_PRIOR_SDS)
                {
                    p.verdict = Some(Verdict::ImplausibleUnderPrior {
                        symbol,
                        value,
                        prior_sds,
                    });
                }
                p.fit = Some((f, setup));
            }
            Err(e) => p.verdict = Some(Verdict::FitFailed { reason: e.to_string() }),
        }
        Ok(())
    }

    /// Whether a candidate's fitted values are plausible under its stated
    /// prior: within [`PLAUSIBLE_PRIOR_SDS`] prior standard deviations of the
    /// measured value (a candidate without a prior, an effect, always is).
    pub(super) fn plausible(&self, candidate: &Candidate, values: &[f64]) -> bool {
        farthest_from_prior(self.stated, &[candidate], values).is_none_or(|(_, _, sds)| sds <= PLAUSIBLE_PRIOR_SDS)
    }

    /// [`farthest_from_prior`] under the stated priors.
    fn farthest_from_prior(&self, members: &[&Candidate], values: &[f64]) -> Option<(String, f64, f64)> {
        farthest_from_prior(self.stated, members, values)
    }
}

#[cfg(test)]
#[path = "selection_tests.rs"]
pub(super) mod tests;
