//! `bikedyn eig`: eigenvalues and modes over forward speed (table, CSV or
//! JSON, streamed when long) and the continuation diagram.

use super::args::{BikeArg, Format, OutputArgs, PlotArgs};
use super::{check_outputs, emit, load, plot_options, range_spec, MAX_STREAMED_POINTS, MAX_TABLE_ROWS};
use anyhow::{bail, Result};
use bikedyn::report::output;
use bikedyn::report::plot::locus::{plot_mode_shapes, plot_root_locus};
use bikedyn::report::plot::{plot_continuation, subject};
use bikedyn::runtime::eigen::{critical_speeds_of, eigen_sweep_of, LinearBicycle};
use bikedyn::sensitivity::EigenvalueSpread;
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
    let (start, step, n) = range_spec(&speeds, "--speeds", limit).map_err(|e| match format {
        Format::Table => {
            anyhow::anyhow!(
                "{e}; a table holds every row, --format csv or json streams up to {MAX_STREAMED_POINTS} points"
            )
        }
        _ => e,
    })?;
    let lin = b.linear_with(model.as_deref())?;
    eprintln!("model: {}", lin.model);
    opts.subject = Some(subject(&b.name, Some(lin.model)));
    let c: &dyn LinearBicycle = &lin;
    // The eigenvalues' standard deviations from the file's +/- values
    // (first order, exact derivatives), in CSV and JSON.
    let spread = if b.uncertainties.is_empty() || matches!(format, Format::Table) || !write_table {
        None
    } else {
        match EigenvalueSpread::of(&b, model.as_deref()) {
            Ok(s) => s,
            Err(e) => {
                eprintln!("note: no standard deviations of the eigenvalues from the file's +/- values: {e}");
                None
            }
        }
    };
    let spread_fn = spread
        .as_ref()
        .map(|s| move |v: f64, z: &[[f64; 2]]| s.of_eigenvalues(v, z));
    let spread_arg: Option<output::EigenSpread<'_>> = spread_fn.as_ref().map(|f| f as output::EigenSpread<'_>);
    if !b.uncertainties.is_empty() && matches!(format, Format::Table) && write_table {
        eprintln!("note: the eigenvalues' standard deviations from the file's +/- values are in --format csv (re_sd_k, im_sd_k) and json (standard_deviations)");
    }
    let speed = |k: usize| start + k as f64 * step;
    let stream = |fmt: output::StreamFormat| -> Result<()> {
        match &out {
            Some(p) => output::write_atomic(p, |w| output::stream_eigen_sweep_with(c, n, speed, fmt, w, spread_arg))?,
            None => {
                let mut w = std::io::BufWriter::new(std::io::stdout().lock());
                output::stream_eigen_sweep_with(c, n, speed, fmt, &mut w, spread_arg)
                    .map_err(super::stdout_error_of)?;
                std::io::Write::flush(&mut w).map_err(super::stdout_error)?;
            }
        }
        Ok(())
    };
    match format {
        _ if !write_table => {
            eprintln!("table not printed (a figure was asked for): add --format table|csv|json or --output FILE for it")
        }
        Format::Table => {
            let speeds: Vec<f64> = (0..n).map(speed).collect();
            emit(&output::format_eigen_table(&eigen_sweep_of(c, &speeds)?), &out)?;
        }
        Format::Csv => stream(output::StreamFormat::Csv)?,
        Format::Json => stream(output::StreamFormat::Json)?,
    }
    if plots.continuation.is_some() || plots.root_locus.is_some() {
        // A diagram needs no more than 20,001 points: longer ranges are
        // plotted at evenly spaced speeds over the same interval.
        const PLOT_POINTS: usize = 20_001;
        let last = speed(n - 1);
        let speeds: Vec<f64> = if n <= PLOT_POINTS {
            (0..n).map(speed).collect()
        } else {
            (0..PLOT_POINTS)
                .map(|k| start + (last - start) * k as f64 / (PLOT_POINTS - 1) as f64)
                .collect()
        };
        let sweep = eigen_sweep_of(c, &speeds)?;
        if let Some(p) = &plots.continuation {
            let vmax = last.max(start + 1e-9);
            let crit = critical_speeds_of(c, start, vmax).ok();
            plot_continuation(p, &sweep, crit.as_ref(), &opts)?;
            eprintln!("wrote {}", p.display());
        }
        if let Some(p) = &plots.root_locus {
            plot_root_locus(p, &sweep, &opts)?;
            eprintln!("wrote {}", p.display());
        }
    }
    if let (Some(p), Some(v)) = (&plots.mode_shapes, plots.speed) {
        let at = eigen_sweep_of(c, &[v])?;
        plot_mode_shapes(p, &at.points[0], &opts)?;
        eprintln!("wrote {}", p.display());
    }
    Ok(true)
}
