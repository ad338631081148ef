//! `bikedyn bode`: the transfer functions from the roll and steer torques to
//! the roll and steer angles at a speed, as a table, CSV or JSON, and a
//! Bode plot.

use super::args::{BikeArg, Format, OutputArgs, PlotArgs};
use super::{emit, plot_options};
use anyhow::{bail, Context, Result};
use bikedyn::frequency::{frequency_response, FrequencyOptions, MAX_POINTS};
use bikedyn::report::frequency::write_frequency_response_csv;
use bikedyn::report::output::{format_significant, format_table};
use bikedyn::report::plot::bode::plot_bode;
use bikedyn::report::plot::subject;
use std::path::PathBuf;

/// `--omega MIN:MAX` (rad/s).
fn omega_range(spec: &str) -> Result<(f64, f64)> {
    let v: Option<Vec<f64>> = spec.split(':').map(|p| p.trim().parse::<f64>().ok()).collect();
    match v.as_deref() {
        Some([a, b]) if a.is_finite() && b.is_finite() && *a > 0.0 && b > a => Ok((*a, *b)),
        _ => bail!(
            "--omega `{spec}`: expected MIN:MAX, two positive finite angular frequencies in rad/s with MIN < MAX (e.g. --omega 0.1:100)"
        ),
    }
}

/// Run `bikedyn bode`.
#[allow(clippy::too_many_arguments)]
pub fn run(
    bike: BikeArg,
    speed: f64,
    omega: String,
    points: usize,
    out: OutputArgs,
    plot: Option<PathBuf>,
    plot_args: PlotArgs,
) -> Result<bool> {
    let BikeArg { spec: bike, model } = bike;
    let format = out.format();
    let out = out.output;
    let mut opts = plot_options(&plot_args, None)?;
    if !speed.is_finite() {
        bail!("--speed {speed}: must be a finite forward speed (m/s), e.g. --speed 5");
    }
    let (omega_min, omega_max) = omega_range(&omega)?;
    if !(2..=MAX_POINTS).contains(&points) {
        bail!("--points {points}: between 2 and {MAX_POINTS} frequencies");
    }
    if let Some((a, _)) = opts.x_range {
        if a <= 0.0 {
            bail!("--xlim: the frequency axis is logarithmic, its limits must be positive angular frequencies (rad/s)");
        }
    }
    let b = super::load_with_outputs(&bike, out.as_deref(), plot.as_deref())?;
    let r = frequency_response(
        &b,
        &FrequencyOptions {
            model,
            speed,
            omega_min,
            omega_max,
            points,
        },
    )?;
    if !matches!(format, Format::Table) {
        eprintln!("model: {}", r.model);
    }
    if !r.response.stable {
        eprintln!(
            "note: the bicycle is unstable at {speed} m/s: G(i omega) is its transfer function on the imaginary axis, not a steady-state response it would show"
        );
    }
    if let Some(p) = &plot {
        opts.subject = Some(subject(&b.name, Some(r.model)));
        plot_bode(p, &r.response, &opts)?;
        eprintln!("wrote {}", p.display());
    }
    let text = match format {
        Format::Table => format!("model: {}\n", r.model) + &summary(&r.response),
        Format::Json => serde_json::to_string_pretty(&r)? + "\n",
        Format::Csv => {
            let mut buf = Vec::new();
            write_frequency_response_csv(&mut buf, &r.response).context("writing the CSV")?;
            String::from_utf8(buf)?
        }
    };
    emit(&text, &out)?;
    Ok(true)
}

/// The table: per input-output pair, the static gain and the peak of the
/// magnitude on the grid (the whole grid is in the CSV and JSON).
fn summary(r: &bikedyn::frequency::FrequencyResponse) -> String {
    let f = |x: f64| format_significant(x, 5);
    let header: Vec<String> = [
        "input",
        "output",
        "G(0) (rad/(N m))",
        "peak |G| (dB)",
        "at omega (rad/s)",
        "phase there (deg)",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    let rows: Vec<Vec<String>> = r
        .responses
        .iter()
        .map(|g| {
            let k = (0..r.omega.len())
                .max_by(|&a, &b| g.magnitude_db[a].total_cmp(&g.magnitude_db[b]))
                .unwrap_or(0);
            vec![
                g.input.to_string(),
                g.output.to_string(),
                g.static_gain.map_or("infinite".into(), f),
                f(g.magnitude_db[k]),
                f(r.omega[k]),
                f(g.phase_deg[k]),
            ]
        })
        .collect();
    format!(
        "transfer functions G(i omega) = C (i omega I - A)^-1 B at v = {} m/s ({}), {} frequencies {}-{} rad/s; --format csv or json for every frequency\n",
        f(r.speed),
        if r.stable { "stable" } else { "unstable" },
        r.omega.len(),
        f(r.omega[0]),
        f(r.omega[r.omega.len() - 1])
    ) + &format_table(&header, &rows)
}
