//! Plots of measured runs (SVG): the response with its fit and the speed
//! trace (like the thesis's Figures 9-10), and the continuation diagram with
//! each measured weave eigenvalue on its speed segment with error bars
//! (Figures 14-15).

use crate::output::write_string_atomic;
use crate::plot::{find_font, use_font, PlotError};
use bikedyn_runtime::eigen::{eigen_sweep_of, LinearBicycle, Mode};
use bikedyn_runtime::experiment::fit::FitForm;
use bikedyn_runtime::experiment::KickFit;
use plotters::prelude::*;
use std::path::Path;

const MEASURED: RGBColor = RGBColor(90, 90, 90);
const FITTED: RGBColor = RGBColor(213, 94, 0);
const REAL: RGBColor = RGBColor(0, 114, 178);
const IMAG: RGBColor = RGBColor(0, 158, 115);

fn font_ready() -> Result<(), PlotError> {
    use_font(find_font()?)
}

fn drawing(path: &Path, e: impl std::fmt::Display) -> PlotError {
    PlotError::Drawing {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

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

/// Measured roll (deg) or roll rate (deg/s, for roll-rate fits) with the
/// reported fit, over the window, and the speed below.
pub fn plot_response(path: &Path, k: &KickFit) -> Result<(), PlotError> {
    let s = &k.samples;
    if s.t.is_empty() {
        return Err(PlotError::NoData {
            path: path.to_path_buf(),
        });
    }
    font_ready()?;
    let fit = k.chosen_fit();
    let on_rate = fit.is_some_and(|f| matches!(f.form, FitForm::RollRate | FitForm::SpeedVaryingRollRate));
    let y: Vec<f64> = if on_rate { &s.roll_rate } else { &s.roll }
        .iter()
        .map(|v| v.to_degrees())
        .collect();
    let fitted: Vec<f64> = match fit {
        Some(f) => f.evaluate(&s.t).iter().map(|v| v.to_degrees()).collect(),
        None => Vec::new(),
    };
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 620)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| drawing(path, e))?;
        let (top, bottom) = root.split_vertically(420);
        let (x0, x1) = (s.t[0], s.t[s.t.len() - 1]);
        let (y0, y1) = range(y.iter().chain(fitted.iter()).copied());
        let title = match fit {
            Some(f) => format!(
                "{} kick {:.2} s: {:.3} {:+.3} i (r2 {:.4}, {})",
                k.run
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                k.kick_time,
                f.eigenvalue[0],
                f.eigenvalue[1],
                f.r2,
                f.form.name()
            ),
            None => format!("kick {:.2} s: no fit", k.kick_time),
        };
        let mut c = ChartBuilder::on(&top)
            .caption(title, ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, y0..y1)
            .map_err(|e| drawing(path, e))?;
        c.configure_mesh()
            .y_desc(if on_rate { "roll rate (deg/s)" } else { "roll (deg)" })
            .draw()
            .map_err(|e| drawing(path, e))?;
        c.draw_series(
            s.t.iter()
                .zip(&y)
                .map(|(a, b)| Circle::new((*a, *b), 2, MEASURED.filled())),
        )
        .map_err(|e| drawing(path, e))?
        .label("measured")
        .legend(|(x, y)| Circle::new((x + 8, y), 3, MEASURED.filled()));
        if !fitted.is_empty() {
            c.draw_series(LineSeries::new(
                s.t.iter().zip(&fitted).map(|(a, b)| (*a, *b)),
                FITTED.stroke_width(2),
            ))
            .map_err(|e| drawing(path, e))?
            .label("fit")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], FITTED.stroke_width(2)));
        }
        c.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(|e| drawing(path, e))?;
        let (v0, v1) = range(s.speed.iter().copied());
        let mut c2 = ChartBuilder::on(&bottom)
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(x0..x1, v0..v1)
            .map_err(|e| drawing(path, e))?;
        c2.configure_mesh()
            .x_desc("time (s)")
            .y_desc("speed (m/s)")
            .draw()
            .map_err(|e| drawing(path, e))?;
        c2.draw_series(LineSeries::new(
            s.t.iter()
                .zip(&s.speed)
                .filter(|(_, v)| v.is_finite())
                .map(|(a, b)| (*a, *b)),
            REAL.stroke_width(2),
        ))
        .map_err(|e| drawing(path, e))?;
        root.present().map_err(|e| drawing(path, e))?;
    }
    write_string_atomic(path, &svg)?;
    Ok(())
}

