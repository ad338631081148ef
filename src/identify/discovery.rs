//! Discovering a force the library does not name (issue 37, item 2), from a
//! table of measured weave eigenvalues: the runtime's dictionary search
//! (`bikedyn_runtime::identify::discovery`) on the linear equations of the
//! driven model with the library's selection, its parameters refitted with
//! the terms. This file builds the problem and says what was found in
//! physical words; the runtime computes.

use super::candidates::identification_models;
use super::predict::plants;
use super::IdentifyError;
use crate::bicycle::Bicycle;
use bikedyn_runtime::identify::discovery::{
    discover, Coordinate, Discovery, FoundTerm, LibraryParameter, PlantAt, Problem, Row, Signal, Term,
};
use bikedyn_runtime::identify::remaining::Remaining;
use bikedyn_runtime::identify::Candidate;
use bikedyn_runtime::registry::ModelInfo;
use serde::Serialize;
use std::collections::BTreeMap;

/// Most terms the discovery adds.
pub const MAX_TERMS: usize = 3;

/// What the discovery found on a table, with the errors at the three
/// stages.
#[derive(Clone, Debug, Serialize)]
pub struct TableDiscovery {
    #[serde(flatten)]
    pub discovery: Discovery,
    /// Each found term in physical words.
    pub readings: Vec<String>,
    /// RMS |measured - predicted| weave eigenvalue (1/s) with the library
    /// alone and with the discovered terms: all rows fitted, and each row
    /// held out (predicted with the values fitted to the other folds).
    pub rms_library: f64,
    pub rms_after: f64,
    pub rms_library_held_out: f64,
    pub rms_held_out: f64,
}

/// Why the discovery did not run, or what it found.
#[derive(Clone, Debug, Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum DiscoveryOutcome {
    Ran(Box<TableDiscovery>),
    NotRun { reason: String },
}

/// Why the search is not run after the remaining-residual test
/// (`remaining`): it searches only where the library leaves a structured
/// residual, so that it never fits terms to the measurements' scatter.
pub fn not_warranted(remaining: Option<&Remaining>) -> Option<DiscoveryOutcome> {
    let reason = match remaining {
        None => "too few measurements to test what the library leaves for structure",
        Some(r) if !r.structured => {
            "the library leaves no structured residual (it is within the measurements' scatter)"
        }
        Some(_) => return None,
    };
    Some(DiscoveryOutcome::NotRun { reason: reason.into() })
}

/// RMS |measured - predicted| (1/s) over the rows with a prediction.
pub fn rms(measured: &[[f64; 2]], predicted: &[Option<[f64; 2]>]) -> f64 {
    let d: Vec<f64> = measured
        .iter()
        .zip(predicted)
        .filter_map(|(m, p)| p.map(|p| (m[0] - p[0]).powi(2) + (m[1] - p[1]).powi(2)))
        .collect();
    (d.iter().sum::<f64>() / d.len().max(1) as f64).sqrt()
}

/// Run the dictionary search on the rows after the library's selection
/// `selected` at values `values` (the library's fit, one per parameter).
pub fn discover_on_table<R: bikedyn_runtime::registry::ModelRegistry>(
    driven: &ModelInfo,
    bike: &Bicycle<R>,
    rows: &[Row],
    selected: &[&Candidate],
    values: &[f64],
    max_folds: usize,
) -> Result<DiscoveryOutcome, IdentifyError> {
    let library: Vec<LibraryParameter> = selected
        .iter()
        .flat_map(|c| c.parameters.iter())
        .zip(values)
        .map(|(p, &v)| LibraryParameter {
            name: p.symbol.clone(),
            start: v,
            prior: p.prior,
            scale: p.scale,
        })
        .collect();
    let speeds: Vec<f64> = rows.iter().map(|r| r.speed).collect();
    let start = super::candidates::values_map(selected, values);
    if plants(driven, bike, &start, &speeds)?.is_none() {
        let alt = identification_models(bike, false)?
            .2
            .map_or("another model", |m| m.name);
        return Ok(DiscoveryOutcome::NotRun {
            reason: format!(
                "the library's selection needs {alt}, whose extra states give no mass, damping and stiffness matrices to add the terms to"
            ),
        });
    }
    let plant = |x: &[f64]| -> Vec<Option<PlantAt>> {
        let vals = super::candidates::values_map(selected, x);
        plants(driven, bike, &vals, &speeds)
            .ok()
            .flatten()
            .unwrap_or_else(|| vec![None; speeds.len()])
    };
    Ok(search(
        rows,
        &plant,
        &library,
        bike.feedback.is_some(),
        max_folds,
        None,
        None,
    ))
}

