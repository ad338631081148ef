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

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use plotters::prelude::*;

use crate::output::{write_atomic, write_string_atomic, OutputError};
use bikedyn_runtime::eigen::{CriticalSpeeds, EigenSweep, Mode};
use bikedyn_runtime::sweep::{MapQuantity, StabilityMap};
use canvas::Canvas;
use style::{Area, Frame, Icon, Legend, Stroke};

/// Font family name under which the font is registered and used.
const FAMILY: &str = "sans-serif";

pub mod bode;
mod canvas;
pub mod locus;
pub mod sensitivity;
pub(crate) mod style;
pub mod sweep;

/// Environment variable naming a TTF/OTF font file for plot text.
pub const FONT_ENV: &str = "BIKEDYN_FONT";

/// The largest font file read (bytes): the largest common fonts (CJK
/// collections) are about 30 MB; a larger file is not a font and would be
/// held in memory for good.
pub const MAX_FONT_BYTES: u64 = 64 << 20;

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
// Fonts

static REGISTERED: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);
static DEFAULT_FONT: Mutex<Option<PathBuf>> = Mutex::new(None);

const FONT_CANDIDATES: &[&str] = &[
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/local/share/fonts/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/liberation2/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation-sans/LiberationSans-Regular.ttf",
    "/usr/share/fonts/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
    "/usr/share/fonts/gnu-free/FreeSans.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
    "/Library/Fonts/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

const FONT_DIRS: &[&str] = &[
    "/usr/share/fonts",
    "/usr/local/share/fonts",
    "/System/Library/Fonts",
    "/Library/Fonts",
];

fn scan_fonts(dir: &Path, depth: u32, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            if depth > 0 {
                scan_fonts(&p, depth - 1, out);
            }
        } else if p
            .extension()
            .map(|e| matches!(e.to_string_lossy().to_ascii_lowercase().as_str(), "ttf" | "otf"))
            .unwrap_or(false)
        {
            out.push(p);
        }
    }
}

