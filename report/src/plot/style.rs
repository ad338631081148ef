//! The one style of every figure: colours, title, axes with their grid and
//! tick labels, curves (solid real parts, dashed imaginary parts),
//! measured points with error bars, and a legend placed where it covers no
//! data. Every figure of the crate is drawn through these helpers, so they
//! share fonts, line widths, grid and legend.

use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

use super::canvas::{Canvas, Line};
use super::{clip_polyline, de, label_area_width, tick, DrawErr, PlotOptions};

/// A drawing area of a figure.
pub(crate) type Area<'b> = DrawingArea<Canvas<'b>, Shift>;

/// A chart with `f64` axes.
pub(crate) type Chart<'a, 'b> = ChartContext<'a, Canvas<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

// Okabe-Ito colours (distinguishable with colour-blindness), by role.
/// Blue: weave, model curves.
pub(crate) const BLUE: RGBColor = RGBColor(0, 114, 178);
/// Vermilion: capsize, fits, "after".
pub(crate) const VERMILION: RGBColor = RGBColor(213, 94, 0);
/// Reddish purple: castering.
pub(crate) const PURPLE: RGBColor = RGBColor(117, 112, 179);
/// Bluish green: self-stable band, speed.
pub(crate) const GREEN: RGBColor = RGBColor(0, 158, 115);
/// Sky blue.
pub(crate) const SKY: RGBColor = RGBColor(86, 180, 233);
/// Orange.
pub(crate) const ORANGE: RGBColor = RGBColor(230, 159, 0);
/// Pink (reddish purple of Okabe-Ito).
pub(crate) const PINK: RGBColor = RGBColor(204, 121, 167);
/// Dark yellow (olive), readable on white.
pub(crate) const OLIVE: RGBColor = RGBColor(150, 130, 0);
/// Measured data.
pub(crate) const DATA: RGBColor = RGBColor(40, 40, 40);
/// Unclassified curves.
pub(crate) const GREY: RGBColor = RGBColor(110, 110, 110);
/// Grid lines.
pub(crate) const GRID: RGBColor = RGBColor(225, 225, 225);
/// Markers of critical speeds, kicks and pulses.
pub(crate) const MARK: RGBColor = RGBColor(90, 90, 90);

/// Line width of curves (image pixels at scale 1).
pub(crate) const CURVE_WIDTH: f64 = 2.0;
/// Dash of imaginary parts: on, off (image pixels at scale 1).
pub(crate) const DASH: (f64, f64) = (9.0, 5.0);
/// Dash of markers (critical speeds, kicks): on, off.
pub(crate) const MARK_DASH: (f64, f64) = (5.0, 4.0);
/// Radius of measured points.
pub(crate) const POINT_RADIUS: f64 = 4.0;

impl PlotOptions {
    /// Dash lengths in canvas units.
    pub(crate) fn dash(&self, (on, off): (f64, f64)) -> Option<(u32, u32)> {
        Some((self.pxu(on), self.pxu(off)))
    }
}

/// The title of a figure whose own description is `default`: `o.title`,
/// else `o.subject` and the description.
pub(crate) fn title_text(o: &PlotOptions, default: &str) -> String {
    match (&o.title, &o.subject) {
        (Some(t), _) => t.clone(),
        (None, Some(s)) if !default.is_empty() => format!("{s}: {default}"),
        (None, Some(s)) => s.clone(),
        (None, None) => default.to_string(),
    }
}

/// Draw the title (see [`title_text`]) centred at the top of `area`,
/// smaller when it would not fit; returns the area below it.
pub(crate) fn titled<'b>(area: &Area<'b>, o: &PlotOptions, default: &str) -> Result<Area<'b>, DrawErr> {
    let text = title_text(o, default);
    let text = text.as_str();
    if text.is_empty() {
        return Ok(area.clone());
    }
    let (w, _) = area.dim_in_pixel();
    let mut rel = 1.2;
    let mut font = o.font(rel);
    while rel > 0.7 {
        let tw = area.estimate_text_size(text, &font).map_err(de)?.0;
        if tw + o.pxu(20.0) <= w {
            break;
        }
        rel -= 0.05;
        font = o.font(rel);
    }
    let h = o.pxi(o.font_size * rel * 1.25 + 14.0);
    let (top, rest) = area.split_vertically(h);
    top.draw(&Text::new(
        text.to_string(),
        ((w / 2) as i32, o.pxi(8.0)),
        font.pos(plotters::style::text_anchor::Pos::new(
            plotters::style::text_anchor::HPos::Center,
            plotters::style::text_anchor::VPos::Top,
        )),
    ))
    .map_err(de)?;
    Ok(rest)
}

