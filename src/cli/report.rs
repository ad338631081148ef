//! `bikedyn report`: the main job on embedded defaults
//! ([`bikedyn::main_report`]), printed.

use super::progress::ProgressDisplay;
use super::text::{canonical_text, stability_text};
use anyhow::Result;
use bikedyn::identify::report;
use bikedyn::main_report::{main_report, MainReportOptions};
use std::path::PathBuf;

/// Run `bikedyn report --out OUT`: the folder is written whole beside its
/// place and moved in at the end, so a kill leaves the earlier report or
/// the new one; it must be new, empty or an earlier `report` folder.
pub fn run(target: PathBuf) -> Result<bool> {
    let display = ProgressDisplay::new();
    let r = main_report(&MainReportOptions::new(&target), &|p| display.show(p))?;
    drop(display);
    for (m, passed) in &r.verified {
        outln!("verify {m}: {}", if *passed { "passed" } else { "FAILED" });
    }
    for b in &r.bicycles {
        outln!("\n{}", stability_text(b.name, &b.critical, false));
        outln!("{}", canonical_text(&b.canonical));
    }
    if let Some(id) = &r.identification {
        outln!(
            "\nidentify {} (runs made by `bikedyn synth` with an effect hidden):",
            bikedyn::identify::EXAMPLE_SET
        );
        outln!(
            "wrote tables, plots and the identification report to {}",
            r.folder.display()
        );
        outln!("{}", report::summary(&id.outcome));
        outln!("report: {}", id.folder.join("report.md").display());
    }
    Ok(r.verified())
}
