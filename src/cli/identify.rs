//! `bikedyn identify`: from the residual of measured runs to the missing
//! effect; prints the summary or JSON, writes the report folder.

use super::args::IdentifyArgs;
use super::ProgressDisplay;
use anyhow::Result;
use bikedyn::fit::BikeRequired;
use bikedyn::identify::{eigen_table, plan, report, run_builtin_plan, IdentifyRequest, Outcome};

/// The library's request from the command line.
pub fn request(a: &IdentifyArgs) -> IdentifyRequest {
    IdentifyRequest {
        inputs: a.inputs.clone(),
        calibration: a.calibration.clone(),
        bike: a.bike.clone(),
        effects: a.effects.clone(),
        folds: a.folds,
        corrections: a.corrections,
        discover: !a.no_discover,
        max_fits_per_step: a.max_fits_per_step,
        family_wise_bar: a.family_wise_bar,
    }
}

/// Plan, say which model runs, then identify with the progress on stderr.
fn run_with_progress(request: &IdentifyRequest) -> Result<Outcome> {
    let plan = plan(request)?;
    eprintln!(
        "identify: model {} (driven twin {})",
        plan.model.name, plan.driven_model.name
    );
    let display = ProgressDisplay::new();
    Ok(run_builtin_plan(&plan, request, &|p| display.show(p))?)
}

/// Run `bikedyn identify`.
pub fn run(a: &IdentifyArgs) -> Result<bool> {
    // A report folder that cannot be written fails now, not after the
    // computation.
    let plot_opts = super::plot_options(&a.plot_args, None)?;
    let mut paths = super::Paths::new()
        .input("--eigenvalues", a.eigenvalues.as_deref())
        .input("--calibration", a.calibration.as_deref())
        .bike("--bike", a.bike.as_deref())
        .folder("--report", a.report.as_deref());
    for i in &a.inputs {
        paths = paths.input("INPUT", Some(i));
    }
    paths.check()?;
    if let Some(dir) = &a.report {
        bikedyn::report::staged::StagedDir::check(dir, bikedyn::report::staged::FolderKind::IdentifyReport)?;
    }
    if let Some(table) = &a.eigenvalues {
        // A table of someone's measured eigenvalues is no thesis-format run:
        // its bicycle must be named.
        let bike = a.bike.clone().ok_or_else(|| BikeRequired {
            inputs: vec![table.clone()],
        })?;
        let o = eigen_table::identify_table(&eigen_table::TableRequest {
            path: table.clone(),
            bike,
            effects: a.effects.clone(),
            corrections: a.corrections,
            discover: !a.no_discover,
        })?;
        if let Some(dir) = &a.report {
            eigen_table::write_table_report(&o, dir)?;
        }
        if a.json {
            outln!("{}", serde_json::to_string_pretty(&o)?);
        } else {
            outln!("{}", eigen_table::table_summary(&o));
        }
        return Ok(true);
    }
    let request = request(a);
    let o = run_with_progress(&request)?;
    if o.identification.folds != request.folds {
        eprintln!(
            "note: --folds {}: cross-validation used {} folds (each fold holds out whole runs or logs, and there are {} kicks in {} runs or logs)",
            request.folds,
            o.identification.folds,
            o.segments.len(),
            o.segments.iter().map(|s| s.run.as_str()).collect::<std::collections::BTreeSet<_>>().len()
        );
    }
    if let Some(dir) = &a.report {
        report::write_report(&o, &request, dir, &plot_opts)?;
    }
    if a.json {
        outln!("{}", serde_json::to_string_pretty(&report::result(&o))?);
    } else {
        outln!("{}", report::summary(&o));
        if let Some(dir) = &a.report {
            outln!("report: {}", dir.join("report.md").display());
        }
    }
    // As `fit`: exit status 1 when a run or log could not be processed (the
    // summary and the JSON say why; kicks that are no weave are listed too,
    // but they are the data's, not a failure).
    Ok(o.failed_inputs.is_empty())
}
