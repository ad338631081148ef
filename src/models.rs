//! Dispatch over the generated models by name (for the CLI and the bench).

use crate::generated::{ThesisWhipple, WhippleOffset};
use bikedyn_runtime::linearize::parameter_vector;
use bikedyn_runtime::parameters::{BenchmarkParameters, ThesisParameters};
use bikedyn_runtime::verify::{verify, VerifyOptions, VerifyReport};
use bikedyn_runtime::MultibodyModel;

/// Names of the generated models.
pub const MODELS: &[&str] = &[ThesisWhipple::NAME, WhippleOffset::NAME];

/// Default parameter vector of a model: the thesis bicycle for the thesis
/// model, the benchmark bicycle (which needs the offset) for the variant, at
/// a forward speed of 4.5 m/s.
pub fn default_parameters<M: MultibodyModel>() -> Vec<f64> {
    let p = if M::PARAMETERS.contains(&"d4") {
        BenchmarkParameters::benchmark_bicycle()
            .to_thesis()
            .expect("the benchmark bicycle converts")
    } else {
        ThesisParameters::thesis_bicycle()
    };
    parameter_vector::<M>(|s| p.get(s), 4.5).expect("built-in bicycles define every model parameter")
}

/// Verify one model by name; `None` for an unknown name.
pub fn verify_model(name: &str, opts: &VerifyOptions) -> Option<VerifyReport> {
    match name {
        "thesis_whipple" => Some(verify::<ThesisWhipple>(&default_parameters::<ThesisWhipple>(), opts)),
        "whipple_offset" => Some(verify::<WhippleOffset>(&default_parameters::<WhippleOffset>(), opts)),
        _ => None,
    }
}