/// Margins and label areas of a chart.
#[derive(Clone, Copy)]
pub(crate) struct Frame {
    /// Room for the x tick labels and description (false: ticks only, for
    /// stacked panels sharing a time axis).
    pub x_desc: bool,
    /// Extra right margin (image pixels at scale 1), e.g. for a legend
    /// outside the plot.
    pub right: f64,
    /// Extra top margin (image pixels at scale 1), e.g. for labels above
    /// the plot.
    pub top: f64,
    /// Width of the y label area in canvas units (default: from the
    /// range's tick labels); stacked panels share the widest.
    pub y_label_width: Option<u32>,
}

impl Default for Frame {
    fn default() -> Self {
        Frame {
            x_desc: true,
            right: 0.0,
            top: 0.0,
            y_label_width: None,
        }
    }
}

/// A chart over `xr x yr` on `area` with the standard margins.
pub(crate) fn chart<'a, 'b>(
    area: &'a Area<'b>,
    o: &PlotOptions,
    xr: (f64, f64),
    yr: (f64, f64),
    f: Frame,
) -> Result<Chart<'a, 'b>, DrawErr> {
    ChartBuilder::on(area)
        .margin_top(o.pxu(12.0 + f.top))
        .margin_right(o.pxu(24.0 + f.right))
        .margin_left(o.pxu(10.0))
        .margin_bottom(o.pxu(if f.x_desc { 10.0 } else { 4.0 }))
        .x_label_area_size(o.pxu(o.font_size * if f.x_desc { 3.4 } else { 1.8 }))
        .y_label_area_size(f.y_label_width.unwrap_or_else(|| label_area_width(area, o, yr, 8)))
        .build_cartesian_2d(xr.0..xr.1, yr.0..yr.1)
        .map_err(de)
}

/// Grid, ticks, tick labels and axis descriptions (`x_desc` empty: none),
/// and a frame around the plot.
pub(crate) fn mesh(chart: &mut Chart<'_, '_>, o: &PlotOptions, x_desc: &str, y_desc: &str) -> Result<(), DrawErr> {
    let mut m = chart.configure_mesh();
    m.bold_line_style(GRID.stroke_width(o.pxu(1.0)))
        .light_line_style(TRANSPARENT)
        .axis_style(BLACK.stroke_width(o.pxu(1.0)))
        .set_all_tick_mark_size(o.pxi(5.0))
        .x_labels(10)
        .y_labels(8)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(o.font(0.9))
        .axis_desc_style(o.font(1.0))
        .y_desc(y_desc);
    if !x_desc.is_empty() {
        m.x_desc(x_desc);
    }
    m.draw().map_err(de)?;
    frame(chart, o)
}

/// A frame around the plotting area.
pub(crate) fn frame(chart: &mut Chart<'_, '_>, o: &PlotOptions) -> Result<(), DrawErr> {
    let (xr, yr) = (chart.x_range(), chart.y_range());
    chart
        .draw_series(std::iter::once(Rectangle::new(
            [(xr.start, yr.start), (xr.end, yr.end)],
            BLACK.stroke_width(o.pxu(1.0)),
        )))
        .map_err(de)?;
    Ok(())
}

/// How a curve is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Stroke {
    pub color: RGBColor,
    /// Width relative to [`CURVE_WIDTH`].
    pub width: f64,
    /// Dashed (imaginary parts, markers).
    pub dashed: bool,
}

impl Stroke {
    /// A solid curve.
    pub(crate) fn solid(color: RGBColor) -> Self {
        Stroke {
            color,
            width: 1.0,
            dashed: false,
        }
    }

