//! The identification's outputs: the five-line summary, the JSON summary
//! (schema in docs/identification.md, "What it does", step 5), and the report
//! folder (`report.md`, `report.json`, plots, the fitted parameter file).

mod markdown;

use markdown::report_markdown;

use super::candidates::identification_models;
use super::confounded::confounding_lines;
use super::predict::{linear_equivalent, predict};
use super::result::{
    CandidateTrial, Confounded, Details, Errors, Estimate, ExcludedKick, FittedValue, HeldOutErrors, IdentifyResult,
    KickErrors, MemberCheck, Prior, RunDetails, Source,
};
use super::weave_errors::{eigen_rms, eigen_weighted_rms};
use super::words::{bound_text, excluded_kick_text, median, nan, verdict_text};
use super::{IdentifyError, IdentifyRequest, Outcome};
use crate::bicycle::files::ParameterFile;
use crate::bicycle::Bicycle;
use bikedyn_report::identify::plot::{plot_continuation, plot_run, Channel, MeasuredWeave};
use bikedyn_report::output::{save_json, write_string_atomic};
use bikedyn_report::staged::{FolderKind, StagedDir};
use bikedyn_runtime::identify::{pooled_rms, Candidate};
use bikedyn_runtime::registry::ModelRegistry;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

fn display_name(c: &Candidate) -> String {
    if c.speed_decay {
        format!("{} (speed decay)", c.name)
    } else {
        c.name.clone()
    }
}

/// The errors at one stage: before identification (the base model, whose
/// held-out errors are its own) or after (the selection, each run held out
/// predicted with the values fitted to the others).
pub(super) fn errors<R: ModelRegistry>(o: &Outcome<R>, after: bool) -> Errors {
    let id = &o.identification;
    let fit = if after { &id.after } else { &id.before };
    let pred = if after { &o.predicted_after } else { &o.predicted_before };
    let held_pred = if after {
        &o.predicted_held_out
    } else {
        &o.predicted_before
    };
    Errors {
        eigen_rms: eigen_rms(&o.segments, pred, &o.weave_kicks),
        eigen_weighted_rms: Some(eigen_weighted_rms(&o.segments, pred, &o.weave_kicks)),
        median_run_roll_rms: Some(median(fit.errors.iter().map(|e| e.roll_rms))),
        median_run_steer_rms: Some(median(fit.errors.iter().map(|e| e.steer_rms))),
        roll_rms: Some(pooled_rms(&fit.errors, 0)),
        steer_rms: Some(pooled_rms(&fit.errors, 1)),
        speed_rms: Some(pooled_rms(&fit.errors, 2)),
        held_out: HeldOutErrors {
            eigen_rms: eigen_rms(&o.segments, held_pred, &o.weave_kicks),
            eigen_weighted_rms: Some(eigen_weighted_rms(&o.segments, held_pred, &o.weave_kicks)),
            roll_rms: Some(pooled_rms(&fit.held_out, 0)),
            steer_rms: Some(pooled_rms(&fit.held_out, 1)),
            speed_rms: Some(pooled_rms(&fit.held_out, 2)),
        },
        per_run: o
            .segments
            .iter()
            .enumerate()
            .map(|(i, s)| KickErrors {
                run: s.run.clone(),
                window_start: s.t0,
                roll_rms: fit.errors[i].roll_rms,
                steer_rms: fit.errors[i].steer_rms,
                speed_rms: fit.errors[i].speed_rms,
                held_out_roll_rms: fit.held_out[i].roll_rms,
                measured_weave: s.weave.map(|w| w.0),
                weave_counted: o.weave_kicks[i],
                predicted_weave: pred[i],
            })
            .collect(),
    }
}

