//! The commands of the binary: each parses its arguments into the
//! library's options, calls the library and prints. Shared here: range
//! parsing with its limits, bicycle loading with warnings, output to a file
//! or standard output, and the progress display.

pub mod args;
pub mod bench;
mod bench_generated;
mod bench_simulate;
pub mod bode;
pub mod canonical;
pub mod eig;
pub mod fit;
pub mod identify;
pub mod models;
mod outputs;
pub mod params;
mod progress;
pub mod report;
pub mod sensitivity;
pub mod serve;
pub mod simulate;
pub mod stability;
pub mod sweep;
pub mod synth;
pub mod text;
pub mod verify;

pub use outputs::Paths;
pub use progress::ProgressDisplay;

use anyhow::{bail, Context, Result};
use bikedyn::bicycle::Bicycle;
use bikedyn::report::output;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// Most points a `START:STOP:STEP` range may have when all its results are
/// held in memory (sweeps, tables, plots).
pub const MAX_POINTS: usize = 10_000_000;
/// Most rows of a terminal table (`eig --format table`): the table is
/// aligned, so it is held in memory; CSV and JSON stream instead.
pub const MAX_TABLE_ROWS: usize = 100_000;
/// Most cells of a two-parameter stability map (each cell is one
/// linearization and one critical-speed search, held in memory).
pub const MAX_MAP_CELLS: usize = 10_000_000;
/// Most speeds of `eig` with CSV or JSON output, which streams its rows (memory
/// stays flat; the limit only bounds the run time, about 1 µs per speed).
pub const MAX_STREAMED_POINTS: usize = 1_000_000_000;

/// `START:STOP:STEP` (or one number) as `(start, step, count)`, with at most
/// `limit` points.
pub fn range_spec(s: &str, what: &str, limit: usize) -> Result<(f64, f64, usize)> {
    let parts: Vec<&str> = s.split(':').collect();
    let nums: Vec<f64> = parts
        .iter()
        .map(|p| {
            p.trim()
                .parse::<f64>()
                .with_context(|| format!("{what}: `{p}` is not a number (expected START:STOP:STEP)"))
        })
        .collect::<Result<_>>()?;
    match nums.as_slice() {
        [x] if x.is_finite() => Ok((*x, 0.0, 1)),
        [a, b, h] if a.is_finite() && b.is_finite() && h.is_finite() && *h > 0.0 && b >= a => {
            // Count in floating point: `as usize` would saturate (and `+ 1`
            // wrap) for a tiny step such as 1e-300.
            let intervals = ((b - a) / h + 1e-9).floor();
            if intervals.is_nan() || intervals >= limit as f64 {
                bail!(
                    "{what}: `{s}` gives {} points, more than the limit of {limit} \
                     (use a larger STEP or a shorter range)",
                    output::format_significant(intervals + 1.0, 4)
                );
            }
            Ok((*a, *h, intervals as usize + 1))
        }
        _ => bail!("{what}: `{s}` must be START:STOP:STEP with STEP > 0 and STOP >= START"),
    }
}

/// `--speed-max`: the searched speeds are 0 to it, so it must be a
/// positive finite speed (0 searched nothing and reported "never
/// self-stable").
pub fn check_speed_max(v: f64) -> Result<f64> {
    if !(v.is_finite() && v > 0.0) {
        bail!("--speed-max {v}: the upper end of the searched speeds must be a positive finite speed (m/s), e.g. --speed-max 10");
    }
    Ok(v)
}

pub fn parse_range(s: &str, what: &str) -> Result<Vec<f64>> {
    let (a, h, n) = range_spec(s, what, MAX_POINTS)?;
    Ok((0..n).map(|k| a + k as f64 * h).collect())
}

/// The bicycle of a command that writes a table (`--output`) and a figure
/// (`--plot`): every path is checked (the bicycle file readable, the
/// outputs writable and not an input) before the bicycle is read.
pub fn load_with_outputs(bike: &str, out: Option<&std::path::Path>, plot: Option<&std::path::Path>) -> Result<Bicycle> {
    Paths::new()
        .bike("--bike", Some(bike))
        .file("--output", out)
        .file("--plot", plot)
        .check()?;
    check_outputs(out, plot)?;
    load(bike)
}

pub fn load(bike: &str) -> Result<Bicycle> {
    let b = Bicycle::resolve(bike)?;
    show_warnings(&b);
    Ok(b)
}

static VERBOSE: AtomicBool = AtomicBool::new(false);

/// `--verbose`: every parameter warning in full.
pub fn set_verbose(verbose: bool) {
    VERBOSE.store(verbose, Ordering::Relaxed);
}

