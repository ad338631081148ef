//! Fonts for plot text: the font file is found (the options, the
//! environment, common system locations, a scan of the font directories),
//! read once and registered with plotters' text engine (see the module
//! docs of [`super`] under *Fonts*).
//!
//! Apart because it is the one part of plotting that touches the system
//! and keeps process-wide state (the fonts registered so far).

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use super::{PlotError, PlotOptions};

/// Environment variable naming a TTF/OTF font file for plot text.
pub const FONT_ENV: &str = "BIKEDYN_FONT";

/// The largest font file read (bytes): the largest common fonts (CJK
/// collections) are about 30 MB; a larger file is not a font and would be
/// held in memory for good.
pub const MAX_FONT_BYTES: u64 = 64 << 20;

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
    plotters::style::register_font(super::FAMILY, plotters::style::FontStyle::Normal, bytes).map_err(|_| {
        PlotError::Font {
            path: path.to_path_buf(),
            message: "not a valid TrueType/OpenType font".into(),
        }
    })
}

pub(super) fn ensure_font(opts: &PlotOptions) -> Result<(), PlotError> {
    if let Some(p) = &opts.font_path {
        return use_font(p);
    }
    if DEFAULT_FONT.lock().unwrap_or_else(|e| e.into_inner()).is_some() {
        return Ok(());
    }
    use_font(find_font()?)
}