/// The result of an identification from runs or logs, in the schema a
/// table's shares (`super::result`).
pub fn result<R: ModelRegistry>(o: &Outcome<R>) -> IdentifyResult {
    let id = &o.identification;
    let selected_effects: Vec<String> = id
        .selected
        .iter()
        .filter_map(|n| o.candidates.iter().find(|c| &c.name == n))
        .map(display_name)
        .collect();
    // The stated prior of a symbol is its candidate's, as the plan declared
    // it (the fit's parameter carries it too; the plan's is the source).
    let parameters = id
        .after
        .parameters
        .iter()
        .zip(id.after.values.iter().zip(&id.after.stderr))
        .map(|(p, (&v, &se))| {
            let mut e = Estimate::of(p, v, se);
            let prior = o.stated_prior(&p.symbol);
            e.prior = prior.map(|(mean, sd)| Prior { mean, sd });
            e.prior_sds = prior.map(|(mean, sd)| (v - mean) / sd);
            (p.symbol.clone(), e)
        })
        .collect();
    let mut candidates = Vec::new();
    for (k, step) in id.steps.iter().enumerate() {
        for t in &step.trials {
            let fitted = t.fit.as_ref();
            candidates.push(CandidateTrial {
                step: k + 1,
                name: t.name.clone(),
                members: t.members.clone(),
                extends: step.base.clone(),
                score: fitted.map(|f| f.bic - step.base_bic),
                predicted_score: t.predicted_bic_change,
                cv: fitted.map(|f| f.cv).filter(|cv| cv.is_finite()),
                base_cv: step.base_cv,
                values: fitted.map(|f| {
                    f.parameters
                        .iter()
                        .zip(f.values.iter().zip(&f.stderr))
                        .map(|(p, (&value, &stderr))| FittedValue {
                            symbol: p.symbol.clone(),
                            value,
                            stderr,
                        })
                        .collect()
                }),
                selected: t.verdict.added(),
                outcome: t.verdict.clone(),
                verdict: verdict_text(&t.verdict),
            });
        }
    }
    let confounded = id
        .steps
        .iter()
        .enumerate()
        .flat_map(|(k, step)| {
            step.confounded.iter().map(move |c| Confounded {
                step: k + 1,
                chosen: c.chosen.clone(),
                rival: c.rival.clone(),
                correlation: c.correlation,
                held_out_gain: c.held_out_gain.map(|h| h.gain),
                held_out_gain_stderr: c.held_out_gain.map(|h| h.stderr),
                predicts_alike: c.predicts_alike(),
                confounded: c.not_separated(),
                designs: c.designs.clone(),
            })
        })
        .collect();
    IdentifyResult {
        source: Source::Runs,
        selected_effects,
        parameters,
        candidates,
        error_before: errors(o, false),
        error_after: errors(o, true),
        driven_model: o.driven_model,
        remaining: o.remaining.clone(),
        discovery: o.discovery.clone(),
        details: Details::Runs(Box::new(RunDetails {
            model: o.model,
            roll_channel: o.roll_channel(),
            speed_imposed: o.speed_imposed,
            kicks: o.segments.len(),
            skipped: o.skipped.clone(),
            eigen_excluded: o.eigen_excluded.iter().map(ExcludedKick::from).collect(),
            findings: o.findings.clone(),
            state_correlation: o.state_correlation.clone(),
            time_series_discovery: o.time_series.clone(),
            final_check: id.final_check.iter().map(MemberCheck::from).collect(),
            confounded,
            weights: id.weights.clone(),
            folds: id.folds,
            simulations: id.simulations,
            seconds: o.seconds,
        })),
    }
}

