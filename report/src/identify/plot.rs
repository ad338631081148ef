//! Plots of an identification report: the weave eigenvalue over speed
//! before and after adding the selected effect (real parts solid,
//! imaginary parts dashed), with each measured eigenvalue at its mean speed
//! (error bar: one standard error; its speed interval as a light segment);
//! and the residual time series of one run before and after. Same style
//! and options as every figure ([`crate::plot`]).

// A measured eigenvalue is the measured runs' own (`experiment`); its
// type is here too, for the continuation figure's callers.
pub use crate::experiment::plot::MeasuredWeave;
use crate::experiment::plot::{measured_parts, range};
use crate::plot::style::{self, Area, Frame, Icon, Legend, Marker, Stroke};
use crate::plot::{de, label_area_width, render, DrawErr, Figure, PlotError, PlotOptions};
use plotters::prelude::*;
use std::path::Path;

const BEFORE: RGBColor = style::BLUE;
const AFTER: RGBColor = style::VERMILION;
const MEASURED: RGBColor = style::DATA;

/// Weave eigenvalue curves `(speed, re, im)` of the model before and after,
/// and the measured eigenvalues. The default size (when `opts` gives none)
/// is 900x620.
pub fn plot_continuation(
    path: &Path,
    before: &[(f64, f64, f64)],
    after: &[(f64, f64, f64)],
    after_label: &str,
    measured: &[MeasuredWeave],
    opts: &PlotOptions,
) -> Result<(), PlotError> {
    let o = opts.sized_by_default((900, 620));
    render(
        path,
        &o,
        &Continuation {
            before,
            after,
            after_label,
            measured,
        },
    )
}

struct Continuation<'a> {
    before: &'a [(f64, f64, f64)],
    after: &'a [(f64, f64, f64)],
    after_label: &'a str,
    measured: &'a [MeasuredWeave],
}

impl Figure for Continuation<'_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        let (before, after, measured) = (self.before, self.after, self.measured);
        root.fill(&WHITE).map_err(de)?;
        let area = style::titled(root, o, "weave eigenvalue before and after identification")?;
        let vmax = before.iter().chain(after).map(|p| p.0).fold(1.0, f64::max);
        let xr = o.x_range.unwrap_or((0.0, vmax));
        let yr = o.y_range.unwrap_or_else(|| {
            let (y0, y1) = range(
                before
                    .iter()
                    .chain(after)
                    .flat_map(|p| [p.1, p.2])
                    .chain(measured.iter().flat_map(|m| m.eigenvalue)),
            );
            (y0.max(-15.0), y1.min(15.0))
        });
        let curves: Vec<(Vec<(f64, f64)>, Stroke)> = [(before, BEFORE), (after, AFTER)]
            .iter()
            .flat_map(|(c, col)| {
                [
                    (c.iter().map(|p| (p.0, p.1)).collect(), Stroke::solid(*col)),
                    (c.iter().map(|p| (p.0, p.2)).collect(), Stroke::dashed(*col)),
                ]
            })
            .collect();
        let [re, im] = measured_parts(measured);
        let mut legend = Legend::default();
        legend.add("model before", Icon::Line(Stroke::solid(BEFORE)));
        legend.add(
            format!("model after ({})", self.after_label),
            Icon::Line(Stroke::solid(AFTER)),
        );
        legend.add("real part", Icon::Line(Stroke::solid(style::GREY)));
        legend.add("imaginary part", Icon::Line(Stroke::dashed(style::GREY)));
        if !measured.is_empty() {
            legend.add(
                "measured real part (bar: 1 s.e.)",
                Icon::PointWithError(Marker::filled(MEASURED)),
            );
            legend.add("measured imaginary part", Icon::PointWithError(Marker::open(MEASURED)));
        }
        let points: Vec<(f64, f64)> = re.iter().chain(&im).map(|m| (m.x, m.y)).collect();
        let mut data: Vec<&[(f64, f64)]> = curves.iter().map(|c| c.0.as_slice()).collect();
        data.push(&points);
        let (mut chart, place, _) = style::chart_with_legend(&area, o, xr, yr, Frame::default(), &legend, &data, &[])?;
        let xl = o.x_label.clone().unwrap_or_else(|| "forward speed v (m/s)".into());
        let yl = o.y_label.clone().unwrap_or_else(|| "weave eigenvalue (1/s)".into());
        style::mesh(&mut chart, o, &xl, &yl)?;
        if yr.0 < 0.0 && yr.1 > 0.0 {
            style::hline(&mut chart, o, 0.0)?;
        }
        for (pts, s) in &curves {
            style::curve(&mut chart, o, pts, *s)?;
        }
        style::measured(&mut chart, o, &re, Marker::filled(MEASURED))?;
        style::measured(&mut chart, o, &im, Marker::open(MEASURED))?;
        style::frame(&mut chart, o)?;
        legend.draw(root, &chart, o, place)
    }
}

