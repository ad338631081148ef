//! `bikedyn sweep`: stability over one parameter, or a stability map over two.

use super::args::{BikeArg, Format, MapArg, SweepArgs};
use super::{emit, parse_range, plot_options, CellProgressBar, MAX_MAP_CELLS};
use anyhow::{bail, Result};
use bikedyn::bicycle::Bicycle;
use bikedyn::report::output;
use bikedyn::report::plot::sweep::plot_parameter_sweep;
use bikedyn::report::plot::{plot_stability_map, subject, PlotOptions};
use bikedyn::runtime::sweep::{parameter_sweep, stability_map, MapQuantity, ParamAxis, SweepOptions};
use bikedyn::sensitivity::{speed_spread_over, SensitivityOptions};

/// Run `bikedyn sweep`.
pub fn run(a: SweepArgs) -> Result<bool> {
    let SweepArgs {
        bike: BikeArg { spec: bike, model },
        param,
        values,
        param2,
        values2,
        speed_max,
        out: output_args,
        plot,
        plot_args,
        map,
        at_speed,
    } = a;
    let format = output_args.format();
    let out = output_args.output;
    let base_opts = plot_options(&plot_args, None)?;
    let speed_max = super::check_speed_max(speed_max)?;
    if param2.as_deref().is_some_and(|p2| p2.trim() == param.trim()) {
        bail!("--param and --param2 both name `{param}`: a map needs two different parameters (for one, drop --param2 and --values2)");
    }
    let b = super::load_with_outputs(&bike, out.as_deref(), plot.as_deref())?;
    let quantity = match map {
        MapArg::Width => MapQuantity::StableWidth,
        MapArg::Weave => MapQuantity::WeaveSpeed,
        MapArg::Capsize => MapQuantity::CapsizeSpeed,
        MapArg::LeastStable => MapQuantity::LeastStableRealPart,
    };
    if matches!(map, MapArg::LeastStable) && at_speed.is_none() {
        bail!("--map least-stable needs --at-speed V (m/s)");
    }
    if let Some(v) = at_speed {
        if !v.is_finite() {
            bail!("--at-speed must be a finite speed, found {v:?}");
        }
    }
    let xs = parse_range(&values, "--values")?;
    // One model for every cell: the one that represents the design
    // with the swept parameters at their first non-zero values (a
    // sweep of c_steer from 0 runs wholly through the model with
    // steer damping), unless the user names it.
    let model: Option<String> = match model {
        Some(m) => Some(m),
        None => {
            let pick = |b: &Bicycle, name: &str, vals: &[f64]| -> Result<Bicycle> {
                let v = vals.iter().copied().find(|&v| v != 0.0).unwrap_or(vals[0]);
                Ok(b.with_parameter(name, v)?)
            };
            let mut probe = pick(&b, &param, &xs)?;
            if let (Some(p2), Some(v2)) = (&param2, &values2) {
                probe = pick(&probe, p2, &parse_range(v2, "--values2")?)?;
            }
            Some(probe.model(None)?.name.to_string())
        }
    };
    eprintln!("model: {}", model.as_deref().unwrap_or_default());
    let info = model.as_deref().and_then(bikedyn::models::model_info);
    let describe = |symbol: &str| output::describe_parameter(symbol, info);
    // "trail (m) [c]" from a parameter symbol, for plot axes.
    let axis_label = |symbol: &str| match describe(symbol) {
        Some(d) => format!("{d} [{symbol}]"),
        None => symbol.to_string(),
    };
    let opts = SweepOptions {
        probe_speed: at_speed,
        ..SweepOptions::with_speed_range(0.0, speed_max)
    };
    let text = match (param2, values2) {
        (Some(p2), Some(v2)) => {
            let ys = parse_range(&v2, "--values2")?;
            let cells = xs.len() as f64 * ys.len() as f64;
            if cells > MAX_MAP_CELLS as f64 {
                bail!(
                    "--values x --values2 gives {} x {} = {} cells, more than the limit of {MAX_MAP_CELLS} \
                     (use larger steps)",
                    xs.len(),
                    ys.len(),
                    output::format_significant(cells, 4)
                );
            }
            b.with_parameter(&param, xs[0])?.with_parameter(&p2, ys[0])?;
            if plot.is_none() && matches!(format, Format::Csv) {
                // A large map streams its CSV a row (one value of the first
                // parameter) at a time, as `eig` does, instead of printing
                // nothing until the whole grid is done.
                let bar = CellProgressBar::new(xs.len() * ys.len(), "stability map");
                let stream = |w: &mut dyn std::io::Write| -> Result<(), output::BoxError> {
                    let mut wr = csv::Writer::from_writer(w);
                    for (i, &x) in xs.iter().enumerate() {
                        let row = stability_map(
                            ParamAxis::new(param.clone(), vec![x]),
                            ParamAxis::new(p2.clone(), ys.clone()),
                            |x, y| {
                                b.with_parameter(&param, x)
                                    .and_then(|b| b.with_parameter(&p2, y))
                                    .and_then(|b| b.linear_with(model.as_deref()))
                            },
                            &opts,
                            &|done, total| bar.cell_done(done, total),
                        )?;
                        refuse_failed_cells(
                            row.cells
                                .iter()
                                .zip(&ys)
                                .map(|(c, y)| (format!("{param} = {x}, {p2} = {y}"), c)),
                        )
                        .map_err(|e| -> output::BoxError { e.to_string().into() })?;
                        if i == 0 {
                            wr.write_record(output::stability_map_csv_header(&row))?;
                        }
                        output::write_stability_map_csv_rows(&mut wr, &row, i)?;
                        wr.flush()?;
                    }
                    Ok(())
                };
                match &out {
                    Some(p) => output::write_atomic(p, |w| stream(w))?,
                    None => {
                        let mut w = std::io::BufWriter::new(std::io::stdout().lock());
                        stream(&mut w).map_err(super::stdout_error_of)?;
                        std::io::Write::flush(&mut w).map_err(super::stdout_error)?;
                    }
                }
                drop(bar);
                return Ok(true);
            }
            let bar = CellProgressBar::new(xs.len() * ys.len(), "stability map");
            let map = stability_map(
                ParamAxis::new(param.clone(), xs),
                ParamAxis::new(p2.clone(), ys),
                |x, y| {
                    b.with_parameter(&param, x)
                        .and_then(|b| b.with_parameter(&p2, y))
                        .and_then(|b| b.linear_with(model.as_deref()))
                },
                &opts,
                &|done, total| bar.cell_done(done, total),
            )?;
            drop(bar);
            refuse_failed_cells(map.cells.iter().enumerate().map(|(k, c)| {
                let (ny, x, y) = (map.y.values.len(), &map.x.values, &map.y.values);
                (format!("{param} = {}, {p2} = {}", x[k / ny], y[k % ny]), c)
            }))?;
            if let Some(p) = &plot {
                let opts = PlotOptions {
                    x_label: Some(axis_label(&param)),
                    y_label: Some(axis_label(&p2)),
                    subject: Some(subject(&b.name, model.as_deref())),
                    ..base_opts.clone()
                };
                plot_stability_map(p, &map, quantity, at_speed, &opts)?;
                eprintln!("wrote {}", p.display());
            }
            match format {
                Format::Table => output::format_stability_map_table(&map, &describe),
                Format::Json => serde_json::to_string_pretty(&output::stability_map_json(&map))? + "\n",
                Format::Csv => {
                    let mut buf = Vec::new();
                    output::write_stability_map_csv(&mut buf, &map)?;
                    String::from_utf8(buf)?
                }
            }
        }
        (None, None) => {
            b.with_parameter(&param, xs[0])?;
            let bar = CellProgressBar::new(xs.len(), "parameter sweep");
            let s = parameter_sweep(
                ParamAxis::new(param.clone(), xs),
                |x| {
                    b.with_parameter(&param, x)
                        .and_then(|b| b.linear_with(model.as_deref()))
                },
                &opts,
                &|done, total| bar.cell_done(done, total),
            )?;
            drop(bar);
            refuse_failed_cells(
                s.points
                    .iter()
                    .zip(&s.param.values)
                    .map(|(c, x)| (format!("{param} = {x}"), c)),
            )?;
            if let Some(p) = &plot {
                let opts = PlotOptions {
                    x_label: Some(axis_label(&param)),
                    subject: Some(subject(&b.name, model.as_deref())),
                    ..base_opts.clone()
                };
                plot_parameter_sweep(p, &s, quantity, at_speed, &opts)?;
                eprintln!("wrote {}", p.display());
            }
            // The critical speeds' standard deviations at each value from
            // the file's other +/- values (the swept parameter is set, so
            // its own is left out), in CSV and JSON.
            let spread = if b.uncertainties.is_empty() || matches!(format, Format::Table) {
                Vec::new()
            } else {
                let options = SensitivityOptions {
                    model: model.clone(),
                    speed_max,
                    ..SensitivityOptions::default()
                };
                match speed_spread_over(&b, &param, &s.param.values, &options) {
                    Some(u) => vec![("weave_speed_sd", u.weave_speed), ("capsize_speed_sd", u.capsize_speed)],
                    None => {
                        eprintln!("note: no standard deviations in the sweep: `{param}` is not in the file's form, and setting it converts the file");
                        Vec::new()
                    }
                }
            };
            match format {
                Format::Table => output::format_parameter_table(&s, &describe),
                Format::Json => serde_json::to_string_pretty(&output::parameter_sweep_json_with(&s, &spread))? + "\n",
                Format::Csv => {
                    let mut buf = Vec::new();
                    output::write_parameter_sweep_csv_with(&mut buf, &s, &spread)?;
                    String::from_utf8(buf)?
                }
            }
        }
        _ => bail!("--param2 and --values2 go together"),
    };
    emit(&text, &out)?;
    Ok(true)
}

/// A sweep with failed cells is an error listing them (at most ten), never
/// a table with messages in it.
fn refuse_failed_cells<'a>(
    cells: impl Iterator<Item = (String, &'a bikedyn::runtime::sweep::CellResult)>,
) -> Result<()> {
    let failed: Vec<String> = cells
        .filter_map(|(at, c)| c.as_ref().err().map(|e| format!("  {at}: {}", e.message)))
        .collect();
    if failed.is_empty() {
        return Ok(());
    }
    let shown = failed.iter().take(10).cloned().collect::<Vec<_>>().join("\n");
    let more = if failed.len() > 10 {
        format!("\n  ... and {} more", failed.len() - 10)
    } else {
        String::new()
    };
    bail!(
        "{} of the sweep's designs failed, no table written:\n{shown}{more}",
        failed.len()
    )
}
