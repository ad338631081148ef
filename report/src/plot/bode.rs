//! The Bode plot of a frequency response: magnitude (dB) and phase
//! (degrees) against angular frequency on a logarithmic axis, in two
//! stacked panels, one curve per input-output pair (colour: the input;
//! solid: roll, dashed: steer).

use std::path::Path;

use plotters::prelude::*;

use super::style::{self, Area, Chart, Frame, Icon, Legend, Stroke};
use super::{
    de, label_area_width, padded, render, tick, DrawErr, Figure, ImageFormat, PlotError, PlotOptions, DEFAULT_SIZE,
};
use bikedyn_runtime::frequency::FrequencyResponse;

struct BodeFigure<'a> {
    r: &'a FrequencyResponse,
    xr: (f64, f64),
}

/// Draw the Bode plot of `r` to `path` (default size 800x900; `--xlim` is
/// in rad/s, `--ylim` the magnitude panel's range in dB).
pub fn plot_bode(path: impl AsRef<Path>, r: &FrequencyResponse, opts: &PlotOptions) -> Result<(), PlotError> {
    let path = path.as_ref();
    ImageFormat::from_path(path)?;
    opts.check(path)?;
    let positive: Vec<f64> = r.omega.iter().copied().filter(|w| *w > 0.0).collect();
    if positive.len() < 2 || r.responses.is_empty() {
        return Err(PlotError::NoData {
            path: path.to_path_buf(),
        });
    }
    let xr = match opts.x_range {
        Some((a, b)) if a > 0.0 => (a.log10(), b.log10()),
        Some(_) => {
            return Err(PlotError::InvalidOptions {
                path: path.to_path_buf(),
                message: "the frequency axis is logarithmic: its limits must be positive (rad/s)".into(),
            })
        }
        None => (positive[0].log10(), positive[positive.len() - 1].log10()),
    };
    let o = opts.sized_by_default((DEFAULT_SIZE.0, 900));
    render(path, &o, &BodeFigure { r, xr })
}

/// Grid, ticks and labels with a logarithmic x axis (`x` is `log10 omega`).
fn log_mesh(
    chart: &mut Chart<'_, '_>,
    o: &PlotOptions,
    x_desc: &str,
    y_desc: &str,
    decades: f64,
) -> Result<(), DrawErr> {
    let x_label = |v: &f64| {
        if decades < 1.5 || (v - v.round()).abs() < 1e-9 {
            tick(10f64.powf(*v))
        } else {
            String::new()
        }
    };
    let mut m = chart.configure_mesh();
    m.bold_line_style(style::GRID.stroke_width(o.pxu(1.0)))
        .light_line_style(TRANSPARENT)
        .axis_style(BLACK.stroke_width(o.pxu(1.0)))
        .set_all_tick_mark_size(o.pxi(5.0))
        .x_labels(12)
        .y_labels(8)
        .x_label_formatter(&x_label)
        .y_label_formatter(&|v| tick(*v))
        .label_style(o.font(0.9))
        .axis_desc_style(o.font(1.0))
        .y_desc(y_desc);
    if !x_desc.is_empty() {
        m.x_desc(x_desc);
    }
    m.draw().map_err(de)?;
    style::frame(chart, o)
}

fn label(input: &str, output: &str) -> String {
    format!("{} torque to {output}", input.trim_end_matches("_torque"))
}

impl Figure for BodeFigure<'_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        root.fill(&WHITE).map_err(de)?;
        let r = self.r;
        let area = style::titled(
            root,
            o,
            &format!(
                "frequency response at v = {} m/s{}",
                tick(r.speed),
                if r.stable { "" } else { " (unstable there)" }
            ),
        )?;
        let panels = area.split_evenly((2, 1));
        let x: Vec<f64> = r
            .omega
            .iter()
            .map(|w| if *w > 0.0 { w.log10() } else { f64::NAN })
            .collect();
        let stroke = |input: &str, output: &str| {
            let c = if input == "roll_torque" {
                style::BLUE
            } else {
                style::VERMILION
            };
            if output == "roll" {
                Stroke::solid(c)
            } else {
                Stroke::dashed(c)
            }
        };
        let curves = |values: fn(&bikedyn_runtime::frequency::Response) -> &[f64]| -> Vec<Vec<(f64, f64)>> {
            r.responses
                .iter()
                .map(|g| {
                    x.iter()
                        .zip(values(g))
                        .filter(|(a, b)| a.is_finite() && b.is_finite())
                        .map(|(a, b)| (*a, *b))
                        .collect()
                })
                .collect()
        };
        let mag = curves(|g| &g.magnitude_db);
        let phase = curves(|g| &g.phase_deg);
        let range = |c: &[Vec<(f64, f64)>]| {
            let (lo, hi) = c
                .iter()
                .flatten()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p.1), h.max(p.1)));
            padded(lo, hi, 0.05)
        };
        let yr_mag = o.y_range.unwrap_or_else(|| range(&mag));
        let yr_phase = range(&phase);
        let label_w = label_area_width(root, o, yr_mag, 8).max(label_area_width(root, o, yr_phase, 8));
        let mut legend = Legend::default();
        for g in &r.responses {
            legend.add(label(g.input, g.output), Icon::Line(stroke(g.input, g.output)));
        }
        let decades = self.xr.1 - self.xr.0;
        for (k, (panel, (data, yr, what))) in panels
            .iter()
            .zip([
                (&mag, yr_mag, "magnitude (dB re 1 rad/(N m))"),
                (&phase, yr_phase, "phase (deg)"),
            ])
            .enumerate()
        {
            let last = k == 1;
            let frame = Frame {
                x_desc: last,
                y_label_width: Some(label_w),
                ..Frame::default()
            };
            let refs: Vec<&[(f64, f64)]> = data.iter().map(Vec::as_slice).collect();
            let (mut chart, place) = if k == 0 {
                let (c, p, _) = style::chart_with_legend(panel, o, self.xr, yr, frame, &legend, &refs, &[])?;
                (c, Some(p))
            } else {
                (style::chart(panel, o, self.xr, yr, frame)?, None)
            };
            log_mesh(
                &mut chart,
                o,
                if last { "angular frequency omega (rad/s)" } else { "" },
                what,
                decades,
            )?;
            for (g, pts) in r.responses.iter().zip(data) {
                style::curve(&mut chart, o, pts, stroke(g.input, g.output))?;
            }
            style::frame(&mut chart, o)?;
            if let Some(p) = place {
                legend.draw(root, &chart, o, p)?;
            }
        }
        Ok(())
    }
}