    /// A dashed curve.
    pub(crate) fn dashed(color: RGBColor) -> Self {
        Stroke {
            color,
            width: 1.0,
            dashed: true,
        }
    }

    /// The same stroke, `w` times the standard width.
    pub(crate) fn width(self, w: f64) -> Self {
        Stroke { width: w, ..self }
    }

    fn line<C>(&self, o: &PlotOptions, points: Vec<C>) -> Line<C> {
        Line {
            points,
            color: self.color,
            width: o.pxu(CURVE_WIDTH * self.width),
            dash: if self.dashed { o.dash(DASH) } else { None },
        }
    }
}

/// Draw a curve, clipped to the chart's ranges.
pub(crate) fn curve(chart: &mut Chart<'_, '_>, o: &PlotOptions, pts: &[(f64, f64)], s: Stroke) -> Result<(), DrawErr> {
    let (xr, yr) = (chart.x_range(), chart.y_range());
    for piece in clip_polyline(pts, (xr.start, xr.end), (yr.start, yr.end)) {
        chart.draw_series(std::iter::once(s.line(o, piece))).map_err(de)?;
    }
    Ok(())
}

/// A vertical dashed marker line at `x` over the whole height.
pub(crate) fn vline(chart: &mut Chart<'_, '_>, o: &PlotOptions, x: f64, color: RGBColor) -> Result<(), DrawErr> {
    let yr = chart.y_range();
    chart
        .draw_series(std::iter::once(Line {
            points: vec![(x, yr.start), (x, yr.end)],
            color,
            width: o.pxu(1.0),
            dash: o.dash(MARK_DASH),
        }))
        .map_err(de)?;
    Ok(())
}

/// A horizontal line at `y` (thin, solid): the zero line.
pub(crate) fn hline(chart: &mut Chart<'_, '_>, o: &PlotOptions, y: f64) -> Result<(), DrawErr> {
    let xr = chart.x_range();
    chart
        .draw_series(std::iter::once(Line {
            points: vec![(xr.start, y), (xr.end, y)],
            color: BLACK,
            width: o.pxu(1.0),
            dash: None,
        }))
        .map_err(de)?;
    Ok(())
}

/// A measured value: a filled point (with a white rim) at `(x, y)`, an
/// optional vertical error bar `y ± err` with caps and an optional
/// horizontal segment (the value's range of `x`, e.g. a speed interval).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Measured {
    pub x: f64,
    pub y: f64,
    pub err: Option<f64>,
    pub x_span: Option<(f64, f64)>,
}

/// How measured points are drawn: filled (real parts) or open (imaginary
/// parts).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Marker {
    pub color: RGBColor,
    pub open: bool,
    /// Radius relative to [`POINT_RADIUS`].
    pub size: f64,
}

impl Marker {
    /// A filled point.
    pub(crate) fn filled(color: RGBColor) -> Self {
        Marker {
            color,
            open: false,
            size: 1.0,
        }
    }

    /// An open point.
    pub(crate) fn open(color: RGBColor) -> Self {
        Marker {
            color,
            open: true,
            size: 1.0,
        }
    }

    /// The same marker, `s` times the standard size (samples of a time
    /// series: 0.6).
    pub(crate) fn size(self, s: f64) -> Self {
        Marker { size: s, ..self }
    }

    fn draw_at(&self, area: &Area<'_>, o: &PlotOptions, (x, y): (i32, i32)) -> Result<(), DrawErr> {
        let r = o.pxu(POINT_RADIUS * self.size);
        area.draw(&Circle::new((x, y), r + o.pxu(1.0), WHITE.filled()))
            .map_err(de)?;
        if self.open {
            area.draw(&Circle::new((x, y), r, self.color.stroke_width(o.pxu(1.5))))
                .map_err(de)?;
        } else {
            area.draw(&Circle::new((x, y), r, self.color.filled())).map_err(de)?;
        }
        Ok(())
    }
}

