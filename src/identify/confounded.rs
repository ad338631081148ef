//! The console's account of candidates the data cannot tell apart
//! (`identify::confounding` in the runtime computes it).

use super::Outcome;
use bikedyn_runtime::identify::confounding::CONFOUNDED;
use bikedyn_runtime::registry::ModelRegistry;

/// One sentence per pair of candidates the data cannot tell apart: both,
/// how alike they are, and the kicks that would separate them.
pub fn confounding_lines<R: ModelRegistry>(o: &Outcome<R>) -> Vec<String> {
    let id = &o.identification;
    let mut out = Vec::new();
    for step in &id.steps {
        for c in step.confounded.iter().filter(|c| c.correlation >= CONFOUNDED) {
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
                                format!("{} = {:.4} +- {:.4} {} (95 %)", p.symbol, v, 1.96 * se, p.unit)
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
            out.push(format!(
                "not separable: {} ({}) and {} ({}) move the responses alike (correlation {:.3} in the Fisher information); {separate}",
                c.chosen,
                values(&c.chosen),
                c.rival,
                values(&c.rival),
                c.correlation
            ));
        }
    }
    out
}