/// One channel of a run: measured and simulated before and after.
pub struct Channel<'a> {
    pub name: &'a str,
    pub unit: &'a str,
    pub t: &'a [f64],
    pub measured: &'a [f64],
    pub before: &'a [f64],
    pub after: &'a [f64],
}

/// Measured and simulated roll, steer and speed of one run, before and
/// after, in stacked panels sharing the time axis. The default size (when
/// `opts` gives none) is 900 wide and 260 per channel.
pub fn plot_run(path: &Path, title: &str, channels: &[Channel<'_>], opts: &PlotOptions) -> Result<(), PlotError> {
    let o = opts.sized_by_default((900, 260 * channels.len() as u32 + 40));
    render(path, &o, &RunFigure { title, channels })
}

struct RunFigure<'a, 'b> {
    title: &'a str,
    channels: &'a [Channel<'b>],
}

impl Figure for RunFigure<'_, '_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        let channels = self.channels;
        root.fill(&WHITE).map_err(de)?;
        let area = style::titled(root, o, self.title)?;
        let areas = area.split_evenly((channels.len().max(1), 1));
        let ranges: Vec<(f64, f64)> = channels
            .iter()
            .map(|c| range(c.measured.iter().chain(c.before).chain(c.after).copied()))
            .collect();
        let label_w = ranges
            .iter()
            .map(|r| label_area_width(root, o, *r, 8))
            .max()
            .unwrap_or(0);
        let mut legend = Legend::default();
        legend.add("measured", Icon::Line(Stroke::solid(MEASURED).width(0.75)));
        legend.add("model before", Icon::Line(Stroke::dashed(BEFORE)));
        legend.add("model after", Icon::Line(Stroke::solid(AFTER)));
        let n = channels.len();
        for (k, ((panel, c), yr)) in areas.iter().zip(channels).zip(&ranges).enumerate() {
            if c.t.is_empty() {
                continue;
            }
            let x1 = c.t.last().copied().unwrap_or(1.0).max(1e-3);
            let xr = o.x_range.unwrap_or((0.0, x1));
            let series: Vec<(Vec<(f64, f64)>, Stroke)> = [
                (c.measured, Stroke::solid(MEASURED).width(0.75)),
                (c.before, Stroke::dashed(BEFORE)),
                (c.after, Stroke::solid(AFTER)),
            ]
            .iter()
            .map(|(y, s)| (c.t.iter().copied().zip(y.iter().copied()).collect(), *s))
            .collect();
            let last = k + 1 == n;
            let frame = Frame {
                x_desc: last,
                y_label_width: Some(label_w),
                ..Frame::default()
            };
            let data: Vec<&[(f64, f64)]> = series.iter().map(|s| s.0.as_slice()).collect();
            let (mut ch, place) = if k == 0 {
                let (c, p, _) = style::chart_with_legend(panel, o, xr, *yr, frame, &legend, &data, &[])?;
                (c, Some(p))
            } else {
                (style::chart(panel, o, xr, *yr, frame)?, None)
            };
            style::mesh(
                &mut ch,
                o,
                if last { "time after the window start (s)" } else { "" },
                &format!("{} ({})", c.name, c.unit),
            )?;
            for (pts, s) in &series {
                style::curve(&mut ch, o, pts, *s)?;
            }
            style::frame(&mut ch, o)?;
            if let Some(p) = place {
                legend.draw(root, &ch, o, p)?;
            }
        }
        Ok(())
    }
}
