//! The rivals of a step's added candidate: every other fitted candidate
//! that also lowered the criterion and is plausible under its prior (or,
//! beside a chosen correction beyond its prior, is a correction beyond its
//! own that was cross-validated too), with how far the data tell the two
//! apart ([`super::confounding`]) and, for a rival that passed
//! cross-validation too, its paired held-out gain.

use super::confounding::{self, Confounding, HeldOutGain};
use super::cross_validation::paired_gain;
use super::selection::{Pending, Search};
use super::{Candidate, Verdict};

impl<'s> Search<'s> {
    /// The candidate a step adds against each fitted rival that also
    /// lowered the information criterion and is plausible under its
    /// prior: their correlation on the measured kicks, for a rival that
    /// passed cross-validation too their paired held-out gain, and for a
    /// pair not separated either way the designs of kicks that would separate them (at
    /// speeds from 1.5 m/s below the slowest kick to 1.5 m/s above the
    /// fastest).
    pub(super) fn rivals(
        &self,
        pending: &[Pending<'s>],
        best: usize,
        selected: &[&'s Candidate],
        base_bic: f64,
    ) -> Vec<Confounding> {
        let chosen = pending[best].members[0];
        let Some((fit, _)) = &pending[best].fit else {
            return Vec::new();
        };
        let speeds: Vec<f64> = {
            let v = self.segments.iter().map(|s| s.mean_speed).filter(|v| v.is_finite());
            let (lo, hi) = v.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| (a.min(x), b.max(x)));
            if lo.is_finite() {
                let (lo, hi) = ((lo - 1.5).max(1.0), hi + 1.5);
                (0..6).map(|i| lo + (hi - lo) * i as f64 / 5.0).collect()
            } else {
                Vec::new()
            }
        };
        let ks: usize = selected.iter().map(|c| c.parameters.len()).sum();
        let kc = chosen.parameters.len();
        // A chosen correction beyond its prior (the encompassing test's):
        // its rivals beyond theirs that were cross-validated beside it are
        // as plausible as it is, and are weighed as well.
        let chosen_far = !self.plausible(chosen, &fit.values[ks.min(fit.values.len())..]);
        let mut out = Vec::new();
        for (i, p) in pending.iter().enumerate() {
            let Some((rival_fit, _)) = &p.fit else { continue };
            if i == best || p.members.len() != 1 || !rival_fit.physical || !(rival_fit.bic < base_bic) {
                continue;
            }
            let rival = p.members[0];
            let plausible = self.plausible(rival, &rival_fit.values[ks..]);
            let far_rival = chosen_far && !plausible && rival_fit.cv.is_finite();
            if !plausible && !far_rival {
                continue;
            }
            let mut active: Vec<&Candidate> = selected.to_vec();
            active.push(chosen);
            active.push(rival);
            let factory = match self.alternative.filter(|_| active.iter().any(|a| a.alternative_model)) {
                Some(f) => f,
                None if active.iter().any(|a| a.alternative_model) => continue,
                None => self.main,
            };
            let Ok(setup) = factory.setup(self.segments, self.weights, &active) else {
                continue;
            };
            let mut g = fit.values.clone();
            if far_rival {
                // Two corrections beyond their priors, each fitted for the
                // same misfit: both at their fitted values would count the
                // shift twice (a model the runs are far from, whose kicks
                // may not simulate). The information is taken at the
                // chosen one's fit with the rival at its measured value.
                g.extend(rival.parameters.iter().map(|q| q.prior.map_or(0.0, |p| p.0)));
            } else {
                g.extend(rival_fit.values.iter().skip(ks));
            }
            if g.len() != setup.k() {
                continue;
            }
            let a: Vec<usize> = (ks..ks + kc).collect();
            let b: Vec<usize> = (ks + kc..setup.k()).collect();
            // A rival that passed cross-validation too: how much better or
            // worse it predicts the held-out runs, run by run.
            let passed = far_rival
                || matches!(
                    p.verdict,
                    Some(Verdict::PassedCriterionAbove { .. } | Verdict::PassedHeldOutBelow { .. })
                );
            let held_out_gain = passed
                .then(|| paired_gain(fit, rival_fit, self.weights))
                .flatten()
                .map(|(gain, stderr)| HeldOutGain { gain, stderr });
            let alike = held_out_gain.is_some_and(|h| h.within_scatter());
            if let Some((correlation, designs)) =
                confounding::confounding(&setup, factory, &active, &g, &fit.nuisance, &a, &b, &speeds, alike)
            {
                out.push(Confounding {
                    chosen: chosen.name.clone(),
                    rival: rival.name.clone(),
                    correlation,
                    held_out_gain,
                    beyond_priors: far_rival,
                    designs,
                });
            }
        }
        out
    }
}
