//! Publication plots with plotters: the eigenvalue continuation diagram
//! (Meijaard et al. 2007, Fig. 3), the root locus and mode shapes
//! ([`locus`]), two-parameter stability maps and one-parameter sweeps
//! ([`sweep`]).
//!
//! The format follows the file extension: `.svg` (vector, for papers) or
//! `.png` (raster, antialiased, with its resolution recorded); anything
//! else is [`PlotError::UnsupportedFormat`]. Files are written atomically
//! (see [`crate::output`]). Every figure of the crate (these, the
//! simulation, fit and identification plots) shares one style
//! ([`style`]) and one drawing surface (`canvas`), and takes the same
//! [`PlotOptions`]: size, resolution, title, axis limits, legend.
//!
//! # Layout
//!
//! Here: the options and errors every figure shares ([`PlotOptions`],
//! [`PlotError`], [`ImageFormat`]), the rendering of a figure to a file
//! (`render`) and the axis helpers (tick labels, clipping, label widths).
//! The fonts are found and registered in `font.rs`; the continuation
//! diagram is drawn in `continuation.rs` ([`plot_continuation`]), the
//! stability map in `map.rs` ([`plot_stability_map`]); the other figures
//! have their modules below.
//!
//! # Size and resolution
//! `width x height` are pixels at `scale = 1`, which is 100 dpi: the default
//! 800 x 600 is an 8 x 6 inch figure. `scale` multiplies pixels, fonts and
//! lines alike, so `scale = 3` is the same figure at 300 dpi (what the PNG
//! records in its `pHYs` chunk).
//!
//! # Fonts
//! plotters is built with its pure-Rust `ab_glyph` text engine, which needs a
//! TrueType/OpenType font registered at run time, for PNG *and* SVG (plotters
//! measures text to lay out labels even when the SVG only references the
//! family `sans-serif`). The font is taken from, in order:
//! [`PlotOptions::font_path`], the environment variable `BIKEDYN_FONT`, a list
//! of common system locations (DejaVu Sans, Liberation Sans, FreeSans, Arial),
//! and finally a scan of the system font directories. If none is found,
//! [`PlotError::NoFont`] says what was searched (on Debian/Ubuntu:
//! `apt-get install fonts-dejavu-core`). The font bytes are loaded once per
//! distinct font file and kept for the life of the process.

use std::path::{Path, PathBuf};

use plotters::prelude::*;

use crate::output::{write_atomic, write_string_atomic, OutputError};
use canvas::Canvas;
use style::Area;

/// Font family name under which the font is registered and used.
const FAMILY: &str = "sans-serif";

pub mod bode;
mod canvas;
pub mod locus;
pub mod sensitivity;
pub(crate) mod style;
pub mod sweep;

mod continuation;
mod font;
mod map;

pub use continuation::plot_continuation;
pub(crate) use continuation::{mode_class, CLASS_COLORS};
use font::ensure_font;
pub use font::{find_font, use_font, FONT_ENV, MAX_FONT_BYTES};
pub use map::plot_stability_map;
pub(crate) use map::viridis;

/// Errors of the plot functions; all name the offending path where there is one.
#[derive(Debug, thiserror::Error)]
pub enum PlotError {
    /// File extension is neither `.svg` nor `.png`.
    #[error("cannot plot to {}: unsupported file extension (use .svg or .png)", .path.display())]
    UnsupportedFormat {
        /// Requested output path.
        path: PathBuf,
    },
    /// No usable font file was found.
    #[error(
        "no TrueType/OpenType font found for plot text (searched {}); install one \
         (Debian/Ubuntu: apt-get install fonts-dejavu-core) or set {FONT_ENV} or PlotOptions::font_path",
        .searched.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(", ")
    )]
    NoFont {
        /// Locations tried.
        searched: Vec<PathBuf>,
    },
    /// A font file could not be read or parsed.
    #[error("cannot use font {}: {message}", .path.display())]
    Font {
        /// Font file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// Nothing to plot (empty sweep or grid).
    #[error("cannot plot to {}: no data", .path.display())]
    NoData {
        /// Requested output path.
        path: PathBuf,
    },
    /// Invalid plot options (size, ranges).
    #[error("cannot plot to {}: invalid options: {message}", .path.display())]
    InvalidOptions {
        /// Requested output path.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// plotters reported an error while drawing.
    #[error("cannot plot to {}: drawing failed: {message}", .path.display())]
    Drawing {
        /// Requested output path.
        path: PathBuf,
        /// plotters' message.
        message: String,
    },
    /// Writing the file failed (nothing was written at the path).
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// Image format, from the file extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ImageFormat {
    /// Scalable vector graphics.
    Svg,
    /// Portable network graphics (RGB).
    Png,
}

impl ImageFormat {
    /// Format from the (case-insensitive) extension of `path`.
    pub fn from_path(path: &Path) -> Result<Self, PlotError> {
        match path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .as_deref()
        {
            Some("svg") => Ok(ImageFormat::Svg),
            Some("png") => Ok(ImageFormat::Png),
            _ => Err(PlotError::UnsupportedFormat {
                path: path.to_path_buf(),
            }),
        }
    }
}

/// Where the legend goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum LegendPosition {
    /// A corner (or the middle of the top or bottom edge) of the plot area
    /// that covers no data, else right of the plot area.
    #[default]
    Auto,
    /// Upper left corner of the plot area.
    UpperLeft,
    /// Upper right corner.
    UpperRight,
    /// Lower left corner.
    LowerLeft,
    /// Lower right corner.
    LowerRight,
    /// Right of the plot area.
    Outside,
    /// No legend.
    Hidden,
}

