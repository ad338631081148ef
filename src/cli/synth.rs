//! `bikedyn synth`: synthetic field runs (issue 7, point 6); the work is
//! `bikedyn::synth`, this parses the effects and speeds and prints a line
//! per run.

use super::args::SynthArgs;
use anyhow::{Context, Result};
use bikedyn::synth::{synth, SynthOptions, SynthRun};
use std::path::Path;

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

/// `LO:HI` of `--speeds` (m/s).
fn speeds(s: &str) -> Result<[f64; 2]> {
    let (lo, hi) = s
        .split_once(':')
        .and_then(|(l, h)| Some((l.trim().parse::<f64>().ok()?, h.trim().parse::<f64>().ok()?)))
        .filter(|(l, h)| l.is_finite() && h.is_finite() && *l > 0.0 && h >= l)
        .with_context(|| format!("--speeds `{s}`: expected LO:HI with 0 < LO <= HI (m/s)"))?;
    Ok([lo, hi])
}

fn print_run(r: &SynthRun) {
    let plan = &r.plan;
    if r.name == "run01" {
        println!("model: {}", r.model);
    }
    println!(
        "{}: release at {:.2} s, {:.2} m/s, kick {:+.2} N s at {:.2} s, {}",
        r.name,
        plan.launch_duration,
        plan.speed,
        plan.kick_impulse,
        plan.launch_duration + plan.kick_delay,
        r.stop
    );
}

/// Make the set and print a line per run and the folder.
fn make(opts: &SynthOptions) -> Result<bool> {
    synth(opts, &mut print_run)?;
    println!("wrote {} runs to {}", opts.runs, opts.out.display());
    Ok(true)
}

/// Run `bikedyn synth`.
pub fn run(a: SynthArgs) -> Result<bool> {
    if a.runs == 0 || a.runs > 1000 {
        anyhow::bail!("--runs must be between 1 and 1000");
    }
    let effects = a.effects.iter().map(|e| effect(e)).collect::<Result<_>>()?;
    make(&SynthOptions {
        speeds: speeds(&a.speeds)?,
        bike: a.bike,
        model: a.model,
        effects,
        runs: a.runs,
        seed: a.seed,
        out: a.out,
    })
}

/// A synthetic set of the thesis bicycle at 4-6.5 m/s with `effects`
/// (`SYMBOL=VALUE`) hidden (for the identification bench).
pub fn thesis_set(out: &Path, runs: usize, seed: u64, effects: &[&str]) -> Result<bool> {
    make(&SynthOptions {
        effects: effects.iter().map(|e| effect(e)).collect::<Result<_>>()?,
        speeds: [4.0, 6.5],
        runs,
        seed,
        out: out.to_path_buf(),
        ..SynthOptions::default()
    })
}
