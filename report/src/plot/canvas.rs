//! The one drawing surface of every figure: an SVG writer and a
//! supersampled bitmap behind a single plotters backend, [`Canvas`].
//!
//! plotters works in whole backend pixels, which draws curves in visible
//! pixel steps. A figure is therefore drawn on a canvas
//! several times larger than the image: the SVG writer
//! divides every coordinate by that factor (quarter-pixel coordinates), and
//! the bitmap is averaged down to the image size (antialiased lines and
//! text). Dashed lines ([`Line`] with a dash) are real `stroke-dasharray`
//! polylines in SVG and dashes cut along the path in PNG. PNG files carry
//! their resolution (`pHYs`), so they print at the size asked for.

use std::fmt::Write as _;

use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, VPos};
use plotters::style::FontTransform;
use plotters_backend::{BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind};

/// Error of the canvas (the bitmap's message).
#[derive(Debug)]
pub(crate) struct CanvasError(pub String);

impl std::fmt::Display for CanvasError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for CanvasError {}

enum Target<'a> {
    Svg(&'a mut String, bool),
    Bitmap(BitMapBackend<'a>),
}

/// A plotters backend writing SVG text or drawing into an RGB buffer, at
/// `oversampling` canvas units per image pixel.
pub(crate) struct Canvas<'a> {
    target: Target<'a>,
    /// Canvas size in canvas units.
    size: (u32, u32),
    oversampling: u32,
}

/// Canvas units per image pixel of SVG output.
pub(crate) const SVG_OVERSAMPLING: u32 = 4;

/// Canvas units per image pixel of a PNG of `w x h` pixels: 3, fewer for
/// very large images (the canvas stays under about 80 million pixels).
pub(crate) fn png_oversampling((w, h): (u32, u32)) -> u32 {
    let px = w as f64 * h as f64;
    (1..=3u32).rev().find(|s| px * (s * s) as f64 <= 8e7).unwrap_or(1)
}

fn map_err<E: std::error::Error + Send + Sync>(e: DrawingErrorKind<E>) -> DrawingErrorKind<CanvasError> {
    match e {
        DrawingErrorKind::DrawingError(e) => DrawingErrorKind::DrawingError(CanvasError(e.to_string())),
        DrawingErrorKind::FontError(f) => DrawingErrorKind::FontError(f),
    }
}

fn color_hex(c: BackendColor) -> String {
    format!("#{:02X}{:02X}{:02X}", c.rgb.0, c.rgb.1, c.rgb.2)
}

fn escape(buf: &mut String, s: &str) {
    for c in s.chars() {
        match c {
            '<' => buf.push_str("&lt;"),
            '>' => buf.push_str("&gt;"),
            '&' => buf.push_str("&amp;"),
            '"' => buf.push_str("&quot;"),
            '\'' => buf.push_str("&apos;"),
            o => buf.push(o),
        }
    }
}

impl<'a> Canvas<'a> {
    /// An SVG canvas for an image of `size` pixels, written into `text`
    /// (complete after [`DrawingBackend::present`]).
    pub(crate) fn svg(text: &'a mut String, size: (u32, u32)) -> Self {
        let s = SVG_OVERSAMPLING;
        let _ = writeln!(
            text,
            r#"<svg width="{w}" height="{h}" viewBox="0 0 {w} {h}" xmlns="http://www.w3.org/2000/svg">"#,
            w = size.0,
            h = size.1
        );
        Canvas {
            target: Target::Svg(text, false),
            size: (size.0 * s, size.1 * s),
            oversampling: s,
        }
    }

    /// A bitmap canvas drawing into `buf` (RGB, `(size * oversampling)^2`
    /// pixels).
    pub(crate) fn bitmap(buf: &'a mut [u8], size: (u32, u32), oversampling: u32) -> Self {
        let big = (size.0 * oversampling, size.1 * oversampling);
        Canvas {
            target: Target::Bitmap(BitMapBackend::with_buffer(buf, big)),
            size: big,
            oversampling,
        }
    }

    fn unit(&self, v: i32) -> String {
        let s = self.oversampling as f64;
        let x = v as f64 / s;
        if x.fract() == 0.0 {
            format!("{}", x as i64)
        } else {
            format!("{x:.2}")
                .trim_end_matches('0')
                .trim_end_matches('.')
                .to_string()
        }
    }

    fn svg_points(&self, pts: &[BackendCoord]) -> String {
        let mut s = String::new();
        for p in pts {
            let _ = write!(s, "{},{} ", self.unit(p.0), self.unit(p.1));
        }
        s.pop();
        s
    }

