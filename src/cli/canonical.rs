//! `bikedyn canonical`: the canonical matrices, or the state-space matrices
//! A(v), B(v) of a bicycle without canonical form.

use super::args::BikeArg;
use super::text::{canonical_json, canonical_text, matrix_text, state_input_rows, state_space_text};
use super::{load, parse_range};
use anyhow::{Context, Result};
use bikedyn::runtime::eigen::{LinearBicycle, StateSpaceBicycle};
use bikedyn::sensitivity::canonical_uncertainties;

/// Run `bikedyn canonical`.
pub fn run(bike: BikeArg, speeds: String, json: bool) -> Result<bool> {
    let BikeArg { spec: bike, model } = bike;
    // Checked even when the bicycle has a canonical form and the speeds are
    // not used: a bad value is a slip to show, not to pass over.
    let speeds = parse_range(&speeds, "--speeds")?;
    let b = load(&bike)?;
    let lin = b.linear_with(model.as_deref())?;
    match &lin.canonical {
        Some(c) => {
            // The entries' standard deviations from the file's +/- values.
            let sd = match canonical_uncertainties(&b, model.as_deref()) {
                Ok(sd) => sd,
                Err(e) => {
                    eprintln!("note: no standard deviations of the matrices from the file's +/- values: {e}");
                    None
                }
            };
            if json {
                let mut v = canonical_json(c);
                v["model"] = serde_json::json!(lin.model);
                if let Some(sd) = &sd {
                    let mut s = canonical_json(sd);
                    if let Some(o) = s.as_object_mut() {
                        o.remove("g");
                    }
                    v["standard_deviations"] = s;
                }
                outln!("{}", serde_json::to_string_pretty(&v)?);
            } else {
                outln!("model: {}", lin.model);
                out!("{}", canonical_text(c));
                if let Some(sd) = &sd {
                    outln!("standard deviations from the file's +/- values (first order, exact derivatives, parameters independent):");
                    for (name, m) in [("M0", &sd.m0), ("C1", &sd.c1), ("K0", &sd.k0), ("K2", &sd.k2)] {
                        let rows = [m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]];
                        out!("{}", matrix_text(&format!("sd({name})"), 2, &rows));
                    }
                }
            }
        }
        None => {
            // Why there is no canonical form, then A(v), B(v).
            let why = b
                .canonical_with(model.as_deref())
                .err()
                .map(|e| e.to_string())
                .unwrap_or_default();
            if let Some(first) = lin.first_order() {
                return first_order(lin.model, first, &speeds, json);
            }
            let mut rows = Vec::new();
            for &v in &speeds {
                let m = lin.at_speed(v)?;
                let a = m
                    .state_matrix()
                    .with_context(|| format!("singular mass matrix at {v} m/s"))?;
                let minv = m.mass.try_inverse().context("singular mass matrix")?;
                rows.push((v, a, minv));
            }
            if json {
                let v: Vec<_> = rows
                    .iter()
                    .map(|(v, a, minv)| {
                        serde_json::json!({
                            "speed": v,
                            "A": (0..4).map(|i| (0..4).map(|j| a[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
                            "B": state_input_rows(minv),
                        })
                    })
                    .collect();
                let out = serde_json::json!({
                    "model": lin.model,
                    "canonical": null,
                    "why": why,
                    "state": ["roll", "steer", "roll_rate", "steer_rate"],
                    "inputs": ["roll_torque", "steer_torque"],
                    "state_space": v,
                });
                outln!("{}", serde_json::to_string_pretty(&out)?);
            } else {
                outln!("model: {}", lin.model);
                outln!("no canonical form: {why}");
                outln!("state-space form x' = A(v) x + B(v) u, x = [roll, steer, roll rate, steer rate] (rad, rad/s), u = [roll torque, steer torque] (N m), benchmark signs:");
                for (v, a, minv) in &rows {
                    out!("{}", state_space_text(*v, a, minv));
                }
            }
        }
    }
    Ok(true)
}

/// A model with extra states: its lateral first-order equations `x' = A(v) x`
/// with the state named (no roll-steer form, so no `M`, `C`, `K`; the
/// torque inputs are not formed for these models).
fn first_order(model: &str, eq: &dyn StateSpaceBicycle, speeds: &[f64], json: bool) -> Result<bool> {
    let mut rows = Vec::new();
    for &v in speeds {
        rows.push((v, eq.lateral_states(v)?));
    }
    let names = rows.first().map(|(_, l)| l.names.clone()).unwrap_or_default();
    let extra: Vec<&str> = rows
        .first()
        .map(|(_, l)| l.extra.iter().map(|&i| l.names[i].as_str()).collect())
        .unwrap_or_default();
    let why = &format!(
        "model `{model}` has extra first-order states ({}): its lateral equations have no second-order roll-steer form",
        extra.join(", ")
    );
    if json {
        let v: Vec<_> = rows
            .iter()
            .map(|(v, l)| {
                serde_json::json!({
                    "speed": v,
                    "A": (0..l.a.nrows()).map(|i| (0..l.a.ncols()).map(|j| l.a[(i, j)]).collect::<Vec<_>>()).collect::<Vec<_>>(),
                })
            })
            .collect();
        let out = serde_json::json!({
            "model": model,
            "canonical": null,
            "why": why,
            "state": names,
            "state_space": v,
        });
        outln!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        outln!("model: {model}");
        outln!("no canonical form: {why}");
        outln!(
            "first-order lateral equations x' = A(v) x, x = [{}] (the model's own coordinates and signs; rates are d + coordinate, then the extra states):",
            names.join(", ")
        );
        for (v, l) in &rows {
            outln!("v = {v} m/s");
            let e: Vec<f64> = l.a.transpose().iter().copied().collect();
            out!("{}", matrix_text("A", l.a.ncols(), &e));
        }
    }
    Ok(true)
}
