//! `bikedyn eig`: eigenvalues and modes over forward speed (table, CSV or
//! JSON, streamed when long) and the continuation diagram. The job is
//! [`bikedyn::eigen`]; this checks the paths, calls it and prints, writes
//! or plots its result.

use super::args::{BikeArg, Format, OutputArgs, PlotArgs};
use super::{check_outputs, emit, load, plot_options, range_spec, MAX_STREAMED_POINTS, MAX_TABLE_ROWS};
use anyhow::{bail, Result};
use bikedyn::eigen::{eigen_sweep, EigenJob, EigenOptions, Speeds};
use bikedyn::report::output;
use bikedyn::report::plot::locus::{plot_mode_shapes, plot_root_locus};
use bikedyn::report::plot::{plot_continuation, subject};
use std::path::PathBuf;

/// The figures `eig` draws and their options.
pub struct Plots {
    /// Continuation diagram (`--plot`).
    pub continuation: Option<PathBuf>,
    /// Root locus (`--plot-root-locus`).
    pub root_locus: Option<PathBuf>,
    /// Mode shapes at `speed` (`--plot-mode-shapes`).
    pub mode_shapes: Option<PathBuf>,
    /// `--speed` of the mode shapes.
    pub speed: Option<f64>,
    /// Size, resolution and limits.
    pub args: PlotArgs,
}

/// Run `bikedyn eig`.
pub fn run(bike: BikeArg, speeds: String, out: OutputArgs, plots: Plots) -> Result<bool> {
    let BikeArg { spec: bike, model } = bike;
    // With a figure asked for, the table is written only when asked for
    // too (`--format`, `--json` or `--output`): a plot's speeds are often
    // thousands of rows nobody wants on the terminal.
    let plotting = plots.continuation.is_some() || plots.root_locus.is_some() || plots.mode_shapes.is_some();
    let write_table = !plotting || out.asked_for();
    let format = out.format();
    let out = out.output;
    // Every output and plot option is checked before any work.
    let mut opts = plot_options(&plots.args, None)?;
    super::Paths::new()
        .bike("--bike", Some(&bike))
        .file("--output", out.as_deref())
        .file("--plot", plots.continuation.as_deref())
        .file("--plot-root-locus", plots.root_locus.as_deref())
        .file("--plot-mode-shapes", plots.mode_shapes.as_deref())
        .check()?;
    check_outputs(out.as_deref(), plots.continuation.as_deref())?;
    check_outputs(None, plots.root_locus.as_deref())?;
    check_outputs(None, plots.mode_shapes.as_deref())?;
    if let Some(v) = plots.speed {
        if !v.is_finite() {
            bail!("--speed must be a finite speed (m/s), found {v}");
        }
        if plots.mode_shapes.is_none() {
            bail!("--speed is the speed of --plot-mode-shapes FILE: give that too (the table's speeds are --speeds)");
        }
    }
    let b = load(&bike)?;
    let limit = match format {
        Format::Table => MAX_TABLE_ROWS,
        Format::Csv | Format::Json => MAX_STREAMED_POINTS,
    };
    let (start, step, count) = range_spec(&speeds, "--speeds", limit).map_err(|e| match format {
        Format::Table => {
            anyhow::anyhow!(
                "{e}; a table holds every row, --format csv or json streams up to {MAX_STREAMED_POINTS} points"
            )
        }
        _ => e,
    })?;
    let speeds = Speeds::Range { start, step, count };
    let options = EigenOptions {
        model: model.clone(),
        speeds: speeds.clone(),
        // The eigenvalues' standard deviations from the file's +/- values
        // (first order, exact derivatives), in CSV and JSON.
        standard_deviations: write_table && !matches!(format, Format::Table),
        critical_speeds: false,
    };
    let job = EigenJob::new(&b, &options)?;
    eprintln!("model: {}", job.model);
    opts.subject = Some(subject(&b.name, Some(job.model)));
    if let Some(why) = &job.standard_deviations_missing {
        eprintln!("note: no standard deviations of the eigenvalues from the file's +/- values: {why}");
    }
    if !b.uncertainties.is_empty() && matches!(format, Format::Table) && write_table {
        eprintln!("note: the eigenvalues' standard deviations from the file's +/- values are in --format csv (re_sd_k, im_sd_k) and json (standard_deviations)");
    }
    let write = |w: &mut dyn std::io::Write| -> Result<(), output::BoxError> {
        match format {
            Format::Csv => {
                let mut wr = csv::Writer::from_writer(w);
                wr.write_record(output::eigen_csv_header(
                    job.extra_eigenvalues,
                    job.standard_deviations(),
                ))?;
                for p in job.points() {
                    let p = p?;
                    wr.write_record(output::eigen_point_csv_row_with(
                        &p.point,
                        p.standard_deviations.as_deref(),
                    ))?;
                }
                wr.flush()?;
            }
            _ => {
                // One speed's object per line, as each is computed.
                w.write_all(b"[")?;
                for (i, p) in job.points().enumerate() {
                    w.write_all(if i == 0 { b"\n  " } else { b",\n  " })?;
                    serde_json::to_writer(&mut *w, &p?)?;
                }
                w.write_all(b"\n]\n")?;
            }
        }
        Ok(())
    };
    match format {
        _ if !write_table => {
            eprintln!("table not printed (a figure was asked for): add --format table|csv|json or --output FILE for it")
        }
        Format::Table => {
            let report = job.report()?;
            emit(&output::format_eigen_table(&report.sweep()), &out)?;
        }
        Format::Csv | Format::Json => match &out {
            Some(p) => output::write_atomic(p, |w| write(w))?,
            None => {
                let mut w = std::io::BufWriter::new(std::io::stdout().lock());
                write(&mut w).map_err(super::stdout_error_of)?;
                std::io::Write::flush(&mut w).map_err(super::stdout_error)?;
            }
        },
    }
    if plots.continuation.is_some() || plots.root_locus.is_some() {
        // A diagram needs no more than 20,001 points: longer ranges are
        // plotted at evenly spaced speeds over the same interval.
        const PLOT_POINTS: usize = 20_001;
        let last = speeds.at(count - 1);
        let plotted = if count <= PLOT_POINTS {
            speeds
        } else {
            Speeds::List(
                (0..PLOT_POINTS)
                    .map(|k| start + (last - start) * k as f64 / (PLOT_POINTS - 1) as f64)
                    .collect(),
            )
        };
        let report = eigen_sweep(
            &b,
            &EigenOptions {
                model: model.clone(),
                speeds: plotted,
                standard_deviations: false,
                critical_speeds: plots.continuation.is_some(),
            },
        )?;
        let sweep = report.sweep();
        if let Some(p) = &plots.continuation {
            plot_continuation(p, &sweep, report.critical.as_ref(), &opts)?;
            eprintln!("wrote {}", p.display());
        }
        if let Some(p) = &plots.root_locus {
            plot_root_locus(p, &sweep, &opts)?;
            eprintln!("wrote {}", p.display());
        }
    }
    if let (Some(p), Some(v)) = (&plots.mode_shapes, plots.speed) {
        let at = eigen_sweep(
            &b,
            &EigenOptions {
                model,
                speeds: Speeds::List(vec![v]),
                standard_deviations: false,
                critical_speeds: false,
            },
        )?;
        plot_mode_shapes(p, &at.points[0].point, &opts)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(true)
}
