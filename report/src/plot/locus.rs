//! The views of the linear modes users know from bicycleparameters: the
//! root locus (every eigenvalue in the complex plane, coloured by speed,
//! with a colour bar) and the mode shapes at one speed (roll and steer of
//! each mode as phasors: amplitude and phase).

use std::path::Path;

use nalgebra::Complex;
use plotters::prelude::*;

use super::style::{self, Area, Frame, Stroke};
use super::{
    de, mode_class, padded, render, tick, viridis, DrawErr, Figure, ImageFormat, PlotError, PlotOptions, CLASS_COLORS,
};
use bikedyn_runtime::eigen::{EigenPoint, EigenSweep};

struct RootLocus<'a> {
    sweep: &'a EigenSweep,
    vrange: (f64, f64),
    xr: (f64, f64),
    yr: (f64, f64),
}

/// Draw the root locus of `sweep` to `path`: the four eigenvalues at each
/// speed as points in the complex plane (real part across, imaginary part
/// up), coloured by speed, with a colour bar, the imaginary axis (the
/// stability boundary) and the real axis.
pub fn plot_root_locus(path: impl AsRef<Path>, sweep: &EigenSweep, opts: &PlotOptions) -> Result<(), PlotError> {
    let path = path.as_ref();
    ImageFormat::from_path(path)?;
    opts.check(path)?;
    let pts: Vec<Complex<f64>> = sweep
        .points
        .iter()
        .flat_map(|p| p.eigenvalues)
        .filter(|s| s.re.is_finite() && s.im.is_finite())
        .collect();
    if pts.is_empty() {
        return Err(PlotError::NoData {
            path: path.to_path_buf(),
        });
    }
    let fold = |f: &dyn Fn(&Complex<f64>) -> f64| {
        pts.iter()
            .map(f)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(v), h.max(v)))
    };
    let (rlo, rhi) = fold(&|s| s.re);
    let (_, ihi) = fold(&|s| s.im.abs());
    let xr = opts.x_range.unwrap_or_else(|| padded(rlo.min(0.0), rhi.max(0.0), 0.05));
    let yr = opts
        .y_range
        .unwrap_or_else(|| padded(-ihi.max(1.0), ihi.max(1.0), 0.05));
    let vs = sweep.points.iter().map(|p| p.v);
    let vrange = (
        vs.clone().fold(f64::INFINITY, f64::min),
        vs.fold(f64::NEG_INFINITY, f64::max),
    );
    let vrange = if vrange.1 > vrange.0 {
        vrange
    } else {
        padded(vrange.0, vrange.1, 0.0)
    };
    render(path, opts, &RootLocus { sweep, vrange, xr, yr })
}

impl Figure for RootLocus<'_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        root.fill(&WHITE).map_err(de)?;
        let area = style::titled(root, o, "root locus: eigenvalues coloured by speed")?;
        let (w, _) = area.dim_in_pixel();
        let bar_w = o.pxi(110.0).min(w as i32 / 4);
        let (main, side) = area.split_horizontally(w as i32 - bar_w);
        let (xr, yr) = (self.xr, self.yr);
        let mut chart = style::chart(&main, o, xr, yr, Frame::default())?;
        let xl = o.x_label.clone().unwrap_or_else(|| "real part (1/s)".into());
        let yl = o.y_label.clone().unwrap_or_else(|| "imaginary part (rad/s)".into());
        style::mesh(&mut chart, o, &xl, &yl)?;
        if xr.0 < 0.0 && xr.1 > 0.0 {
            style::vline(&mut chart, o, 0.0, BLACK)?;
        }
        if yr.0 < 0.0 && yr.1 > 0.0 {
            style::hline(&mut chart, o, 0.0)?;
        }
        let (v0, v1) = self.vrange;
        let r = o.pxu(2.5);
        for p in &self.sweep.points {
            let c = viridis((p.v - v0) / (v1 - v0));
            chart
                .draw_series(
                    p.eigenvalues
                        .iter()
                        .filter(|s| s.re >= xr.0 && s.re <= xr.1 && s.im >= yr.0 && s.im <= yr.1)
                        .map(|s| Circle::new((s.re, s.im), r, c.filled())),
                )
                .map_err(de)?;
        }
        style::frame(&mut chart, o)?;
        // Colour bar beside the plot, as tall as it.
        let plot = chart.plotting_area().get_pixel_range();
        let side_y0 = side.get_pixel_range().1.start;
        let bar = side.margin((plot.1.start - side_y0).max(0) as u32, 0, 0, 0);
        let bar = bar.shrink(
            (o.pxi(10.0), 0),
            (
                (bar_w - o.pxi(14.0)).max(10) as u32,
                (plot.1.end - plot.1.start).max(10) as u32,
            ),
        );
        let mut cb = ChartBuilder::on(&bar)
            .right_y_label_area_size((bar_w - o.pxi(14.0) - o.pxi(22.0)).max(10) as u32)
            .build_cartesian_2d(0.0..1.0, v0..v1)
            .map_err(de)?;
        let steps = 128;
        cb.draw_series((0..steps).map(|k| {
            let a = v0 + (v1 - v0) * k as f64 / steps as f64;
            let b = v0 + (v1 - v0) * (k + 1) as f64 / steps as f64;
            Rectangle::new([(0.0, a), (1.0, b)], viridis((k as f64 + 0.5) / steps as f64).filled())
        }))
        .map_err(de)?;
        cb.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .axis_style(BLACK.stroke_width(o.pxu(1.0)))
            .set_all_tick_mark_size(o.pxi(4.0))
            .y_labels(8)
            .y_label_formatter(&|v| tick(*v))
            .label_style(o.font(0.85))
            .axis_desc_style(o.font(0.95))
            .y_desc("forward speed v (m/s)")
            .draw()
            .map_err(de)?;
        Ok(())
    }
}

