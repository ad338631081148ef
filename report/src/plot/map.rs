//! Two-parameter stability maps: a heat map of a quantity (stable range
//! width, weave or capsize speed, least stable real part) over a grid of
//! two parameters, with its colour bar, the sequential (viridis, also the
//! root locus's) and diverging colour maps and the zero contour of a signed
//! quantity.
//!
//! Apart because the map's cells, colour scales and contour have nothing
//! in common with the curve figures but the shared options and style.

use std::path::Path;

use plotters::prelude::*;

use super::style::{self, Area, Stroke};
use super::{
    de, label_area_width, padded, render, tick, widest_tick, DrawErr, Figure, ImageFormat, PlotError, PlotOptions,
};
use bikedyn_runtime::sweep::{MapQuantity, StabilityMap};

const MISSING: RGBColor = RGBColor(200, 200, 200);
const FAILED: RGBColor = RGBColor(120, 120, 120);

/// The colour at `t` in `[0, 1]` of a map given by evenly spaced stops,
/// each channel interpolated linearly between the two stops around it.
fn interpolate(stops: &[(u8, u8, u8)], t: f64) -> RGBColor {
    let s = t * (stops.len() - 1) as f64;
    let k = (s.floor() as usize).min(stops.len() - 2);
    let f = s - k as f64;
    let lerp = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    RGBColor(
        lerp(stops[k].0, stops[k + 1].0),
        lerp(stops[k].1, stops[k + 1].1),
        lerp(stops[k].2, stops[k + 1].2),
    )
}

/// Viridis colour map (matplotlib), `t` in `[0, 1]`.
pub(crate) fn viridis(t: f64) -> RGBColor {
    const C: [(u8, u8, u8); 9] = [
        (68, 1, 84),
        (72, 40, 120),
        (62, 73, 137),
        (49, 104, 142),
        (38, 130, 142),
        (31, 158, 137),
        (53, 183, 121),
        (110, 206, 88),
        (253, 231, 37),
    ];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 };
    interpolate(&C, t)
}

/// Cell edges of a (sorted or unsorted) axis: midpoints between neighbours.
fn cell_edges(values: &[f64]) -> Vec<(f64, f64)> {
    let n = values.len();
    (0..n)
        .map(|k| {
            let v = values[k];
            let lo = if k > 0 {
                0.5 * (values[k - 1] + v)
            } else if n > 1 {
                v - 0.5 * (values[1] - v)
            } else {
                v - 0.5
            };
            let hi = if k + 1 < n {
                0.5 * (v + values[k + 1])
            } else if n > 1 {
                v + 0.5 * (v - values[k - 1])
            } else {
                v + 0.5
            };
            (lo.min(hi), lo.max(hi))
        })
        .collect()
}

fn missing_label(q: MapQuantity) -> &'static str {
    match q {
        MapQuantity::StableWidth => "not self-stable",
        MapQuantity::WeaveSpeed => "no weave speed",
        MapQuantity::CapsizeSpeed => "no capsize speed",
        MapQuantity::LeastStableRealPart => "no probe speed",
    }
}

struct MapFigure<'a> {
    map: &'a StabilityMap,
    quantity: MapQuantity,
    probe_speed: Option<f64>,
    vrange: (f64, f64),
    signed: bool,
}

/// Diverging colour map (ColorBrewer RdBu, reversed): `t = 0` blue
/// (negative: stable), `t = 0.5` white (zero), `t = 1` red (positive).
pub(crate) fn diverging(t: f64) -> RGBColor {
    const C: [(u8, u8, u8); 9] = [
        (33, 102, 172),
        (67, 147, 195),
        (146, 197, 222),
        (209, 229, 240),
        (247, 247, 247),
        (253, 219, 199),
        (244, 165, 130),
        (214, 96, 77),
        (178, 24, 43),
    ];
    let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.5 };
    interpolate(&C, t)
}