/// Plot options. `PlotOptions::default()` gives each figure its own size
/// (800x600, 8 x 6 inches at 100 dpi, for one panel) with automatic ranges, each figure's default title,
/// 18 px text and a legend placed where it covers no data.
#[derive(Clone, Debug, PartialEq)]
pub struct PlotOptions {
    /// Width and height in pixels at `scale = 1`. `None`: the figure's own
    /// size ([`DEFAULT_SIZE`] for one panel; figures with several panels
    /// are taller). A size that is given is always kept, even when it equals
    /// the default.
    pub size: Option<(u32, u32)>,
    /// Multiplies the pixel size, fonts and line widths (default 1; use 2-3
    /// for print-resolution PNG). SVG output is resolution independent anyway.
    pub scale: f64,
    /// Title above the plot (default: a description of the figure; the
    /// command line names the bicycle and the model). `Some("")`: none.
    pub title: Option<String>,
    /// What the figure shows the dynamics of, e.g. "benchmark bicycle, model
    /// whipple_offset": put before each figure's own description in the
    /// default title (default none).
    pub subject: Option<String>,
    /// Horizontal range; default: the data's range.
    pub x_range: Option<(f64, f64)>,
    /// Vertical range (continuation diagram); default: all eigenvalue parts
    /// with 5% padding. Curves are clipped at the limits (e.g. `(-10, 10)` cuts
    /// off the fast castering mode).
    pub y_range: Option<(f64, f64)>,
    /// Horizontal axis label; default per plot ("forward speed v (m/s)", or the
    /// parameter name of a map).
    pub x_label: Option<String>,
    /// Vertical axis label; default "eigenvalue (1/s)" or the parameter name.
    pub y_label: Option<String>,
    /// Base font size in pixels at `scale = 1` (default 18; plotters renders SVG
    /// text at this size / 1.24).
    pub font_size: f64,
    /// Legend placement (default [`LegendPosition::Auto`]).
    pub legend: LegendPosition,
    /// Shade the self-stable speed intervals and mark `v_d`, `v_w`, `v_c`
    /// (default true; needs critical speeds).
    pub show_stable_band: bool,
    /// TTF/OTF font for text (default: search, see the module docs).
    pub font_path: Option<PathBuf>,
}

/// Size in pixels at `scale = 1` of a one-panel figure when none is given
/// (8 x 6 inches at 100 dpi).
pub const DEFAULT_SIZE: (u32, u32) = (800, 600);

/// The most pixels a figure may have: 40 million (a 8000 x 5000 poster,
/// 27 x 17 inches at 300 dpi). A PNG is drawn on an oversampled canvas of
/// up to 80 million pixels and averaged down, so the peak memory stays
/// near 300 MB; the earlier cap of 20000 x 20000 pixels took 2.3 GB.
pub const MAX_PIXELS: u64 = 40_000_000;

/// The longest side of a figure (pixels).
pub const MAX_SIDE: u32 = 20_000;

impl Default for PlotOptions {
    fn default() -> Self {
        Self {
            size: None,
            scale: 1.0,
            title: None,
            subject: None,
            x_range: None,
            y_range: None,
            x_label: None,
            y_label: None,
            font_size: 18.0,
            legend: LegendPosition::Auto,
            show_stable_band: true,
            font_path: None,
        }
    }
}