/// Draw measured values with `marker` (points drawn last, on top).
pub(crate) fn measured(
    chart: &mut Chart<'_, '_>,
    o: &PlotOptions,
    pts: &[Measured],
    marker: Marker,
) -> Result<(), DrawErr> {
    let color = marker.color;
    let (xr, yr) = (chart.x_range(), chart.y_range());
    let inside = |x: f64, y: f64| x >= xr.start && x <= xr.end && y >= yr.start && y <= yr.end;
    let thin = o.pxu(1.5);
    for m in pts {
        if let Some((a, b)) = m.x_span {
            for piece in clip_polyline(&[(a, m.y), (b, m.y)], (xr.start, xr.end), (yr.start, yr.end)) {
                chart
                    .draw_series(std::iter::once(Line {
                        points: piece,
                        color: lighten(color, 0.5),
                        width: o.pxu(3.0),
                        dash: None,
                    }))
                    .map_err(de)?;
            }
        }
        if let Some(e) = m.err.filter(|e| e.is_finite() && *e > 0.0) {
            for piece in clip_polyline(
                &[(m.x, m.y - e), (m.x, m.y + e)],
                (xr.start, xr.end),
                (yr.start, yr.end),
            ) {
                chart
                    .draw_series(std::iter::once(Line {
                        points: piece,
                        color,
                        width: thin,
                        dash: None,
                    }))
                    .map_err(de)?;
            }
            // Caps as wide as the point.
            let r = chart.plotting_area().get_pixel_range();
            let dx = o.px(POINT_RADIUS) * (xr.end - xr.start) / (r.0.end - r.0.start).max(1) as f64;
            for y in [m.y - e, m.y + e] {
                if inside(m.x, y) {
                    chart
                        .draw_series(std::iter::once(Line {
                            points: vec![(m.x - dx, y), (m.x + dx, y)],
                            color,
                            width: thin,
                            dash: None,
                        }))
                        .map_err(de)?;
                }
            }
        }
    }
    let area = chart.plotting_area().strip_coord_spec();
    let origin = {
        let r = area.get_pixel_range();
        (r.0.start, r.1.start)
    };
    for m in pts.iter().filter(|m| inside(m.x, m.y)) {
        let (x, y) = chart.backend_coord(&(m.x, m.y));
        marker.draw_at(&area, o, (x - origin.0, y - origin.1))?;
    }
    Ok(())
}

/// `c` mixed with white (`t = 0`: `c`, `t = 1`: white).
pub(crate) fn lighten(c: RGBColor, t: f64) -> RGBColor {
    let f = |x: u8| (x as f64 + t * (255.0 - x as f64)).round() as u8;
    RGBColor(f(c.0), f(c.1), f(c.2))
}

/// The symbol of a legend entry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Icon {
    /// A line (solid or dashed).
    Line(Stroke),
    /// A measured sample: the marker alone.
    Point(Marker),
    /// A measured point with its error bar.
    PointWithError(Marker),
    /// A filled patch (a shaded band).
    Patch(RGBColor, f64),
}

/// Where a legend went.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Placement {
    /// Inside the plot, top-left corner of the box at these backend pixels.
    Inside(i32, i32),
    /// Right of the plot (the chart was built with room for it).
    Outside,
    /// Not drawn.
    Hidden,
}

/// A legend: entries, then placement where it covers no data.
#[derive(Default)]
pub(crate) struct Legend {
    pub entries: Vec<(String, Icon)>,
}

impl Legend {
    /// Add an entry.
    pub(crate) fn add(&mut self, label: impl Into<String>, icon: Icon) {
        self.entries.push((label.into(), icon));
    }

    fn icon_w(o: &PlotOptions) -> i32 {
        o.pxi(30.0)
    }

    fn row_h(o: &PlotOptions) -> i32 {
        o.pxi(o.font_size * 1.3)
    }

    /// Box size in backend pixels.
    pub(crate) fn size(&self, area: &Area<'_>, o: &PlotOptions) -> (i32, i32) {
        let font = o.font(0.85);
        let text_w = self
            .entries
            .iter()
            .map(|(l, _)| area.estimate_text_size(l, &font).map(|d| d.0).unwrap_or(0))
            .max()
            .unwrap_or(0) as i32;
        (
            text_w + Self::icon_w(o) + o.pxi(22.0),
            self.entries.len() as i32 * Self::row_h(o) + o.pxi(10.0),
        )
    }