/// A bicycle's parameter warnings on standard error, once per file per
/// command. The built-in bicycles' warnings are known (the thesis's
/// measured inertias violate the triangle inequality, as published) and
/// shown only with `--verbose`; a file's notes that ask for no action (the
/// triangle inequality, names kept aside) are one summary line each, with
/// what they mean; the rest in full.
pub fn show_warnings<R: bikedyn::registry::ModelRegistry>(b: &bikedyn::bicycle::Bicycle<R>) {
    use bikedyn::bicycle::ParameterWarning;
    static SHOWN: std::sync::Mutex<Vec<String>> = std::sync::Mutex::new(Vec::new());
    let verbose = VERBOSE.load(Ordering::Relaxed);
    let built_in = matches!(b.name.as_str(), "thesis" | "benchmark");
    if b.warnings.is_empty() || (built_in && !verbose) {
        return;
    }
    if let Ok(mut shown) = SHOWN.lock() {
        if shown.contains(&b.name) {
            return;
        }
        shown.push(b.name.clone());
    }
    if verbose {
        for w in &b.warnings {
            eprintln!("warning ({}): {w}", b.name);
        }
        return;
    }
    let mut triangle = Vec::new();
    let mut extra = Vec::new();
    for w in &b.warnings {
        match w {
            ParameterWarning::TriangleInequality { body, .. } => triangle.push(*body),
            ParameterWarning::ExtraField { field, .. } => extra.push(field.as_str()),
            w => eprintln!("warning ({}): {w}", b.name),
        }
    }
    if !triangle.is_empty() {
        eprintln!(
            "note ({}): the inertia of the {} violates the triangle inequality: no rigid body has such principal moments (a measurement or transcription error in the source); bikedyn uses them as given (--verbose for the values)",
            b.name,
            triangle.join(" and the ")
        );
    }
    if !extra.is_empty() {
        eprintln!(
            "note ({}): {} not a model parameter and kept aside: {} (--verbose for what each means)",
            b.name,
            if extra.len() == 1 {
                "one name is"
            } else {
                "these names are"
            },
            extra.join(", ")
        );
    }
}

/// Check every output before any work (a data file and, optionally, a
/// plot whose extension must name a supported image format), so that a bad
/// path fails at once rather than after the computation.
pub fn check_outputs(out: Option<&std::path::Path>, plot: Option<&std::path::Path>) -> Result<()> {
    if let Some(p) = out {
        output::output_target(p)?;
    }
    if let Some(p) = plot {
        bikedyn::report::plot::ImageFormat::from_path(p)?;
        output::output_target(p)?;
    }
    Ok(())
}

/// The plot options of `--plot-size`, `--dpi`, `--xlim`, `--ylim` with
/// the figure's `subject`, checked before any computation: a bad value is
/// an error naming its flag.
pub fn plot_options(a: &args::PlotArgs, subject: Option<String>) -> Result<bikedyn::report::plot::PlotOptions> {
    use anyhow::bail;
    use bikedyn::report::plot::PlotOptions;
    let mut o = PlotOptions {
        subject,
        ..PlotOptions::default()
    };
    if let Some(d) = a.dpi {
        if !(d.is_finite() && (10.0..=2400.0).contains(&d)) {
            bail!("--dpi {d}: the resolution must be between 10 and 2400 dots per inch");
        }
        o.scale = d / 100.0;
    }
    if let Some(spec) = &a.plot_size {
        let t = spec.trim().to_ascii_lowercase();
        let (num, per_inch) = if let Some(n) = t.strip_suffix("cm") {
            (n, 1.0 / 2.54)
        } else if let Some(n) = t.strip_suffix("mm") {
            (n, 1.0 / 25.4)
        } else if let Some(n) = t.strip_suffix("px") {
            (n, 0.01)
        } else {
            (t.strip_suffix("in").unwrap_or(&t), 1.0)
        };
        let parts: Vec<&str> = num.split(['x', '*']).collect();
        let vals: Option<Vec<f64>> = parts.iter().map(|p| p.trim().parse::<f64>().ok()).collect();
        let (w, h) = match vals.as_deref() {
            Some([w, h]) => (*w * per_inch, *h * per_inch),
            _ => bail!(
                "--plot-size `{spec}`: expected WIDTHxHEIGHT in inches (e.g. 8x6), or with cm, mm or px (e.g. 16x12cm)"
            ),
        };
        if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0) {
            bail!("--plot-size `{spec}`: width and height must be positive");
        }
        let size = ((w * 100.0).round() as u32, (h * 100.0).round() as u32);
        o.size = Some(size);
        if size.0 < 200 || size.1 < 150 {
            bail!("--plot-size `{spec}`: too small for a figure with axes and labels (at least 2x1.5 inches)");
        }
    }
    let (pw, ph) = o.pixel_size();
    use bikedyn::report::plot::{MAX_PIXELS, MAX_SIDE};
    if pw > MAX_SIDE || ph > MAX_SIDE || pw as u64 * ph as u64 > MAX_PIXELS {
        bail!(
            "--plot-size {} at --dpi {} gives {pw}x{ph} pixels, more than {MAX_SIDE} on a side or {} million in all (the memory a figure may take): give a smaller size or --dpi",
            a.plot_size.as_deref().unwrap_or("8x6"),
            o.dpi(),
            MAX_PIXELS / 1_000_000
        );
    }
    let limits = |flag: &str, spec: &Option<String>| -> Result<Option<(f64, f64)>> {
        let Some(spec) = spec else { return Ok(None) };
        let v: Option<Vec<f64>> = spec.split(':').map(|p| p.trim().parse::<f64>().ok()).collect();
        match v.as_deref() {
            Some([a, b]) if a.is_finite() && b.is_finite() && a < b => Ok(Some((*a, *b))),
            Some([a, b]) if a.is_finite() && b.is_finite() => {
                bail!("{flag} {spec}: the lower limit must be below the upper (A:B with A < B)")
            }
            _ => bail!("{flag} `{spec}`: expected two finite numbers A:B (e.g. {flag} 0:10, or {flag}=-10:10)"),
        }
    };
    o.x_range = limits("--xlim", &a.xlim)?;
    o.y_range = limits("--ylim", &a.ylim)?;
    Ok(o)
}

