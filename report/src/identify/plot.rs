//! Plots of an identification report (SVG): the weave eigenvalue over speed
//! before and after adding the selected effect, with each measured
//! eigenvalue on its speed segment; and the residual time series of one run
//! before and after.

use crate::experiment::plot::range;
use crate::plot::{de, render, DrawErr, Figure, PlotError, PlotOptions};
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::Path;

const BEFORE: RGBColor = RGBColor(0, 114, 178);
const AFTER: RGBColor = RGBColor(213, 94, 0);
const MEASURED: RGBColor = RGBColor(60, 60, 60);

/// A measured weave eigenvalue on its speed segment (m/s; 1/s).
pub struct MeasuredWeave {
    pub speed_interval: [f64; 2],
    pub mean_speed: f64,
    pub eigenvalue: [f64; 2],
    pub stderr: [f64; 2],
}

/// Weave eigenvalue curves `(speed, re, im)` of the model before and after,
/// and the measured eigenvalues.
pub fn plot_continuation(
    path: &Path,
    before: &[(f64, f64, f64)],
    after: &[(f64, f64, f64)],
    after_label: &str,
    measured: &[MeasuredWeave],
) -> Result<(), PlotError> {
    let opts = PlotOptions {
        width: 900,
        height: 620,
        ..PlotOptions::default()
    };
    render(
        path,
        &opts,
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
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawErr> {
        let (before, after, after_label, measured) = (self.before, self.after, self.after_label, self.measured);
        let vmax = before.iter().chain(after).map(|p| p.0).fold(1.0, f64::max);
        let (y0, y1) = range(
            before
                .iter()
                .chain(after)
                .flat_map(|p| [p.1, p.2])
                .chain(measured.iter().flat_map(|m| m.eigenvalue)),
        );
        {
            root.fill(&WHITE).map_err(de)?;
            let mut ch = ChartBuilder::on(root)
                .caption("weave eigenvalue before and after identification", ("sans-serif", 18))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(0.0..vmax, y0.max(-15.0)..y1.min(15.0))
                .map_err(de)?;
            ch.configure_mesh()
                .x_desc("forward speed (m/s)")
                .y_desc("weave eigenvalue, real and imaginary parts (1/s)")
                .draw()
                .map_err(de)?;
            for (curve, col, label, dashed) in [
                (before, BEFORE, "model before".to_string(), true),
                (after, AFTER, format!("model after ({after_label})"), false),
            ] {
                for part in 0..2 {
                    let pts: Vec<(f64, f64)> = curve.iter().map(|p| (p.0, if part == 0 { p.1 } else { p.2 })).collect();
                    let style = col.stroke_width(if dashed { 1 } else { 2 });
                    let s = ch.draw_series(LineSeries::new(pts, style)).map_err(de)?;
                    if part == 0 {
                        let l = format!("{label}: real (lower) and imaginary (upper) parts");
                        s.label(l)
                            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], style));
                    }
                }
            }
            for (i, m) in measured.iter().enumerate() {
                for part in 0..2 {
                    let (val, se) = (m.eigenvalue[part], m.stderr[part]);
                    let [lo, hi] = m.speed_interval;
                    let s = ch
                        .draw_series(std::iter::once(PathElement::new(
                            vec![(lo, val), (hi, val)],
                            MEASURED.stroke_width(3),
                        )))
                        .map_err(de)?;
                    if i == 0 && part == 0 {
                        s.label("measured (over its speed interval, bar: one standard error)")
                            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], MEASURED.stroke_width(3)));
                    }
                    ch.draw_series(std::iter::once(PathElement::new(
                        vec![(m.mean_speed, val - se), (m.mean_speed, val + se)],
                        BLACK.stroke_width(1),
                    )))
                    .map_err(de)?;
                }
            }
            ch.configure_series_labels()
                .position(SeriesLabelPosition::UpperLeft)
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .label_font(("sans-serif", 13))
                .draw()
                .map_err(de)?;
        }
        Ok(())
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

/// Measured and simulated roll, steer and speed of one run, before and after.
pub fn plot_run(path: &Path, title: &str, channels: &[Channel<'_>]) -> Result<(), PlotError> {
    let opts = PlotOptions {
        width: 900,
        height: 260 * channels.len() as u32 + 40,
        ..PlotOptions::default()
    };
    render(path, &opts, &RunFigure { title, channels })
}

struct RunFigure<'a, 'b> {
    title: &'a str,
    channels: &'a [Channel<'b>],
}

impl Figure for RunFigure<'_, '_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawErr> {
        let (title, channels) = (self.title, self.channels);
        {
            root.fill(&WHITE).map_err(de)?;
            let root = root.titled(title, ("sans-serif", 18)).map_err(de)?;
            let areas = root.split_evenly((channels.len(), 1));
            for (area, c) in areas.iter().zip(channels) {
                if c.t.is_empty() {
                    continue;
                }
                let x1 = c.t.last().copied().unwrap_or(1.0).max(1e-3);
                let (y0, y1) = range(c.measured.iter().chain(c.before).chain(c.after).copied());
                let mut ch = ChartBuilder::on(area)
                    .margin(8)
                    .x_label_area_size(35)
                    .y_label_area_size(60)
                    .build_cartesian_2d(0.0..x1, y0..y1)
                    .map_err(de)?;
                ch.configure_mesh()
                    .x_desc("time after the window start (s)")
                    .y_desc(format!("{} ({})", c.name, c.unit))
                    .draw()
                    .map_err(de)?;
                let series = [
                    (c.measured, MEASURED, "measured", 1),
                    (c.before, BEFORE, "model before", 2),
                    (c.after, AFTER, "model after", 2),
                ];
                for (y, col, label, w) in series {
                    let pts: Vec<(f64, f64)> = c.t.iter().copied().zip(y.iter().copied()).collect();
                    ch.draw_series(LineSeries::new(pts, col.stroke_width(w)))
                        .map_err(de)?
                        .label(label)
                        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], col.stroke_width(w)));
                }
                ch.configure_series_labels()
                    .background_style(WHITE.mix(0.85))
                    .border_style(BLACK)
                    .label_font(("sans-serif", 12))
                    .draw()
                    .map_err(de)?;
            }
        }
        Ok(())
    }
}
