//! One-parameter sweeps: the chosen quantity (self-stable range width,
//! weave or capsize speed, or the real part of the least stable eigenvalue
//! at a probe speed) against the swept parameter.

use std::path::Path;

use plotters::prelude::*;

use super::style::{self, Area, Frame, Marker, Measured, Stroke};
use super::{de, padded, render, tick, DrawErr, Figure, ImageFormat, PlotError, PlotOptions};
use bikedyn_runtime::sweep::{MapQuantity, ParameterSweep};

struct SweepFigure<'a> {
    sweep: &'a ParameterSweep,
    quantity: MapQuantity,
    probe_speed: Option<f64>,
    pieces: Vec<Vec<(f64, f64)>>,
    xr: (f64, f64),
    yr: (f64, f64),
}

/// Draw `quantity` against the swept parameter of `sweep` to `path`: a
/// line through the values with a point at each (a gap where the quantity
/// does not exist, e.g. never self-stable). A signed quantity (the real
/// part of the least stable eigenvalue at `probe_speed`) gets its zero
/// line; the figure says the speed it was made at.
pub fn plot_parameter_sweep(
    path: impl AsRef<Path>,
    sweep: &ParameterSweep,
    quantity: MapQuantity,
    probe_speed: Option<f64>,
    opts: &PlotOptions,
) -> Result<(), PlotError> {
    let path = path.as_ref();
    ImageFormat::from_path(path)?;
    opts.check(path)?;
    let mut order: Vec<usize> = (0..sweep.points.len().min(sweep.param.values.len())).collect();
    order.sort_by(|&a, &b| sweep.param.values[a].total_cmp(&sweep.param.values[b]));
    let mut pieces: Vec<Vec<(f64, f64)>> = vec![Vec::new()];
    for k in order {
        let x = sweep.param.values[k];
        match quantity
            .value(&sweep.points[k])
            .filter(|v| v.is_finite() && x.is_finite())
        {
            Some(y) => pieces.last_mut().expect("one piece").push((x, y)),
            None => pieces.push(Vec::new()),
        }
    }
    pieces.retain(|p| !p.is_empty());
    if pieces.is_empty() {
        return Err(PlotError::NoData {
            path: path.to_path_buf(),
        });
    }
    let all = pieces.iter().flatten();
    let fold = |f: fn(&(f64, f64)) -> f64| {
        all.clone()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)))
    };
    let (x0, x1) = fold(|p| p.0);
    let (y0, y1) = fold(|p| p.1);
    let signed = quantity == MapQuantity::LeastStableRealPart;
    let xr = opts.x_range.unwrap_or_else(|| padded(x0, x1, 0.02));
    let yr = opts.y_range.unwrap_or_else(|| {
        if signed {
            padded(y0.min(0.0), y1.max(0.0), 0.08)
        } else {
            let (lo, hi) = padded(y0.min(0.0), y1, 0.08);
            (lo.max(0.0), hi)
        }
    });
    render(
        path,
        opts,
        &SweepFigure {
            sweep,
            quantity,
            probe_speed,
            pieces,
            xr,
            yr,
        },
    )
}

impl Figure for SweepFigure<'_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        root.fill(&WHITE).map_err(de)?;
        let [a, b] = self.sweep.speed_range;
        let what = match (self.quantity, self.probe_speed) {
            (MapQuantity::LeastStableRealPart, Some(v)) => {
                format!("least stable eigenvalue's real part at v = {} m/s", tick(v))
            }
            (q, _) => format!(
                "{} (speeds {}-{} m/s searched)",
                q.label().split(" (").next().unwrap_or(""),
                tick(a),
                tick(b)
            ),
        };
        let area = style::titled(root, o, &what)?;
        let mut chart = style::chart(&area, o, self.xr, self.yr, Frame::default())?;
        let xl = o.x_label.clone().unwrap_or_else(|| self.sweep.param.name.clone());
        let yl = o
            .y_label
            .clone()
            .unwrap_or_else(|| match (self.quantity, self.probe_speed) {
                (MapQuantity::LeastStableRealPart, Some(v)) => {
                    format!("largest real part at v = {} m/s (1/s)", tick(v))
                }
                (q, _) => q.label().to_string(),
            });
        style::mesh(&mut chart, o, &xl, &yl)?;
        if self.yr.0 < 0.0 && self.yr.1 > 0.0 {
            style::hline(&mut chart, o, 0.0)?;
        }
        for p in &self.pieces {
            style::curve(&mut chart, o, p, Stroke::solid(style::BLUE))?;
            let pts: Vec<Measured> = p
                .iter()
                .map(|&(x, y)| Measured {
                    x,
                    y,
                    err: None,
                    x_span: None,
                })
                .collect();
            style::measured(&mut chart, o, &pts, Marker::filled(style::BLUE).size(0.7))?;
        }
        style::frame(&mut chart, o)
    }
}
