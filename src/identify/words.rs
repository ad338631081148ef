//! Identification's words: a verdict, a bound, a complex number and the
//! steps of a search as the reports write them. Plain formatting of the
//! runtime's results, shared by every report (runs, tables, the dictionary's
//! searches) and depending on no other module of `identify`.

use bikedyn_runtime::identify::confounding::CONFOUNDED;
use bikedyn_runtime::identify::{Bound, Trial, Verdict, PLAUSIBLE_PRIOR_SDS};
use std::fmt::Write as _;

use super::weave_errors::Excluded;

/// An error a source may not have, NaN where it has none (as printed).
pub(crate) fn nan(x: Option<f64>) -> f64 {
    x.unwrap_or(f64::NAN)
}

pub(crate) fn median(x: impl Iterator<Item = f64>) -> f64 {
    let mut v: Vec<f64> = x.filter(|a| a.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

pub(crate) fn fmt_c(z: Option<[f64; 2]>) -> String {
    z.map_or("-".into(), |z| format!("{:.3}{:+.3}i", z[0], z[1]))
}

/// Why a member of the final model kept its place although the criterion
/// or the held-out error alone would remove it: without it, correction
/// `symbol` fits at `value`, `sds` prior standard deviations from its
/// measured value.
pub fn kept_as_no_plausible_rival(symbol: &str, value: f64, sds: f64) -> String {
    format!(
        "keeps its place: without it {symbol} fits at {value:.4} ({sds:.1} prior standard deviations from its measured value), no plausible rival"
    )
}

/// A candidate's verdict in words, with its numbers (changes of the
/// criterion against the step's base; negative is better).
pub fn verdict_text(v: &Verdict) -> String {
    match v {
        Verdict::Added {
            bic_change,
            cv,
            base_cv,
            held_out_gain,
        } => {
            let consistent = held_out_gain.map_or(String::new(), |g| {
                format!(
                    "; held-out gain per run {:.4} +- {:.4} (1 SE, {:.1} SE)",
                    g.gain,
                    g.stderr,
                    g.gain / g.stderr
                )
            });
            format!("warranted: BIC {bic_change:+.1}, held-out error {cv:.4} (was {base_cv:.4}){consistent}")
        }
        Verdict::NoPredictedGain { predicted_bic_change } => format!(
            "not fitted: linearised at the current fit (score test), its best BIC change is {predicted_bic_change:+.1}, no gain"
        ),
        Verdict::BehindAdded { predicted_bic_change, added } => format!(
            "not fitted: predicted BIC change {predicted_bic_change:+.1}, under half of what the passing fit gained (it could not beat it); the step added {added} (tried again in the next step)"
        ),
        Verdict::BeyondBudget { predicted_bic_change, budget } => format!(
            "not fitted: predicted BIC change {predicted_bic_change:+.1}; the step had fitted its budget of {budget} candidates before reaching it (a compute limit, not a verdict)"
        ),
        Verdict::CriterionAboveAdded { bic_change, added } => {
            format!("not added: BIC {bic_change:+.1}, above that of {added} (not cross-validated)")
        }
        Verdict::PassedHeldOutBelow { bic_change, cv, added, added_cv } => format!(
            "passed (BIC {bic_change:+.1}, held-out error {cv:.4}), not added: {added} predicts the held-out runs consistently better ({added_cv:.4}; the gain run by run beyond two standard errors)"
        ),
        Verdict::PassedCriterionAbove { bic_change, cv, added } => format!(
            "passed (BIC {bic_change:+.1}, held-out error {cv:.4}), not added: {added} is ahead in the criterion, and this one's held-out gain over it is not consistent run by run"
        ),
        Verdict::FitFailed { reason } => format!("fit failed: {reason}"),
        Verdict::ImplausibleUnderPrior { symbol, value, prior_sds } => format!(
            "rejected: {symbol} = {value:.4} lies {prior_sds:.1} prior standard deviations from its measured value (beyond {PLAUSIBLE_PRIOR_SDS}: implausible under the measurement, more likely it absorbs a missing effect; tried only when no plausible candidate passes)"
        ),
        Verdict::NotPhysical => "rejected: a dissipative parameter fitted at or below zero, or at its floor (not physics; not cross-validated)".into(),
        Verdict::TakenOver { z } => format!(
            "dropped: refitted with the terms added after it, its coefficient is {z:.2} standard errors from zero; they took it over"
        ),
        Verdict::LagNotResolved { time_constant } => {
            format!("rejected: a lag fitted to {time_constant:.2e} s, outside what the data resolve (from a hundredth of the shortest weave period, where it is the direct term tried on its own, to ten of the longest)")
        }
        Verdict::NotDistinctFromZero { value, stderr } => format!(
            "rejected: its coefficient {value:.4} +- {:.4} (95 %) holds zero: the data do not show the force (not cross-validated)",
            1.96 * stderr
        ),
        Verdict::NotBetterThanReference { gain, stderr } => format!(
            "rejected: it predicts the held-out kicks better than the library's values, but not consistently better than the base model (mean gain per kick {gain:.4}, standard error {stderr:.4}): it takes back how far the time series' fit moved the kicks' eigenvalues from the measured ones"
        ),
        Verdict::NoCriterionGain { bic_change } => {
            format!("rejected: BIC {bic_change:+.1} (no gain beyond its added parameters; not cross-validated)")
        }
        Verdict::HeldOutNotLower { cv, base_cv } => {
            format!("rejected: held-out error {cv:.4} not below {base_cv:.4} (does not generalise)")
        }
        Verdict::WithinOneStandardError { cv, base_cv, stderr } => format!(
            "removed: without it the held-out error is {base_cv:.4} against {cv:.4}, within one standard error ({stderr:.4}); the simpler model is kept"
        ),
        Verdict::HeldOutGainNotConsistent {
            gain,
            stderr,
            sigmas,
            family,
        } => format!(
            "rejected: mean held-out gain per run (per row or kick in the dictionary's search) {gain:.4}, within {} standard errors of zero (standard error {stderr:.4}, {:.1} SE{}; not a consistent improvement)",
            if (*sigmas - 2.0).abs() < 1e-9 { "two".to_string() } else { format!("{sigmas:.2}") },
            gain / stderr,
            if *family > 1 {
                format!("; the bar of one of the {family} candidates this step fitted")
            } else {
                String::new()
            }
        ),
        Verdict::Encompassed { by, t, remains } => format!(
            "replaced by {by}: fitted together with it, its parameters keep {:.0} % of their shift alone ({t:.1} standard errors from their absence) while {by} stays significant; it stood in for {by}",
            100.0 * remains
        ),
        Verdict::NotAdded => "fitted for the encompassing test only (not a candidate of its own)".into(),
    }
}

/// A fitted value that ended on its floor or ceiling is a limit: the data
/// asked for a value beyond it, and it has no interval.
pub(crate) fn bound_text(b: Bound) -> String {
    match b {
        Bound::Floor(lo) => format!("on its floor {lo}: the data ask for less"),
        Bound::Ceiling(hi) => format!("on its ceiling {hi}: the data ask for more"),
    }
}

/// The steps of a forward search as tables: each candidate tried with its
/// fit, criterion, held-out error and verdict, and the rivals of the one
/// added (steps numbered from `first`).
pub(crate) fn steps_markdown(s: &mut String, steps: &[bikedyn_runtime::identify::Step], first: usize) {
    for (k, step) in steps.iter().enumerate() {
        let base = if step.base.is_empty() {
            "the base model".to_string()
        } else {
            step.base.join(" + ")
        };
        let _ = writeln!(
            s,
            "Step {}: candidates tried on top of {base} (whose BIC is {:.1}, held-out error {:.4}).\n",
            first + k,
            step.base_bic,
            step.base_cv
        );
        let _ = writeln!(
            s,
            "| candidate | fitted values (+- one standard error) | BIC change | held-out error | verdict |\n|---|---|---|---|---|"
        );
        // Fitted trials by their criterion, then those not fitted by their
        // predicted change.
        let key = |t: &Trial| match &t.fit {
            Some(f) => (0, f.bic - step.base_bic),
            None => (1, t.predicted_bic_change.unwrap_or(f64::INFINITY)),
        };
        let mut rows: Vec<&Trial> = step.trials.iter().collect();
        rows.sort_by(|x, y| {
            let (a, b) = (key(x), key(y));
            a.0.cmp(&b.0).then(a.1.total_cmp(&b.1))
        });
        for t in rows {
            let name = &t.name;
            let why = verdict_text(&t.verdict);
            match &t.fit {
                Some(f) => {
                    let vals: Vec<String> = f
                        .parameters
                        .iter()
                        .zip(f.values.iter().zip(&f.stderr))
                        .map(|(p, (v, se))| format!("{} = {:.4} +- {:.4}", p.symbol, v, se))
                        .collect();
                    let cv = if f.cv.is_finite() {
                        format!("{:.4}", f.cv)
                    } else {
                        "-".into()
                    };
                    let _ = writeln!(
                        s,
                        "| `{name}` | {} | {:+.1} | {cv} | {why} |",
                        vals.join(", "),
                        f.bic - step.base_bic
                    );
                }
                None => match t.predicted_bic_change {
                    Some(p) => {
                        let _ = writeln!(s, "| `{name}` | not fitted | {p:+.1} (predicted) | - | {why} |");
                    }
                    None => {
                        let _ = writeln!(s, "| `{name}` | - | - | - | {why} |");
                    }
                },
            }
        }
        let _ = writeln!(s);
        if !step.confounded.is_empty() {
            let _ = writeln!(
                s,
                "How far the data tell the added candidate from each rival that also lowered the criterion. Correlation: the largest canonical correlation of their parameters in the Fisher information, after every kick's initial state is fitted (1: indistinguishable; at or above {CONFOUNDED}: not separable). Held-out gain: for a rival that passed cross-validation too, how much better it predicts the held-out runs, paired run by run, +- one standard error (within two standard errors of zero: not separated by these runs).\n"
            );
            let _ = writeln!(
                s,
                "| added | rival | correlation | held-out gain of the rival | kicks that would separate them (correlation) |\n|---|---|---|---|---|"
            );
            for c in &step.confounded {
                let designs: Vec<String> = c
                    .designs
                    .iter()
                    .take(4)
                    .map(|d| format!("{} ({:.2})", d.description, d.correlation))
                    .collect();
                let gain = match c.held_out_gain {
                    Some(h) => format!(
                        "{:+.4} +- {:.4} (1 SE){}",
                        h.gain,
                        h.stderr,
                        if h.within_scatter() { " (not separated)" } else { "" }
                    ),
                    None => "-".to_string(),
                };
                let _ = writeln!(
                    s,
                    "| `{}` | `{}` | {:.3}{} | {gain} | {} |",
                    c.chosen,
                    c.rival,
                    c.correlation,
                    if c.correlation >= CONFOUNDED {
                        " (not separable)"
                    } else {
                        ""
                    },
                    if designs.is_empty() {
                        "-".to_string()
                    } else {
                        designs.join("; ")
                    }
                );
            }
            let _ = writeln!(s);
        }
    }
}

/// A kick kept out of the eigenvalue figures: its run, window start and
/// why, as the summary and `report.md` both list it.
pub(crate) fn excluded_kick_text(e: &Excluded) -> String {
    format!(
        "{} at {:.2} s: {}",
        e.run,
        e.window_start,
        bikedyn_report::experiment::accept::rejected_text(&e.rejected)
    )
}