/// The subject of a figure (see [`PlotOptions::subject`]): the bicycle (a
/// built-in name, or a parameter file by its file name without directory)
/// and the model, e.g. "bicycle benchmark, model whipple_offset" or
/// "bicycle.toml, model whipple_offset".
pub fn subject(bike: &str, model: Option<&str>) -> String {
    let p = Path::new(bike);
    // A parameter file is named by its file name (`bicycle.toml` would
    // otherwise read "bicycle bicycle"); a built-in bicycle by its name.
    let name = if bike.contains(std::path::MAIN_SEPARATOR) || p.extension().is_some() {
        p.file_name().map_or(bike.into(), |s| s.to_string_lossy().into_owned())
    } else {
        format!("bicycle {bike}")
    };
    match model {
        Some(m) => format!("{name}, model {m}"),
        None => name,
    }
}

impl PlotOptions {
    /// Check the options (size, scale, font size, ranges) for a plot to `path`.
    pub fn check(&self, path: &Path) -> Result<(), PlotError> {
        let bad = |m: String| {
            Err(PlotError::InvalidOptions {
                path: path.to_path_buf(),
                message: m,
            })
        };
        if !(self.scale.is_finite() && self.scale > 0.0) {
            return bad(format!("scale must be positive, got {}", self.scale));
        }
        if !(self.font_size.is_finite() && self.font_size > 0.0) {
            return bad(format!("font_size must be positive, got {}", self.font_size));
        }
        let (w, h) = self.pixel_size();
        if w < 200 || h < 150 || w > MAX_SIDE || h > MAX_SIDE || w as u64 * h as u64 > MAX_PIXELS {
            return bad(format!(
                "image size {w}x{h} px out of range (at least 200x150, at most {MAX_SIDE} on a side and {} million pixels)",
                MAX_PIXELS / 1_000_000
            ));
        }
        for (name, r) in [("x_range", self.x_range), ("y_range", self.y_range)] {
            if let Some((lo, hi)) = r {
                if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                    return bad(format!("{name} must be finite and increasing, got ({lo}, {hi})"));
                }
            }
        }
        Ok(())
    }

    /// Resolution of a PNG (dots per inch): 100 at `scale = 1`.
    pub fn dpi(&self) -> f64 {
        100.0 * self.scale
    }

    /// The same options with `s` times the scale (the canvas of a figure).
    fn oversampled(&self, s: u32) -> Self {
        PlotOptions {
            scale: self.scale * s as f64,
            ..self.clone()
        }
    }

    /// Image size in pixels.
    pub fn pixel_size(&self) -> (u32, u32) {
        let (w, h) = self.size.unwrap_or(DEFAULT_SIZE);
        (
            (w as f64 * self.scale).round() as u32,
            (h as f64 * self.scale).round() as u32,
        )
    }

    /// These options with `size` as the figure's own size when none is given.
    pub fn sized_by_default(&self, size: (u32, u32)) -> PlotOptions {
        PlotOptions {
            size: Some(self.size.unwrap_or(size)),
            ..self.clone()
        }
    }

    pub(crate) fn px(&self, x: f64) -> f64 {
        x * self.scale
    }

    pub(crate) fn pxi(&self, x: f64) -> i32 {
        (x * self.scale).round() as i32
    }

    pub(crate) fn pxu(&self, x: f64) -> u32 {
        (x * self.scale).round().max(1.0) as u32
    }

    pub(crate) fn font(&self, rel: f64) -> TextStyle<'static> {
        TextStyle::from((FAMILY, self.font_size * self.scale * rel).into_font())
    }
}

// ---------------------------------------------------------------------------
// Rendering

pub(crate) type DrawErr = String;

pub(crate) fn de<E: std::fmt::Display>(e: E) -> DrawErr {
    e.to_string()
}

/// A figure: draws itself on a canvas with the options scaled to it.
pub(crate) trait Figure {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr>;
}