/// The zero contour of `f` over a grid (marching squares on the cell
/// centres `xs x ys`; `f(i, j)` is `None` where the value is missing):
/// line segments, linear interpolation along the square's edges.
pub(crate) fn zero_contour(xs: &[f64], ys: &[f64], f: impl Fn(usize, usize) -> Option<f64>) -> Vec<[(f64, f64); 2]> {
    let mut out = Vec::new();
    if xs.len() < 2 || ys.len() < 2 {
        return out;
    }
    for i in 0..xs.len() - 1 {
        for j in 0..ys.len() - 1 {
            let c = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            let v: Option<Vec<f64>> = c.iter().map(|&(a, b)| f(a, b)).collect();
            let Some(v) = v else { continue };
            let p = |k: usize| (xs[c[k].0], ys[c[k].1]);
            let mut cuts = Vec::new();
            for k in 0..4 {
                let (a, b) = (v[k], v[(k + 1) % 4]);
                if (a < 0.0) != (b < 0.0) {
                    let t = a / (a - b);
                    let (pa, pb) = (p(k), p((k + 1) % 4));
                    cuts.push((pa.0 + t * (pb.0 - pa.0), pa.1 + t * (pb.1 - pa.1)));
                }
            }
            match cuts.len() {
                2 => out.push([cuts[0], cuts[1]]),
                4 => {
                    // Saddle: pair the cuts by the sign of the centre.
                    let centre = v.iter().sum::<f64>() / 4.0;
                    if (centre < 0.0) == (v[0] < 0.0) {
                        out.push([cuts[0], cuts[3]]);
                        out.push([cuts[1], cuts[2]]);
                    } else {
                        out.push([cuts[0], cuts[1]]);
                        out.push([cuts[2], cuts[3]]);
                    }
                }
                _ => {}
            }
        }
    }
    out
}

/// Draw a heat map of `quantity` over the grid of `map` with a colour bar to
/// `path` (`.svg` or `.png`). Cells without the quantity (e.g. never
/// self-stable) are light grey, failed cells dark grey. A signed quantity
/// (the real part of the least stable eigenvalue at `probe_speed`) is drawn
/// in a diverging colour map centred on zero (blue stable, red unstable)
/// with its zero contour; the figure says the speed it was made at (the
/// probe speed, or the range of speeds searched).
pub fn plot_stability_map(
    path: impl AsRef<Path>,
    map: &StabilityMap,
    quantity: MapQuantity,
    probe_speed: Option<f64>,
    opts: &PlotOptions,
) -> Result<(), PlotError> {
    let path = path.as_ref();
    ImageFormat::from_path(path)?;
    opts.check(path)?;
    let (nx, ny) = map.shape();
    if nx == 0 || ny == 0 || map.cells.len() != nx * ny {
        return Err(PlotError::NoData {
            path: path.to_path_buf(),
        });
    }
    if map.x.values.iter().chain(&map.y.values).any(|v| !v.is_finite()) {
        return Err(PlotError::InvalidOptions {
            path: path.to_path_buf(),
            message: "non-finite grid value".into(),
        });
    }
    let vals: Vec<f64> = map.cells.iter().filter_map(|c| quantity.value(c)).collect();
    let (mut lo, hi) = vals
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
    let signed = quantity == MapQuantity::LeastStableRealPart;
    if quantity == MapQuantity::StableWidth {
        lo = 0.0;
    }
    let vrange = if vals.is_empty() {
        (0.0, 1.0)
    } else if signed {
        let m = lo.abs().max(hi.abs());
        if m > 0.0 {
            (-m, m)
        } else {
            (-1.0, 1.0)
        }
    } else if hi - lo > 1e-12 * hi.abs().max(1.0) {
        (lo, hi)
    } else {
        padded(lo, hi, 0.0)
    };
    render(
        path,
        opts,
        &MapFigure {
            map,
            quantity,
            probe_speed,
            vrange,
            signed,
        },
    )
}

impl MapFigure<'_> {
    fn color(&self, v: f64) -> RGBColor {
        let (lo, hi) = self.vrange;
        let t = (v - lo) / (hi - lo);
        if self.signed {
            diverging(t)
        } else {
            viridis(t)
        }
    }

    /// Colour-bar label, with the speed the map was made at.
    fn bar_label(&self) -> String {
        match (self.quantity, self.probe_speed) {
            (MapQuantity::LeastStableRealPart, Some(v)) => {
                format!("largest real part at v = {} m/s (1/s)", tick(v))
            }
            (q, _) => q.label().to_string(),
        }
    }

    fn default_title(&self) -> String {
        let [a, b] = self.map.speed_range;
        match (self.quantity, self.probe_speed) {
            (MapQuantity::LeastStableRealPart, Some(v)) => {
                format!("least stable eigenvalue's real part at v = {} m/s", tick(v))
            }
            (q, _) => format!(
                "{} (speeds {}-{} m/s searched)",
                q.label().split(" (").next().unwrap_or(""),
                tick(a),
                tick(b)
            ),
        }
    }
}

