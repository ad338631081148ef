//! `bikedyn stability`: weave and capsize speeds and the self-stable speeds.

use super::args::BikeArg;
use super::load;
use super::text::{stability_json, stability_text};
use anyhow::Result;
use bikedyn::runtime::eigen::critical_speeds_of;

/// Run `bikedyn stability`.
pub fn run(bike: BikeArg, speed_max: f64, json: bool) -> Result<bool> {
    let BikeArg { spec: bike, model } = bike;
    let speed_max = super::check_speed_max(speed_max)?;
    let b = load(&bike)?;
    let lin = b.linear_with(model.as_deref())?;
    let crit = critical_speeds_of(&lin, 0.0, speed_max)?;
    if json {
        let mut v = stability_json(&bike, &crit);
        v["model"] = serde_json::json!(lin.model);
        outln!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        outln!("model: {}", lin.model);
        out!("{}", stability_text(&bike, &crit));
    }
    Ok(true)
}
