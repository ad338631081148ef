//! `bikedyn canonical`: the canonical matrices, or the state-space matrices
//! A(v), B(v) of a bicycle without canonical form. The job is
//! [`bikedyn::canonical::canonical`]; this prints its result.

use super::args::BikeArg;
use super::text::{canonical_text, matrix_text};
use super::{load, parse_range};
use anyhow::Result;
use bikedyn::canonical::{canonical, CanonicalOptions, CanonicalReport, StateSpace};

/// Run `bikedyn canonical`.
pub fn run(bike: BikeArg, speeds: String, json: bool) -> Result<bool> {
    let BikeArg { spec: bike, model } = bike;
    // Checked even when the bicycle has a canonical form and the speeds are
    // not used: a bad value is a slip to show, not to pass over.
    let speeds = parse_range(&speeds, "--speeds")?;
    let b = load(&bike)?;
    let report = canonical(&b, &CanonicalOptions { model, speeds })?;
    if let CanonicalReport::Canonical(c) = &report {
        if let Some(why) = &c.standard_deviations_missing {
            eprintln!("note: no standard deviations of the matrices from the file's +/- values: {why}");
        }
    }
    if json {
        outln!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(true);
    }
    match &report {
        CanonicalReport::Canonical(c) => {
            outln!("model: {}", c.model);
            out!("{}", canonical_text(&c.exact));
            if let Some(sd) = &c.standard_deviations {
                outln!("standard deviations from the file's +/- values (first order, exact derivatives, parameters independent):");
                for (name, m) in [("M0", &sd.m0), ("C1", &sd.c1), ("K0", &sd.k0), ("K2", &sd.k2)] {
                    let rows = [m[0][0], m[0][1], m[1][0], m[1][1]];
                    out!("{}", matrix_text(&format!("sd({name})"), 2, &rows));
                }
            }
        }
        CanonicalReport::StateSpace(n) => {
            outln!("model: {}", n.state_space.model);
            outln!("no canonical form: {}", n.why);
            state_space_text(&n.state_space)?;
        }
    }
    Ok(true)
}

/// The state-space matrices, speed by speed.
fn state_space_text(ss: &StateSpace) -> Result<()> {
    if ss.model_coordinates {
        outln!(
            "first-order lateral equations x' = A(v) x, x = [{}] (the model's own coordinates and signs; rates are d + coordinate, then the extra states):",
            ss.states.join(", ")
        );
    } else {
        outln!("state-space form x' = A(v) x + B(v) u, x = [roll, steer, roll rate, steer rate] (rad, rad/s), u = [roll torque, steer torque] (N m), benchmark signs:");
    }
    for at in &ss.at {
        outln!("v = {} m/s", at.speed);
        let a: Vec<f64> = at.a.iter().flatten().copied().collect();
        out!("{}", matrix_text("A", at.a.first().map_or(0, Vec::len), &a));
        if let Some(b) = &at.b {
            let b: Vec<f64> = b.iter().flatten().copied().collect();
            out!("{}", matrix_text("B", 2, &b));
        }
    }
    Ok(())
}
