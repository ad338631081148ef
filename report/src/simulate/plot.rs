//! Time-history plot of a simulation: roll and steer (degrees) and forward
//! speed against time, in three stacked panels sharing the time axis (one
//! time label, at the bottom), with the kicks and torque pulses marked. Same
//! style, formats (`.svg`, `.png`) and atomic writing as [`crate::plot`].

use std::path::Path;

use plotters::prelude::*;

use crate::plot::style::{self, Area, Frame, Icon, Legend, Stroke};
use crate::plot::{de, label_area_width, padded, render, tick, DrawErr, Figure, PlotError, PlotOptions, DEFAULT_SIZE};

use bikedyn_runtime::simulate::{Inputs, PulseTarget, Simulation};

struct TimeHistory<'a> {
    sim: &'a Simulation,
    inputs: &'a Inputs,
    roll: Vec<f64>,
    steer: Vec<f64>,
}

/// Plot roll, steer and speed of `sim` against time to `path`, marking the
/// kicks and torque pulses of `inputs`. The default size (when `opts` gives
/// none) is 800x900. The speed axis spans the speed's own
/// variation (a constant speed is drawn in a narrow band around its value).
pub fn plot_simulation(
    path: impl AsRef<Path>,
    sim: &Simulation,
    inputs: &Inputs,
    opts: &PlotOptions,
) -> Result<(), PlotError> {
    let path = path.as_ref();
    crate::plot::ImageFormat::from_path(path)?;
    opts.check(path)?;
    use bikedyn_runtime::model::CoordinateRole as R;
    let (roll, steer) = match (sim.coordinate_of(R::Roll), sim.coordinate_of(R::Steer)) {
        (Some(r), Some(s)) if sim.t.len() >= 2 => (r, s),
        _ => {
            return Err(PlotError::NoData {
                path: path.to_path_buf(),
            })
        }
    };
    let o = opts.sized_by_default((DEFAULT_SIZE.0, 900));
    render(
        path,
        &o,
        &TimeHistory {
            sim,
            inputs,
            roll: roll.iter().map(|x| x.to_degrees()).collect(),
            steer: steer.iter().map(|x| x.to_degrees()).collect(),
        },
    )
}

/// Range of the speed panel: the speed's variation with 10 % padding, or a
/// band of ±1 % around a constant speed.
pub(crate) fn speed_range(v: &[f64]) -> (f64, f64) {
    let lo = v
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(f64::INFINITY, f64::min);
    let hi = v
        .iter()
        .copied()
        .filter(|x| x.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    let scale = lo.abs().max(hi.abs()).max(0.1);
    if hi - lo < 1e-6 * scale {
        let m = 0.5 * (lo + hi);
        return (m - 0.01 * scale, m + 0.01 * scale);
    }
    padded(lo, hi, 0.1)
}

impl Figure for TimeHistory<'_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        root.fill(&WHITE).map_err(de)?;
        let area = style::titled(root, o, "roll, steer and speed after the inputs")?;
        let panels = area.split_evenly((3, 1));
        let t = &self.sim.t;
        let xr = o.x_range.unwrap_or((t[0], *t.last().expect("two samples")));
        let series: [(&[f64], &str, RGBColor); 3] = [
            (&self.roll, "roll (deg)", style::BLUE),
            (&self.steer, "steer (deg)", style::VERMILION),
            (&self.sim.speed, "speed (m/s)", style::GREEN),
        ];
        let ranges: Vec<(f64, f64)> = series
            .iter()
            .enumerate()
            .map(|(k, (ys, _, _))| {
                if k == 2 {
                    return speed_range(ys);
                }
                if let Some(r) = o.y_range {
                    return r;
                }
                let lo = ys.iter().copied().fold(f64::INFINITY, f64::min);
                let hi = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                padded(lo.min(-1e-3), hi.max(1e-3), 0.05)
            })
            .collect();
        let label_w = ranges
            .iter()
            .map(|r| label_area_width(root, o, *r, 8))
            .max()
            .unwrap_or(0);
        // Inputs inside the time range.
        let kicks: Vec<f64> = self
            .inputs
            .kicks
            .iter()
            .map(|k| k.time)
            .filter(|t| *t >= xr.0 && *t <= xr.1)
            .collect();
        let pulses: Vec<(f64, f64, PulseTarget)> = self
            .inputs
            .pulses
            .iter()
            .map(|p| (p.start.max(xr.0), (p.start + p.duration).min(xr.1), p.target))
            .filter(|(a, b, _)| b > a)
            .collect();
        let mut legend = Legend::default();
        if !kicks.is_empty() {
            legend.add("kick", Icon::Line(Stroke::dashed(style::MARK).width(0.5)));
        }
        for (target, name, color) in [
            (PulseTarget::Roll, "roll torque pulse", style::PURPLE),
            (PulseTarget::Steer, "steer torque pulse", style::ORANGE),
        ] {
            if pulses.iter().any(|p| p.2 == target) {
                legend.add(name, Icon::Patch(color, 0.25));
            }
        }
        for (k, (panel, ((ys, label, color), yr))) in panels.iter().zip(series.iter().zip(&ranges)).enumerate() {
            let last = k == 2;
            let frame = Frame {
                x_desc: last,
                y_label_width: Some(label_w),
                ..Frame::default()
            };
            let pts: Vec<(f64, f64)> = t.iter().copied().zip(ys.iter().copied()).collect();
            let (mut chart, place) = if k == 0 {
                let (c, p, _) = style::chart_with_legend(panel, o, xr, *yr, frame, &legend, &[&pts], &[])?;
                (c, Some(p))
            } else {
                (style::chart(panel, o, xr, *yr, frame)?, None)
            };
            style::mesh(&mut chart, o, if last { "time t (s)" } else { "" }, label)?;
            for (a, b, target) in &pulses {
                let c = if *target == PulseTarget::Roll {
                    style::PURPLE
                } else {
                    style::ORANGE
                };
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(*a, yr.0), (*b, yr.1)],
                        c.mix(0.18).filled(),
                    )))
                    .map_err(de)?;
            }
            for kt in &kicks {
                style::vline(&mut chart, o, *kt, style::MARK)?;
            }
            if !last && yr.0 < 0.0 && yr.1 > 0.0 {
                style::hline(&mut chart, o, 0.0)?;
            }
            style::curve(&mut chart, o, &pts, Stroke::solid(*color))?;
            style::frame(&mut chart, o)?;
            if let Some(p) = place {
                legend.draw(root, &chart, o, p)?;
            }
        }
        let _ = tick;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn speed_axis_follows_the_variation() {
        // A speed varying by 2 cm/s gets an axis about that wide, not 0-5.
        let (lo, hi) = speed_range(&[4.99, 5.0, 5.01]);
        assert!(lo > 4.98 && hi < 5.02, "{lo} {hi}");
        // A constant speed: a narrow band around it.
        let (lo, hi) = speed_range(&[4.0; 10]);
        assert!(lo < 4.0 && hi > 4.0 && hi - lo < 0.1, "{lo} {hi}");
    }
}