/// Locate a font for plot text: `$BIKEDYN_FONT`, known system paths, then a
/// scan of the system font directories (preferring regular sans-serif faces).
pub fn find_font() -> Result<PathBuf, PlotError> {
    let mut searched = Vec::new();
    if let Some(p) = std::env::var_os(FONT_ENV).filter(|p| !p.is_empty()) {
        // A font the user named is used or refused, never passed over for
        // another one without a word.
        let p = PathBuf::from(p);
        let why = match std::fs::metadata(&p) {
            Err(e) => e.to_string(),
            Ok(m) if m.is_dir() => "a folder, not a font file".into(),
            Ok(m) if !m.is_file() => "a device or pipe, not a font file".into(),
            Ok(m) if m.len() > MAX_FONT_BYTES => format!(
                "{} bytes, more than a font file holds ({MAX_FONT_BYTES} at most)",
                m.len()
            ),
            Ok(_) => return Ok(p),
        };
        return Err(PlotError::Font {
            path: p,
            message: format!("{why} (named by {FONT_ENV}: give a .ttf or .otf file, or unset it to use a system font)"),
        });
    }
    for c in FONT_CANDIDATES {
        let p = PathBuf::from(c);
        if p.is_file() {
            return Ok(p);
        }
    }
    searched.extend(FONT_CANDIDATES.iter().map(PathBuf::from));
    let mut dirs: Vec<PathBuf> = FONT_DIRS.iter().map(PathBuf::from).collect();
    if let Some(home) = std::env::var_os("HOME") {
        dirs.push(Path::new(&home).join(".local/share/fonts"));
        dirs.push(Path::new(&home).join(".fonts"));
    }
    let mut found = Vec::new();
    for d in &dirs {
        scan_fonts(d, 4, &mut found);
    }
    searched.extend(dirs);
    let score = |p: &PathBuf| {
        let n = p
            .file_stem()
            .map(|s| s.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        let styled = [
            "bold",
            "italic",
            "oblique",
            "light",
            "mono",
            "condensed",
            "black",
            "thin",
            "narrow",
            "serif",
        ]
        .iter()
        .any(|s| n.replace("sans", "").contains(s));
        (!n.contains("sans") as u8) + 2 * (styled as u8)
    };
    found.sort_by_key(score);
    found.into_iter().next().ok_or(PlotError::NoFont { searched })
}

/// Register the font file `path` for plot text (idempotent per path). Later
/// plots without [`PlotOptions::font_path`] use it too.
pub fn use_font(path: impl AsRef<Path>) -> Result<(), PlotError> {
    let path = path.as_ref().to_path_buf();
    let mut reg = REGISTERED.lock().unwrap_or_else(|e| e.into_inner());
    let reg = reg.get_or_insert_with(HashSet::new);
    let mut default = DEFAULT_FONT.lock().unwrap_or_else(|e| e.into_inner());
    if reg.contains(&path) {
        if default.as_ref() != Some(&path) {
            // Re-register to make it current (bytes are already leaked).
            register_file(&path)?;
            *default = Some(path);
        }
        return Ok(());
    }
    register_file(&path)?;
    reg.insert(path.clone());
    *default = Some(path);
    Ok(())
}

/// In WebAssembly plotters draws text through the browser's fonts, and there
/// are no font files to read: the browser build draws its own figures.
#[cfg(target_arch = "wasm32")]
fn register_file(path: &Path) -> Result<(), PlotError> {
    Err(PlotError::Font {
        path: path.to_path_buf(),
        message: "font files are not read in the WebAssembly build".into(),
    })
}

#[cfg(not(target_arch = "wasm32"))]
fn register_file(path: &Path) -> Result<(), PlotError> {
    let bytes = std::fs::read(path).map_err(|e| PlotError::Font {
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    // plotters' ab_glyph registry needs 'static bytes; the leak is bounded by
    // one copy per distinct font file (see `use_font`).
    static LEAKED: Mutex<Vec<(PathBuf, &'static [u8])>> = Mutex::new(Vec::new());
    let mut leaked = LEAKED.lock().unwrap_or_else(|e| e.into_inner());
    let bytes: &'static [u8] = match leaked.iter().find(|(p, _)| p == path) {
        Some((_, b)) => b,
        None => {
            let b: &'static [u8] = Box::leak(bytes.into_boxed_slice());
            leaked.push((path.to_path_buf(), b));
            b
        }
    };
    plotters::style::register_font(FAMILY, FontStyle::Normal, bytes).map_err(|_| PlotError::Font {
        path: path.to_path_buf(),
        message: "not a valid TrueType/OpenType font".into(),
    })
}

fn ensure_font(opts: &PlotOptions) -> Result<(), PlotError> {
    if let Some(p) = &opts.font_path {
        return use_font(p);
    }
    if DEFAULT_FONT.lock().unwrap_or_else(|e| e.into_inner()).is_some() {
        return Ok(());
    }
    use_font(find_font()?)
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

const BAND: RGBColor = style::GREEN;
const MISSING: RGBColor = RGBColor(200, 200, 200);
const FAILED: RGBColor = RGBColor(120, 120, 120);

/// Class of a mode label in the diagrams: each single mode, each merged
/// pair and the unclassified modes have their own colour.
pub(crate) fn mode_class(m: Mode) -> usize {
    match m {
        Mode::Weave => 0,
        Mode::Capsize => 1,
        Mode::Castering => 2,
        Mode::WeaveCapsize => 3,
        Mode::WeaveCastering => 4,
        Mode::CapsizeCastering => 5,
        Mode::Other(_) => 6,
    }
}

pub(crate) const CLASS_NAMES: [&str; 7] = [
    "weave",
    "capsize",
    "castering",
    "weave-capsize pair",
    "weave-castering pair",
    "capsize-castering pair",
    "other",
];
/// Single modes: blue, vermilion, purple; merged pairs: pink, sky blue,
/// olive (none close to a single mode's colour); others grey.
pub(crate) const CLASS_COLORS: [RGBColor; 7] = [
    style::BLUE,
    style::VERMILION,
    style::PURPLE,
    style::PINK,
    style::SKY,
    style::OLIVE,
    style::GREY,
];

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

// ---------------------------------------------------------------------------
// Continuation diagram

struct Curve {
    class: usize,
    imag: bool,
    points: Vec<(f64, f64)>,
}

/// Real parts per mode (one branch per distinct root, conjugates merged) and
/// the positive imaginary part per mode, as continuous pieces.
fn continuation_curves(sweep: &EigenSweep) -> Vec<Curve> {
    let mut curves = Vec::new();
    for class in 0..CLASS_NAMES.len() {
        let per_point: Vec<Vec<f64>> = sweep
            .points
            .iter()
            .map(|p| {
                let mut re: Vec<f64> = (0..4)
                    .filter(|&k| mode_class(p.modes[k]) == class && p.eigenvalues[k].im >= 0.0)
                    .map(|k| p.eigenvalues[k].re)
                    .collect();
                re.sort_by(|a, b| b.total_cmp(a));
                re
            })
            .collect();
        let branches = per_point.iter().map(Vec::len).max().unwrap_or(0);
        for b in 0..branches {
            let mut cur = Vec::new();
            for (p, re) in sweep.points.iter().zip(&per_point) {
                match re.get(b) {
                    Some(&r) => cur.push((p.v, r)),
                    None => {
                        if !cur.is_empty() {
                            curves.push(Curve {
                                class,
                                imag: false,
                                points: std::mem::take(&mut cur),
                            });
                        }
                    }
                }
            }
            if !cur.is_empty() {
                curves.push(Curve {
                    class,
                    imag: false,
                    points: cur,
                });
            }
        }
        // Imaginary part: largest positive imaginary part of the class; pieces
        // start/end at the neighbouring samples where it is zero.
        let im: Vec<Option<f64>> = sweep
            .points
            .iter()
            .map(|p| {
                let ks: Vec<usize> = (0..4).filter(|&k| mode_class(p.modes[k]) == class).collect();
                if ks.is_empty() {
                    None
                } else {
                    Some(ks.iter().map(|&k| p.eigenvalues[k].im.abs()).fold(0.0, f64::max))
                }
            })
            .collect();
        let n = im.len();
        let positive = |k: usize| im[k].is_some_and(|x| x > 0.0);
        let mut cur: Vec<(f64, f64)> = Vec::new();
        for k in 0..n {
            let include =
                positive(k) || (im[k].is_some() && ((k > 0 && positive(k - 1)) || (k + 1 < n && positive(k + 1))));
            if include {
                cur.push((sweep.points[k].v, im[k].unwrap_or(0.0)));
                if !positive(k) && cur.len() > 1 {
                    curves.push(Curve {
                        class,
                        imag: true,
                        points: std::mem::take(&mut cur),
                    });
                    // A zero sample can also start the next piece.
                    if k + 1 < n && positive(k + 1) {
                        cur.push((sweep.points[k].v, 0.0));
                    }
                }
            } else if !cur.is_empty() {
                if cur.len() > 1 {
                    curves.push(Curve {
                        class,
                        imag: true,
                        points: std::mem::take(&mut cur),
                    });
                }
                cur.clear();
            }
        }
        if cur.len() > 1 {
            curves.push(Curve {
                class,
                imag: true,
                points: cur,
            });
        }
    }
    curves
}

struct Continuation<'a> {
    critical: Option<&'a CriticalSpeeds>,
    curves: Vec<Curve>,
    xr: (f64, f64),
    yr: (f64, f64),
}

/// Draw the continuation diagram of `sweep` (real parts solid, imaginary parts
/// dashed, one colour per mode and per merged pair) to `path` (`.svg` or
/// `.png`).
///
/// With `critical`, the self-stable speed intervals are shaded and `v_d`,
/// `v_w`, `v_c` are marked and labelled above the plot, in rows when they are
/// close (if in the plotted range and [`PlotOptions::show_stable_band`] is
/// set).
pub fn plot_continuation(
    path: impl AsRef<Path>,
    sweep: &EigenSweep,
    critical: Option<&CriticalSpeeds>,
    opts: &PlotOptions,
) -> Result<(), PlotError> {
    let path = path.as_ref();
    ImageFormat::from_path(path)?;
    opts.check(path)?;
    if sweep.points.is_empty() {
        return Err(PlotError::NoData {
            path: path.to_path_buf(),
        });
    }
    let curves = continuation_curves(sweep);
    let xr = opts.x_range.unwrap_or_else(|| {
        let lo = sweep.points.iter().map(|p| p.v).fold(f64::INFINITY, f64::min);
        let hi = sweep.points.iter().map(|p| p.v).fold(f64::NEG_INFINITY, f64::max);
        if hi > lo {
            (lo, hi)
        } else {
            padded(lo, hi, 0.0)
        }
    });
    let yr = opts.y_range.unwrap_or_else(|| {
        let vals = curves
            .iter()
            .flat_map(|c| c.points.iter())
            .filter(|p| p.0 >= xr.0 && p.0 <= xr.1)
            .map(|p| p.1)
            .chain([0.0]);
        let (lo, hi) = vals.fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), y| (l.min(y), h.max(y)));
        padded(lo, hi, 0.05)
    });
    render(
        path,
        opts,
        &Continuation {
            critical,
            curves,
            xr,
            yr,
        },
    )
}

/// Layout of "main, subscript, rest" (e.g. "v", "w", " = 4.29 m/s"): x
/// offsets of the three parts and the total width. Leading spaces of the rest
/// become an explicit gap (SVG viewers drop leading whitespace in text).
pub(crate) fn subscript_layout(
    root: &Area<'_>,
    parts: (&str, &str, &str),
    o: &PlotOptions,
) -> Result<([i32; 3], i32), DrawErr> {
    let main = o.font(1.0);
    let small = o.font(0.72);
    let w1 = root.estimate_text_size(parts.0, &main).map_err(de)?.0 as i32;
    let w2 = root.estimate_text_size(parts.1, &small).map_err(de)?.0 as i32;
    let rest = parts.2.trim_start();
    let gap = if rest.len() < parts.2.len() {
        o.pxi(o.font_size * 0.3)
    } else {
        o.pxi(1.0)
    };
    let w3 = root.estimate_text_size(rest, &main).map_err(de)?.0 as i32;
    Ok(([0, w1, w1 + w2 + gap], w1 + w2 + gap + w3))
}

/// Draw a subscripted label (see [`subscript_layout`]) with its top-left at `(x, y)`.
pub(crate) fn draw_subscripted(
    root: &Area<'_>,
    (x, y): (i32, i32),
    parts: (&str, &str, &str),
    o: &PlotOptions,
) -> Result<(), DrawErr> {
    let (off, _) = subscript_layout(root, parts, o)?;
    let main = o.font(1.0);
    root.draw(&Text::new(parts.0.to_string(), (x + off[0], y), main.clone()))
        .map_err(de)?;
    root.draw(&Text::new(
        parts.1.to_string(),
        (x + off[1], y + o.pxi(o.font_size * 0.45)),
        o.font(0.72),
    ))
    .map_err(de)?;
    root.draw(&Text::new(parts.2.trim_start().to_string(), (x + off[2], y), main))
        .map_err(de)?;
    Ok(())
}

/// Labels of marked speeds, placed in rows above the plot: each centred on
/// its line when it can be, moved to the next row when it would overlap a
/// label already placed. `marks` are `(pixel x, label width)`; `(x0, x1)`
/// the plot's pixel range. Returns each label's left edge and row.
pub(crate) fn layout_mark_labels(marks: &[(i32, i32)], (x0, x1): (i32, i32), gap: i32) -> Vec<(i32, usize)> {
    let mut order: Vec<usize> = (0..marks.len()).collect();
    order.sort_by_key(|&k| marks[k].0);
    let mut placed: Vec<(i32, i32, usize)> = Vec::new();
    let mut out = vec![(0, 0); marks.len()];
    for k in order {
        let (x, w) = marks[k];
        let left = (x - w / 2).clamp(x0, (x1 - w).max(x0));
        let mut row = 0;
        while placed
            .iter()
            .any(|&(a, b, r)| r == row && left < b + gap && left + w + gap > a)
        {
            row += 1;
        }
        placed.push((left, left + w, row));
        out[k] = (left, row);
    }
    out
}

impl Figure for Continuation<'_> {
    fn draw(&self, root: &Area<'_>, o: &PlotOptions) -> Result<(), DrawErr> {
        let (xr, yr) = (self.xr, self.yr);
        root.fill(&WHITE).map_err(de)?;
        let area = style::titled(root, o, "eigenvalues over forward speed")?;

        let band = o.show_stable_band.then_some(self.critical).flatten();
        let stable: Vec<(f64, f64)> = band
            .map(|cs| {
                cs.stable_intervals
                    .iter()
                    .map(|[lo, hi]| (lo.max(xr.0), hi.min(xr.1)))
                    .filter(|(lo, hi)| hi > lo)
                    .collect()
            })
            .unwrap_or_default();
        // Marked speeds: v_d (at the double real root when known), v_w, v_c.
        let marks: Vec<(f64, &str, Option<f64>)> = band
            .map(|cs| {
                [
                    (cs.weave_real_pair_merge, "d", cs.weave_merge_eigenvalue),
                    (cs.weave_speed, "w", Some(0.0)),
                    (cs.capsize_speed, "c", Some(0.0)),
                ]
                .into_iter()
                .filter_map(|(v, s, y)| v.filter(|v| *v >= xr.0 && *v <= xr.1).map(|v| (v, s, y)))
                .collect()
            })
            .unwrap_or_default();

        let mut legend = Legend::default();
        let mut classes: Vec<usize> = self.curves.iter().map(|c| c.class).collect();
        classes.sort();
        classes.dedup();
        for &cl in &classes {
            legend.add(CLASS_NAMES[cl], Icon::Line(Stroke::solid(CLASS_COLORS[cl])));
        }
        legend.add("real part", Icon::Line(Stroke::solid(style::DATA)));
        if self.curves.iter().any(|c| c.imag) {
            legend.add("imaginary part", Icon::Line(Stroke::dashed(style::DATA)));
        }
        if !stable.is_empty() {
            legend.add("self-stable", Icon::Patch(BAND, 0.25));
        }
        let data: Vec<&[(f64, f64)]> = self.curves.iter().map(|c| c.points.as_slice()).collect();

        // Mark labels above the plot: rows as needed.
        let texts: Vec<String> = marks
            .iter()
            .map(|(v, _, _)| format!(" = {} m/s", fmt_speed(*v)))
            .collect();
        let widths: Vec<i32> = marks
            .iter()
            .zip(&texts)
            .map(|((_, sub, _), t)| subscript_layout(root, ("v", sub, t), o).map(|l| l.1))
            .collect::<Result<_, _>>()?;
        let row_h = o.font_size * 1.35;
        let gap = o.pxi(10.0);
        let layout_on = |chart: &style::Chart<'_, '_>| {
            let r = chart.plotting_area().get_pixel_range();
            let pos: Vec<(i32, i32)> = marks
                .iter()
                .zip(&widths)
                .map(|((v, _, _), w)| (chart.backend_coord(&(*v, yr.1)).0, *w))
                .collect();
            layout_mark_labels(&pos, (r.0.start, r.0.end), gap)
        };
        let rows_of = |l: &[(i32, usize)]| l.iter().map(|p| p.1 + 1).max().unwrap_or(0);
        let first = style::chart(&area, o, xr, yr, Frame::default())?;
        let rows = rows_of(&layout_on(&first));
        drop(first);
        let frame = Frame {
            top: rows as f64 * row_h,
            ..Frame::default()
        };
        let (mut chart, place, frame) = style::chart_with_legend(&area, o, xr, yr, frame, &legend, &data, &[])?;
        let mut layout = layout_on(&chart);
        if rows_of(&layout) > rows {
            let f = Frame {
                top: rows_of(&layout) as f64 * row_h,
                ..frame
            };
            chart = style::chart(&area, o, xr, yr, f)?;
            layout = layout_on(&chart);
        }
        let xl = o.x_label.clone().unwrap_or_else(|| "forward speed v (m/s)".into());
        let yl = o.y_label.clone().unwrap_or_else(|| "eigenvalue (1/s)".into());
        style::mesh(&mut chart, o, &xl, &yl)?;
        for (lo, hi) in &stable {
            chart
                .draw_series(std::iter::once(Rectangle::new(
                    [(*lo, yr.0), (*hi, yr.1)],
                    BAND.mix(0.13).filled(),
                )))
                .map_err(de)?;
        }
        if yr.0 <= 0.0 && yr.1 >= 0.0 {
            style::hline(&mut chart, o, 0.0)?;
        }
        for (v, _, _) in &marks {
            style::vline(&mut chart, o, *v, style::MARK)?;
        }
        // Curves: imaginary (dashed) first so real parts are on top.
        for imag in [true, false] {
            for c in self.curves.iter().filter(|c| c.imag == imag) {
                let s = if imag {
                    Stroke::dashed(CLASS_COLORS[c.class])
                } else {
                    Stroke::solid(CLASS_COLORS[c.class])
                };
                style::curve(&mut chart, o, &c.points, s)?;
            }
        }
        style::frame(&mut chart, o)?;
        for (v, _, y) in &marks {
            if let Some(y) = y.filter(|y| *y >= yr.0 && *y <= yr.1) {
                chart
                    .draw_series(std::iter::once(Circle::new((*v, y), o.pxu(4.0), BLACK.filled())))
                    .map_err(de)?;
            }
        }
        // Labels above the plot, bottom row nearest to it.
        let top = chart.plotting_area().get_pixel_range().1.start;
        let (ox, oy) = {
            let r = root.get_pixel_range();
            (r.0.start, r.1.start)
        };
        let total = rows_of(&layout);
        for (((_, sub, _), t), (left, row)) in marks.iter().zip(&texts).zip(&layout) {
            let y = top - (total - row) as i32 * o.pxi(row_h) - o.pxi(2.0);
            draw_subscripted(root, (left - ox, y - oy), ("v", sub, t), o)?;
        }
        legend.draw(root, &chart, o, place)
    }
}