/// The model's weave eigenvalue (real and imaginary parts) over speed, and
/// each measured eigenvalue as a segment over its speed interval with error
/// bars (one standard error) at its mean speed.
pub fn plot_measured_continuation(path: &Path, c: &dyn LinearBicycle, kicks: &[&KickFit]) -> Result<(), PlotError> {
    font_ready()?;
    let vmax = kicks
        .iter()
        .map(|k| k.speed_interval[1])
        .filter(|v| v.is_finite())
        .fold(8.0f64, f64::max)
        + 1.0;
    let speeds: Vec<f64> = (0..=400).map(|i| vmax * i as f64 / 400.0).collect();
    let sweep = eigen_sweep_of(c, &speeds).map_err(|e| drawing(path, e))?;
    let mut re = Vec::new();
    let mut im = Vec::new();
    for p in &sweep.points {
        for k in 0..4 {
            if p.modes[k] == Mode::Weave && p.eigenvalues[k].im > 0.0 {
                re.push((p.v, p.eigenvalues[k].re));
                im.push((p.v, p.eigenvalues[k].im));
            }
        }
    }
    let meas: Vec<_> = kicks.iter().filter_map(|k| k.chosen_fit().map(|f| (k, f))).collect();
    let (y0, y1) = range(
        re.iter()
            .chain(im.iter())
            .map(|p| p.1)
            .chain(meas.iter().flat_map(|(_, f)| f.eigenvalue)),
    );
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (900, 620)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| drawing(path, e))?;
        let mut ch = ChartBuilder::on(&root)
            .caption("weave eigenvalue: model and measured", ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..vmax, y0.max(-15.0)..y1.min(15.0))
            .map_err(|e| drawing(path, e))?;
        ch.configure_mesh()
            .x_desc("speed (m/s)")
            .y_desc("eigenvalue (1/s)")
            .draw()
            .map_err(|e| drawing(path, e))?;
        ch.draw_series(LineSeries::new(re.clone(), REAL.stroke_width(2)))
            .map_err(|e| drawing(path, e))?
            .label("model, real part")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], REAL.stroke_width(2)));
        ch.draw_series(LineSeries::new(im.clone(), IMAG.stroke_width(2)))
            .map_err(|e| drawing(path, e))?
            .label("model, imaginary part")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 16, y)], IMAG.stroke_width(2)));
        for (k, f) in &meas {
            let [lo, hi] = k.speed_interval;
            for (val, se, col) in [
                (f.eigenvalue[0], f.eigenvalue_stderr[0], REAL),
                (f.eigenvalue[1], f.eigenvalue_stderr[1], IMAG),
            ] {
                ch.draw_series(std::iter::once(PathElement::new(
                    vec![(lo, val), (hi, val)],
                    col.stroke_width(3),
                )))
                .map_err(|e| drawing(path, e))?;
                ch.draw_series(std::iter::once(PathElement::new(
                    vec![(k.mean_speed, val - se), (k.mean_speed, val + se)],
                    BLACK.stroke_width(1),
                )))
                .map_err(|e| drawing(path, e))?;
            }
        }
        ch.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(|e| drawing(path, e))?;
        root.present().map_err(|e| drawing(path, e))?;
    }
    write_string_atomic(path, &svg)?;
    Ok(())
}