/// Roll and steer of one mode as phasors: amplitudes relative to the
/// larger, phases relative to the larger (degrees).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModeShape {
    /// Index of the eigenvalue in the [`EigenPoint`].
    pub index: usize,
    /// The eigenvalue (1/s).
    pub eigenvalue: Complex<f64>,
    /// `[roll, steer]` as complex numbers, the larger of unit modulus and
    /// real positive.
    pub phasors: [Complex<f64>; 2],
}

/// The mode shapes of an eigen point, one per mode (a complex pair once,
/// by its eigenvalue of positive imaginary part).
pub fn mode_shapes(p: &EigenPoint) -> Vec<ModeShape> {
    (0..4)
        .filter(|&k| p.eigenvalues[k].im >= 0.0)
        .map(|k| {
            let (r, s) = (p.eigenvectors[k][0], p.eigenvectors[k][1]);
            let big = if r.norm() >= s.norm() { r } else { s };
            let n = if big.norm() > 0.0 {
                big.conj() / big.norm() / big.norm()
            } else {
                Complex::new(1.0, 0.0)
            };
            ModeShape {
                index: k,
                eigenvalue: p.eigenvalues[k],
                phasors: [r * n, s * n],
            }
        })
        .collect()
}

struct ModeShapes<'a> {
    point: &'a EigenPoint,
    shapes: Vec<ModeShape>,
}

/// Draw the mode shapes at the speed of `point` to `path`: per mode, a
/// phasor diagram of roll (blue) and steer (vermilion) on the unit circle,
/// with each amplitude and phase written beside it and the eigenvalue as
/// the panel's title.
pub fn plot_mode_shapes(path: impl AsRef<Path>, point: &EigenPoint, opts: &PlotOptions) -> Result<(), PlotError> {
    let path = path.as_ref();
    ImageFormat::from_path(path)?;
    opts.check(path)?;
    let shapes = mode_shapes(point);
    if shapes.is_empty() {
        return Err(PlotError::NoData {
            path: path.to_path_buf(),
        });
    }
    render(path, opts, &ModeShapes { point, shapes })
}

fn eigenvalue_text(s: Complex<f64>) -> String {
    if s.im == 0.0 {
        format!("{:.3} 1/s", s.re)
    } else {
        format!("{:.3} ± {:.3}i 1/s", s.re, s.im.abs())
    }
}

