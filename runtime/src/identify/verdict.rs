//! The verdict of each candidate of a selection step: why it was or was
//! not added, with the numbers behind it. The report formats these; the
//! selection decides them.

use super::confounding::HeldOutGain;
use serde::Serialize;

/// Why a candidate of a step was or was not added, with the numbers behind
/// it. Changes of the criterion are against the step's base model
/// (negative: better).
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Verdict {
    /// Added: it lowers the criterion and the held-out error, consistently
    /// over the runs. `held_out_gain`: the mean gain in held-out error per
    /// run (or row, or kick) over the step's base model and its standard
    /// error, where the entry test measured it (the bar it passed is that of
    /// [`Verdict::HeldOutGainNotConsistent`]); `None` for a member kept by
    /// the backward check.
    Added {
        bic_change: f64,
        cv: f64,
        base_cv: f64,
        #[serde(skip_serializing_if = "Option::is_none")]
        held_out_gain: Option<HeldOutGain>,
    },
    /// The score test's linearised fit does not lower the criterion: it
    /// cannot win this step (not fitted).
    NoPredictedGain { predicted_bic_change: f64 },
    /// Not fitted: the step added another candidate, and this one was
    /// predicted to gain less than half of what a passing fit gained (it
    /// could not beat it once fitted).
    BehindAdded { predicted_bic_change: f64, added: String },
    /// Not fitted: the step had fitted its budget of candidates
    /// ([`super::IdentifyOptions::max_fits_per_step`]) before reaching it.
    BeyondBudget { predicted_bic_change: f64, budget: usize },
    /// Fitted, with a criterion above the added candidate's: not
    /// cross-validated.
    CriterionAboveAdded { bic_change: f64, added: String },
    /// It passed every test and the criterion ranked it first, but another
    /// that also passed predicts the held-out runs consistently better (run
    /// by run, beyond two standard errors; `added_cv`) and was added.
    PassedHeldOutBelow {
        bic_change: f64,
        cv: f64,
        added: String,
        added_cv: f64,
    },
    /// It passed every test, behind the added candidate in the criterion,
    /// and its held-out gain over it is not consistent.
    PassedCriterionAbove { bic_change: f64, cv: f64, added: String },
    /// The fit failed.
    FitFailed { reason: String },
    /// A dissipative parameter fitted at or below zero, or at its floor
    /// (not physics; not cross-validated).
    NotPhysical,
    /// A correction fitted further from its measured value than
    /// [`super::PLAUSIBLE_PRIOR_SDS`] standard deviations of its stated
    /// uncertainty: the data ask for a value the measurement makes
    /// implausible, so the correction more likely absorbs a missing effect.
    /// It is cross-validated only when no plausible candidate passes.
    ImplausibleUnderPrior { symbol: String, value: f64, prior_sds: f64 },
    /// The fit does not lower the criterion beyond its added parameters
    /// (not cross-validated).
    NoCriterionGain { bic_change: f64 },
    /// The held-out error does not fall: it does not generalise.
    HeldOutNotLower { cv: f64, base_cv: f64 },
    /// A member of the final model whose removal raises the held-out error
    /// (`cv` with it, `base_cv` without) by no more than one standard error
    /// of it (`stderr`): the data do not tell the simpler model apart, and
    /// the simpler is kept (the one-standard-error rule).
    WithinOneStandardError { cv: f64, base_cv: f64, stderr: f64 },
    /// The held-out gain per run is within two standard errors of zero:
    /// not a consistent improvement.
    HeldOutGainNotConsistent {
        gain: f64,
        stderr: f64,
        /// The bar: standard errors the gain must exceed (2 for the
        /// library; more for a dictionary of many terms, see
        /// [`super::selection::family_wise_sigmas`]).
        sigmas: f64,
        /// The hypotheses the bar is family-wise over: the candidates its
        /// step had fitted (1: the bar of a single test, or one set for a
        /// whole dictionary).
        family: usize,
    },
    /// It passed, but fitted together with a correction beyond its prior
    /// that fits better, its parameters fall within two standard errors of
    /// their absence (largest |shift / standard error| `t`) or keep less
    /// than half of their shift alone (`remains`, the largest share), while
    /// the correction's shift stays significant: it stood in for that
    /// correction, which is added instead.
    Encompassed { by: String, t: f64, remains: f64 },
    /// A pair fitted for the encompassing test: not a candidate of its own.
    NotAdded,
    /// Added, then dropped: refitted with the terms added after it, its
    /// coefficient is within two standard errors of zero (`z`, its ratio to
    /// its standard error); they took it over.
    TakenOver { z: f64 },
    /// A lagged term whose time constant (s) fitted outside what the data
    /// resolve: far shorter than a weave period (the direct term, which the
    /// dictionary also holds) or far longer (a torque that never builds).
    LagNotResolved { time_constant: f64 },
    /// A discovered term whose coefficient's 95 % interval contains zero
    /// (`|value| < 1.96 stderr`): the data do not show the force exists,
    /// however much it lowers the criterion by moving other values.
    NotDistinctFromZero { value: f64, stderr: f64 },
    /// A discovered term on runs' kicks that predicts the held-out kicks
    /// consistently better than the library's values, but not than the
    /// base model (mean paired gain per kick within two standard errors of
    /// zero): it takes back what the time series' fit moved the kicks'
    /// eigenvalues away from the measured ones, and shows no force.
    NotBetterThanReference { gain: f64, stderr: f64 },
}

impl Verdict {
    /// The candidate was added.
    pub fn added(&self) -> bool {
        matches!(self, Verdict::Added { .. })
    }

    /// The candidate passed every test of its step: added, or passed
    /// behind the one added.
    pub fn passed(&self) -> bool {
        matches!(
            self,
            Verdict::Added { .. } | Verdict::PassedHeldOutBelow { .. } | Verdict::PassedCriterionAbove { .. }
        )
    }
}