/// The search on `rows` with the plant and library parameters given, and
/// the errors of its stages (`NotRun` with the reason when it cannot run).
fn search(
    rows: &[Row],
    plant: &bikedyn_runtime::identify::discovery::Plant<'_>,
    library: &[LibraryParameter],
    controller: bool,
    max_folds: usize,
    folds: Option<&[usize]>,
    reference: Option<&[Option<[f64; 2]>]>,
) -> DiscoveryOutcome {
    let problem = Problem {
        rows,
        plant,
        library,
        dictionary: Term::dictionary(controller),
        max_terms: MAX_TERMS,
        max_folds,
        folds,
        reference,
    };
    let d = match discover(&problem) {
        Ok(d) => d,
        Err(e) => return DiscoveryOutcome::NotRun { reason: e.to_string() },
    };
    let measured: Vec<[f64; 2]> = rows.iter().map(|r| r.measured).collect();
    DiscoveryOutcome::Ran(Box::new(TableDiscovery {
        readings: d.terms.iter().map(reading).collect(),
        rms_library: rms(&measured, &d.predicted_library),
        rms_after: rms(&measured, &d.predicted_after),
        rms_library_held_out: rms(&measured, &d.predicted_library_held_out),
        rms_held_out: rms(&measured, &d.predicted_held_out),
        discovery: d,
    }))
}

/// The search on the weave eigenvalues that `fit` measured on the kicks of
/// runs or logs (`rows`, with `values` the identified model's values, each
/// kick's own: a friction's describing function depends on its
/// amplitude), the kicks of a run or log held out together (`folds`). The
/// library's values stay as the time-series fit left them (no library
/// parameter is refitted here), so a term must also predict the held-out
/// kicks consistently better than the base model (`base`: its weave at
/// each row), not only than those values.
pub fn discover_on_kicks<R: bikedyn_runtime::registry::ModelRegistry>(
    driven: &ModelInfo,
    bike: &Bicycle<R>,
    rows: &[Row],
    values: &[BTreeMap<String, f64>],
    folds: &[usize],
    base: &[Option<[f64; 2]>],
) -> Result<DiscoveryOutcome, IdentifyError> {
    let mut fixed = Vec::with_capacity(rows.len());
    for (row, vals) in rows.iter().zip(values) {
        match plants(driven, bike, vals, &[row.speed])? {
            Some(p) => fixed.push(p[0]),
            None => {
                let alt = identification_models(bike, false)?
                    .2
                    .map_or("another model", |m| m.name);
                return Ok(DiscoveryOutcome::NotRun {
                    reason: format!(
                        "the identified model needs {alt}, whose extra states give no mass, damping and stiffness matrices to add the terms to"
                    ),
                });
            }
        }
    }
    let plant = move |_: &[f64]| fixed.clone();
    let distinct = folds.iter().collect::<std::collections::BTreeSet<_>>().len();
    if distinct < 2 {
        return Ok(DiscoveryOutcome::NotRun {
            reason: "the kicks come from fewer than two runs or logs, so none can be held out".into(),
        });
    }
    Ok(search(
        rows,
        &plant,
        &[],
        bike.feedback.is_some(),
        distinct,
        Some(folds),
        Some(base),
    ))
}

/// What was found, in words: the terms, or that none passes, or why the
/// search did not run.
fn found_sentence(d: &DiscoveryOutcome) -> Result<(String, &TableDiscovery), String> {
    match d {
        DiscoveryOutcome::NotRun { reason } => Err(format!("discovery beyond the library not run: {reason}")),
        DiscoveryOutcome::Ran(t) => Ok((
            if t.readings.is_empty() {
                format!(
                    "discovered beyond the library: no term of the dictionary passes ({} tried)",
                    t.discovery.trials.iter().filter(|x| x.step == 1).count()
                )
            } else {
                format!("discovered beyond the library: {}", t.readings.join("; "))
            },
            t,
        )),
    }
}

/// The table summary's lines: the finding and the weave RMS of the three
/// stages (`base`: the model before the library), fitted and held out.
pub fn table_sentence(d: &DiscoveryOutcome, base: f64) -> String {
    match found_sentence(d) {
        Err(e) => e,
        Ok((found, t)) => format!(
            "{found}\nweave eigenvalue RMS: base model {base:.3}, with the library {:.3}, with the discovered terms {:.3} 1/s; held out: with the library {:.3}, with the discovered terms {:.3} 1/s",
            t.rms_library, t.rms_after, t.rms_library_held_out, t.rms_held_out
        ),
    }
}

