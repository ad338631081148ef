//! Plots of measured runs: the response with its fit and the speed trace
//! (like the thesis's Figures 9-10), and the continuation diagram with
//! each measured weave eigenvalue at its mean speed, with error bars and
//! its speed interval (Figures 14-15). Same style, formats and options as
//! every figure ([`crate::plot`]).

use super::accept::rejected_label;
use crate::plot::style::{self, Area, Frame, Icon, Legend, Marker, Measured, Stroke};
use crate::plot::{de, label_area_width, render, DrawErr, Figure, PlotError, PlotOptions};
use crate::simulate::plot::speed_range;
use bikedyn_runtime::eigen::{eigen_sweep_of, LinearBicycle, Mode};
use bikedyn_runtime::experiment::fit::FitForm;
use bikedyn_runtime::experiment::KickFit;
use plotters::prelude::*;
use std::path::Path;

/// Data range with 8 % padding (`(0, 1)` without finite data).
pub(crate) fn range(x: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = x
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| (a.min(v), b.max(v)));
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    let pad = ((hi - lo) * 0.08).max(1e-6);
    (lo - pad, hi + pad)
}

/// A measured weave eigenvalue on its speed segment (m/s; 1/s).
pub struct MeasuredWeave {
    pub speed_interval: [f64; 2],
    pub mean_speed: f64,
    pub eigenvalue: [f64; 2],
    pub stderr: [f64; 2],
}

/// Measured real parts (filled points) and imaginary parts (open points)
/// with their error bars and speed intervals.
pub(crate) fn measured_parts(measured: &[MeasuredWeave]) -> [Vec<Measured>; 2] {
    let part = |k: usize| {
        measured
            .iter()
            .map(|m| Measured {
                x: m.mean_speed,
                y: m.eigenvalue[k],
                err: Some(m.stderr[k]),
                x_span: Some((m.speed_interval[0], m.speed_interval[1])),
            })
            .collect()
    };
    [part(0), part(1)]
}

/// Measured roll (deg) or roll rate (deg/s, for roll-rate fits) with the
/// reported fit, over the window, and the speed below. The default size
/// (when `opts` gives none) is 900x620.
pub fn plot_response(path: &Path, k: &KickFit, opts: &PlotOptions) -> Result<(), PlotError> {
    if k.samples.t.is_empty() {
        return Err(PlotError::NoData {
            path: path.to_path_buf(),
        });
    }
    let o = opts.sized_by_default((900, 620));
    render(path, &o, &Response { k })
}

struct Response<'a> {
    k: &'a KickFit,
}