/// Draw `fig` to `path` (SVG or PNG by extension), atomically.
pub(crate) fn render(path: &Path, opts: &PlotOptions, fig: &impl Figure) -> Result<(), PlotError> {
    let format = ImageFormat::from_path(path)?;
    opts.check(path)?;
    ensure_font(opts)?;
    let size = opts.pixel_size();
    let drawing = |message| PlotError::Drawing {
        path: path.to_path_buf(),
        message,
    };
    match format {
        ImageFormat::Svg => {
            let mut svg = String::new();
            {
                let o = opts.oversampled(canvas::SVG_OVERSAMPLING);
                let root = Canvas::svg(&mut svg, size).into_drawing_area();
                fig.draw(&root, &o).map_err(drawing)?;
                root.present().map_err(|e| drawing(e.to_string()))?;
            }
            write_string_atomic(path, &svg)?;
        }
        ImageFormat::Png => {
            let s = canvas::png_oversampling(size);
            let mut big = vec![255u8; (size.0 * s) as usize * (size.1 * s) as usize * 3];
            {
                let o = opts.oversampled(s);
                let root = Canvas::bitmap(&mut big, size, s).into_drawing_area();
                fig.draw(&root, &o).map_err(drawing)?;
                root.present().map_err(|e| drawing(e.to_string()))?;
            }
            let rgb = canvas::downsample(&big, size, s);
            drop(big);
            let bytes = canvas::encode_png(&rgb, size, opts.dpi()).map_err(drawing)?;
            write_atomic(path, |w| w.write_all(&bytes))?;
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Helpers

/// Tick label: shortest decimal of the value rounded to 6 significant places.
pub(crate) fn tick(v: f64) -> String {
    if v == 0.0 || v.abs() < 1e-12 {
        return "0".into();
    }
    let mag = v.abs().log10().floor() as i32;
    if !(-4..=6).contains(&mag) {
        return format!("{v:.2e}");
    }
    let decimals = (5 - mag).clamp(0, 10) as usize;
    let s = format!("{v:.decimals$}");
    let s = if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    };
    if s == "-0" {
        "0".into()
    } else {
        s
    }
}

/// Clip a polyline to the box, returning the visible pieces.
pub(crate) fn clip_polyline(pts: &[(f64, f64)], (x0, x1): (f64, f64), (y0, y1): (f64, f64)) -> Vec<Vec<(f64, f64)>> {
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let inside = |p: (f64, f64)| p.0 >= x0 && p.0 <= x1 && p.1 >= y0 && p.1 <= y1;
    if pts.len() == 1 && inside(pts[0]) {
        return vec![pts.to_vec()];
    }
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        // Liang-Barsky.
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        let mut visible = true;
        for (p, q) in [(-dx, a.0 - x0), (dx, x1 - a.0), (-dy, a.1 - y0), (dy, y1 - a.1)] {
            if p == 0.0 {
                if q < 0.0 {
                    visible = false;
                    break;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        if !visible || t0 > t1 {
            if cur.len() > 1 {
                out.push(std::mem::take(&mut cur));
            }
            cur.clear();
            continue;
        }
        let pa = (a.0 + t0 * dx, a.1 + t0 * dy);
        let pb = (a.0 + t1 * dx, a.1 + t1 * dy);
        if cur.is_empty() || t0 > 0.0 {
            if cur.len() > 1 {
                out.push(std::mem::take(&mut cur));
            }
            cur.clear();
            cur.push(pa);
        }
        cur.push(pb);
        if t1 < 1.0 {
            out.push(std::mem::take(&mut cur));
        }
    }
    if cur.len() > 1 {
        out.push(cur);
    }
    out
}

/// Width of the widest tick label of `lo..hi` with about `n` "nice" ticks
/// (1-2-5 steps, as plotters chooses them).
fn widest_tick(root: &Area<'_>, font: &TextStyle<'_>, (lo, hi): (f64, f64), n: usize) -> u32 {
    let raw = (hi - lo) / n.max(1) as f64;
    let mut widest = 0;
    if raw.is_finite() && raw > 0.0 {
        let p = 10f64.powf(raw.log10().floor());
        let step = [1.0, 2.0, 5.0, 10.0]
            .iter()
            .map(|m| m * p)
            .find(|s| *s >= raw)
            .unwrap_or(10.0 * p);
        let mut k = (lo / step).ceil();
        while k * step <= hi && widest < 10_000 {
            let w = root.estimate_text_size(&tick(k * step), font).map(|t| t.0).unwrap_or(0);
            widest = widest.max(w);
            k += 1.0;
            if k > (lo / step).ceil() + 100.0 {
                break;
            }
        }
    }
    widest
}

/// Width of the left label area: widest tick label plus tick marks and the
/// rotated axis description.
pub(crate) fn label_area_width(root: &Area<'_>, o: &PlotOptions, range: (f64, f64), n: usize) -> u32 {
    widest_tick(root, &o.font(0.9), range, n) + o.pxu(5.0 + 8.0) + o.pxu(o.font_size * 1.9)
}

pub(crate) fn padded(lo: f64, hi: f64, frac: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (-1.0, 1.0);
    }
    if hi - lo <= 1e-12 * lo.abs().max(hi.abs()).max(1.0) {
        return (lo - 0.5, hi + 0.5);
    }
    let d = (hi - lo) * frac;
    (lo - d, hi + d)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_names_a_parameter_file_by_its_file_name_and_a_builtin_as_a_bicycle() {
        let file = std::path::Path::new("some").join("dir").join("bicycle.toml");
        assert_eq!(
            subject(&file.to_string_lossy(), Some("whipple_offset")),
            "bicycle.toml, model whipple_offset"
        );
        assert_eq!(
            subject("benchmark", Some("whipple")),
            "bicycle benchmark, model whipple"
        );
        assert_eq!(subject("BluenosePar.txt", None), "BluenosePar.txt");
    }

    #[test]
    fn plot_clip_polyline_splits_at_box() {
        let pts = [(0.0, 0.0), (1.0, 2.0), (2.0, 0.0), (3.0, 0.5)];
        let pieces = clip_polyline(&pts, (0.0, 3.0), (-1.0, 1.0));
        assert_eq!(pieces.len(), 2);
        assert_eq!(pieces[0], vec![(0.0, 0.0), (0.5, 1.0)]);
        assert_eq!(pieces[1], vec![(1.5, 1.0), (2.0, 0.0), (3.0, 0.5)]);
        assert!(clip_polyline(&[(0.0, 5.0), (1.0, 6.0)], (0.0, 1.0), (0.0, 1.0)).is_empty());
        assert_eq!(clip_polyline(&pts, (-1.0, 4.0), (-3.0, 3.0)), vec![pts.to_vec()]);
    }

    #[test]
    fn plot_tick_labels_are_short() {
        assert_eq!(tick(0.0), "0");
        assert_eq!(tick(-0.0), "0");
        assert_eq!(tick(2.0), "2");
        assert_eq!(tick(-25.0), "-25");
        assert_eq!(tick(0.30000000000000004), "0.3");
        assert_eq!(tick(1.2), "1.2");
        assert_eq!(tick(1e-7), "1.00e-7");
    }

    /// Issue 20: PNG lines are antialiased (intermediate shades beside a
    /// diagonal), not pixel steps.
    #[test]
    fn issue_20_png_lines_are_smooth() {
        struct Diagonal;
        impl Figure for Diagonal {
            fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
                root.fill(&WHITE).map_err(de)?;
                let (w, h) = root.dim_in_pixel();
                root.draw(&canvas::Line {
                    points: vec![(0, 0), (w as i32, (h as i32) / 3)],
                    color: BLACK,
                    width: o.pxu(1.0),
                    dash: None,
                })
                .map_err(de)
            }
        }
        let path = std::env::temp_dir().join(format!("bikedyn-smooth-{}.png", std::process::id()));
        let opts = PlotOptions {
            size: Some((300, 200)),
            ..PlotOptions::default()
        };
        render(&path, &opts, &Diagonal).unwrap();
        let decoder = png::Decoder::new(std::fs::File::open(&path).unwrap());
        let mut reader = decoder.read_info().unwrap();
        let mut buf = vec![0; reader.output_buffer_size()];
        reader.next_frame(&mut buf).unwrap();
        let _ = std::fs::remove_file(&path);
        let grey: std::collections::HashSet<u8> = buf.chunks(3).map(|p| p[0]).filter(|v| *v > 10 && *v < 245).collect();
        assert!(grey.len() > 5, "{} intermediate shades", grey.len());
    }

    #[test]
    fn plot_format_from_extension() {
        assert_eq!(ImageFormat::from_path(Path::new("a/b.SVG")).unwrap(), ImageFormat::Svg);
        assert_eq!(ImageFormat::from_path(Path::new("b.png")).unwrap(), ImageFormat::Png);
        assert!(ImageFormat::from_path(Path::new("b.jpg")).is_err());
        assert!(ImageFormat::from_path(Path::new("png")).is_err());
    }
}