/// The runs' summary lines: the finding on the kicks' weave eigenvalues and
/// their RMS with the library (its values as fitted to every run) and
/// with the discovered terms, fitted and held out by the folds of runs.
pub fn kicks_sentence(d: &DiscoveryOutcome) -> String {
    match found_sentence(d) {
        Err(e) => e,
        Ok((found, t)) => format!(
            "{found} (on the kicks' weave eigenvalues)\nkicks' weave eigenvalue RMS: with the library {:.3}, with the discovered terms {:.3} 1/s; held out by folds of runs: {:.3} (the library's values as fitted to every run) -> {:.3} 1/s",
            t.rms_library, t.rms_after, t.rms_library_held_out, t.rms_held_out
        ),
    }
}

/// The report's section on the dictionary: every term tried at every step
/// with its values, criterion, held-out error and verdict.
pub fn trials_markdown(d: &TableDiscovery) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
            s,
            "\n## Discovery: terms of the dictionary\n\nGeneralized forces on the roll and steer equations (benchmark signs), fitted with the library's parameters; values +- one standard error.\n\n| step | term | coefficient (unit) | time constant (s) | BIC change | held-out error | verdict |\n|---|---|---|---|---|---|---|"
        );
    for t in &d.discovery.trials {
        let coefficient = if t.term.parameter_count() > usize::from(t.term.lagged) {
            t.values
                .first()
                .map_or("-".into(), |(v, se)| format!("{v:.4} +- {se:.4} ({})", t.term.unit()))
        } else {
            "-".into()
        };
        let tau = if t.term.lagged {
            t.values
                .last()
                .map_or("-".into(), |(v, se)| format!("{v:.4} +- {se:.4}"))
        } else {
            "-".into()
        };
        let _ = writeln!(
            s,
            "| {} | `{}` | {} | {} | {:+.1} | {:.4} | {} |",
            t.step,
            t.term.name(),
            coefficient,
            tau,
            t.bic_change,
            t.cv,
            super::words::verdict_text(&t.verdict)
        );
    }
    s
}

fn coordinate(c: Coordinate) -> &'static str {
    match c {
        Coordinate::Roll => "roll",
        Coordinate::Steer => "steer",
    }
}

/// A found term in physical words, with its value and 95 % interval
/// (benchmark signs: roll and steer positive to the right).
pub fn reading(f: &FoundTerm) -> String {
    let t = f.term;
    let interval = |(v, se): (f64, f64), unit: &str| format!("{v:.4} +- {:.4} {unit} (95 %)", 1.96 * se);
    let speed = match t.speed_power {
        0 => "",
        1 => ", growing in proportion to the forward speed (as gyroscopic and trail couplings do)",
        _ => ", growing with the forward speed squared (as centrifugal and tyre-force couplings do)",
    };
    let lag = f.time_constant.map_or(String::new(), |tau| {
        format!(
            ", through a first-order lag of {} (an actuator, a tyre or a controller with its own dynamics)",
            interval(tau, "s")
        )
    });
    let Some((theta, se)) = f.coefficient else {
        return format!(
            "the declared controller's torque reaches the bicycle through a first-order lag of {} (a steer motor that follows its command late)",
            interval(f.time_constant.unwrap_or((f64::NAN, f64::NAN)), "s")
        );
    };
    let value = interval((theta, se), &t.unit());
    let negated = interval((-theta, se), &t.unit());
    let what = match (t.equation, t.signal) {
        (e, Signal::Rate(s)) if e == s => {
            if theta < 0.0 {
                format!("a {} damper: {negated}", coordinate(e))
            } else {
                format!("a {} torque that feeds its own rate (negative damping): {value}", coordinate(e))
            }
        }
        (e, Signal::Angle(s)) if e == s => {
            if theta < 0.0 {
                format!("a {} spring (a restoring torque): {negated}", coordinate(e))
            } else {
                format!(
                    "a {} torque that grows with the {} angle (a negative stiffness): {value}",
                    coordinate(e),
                    coordinate(e)
                )
            }
        }
        (e, Signal::Acceleration(s)) if e == s => {
            format!("an added {} inertia (a motor's reflected inertia, a heavier assembly): {negated}", coordinate(e))
        }
        (e, Signal::Acceleration(_)) => {
            format!("an added roll-steer product of inertia in the {} equation: {negated}", coordinate(e))
        }
        (Coordinate::Steer, Signal::Rate(Coordinate::Roll)) => format!(
            "a steer torque from the roll rate, steering {} the lean (a roll-rate feedback, as a controller or a rider applies): {value}",
            if theta > 0.0 { "into" } else { "out of" }
        ),
        (Coordinate::Steer, Signal::Angle(Coordinate::Roll)) => format!(
            "a steer torque from the roll angle, steering {} the lean: {value}",
            if theta > 0.0 { "into" } else { "out of" }
        ),
        (Coordinate::Roll, Signal::Rate(Coordinate::Steer)) => {
            format!("a roll torque from the steer rate: {value}")
        }
        (Coordinate::Roll, Signal::Angle(Coordinate::Steer)) => {
            format!("a roll torque from the steer angle: {value}")
        }
        (e, Signal::Constant) => format!(
            "a constant {} torque to the {} (a bias: a cable or a load pulling to one side, a motor's offset): {value}",
            coordinate(e),
            if theta > 0.0 { "right" } else { "left" }
        ),
        (e, Signal::Coulomb(s)) => {
            if theta > 0.0 {
                format!("{} friction (a Coulomb-like torque opposing the {} rate): {value}", coordinate(e), coordinate(s))
            } else {
                format!("a torque of constant size that drives the {} rate (negative friction): {value}", coordinate(s))
            }
        }
        _ => format!("{}: {value}", t.name()),
    };
    let alike = match f.alike.len() {
        0 => String::new(),
        1..=3 => format!(
            " [the data do not tell it from {}]",
            f.alike.iter().map(Term::name).collect::<Vec<_>>().join(", ")
        ),
        n => format!(
            " [the data do not tell it from {n} other terms, such as {} (all in the report)]",
            f.alike.iter().take(3).map(Term::name).collect::<Vec<_>>().join(", ")
        ),
    };
    format!("{what}{speed}{lag}{alike}")
}