impl Figure for Response<'_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        let (k, s) = (self.k, &self.k.samples);
        let fit = k.chosen_fit();
        let on_rate = fit.is_some_and(|f| matches!(f.form, FitForm::RollRate | FitForm::SpeedVaryingRollRate));
        let y: Vec<f64> = if on_rate { &s.roll_rate } else { &s.roll }
            .iter()
            .map(|v| v.to_degrees())
            .collect();
        let fitted: Vec<(f64, f64)> = match fit {
            Some(f) => {
                s.t.iter()
                    .copied()
                    .zip(f.evaluate(&s.t).iter().map(|v| v.to_degrees()))
                    .collect()
            }
            None => Vec::new(),
        };
        let run = k
            .run
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        // A fit that is no measured weave eigenvalue is drawn, and the
        // title says so.
        let title = match (fit, &k.rejected) {
            (Some(f), None) => format!(
                "{run}, kick at {:.2} s: eigenvalue {:.3} {:+.3}i 1/s (r2 {:.4}, {})",
                k.kick_time,
                f.eigenvalue[0],
                f.eigenvalue[1],
                f.r2,
                f.form.name()
            ),
            (Some(f), Some(r)) => format!(
                "{run}, kick at {:.2} s: refused ({}): fit {:.3} {:+.3}i 1/s (r2 {:.4}, {})",
                k.kick_time,
                rejected_label(r),
                f.eigenvalue[0],
                f.eigenvalue[1],
                f.r2,
                f.form.name()
            ),
            (None, _) => format!("{run}, kick at {:.2} s: no fit", k.kick_time),
        };
        root.fill(&WHITE).map_err(de)?;
        let area = style::titled(root, o, &title)?;
        let (h, _) = (area.dim_in_pixel().1, ());
        let (top, bottom) = area.split_vertically((h as f64 * 0.68) as u32);
        let xr = o.x_range.unwrap_or((s.t[0], s.t[s.t.len() - 1]));
        let yr = o
            .y_range
            .unwrap_or_else(|| range(y.iter().copied().chain(fitted.iter().map(|p| p.1))));
        let vr = speed_range(&s.speed);
        let label_w = [yr, vr]
            .iter()
            .map(|r| label_area_width(root, o, *r, 8))
            .max()
            .unwrap_or(0);
        let measured: Vec<Measured> =
            s.t.iter()
                .zip(&y)
                .map(|(t, y)| Measured {
                    x: *t,
                    y: *y,
                    err: None,
                    x_span: None,
                })
                .collect();
        let dots = Marker::filled(style::DATA).size(0.6);
        let mut legend = Legend::default();
        legend.add("measured", Icon::Point(dots));
        if !fitted.is_empty() {
            legend.add("fit", Icon::Line(Stroke::solid(style::VERMILION)));
        }
        let pts: Vec<(f64, f64)> = measured.iter().map(|m| (m.x, m.y)).collect();
        let frame = Frame {
            x_desc: false,
            y_label_width: Some(label_w),
            ..Frame::default()
        };
        let (mut c, place, _) = style::chart_with_legend(&top, o, xr, yr, frame, &legend, &[&pts, &fitted], &[])?;
        style::mesh(&mut c, o, "", if on_rate { "roll rate (deg/s)" } else { "roll (deg)" })?;
        if yr.0 < 0.0 && yr.1 > 0.0 {
            style::hline(&mut c, o, 0.0)?;
        }
        style::measured(&mut c, o, &measured, dots)?;
        if !fitted.is_empty() {
            style::curve(&mut c, o, &fitted, Stroke::solid(style::VERMILION))?;
        }
        style::frame(&mut c, o)?;
        legend.draw(root, &c, o, place)?;
        let frame = Frame {
            y_label_width: Some(label_w),
            ..Frame::default()
        };
        let mut c2 = style::chart(&bottom, o, xr, vr, frame)?;
        style::mesh(&mut c2, o, "time (s)", "speed (m/s)")?;
        let speed: Vec<(f64, f64)> =
            s.t.iter()
                .zip(&s.speed)
                .filter(|(_, v)| v.is_finite())
                .map(|(a, b)| (*a, *b))
                .collect();
        style::curve(&mut c2, o, &speed, Stroke::solid(style::GREEN))?;
        style::frame(&mut c2, o)
    }
}

