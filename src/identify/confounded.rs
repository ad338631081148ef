//! The console's account of candidates the data cannot tell apart
//! (`identify::confounding` in the runtime computes it).

use super::Outcome;
use bikedyn_runtime::identify::confounding::CONFOUNDED;
use bikedyn_runtime::identify::PLAUSIBLE_PRIOR_SDS;
use bikedyn_runtime::registry::ModelRegistry;

/// One sentence per pair of candidates the data cannot tell apart: both,
/// how alike they are, and the kicks that would separate them.
pub fn confounding_lines<R: ModelRegistry>(o: &Outcome<R>) -> Vec<String> {
    let id = &o.identification;
    let mut out = Vec::new();
    for step in &id.steps {
        for c in step.confounded.iter().filter(|c| c.not_separated()) {
            // The trial's own parameters (those beyond the step's base),
            // each correction with its distance from its measured value.
            let values = |name: &str| {
                step.trials
                    .iter()
                    .find(|t| t.name == name)
                    .and_then(|t| t.fit.as_ref())
                    .map(|f| {
                        let own = f.parameters.len().saturating_sub(
                            o.candidates
                                .iter()
                                .find(|x| x.name == name)
                                .map_or(0, |x| x.parameters.len()),
                        );
                        f.parameters
                            .iter()
                            .zip(f.values.iter().zip(&f.stderr))
                            .skip(own)
                            .map(|(p, (v, se))| {
                                let prior = o
                                    .stated_prior(&p.symbol)
                                    .map(|(mean, sd)| format!(", {:+.1} prior sd", (v - mean) / sd))
                                    .unwrap_or_default();
                                format!("{} = {:.4} +- {:.4} {} (95 %{prior})", p.symbol, v, 1.96 * se, p.unit)
                            })
                            .collect::<Vec<_>>()
                            .join(", ")
                    })
                    .unwrap_or_default()
            };
            let better: Vec<String> = c
                .designs
                .iter()
                .filter(|d| d.correlation < 0.8 * c.correlation.min(1.0))
                .take(3)
                .map(|d| format!("{} (correlation {:.2})", d.description, d.correlation))
                .collect();
            let separate = if better.is_empty() {
                "none of the kicks tried (other speeds, three times the amplitude, a steer-torque kick) would separate them".to_string()
            } else {
                format!("data that would separate them: {}", better.join("; "))
            };
            // Why they are not separated: the information (their
            // estimates correlate) or the held-out runs (both pass and
            // neither predicts consistently better), or both.
            let mut why = Vec::new();
            if c.correlation >= CONFOUNDED {
                why.push(format!(
                    "move the responses alike (correlation {:.3} in the Fisher information)",
                    c.correlation
                ));
            }
            if let Some(h) = c.held_out_gain.filter(|h| h.within_scatter()) {
                let both = if c.beyond_priors {
                    format!(
                        "both lie beyond {PLAUSIBLE_PRIOR_SDS} prior standard deviations of their measured values, both were cross-validated,"
                    )
                } else {
                    "both pass cross-validation".to_string()
                };
                why.push(format!(
                    "{both} and neither predicts the held-out runs consistently better (the rival's paired gain {:+.4} +- {:.4}, 1 SE; correlation {:.3})",
                    h.gain, h.stderr, c.correlation
                ));
                if c.beyond_priors {
                    why.push(
                        "so these runs call for a correction beyond its measurement without telling which (weigh or swing the parts again)"
                            .to_string(),
                    );
                }
            }
            out.push(format!(
                "not separable: {} ({}) and {} ({}) {}; {separate}",
                c.chosen,
                values(&c.chosen),
                c.rival,
                values(&c.rival),
                why.join(", and ")
            ));
        }
    }
    out
}
