//! The summary and the report folder of an identification from a table.

use super::super::IdentifyError;
use super::TableOutcome;
use crate::identify::discovery::DiscoveryOutcome;
use std::path::Path;

/// The summary printed by `identify --eigenvalues`.
pub fn table_summary(o: &TableOutcome) -> String {
    let mut s = format!(
        "eigenvalue table: {} speeds from {}; model {}\n",
        o.points.len(),
        o.table.display(),
        o.driven_model
    );
    s += &format!(
        "selected: {}\n",
        if o.selected.is_empty() {
            "no effect warranted".to_string()
        } else {
            o.selected.join(" + ")
        }
    );
    let vals: Vec<String> = o
        .parameters
        .iter()
        .map(|(k, e)| format!("{k} = {:.4} +- {:.4} {}", e.value, e.high - e.value, e.unit))
        .collect();
    s += &format!(
        "parameters (+- 95 % interval): {}\n",
        if vals.is_empty() { "-".into() } else { vals.join(", ") }
    );
    s += &format!(
        "weave eigenvalue RMS {:.3} -> {:.3} 1/s (leave one speed out: {:.3})",
        o.eigen_rms_before, o.eigen_rms_after, o.eigen_rms_held_out
    );
    if let Some(r) = &o.remaining {
        s += &format!("\n{}", super::super::remaining::remaining_sentence(r, "rows"));
    }
    if let Some(d) = &o.discovery {
        s += &format!(
            "\n{}",
            crate::identify::discovery::table_sentence(d, o.eigen_rms_before)
        );
    }
    for (name, why) in &o.not_tried {
        s += &format!("\nnot tried: {name}: {why}");
    }
    s
}

/// Write `report.json` (the outcome) and `report.md` (summary, candidates
/// at every step, per-speed table) into `dir`.
pub fn write_table_report(o: &TableOutcome, dir: &Path) -> Result<(), IdentifyError> {
    use bikedyn_report::output::{save_json, write_string_atomic};
    use bikedyn_report::staged::{FolderKind, StagedDir};
    use std::fmt::Write as _;
    // Written beside `dir` and moved into place at the end (see
    // `bikedyn_report::staged`).
    let staged = StagedDir::new(dir, FolderKind::IdentifyReport)?;
    let out = staged.path();
    save_json(
        out.join("report.json"),
        &serde_json::to_value(o).map_err(|e| IdentifyError::EigenTable {
            path: o.table.clone(),
            line: 0,
            message: e.to_string(),
        })?,
    )?;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Identification from a measured eigenvalue table\n\n```\n{}\n```\n",
        table_summary(o)
    );
    let _ = writeln!(s, "## Candidates\n\n| step | candidate | fitted values (+- standard error) | BIC change | leave-one-speed-out error | verdict |\n|---|---|---|---|---|---|");
    for t in &o.trials {
        let vals: Vec<String> = t
            .values
            .iter()
            .map(|(k, (v, se))| format!("{k} = {v:.4} +- {se:.4}"))
            .collect();
        let _ = writeln!(
            s,
            "| {} | `{}` | {} | {:+.1} | {:.4} | {} |",
            t.step,
            t.name,
            vals.join(", "),
            t.bic_change,
            t.cv,
            crate::identify::words::verdict_text(&t.verdict)
        );
    }
    if let Some(DiscoveryOutcome::Ran(d)) = &o.discovery {
        s += &crate::identify::discovery::trials_markdown(d);
    }
    let _ = writeln!(s, "\n## Per speed\n\n| line | speed (m/s) | measured | predicted before | predicted after |\n|---|---|---|---|---|");
    let c = |z: Option<[f64; 2]>| z.map_or("-".to_string(), |z| format!("{:.3}{:+.3}i", z[0], z[1]));
    for (i, p) in o.points.iter().enumerate() {
        let _ = writeln!(
            s,
            "| {} | {:.2} | {} | {} | {} |",
            p.line,
            p.speed,
            c(Some(p.eigenvalue)),
            c(o.predicted_before[i]),
            c(o.predicted_after[i])
        );
    }
    if let Some(DiscoveryOutcome::Ran(d)) = &o.discovery {
        if !d.discovery.terms.is_empty() {
            match crate::identify::discovery::effect_file("discovered", &d.discovery.terms) {
                Ok(file) => {
                    let _ = writeln!(
                        s,
                        "\nThe discovered terms are written as an effect file in the modeler's form: `discovered.rs` (for `modeler/src/effects/` or a crate of your own)."
                    );
                    write_string_atomic(out.join("discovered.rs"), &file)?;
                }
                Err(e) => {
                    let _ = writeln!(s, "\nNo effect file was written: {e}.");
                }
            }
        }
    }
    write_string_atomic(out.join("report.md"), &s)?;
    staged.commit()?;
    Ok(())
}
