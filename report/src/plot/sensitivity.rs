//! The elasticities of the weave and capsize speeds to each parameter as a
//! horizontal bar chart, ranked as the table is (largest at the top).

use std::path::Path;

use plotters::prelude::*;

use super::style::{self, Area, Chart, Icon, Legend, Placement};
use super::{de, padded, render, tick, DrawErr, Figure, ImageFormat, PlotError, PlotOptions, DEFAULT_SIZE};
use crate::sensitivity::{ranked, RankedRow};
use bikedyn_runtime::sensitivity::CriticalSensitivity;

struct Bars {
    rows: Vec<RankedRow>,
    weave: Option<f64>,
    capsize: Option<f64>,
    xr: (f64, f64),
}

/// Draw the elasticities `(p / v) dv/dp` of the weave and capsize speeds
/// (each where it exists) to `path`, one pair of bars per parameter,
/// ranked by the larger of the two; parameters that move neither speed
/// (e.g. the inertias about the wheel-perpendicular axes, or a parameter
/// whose value is zero) are left out. The default height grows with the
/// number of parameters.
pub fn plot_sensitivity(
    path: impl AsRef<Path>,
    weave: Option<&CriticalSensitivity>,
    capsize: Option<&CriticalSensitivity>,
    opts: &PlotOptions,
) -> Result<(), PlotError> {
    let path = path.as_ref();
    ImageFormat::from_path(path)?;
    opts.check(path)?;
    let all = ranked(weave, capsize);
    let largest = all.iter().map(RankedRow::size).fold(0.0, f64::max);
    let rows: Vec<RankedRow> = all
        .into_iter()
        .filter(|r| r.size() > 1e-9 * largest && r.size().is_finite())
        .collect();
    if rows.is_empty() {
        return Err(PlotError::NoData {
            path: path.to_path_buf(),
        });
    }
    let values = rows
        .iter()
        .flat_map(|r| [r.weave.map(|x| x.1), r.capsize.map(|x| x.1)])
        .flatten();
    let (lo, hi) = values.fold((0.0f64, 0.0f64), |(l, h), v| (l.min(v), h.max(v)));
    let xr = opts.x_range.unwrap_or_else(|| padded(lo, hi, 0.06));
    let height = (150 + 34 * rows.len() as u32).max(DEFAULT_SIZE.1 / 2);
    let o = opts.sized_by_default((DEFAULT_SIZE.0, height));
    render(
        path,
        &o,
        &Bars {
            rows,
            weave: weave.map(|c| c.speed),
            capsize: capsize.map(|c| c.speed),
            xr,
        },
    )
}

impl Bars {
    fn chart<'a, 'b>(&self, area: &'a Area<'b>, o: &PlotOptions, right: f64) -> Result<Chart<'a, 'b>, DrawErr> {
        let n = self.rows.len();
        let font = o.font(0.9);
        let widest = self
            .rows
            .iter()
            .map(|r| area.estimate_text_size(r.parameter, &font).map(|d| d.0).unwrap_or(0))
            .max()
            .unwrap_or(0);
        ChartBuilder::on(area)
            .margin_top(o.pxu(12.0))
            .margin_right(o.pxu(24.0 + right))
            .margin_left(o.pxu(10.0))
            .margin_bottom(o.pxu(10.0))
            .x_label_area_size(o.pxu(o.font_size * 3.4))
            .y_label_area_size(widest + o.pxu(16.0))
            .build_cartesian_2d(self.xr.0..self.xr.1, -0.5..(n as f64 - 0.5))
            .map_err(de)
    }
}

impl Figure for Bars {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        root.fill(&WHITE).map_err(de)?;
        let area = style::titled(root, o, "sensitivity of the critical speeds")?;
        let n = self.rows.len();
        let mut legend = Legend::default();
        if let Some(v) = self.weave {
            legend.add(
                format!("weave speed v_w = {} m/s", tick(v)),
                Icon::Patch(style::BLUE, 0.85),
            );
        }
        if let Some(v) = self.capsize {
            legend.add(
                format!("capsize speed v_c = {} m/s", tick(v)),
                Icon::Patch(style::VERMILION, 0.85),
            );
        }
        // The bars as rectangles in data coordinates: (x0, y0, x1, y1, colour).
        let half = 0.38;
        let mut bars = Vec::new();
        for (k, r) in self.rows.iter().enumerate() {
            let y = (n - 1 - k) as f64;
            if let Some((_, e)) = r.weave {
                bars.push((0.0, y, e, y + half, style::BLUE));
            }
            if let Some((_, e)) = r.capsize {
                bars.push((0.0, y - half, e, y, style::VERMILION));
            }
        }
        let outlines: Vec<Vec<(f64, f64)>> = bars
            .iter()
            .map(|&(x0, y0, x1, y1, _)| vec![(x0, y0), (x1, y0), (x1, y1), (x0, y1), (x0, y0)])
            .collect();
        let data: Vec<&[(f64, f64)]> = outlines.iter().map(Vec::as_slice).collect();
        let mut chart = self.chart(&area, o, 0.0)?;
        let place = legend.place(&chart, &area, o, &style::pixels(&chart, o, &data), &[]);
        if place == Placement::Outside {
            chart = self.chart(&area, o, legend.outside_width(&area, o))?;
        }
        let names: Vec<&str> = self.rows.iter().map(|r| r.parameter).collect();
        let label = |v: &f64| {
            let k = v.round();
            if (v - k).abs() < 1e-6 && k >= 0.0 && (k as usize) < n {
                names[n - 1 - k as usize].to_string()
            } else {
                String::new()
            }
        };
        chart
            .configure_mesh()
            .bold_line_style(style::GRID.stroke_width(o.pxu(1.0)))
            .light_line_style(TRANSPARENT)
            .axis_style(BLACK.stroke_width(o.pxu(1.0)))
            .set_all_tick_mark_size(o.pxi(5.0))
            .x_labels(10)
            .y_labels(n + 1)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&label)
            .label_style(o.font(0.9))
            .axis_desc_style(o.font(1.0))
            .x_desc("elasticity (p / v) dv/dp (% per %)")
            .draw()
            .map_err(de)?;
        for &(x0, y0, x1, y1, c) in &bars {
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(x0, y0), (x1, y1)],
                    c.mix(0.85).filled(),
                )))
                .map_err(de)?;
        }
        let yr = chart.y_range();
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(0.0, yr.start), (0.0, yr.end)],
                BLACK.stroke_width(o.pxu(1.0)),
            )))
            .map_err(de)?;
        style::frame(&mut chart, o)?;
        legend.draw(root, &chart, o, place)
    }
}