fn fmt_speed(v: f64) -> String {
    format!("{v:.2}")
}

// ---------------------------------------------------------------------------
// Stability map

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
    let s = t * (C.len() - 1) as f64;
    let k = (s.floor() as usize).min(C.len() - 2);
    let f = s - k as f64;
    let lerp = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    RGBColor(
        lerp(C[k].0, C[k + 1].0),
        lerp(C[k].1, C[k + 1].1),
        lerp(C[k].2, C[k + 1].2),
    )
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
    let s = t * (C.len() - 1) as f64;
    let k = (s.floor() as usize).min(C.len() - 2);
    let f = s - k as f64;
    let lerp = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    RGBColor(
        lerp(C[k].0, C[k + 1].0),
        lerp(C[k].1, C[k + 1].1),
        lerp(C[k].2, C[k + 1].2),
    )
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

    #[test]
    fn plot_cell_edges_and_colormap() {
        assert_eq!(cell_edges(&[0.0, 1.0, 3.0]), vec![(-0.5, 0.5), (0.5, 2.0), (2.0, 4.0)]);
        assert_eq!(cell_edges(&[2.0]), vec![(1.5, 2.5)]);
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(f64::NAN), RGBColor(68, 1, 84));
    }

    /// Issue 20: the colours of merged pairs differ from every single
    /// mode's (and from one another).
    #[test]
    fn issue_20_merged_pair_colours_are_distinct() {
        let d = |a: RGBColor, b: RGBColor| {
            ((a.0 as f64 - b.0 as f64).powi(2) + (a.1 as f64 - b.1 as f64).powi(2) + (a.2 as f64 - b.2 as f64).powi(2))
                .sqrt()
        };
        for merged in 3..6 {
            for other in 0..7 {
                if other != merged {
                    let dist = d(CLASS_COLORS[merged], CLASS_COLORS[other]);
                    assert!(dist > 60.0, "{} vs {}: {dist}", CLASS_NAMES[merged], CLASS_NAMES[other]);
                }
            }
        }
    }

    /// Issue 20: labels of close speeds go on separate rows; distant ones
    /// share the first.
    #[test]
    fn issue_20_mark_labels_keep_apart() {
        let l = layout_mark_labels(&[(100, 80), (130, 80), (400, 80)], (0, 800), 10);
        assert_eq!(l[0].1, 0);
        assert_eq!(l[1].1, 1);
        assert_eq!(l[2].1, 0);
        // Clamped inside the plot.
        assert_eq!(layout_mark_labels(&[(5, 80)], (0, 800), 10)[0].0, 0);
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
