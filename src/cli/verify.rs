//! `bikedyn verify`: every generated derivative against finite differences.

use anyhow::{Context, Result};
use bikedyn::runtime::verify::VerifyOptions;

/// Run `bikedyn verify`.
pub fn run(model: Option<String>, states: usize, seed: u64, json: bool) -> Result<bool> {
    let names: Vec<&str> = match &model {
        Some(m) => vec![m.as_str()],
        None => bikedyn::models::model_names(),
    };
    let opts = VerifyOptions {
        states,
        seed,
        ..VerifyOptions::default()
    };
    let mut reports = Vec::new();
    for n in names {
        let r = bikedyn::models::verify_model(n, &opts).with_context(|| {
            format!(
                "unknown model `{n}` (models: {})",
                bikedyn::models::model_names().join(", ")
            )
        })?;
        reports.push(r);
    }
    let passed = reports.iter().all(|r| r.passed);
    if json {
        let quantities: Vec<_> = reports
            .iter()
            .flat_map(|r| r.quantities.iter().map(move |q| serde_json::json!({
                "model": r.model, "name": q.name, "max_rel_error": q.max_rel_error, "tolerance": q.tolerance, "passed": q.passed
            })))
            .collect();
        outln!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({"passed": passed, "quantities": quantities}))?
        );
    } else {
        for r in &reports {
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
            if passed {
                "verification passed"
            } else {
                "verification FAILED"
            }
        );
    }
    Ok(passed)
}
