//! `bikedyn stability`: weave and capsize speeds and the self-stable speeds.

use super::args::BikeArg;
use super::load;
use super::text::stability_text;
use anyhow::Result;
use bikedyn::monte_carlo::MonteCarloSpeeds;
use bikedyn::report::output::format_significant;
use bikedyn::sensitivity::StabilityUncertainty;
use bikedyn::stability::{stability, StabilityOptions};

/// Run `bikedyn stability`. The job is [`bikedyn::stability::stability`];
/// this prints its result.
pub fn run(bike: BikeArg, speed_max: f64, json: bool, monte_carlo: Option<(usize, u64)>) -> Result<bool> {
    let BikeArg { spec: bike, model } = bike;
    let speed_max = super::check_speed_max(speed_max)?;
    let b = load(&bike)?;
    if monte_carlo.is_some() && b.uncertainties.is_empty() {
        anyhow::bail!("--monte-carlo draws about the file's +/- standard deviations, and `{bike}` gives none");
    }
    let report = stability(
        &b,
        &StabilityOptions {
            model,
            speed_min: 0.0,
            speed_max,
            monte_carlo,
            label: Some(bike.clone()),
        },
    )?;
    // A bicycle without canonical form, or where a derivative does not
    // exist, says why it has no standard deviations.
    if let Some(why) = &report.uncertainty_missing {
        eprintln!("note: no standard deviations of the speeds from the file's +/- values: {why}");
    }
    if json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        outln!("model: {}", report.model);
        out!("{}", stability_text(&bike, &report.critical, b.feedback.is_some()));
        if let Some(u) = &report.uncertainty {
            out!("{}", uncertainty_text(u));
        }
        if let Some(m) = &report.monte_carlo {
            out!("{}", monte_carlo_text(m, report.uncertainty.as_ref()));
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
