//! A run folder's `run.toml`: which run it is, its sensors' files, rates
//! and clock offset, and the wheel's magnets and circumference, read into
//! the runtime's [`RunMeta`].

use super::*;
use crate::capped::{read_text_capped, MAX_TEXT_FILE_BYTES};
use bikedyn_runtime::experiment::records::RunKind;

/// Most magnets a wheel carries (real set-ups use 1 to a few dozen).
pub const MAX_MAGNETS: usize = 1000;

/// Highest sample rate accepted (Hz).
pub const MAX_RATE_HZ: f64 = 1e6;

/// Read `run.toml`.
pub fn read_meta(path: &Path) -> Result<RunMeta, ReadError> {
    let text = read_text_capped(path, MAX_TEXT_FILE_BYTES).map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let meta = |message: String| ReadError::Metadata {
        path: path.to_path_buf(),
        message,
    };
    let v: toml::Table = text
        .parse()
        .map_err(|e: toml::de::Error| meta(clip_lines(&e.to_string(), MAX_ECHOED_CHARS)))?;
    let num = |sec: &str, key: &str| -> Result<f64, ReadError> {
        let x = v
            .get(sec)
            .and_then(|s| s.get(key))
            .ok_or_else(|| meta(format!("missing [{sec}] {key}")))?;
        let x = x
            .as_float()
            .or_else(|| x.as_integer().map(|i| i as f64))
            .ok_or_else(|| meta(format!("[{sec}] {key} is not a number")))?;
        if !x.is_finite() {
            return Err(meta(format!("[{sec}] {key} is not finite")));
        }
        Ok(x)
    };
    let kind = match v.get("kind").and_then(|k| k.as_str()) {
        Some("run") | None => RunKind::Run,
        Some("calibration") => RunKind::Calibration,
        Some(other) => {
            return Err(meta(format!(
                "kind = \"{other}\" (expected \"run\" or \"calibration\")"
            )))
        }
    };
    // A run's files live in its folder: a plain file name, never an
    // absolute path or a way out of the folder (`..`), so that reading a run
    // cannot reach, or echo in a message, another file of the machine.
    let inside = |key: &str, name: &str| -> Result<String, ReadError> {
        let p = Path::new(name);
        let plain = !name.is_empty() && p.components().all(|c| matches!(c, std::path::Component::Normal(_)));
        if plain {
            Ok(name.to_string())
        } else {
            Err(meta(format!(
                "{key} = \"{name}\" must name a file inside the run folder (no absolute path, no `..`)"
            )))
        }
    };
    let imu_files = match v.get("imu").and_then(|s| s.get("files")).and_then(|f| f.as_array()) {
        Some(a) if a.len() == 2 && a.iter().all(|x| x.is_str()) => [
            inside("[imu] files", a[0].as_str().unwrap_or_default())?,
            inside("[imu] files", a[1].as_str().unwrap_or_default())?,
        ],
        Some(_) => return Err(meta("[imu] files must list two file names (frame, handlebar)".into())),
        None => ["imu_frame.csv".into(), "imu_handlebar.csv".into()],
    };
    // One sensor read as both: a steer of zero throughout.
    if imu_files[0] == imu_files[1] {
        return Err(meta(format!(
            "[imu] files names \"{}\" twice: give the frame sensor's file, then the handlebar sensor's",
            imu_files[0]
        )));
    }
    // Counts and rates in plausible ranges: a count sizes the arrays built
    // from it (`magnets = 1e9` would ask for gigabytes).
    let magnets = num("speed_switch", "magnets")?;
    if !(magnets >= 1.0 && magnets.fract() == 0.0 && magnets <= MAX_MAGNETS as f64) {
        return Err(meta(format!(
            "[speed_switch] magnets = {magnets} is not a whole number from 1 to {MAX_MAGNETS}"
        )));
    }
    let circ = num("speed_switch", "wheel_circumference_m")?;
    if !(circ > 0.1 && circ < 10.0) {
        return Err(meta(format!(
            "[speed_switch] wheel_circumference_m = {circ} is not a wheel's circumference in metres (0.1 to 10)"
        )));
    }
    let imu_rate_hz = num("imu", "rate_hz")?;
    let switch_rate_hz = num("speed_switch", "rate_hz")?;
    for (key, r) in [
        ("[imu] rate_hz", imu_rate_hz),
        ("[speed_switch] rate_hz", switch_rate_hz),
    ] {
        if !(r >= 1.0 && r <= MAX_RATE_HZ) {
            return Err(meta(format!(
                "{key} = {r} is not a sample rate from 1 to {MAX_RATE_HZ} Hz"
            )));
        }
    }
    Ok(RunMeta {
        name: v
            .get("name")
            .and_then(|n| n.as_str())
            .map(str::to_string)
            .unwrap_or_else(|| {
                path.parent()
                    .and_then(|p| p.file_name())
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default()
            }),
        kind,
        nominal_offset_s: num("clocks", "nominal_offset_s")?,
        imu_rate_hz,
        imu_files,
        switch_rate_hz,
        switch_file: v
            .get("speed_switch")
            .and_then(|s| s.get("file"))
            .and_then(|f| f.as_str())
            .map(|f| inside("[speed_switch] file", f))
            .transpose()?
            .unwrap_or_else(|| "speed_switch.csv".to_string()),
        magnets: magnets as usize,
        wheel_circumference_m: circ,
        supply_v: num("speed_switch", "supply_v").ok(),
    })
}
