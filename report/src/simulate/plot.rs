//! Time-history plot of a simulation: roll and steer (degrees) and forward
//! speed against time, in three stacked panels sharing the time axis. Same
//! fonts, formats (`.svg`, `.png`) and atomic writing as [`crate::plot`].

use std::path::Path;

use plotters::coord::Shift;
use plotters::prelude::*;

use crate::plot::{de, padded, render, tick, DrawErr, Figure, PlotError, PlotOptions};

use bikedyn_runtime::simulate::Simulation;

struct TimeHistory<'a> {
    sim: &'a Simulation,
    opts: &'a PlotOptions,
    roll: Vec<f64>,
    steer: Vec<f64>,
}

/// Plot roll, steer and speed of `sim` against time to `path`. The default
/// size (when `opts` has the 800x600 default) is 800x900.
pub fn plot_simulation(path: impl AsRef<Path>, sim: &Simulation, opts: &PlotOptions) -> Result<(), PlotError> {
    let path = path.as_ref();
    crate::plot::ImageFormat::from_path(path)?;
    use bikedyn_runtime::model::CoordinateRole as R;
    let (roll, steer) = match (sim.coordinate_of(R::Roll), sim.coordinate_of(R::Steer)) {
        (Some(r), Some(s)) if sim.t.len() >= 2 => (r, s),
        _ => {
            return Err(PlotError::NoData {
                path: path.to_path_buf(),
            })
        }
    };
    let mut o = opts.clone();
    if o.width == 800 && o.height == 600 {
        o.height = 900;
    }
    render(
        path,
        &o,
        &TimeHistory {
            sim,
            opts: &o,
            roll: roll.iter().map(|x| x.to_degrees()).collect(),
            steer: steer.iter().map(|x| x.to_degrees()).collect(),
        },
    )
}

impl Figure for TimeHistory<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawErr> {
        let o = self.opts;
        root.fill(&WHITE).map_err(de)?;
        let root = match &o.title {
            Some(t) => root.titled(t, o.font(1.2)).map_err(de)?,
            None => root.clone(),
        };
        let panels = root.split_evenly((3, 1));
        let t = &self.sim.t;
        let xr = (t[0], *t.last().expect("two samples"));
        let series: [(&[f64], &str, RGBColor); 3] = [
            (&self.roll, "roll theta (deg)", RGBColor(31, 119, 180)),
            (&self.steer, "steer gamma (deg)", RGBColor(214, 39, 40)),
            (&self.sim.speed, "speed (m/s)", RGBColor(44, 160, 44)),
        ];
        for (k, (panel, (ys, label, color))) in panels.iter().zip(series).enumerate() {
            let lo = ys.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let yr = if k == 2 {
                padded(lo.min(0.0), hi.max(1e-3), 0.05)
            } else {
                padded(lo.min(-1e-3), hi.max(1e-3), 0.05)
            };
            let mut chart = ChartBuilder::on(panel)
                .margin_top(o.pxu(10.0))
                .margin_right(o.pxu(24.0))
                .margin_left(o.pxu(10.0))
                .x_label_area_size(o.pxu(o.font_size * 2.8))
                .y_label_area_size(o.pxu(o.font_size * 4.5))
                .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
                .map_err(de)?;
            chart
                .configure_mesh()
                .bold_line_style(RGBColor(225, 225, 225).stroke_width(o.pxu(1.0)))
                .light_line_style(TRANSPARENT)
                .axis_style(BLACK.stroke_width(o.pxu(1.0)))
                .x_labels(11)
                .y_labels(6)
                .x_label_formatter(&|v| tick(*v))
                .y_label_formatter(&|v| tick(*v))
                .label_style(o.font(0.85))
                .axis_desc_style(o.font(0.95))
                .x_desc("time t (s)")
                .y_desc(label)
                .draw()
                .map_err(de)?;
            if k < 2 {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(xr.0, 0.0), (xr.1, 0.0)],
                        BLACK.stroke_width(o.pxu(1.0)),
                    )))
                    .map_err(de)?;
            }
            chart
                .draw_series(std::iter::once(PathElement::new(
                    t.iter().copied().zip(ys.iter().copied()).collect::<Vec<_>>(),
                    color.stroke_width(o.pxu(2.0)),
                )))
                .map_err(de)?;
        }
        Ok(())
    }
}