    fn push_tag(&mut self, tag: &str, attrs: &[(&str, String)], body: Option<&str>) {
        let Target::Svg(buf, _) = &mut self.target else { return };
        buf.push('<');
        buf.push_str(tag);
        for (k, v) in attrs {
            buf.push(' ');
            buf.push_str(k);
            buf.push_str("=\"");
            escape(buf, v);
            buf.push('"');
        }
        match body {
            None => buf.push_str("/>\n"),
            Some(b) => {
                buf.push('>');
                escape(buf, b);
                buf.push_str("</");
                buf.push_str(tag);
                buf.push_str(">\n");
            }
        }
    }

    fn opacity(c: BackendColor) -> Option<(&'static str, String)> {
        (c.alpha < 1.0).then(|| ("opacity", format!("{:.3}", c.alpha)))
    }

    /// A polyline, solid or dashed (`dash`: on and off lengths in canvas
    /// units), with round joins.
    pub(crate) fn polyline(
        &mut self,
        pts: &[BackendCoord],
        color: BackendColor,
        width: u32,
        dash: Option<(u32, u32)>,
    ) -> Result<(), DrawingErrorKind<CanvasError>> {
        if pts.len() < 2 || color.alpha == 0.0 {
            return Ok(());
        }
        if let Target::Svg(..) = self.target {
            let mut attrs = vec![
                ("fill", "none".to_string()),
                ("stroke", color_hex(color)),
                ("stroke-width", self.unit(width as i32)),
                ("stroke-linejoin", "round".to_string()),
            ];
            if let Some(o) = Self::opacity(color) {
                attrs.push(o);
            }
            if let Some((on, off)) = dash {
                attrs.push((
                    "stroke-dasharray",
                    format!("{} {}", self.unit(on as i32), self.unit(off as i32)),
                ));
            }
            attrs.push(("points", self.svg_points(pts)));
            self.push_tag("polyline", &attrs, None);
            return Ok(());
        }
        let style = ShapeStyle {
            color: RGBAColor(color.rgb.0, color.rgb.1, color.rgb.2, color.alpha),
            filled: false,
            stroke_width: width,
        };
        match dash {
            None => self.bitmap_path(pts, &style),
            Some((on, off)) => {
                for piece in dashes(pts, on.max(1) as f64, off as f64) {
                    self.bitmap_path(&piece, &style)?;
                }
                Ok(())
            }
        }
    }

    fn bitmap_path(&mut self, pts: &[BackendCoord], style: &ShapeStyle) -> Result<(), DrawingErrorKind<CanvasError>> {
        let Target::Bitmap(b) = &mut self.target else {
            return Ok(());
        };
        b.draw_path(pts.iter().copied(), style).map_err(map_err)?;
        // Round joins and caps: a disc at each vertex of a thick line.
        if style.stroke_width > 2 {
            let r = style.stroke_width / 2;
            for p in pts {
                b.draw_circle(*p, r, &style.color.filled(), true).map_err(map_err)?;
            }
        }
        Ok(())
    }
}

/// The dashes of a polyline: pieces `on` long separated by `off`.
pub(crate) fn dashes(pts: &[BackendCoord], on: f64, off: f64) -> Vec<Vec<BackendCoord>> {
    let mut out = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let (mut solid, mut left) = (true, on);
    let f = |p: BackendCoord| (p.0 as f64, p.1 as f64);
    let push = |out: &mut Vec<Vec<BackendCoord>>, cur: &mut Vec<(f64, f64)>| {
        if cur.len() > 1 {
            out.push(cur.iter().map(|p| (p.0.round() as i32, p.1.round() as i32)).collect());
        }
        cur.clear();
    };
    if off <= 0.0 {
        return vec![pts.to_vec()];
    }
    for w in pts.windows(2) {
        let (mut a, b) = (f(w[0]), f(w[1]));
        if solid && cur.is_empty() {
            cur.push(a);
        }
        loop {
            let d = (b.0 - a.0).hypot(b.1 - a.1);
            if d <= left {
                left -= d;
                if solid {
                    cur.push(b);
                }
                break;
            }
            let t = left / d;
            let m = (a.0 + t * (b.0 - a.0), a.1 + t * (b.1 - a.1));
            if solid {
                cur.push(m);
                push(&mut out, &mut cur);
            } else {
                cur.push(m);
            }
            solid = !solid;
            left = if solid { on } else { off };
            a = m;
        }
    }
    if solid {
        push(&mut out, &mut cur);
    }
    out
}