    /// Width to reserve right of the plot for a legend outside it (image
    /// pixels at scale 1).
    pub(crate) fn outside_width(&self, area: &Area<'_>, o: &PlotOptions) -> f64 {
        (self.size(area, o).0 as f64 / o.scale) + 6.0
    }

    /// The placement: `o.legend` when fixed; otherwise the candidate place
    /// inside the plot (corners, then the middles of the top and bottom
    /// edges) covering the fewest `data` pixels and no `obstacle`, or
    /// [`Placement::Outside`] when every place inside covers data.
    pub(crate) fn place(
        &self,
        chart: &Chart<'_, '_>,
        area: &Area<'_>,
        o: &PlotOptions,
        data: &[(i32, i32)],
        obstacles: &[(i32, i32, i32, i32)],
    ) -> Placement {
        use super::LegendPosition as P;
        if self.entries.is_empty() || o.legend == P::Hidden {
            return Placement::Hidden;
        }
        let (w, h) = self.size(area, o);
        let r = chart.plotting_area().get_pixel_range();
        let (x0, y0, x1, y1) = (r.0.start, r.1.start, r.0.end, r.1.end);
        let m = o.pxi(8.0);
        let ll = (x0 + m, y1 - m - h);
        let lr = (x1 - m - w, y1 - m - h);
        let ul = (x0 + m, y0 + m);
        let ur = (x1 - m - w, y0 + m);
        let fixed = match o.legend {
            P::UpperLeft => Some(ul),
            P::UpperRight => Some(ur),
            P::LowerLeft => Some(ll),
            P::LowerRight => Some(lr),
            P::Outside => return Placement::Outside,
            P::Auto | P::Hidden => None,
        };
        if let Some((x, y)) = fixed {
            return Placement::Inside(x, y);
        }
        if w + 2 * m > x1 - x0 || h + 2 * m > y1 - y0 {
            return Placement::Outside;
        }
        let cx = (x0 + x1 - w) / 2;
        let candidates = [ur, ul, lr, ll, (cx, y0 + m), (cx, y1 - m - h)];
        let pad = o.pxi(4.0);
        let mut best = (usize::MAX, ur);
        for (x, y) in candidates {
            let covered = data
                .iter()
                .filter(|p| p.0 >= x - pad && p.0 <= x + w + pad && p.1 >= y - pad && p.1 <= y + h + pad)
                .count();
            let blocked = obstacles
                .iter()
                .any(|b| b.0 < x + w && b.2 > x && b.1 < y + h && b.3 > y);
            let cost = covered + if blocked { 1_000_000 } else { 0 };
            if cost < best.0 {
                best = (cost, (x, y));
            }
        }
        if best.0 > 0 {
            return Placement::Outside;
        }
        Placement::Inside(best.1 .0, best.1 .1)
    }