impl Figure for ModeShapes<'_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        root.fill(&WHITE).map_err(de)?;
        let area = style::titled(
            root,
            o,
            &format!("mode shapes at v = {} m/s (roll and steer phasors)", tick(self.point.v)),
        )?;
        let n = self.shapes.len();
        let (rows, cols) = if n <= 2 { (1, n) } else { (n.div_ceil(2), 2) };
        let panels = area.split_evenly((rows, cols));
        for (panel, m) in panels.iter().zip(&self.shapes) {
            let mode = self.point.modes[m.index];
            let color = CLASS_COLORS[mode_class(mode)];
            let (pw, _) = panel.dim_in_pixel();
            let head = format!("{}: {}", mode.name(), eigenvalue_text(m.eigenvalue));
            panel
                .draw(&Text::new(head, (o.pxi(12.0), o.pxi(6.0)), o.font(0.95).color(&color)))
                .map_err(de)?;
            let body = panel.margin(o.pxu(o.font_size * 1.6), 0, 0, 0);
            let (bw, bh) = body.dim_in_pixel();
            let text_w = (pw as f64 * 0.45) as u32;
            let (dial, text) = body.split_horizontally(bw.saturating_sub(text_w).max(bh.min(bw / 2)));
            let (dw, dh) = dial.dim_in_pixel();
            // Equal scales on both axes: the dial's range follows its shape.
            let side = dw.min(dh).max(1) as f64;
            let (hx, hy) = (1.25 * dw as f64 / side, 1.25 * dh as f64 / side);
            let mut chart = ChartBuilder::on(&dial)
                .margin(o.pxu(6.0))
                .build_cartesian_2d(-hx..hx, -hy..hy)
                .map_err(de)?;
            let circle: Vec<(f64, f64)> = (0..=120)
                .map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / 120.0;
                    (a.cos(), a.sin())
                })
                .collect();
            style::curve(&mut chart, o, &circle, Stroke::solid(style::GRID).width(0.6))?;
            style::curve(
                &mut chart,
                o,
                &[(-1.1, 0.0), (1.1, 0.0)],
                Stroke::solid(style::GRID).width(0.6),
            )?;
            style::curve(
                &mut chart,
                o,
                &[(0.0, -1.1), (0.0, 1.1)],
                Stroke::solid(style::GRID).width(0.6),
            )?;
            let mut lines = Vec::new();
            for (z, name, c) in [
                (m.phasors[0], "roll", style::BLUE),
                (m.phasors[1], "steer", style::VERMILION),
            ] {
                let (x, y) = (z.re, z.im);
                style::curve(&mut chart, o, &[(0.0, 0.0), (x, y)], Stroke::solid(c).width(1.3))?;
                // Arrow head.
                let len = z.norm();
                if len > 0.05 {
                    let (ux, uy) = (x / len, y / len);
                    let h = 0.12;
                    let head = vec![
                        (x, y),
                        (x - h * ux + 0.5 * h * uy, y - h * uy - 0.5 * h * ux),
                        (x - h * ux - 0.5 * h * uy, y - h * uy + 0.5 * h * ux),
                    ];
                    chart
                        .draw_series(std::iter::once(Polygon::new(head, c.filled())))
                        .map_err(de)?;
                }
                let phase = format!("{:+.0}", z.arg().to_degrees());
                let phase = if phase == "-0" || phase == "+0" {
                    "0".into()
                } else {
                    phase
                };
                lines.push((format!("{name}: amplitude {len:.3}"), c));
                lines.push((format!("    phase {phase}°"), c));
            }
            let (_, th) = text.dim_in_pixel();
            let row = o.pxi(o.font_size * 1.25);
            for (k, (l, c)) in lines.iter().enumerate() {
                text.draw(&Text::new(
                    l.clone(),
                    (0, (th / 2) as i32 + (k as i32 - 2) * row),
                    o.font(0.8).color(c),
                ))
                .map_err(de)?;
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bikedyn_runtime::eigen::Mode;

    #[test]
    fn mode_shapes_normalise_to_the_larger_component() {
        let c = |a: f64, b: f64| Complex::new(a, b);
        let p = EigenPoint {
            v: 5.0,
            eigenvalues: [c(-1.0, 4.0), c(-1.0, -4.0), c(-2.0, 0.0), c(-10.0, 0.0)],
            modes: [Mode::Weave, Mode::Weave, Mode::Capsize, Mode::Castering],
            eigenvectors: [
                [c(0.0, 0.5), c(0.25, 0.0), c(0.0, 0.0), c(0.0, 0.0)],
                [c(0.0, -0.5), c(0.25, 0.0), c(0.0, 0.0), c(0.0, 0.0)],
                [c(1.0, 0.0), c(0.1, 0.0), c(0.0, 0.0), c(0.0, 0.0)],
                [c(0.1, 0.0), c(-2.0, 0.0), c(0.0, 0.0), c(0.0, 0.0)],
            ],
            extra_eigenvalues: Vec::new(),
        };
        let s = mode_shapes(&p);
        // The pair once, then the two real modes.
        assert_eq!(s.iter().map(|m| m.index).collect::<Vec<_>>(), vec![0, 2, 3]);
        // Weave: roll larger, made real; steer half as large, 90 deg behind.
        assert!((s[0].phasors[0] - c(1.0, 0.0)).norm() < 1e-12);
        assert!((s[0].phasors[1] - c(0.0, -0.5)).norm() < 1e-12);
        // Castering: steer larger; roll in antiphase.
        assert!((s[2].phasors[1] - c(1.0, 0.0)).norm() < 1e-12);
        assert!((s[2].phasors[0] - c(-0.05, 0.0)).norm() < 1e-12);
    }
}