/// Five-line summary.
pub fn summary<R: ModelRegistry>(o: &Outcome<R>) -> String {
    let id = &o.identification;
    let b = errors(o, false);
    let a = errors(o, true);
    let mut s = String::new();
    let (roll, unit) = (o.roll_channel().describe(), o.roll_channel().unit_deg());
    let _ = writeln!(
        s,
        "kicks: {} from {} runs ({} skipped); model {}{}",
        o.segments.len(),
        o.segments
            .iter()
            .map(|s| &s.run)
            .collect::<std::collections::BTreeSet<_>>()
            .len(),
        o.skipped.len(),
        o.model,
        if o.speed_imposed { " (speed imposed)" } else { "" }
    );
    // Why any run or kick was left out, in the summary itself.
    for why in &o.skipped {
        let _ = writeln!(s, "skipped: {why}");
    }
    for e in &o.eigen_excluded {
        let _ = writeln!(
            s,
            "not a weave (kept out of the eigenvalue figures): {}",
            excluded_kick_text(e)
        );
    }
    let sel = if id.selected.is_empty() {
        "no effect warranted".to_string()
    } else {
        id.selected.join(" + ")
    };
    let _ = writeln!(s, "selected: {sel}");
    for c in id.final_check.iter().filter(|c| c.removed) {
        let _ = writeln!(
            s,
            "removed by the final check: {} (against the model without it, {})",
            c.name,
            verdict_text(&c.verdict)
        );
    }
    for line in confounding_lines(o) {
        let _ = writeln!(s, "{line}");
    }
    let vals: Vec<String> = id
        .after
        .parameters
        .iter()
        .zip(id.after.values.iter().zip(&id.after.stderr))
        .map(|(p, (v, se))| {
            let prior = o
                .stated_prior(&p.symbol)
                .map(|(mean, sd)| format!(" ({:+.1} prior sd from the measured {mean:.4})", (v - mean) / sd))
                .unwrap_or_default();
            match p.on_bound(*v) {
                Some(b) => format!("{} = {:.4} {} ({})", p.symbol, v, p.unit, bound_text(b)),
                None => format!("{} = {:.4} +- {:.4} {}{prior}", p.symbol, v, 1.96 * se, p.unit),
            }
        })
        .collect();
    let _ = writeln!(
        s,
        "parameters (+- 95 % interval): {}",
        if vals.is_empty() { "-".into() } else { vals.join(", ") }
    );
    // The headline: runs predicted with the values fitted to the others.
    let held_roll = |e: &Errors| nan(e.held_out.roll_rms);
    let confirmed = if !id.selected.is_empty()
        && !(a.held_out.eigen_rms < b.held_out.eigen_rms || held_roll(&a) < held_roll(&b))
    {
        "; not confirmed on held-out data: neither the weave eigenvalue nor the roll error of the held-out runs falls"
    } else {
        ""
    };
    let _ = writeln!(
        s,
        "held-out runs: weave RMS {:.3} -> {:.3} 1/s, {roll} RMS {:.3} -> {:.3} {unit} ({} folds, {} simulations, {:.1} s){confirmed}",
        b.held_out.eigen_rms,
        a.held_out.eigen_rms,
        held_roll(&b).to_degrees(),
        held_roll(&a).to_degrees(),
        id.folds,
        id.simulations,
        o.seconds
    );
    let _ = write!(
        s,
        "fitted runs, error before -> after: weave eigenvalue RMS {:.3} -> {:.3} 1/s (weighted {:.3} -> {:.3}; {} of {} kicks a weave), {roll} RMS {:.3} -> {:.3} {unit} (median run {:.3} -> {:.3}), steer RMS {:.3} -> {:.3} deg",
        b.eigen_rms,
        a.eigen_rms,
        nan(b.eigen_weighted_rms),
        nan(a.eigen_weighted_rms),
        o.weave_kicks.iter().filter(|&&k| k).count(),
        o.segments.len(),
        nan(b.roll_rms).to_degrees(),
        nan(a.roll_rms).to_degrees(),
        nan(b.median_run_roll_rms).to_degrees(),
        nan(a.median_run_roll_rms).to_degrees(),
        nan(b.steer_rms).to_degrees(),
        nan(a.steer_rms).to_degrees(),
    );
    // Whether the library ran out: a pattern left beyond the kicks' scatter.
    if let Some(r) = &o.remaining {
        let _ = write!(s, "\n{}", super::remaining::remaining_sentence(r, "kicks"));
    }
    if !o.state_correlation.is_empty() {
        let _ = write!(
            s,
            "\n{}",
            super::remaining::state_correlation_sentence(&o.state_correlation)
        );
    }
    if let Some(d) = &o.discovery {
        let _ = write!(s, "\n{}", super::discovery::kicks_sentence(d));
    }
    if let Some(t) = &o.time_series {
        let _ = write!(s, "\n{}", super::time_series::sentence(t, unit, 1f64.to_degrees()));
    }
    s
}