    /// Draw the legend at `p` (backend pixels; `Outside`: right of the
    /// chart's plotting area, at its top).
    pub(crate) fn draw(
        &self,
        root: &Area<'_>,
        chart: &Chart<'_, '_>,
        o: &PlotOptions,
        p: Placement,
    ) -> Result<(), DrawErr> {
        let (x, y) = match p {
            Placement::Hidden => return Ok(()),
            Placement::Inside(x, y) => (x, y),
            Placement::Outside => {
                let r = chart.plotting_area().get_pixel_range();
                (r.0.end + o.pxi(12.0), r.1.start)
            }
        };
        // Backend pixels to `root`'s coordinates.
        let (ox, oy) = {
            let r = root.get_pixel_range();
            (r.0.start, r.1.start)
        };
        let (x, y) = (x - ox, y - oy);
        let (w, h) = self.size(root, o);
        root.draw(&Rectangle::new([(x, y), (x + w, y + h)], WHITE.mix(0.92).filled()))
            .map_err(de)?;
        root.draw(&Rectangle::new(
            [(x, y), (x + w, y + h)],
            RGBColor(160, 160, 160).stroke_width(o.pxu(1.0)),
        ))
        .map_err(de)?;
        let font = o.font(0.85);
        let iw = Self::icon_w(o);
        for (k, (label, icon)) in self.entries.iter().enumerate() {
            let cy = y + o.pxi(5.0) + k as i32 * Self::row_h(o) + Self::row_h(o) / 2;
            let ix = x + o.pxi(8.0);
            match icon {
                Icon::Line(s) => {
                    root.draw(&s.line(o, vec![(ix, cy), (ix + iw, cy)])).map_err(de)?;
                }
                Icon::Point(mk) => mk.draw_at(root, o, (ix + iw / 2, cy))?,
                Icon::PointWithError(mk) => {
                    let e = o.pxi(o.font_size * 0.45);
                    let mid = ix + iw / 2;
                    root.draw(&Line {
                        points: vec![(mid, cy - e), (mid, cy + e)],
                        color: mk.color,
                        width: o.pxu(1.5),
                        dash: None,
                    })
                    .map_err(de)?;
                    mk.draw_at(root, o, (mid, cy))?;
                }
                Icon::Patch(c, alpha) => {
                    let hh = o.pxi(6.0);
                    root.draw(&Rectangle::new(
                        [(ix, cy - hh), (ix + iw, cy + hh)],
                        c.mix(*alpha).filled(),
                    ))
                    .map_err(de)?;
                }
            }
            root.draw(&Text::new(
                label.clone(),
                (ix + iw + o.pxi(8.0), cy),
                font.pos(plotters::style::text_anchor::Pos::new(
                    plotters::style::text_anchor::HPos::Left,
                    plotters::style::text_anchor::VPos::Center,
                )),
            ))
            .map_err(de)?;
        }
        Ok(())
    }
}

/// Curve samples in backend pixels, densified to about 4 px spacing (what a
/// legend must not cover).
pub(crate) fn pixels(chart: &Chart<'_, '_>, o: &PlotOptions, curves: &[&[(f64, f64)]]) -> Vec<(i32, i32)> {
    let (xr, yr) = (chart.x_range(), chart.y_range());
    let step = o.px(4.0).max(1.0);
    let mut out = Vec::new();
    for c in curves {
        for piece in clip_polyline(c, (xr.start, xr.end), (yr.start, yr.end)) {
            if piece.len() == 1 {
                out.push(chart.backend_coord(&piece[0]));
            }
            for w in piece.windows(2) {
                let a = chart.backend_coord(&w[0]);
                let b = chart.backend_coord(&w[1]);
                let d = ((b.0 - a.0) as f64).hypot((b.1 - a.1) as f64);
                let n = (d / step).ceil().max(1.0) as i32;
                for k in 0..=n {
                    let t = k as f64 / n as f64;
                    out.push((
                        (a.0 as f64 + t * (b.0 - a.0) as f64) as i32,
                        (a.1 as f64 + t * (b.1 - a.1) as f64) as i32,
                    ));
                }
            }
        }
    }
    out
}

/// Build a chart and place its legend: when the legend covers data
/// everywhere inside, the chart is built again with room for it on the
/// right. `data` are the curves the legend must not cover.
pub(crate) fn chart_with_legend<'a, 'b>(
    area: &'a Area<'b>,
    o: &PlotOptions,
    xr: (f64, f64),
    yr: (f64, f64),
    frame: Frame,
    legend: &Legend,
    data: &[&[(f64, f64)]],
    obstacles: &[(i32, i32, i32, i32)],
) -> Result<(Chart<'a, 'b>, Placement, Frame), DrawErr> {
    let c = chart(area, o, xr, yr, frame)?;
    let px = pixels(&c, o, data);
    match legend.place(&c, area, o, &px, obstacles) {
        Placement::Outside => {
            let f = Frame {
                right: frame.right + legend.outside_width(area, o),
                ..frame
            };
            Ok((chart(area, o, xr, yr, f)?, Placement::Outside, f))
        }
        p => Ok((c, p, frame)),
    }
}
