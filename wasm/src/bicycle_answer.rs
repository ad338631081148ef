//! The `bicycle` job's answer: the bicycle's parameters in both forms,
//! derived geometry, uncertainties, effects, warnings, controller, model
//! and TOML. Its own module because both the requests (`request.rs`) and
//! the explorer's one answer (`explore.rs`) give it.

use bikedyn::bicycle::files::ParameterFile;
use bikedyn::bicycle::{Bicycle, BicycleError};
use bikedyn::runtime::parameters::{BenchmarkParameters, ThesisParameters};
use serde::Serialize;
use std::collections::BTreeMap;

/// The bicycle of `bikedyn bicycle`-like requests: parameters in both
/// forms, derived geometry, uncertainties, effects, warnings, the model the
/// bicycle gets, and its TOML (benchmark form, effects after).
#[derive(Serialize)]
pub(crate) struct BicycleAnswer {
    name: String,
    form: &'static str,
    model: String,
    /// `[symbol, value]` in Meijaard et al. (2007) Table 1's order (SI).
    benchmark: Vec<(&'static str, f64)>,
    /// `[symbol, value]` in the thesis's order (SI).
    thesis: Vec<(&'static str, f64)>,
    effects: BTreeMap<String, f64>,
    uncertainties: BTreeMap<String, f64>,
    warnings: Vec<String>,
    derived_geometry: Vec<GeometryRow>,
    /// The file's `[feedback]` controller (the linear analyses close the
    /// loop with it), if any.
    feedback: Option<FeedbackAnswer>,
    toml: String,
}

/// A `[feedback]` gain schedule as the file gives it: knot speeds (m/s)
/// and each non-zero gain over them (N m/rad, N m s/rad), by its file name
/// (`kTdel_phid`: steer torque from roll rate).
#[derive(Serialize)]
struct FeedbackAnswer {
    speeds: Vec<f64>,
    gains: Vec<(&'static str, Vec<f64>)>,
}

#[derive(Serialize)]
struct GeometryRow {
    symbol: &'static str,
    value: f64,
    unit: &'static str,
    what: &'static str,
}

/// The answer to the `bicycle` job for `b` (with model `model`, or the one
/// the bicycle gets).
pub(crate) fn bicycle_answer(b: &Bicycle, model: Option<&str>) -> Result<BicycleAnswer, BicycleError> {
    let benchmark = b.parameters.to_benchmark()?;
    let thesis = b.thesis()?;
    let mut toml = benchmark.to_toml_string();
    let effects = b.effects_toml();
    if !effects.is_empty() {
        toml.push_str(&format!("\n# Effect parameters of {}:\n{effects}", b.name));
    }
    Ok(BicycleAnswer {
        name: b.name.clone(),
        form: match b.parameters.form() {
            bikedyn::runtime::parameters::Form::Thesis => "thesis",
            bikedyn::runtime::parameters::Form::Benchmark => "benchmark",
        },
        model: b.model(model)?.name.to_string(),
        benchmark: BenchmarkParameters::SYMBOLS
            .iter()
            .map(|s| (*s, benchmark.get(s).unwrap_or(f64::NAN)))
            .collect(),
        thesis: ThesisParameters::SYMBOLS
            .iter()
            .map(|s| (*s, thesis.get(s).unwrap_or(f64::NAN)))
            .collect(),
        effects: b.effects.clone(),
        uncertainties: b.uncertainties.clone(),
        warnings: b.warnings.iter().map(|w| w.to_string()).collect(),
        derived_geometry: b
            .derived_geometry()?
            .rows()
            .into_iter()
            .map(|(symbol, value, unit, what)| GeometryRow {
                symbol,
                value,
                unit,
                what,
            })
            .collect(),
        feedback: b.feedback.as_ref().map(|f| FeedbackAnswer {
            speeds: f.speeds().to_vec(),
            gains: bikedyn::runtime::feedback::GAIN_NAMES
                .iter()
                .enumerate()
                .map(|(j, name)| (*name, f.gains().iter().map(|k| k[(j / 4, j % 4)]).collect::<Vec<f64>>()))
                .filter(|(_, values)| values.iter().any(|&x| x != 0.0))
                .collect(),
        }),
        toml,
    })
}