/// Write to standard output, turning a failed write into an error that
/// says what happened (see the `out!` macro).
pub fn write_out(args: std::fmt::Arguments<'_>) -> Result<()> {
    use std::io::Write;
    std::io::stdout().lock().write_fmt(args).map_err(stdout_error)
}

/// Standard output was closed by its reader (`| head -1`): the reader has
/// what it wanted, so the command stops quietly with exit status 0, as
/// Unix tools do (issue 35, reproducer 28). Other write errors (a full
/// disk) remain errors.
#[derive(Debug, thiserror::Error)]
#[error("standard output was closed before everything was written (broken pipe)")]
pub struct StdoutClosed;

/// The error of a failed write to standard output.
pub fn stdout_error(e: std::io::Error) -> anyhow::Error {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        anyhow::Error::new(StdoutClosed)
    } else {
        anyhow::anyhow!("writing to standard output: {e}; the output is incomplete")
    }
}

/// A streamed write's error: when a closed pipe or another I/O error on
/// standard output is its cause, the message of [`stdout_error`].
pub fn stdout_error_of(e: Box<dyn std::error::Error + Send + Sync>) -> anyhow::Error {
    let mut cause: Option<&(dyn std::error::Error + 'static)> = Some(&*e);
    while let Some(c) = cause {
        if let Some(io) = c.downcast_ref::<std::io::Error>() {
            return stdout_error(std::io::Error::new(io.kind(), io.to_string()));
        }
        // A CSV writer's I/O error is its kind, not its source.
        if let Some(csv::ErrorKind::Io(io)) = c.downcast_ref::<csv::Error>().map(|e| e.kind()) {
            return stdout_error(std::io::Error::new(io.kind(), io.to_string()));
        }
        // So is a JSON writer's (its `source` skips the I/O error).
        if let Some(kind) = c.downcast_ref::<serde_json::Error>().and_then(|e| e.io_error_kind()) {
            return stdout_error(std::io::Error::new(kind, c.to_string()));
        }
        cause = c.source();
    }
    anyhow::anyhow!(e)
}

pub fn emit(text: &str, output: &Option<PathBuf>) -> Result<()> {
    match output {
        Some(p) => output::write_string_atomic(p, text)?,
        None => out!("{text}"),
    }
    Ok(())
}

/// The bar of a sweep, fed by the runtime's cell callback
/// (`sweep::OnCellDone`). It starts hidden and moves to standard error once
/// the run has lasted [`CellProgressBar::DELAY`], and only on a terminal and
/// for more than one cell, so short runs, tests and redirected output stay
/// quiet.
pub struct CellProgressBar {
    bar: ProgressBar,
    enabled: bool,
    shown: AtomicBool,
}

impl CellProgressBar {
    /// How long a sweep runs before its bar appears.
    pub const DELAY: Duration = Duration::from_secs(1);

    /// A bar for `cells` cells, labelled `what` ("parameter sweep").
    pub fn new(cells: usize, what: &'static str) -> Self {
        let bar = ProgressBar::with_draw_target(Some(cells as u64), ProgressDrawTarget::hidden());
        if let Ok(style) = ProgressStyle::with_template("{msg} [{elapsed_precise}] {wide_bar} {pos}/{len} (eta {eta})")
        {
            bar.set_style(style);
        }
        bar.set_message(what);
        Self {
            bar,
            enabled: std::io::stderr().is_terminal() && cells > 1,
            shown: AtomicBool::new(false),
        }
    }

    /// One cell finished (the callback's `(done, total)` counts cells; the
    /// bar counts its own calls, since reports from the worker threads may
    /// arrive out of order).
    pub fn cell_done(&self, _done: usize, _total: usize) {
        self.bar.inc(1);
        if self.enabled
            && !self.shown.load(Ordering::Relaxed)
            && self.bar.elapsed() >= Self::DELAY
            && !self.shown.swap(true, Ordering::AcqRel)
        {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }
}

impl Drop for CellProgressBar {
    fn drop(&mut self) {
        self.bar.finish_and_clear();
    }
}
