//! `bikedyn sensitivity`: exact derivatives of the weave and capsize speeds
//! (and of the eigenvalues at a speed) with respect to every parameter, as
//! a ranked table of elasticities, CSV or JSON, and a bar chart.

use super::args::{BikeArg, FormName, Format, OutputArgs, PlotArgs};
use super::{emit, plot_options};
use anyhow::{bail, Context, Result};
use bikedyn::bicycle::Form;
use bikedyn::report::plot::sensitivity::plot_sensitivity;
use bikedyn::report::plot::subject;
use bikedyn::report::sensitivity::{sensitivity_table, write_sensitivity_csv};
use bikedyn::sensitivity::{sensitivity, SensitivityError, SensitivityOptions};
use std::path::PathBuf;

/// Run `bikedyn sensitivity`.
#[allow(clippy::too_many_arguments)]
pub fn run(
    bike: BikeArg,
    form: Option<FormName>,
    speed: Option<f64>,
    speed_max: f64,
    out: OutputArgs,
    plot: Option<PathBuf>,
    plot_args: PlotArgs,
) -> Result<bool> {
    let BikeArg { spec: bike, model } = bike;
    let format = out.format();
    let out = out.output;
    let mut opts = plot_options(&plot_args, None)?;
    let speed_max = super::check_speed_max(speed_max)?;
    if let Some(v) = speed {
        if !v.is_finite() {
            bail!("--speed {v}: the speed of the eigenvalue derivatives must be a finite speed (m/s), e.g. --speed 5");
        }
    }
    let b = super::load_with_outputs(&bike, out.as_deref(), plot.as_deref())?;
    let s = sensitivity(
        &b,
        &SensitivityOptions {
            model: model.clone(),
            form: form.map(|f| match f {
                FormName::Benchmark => Form::Benchmark,
                FormName::Thesis => Form::Thesis,
            }),
            speed,
            speed_max,
        },
    )
    .map_err(|e| match e {
        SensitivityError::NoCrossing { .. } => {
            anyhow::anyhow!(
                "--speed-max {speed_max}: {e}; raise --speed-max, or give --speed V for the eigenvalues alone"
            )
        }
        SensitivityError::Runtime {
            source: bikedyn::sensitivity::RuntimeError::DoubleEigenvalue { .. },
            ..
        } => anyhow::Error::new(e).context(format!("--speed {}", speed.unwrap_or_default())),
        e => anyhow::Error::new(e),
    })?;
    if !matches!(format, Format::Table) {
        eprintln!("model: {}", s.model);
    }
    if let Some(p) = &plot {
        opts.subject = Some(subject(&b.name, Some(s.model)));
        if s.weave_speed.is_none() && s.capsize_speed.is_none() {
            bail!("--plot: no weave or capsize speed between 0 and {speed_max} m/s, so there are no elasticities to draw (raise --speed-max)");
        }
        plot_sensitivity(p, s.weave_speed.as_ref(), s.capsize_speed.as_ref(), &opts)?;
        eprintln!("wrote {}", p.display());
    }
    let modes = s.eigenvalues.as_ref().map(|e| e.modes.as_slice()).unwrap_or(&[]);
    let text = match format {
        Format::Table => {
            format!("model: {}\n", s.model)
                + &sensitivity_table(
                    s.parameter_form,
                    s.weave_speed.as_ref(),
                    s.capsize_speed.as_ref(),
                    s.eigenvalues.as_ref().map(|e| (e.speed, e.modes.as_slice())),
                )
        }
        Format::Json => serde_json::to_string_pretty(&s)? + "\n",
        Format::Csv => {
            let mut buf = Vec::new();
            write_sensitivity_csv(&mut buf, s.weave_speed.as_ref(), s.capsize_speed.as_ref(), modes)
                .context("writing the CSV")?;
            String::from_utf8(buf)?
        }
    };
    emit(&text, &out)?;
    Ok(true)
}
