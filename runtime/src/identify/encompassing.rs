//! The encompassing test: a plausible candidate that passed a step, but
//! fitted worse than a correction beyond its prior, is fitted together with
//! that correction; when the correction explains most of what the winner
//! did, the winner was a stand-in and the correction takes its place.
//!
//! Corrections beyond [`PLAUSIBLE_PRIOR_SDS`](super::PLAUSIBLE_PRIOR_SDS) standard deviations of their
//! measured value are otherwise tried only when nothing plausible passes
//! (they more often absorb a missing effect than find a gross measurement
//! error). This test lets a gross error through only where the data say
//! so: the plausible winner keeps less than half of its shift, or falls
//! within two standard errors of its absence, beside the correction.

use super::cross_validation::cross_validate;
use super::selection::{Pending, Search, Verdict};
use super::{Candidate, CandidateFit, IdentifyError};

impl<'s> Search<'s> {
    /// The encompassing test of a plausible winner `w` against the
    /// corrections of the step that fitted better but lie beyond their
    /// prior: fitted together with the best of them, does the winner still
    /// explain anything? When its parameters fall within two standard
    /// errors of their absence, or keep less than half of their shift,
    /// while the correction's shift stays significant, the winner was a
    /// proxy for the correction, and the correction is added in its place
    /// if it passes the held-out test itself (a measurement can be wrong by
    /// more than its stated uncertainty: a lamp or a bag on the handlebar).
    /// Returns the new winner, if any; the pair's fit is kept as a trial.
    pub(super) fn encompassed(
        &self,
        pending: &mut Vec<Pending<'s>>,
        w: usize,
        single: usize,
        current: &CandidateFit,
        selected: &[&'s Candidate],
        base_bic: f64,
    ) -> Result<Option<usize>, IdentifyError> {
        let bic_of = |p: &Pending<'s>| p.fit.as_ref().map_or(f64::INFINITY, |f| f.0.bic);
        let wbic = bic_of(&pending[w]);
        let Some(x) = (0..single)
            .filter(|&i| matches!(pending[i].verdict, Some(Verdict::ImplausibleUnderPrior { .. })))
            .filter(|&i| bic_of(&pending[i]) < wbic)
            .min_by(|&a, &b| bic_of(&pending[a]).total_cmp(&bic_of(&pending[b])))
        else {
            return Ok(None);
        };
        if pending[w].members.len() != 1 {
            return Ok(None);
        }
        let mut pair = Pending {
            members: vec![pending[w].members[0], pending[x].members[0]],
            predicted: None,
            fit: None,
            verdict: None,
        };
        self.fit(&mut pair, current, selected, base_bic)?;
        (self.progress)(&format!("fitted pair {} (encompassing test)", pair.name()), None);
        let ks = current.values.len();
        let kw = pending[w].members[0].parameters.len();
        // How far each member's parameters lie from their absence (zero for
        // an effect, the measured value for a correction), in standard
        // errors of the joint fit: the largest of each member.
        let distance = |f: &CandidateFit, from: usize, member: &Candidate| {
            member
                .parameters
                .iter()
                .enumerate()
                .map(|(j, q)| {
                    let absent = q.prior.map_or(0.0, |p| p.0);
                    ((f.values[from + j] - absent) / f.stderr[from + j]).abs()
                })
                .filter(|d| d.is_finite())
                .fold(0.0f64, f64::max)
        };
        // The winner's shift from its absence, alone and beside the
        // correction (largest over its parameters, relative).
        let shift = |values: &[f64], from: usize, member: &Candidate| {
            member
                .parameters
                .iter()
                .enumerate()
                .map(|(j, q)| values[from + j] - q.prior.map_or(0.0, |p| p.0))
                .collect::<Vec<f64>>()
        };
        let alone = pending[w]
            .fit
            .as_ref()
            .map(|(f, _)| shift(&f.values, ks, pair.members[0]));
        let swap = match (&pair.fit, alone) {
            (Some((f, _)), Some(alone))
                if f.physical && f.values.len() == f.stderr.len() && f.values.len() > ks + kw =>
            {
                let t_winner = distance(f, ks, pair.members[0]);
                let t_correction = distance(f, ks + kw, pair.members[1]);
                let beside = shift(&f.values, ks, pair.members[0]);
                // The share of the winner's own shift that remains beside the
                // correction: below one half, the correction explains most
                // of what the winner did (its parameters may still be
                // significant: with many samples a remnant always is).
                let remains = beside
                    .iter()
                    .zip(&alone)
                    .map(|(b, a)| if *a != 0.0 { (b / a).max(0.0) } else { 1.0 })
                    .fold(0.0f64, f64::max);
                ((t_winner < 2.0 || remains < 0.5) && t_correction > 2.0).then_some((t_winner, remains))
            }
            _ => None,
        };
        if pair.verdict.is_none() || matches!(pair.verdict, Some(Verdict::ImplausibleUnderPrior { .. })) {
            pair.verdict = Some(Verdict::NotAdded);
        }
        pending.push(pair);
        let Some((t_winner, remains)) = swap else {
            return Ok(None);
        };
        let family = self.family(pending);
        let Some(verdict) = self.validate_one(&mut pending[x], current, family) else {
            return Ok(None);
        };
        if !verdict.added() {
            return Ok(None);
        }
        pending[x].verdict = Some(verdict);
        // The other corrections beyond their priors that also fitted better
        // than the stand-in are cross-validated too, their verdicts kept:
        // the criterion counts no prior, and two such corrections of one
        // assembly can trade places by less than the runs' scatter (on an
        // independent set the front wheel's diametral inertia fitted best
        // where the fork's steer-axis inertia was wrong, and predicted the
        // held-out runs no better). The rivals of the one added then show
        // whether the runs tell them apart.
        for y in (0..single).filter(|&y| y != x) {
            let far = matches!(pending[y].verdict, Some(Verdict::ImplausibleUnderPrior { .. }));
            if far && bic_of(&pending[y]) < wbic {
                if let Some((fit, setup)) = pending[y].fit.as_mut() {
                    cross_validate(setup, fit, self.fold_of, self.opts);
                }
            }
        }
        pending[w].verdict = Some(Verdict::Encompassed {
            by: pending[x].name(),
            t: t_winner,
            remains,
        });
        Ok(Some(x))
    }
}