impl Figure for MapFigure<'_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        let m = self.map;
        root.fill(&WHITE).map_err(de)?;
        let area = style::titled(root, o, &self.default_title())?;
        let (w, _) = area.dim_in_pixel();
        let (vlo, vhi) = self.vrange;
        let any_missing = m.cells.iter().any(|c| c.is_ok() && self.quantity.value(c).is_none());
        let any_failed = m.cells.iter().any(|c| c.is_err());
        // Colour-bar column: bar, tick labels, rotated description; wide enough
        // for the grey-patch labels below it.
        let bar_x = o.pxi(14.0);
        let bar_w = o.pxi(22.0);
        let tick_font = o.font(0.85);
        let tick_w = widest_tick(root, &tick_font, (vlo, vhi), 8) as i32;
        let label_area = tick_w + o.pxi(10.0) + o.pxi(o.font_size * 0.95 * 1.25);
        let patch_font = o.font(0.8);
        let patch_text = [(any_missing, missing_label(self.quantity)), (any_failed, "failed")]
            .iter()
            .filter(|(show, _)| *show)
            .map(|(_, t)| root.estimate_text_size(t, &patch_font).map(|d| d.0 as i32).unwrap_or(0))
            .max()
            .map(|t| bar_w + o.pxi(6.0) + t)
            .unwrap_or(0);
        let cb_w = (bar_x + (bar_w + label_area).max(patch_text) + o.pxi(12.0)).min(w as i32 / 3);
        let (main, side) = area.split_horizontally(w as i32 - cb_w);

        let xe = cell_edges(&m.x.values);
        let ye = cell_edges(&m.y.values);
        let xr = o.x_range.unwrap_or_else(|| {
            (
                xe.iter().map(|e| e.0).fold(f64::INFINITY, f64::min),
                xe.iter().map(|e| e.1).fold(f64::NEG_INFINITY, f64::max),
            )
        });
        let yr = o.y_range.unwrap_or_else(|| {
            (
                ye.iter().map(|e| e.0).fold(f64::INFINITY, f64::min),
                ye.iter().map(|e| e.1).fold(f64::NEG_INFINITY, f64::max),
            )
        });
        let mut chart = ChartBuilder::on(&main)
            .margin_top(o.pxu(18.0))
            .margin_right(o.pxu(10.0))
            .margin_left(o.pxu(10.0))
            .margin_bottom(o.pxu(10.0))
            .x_label_area_size(o.pxu(o.font_size * 3.4))
            .y_label_area_size(label_area_width(root, o, yr, 10))
            .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
            .map_err(de)?;
        let (nx, ny) = m.shape();
        let mut rects = Vec::with_capacity(nx * ny);
        for i in 0..nx {
            for j in 0..ny {
                let Some(c) = m.cell(i, j) else { continue };
                let color = match (c, self.quantity.value(c)) {
                    (Err(_), _) => FAILED,
                    (Ok(_), None) => MISSING,
                    (Ok(_), Some(v)) => self.color(v),
                };
                let (x0, x1) = (xe[i].0.max(xr.0), xe[i].1.min(xr.1));
                let (y0, y1) = (ye[j].0.max(yr.0), ye[j].1.min(yr.1));
                if x1 > x0 && y1 > y0 {
                    rects.push(Rectangle::new([(x0, y0), (x1, y1)], color.filled()));
                }
            }
        }
        chart.draw_series(rects).map_err(de)?;
        // Cells whose self-stable range reaches the upper speed limit: the
        // range is cut there (its width is a lower bound); marked with a
        // small open circle.
        let mut cut = Vec::new();
        for i in 0..nx {
            for j in 0..ny {
                if let Some(Ok(s)) = m.cell(i, j) {
                    let (xc, yc) = (m.x.values[i], m.y.values[j]);
                    if s.open_ended && xc >= xr.0 && xc <= xr.1 && yc >= yr.0 && yc <= yr.1 {
                        cut.push(Circle::new((xc, yc), o.pxu(3.0), WHITE.stroke_width(o.pxu(1.0))));
                    }
                }
            }
        }
        let any_cut = !cut.is_empty();
        chart.draw_series(cut).map_err(de)?;
        // The zero contour of a signed quantity (stable on its blue side).
        let mut contour = false;
        if self.signed {
            let (xs, ys) = (&m.x.values, &m.y.values);
            for [a, b] in zero_contour(xs, ys, |i, j| m.cell(i, j).and_then(|c| self.quantity.value(c))) {
                contour = true;
                style::curve(&mut chart, o, &[a, b], Stroke::solid(BLACK))?;
            }
        }
        let notes: Vec<&str> = [
            (contour, "black line: real part = 0"),
            (any_cut, "o: stable up to the speed limit (range cut there)"),
        ]
        .iter()
        .filter(|n| n.0)
        .map(|n| n.1)
        .collect();
        if !notes.is_empty() {
            main.draw_text(&notes.join("; "), &o.font(0.8), (o.pxi(12.0), o.pxi(2.0)))
                .map_err(de)?;
        }
        let xl = o.x_label.clone().unwrap_or_else(|| m.x.name.clone());
        let yl = o.y_label.clone().unwrap_or_else(|| m.y.name.clone());
        chart
            .configure_mesh()
            .disable_mesh()
            .axis_style(BLACK.stroke_width(o.pxu(1.0)))
            .set_all_tick_mark_size(o.pxi(5.0))
            .x_labels(10)
            .y_labels(10)
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .label_style(o.font(0.9))
            .axis_desc_style(o.font(1.0))
            .x_desc(xl)
            .y_desc(yl)
            .draw()
            .map_err(de)?;
        // Frame around the map.
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [(xr.0, yr.0), (xr.1, yr.1)],
                BLACK.stroke_width(o.pxu(1.0)),
            )))
            .map_err(de)?;

        // Colour bar, aligned with the plotting area.
        let plot = chart.plotting_area().get_pixel_range();
        let (side_x0, side_y0) = {
            let r = side.get_pixel_range();
            (r.0.start, r.1.start)
        };
        let patches = any_missing as i32 + any_failed as i32;
        let patch_h = o.pxi(o.font_size * 1.5);
        let bar_top = plot.1.start - side_y0;
        let bar_bottom = plot.1.end - side_y0 - patches * patch_h - if patches > 0 { o.pxi(8.0) } else { 0 };
        let bar = side.margin(bar_top.max(0) as u32, 0, 0, 0);
        let bar = bar.shrink(
            (bar_x, 0),
            ((bar_w + label_area) as u32, (bar_bottom - bar_top).max(10) as u32),
        );
        let mut cb = ChartBuilder::on(&bar)
            .right_y_label_area_size(label_area as u32)
            .build_cartesian_2d(0.0..1.0, vlo..vhi)
            .map_err(de)?;
        let steps = 256;
        cb.draw_series((0..steps).map(|k| {
            let a = vlo + (vhi - vlo) * k as f64 / steps as f64;
            let b = vlo + (vhi - vlo) * (k + 1) as f64 / steps as f64;
            Rectangle::new([(0.0, a), (1.0, b)], self.color(0.5 * (a + b)).filled())
        }))
        .map_err(de)?;
        cb.configure_mesh()
            .disable_mesh()
            .disable_x_axis()
            .axis_style(BLACK.stroke_width(o.pxu(1.0)))
            .set_all_tick_mark_size(o.pxi(4.0))
            .y_labels(8)
            .y_label_formatter(&|v| tick(*v))
            .label_style(tick_font.clone())
            .axis_desc_style(o.font(0.95))
            .y_desc(self.bar_label())
            .draw()
            .map_err(de)?;
        cb.draw_series(std::iter::once(Rectangle::new(
            [(0.0, vlo), (1.0, vhi)],
            BLACK.stroke_width(o.pxu(1.0)),
        )))
        .map_err(de)?;

        // Grey patches for missing / failed cells, below the bar.
        let mut y = plot.1.end - patches * patch_h;
        let x = side_x0 + bar_x;
        for (show, color, label) in [
            (any_missing, MISSING, missing_label(self.quantity)),
            (any_failed, FAILED, "failed"),
        ] {
            if !show {
                continue;
            }
            let s = o.pxi(o.font_size * 0.9);
            root.draw(&Rectangle::new(
                [(x, y + o.pxi(2.0)), (x + bar_w, y + o.pxi(2.0) + s)],
                color.filled(),
            ))
            .map_err(de)?;
            root.draw(&Rectangle::new(
                [(x, y + o.pxi(2.0)), (x + bar_w, y + o.pxi(2.0) + s)],
                BLACK.stroke_width(o.pxu(1.0)),
            ))
            .map_err(de)?;
            root.draw(&Text::new(
                label.to_string(),
                (x + bar_w + o.pxi(6.0), y + o.pxi(2.0)),
                patch_font.clone(),
            ))
            .map_err(de)?;
            y += patch_h;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plot_cell_edges_and_colormap() {
        assert_eq!(cell_edges(&[0.0, 1.0, 3.0]), vec![(-0.5, 0.5), (0.5, 2.0), (2.0, 4.0)]);
        assert_eq!(cell_edges(&[2.0]), vec![(1.5, 2.5)]);
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(f64::NAN), RGBColor(68, 1, 84));
    }
}
