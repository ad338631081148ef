//! The backward check of a forward search: every selected candidate must
//! still earn its place once the ones added after it are in the model.
//!
//! A forward step judges a candidate against the model of that step. A
//! later addition can explain the same misfit better (a steer friction
//! taken up early for what a rear-frame roll inertia explains once the
//! speed loss is right), and the early one then stays in the model with a
//! value near zero. Each selected candidate that was followed by another
//! is therefore tested again, against the final model without it: it
//! stays while the criterion and the held-out error are lower with it
//! (the entry test's criteria, without its bar of a consistent gain over
//! the runs, which is the evidence for entering; exit is easier than entry,
//! so the search cannot cycle). Of those that fail, the one whose removal
//! lowers the criterion most is removed, the model refitted without it,
//! and the others tested again. (The last one added was tested against
//! exactly the model without it when it entered.)
//!
//! Two rules more. A model without the member that puts a correction
//! beyond [`PLAUSIBLE_PRIOR_SDS`] of its stated uncertainty, where every
//! correction is plausible with the member, is no rival (the entry test
//! refuses such a fit too): the member keeps its place,
//! since what it explains would otherwise be pushed into a measured
//! parameter. And a caller may ask for the one-standard-error rule of
//! cross-validation (Breiman et al. 1984, *Classification and Regression
//! Trees*, sec. 3.4.3; Hastie, Tibshirani & Friedman 2009, *The Elements
//! of Statistical Learning*, sec. 7.10): a member stays only if the model
//! without it predicts the held-out data worse by more than one standard
//! error of the held-out error. The search in the time series asks for
//! it: its members entered a model without the term added last, and a
//! correction or term that stood in for that force keeps, beside it, a
//! gain that may be consistent over the runs (a calibration's residue is
//! the same in every run) yet is far inside the scatter of the held-out
//! error; of the models the data do not tell apart, the simplest is
//! kept.

use super::{Search, Verdict};
use crate::identify::criterion::{bic, PLAUSIBLE_PRIOR_SDS};
use crate::identify::cross_validation::held_out_standard_error;
use crate::identify::{cross_validate, fit_candidate, Candidate, CandidateFit, IdentifyError};
use serde::Serialize;

/// A selected candidate tested against the final model without it.
#[derive(Clone, Debug, Serialize)]
pub struct MemberCheck {
    /// The candidate tested.
    pub name: String,
    /// The candidates of the model it was tested in (it included).
    pub model: Vec<String>,
    /// The fit of that model without it (`None`: the fit failed; the
    /// candidate keeps its place).
    pub without: Option<CandidateFit>,
    /// The criterion with it minus without it (negative: it still lowers
    /// the criterion; `NaN` when the fit without it failed).
    pub bic_change: f64,
    /// Held-out error with it, and without it (`NaN`: not cross-validated,
    /// the criterion decided).
    pub cv_with: f64,
    pub cv_without: f64,
    /// The entry test of the candidate against the model without it:
    /// [`Verdict::Added`] means it keeps its place (its numbers are those
    /// of keeping it); any other verdict is why it was removed.
    pub verdict: Verdict,
    /// Whether it was removed.
    pub removed: bool,
    /// Why a member kept its place although the criterion or the held-out
    /// error alone would remove it: the fit without it puts this correction
    /// (symbol, value, distance in stated prior standard deviations)
    /// beyond [`PLAUSIBLE_PRIOR_SDS`].
    pub without_implausible: Option<(String, f64, f64)>,
}

impl<'s> Search<'s> {
    /// Test every selected candidate followed by a later addition (speed
    /// decay apart: every run slows, and its law is chosen in a phase of its
    /// own) against `current` without it; remove those that fail, one at a
    /// time. With `one_standard_error`, a member must also lower the
    /// held-out error by more than one standard error of it. Returns the
    /// checks in the order made.
    pub(in crate::identify) fn eliminate(
        &self,
        current: &mut CandidateFit,
        selected: &mut Vec<&Candidate>,
        simulations: &mut usize,
        one_standard_error: bool,
    ) -> Result<Vec<MemberCheck>, IdentifyError> {
        let mut checks = Vec::new();
        // Each round tests every candidate followed by a later lateral
        // addition; a removal changes the model, so the next round tests
        // the rest again. At most one round per selected candidate.
        // The last one added was tested against exactly the model without
        // it when it entered; after a removal the model has changed, and
        // every member is tested.
        let mut changed = false;
        loop {
            let last_lateral = selected.iter().rposition(|c| !c.speed_decay);
            let testable: Vec<usize> = (0..selected.len())
                .filter(|&j| !selected[j].speed_decay && (changed || Some(j) != last_lateral))
                .collect();
            if testable.is_empty() {
                break;
            }
            let mut failing: Vec<(usize, f64, usize)> = Vec::new();
            let start = checks.len();
            for &j in &testable {
                let (check, fit) = self.without(current, selected, j, one_standard_error, simulations)?;
                if check.removed {
                    let change = fit.as_ref().map_or(f64::INFINITY, |f| f.bic - current.bic);
                    failing.push((j, change, checks.len()));
                }
                checks.push((check, fit));
            }
            // The one whose removal lowers the criterion most goes.
            failing.sort_by(|a, b| a.1.total_cmp(&b.1));
            let Some(&(j, _, at)) = failing.first() else {
                break;
            };
            // Only one is removed per round; the others that failed keep
            // their verdict and are tested again against the refitted model.
            for (k, (c, _)) in checks.iter_mut().enumerate().skip(start) {
                c.removed = k == at;
            }
            let refit = checks[at].1.clone().expect("a removal has its fit");
            (self.progress)(
                &format!("removed {} (no longer earns its place)", selected[j].name),
                None,
            );
            selected.remove(j);
            *current = refit;
            changed = true;
        }
        Ok(checks.into_iter().map(|(c, _)| c).collect())
    }