/// The model's weave eigenvalue (real part solid, imaginary part dashed)
/// over speed, and each measured eigenvalue at its mean speed with error
/// bars (one standard error) and its speed interval: the kicks whose fit is
/// a measured weave eigenvalue ([`KickFit::measured_weave`]); the title
/// counts the others. The default size (when `opts` gives none) is 900x620.
pub fn plot_measured_continuation(
    path: &Path,
    c: &dyn LinearBicycle,
    kicks: &[&KickFit],
    opts: &PlotOptions,
) -> Result<(), PlotError> {
    let vmax = kicks
        .iter()
        .map(|k| k.speed_interval[1])
        .filter(|v| v.is_finite())
        .fold(8.0f64, f64::max)
        + 1.0;
    let speeds: Vec<f64> = (0..=400).map(|i| vmax * i as f64 / 400.0).collect();
    let sweep = eigen_sweep_of(c, &speeds).map_err(|e| PlotError::Drawing {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    let mut model = Vec::new();
    for p in &sweep.points {
        for k in 0..4 {
            if p.modes[k] == Mode::Weave && p.eigenvalues[k].im > 0.0 {
                model.push((p.v, p.eigenvalues[k].re, p.eigenvalues[k].im));
            }
        }
    }
    let measured: Vec<MeasuredWeave> = kicks
        .iter()
        .filter_map(|k| {
            k.measured_weave().map(|f| MeasuredWeave {
                speed_interval: k.speed_interval,
                mean_speed: k.mean_speed,
                eigenvalue: f.eigenvalue,
                stderr: f.eigenvalue_stderr,
            })
        })
        .collect();
    let refused = kicks
        .iter()
        .filter(|k| k.chosen_fit().is_some() && k.rejected.is_some())
        .count();
    let o = opts.sized_by_default((900, 620));
    render(
        path,
        &o,
        &MeasuredContinuation {
            model,
            measured,
            refused,
            vmax,
        },
    )
}

struct MeasuredContinuation {
    model: Vec<(f64, f64, f64)>,
    measured: Vec<MeasuredWeave>,
    /// Fitted eigenvalues left out (not measured weave eigenvalues).
    refused: usize,
    vmax: f64,
}

impl Figure for MeasuredContinuation {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        root.fill(&WHITE).map_err(de)?;
        let title = match self.refused {
            0 => "weave eigenvalue: model and measured".to_string(),
            n => format!("weave eigenvalue: model and measured ({n} fits refused, not shown)"),
        };
        let area = style::titled(root, o, &title)?;
        let re: Vec<(f64, f64)> = self.model.iter().map(|p| (p.0, p.1)).collect();
        let im: Vec<(f64, f64)> = self.model.iter().map(|p| (p.0, p.2)).collect();
        let [mre, mim] = measured_parts(&self.measured);
        let xr = o.x_range.unwrap_or((0.0, self.vmax));
        let yr = o.y_range.unwrap_or_else(|| {
            let (y0, y1) = range(
                re.iter()
                    .chain(&im)
                    .map(|p| p.1)
                    .chain(self.measured.iter().flat_map(|m| m.eigenvalue)),
            );
            (y0.max(-15.0), y1.min(15.0))
        });
        let mut legend = Legend::default();
        legend.add("model, real part", Icon::Line(Stroke::solid(style::BLUE)));
        legend.add("model, imaginary part", Icon::Line(Stroke::dashed(style::BLUE)));
        if !self.measured.is_empty() {
            legend.add(
                "measured real part (bar: 1 s.e.)",
                Icon::PointWithError(Marker::filled(style::DATA)),
            );
            legend.add(
                "measured imaginary part",
                Icon::PointWithError(Marker::open(style::DATA)),
            );
        }
        let points: Vec<(f64, f64)> = mre.iter().chain(&mim).map(|m| (m.x, m.y)).collect();
        let (mut ch, place, _) =
            style::chart_with_legend(&area, o, xr, yr, Frame::default(), &legend, &[&re, &im, &points], &[])?;
        let xl = o.x_label.clone().unwrap_or_else(|| "forward speed v (m/s)".into());
        let yl = o.y_label.clone().unwrap_or_else(|| "weave eigenvalue (1/s)".into());
        style::mesh(&mut ch, o, &xl, &yl)?;
        if yr.0 < 0.0 && yr.1 > 0.0 {
            style::hline(&mut ch, o, 0.0)?;
        }
        style::curve(&mut ch, o, &im, Stroke::dashed(style::BLUE))?;
        style::curve(&mut ch, o, &re, Stroke::solid(style::BLUE))?;
        style::measured(&mut ch, o, &mre, Marker::filled(style::DATA))?;
        style::measured(&mut ch, o, &mim, Marker::open(style::DATA))?;
        style::frame(&mut ch, o)?;
        legend.draw(root, &ch, o, place)
    }
}
