//! `bikedyn report`: the main job on embedded defaults (verify, canonical
//! matrices and self-stable speeds of the built-in bicycles, eigenvalue
//! tables and diagrams, identification of the example set).

use super::text::{canonical_text, stability_json, stability_text};
use super::{load, parse_range};
use anyhow::Result;
use bikedyn::bicycle::BUILT_IN;
use bikedyn::identify::{report, IdentifyRequest};
use bikedyn::report::output;
use bikedyn::report::plot::{plot_continuation, subject, PlotOptions};
use bikedyn::report::staged::{FolderKind, StagedDir};
use bikedyn::runtime::eigen::{critical_speeds, eigen_sweep};
use bikedyn::runtime::verify::VerifyOptions;
use std::path::PathBuf;

/// Run `bikedyn report --out OUT`: the folder is written whole beside its
/// place and moved in at the end, so a kill leaves the earlier report or
/// the new one; it must be new, empty or an earlier `report` folder.
pub fn run(target: PathBuf) -> Result<bool> {
    let staged = StagedDir::new(&target, FolderKind::Report)?;
    let out = staged.path().to_path_buf();
    let mut ok = true;
    for m in bikedyn::models::model_names() {
        let r = bikedyn::models::verify_model(m, &VerifyOptions::default()).expect("known model");
        outln!("verify {m}: {}", if r.passed { "passed" } else { "FAILED" });
        ok &= r.passed;
    }
    let speeds = parse_range("0:10:0.01", "speeds")?;
    for (name, _) in BUILT_IN {
        let b = load(name)?;
        let c = b.canonical()?;
        let crit = critical_speeds(&c, 0.0, 10.0)?;
        outln!("\n{}", stability_text(name, &crit, false));
        outln!("{}", canonical_text(&c));
        let sweep = eigen_sweep(&c, &speeds)?;
        output::save_eigen_sweep_csv(out.join(format!("{name}_eigenvalues.csv")), &sweep)?;
        output::save_eigen_sweep_json(out.join(format!("{name}_eigenvalues.json")), &sweep)?;
        let opts = PlotOptions {
            y_range: Some((-10.0, 10.0)),
            subject: Some(subject(name, Some("canonical form"))),
            ..PlotOptions::default()
        };
        for ext in ["svg", "png"] {
            plot_continuation(
                out.join(format!("{name}_continuation.{ext}")),
                &sweep,
                Some(&crit),
                &opts,
            )?;
        }
        output::save_json(out.join(format!("{name}_stability.json")), &stability_json(name, &crit))?;
    }
    // Close the loop on the committed example set (made by `bikedyn
    // synth` with steer damping hidden): measured eigenvalues on the
    // continuation diagram, the identified effect, before and after.
    let set = PathBuf::from(bikedyn::identify::EXAMPLE_SET);
    let request = IdentifyRequest {
        inputs: vec![set.clone()],
        ..IdentifyRequest::default()
    };
    outln!(
        "\nidentify {} (runs made by `bikedyn synth` with an effect hidden):",
        set.display()
    );
    let o = super::identify::run_with_progress(&request)?;
    let dir = out.join("identify");
    report::write_report(&o, &request, &dir, &PlotOptions::default())?;
    staged.commit()?;
    outln!(
        "wrote tables, plots and the identification report to {}",
        target.display()
    );
    outln!("{}", report::summary(&o));
    outln!("report: {}", target.join("identify/report.md").display());
    Ok(ok)
}