/// A found term's coefficient in the models' signs (the thesis's: steer
/// positive to the left): a benchmark term from coordinate `c` on equation
/// `e` changes sign when exactly one of them is the steer. `None` for the
/// controller's lag and for an added inertia (no generalized force).
pub fn model_coefficient(f: &FoundTerm) -> Option<f64> {
    match f.term.signal {
        Signal::Angle(_) | Signal::Rate(_) | Signal::Constant | Signal::Coulomb(_) => {
            Some(f.coefficient?.0 * f.term.model_sign())
        }
        Signal::Acceleration(_) | Signal::ControllerTorque => None,
    }
}

/// The discovered terms as an effect file in the modeler's form (one file,
/// identification block included), for `modeler/src/effects/NAME.rs` or a
/// user's crate: each coefficient is a parameter with default zero (the
/// effect absent), each lag a first-order state with its time constant as
/// a shape parameter at the value found. The models' signs are the
/// thesis's (steer positive to the left): a benchmark term from coordinate
/// `c` on equation `e` changes sign when exactly one of them is the steer.
/// Terms a generalized force cannot carry (an added inertia multiplies an
/// acceleration; the controller's lag needs the bicycle file's controller)
/// are listed in the file's documentation instead, with what to change.
///
/// The text is parsed as Rust before it is returned (and formatted): an
/// error says what did not parse, and nothing is written.
pub fn effect_file(name: &str, found: &[FoundTerm]) -> Result<String, String> {
    let raw = effect_source(name, found);
    syn::parse_file(&raw)
        .map(|f| prettyplease::unparse(&f))
        .map_err(|e| format!("the effect file for `{name}` does not parse as Rust: {e}"))
}

