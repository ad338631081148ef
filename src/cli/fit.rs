//! `bikedyn fit`: measured weave eigenvalues from raw logs; prints the table
//! or JSON, writes plots.

use super::args::FitArgs;
use super::ProgressDisplay;
use anyhow::{bail, Result};
use bikedyn::fit::{
    calibration_text, kicks_table, plots, refused_text, residuals, run_fit, speed_form_text, FitOptions,
};
use bikedyn::fit::{AngleMethod, KickRecord, LinearBicycle, STEER_AXIS_APART};
use bikedyn::report::experiment::compare;

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
    let mut plot_opts = super::plot_options(&args.plot_args, None)?;
    let opts = options(args)?;
    let mut paths = super::Paths::new()
        .input("--calibration", args.calibration.as_deref())
        .bike("--bike", args.bike.as_deref())
        .folder("--plot", args.plot.as_deref());
    for i in &args.inputs {
        paths = paths.input("INPUT", Some(i));
    }
    paths.check()?;
    if let Some(dir) = &args.plot {
        // Before the computation, as `identify --report`.
        bikedyn::report::staged::StagedDir::check(dir, bikedyn::report::staged::FolderKind::FitPlots)?;
    }
    let out = {
        // The bar is cleared before anything is printed.
        let display = ProgressDisplay::new();
        run_fit(&opts, &|p| display.show(p))?
    };
    // The figures name the bicycle (given, or the thesis default).
    plot_opts.subject = Some(bikedyn::report::plot::subject(&out.bike, None));
    for w in &out.warnings {
        eprintln!("warning: {w}");
    }
    for e in &out.errors {
        eprintln!("skipped: {e}");
    }
    for r in &out.reports {
        // A steer axis apart is among the warnings already.
        for n in r.notes.iter().filter(|n| !n.starts_with(STEER_AXIS_APART)) {
            eprintln!("{}: {n}", r.run.display());
        }
        show_gaps(&r.gaps);
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
        eprintln!("prediction model: {}", out.linear.model);
        let list: Vec<KickRecord> = out
            .reports
            .iter()
            .flat_map(|r| r.kicks.iter())
            .map(|k| KickRecord::of(k, &out.linear as &dyn LinearBicycle))
            .collect();
        outln!("{}", serde_json::to_string_pretty(&list)?);
    } else {
        out!("{}", calibration_text(&out));
        out!("{}", kicks_table(&out));
        // The fits that are no measured weave eigenvalue, and why.
        out!("{}", refused_text(&out));
        out!("{}", speed_form_text(&out));
        let rows = residuals(&out);
        if !rows.is_empty() {
            let model = out.linear.model;
            outln!("\nmeasured against predicted weave eigenvalue (model {model}; z = difference / standard error)");
            out!("{}", compare::format_residuals(&rows));
        }
    }
    if let Some(dir) = &args.plot {
        plots(&out, dir, &plot_opts)?;
    }
    Ok(out.errors.is_empty())
}

/// The gaps of a run, a few per file: a wrong nominal rate in run.toml
/// makes every sample a "gap" (1,213 lines for one run), which says less
/// than one line with the likely cause.
fn show_gaps(gaps: &[String]) {
    const SHOWN: usize = 3;
    let mut files: Vec<(&str, Vec<&String>)> = Vec::new();
    for g in gaps {
        // "FILE:LINE: gap ..."; a path may hold colons, the line may not.
        let file = g.rsplitn(3, ':').nth(2).unwrap_or(g);
        match files.iter_mut().find(|(f, _)| *f == file) {
            Some((_, list)) => list.push(g),
            None => files.push((file, vec![g])),
        }
    }
    for (file, list) in files {
        for g in list.iter().take(SHOWN) {
            eprintln!("{g}");
        }
        if list.len() > SHOWN {
            eprintln!(
                "{file}: {} more gaps ({} in all); if the sensor recorded without interruption, the nominal rate in run.toml ([imu] or [speed_switch] rate_hz) does not match its time stamps",
                list.len() - SHOWN,
                list.len()
            );
        }
    }
}
