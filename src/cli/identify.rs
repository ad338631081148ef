//! `bikedyn identify`: from the residual of measured runs to the missing
//! effect; prints the summary or JSON, writes the report folder.

use super::args::IdentifyArgs;
use super::ProgressDisplay;
use anyhow::Result;
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
    }
}

/// Plan, say which model runs, then identify with the progress on stderr.
pub fn run_with_progress(request: &IdentifyRequest) -> Result<Outcome> {
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
    if let Some(table) = &a.eigenvalues {
        let o = eigen_table::identify_table(&eigen_table::TableRequest {
            path: table.clone(),
            bike: a.bike.clone(),
            effects: a.effects.clone(),
            corrections: a.corrections,
        })?;
        if let Some(dir) = &a.report {
            eigen_table::write_table_report(&o, dir)?;
        }
        if a.json {
            println!("{}", serde_json::to_string_pretty(&o)?);
        } else {
            println!("{}", eigen_table::table_summary(&o));
        }
        return Ok(true);
    }
    let request = request(a);
    let o = run_with_progress(&request)?;
    if let Some(dir) = &a.report {
        report::write_report(&o, &request, dir)?;
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report::outcome_json(&o))?);
    } else {
        println!("{}", report::summary(&o));
        if let Some(dir) = &a.report {
            println!("report: {}", dir.join("report.md").display());
        }
    }
    Ok(true)
}
