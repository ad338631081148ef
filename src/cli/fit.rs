//! `bikedyn fit`: measured weave eigenvalues from raw logs; prints the table
//! or JSON, writes plots.

use super::args::FitArgs;
use super::ProgressDisplay;
use anyhow::{bail, Result};
use bikedyn::fit::{calibration_text, kick_json, kicks_table, plots, residuals, run_fit, FitOptions};
use bikedyn::report::experiment::compare;
use bikedyn::runtime::eigen::LinearBicycle;
use bikedyn::runtime::experiment::angles::AngleMethod;
use serde_json::Value;

/// The library's options from the command line.
pub fn options(args: &FitArgs) -> Result<FitOptions> {
    let angles = match args.angles.as_str() {
        "direct" => AngleMethod::Direct,
        "thesis" => AngleMethod::Thesis,
        other => bail!("--angles {other}: expected direct or thesis"),
    };
    Ok(FitOptions {
        inputs: args.inputs.clone(),
        calibration: args.calibration.clone(),
        bike: args.bike.clone(),
        angles,
        nominal_clock: args.nominal_clock,
    })
}

/// Run `bikedyn fit`: `Ok(false)` when some run was skipped (its error is
/// on stderr; the others are output).
pub fn run(args: &FitArgs) -> Result<bool> {
    let opts = options(args)?;
    let out = {
        // The bar is cleared before anything is printed.
        let display = ProgressDisplay::new();
        run_fit(&opts, &|p| display.show(p))?
    };
    for e in &out.errors {
        eprintln!("skipped: {e}");
    }
    for r in &out.reports {
        for n in &r.notes {
            eprintln!("{}: {n}", r.run.display());
        }
        for g in &r.gaps {
            eprintln!("{g}");
        }
        if r.renormalised.iter().any(|&n| n > 0) {
            eprintln!(
                "{}: normalised {} frame and {} handlebar quaternions",
                r.run.display(),
                r.renormalised[0],
                r.renormalised[1]
            );
        }
    }
    if args.json {
        eprint!("{}", calibration_text(&out));
        if let Some(l) = &out.linear {
            eprintln!("prediction model: {}", l.model);
        }
        let list: Vec<Value> = out
            .reports
            .iter()
            .flat_map(|r| r.kicks.iter())
            .map(|k| kick_json(k, out.linear.as_ref().map(|l| l as &dyn LinearBicycle)))
            .collect();
        outln!("{}", serde_json::to_string_pretty(&list)?);
    } else {
        out!("{}", calibration_text(&out));
        out!("{}", kicks_table(&out));
        let rows = residuals(&out);
        if !rows.is_empty() {
            let model = out.linear.as_ref().map_or("", |l| l.model);
            outln!("\nmeasured against predicted weave eigenvalue (model {model}; z = difference / standard error)");
            out!("{}", compare::format_residuals(&rows));
        }
    }
    if let Some(dir) = &args.plot {
        plots(&out, dir)?;
    }
    Ok(out.errors.is_empty())
}