impl DrawingBackend for Canvas<'_> {
    type ErrorType = CanvasError;

    fn get_size(&self) -> (u32, u32) {
        self.size
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<CanvasError>> {
        Ok(())
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<CanvasError>> {
        match &mut self.target {
            Target::Svg(text, closed) => {
                if !*closed {
                    text.push_str("</svg>\n");
                    *closed = true;
                }
                Ok(())
            }
            Target::Bitmap(b) => b.present().map_err(map_err),
        }
    }

    fn draw_pixel(&mut self, p: BackendCoord, c: BackendColor) -> Result<(), DrawingErrorKind<CanvasError>> {
        match &mut self.target {
            Target::Bitmap(b) => b.draw_pixel(p, c).map_err(map_err),
            Target::Svg(..) => self.draw_rect(p, (p.0 + 1, p.1 + 1), &c, true),
        }
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<CanvasError>> {
        self.polyline(&[from, to], style.color(), style.stroke_width(), None)
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        ul: BackendCoord,
        br: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<CanvasError>> {
        let c = style.color();
        if c.alpha == 0.0 {
            return Ok(());
        }
        if let Target::Bitmap(b) = &mut self.target {
            return b.draw_rect(ul, br, style, fill).map_err(map_err);
        }
        let mut attrs = vec![
            ("x", self.unit(ul.0)),
            ("y", self.unit(ul.1)),
            ("width", self.unit(br.0 - ul.0)),
            ("height", self.unit(br.1 - ul.1)),
        ];
        if fill {
            attrs.push(("fill", color_hex(c)));
            attrs.push(("stroke", "none".into()));
        } else {
            attrs.push(("fill", "none".into()));
            attrs.push(("stroke", color_hex(c)));
            attrs.push(("stroke-width", self.unit(style.stroke_width() as i32)));
        }
        if let Some(o) = Self::opacity(c) {
            attrs.push(o);
        }
        self.push_tag("rect", &attrs, None);
        Ok(())
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<CanvasError>> {
        let pts: Vec<_> = path.into_iter().collect();
        self.polyline(&pts, style.color(), style.stroke_width(), None)
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<CanvasError>> {
        let c = style.color();
        if c.alpha == 0.0 {
            return Ok(());
        }
        if let Target::Bitmap(b) = &mut self.target {
            if fill {
                return b.draw_circle(center, radius, style, true).map_err(map_err);
            }
            // A ring as thick as the stroke.
            let w = style.stroke_width().max(1);
            let n = ((radius as f64) * 0.8).clamp(16.0, 180.0) as usize;
            let ring: Vec<BackendCoord> = (0..=n)
                .map(|k| {
                    let a = std::f64::consts::TAU * k as f64 / n as f64;
                    (
                        center.0 + (radius as f64 * a.cos()).round() as i32,
                        center.1 + (radius as f64 * a.sin()).round() as i32,
                    )
                })
                .collect();
            return self.polyline(&ring, c, w, None);
        }
        let mut attrs = vec![
            ("cx", self.unit(center.0)),
            ("cy", self.unit(center.1)),
            ("r", self.unit(radius as i32)),
        ];
        if fill {
            attrs.push(("fill", color_hex(c)));
            attrs.push(("stroke", "none".into()));
        } else {
            attrs.push(("fill", "none".into()));
            attrs.push(("stroke", color_hex(c)));
            attrs.push(("stroke-width", self.unit(style.stroke_width().max(1) as i32)));
        }
        if let Some(o) = Self::opacity(c) {
            attrs.push(o);
        }
        self.push_tag("circle", &attrs, None);
        Ok(())
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<CanvasError>> {
        let c = style.color();
        if c.alpha == 0.0 {
            return Ok(());
        }
        if let Target::Bitmap(b) = &mut self.target {
            return b.fill_polygon(vert, style).map_err(map_err);
        }
        let pts: Vec<_> = vert.into_iter().collect();
        let mut attrs = vec![("fill", color_hex(c)), ("points", self.svg_points(&pts))];
        if let Some(o) = Self::opacity(c) {
            attrs.push(o);
        }
        self.push_tag("polygon", &attrs, None);
        Ok(())
    }

    fn draw_text<T: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<CanvasError>> {
        let c = style.color();
        if c.alpha == 0.0 {
            return Ok(());
        }
        if let Target::Bitmap(b) = &mut self.target {
            return b.draw_text(text, style, pos).map_err(map_err);
        }
        let anchor = match style.anchor().h_pos {
            HPos::Left => "start",
            HPos::Right => "end",
            HPos::Center => "middle",
        };
        let dy = match style.anchor().v_pos {
            VPos::Top => "0.76em",
            VPos::Center => "0.5ex",
            VPos::Bottom => "-0.5ex",
        };
        let (x, y) = (self.unit(pos.0), self.unit(pos.1));
        let mut attrs = vec![
            ("x", x.clone()),
            ("y", y.clone()),
            ("dy", dy.to_string()),
            ("text-anchor", anchor.to_string()),
            ("font-family", style.family().as_str().to_string()),
            (
                "font-size",
                format!("{:.2}", style.size() / 1.24 / self.oversampling as f64)
                    .trim_end_matches('0')
                    .trim_end_matches('.')
                    .to_string(),
            ),
            ("fill", color_hex(c)),
        ];
        if let Some(o) = Self::opacity(c) {
            attrs.push(o);
        }
        let rot = match style.transform() {
            FontTransform::Rotate90 => Some(90),
            FontTransform::Rotate180 => Some(180),
            FontTransform::Rotate270 => Some(270),
            _ => None,
        };
        if let Some(r) = rot {
            attrs.push(("transform", format!("rotate({r}, {x}, {y})")));
        }
        self.push_tag("text", &attrs, Some(text));
        Ok(())
    }
}

/// A polyline in data coordinates, solid or dashed (dash lengths in canvas
/// units), drawn by the canvas itself (see [`Canvas::polyline`]).
pub(crate) struct Line<C> {
    pub points: Vec<C>,
    pub color: RGBColor,
    pub width: u32,
    pub dash: Option<(u32, u32)>,
}

impl<'a, C> PointCollection<'a, C> for &'a Line<C> {
    type Point = &'a C;
    type IntoIter = &'a [C];
    fn point_iter(self) -> &'a [C] {
        &self.points
    }
}

impl<C> Drawable<Canvas<'_>> for Line<C> {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        points: I,
        backend: &mut Canvas<'_>,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<CanvasError>> {
        let pts: Vec<_> = points.collect();
        let c = self.color;
        backend.polyline(
            &pts,
            BackendColor {
                alpha: 1.0,
                rgb: (c.0, c.1, c.2),
            },
            self.width,
            self.dash,
        )
    }
}

/// Average `s x s` blocks of an RGB image of `(w * s) x (h * s)` pixels
/// down to `w x h`.
pub(crate) fn downsample(big: &[u8], (w, h): (u32, u32), s: u32) -> Vec<u8> {
    if s == 1 {
        return big.to_vec();
    }
    let (w, h, s) = (w as usize, h as usize, s as usize);
    let bw = w * s;
    let mut out = vec![0u8; w * h * 3];
    let n = (s * s) as u32;
    for y in 0..h {
        for x in 0..w {
            let mut acc = [0u32; 3];
            for dy in 0..s {
                let row = (y * s + dy) * bw;
                for dx in 0..s {
                    let k = (row + x * s + dx) * 3;
                    acc[0] += big[k] as u32;
                    acc[1] += big[k + 1] as u32;
                    acc[2] += big[k + 2] as u32;
                }
            }
            let o = (y * w + x) * 3;
            for c in 0..3 {
                out[o + c] = ((acc[c] + n / 2) / n) as u8;
            }
        }
    }
    out
}

/// Encode an RGB image as PNG with its resolution (`dpi`, as `pHYs`).
pub(crate) fn encode_png(rgb: &[u8], (w, h): (u32, u32), dpi: f64) -> Result<Vec<u8>, String> {
    let mut bytes = Vec::new();
    {
        let mut e = png::Encoder::new(&mut bytes, w, h);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(png::BitDepth::Eight);
        let ppm = (dpi / 0.0254).round() as u32;
        e.set_pixel_dims(Some(png::PixelDimensions {
            xppu: ppm,
            yppu: ppm,
            unit: png::Unit::Meter,
        }));
        let mut wr = e.write_header().map_err(|e| e.to_string())?;
        wr.write_image_data(rgb).map_err(|e| e.to_string())?;
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dashes_cut_a_line_into_on_off_pieces() {
        let d = dashes(&[(0, 0), (100, 0)], 10.0, 5.0);
        // 0-10, 15-25, ..., 90-100: seven dashes.
        assert_eq!(d.len(), 7);
        assert_eq!(d[0], vec![(0, 0), (10, 0)]);
        assert_eq!(d[1], vec![(15, 0), (25, 0)]);
        // Across a corner the dash follows the path.
        let d = dashes(&[(0, 0), (6, 0), (6, 10)], 10.0, 5.0);
        assert_eq!(d[0], vec![(0, 0), (6, 0), (6, 4)]);
    }

    #[test]
    fn downsample_averages_blocks() {
        let mut big = vec![255u8; 4 * 4 * 3];
        for c in 0..3 {
            big[c] = 0; // one black pixel of the first 2x2 block
        }
        let small = downsample(&big, (2, 2), 2);
        assert_eq!(small[0], 191);
        assert_eq!(small[3], 255);
    }
}