fn effect_source(name: &str, found: &[FoundTerm]) -> String {
    use std::fmt::Write as _;
    let mut doc = format!(
        "//! `{name}`: generalized forces found by `bikedyn identify` beyond the\n//! effect library (dictionary search on the roll and steer equations).\n//!\n"
    );
    let mut body = String::new();
    let mut fitted = Vec::new();
    for (i, f) in found.iter().enumerate() {
        let t = f.term;
        let _ = writeln!(doc, "//! - {}", reading(f));
        let source = match t.signal {
            Signal::Angle(c) => format!("coord(&parts.{})", coordinate(c)),
            Signal::Rate(c) => format!("rate(&parts.{})", coordinate(c)),
            Signal::Constant => "bikedyn_modeler::expr::num(1)".to_string(),
            // -tanh(w / w0): opposing the rate, smoothed below w0.
            Signal::Coulomb(c) => format!(
                "-(rate(&parts.{}) / bikedyn_modeler::expr::ratio(1, {})).tanh()",
                coordinate(c),
                (1.0 / bikedyn_runtime::identify::discovery::COULOMB_SMOOTHING).round()
            ),
            Signal::Acceleration(c) => {
                let _ = writeln!(
                    doc,
                    "//!   (not written as a force: it multiplies the {} acceleration; add {:.4} kg m^2 to the inertia the bicycle file gives that coordinate)",
                    coordinate(c),
                    -f.coefficient.map_or(f64::NAN, |x| x.0)
                );
                continue;
            }
            Signal::ControllerTorque => {
                let _ = writeln!(
                    doc,
                    "//!   (not written as a force: it lags the bicycle file's [feedback] controller, which is no effect of the model)"
                );
                continue;
            }
        };
        let (Some((theta, se)), Some(theta_model)) = (f.coefficient, model_coefficient(f)) else {
            continue;
        };
        let symbol = format!("{name}_k{i}");
        let power = match t.speed_power {
            0 => String::new(),
            1 => " * v.clone()".to_string(),
            p => format!(" * v.clone().powi({p})"),
        };
        let _ = writeln!(
            body,
            "    // {}: found {theta:.6} +- {se:.6} (one standard error, benchmark signs).",
            t.name()
        );
        let _ = writeln!(
            body,
            "    let k{i} = m.parameter_with_default(\"{symbol}\", \"{} coefficient, thesis signs ({})\", 0.0);",
            t.name(),
            t.unit()
        );
        fitted.push(format!(
            "Fitted::plain(\"{symbol}\", {:.3e}, false)",
            theta_model.abs().max(1e-6)
        ));
        let force = format!("k{i}{power} * {source}");
        let coordinate_of_equation = format!("parts.{}.clone()", coordinate(t.equation));
        if let Some((tau, _)) = f.time_constant {
            let state = format!("{name}_z{i}");
            let _ = writeln!(
                body,
                "    let tau{i} = m.parameter_with_default(\"{name}_tau{i}\", \"time constant of the lag of {} (s)\", {tau:.6});",
                t.name()
            );
            let _ = writeln!(body, "    m.lower_bound(\"{name}_tau{i}\", 0.0, true);");
            let _ = writeln!(
                body,
                "    let z{i} = m.state(\"{state}\", \"lagged {} torque (N m)\", ({force} - Expr::State(\"{state}\".into())) / tau{i});",
                t.name()
            );
            let _ = writeln!(
                body,
                "    m.force(Force::Generalized {{ name: \"{name}_{i}\".into(), coordinate: {coordinate_of_equation}, expr: z{i} }});"
            );
        } else {
            let _ = writeln!(
                body,
                "    m.force(Force::Generalized {{ name: \"{name}_{i}\".into(), coordinate: {coordinate_of_equation}, expr: {force} }});"
            );
        }
    }
    let mut s = doc;
    s += "\nuse bikedyn_modeler::effects::{BicycleParts, Candidate, Effect, Fitted, Identification, Signature};\n";
    s += "#[allow(unused_imports)]\nuse bikedyn_modeler::expr::{coord, rate, Expr};\nuse bikedyn_modeler::model::{Force, ModelBuilder};\n\n";
    s += "#[allow(unused_variables)]\npub fn apply(m: &mut ModelBuilder, parts: &BicycleParts) {\n";
    s += "    let v = m\n        .model()\n        .forward_speed\n        .clone()\n        .expect(\"bicycle models declare their forward speed before effects\");\n";
    s += &body;
    s += "}\n\n";
    let _ = writeln!(s, "const FITTED: &[Fitted] = &[{}];\n", fitted.join(", "));
    let _ = writeln!(
        s,
        "/// The effect.\npub fn effect() -> Effect {{\n    Effect {{\n        name: \"{name}\",\n        doc: \"generalized forces found by identify beyond the effect library\",\n        apply,\n        identification: Identification::Candidate(Candidate {{\n            fitted: FITTED,\n            held: &[],\n            speed_decay: false,\n            signatures: &[Signature::WeaveDampingAndFrequency],\n            reason: \"found by the dictionary search of identify on measured data\",\n            linear_equivalent: None,\n            own_model: {},\n        }}),\n    }}\n}}",
        found.iter().any(|f| f.time_constant.is_some())
    );
    s
}
