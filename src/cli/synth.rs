//! `bikedyn synth`: synthetic field runs (issue 7, point 6); the work is
//! `bikedyn::synth`, this parses the effects and speeds and prints a line
//! per run.

use super::args::SynthArgs;
use anyhow::{Context, Result};
use bikedyn::progress::Progress;
use bikedyn::synth::MAX_SPEED_M_S;
use bikedyn::synth::{synth, SynthOptions, SynthRun};

/// `SYMBOL=VALUE` of `--effects`.
fn effect(e: &str) -> Result<(String, f64)> {
    let (sym, val) = e
        .split_once('=')
        .with_context(|| format!("--effects `{e}`: expected SYMBOL=VALUE"))?;
    let val: f64 = val
        .trim()
        .parse()
        .ok()
        .filter(|v: &f64| v.is_finite())
        .with_context(|| format!("--effects `{e}`: `{}` is not a finite number", val.trim()))?;
    Ok((sym.trim().to_string(), val))
}

/// Every `SYMBOL=VALUE` of `--effects`, each symbol once (a repeated one
/// would silently take its last value).
fn effects(list: &[String]) -> Result<Vec<(String, f64)>> {
    let mut out: Vec<(String, f64)> = Vec::new();
    for e in list {
        let (sym, val) = effect(e)?;
        if let Some((_, first)) = out.iter().find(|(s, _)| *s == sym) {
            anyhow::bail!("--effects: `{sym}` is given twice ({first} and {val}); give each symbol once");
        }
        out.push((sym, val));
    }
    Ok(out)
}

/// `LO:HI` of `--speeds` (m/s).
fn speeds(s: &str) -> Result<[f64; 2]> {
    let (lo, hi) = s
        .split_once(':')
        .and_then(|(l, h)| Some((l.trim().parse::<f64>().ok()?, h.trim().parse::<f64>().ok()?)))
        .filter(|(l, h)| l.is_finite() && h.is_finite() && *l > 0.0 && h >= l && *h <= MAX_SPEED_M_S)
        .with_context(|| format!("--speeds `{s}`: expected LO:HI with 0 < LO <= HI <= {MAX_SPEED_M_S} (m/s)"))?;
    Ok([lo, hi])
}

/// One run's line (and the model's before the first), as `bikedyn synth`
/// and `bikedyn bench --identify` print them.
pub(super) fn print_run(r: &SynthRun) -> Result<()> {
    let plan = &r.plan;
    if r.name == "run01" {
        outln!("model: {}", r.model);
    }
    outln!(
        "{}: release at {:.2} s, {:.2} m/s, kick {:+.2} N s at {:.2} s, {}",
        r.name,
        plan.launch_duration,
        plan.speed,
        plan.kick_impulse,
        plan.launch_duration + plan.kick_delay,
        r.stop
    );
    Ok(())
}

/// Make the set, then print a line per run and the folder: the files are
/// complete before anything is printed, so a closed pipe cannot leave a
/// half-made set.
fn make(opts: &SynthOptions) -> Result<bool> {
    let display = super::ProgressDisplay::new();
    let mut runs = Vec::new();
    synth(opts, &mut |r: &SynthRun| {
        runs.push(r.clone());
        display.show(Progress {
            step: "runs simulated",
            done: runs.len(),
            total: Some(opts.runs),
        });
    })?;
    drop(display);
    for r in &runs {
        print_run(r)?;
    }
    outln!("wrote {} runs to {}", opts.runs, opts.out.display());
    Ok(true)
}

/// Run `bikedyn synth`.
pub fn run(a: SynthArgs) -> Result<bool> {
    if a.runs == 0 || a.runs > 1000 {
        anyhow::bail!("--runs must be between 1 and 1000");
    }
    let effects = effects(&a.effects)?;
    super::Paths::new()
        .bike("--bike", Some(&a.bike))
        .folder("--out", Some(&a.out))
        .check()?;
    make(&SynthOptions {
        speeds: speeds(&a.speeds)?,
        bike: a.bike,
        model: a.model,
        effects,
        runs: a.runs,
        seed: a.seed,
        out: a.out,
        force: a.force,
    })
}
