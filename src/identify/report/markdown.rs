//! The identification's `report.md`: what was measured, the candidates,
//! the fits, the errors before and after, the diagnosis and the plots.

use super::{errors, summary};
use crate::identify::candidates::not_candidates;
use crate::identify::result::{Errors, HeldOutErrors};
use crate::identify::words::{excluded_kick_text, fmt_c, median, nan, steps_markdown, verdict_text};
use crate::identify::{IdentifyRequest, Outcome};
use bikedyn_runtime::registry::ModelRegistry;
use std::fmt::Write as _;
use std::path::Path;

pub(super) fn report_markdown<R: ModelRegistry>(o: &Outcome<R>, a: &IdentifyRequest, dir: &Path) -> String {
    let id = &o.identification;
    let mut s = String::new();
    let inputs: Vec<String> = a.inputs.iter().map(|p| p.display().to_string()).collect();
    let _ = writeln!(s, "# Identification report\n");
    let (roll, unit) = (o.roll_channel().describe(), o.roll_channel().unit_deg());
    let speed = if o.speed_imposed {
        "forward speed imposed (the measured speed over each window: a motor held it)"
    } else {
        "free forward speed"
    };
    let _ = writeln!(
        s,
        "Data: {} ({} kicks). Bicycle: `{}`. Model: `{}` (nonlinear, {speed}, every effect of the library absent unless fitted); weave predictions from its driven-speed twin `{}`.\n",
        inputs.join(", "),
        o.segments.len(),
        o.bike,
        o.model,
        o.driven_model
    );
    let _ = writeln!(s, "## Summary\n\n```\n{}\n```\n", summary(o));
    let _ = writeln!(s, "## What was done\n");
    if o.speed_imposed {
        let _ = writeln!(s, "1. The measured-run pipeline (`bikedyn fit`) found every kick of the logs and its free-response window (from the gyro's roll rate; the next kick or the decay into noise ends it).");
    } else {
        let _ = writeln!(s, "1. The measured-run pipeline (`bikedyn fit`) found every kick and its free-response window, and estimated mounting misalignments (calibration run) and clock offsets: these sensor effects are nuisances, never reported as mechanics.");
    }
    let _ = writeln!(s, "2. Each window was simulated with the full nonlinear equations from its own initial state (roll, steer, their rates, speed, and a tyre model's lagged lateral forces and their rates; fitted per kick as nuisance parameters), and compared with the measured {roll}, steer and speed.");
    let _ = writeln!(s, "3. The residual pattern of the model without any added effect was related to the effects of the library (below).");
    let _ = writeln!(s, "4. Candidates were added one at a time and fitted jointly over all kicks (Levenberg-Marquardt). One was kept only if it lowers the Bayesian information criterion (effective sample sizes for correlated residuals), lowers the error on held-out runs ({}-fold cross-validation by run: each run's or log's kicks are predicted with the values fitted to the others), and its dissipative parameters are positive; of the candidates of a step that pass, the criterion's first is added unless another predicts the held-out runs consistently better (run by run, beyond two standard errors). The search stops when no candidate passes.", id.folds);
    if let Some(r) = &o.remaining {
        let _ = writeln!(s, "5. The identified model's weave residuals (measured minus predicted eigenvalue of each kick counted) were regressed on the states a missing effect would act through ({}); an F test asks whether that pattern exceeds the kicks' own scatter about it, which is the floor a perfect model would reach. Outcome: {}.", crate::identify::remaining::regressors_text(r), crate::identify::remaining::remaining_sentence(r, "kicks"));
    }
    if !o.state_correlation.is_empty() {
        let _ = writeln!(s, "5b. Each channel's residual after identification (every sample of every kick) was regressed on the simulated states (the roll channel and its rate, the steer angle and its rate), with an F test on the effective sample size of correlated samples; its lag-1 autocorrelation measures how far it is from white noise. Outcome: {}.", crate::identify::remaining::state_correlation_sentence(&o.state_correlation));
    }
    if let Some(d) = &o.discovery {
        let _ = writeln!(s, "6. Where a structured residual remains, a dictionary of generalized forces on the roll and steer equations (angles, rates and accelerations, times 1, v or v^2, at once or through a first-order lag) was searched on the counted kicks' weave eigenvalues, with the library's values as fitted; a term is kept when it lowers the criterion and the held-out error of the same folds of runs, consistently over the kicks, than the library's values and than the base model (the time series' fit may have moved the kicks' eigenvalues away from those measured), and when its coefficient's 95 % interval excludes zero. Outcome: {}.", crate::identify::discovery::kicks_sentence(d).replace('\n', "; "));
    }
    if let Some(t) = &o.time_series {
        let _ = writeln!(s, "7. Where a structured residual remains (in the weave or in the time series), the dictionary's terms that the model carries (angles and rates times 1, v or v^2, a bias, a Coulomb-like torque, on the roll and steer equations) were tried one at a time through the nonlinear simulation of every kick, with the library's selection refitted beside them and the same tests as its candidates; then every member was tested against the final model without it. Outcome: {}.", crate::identify::time_series::sentence(t, unit, 1f64.to_degrees()).replace('\n', "; "));
    }
    let _ = writeln!(s);
    let med = |f: &dyn Fn(&bikedyn_runtime::identify::Weights) -> f64| median(id.weights.iter().map(f));
    let _ = writeln!(s, "Channel scales (each kick's RMS residual under the base model, at least the best kick's; median over kicks): {roll} {:.3} {unit}, steer {:.3} deg, speed {:.3} m/s. Each kick and channel is weighed by its own scale, so a run that diverges toward a fall cannot outweigh the others.\n", med(&|w| w.roll).to_degrees(), med(&|w| w.steer).to_degrees(), med(&|w| w.speed));
    let _ = writeln!(s, "## Residual diagnosis (base model)\n");
    let _ = writeln!(
        s,
        "| pattern | evidence | points to | significant (2 sigma) |\n|---|---|---|---|"
    );
    for f in &o.findings {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} |",
            f.pattern,
            f.evidence,
            f.suspects.join(", "),
            if f.significant { "yes" } else { "no" }
        );
    }
    let _ = writeln!(s, "\nCandidates and why each is suspected:\n");
    for c in &o.candidates {
        let p: Vec<String> = c
            .parameters
            .iter()
            .map(|p| format!("`{}` ({})", p.symbol, p.unit))
            .collect();
        let _ = writeln!(
            s,
            "* `{}`{}: {} Fitted: {}.",
            c.name,
            if c.speed_decay { " (speed decay)" } else { "" },
            c.reason,
            p.join(", ")
        );
    }
    if let Some(info) = R::models().iter().find(|m| m.name == o.model) {
        for (e, why) in not_candidates(info) {
            let _ = writeln!(s, "* `{e}` is not a candidate: {why}.");
        }
    }
    let _ = writeln!(s, "\n## Ranking of the candidates\n");
    steps_markdown(&mut s, &id.steps, 1);
    if !id.final_check.is_empty() {
        let _ = writeln!(
            s,
            "Final check: each selected candidate that a later one followed, tested against the model without it: it stays while the criterion and the held-out error are lower with it (the entry test without its bar of a consistent gain over the runs, which is the evidence for entering); one that fails no longer earns its place and is removed, the model refitted without it.\n\n| candidate | in the model | without it: BIC change, held-out error | outcome |\n|---|---|---|---|"
        );
        for c in &id.final_check {
            let without = match &c.without {
                Some(_) if c.cv_without.is_finite() => format!("{:+.1}, {:.4}", -c.bic_change, c.cv_without),
                Some(_) => format!("{:+.1}, -", -c.bic_change),
                None => "fit failed".into(),
            };
            let outcome = if let Some((symbol, value, sds)) = &c.without_implausible {
                crate::identify::words::kept_as_no_plausible_rival(symbol, *value, *sds)
            } else if c.verdict.added() {
                format!("keeps its place ({})", verdict_text(&c.verdict))
            } else if c.removed {
                format!("removed: {}", verdict_text(&c.verdict))
            } else {
                format!(
                    "failed as well ({}); tested again after the removal",
                    verdict_text(&c.verdict)
                )
            };
            let _ = writeln!(s, "| `{}` | {} | {without} | {outcome} |", c.name, c.model.join(" + "));
        }
        let _ = writeln!(s);
    }
    if id.selected.is_empty() {
        let _ = writeln!(s, "**No effect warranted.** No candidate lowered both the information criterion and the held-out error with physical parameter values: the residual of the base model is not explained better by any effect of the library than by noise. The model is left as it is.\n");
    } else {
        let _ = writeln!(
            s,
            "## Identified effects\n\n| parameter | value | 95 % interval | unit |\n|---|---|---|---|"
        );
        for (p, (v, se)) in id
            .after
            .parameters
            .iter()
            .zip(id.after.values.iter().zip(&id.after.stderr))
        {
            let interval = match p.on_bound(*v) {
                Some(b) => crate::identify::words::bound_text(b),
                None => format!("[{:.5}, {:.5}]", v - 1.96 * se, v + 1.96 * se),
            };
            let _ = writeln!(
                s,
                "| `{}`{} | {:.5} | {interval} | {} |",
                p.symbol,
                if p.tied.is_empty() {
                    String::new()
                } else {
                    format!(" (= `{}`)", p.tied.join("`, `"))
                },
                v,
                p.unit
            );
        }
        let _ = writeln!(s);
    }
    let b = errors(o, false);
    let af = errors(o, true);
    let row = |e: &Errors| {
        [
            e.eigen_rms,
            nan(e.eigen_weighted_rms),
            nan(e.roll_rms),
            nan(e.steer_rms),
            nan(e.speed_rms),
        ]
    };
    let held = |e: &HeldOutErrors| {
        [
            e.eigen_rms,
            nan(e.eigen_weighted_rms),
            nan(e.roll_rms),
            nan(e.steer_rms),
            nan(e.speed_rms),
        ]
    };
    let counted = o.weave_kicks.iter().filter(|&&k| k).count();
    let _ = writeln!(s, "## Error before and after\n\nThe weave eigenvalue figures are over the {counted} of {} kicks whose measured eigenvalue is a weave (the others are listed below with the reason; their time series are fitted all the same); the weighted figure weighs each kick by the inverse variance of its measured eigenvalue.\n\n| | weave eigenvalue RMS (1/s) | weighted (1/s) | {roll} RMS ({unit}) | steer RMS (deg) | speed RMS (m/s) |\n|---|---|---|---|---|---|", o.segments.len());
    for (label, [eigen, weighted, roll_rms, steer_rms, speed_rms]) in [
        ("fitted runs, before", row(&b)),
        ("fitted runs, after", row(&af)),
        ("held-out runs, before", held(&b.held_out)),
        ("held-out runs, after", held(&af.held_out)),
    ] {
        let _ = writeln!(
            s,
            "| {label} | {eigen:.4} | {weighted:.4} | {:.4} | {:.4} | {speed_rms:.4} |",
            roll_rms.to_degrees(),
            steer_rms.to_degrees(),
        );
    }
    let _ = writeln!(s, "\nPer kick ({roll} RMS in {unit}; weave eigenvalues in 1/s):\n\n| run | window start (s) | speed over the eigenvalue fit (m/s) | measured weave | predicted before | predicted after | {roll} before | {roll} after | {roll} after, held out |\n|---|---|---|---|---|---|---|---|---|");
    for (i, seg) in o.segments.iter().enumerate() {
        let _ = writeln!(
            s,
            "| {} | {:.2} | {:.2}-{:.2} | {} | {} | {} | {:.3} | {:.3} | {:.3} |",
            seg.run,
            seg.t0,
            seg.speed_interval[0],
            seg.speed_interval[1],
            fmt_c(seg.weave.map(|w| w.0)),
            fmt_c(o.predicted_before[i]),
            fmt_c(o.predicted_after[i]),
            id.before.errors[i].roll_rms.to_degrees(),
            id.after.errors[i].roll_rms.to_degrees(),
            id.after.held_out[i].roll_rms.to_degrees()
        );
    }
    // Each run (log) held out: its kicks predicted with the values fitted
    // to the other runs.
    let mut runs: Vec<&str> = Vec::new();
    for seg in &o.segments {
        if !runs.contains(&seg.run.as_str()) {
            runs.push(&seg.run);
        }
    }
    let pooled = |errs: &[bikedyn_runtime::identify::SegmentError], run: &str| {
        let (mut ss, mut n) = (0.0, 0usize);
        for (e, seg) in errs.iter().zip(&o.segments) {
            if seg.run == run {
                ss += e.roll_rms * e.roll_rms * e.channel_n[0] as f64;
                n += e.channel_n[0];
            }
        }
        (ss / n.max(1) as f64).sqrt()
    };
    let _ = writeln!(s, "\nEach run held out ({roll} RMS in {unit}; `after, held out`: the run's kicks with the effect values fitted to the other runs, only their initial states fitted to it):\n\n| run | kicks | before | after | after, held out |\n|---|---|---|---|---|");
    for run in &runs {
        let _ = writeln!(
            s,
            "| {run} | {} | {:.3} | {:.3} | {:.3} |",
            o.segments.iter().filter(|x| x.run == *run).count(),
            pooled(&id.before.errors, run).to_degrees(),
            pooled(&id.after.errors, run).to_degrees(),
            pooled(&id.after.held_out, run).to_degrees()
        );
    }
    if !o.eigen_excluded.is_empty() {
        let _ = writeln!(s, "\nKicks kept out of the eigenvalue figures:\n");
        for e in &o.eigen_excluded {
            let _ = writeln!(s, "* {}", excluded_kick_text(e));
        }
    }
    let _ = writeln!(s, "\n## Plots\n\n* `continuation.svg`: weave eigenvalue over speed, model before (thin) and after (thick), with each measured eigenvalue on its speed interval.\n* `run_residuals.svg`: measured and simulated {roll}, steer and speed of a typical kick (median error), before and after.\n");
    if !o.skipped.is_empty() {
        let _ = writeln!(s, "## Skipped\n");
        for k in &o.skipped {
            let _ = writeln!(s, "* {k}");
        }
        let _ = writeln!(s);
    }
    let fitted = dir.join("fitted.toml");
    let _ = writeln!(s, "## Reproduce\n\nThe identified bicycle is `{}`: the bicycle's parameters plus the fitted effect values, for the model `{}` (driven speed) or `{}` (free speed). To refit from it, and to simulate it:\n\n```sh\nbikedyn identify {} --bike {}\nbikedyn simulate --bike {} --model {} --speed 5 --kick 0.5:3 --duration 6 --plot kick.svg\n```\n\nThe refit starts from the identified bicycle: the effects found here are part of its model, so the refit should warrant nothing more.", fitted.display(), o.driven_model, o.model, inputs.join(" "), fitted.display(), fitted.display(), o.model);
    s
}