    /// The entry test of `selected[j]` against the model `current` without
    /// it: the check, and the fit without it (cross-validated when the
    /// criterion alone does not decide). With `one_standard_error`, the
    /// held-out error without it must exceed the current one by more than
    /// one standard error of the current one.
    fn without(
        &self,
        current: &CandidateFit,
        selected: &[&Candidate],
        j: usize,
        one_standard_error: bool,
        simulations: &mut usize,
    ) -> Result<(MemberCheck, Option<CandidateFit>), IdentifyError> {
        let model: Vec<String> = selected.iter().map(|c| c.name.clone()).collect();
        let name = selected[j].name.clone();
        (self.progress)(&format!("testing {name} against the model without it"), None);
        let Some(fit) = self.fit_without(current, selected, j)? else {
            let keep = Verdict::Added {
                bic_change: f64::NAN,
                cv: current.cv,
                base_cv: f64::NAN,
                held_out_gain: None,
            };
            return Ok((
                MemberCheck {
                    name,
                    model,
                    without: None,
                    bic_change: f64::NAN,
                    cv_with: current.cv,
                    cv_without: f64::NAN,
                    verdict: keep,
                    removed: false,
                    without_implausible: None,
                },
                None,
            ));
        };
        let active = without_member(selected, j);
        let with_bic = bic(current, self.reference);
        // The exit test is the entry test's criteria without its bar of
        // consistency: a candidate stays while the criterion and the
        // held-out error are lower with it; it goes when either is not.
        // (The bar of a held-out gain beyond two standard errors over the
        // runs is for entering: evidence enough to claim a cause. Applied
        // to a member, it would remove one whose removal raises both the
        // criterion and the held-out error, whenever one run's gain makes
        // the spread over runs wide.) A model kept by this test is
        // cross-validated either way: it may become the final one.
        // Only a removal that takes a model whose corrections are all
        // plausible to one with a correction beyond the plausible range
        // makes the rival implausible; where a correction already lies
        // beyond it with the member, both models are implausible, and the
        // usual criteria decide.
        let with_plausible = self
            .farthest_from_prior(selected, &current.values)
            .is_none_or(|(_, _, sds)| sds <= PLAUSIBLE_PRIOR_SDS);
        let implausible = self
            .farthest_from_prior(&active, &fit.values)
            .filter(|(_, _, sds)| with_plausible && *sds > PLAUSIBLE_PRIOR_SDS);
        let kept = Verdict::Added {
            bic_change: with_bic - fit.bic,
            cv: current.cv,
            base_cv: fit.cv,
            held_out_gain: None,
        };
        let verdict = if implausible.is_some() {
            kept
        } else if !(with_bic < fit.bic) {
            Verdict::NoCriterionGain {
                bic_change: with_bic - fit.bic,
            }
        } else if !(current.cv < fit.cv) {
            Verdict::HeldOutNotLower {
                cv: current.cv,
                base_cv: fit.cv,
            }
        } else if let Some(stderr) = one_standard_error
            .then(|| held_out_standard_error(current, self.weights))
            .flatten()
            .filter(|se| !(fit.cv - current.cv > *se))
        {
            Verdict::WithinOneStandardError {
                cv: current.cv,
                base_cv: fit.cv,
                stderr,
            }
        } else {
            kept
        };
        *simulations += fit.simulations;
        let removed = !verdict.added();
        Ok((
            MemberCheck {
                name,
                model,
                bic_change: with_bic - fit.bic,
                cv_with: current.cv,
                cv_without: fit.cv,
                without: Some(fit.clone()),
                verdict,
                removed,
                without_implausible: implausible,
            },
            Some(fit),
        ))
    }

    /// The model `current` refitted without `selected[j]`, from the
    /// values of the others, and cross-validated by the same folds
    /// (`None`: the fit failed). Its `simulations` count those of the fit
    /// and of the cross-validation.
    pub(in crate::identify) fn fit_without(
        &self,
        current: &CandidateFit,
        selected: &[&Candidate],
        j: usize,
    ) -> Result<Option<CandidateFit>, IdentifyError> {
        let active = without_member(selected, j);
        // The member's parameters in the current values: after those of
        // the candidates before it.
        let offset: usize = selected[..j].iter().map(|c| c.parameters.len()).sum();
        let width = selected[j].parameters.len();
        let mut g0 = current.values.clone();
        g0.drain(offset..offset + width);
        let setup = match self.alternative.filter(|_| active.iter().any(|a| a.alternative_model)) {
            Some(f) => f.setup(self.segments, self.weights, &active)?,
            None => self.main.setup(self.segments, self.weights, &active)?,
        };
        let effects: Vec<String> = active.iter().flat_map(|a| a.effects.clone()).collect();
        let Ok(mut fit) = fit_candidate(
            &setup,
            effects,
            &g0,
            &current.nuisance,
            self.fold_of,
            self.opts,
            Some(self.reference),
        ) else {
            return Ok(None);
        };
        cross_validate(&setup, &mut fit, self.fold_of, self.opts);
        fit.simulations = setup.simulations.load(std::sync::atomic::Ordering::Relaxed);
        Ok(Some(fit))
    }
}

/// The members of `selected` but the `j`-th, in order.
fn without_member<'c>(selected: &[&'c Candidate], j: usize) -> Vec<&'c Candidate> {
    let mut active = selected.to_vec();
    active.remove(j);
    active
}
