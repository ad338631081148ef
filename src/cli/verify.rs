//! `bikedyn verify`: every generated derivative against finite differences
//! ([`bikedyn::models::verify_models`]), printed.

use anyhow::Result;
use bikedyn::models::VerifyOptions;

/// Run `bikedyn verify`.
pub fn run(model: Option<String>, states: usize, seed: u64, json: bool) -> Result<bool> {
    let opts = VerifyOptions {
        states,
        seed,
        ..VerifyOptions::default()
    };
    let v = bikedyn::models::verify_models(model.as_deref(), &opts)?;
    if json {
        outln!("{}", serde_json::to_string_pretty(&v.to_json())?);
    } else {
        for r in &v.reports {
            outln!("model {} ({} random states, seed {}):", r.model, r.states, r.seed);
            for q in &r.quantities {
                outln!(
                    "  {:<40} max rel error {:>10.3e}  tolerance {:>8.1e}  {}",
                    q.name,
                    q.max_rel_error,
                    q.tolerance,
                    if q.passed { "ok" } else { "FAIL" }
                );
            }
        }
        outln!(
            "{}",
            if v.passed {
                "verification passed"
            } else {
                "verification FAILED"
            }
        );
    }
    Ok(v.passed)
}