/// Parameter file of the identified bicycle: the bicycle with its
/// corrected parameters, plus the fitted effect values.
fn fitted_toml<R: ModelRegistry>(
    bike: &Bicycle<R>,
    values: &BTreeMap<String, f64>,
    o: &Outcome<R>,
) -> Result<String, IdentifyError> {
    let mut fitted = bike.clone();
    let mut corrected = Vec::new();
    for (k, v) in values {
        if !bike.effects.contains_key(k) && !crate::models::effect_parameters_in::<R>().iter().any(|p| p.name == k) {
            corrected.push(format!("{k} {:.6e} -> {v:.6e}", bike.value(k).unwrap_or(f64::NAN)));
        }
        fitted = fitted.with_parameter(k, *v)?;
    }
    let mut s = fitted.parameters.to_toml_string();
    if !corrected.is_empty() {
        let _ = writeln!(
            s,
            "\n# Parameters corrected by `bikedyn identify`: {}.",
            corrected.join(", ")
        );
    }
    let _ = writeln!(
        s,
        "\n# Effects identified by `bikedyn identify` (model {}; driven-speed twin {}).",
        o.model, o.driven_model
    );
    s.push_str(&fitted.effects_toml());
    Ok(s)
}

/// Write the report folder; the bicycle of `a` is resolved against the
/// registry the identification ran on.
/// The plots take the size and resolution of `plot`; its axis limits apply
/// to the continuation diagram; their subject is the bicycle and the model.
pub fn write_report<R: ModelRegistry>(
    o: &Outcome<R>,
    a: &IdentifyRequest,
    dir: &Path,
    plot: &bikedyn_report::plot::PlotOptions,
) -> Result<(), IdentifyError> {
    // Written beside `dir` and moved into its place at the end: a failure
    // leaves an earlier report as it was, and no old file stays beside the
    // new ones.
    let staged = StagedDir::new(dir, FolderKind::IdentifyReport)?;
    let out = staged.path();
    let bike = Bicycle::<R>::resolve_in(&o.bike)?;
    save_json(out.join("report.json"), &result(o))?;
    write_string_atomic(out.join("fitted.toml"), &fitted_toml(&bike, &o.values_after, o)?)?;
    // Continuation diagram before and after.
    let vmax = o.segments.iter().map(|s| s.speed_interval[1]).fold(7.0, f64::max) + 1.0;
    let speeds: Vec<f64> = (1..=200).map(|i| vmax * i as f64 / 200.0).collect();
    let (_, driven, _) = identification_models(&bike, false)?;
    let curve = |vals: &BTreeMap<String, f64>| -> Result<Vec<(f64, f64, f64)>, IdentifyError> {
        let pts: Vec<(f64, f64, f64)> = predict(driven, &bike, vals, &speeds)?
            .into_iter()
            .zip(&speeds)
            .filter_map(|(z, &v)| z.map(|z| (v, z[0], z[1])))
            .collect();
        // The weave, followed down from high speed until it stops being
        // one complex pair (a jump far beyond the typical step means
        // another pair took over, e.g. capsize-castering at low speed).
        let steps: Vec<f64> = pts
            .windows(2)
            .map(|w| (w[1].1 - w[0].1).hypot(w[1].2 - w[0].2))
            .collect();
        let typical = median(steps.iter().copied());
        let mut start = 0;
        for k in (0..steps.len()).rev() {
            if steps[k] > 10.0 * typical.max(1e-9) {
                start = k + 1;
                break;
            }
        }
        Ok(pts[start..].to_vec())
    };
    // The measured weave eigenvalues that count in the figures.
    let measured: Vec<MeasuredWeave> = o
        .segments
        .iter()
        .zip(&o.weave_kicks)
        .filter(|(_, &counted)| counted)
        .filter_map(|(s, _)| {
            let (w, se) = s.weave?;
            Some(MeasuredWeave {
                speed_interval: s.speed_interval,
                mean_speed: s.mean_speed,
                eigenvalue: w,
                stderr: se,
            })
        })
        .collect();
    let label = if o.identification.selected.is_empty() {
        "no effect warranted".to_string()
    } else {
        o.identification.selected.join(" + ")
    };
    let mut rates: Vec<f64> = o.steer_rate.iter().copied().filter(|x| x.is_finite()).collect();
    rates.sort_by(f64::total_cmp);
    let median_rate = rates.get(rates.len() / 2).copied().unwrap_or(f64::NAN);
    let driven_info = R::models()
        .iter()
        .find(|m| m.name == o.driven_model)
        .expect("the identification's driven model is registered");
    let plot = bikedyn_report::plot::PlotOptions {
        subject: Some(bikedyn_report::plot::subject(
            &o.bike,
            Some(&o.driven_model.to_string()),
        )),
        ..plot.clone()
    };
    for ext in ["svg", "png"] {
        plot_continuation(
            &out.join(format!("continuation.{ext}")),
            &curve(&BTreeMap::new())?,
            &curve(&linear_equivalent(driven_info, &o.values_after, median_rate))?,
            &label,
            &measured,
            &plot,
        )?;
    }
    let run_plot = bikedyn_report::plot::PlotOptions {
        x_range: None,
        y_range: None,
        ..plot.clone()
    };
    if let Some(rp) = &o.run_plot {
        let s = &o.segments[rp.segment];
        let deg = |x: &[f64]| x.iter().map(|v| v.to_degrees()).collect::<Vec<f64>>();
        let (Some(b), Some(a)) = (&rp.before[rp.segment], &rp.after[rp.segment]) else {
            return Err(IdentifyError::TypicalRunNotSimulated);
        };
        let (mr, br, ar) = (deg(&s.roll), deg(&b.roll), deg(&a.roll));
        let (ms, bs, as_) = (deg(&s.steer), deg(&b.steer), deg(&a.steer));
        for ext in ["svg", "png"] {
            plot_run(
                &out.join(format!("run_residuals.{ext}")),
                &format!(
                    "{} (window from {:.2} s): measured and simulated, before and after",
                    Path::new(&s.run)
                        .file_name()
                        .map_or(s.run.clone(), |n| n.to_string_lossy().into_owned()),
                    s.t0
                ),
                &[
                    Channel {
                        name: s.roll_channel.describe(),
                        unit: s.roll_channel.unit_deg(),
                        t: &s.t,
                        measured: &mr,
                        before: &br,
                        after: &ar,
                    },
                    Channel {
                        name: "steer",
                        unit: "deg",
                        t: &s.t,
                        measured: &ms,
                        before: &bs,
                        after: &as_,
                    },
                    Channel {
                        name: "speed",
                        unit: "m/s",
                        t: &s.speed_t,
                        measured: &s.speed,
                        before: &b.speed,
                        after: &a.speed,
                    },
                ],
                &run_plot,
            )?;
        }
    }
    let mut md = report_markdown(o, a, dir);
    // The effect file: the terms found in the time series (fitted through
    // the nonlinear model), else those found on the kicks' eigenvalues.
    let time_series_file = o.time_series.as_ref().and_then(super::time_series::effect_file_of);
    if let Some(super::time_series::TimeSeriesOutcome::Ran(f)) = &o.time_series {
        md += &super::time_series::markdown(f);
        match &time_series_file {
            Some(Ok(file)) => {
                md += "\nThe terms found in the time series are written as an effect file in the modeler's form: `discovered.rs` (for `modeler/src/effects/` or a crate of your own).\n";
                write_string_atomic(out.join("discovered.rs"), file)?;
            }
            Some(Err(e)) => md += &format!("\nNo effect file was written: {e}.\n"),
            None => {}
        }
    }
    if let Some(super::discovery::DiscoveryOutcome::Ran(d)) = &o.discovery {
        md += &super::discovery::trials_markdown(d);
        if !d.discovery.terms.is_empty() && time_series_file.is_none() {
            match super::discovery::effect_file("discovered", &d.discovery.terms) {
                Ok(file) => {
                    md += "\nThe discovered terms are written as an effect file in the modeler's form: `discovered.rs` (for `modeler/src/effects/` or a crate of your own).\n";
                    write_string_atomic(out.join("discovered.rs"), &file)?;
                }
                Err(e) => md += &format!("\nNo effect file was written: {e}.\n"),
            }
        }
    }
    write_string_atomic(out.join("report.md"), &md)?;
    staged.commit()?;
    Ok(())
}
