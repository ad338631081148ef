//! `bikedyn sweep`: stability over one parameter, or a stability map over
//! two. The job is [`bikedyn::sweep::sweep`]; this checks the options,
//! calls it and prints, writes or plots its result.

use super::args::{BikeArg, Format, MapArg, SweepArgs};
use super::{emit, parse_range, plot_options, CellProgressBar, MAX_MAP_CELLS};
use anyhow::{bail, Result};
use bikedyn::report::output;
use bikedyn::report::plot::sweep::plot_parameter_sweep;
use bikedyn::report::plot::{plot_stability_map, subject, PlotOptions};
use bikedyn::sweep::MapQuantity;
use bikedyn::sweep::{stability_map_row, sweep, sweep_model, SweepOptions, SweepReport, SweptParameter};

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
    let ys = match (&param2, &values2) {
        (Some(_), Some(v2)) => Some(parse_range(v2, "--values2")?),
        _ => None,
    };
    let mut options = SweepOptions {
        model,
        parameter: SweptParameter::new(param.clone(), xs.clone()),
        second: match (&param2, &ys) {
            (Some(p2), Some(ys)) => Some(SweptParameter::new(p2.clone(), ys.clone())),
            _ => None,
        },
        speed_max,
        at_speed,
        // The standard deviations are in CSV and JSON.
        standard_deviations: !matches!(format, Format::Table),
    };
    let model = sweep_model(&b, &options)?;
    eprintln!("model: {model}");
    options.model = Some(model.clone());
    let info = bikedyn::models::model_info(&model);
    let describe = |symbol: &str| output::describe_parameter(symbol, info);
    // "trail (m) [c]" from a parameter symbol, for plot axes.
    let axis_label = |symbol: &str| match describe(symbol) {
        Some(d) => format!("{d} [{symbol}]"),
        None => symbol.to_string(),
    };
    let text = match (param2, ys) {
        (Some(p2), Some(ys)) => {
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
                    for i in 0..xs.len() {
                        let row = stability_map_row(&b, &options, i, &|done, total| bar.cell_done(done, total))?;
                        if i == 0 {
                            wr.write_record(output::stability_map_csv_header(&row.map))?;
                        }
                        output::write_stability_map_csv_rows(&mut wr, &row.map, i)?;
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
            let report = sweep(&b, &options, &|done, total| bar.cell_done(done, total));
            drop(bar);
            let SweepReport::Map(report) = report? else {
                unreachable!("a sweep over two parameters is a map")
            };
            if let Some(p) = &plot {
                let opts = PlotOptions {
                    x_label: Some(axis_label(&param)),
                    y_label: Some(axis_label(&p2)),
                    subject: Some(subject(&b.name, Some(&model))),
                    ..base_opts.clone()
                };
                plot_stability_map(p, &report.map, quantity, at_speed, &opts)?;
                eprintln!("wrote {}", p.display());
            }
            match format {
                Format::Table => output::format_stability_map_table(&report.map, &describe),
                Format::Json => serde_json::to_string_pretty(&SweepReport::Map(report))? + "\n",
                Format::Csv => {
                    let mut buf = Vec::new();
                    output::write_stability_map_csv(&mut buf, &report.map)?;
                    String::from_utf8(buf)?
                }
            }
        }
        (None, None) if values2.is_none() => {
            b.with_parameter(&param, xs[0])?;
            let bar = CellProgressBar::new(xs.len(), "parameter sweep");
            let report = sweep(&b, &options, &|done, total| bar.cell_done(done, total));
            drop(bar);
            let SweepReport::Parameter(report) = report? else {
                unreachable!("a sweep over one parameter is no map")
            };
            if let Some(p) = &plot {
                let opts = PlotOptions {
                    x_label: Some(axis_label(&param)),
                    subject: Some(subject(&b.name, Some(&model))),
                    ..base_opts.clone()
                };
                plot_parameter_sweep(p, &report.sweep, quantity, at_speed, &opts)?;
                eprintln!("wrote {}", p.display());
            }
            if report.standard_deviations_missing {
                eprintln!("note: no standard deviations in the sweep: `{param}` is not in the file's form, and setting it converts the file");
            }
            match format {
                Format::Table => output::format_parameter_table(&report.sweep, &describe),
                Format::Json => serde_json::to_string_pretty(&SweepReport::Parameter(report))? + "\n",
                Format::Csv => {
                    let spread = match &report.standard_deviations {
                        Some(u) => vec![
                            ("weave_speed_sd", u.weave_speed.clone()),
                            ("capsize_speed_sd", u.capsize_speed.clone()),
                        ],
                        None => Vec::new(),
                    };
                    let mut buf = Vec::new();
                    output::write_parameter_sweep_csv_with(&mut buf, &report.sweep, &spread)?;
                    String::from_utf8(buf)?
                }
            }
        }
        _ => bail!("--param2 and --values2 go together"),
    };
    emit(&text, &out)?;
    Ok(true)
}
