//! Cross-validation of a step's fitted trials and the verdict of each:
//! whether it lowers the held-out error consistently over the runs, at
//! the bar of its step ([`entry_bar`]), and which of those that pass is
//! added ([`added_of`]).

use super::super::confounding::HeldOutGain;
use super::super::{cross_validate, CandidateFit, IdentifyError};
use super::{added_of, bic, entry_bar, paired_gain, trial_bar, Pending, Search, Verdict};

impl<'s> Search<'s> {
    /// Cross-validate the fitted trials without a verdict, and judge again
    /// those that passed an earlier call of the step, in the order of the
    /// criterion: the index of the one added, if any passes.
    pub(super) fn validate(
        &self,
        pending: &mut [Pending<'s>],
        current: &CandidateFit,
    ) -> Result<Option<usize>, IdentifyError> {
        // The fitted trials waiting, and those that passed an earlier call
        // of the same step (a passing candidate waits while the candidates
        // that could beat it are fitted: [`first_passing`]); those are
        // judged again among all, without a second cross-validation.
        let passed_before = |p: &Pending<'s>| p.verdict.as_ref().is_some_and(Verdict::passed);
        let mut order: Vec<usize> = (0..pending.len())
            .filter(|&i| (pending[i].verdict.is_none() || passed_before(&pending[i])) && pending[i].fit.is_some())
            .collect();
        order.sort_by(|&a, &b| {
            let bic = |i: usize| pending[i].fit.as_ref().map_or(f64::INFINITY, |f| f.0.bic);
            bic(a).total_cmp(&bic(b))
        });
        let total = order.len();
        let mut passed: Vec<usize> = Vec::new();
        // Every trial waiting here is fitted already: one family for all.
        let family = self.family(pending);
        for (done, i) in order.into_iter().enumerate() {
            let name = pending[i].name();
            let verdict = if passed_before(&pending[i]) {
                self.judge(&pending[i], current, family)
            } else {
                let verdict = self.validate_one(&mut pending[i], current, family);
                (self.progress)(&format!("cross-validated {name}"), Some((done + 1, total)));
                verdict
            };
            let Some(verdict) = verdict else {
                continue;
            };
            if verdict.added() {
                passed.push(i);
            }
            pending[i].verdict = Some(verdict);
        }
        // Every fitted candidate waiting is cross-validated. Of those that
        // pass, the criterion's first is added unless another predicts the
        // held-out runs consistently better ([`added_of`]): the held-out
        // error is the figure the report stands on, and the criterion (a
        // log of each kick's misfit, with effective sample sizes that
        // overstate the data of smooth residuals) can rank a wrong
        // candidate first, but a difference of held-out errors within the
        // runs' scatter does not overturn it.
        let cvs: Vec<f64> = pending
            .iter()
            .map(|p| p.fit.as_ref().map_or(f64::INFINITY, |f| f.0.cv))
            .collect();
        let better = |a: usize, b: usize| match (&pending[a].fit, &pending[b].fit) {
            (Some((fa, _)), Some((fb, _))) => {
                paired_gain(fa, fb, self.weights).is_some_and(|(gain, stderr)| gain > 2.0 * stderr)
            }
            _ => false,
        };
        let Some(best) = added_of(&passed, &cvs, better) else {
            return Ok(None);
        };
        let added = pending[best].name();
        let added_cv = cvs[best];
        let first = passed[0];
        for &i in passed.iter().filter(|&&i| i != best) {
            let bic_change = pending[i]
                .fit
                .as_ref()
                .map_or(f64::NAN, |f| f.0.bic - bic(current, self.reference));
            pending[i].verdict = Some(if i == first {
                Verdict::PassedHeldOutBelow {
                    bic_change,
                    cv: cvs[i],
                    added: added.clone(),
                    added_cv,
                }
            } else {
                Verdict::PassedCriterionAbove {
                    bic_change,
                    cv: cvs[i],
                    added: added.clone(),
                }
            });
        }
        Ok(Some(best))
    }

    /// The size of the step's family of hypotheses so far: the trials it
    /// has fitted that add a candidate other than a speed-decay law
    /// (singles and pairs alike; not the pairs of the encompassing test,
    /// which are not candidates). Whether it raises the bar is
    /// [`entry_bar`]'s to decide ([`Search::family_wise`]).
    pub(in crate::identify) fn family(&self, pending: &[Pending<'s>]) -> usize {
        pending
            .iter()
            .filter(|p| p.fit.is_some() && !matches!(p.verdict, Some(Verdict::NotAdded)))
            .filter(|p| !p.members.iter().all(|c| c.speed_decay))
            .count()
    }

    /// Cross-validate one fitted trial against `current`, one of `family`
    /// hypotheses its step has fitted ([`Search::family`]): its verdict
    /// (`None`: not fitted).
    pub(in crate::identify) fn validate_one(
        &self,
        p: &mut Pending<'s>,
        current: &CandidateFit,
        family: usize,
    ) -> Option<Verdict> {
        let (fit, setup) = p.fit.as_mut()?;
        cross_validate(setup, fit, self.fold_of, self.opts);
        self.judge(p, current, family)
    }

    /// The verdict of a cross-validated trial against `current`, one of
    /// `family` hypotheses its step has fitted (`None`: not fitted).
    fn judge(&self, p: &Pending<'s>, current: &CandidateFit, family: usize) -> Option<Verdict> {
        let expected = p.members.iter().all(|c| c.speed_decay);
        let single_bar = trial_bar(p.members.len(), expected, self.gain_sigmas, self.pair_gain_sigmas);
        let (sigmas, family) = entry_bar(single_bar, self.family_wise && !expected, family);
        let (fit, _) = p.fit.as_ref()?;
        let held_out_gain = paired_gain(current, fit, self.weights);
        Some(if !(fit.cv < current.cv) {
            Verdict::HeldOutNotLower {
                cv: fit.cv,
                base_cv: current.cv,
            }
        } else if let Some((gain, stderr)) = held_out_gain.filter(|(d, se)| !(*d > sigmas * se)) {
            Verdict::HeldOutGainNotConsistent {
                gain,
                stderr,
                sigmas,
                family,
            }
        } else {
            Verdict::Added {
                bic_change: fit.bic - bic(current, self.reference),
                cv: fit.cv,
                base_cv: current.cv,
                held_out_gain: held_out_gain.map(|(gain, stderr)| HeldOutGain { gain, stderr }),
            }
        })
    }
}
