//! `bikedyn stability`: weave and capsize speeds and the self-stable speeds.

use super::args::BikeArg;
use super::load;
use super::text::{stability_json, stability_text};
use anyhow::{bail, Result};
use bikedyn::monte_carlo::{add_spread_json, monte_carlo_speeds, MonteCarloOptions, MonteCarloSpeeds};
use bikedyn::report::output::format_significant;
use bikedyn::runtime::eigen::critical_speeds_of;
use bikedyn::sensitivity::{speed_uncertainties, SensitivityError, SensitivityOptions, StabilityUncertainty};

/// Run `bikedyn stability`.
pub fn run(bike: BikeArg, speed_max: f64, json: bool, monte_carlo: Option<(usize, u64)>) -> Result<bool> {
    let BikeArg { spec: bike, model } = bike;
    let speed_max = super::check_speed_max(speed_max)?;
    let b = load(&bike)?;
    let lin = b.linear_with(model.as_deref())?;
    let crit = critical_speeds_of(&lin, 0.0, speed_max)?;
    // The standard deviations of v_w and v_c the file's `+/-` values imply
    // (none for a file without them; a bicycle without canonical form, or
    // where a derivative does not exist, says why on standard error).
    let uncertainty = match speed_uncertainties(
        &b,
        &SensitivityOptions {
            model: model.clone(),
            speed_max,
            ..SensitivityOptions::default()
        },
    ) {
        Ok(u) => u,
        Err(SensitivityError::NoCrossing { .. }) => None,
        Err(e) => {
            eprintln!("note: no standard deviations of the speeds from the file's +/- values: {e}");
            None
        }
    };
    let sampled = match monte_carlo {
        None => None,
        Some((draws, seed)) => {
            let s = monte_carlo_speeds(
                &b,
                &MonteCarloOptions {
                    draws,
                    seed,
                    model: model.clone(),
                    speed_max,
                },
            )?;
            if s.is_none() {
                bail!("--monte-carlo draws about the file's +/- standard deviations, and `{bike}` gives none");
            }
            s
        }
    };
    if json {
        let mut v = stability_json(&bike, &crit);
        v["model"] = serde_json::json!(lin.model);
        add_spread_json(&mut v, uncertainty.as_ref(), sampled.as_ref())?;
        outln!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        outln!("model: {}", lin.model);
        out!("{}", stability_text(&bike, &crit, b.feedback.is_some()));
        if let Some(u) = &uncertainty {
            out!("{}", uncertainty_text(u));
        }
        if let Some(m) = &sampled {
            out!("{}", monte_carlo_text(m, uncertainty.as_ref()));
        }
    }
    Ok(true)
}

/// The speeds' standard deviations with the three largest shares.
fn uncertainty_text(u: &StabilityUncertainty) -> String {
    let mut s = String::from(
        "  standard deviations from the file's +/- values (first order, exact derivatives, parameters independent):\n",
    );
    for (name, x) in [("v_w", &u.weave_speed), ("v_c", &u.capsize_speed)] {
        let Some(x) = x else { continue };
        let top: Vec<String> = x
            .shares
            .iter()
            .take(3)
            .map(|p| format!("{} {:.0} %", p.parameter, 100.0 * p.share))
            .collect();
        s += &format!(
            "    {name} = {} +/- {} m/s (variance from {})\n",
            format_significant(x.speed, 6),
            format_significant(x.standard_deviation, 2),
            top.join(", ")
        );
    }
    s
}

/// The drawn bicycles' speeds: mean and standard deviation with its
/// standard error.
fn monte_carlo_text(m: &MonteCarloSpeeds, first: Option<&StabilityUncertainty>) -> String {
    let mut s = format!(
        "  Monte Carlo check: {} bicycles drawn about the file's values (seed {}{}):\n",
        m.draws,
        m.seed,
        if m.not_a_bicycle > 0 {
            format!("; {} left out, no bicycle", m.not_a_bicycle)
        } else {
            String::new()
        }
    );
    for (name, x) in [("v_w", &m.weave_speed), ("v_c", &m.capsize_speed)] {
        let Some(x) = x else { continue };
        s += &format!(
            "    {name}: mean {} m/s, standard deviation {} m/s (+/- {} from {} draws)\n",
            format_significant(x.mean, 6),
            format_significant(x.standard_deviation, 3),
            format_significant(x.standard_error_of_sd, 2),
            x.draws
        );
        // Where the draws' spread departs from the first order's by more
        // than three of its standard errors, the speed is not linear over
        // the parameters' spread.
        let first = first.and_then(|u| {
            if name == "v_w" {
                u.weave_speed.as_ref()
            } else {
                u.capsize_speed.as_ref()
            }
        });
        if let Some(f) = first {
            if (x.standard_deviation - f.standard_deviation).abs() > 3.0 * x.standard_error_of_sd {
                let r = f.standard_deviation / x.standard_deviation - 1.0;
                s += &format!(
                    "    {name}: first order does not hold over this spread (its standard deviation is {:.0} % {} the draws'): read the draws\n",
                    100.0 * r.abs(),
                    if r < 0.0 { "below" } else { "above" }
                );
            }
        }
    }
    s
}
