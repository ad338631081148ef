//! Reading measured runs: the thesis-style run folders of
//! `shared/data/FORMAT.md` and the TU Delft steer-by-wire kick logs, into
//! the runtime's records (`bikedyn_runtime::experiment::records`).
//!
//! The reader tolerates a byte-order mark, CRLF line ends, `#` comment lines,
//! blank lines, surrounding spaces and header variants (`time_s`, `time`, `t`;
//! `q0..q3`, `qw,qx,qy,qz`, `w,x,y,z`; case-insensitive). Everything else that
//! is wrong is an error naming the file and the line: a run with one is
//! reported and skipped by the pipeline; the other runs still go through.

use crate::capped::{read_capped, MAX_DATA_FILE_BYTES, MAX_LOG_FILE_BYTES};
use bikedyn_runtime::experiment::records::{Gap, ImuRecord, RunMeta, SwitchRecord, ThesisRun, TudelftLog};
use nalgebra::{Quaternion, UnitQuaternion};
use std::path::{Path, PathBuf};

mod meta;
pub use meta::{read_meta, MAX_MAGNETS, MAX_RATE_HZ};

/// Quaternion norms within this distance of 1 are taken as they are (the
/// files print 7 decimals, so rounding alone gives ~1e-7).
pub const QUAT_ROUNDING_TOL: f64 = 1e-4;
/// Quaternion norms within this distance of 1 are normalised and counted;
/// farther ones are an error (a corrupt row, not a rounding effect).
pub const QUAT_NORMALISE_TOL: f64 = 0.05;
/// A time step longer than this many nominal sample periods is a gap.
pub const GAP_FACTOR: f64 = 1.5;

/// A problem in a measured file. Every variant names the file; row problems
/// name the line (1-based, counting header and comment lines).
#[derive(Debug, thiserror::Error)]
pub enum ReadError {
    /// The file could not be read.
    #[error("{}: {source}", path.display())]
    Io {
        /// File.
        path: PathBuf,
        /// Cause.
        source: std::io::Error,
    },
    /// No header line.
    #[error("{}: empty file (no header line)", path.display())]
    Empty {
        /// File.
        path: PathBuf,
    },
    /// A header without a needed column.
    #[error("{}:{line}: header has no column `{column}` (found: {found})", path.display())]
    MissingColumn {
        /// File.
        path: PathBuf,
        /// Line of the header.
        line: usize,
        /// Needed column.
        column: &'static str,
        /// The header as read.
        found: String,
    },
    /// A row with the wrong number of fields (not the last line).
    #[error("{}:{line}: malformed row: expected {expected} fields, found {found}", path.display())]
    FieldCount {
        /// File.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Fields in the header.
        expected: usize,
        /// Fields in the row.
        found: usize,
    },
    /// A field that is not a number.
    #[error("{}:{line}: malformed row: column `{column}`: `{text}` is not a number", path.display())]
    NotANumber {
        /// File.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Column name from the header.
        column: String,
        /// The field.
        text: String,
    },
    /// NaN or infinity.
    #[error("{}:{line}: column `{column}` is {text} (not a finite number)", path.display())]
    NotFinite {
        /// File.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Column name.
        column: String,
        /// The field.
        text: String,
    },
    /// A time stamp earlier than the one before.
    #[error("{}:{line}: time {t} s goes back from {previous} s at line {previous_line}", path.display())]
    NonMonotonicTime {
        /// File.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Time stamp (s).
        t: f64,
        /// Previous time stamp (s).
        previous: f64,
        /// Its line.
        previous_line: usize,
    },
    /// The same time stamp twice.
    #[error("{}:{line}: time {t} s duplicates line {previous_line}", path.display())]
    DuplicateTime {
        /// File.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Time stamp (s).
        t: f64,
        /// Line of the first one.
        previous_line: usize,
    },
    /// A quaternion whose norm is far from 1.
    #[error("{}:{line}: quaternion norm {norm:.6} is more than {tol} from 1", path.display())]
    QuaternionNorm {
        /// File.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Its norm.
        norm: f64,
        /// Tolerance ([`QUAT_NORMALISE_TOL`]).
        tol: f64,
    },
    /// The last row is cut off (no line end and too few fields, or a field cut
    /// in the middle).
    #[error("{}:{line}: file is truncated (last row incomplete: `{text}`)", path.display())]
    Truncated {
        /// File.
        path: PathBuf,
        /// Line.
        line: usize,
        /// The incomplete row.
        text: String,
    },
    /// A header but no data.
    #[error("{}: no data rows", path.display())]
    NoData {
        /// File.
        path: PathBuf,
    },
    /// The two IMU files of a run disagree.
    #[error("{}:{line}: time stamp {t} s differs from {other} (the IMU files share one clock)", path.display())]
    ClockMismatch {
        /// File.
        path: PathBuf,
        /// Line.
        line: usize,
        /// Its time stamp (s).
        t: f64,
        /// The other file.
        other: String,
    },
    /// The two IMU files have different lengths.
    #[error("{}: {rows} rows, but {other} has {other_rows} (one file is truncated)", path.display())]
    LengthMismatch {
        /// File.
        path: PathBuf,
        /// Its rows.
        rows: usize,
        /// Other file.
        other: String,
        /// Its rows.
        other_rows: usize,
    },
    /// The handlebar record is the frame's, sample for sample (a copy).
    #[error("{}: the same orientations as {other}, sample for sample: one sensor's file given for both (the steer angle would be zero throughout); give each sensor's own record", path.display())]
    SameImuRecord { path: PathBuf, other: String },
    /// A row that repeats the one before it in every field: a sample
    /// logged twice. In a log without a time column the times come from the
    /// row count, so repeated rows would stretch them (every row twice
    /// halves the measured frequencies).
    #[error(
        "{}:{line}: row repeats line {previous_line} field for field (a sample logged twice; the log has no time column, so its times come from counting rows and a repeated row stretches them): remove the repeated rows",
        path.display()
    )]
    RepeatedRow {
        /// File.
        path: PathBuf,
        /// Line of the repetition.
        line: usize,
        /// Line it repeats.
        previous_line: usize,
    },
    /// A forward speed no bicycle rides at (or a column in other units).
    #[error(
        "{}:{line}: column `speed` is {speed} m/s, not a bicycle's speed (from {MIN_LOG_SPEED_M_S} to {MAX_SPEED_M_S} m/s): check the column's units and the row",
        path.display()
    )]
    ImplausibleSpeed {
        /// File.
        path: PathBuf,
        /// Line.
        line: usize,
        /// The speed (m/s).
        speed: f64,
    },
    /// A bad `run.toml`.
    #[error("{}: {message}", path.display())]
    Metadata {
        /// File.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
}

/// One numeric table: columns in the order asked for, with each row's line.
struct Table {
    cols: Vec<Vec<f64>>,
    lines: Vec<usize>,
}

fn normalise_name(s: &str) -> String {
    s.trim().trim_matches('"').to_ascii_lowercase().replace([' ', '-'], "_")
}

/// Read a comma-separated numeric table. `wanted` lists, per column, the
/// accepted header names (first = canonical name used in messages).
/// With `no_repeats`, a data row equal to the one before it in every field
/// is an error ([`ReadError::RepeatedRow`]): for files without a time
/// column, where nothing else would notice.
fn read_table(path: &Path, wanted: &[&[&'static str]], limit: u64, no_repeats: bool) -> Result<Table, ReadError> {
    let bytes = read_capped(path, limit).map_err(|source| ReadError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let text = String::from_utf8_lossy(&bytes);
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    let ends_with_newline = text.ends_with('\n');
    let all: Vec<&str> = text.split('\n').collect();
    // Index of the last non-empty line, for truncation checks.
    let last_nonempty = all.iter().rposition(|l| !l.trim().is_empty());
    let mut header: Option<(usize, Vec<usize>, usize)> = None; // (line, indices, n_fields)
    let mut cols: Vec<Vec<f64>> = vec![Vec::new(); wanted.len()];
    let mut lines = Vec::new();
    // One buffer of fields for every line (a log has 10^4 lines).
    let mut fields: Vec<&str> = Vec::new();
    let mut previous_row: Option<(&str, usize)> = None;
    for (i, raw) in all.iter().enumerate() {
        let line_no = i + 1;
        let l = raw.trim_end_matches('\r').trim();
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        fields.clear();
        fields.extend(l.split(',').map(|f| f.trim()));
        let Some((_, idx, n_fields)) = &header else {
            let names: Vec<String> = fields.iter().map(|f| normalise_name(f)).collect();
            let mut idx = Vec::new();
            for w in wanted {
                match names.iter().position(|n| w.iter().any(|a| a == n)) {
                    Some(k) => idx.push(k),
                    None => {
                        return Err(ReadError::MissingColumn {
                            path: path.to_path_buf(),
                            line: line_no,
                            column: w[0],
                            // A "header" of a file that is no table can be
                            // megabytes long: echo its start.
                            found: clip_lines(l, MAX_ECHOED_CHARS),
                        });
                    }
                }
            }
            header = Some((line_no, idx, fields.len()));
            continue;
        };
        let is_last = Some(i) == last_nonempty;
        let truncated = |text: &str| ReadError::Truncated {
            path: path.to_path_buf(),
            line: line_no,
            text: text.to_string(),
        };
        if fields.len() != *n_fields {
            if is_last && !ends_with_newline && fields.len() < *n_fields {
                return Err(truncated(l));
            }
            return Err(ReadError::FieldCount {
                path: path.to_path_buf(),
                line: line_no,
                expected: *n_fields,
                found: fields.len(),
            });
        }
        for (c, &k) in idx.iter().enumerate() {
            let f = fields[k];
            let v: f64 = match f.parse() {
                Ok(v) => v,
                Err(_) => {
                    if is_last && !ends_with_newline {
                        return Err(truncated(l));
                    }
                    return Err(ReadError::NotANumber {
                        path: path.to_path_buf(),
                        line: line_no,
                        column: wanted[c][0].to_string(),
                        text: f.to_string(),
                    });
                }
            };
            if !v.is_finite() {
                return Err(ReadError::NotFinite {
                    path: path.to_path_buf(),
                    line: line_no,
                    column: wanted[c][0].to_string(),
                    text: f.to_string(),
                });
            }
            cols[c].push(v);
        }
        if let Some((previous, previous_line)) = previous_row.filter(|_| no_repeats) {
            if previous == l {
                return Err(ReadError::RepeatedRow {
                    path: path.to_path_buf(),
                    line: line_no,
                    previous_line,
                });
            }
        }
        previous_row = Some((l, line_no));
        lines.push(line_no);
    }
    if header.is_none() {
        return Err(ReadError::Empty {
            path: path.to_path_buf(),
        });
    }
    if lines.is_empty() {
        return Err(ReadError::NoData {
            path: path.to_path_buf(),
        });
    }
    Ok(Table { cols, lines })
}

/// Check strictly increasing time stamps; return the gaps longer than
/// [`GAP_FACTOR`] nominal periods.
fn check_time(path: &Path, t: &[f64], lines: &[usize], period: f64) -> Result<Vec<Gap>, ReadError> {
    let mut gaps = Vec::new();
    for k in 1..t.len() {
        let dt = t[k] - t[k - 1];
        if dt == 0.0 {
            return Err(ReadError::DuplicateTime {
                path: path.to_path_buf(),
                line: lines[k],
                t: t[k],
                previous_line: lines[k - 1],
            });
        }
        if dt < 0.0 {
            return Err(ReadError::NonMonotonicTime {
                path: path.to_path_buf(),
                line: lines[k],
                t: t[k],
                previous: t[k - 1],
                previous_line: lines[k - 1],
            });
        }
        if dt > GAP_FACTOR * period {
            gaps.push(Gap {
                start: t[k - 1],
                end: t[k],
                line: lines[k],
            });
        }
    }
    Ok(gaps)
}

/// Read `imu_frame.csv` / `imu_handlebar.csv`. `rate_hz` is the nominal rate
/// (for gap detection).
pub fn read_imu(path: &Path, rate_hz: f64) -> Result<ImuRecord, ReadError> {
    let tab = read_table(
        path,
        &[
            &["time_s", "time", "t", "timestamp", "time_sec"],
            &["q0", "qw", "w", "quat_w"],
            &["q1", "qx", "x", "quat_x"],
            &["q2", "qy", "y", "quat_y"],
            &["q3", "qz", "z", "quat_z"],
        ],
        MAX_DATA_FILE_BYTES,
        false,
    )?;
    let t = tab.cols[0].clone();
    let gaps = check_time(path, &t, &tab.lines, 1.0 / rate_hz)?;
    let mut q = Vec::with_capacity(t.len());
    let mut renormalised = 0;
    for k in 0..t.len() {
        let raw = Quaternion::new(tab.cols[1][k], tab.cols[2][k], tab.cols[3][k], tab.cols[4][k]);
        let n = raw.norm();
        if (n - 1.0).abs() > QUAT_NORMALISE_TOL {
            return Err(ReadError::QuaternionNorm {
                path: path.to_path_buf(),
                line: tab.lines[k],
                norm: n,
                tol: QUAT_NORMALISE_TOL,
            });
        }
        if (n - 1.0).abs() > QUAT_ROUNDING_TOL {
            renormalised += 1;
        }
        q.push(UnitQuaternion::from_quaternion(raw));
    }
    Ok(ImuRecord {
        path: path.to_path_buf(),
        t,
        q,
        renormalised,
        gaps,
        lines: tab.lines,
    })
}

/// Read `speed_switch.csv`.
pub fn read_switch(path: &Path, rate_hz: f64) -> Result<SwitchRecord, ReadError> {
    let tab = read_table(
        path,
        &[
            &["time_s", "time", "t", "timestamp", "time_sec"],
            &["volts", "voltage", "v", "volt", "voltage_v", "volts_v"],
        ],
        MAX_DATA_FILE_BYTES,
        false,
    )?;
    let t = tab.cols[0].clone();
    let gaps = check_time(path, &t, &tab.lines, 1.0 / rate_hz)?;
    Ok(SwitchRecord {
        path: path.to_path_buf(),
        t,
        volts: tab.cols[1].clone(),
        gaps,
    })
}

/// The most characters of one line of a file echoed in a message: the
/// TOML parser quotes the offending line, which may be a 200 KB line of
/// nested brackets.
pub const MAX_ECHOED_CHARS: usize = 160;

/// `text` with each line cut to `max` characters (marked with how many
/// more there were).
pub fn clip_lines(text: &str, max: usize) -> String {
    text.lines()
        .map(|l| {
            let n = l.chars().count();
            if n > max {
                format!(
                    "{}... ({} more characters)",
                    l.chars().take(max).collect::<String>(),
                    n - max
                )
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Read a run folder (or the calibration folder).
pub fn read_run(dir: &Path) -> Result<ThesisRun, ReadError> {
    let (meta, frame, handlebar) = read_run_orientations(dir)?;
    let switch = read_switch(&dir.join(&meta.switch_file), meta.switch_rate_hz)?;
    Ok(ThesisRun {
        dir: dir.to_path_buf(),
        meta,
        frame,
        handlebar,
        switch,
    })
}

/// Read a run folder's `run.toml` and its two IMU records, checked against
/// each other as [`read_run`] checks them, without the reed switch's
/// record (the largest file of a run: a set's steer axis needs only the
/// orientations).
pub fn read_run_orientations(dir: &Path) -> Result<(RunMeta, ImuRecord, ImuRecord), ReadError> {
    let meta = read_meta(&dir.join("run.toml"))?;
    let frame = read_imu(&dir.join(&meta.imu_files[0]), meta.imu_rate_hz)?;
    let handlebar = read_imu(&dir.join(&meta.imu_files[1]), meta.imu_rate_hz)?;
    if frame.t.len() != handlebar.t.len() {
        // The shorter one ends early: name it.
        let (short, long) = if frame.t.len() < handlebar.t.len() {
            (&frame, &handlebar)
        } else {
            (&handlebar, &frame)
        };
        return Err(ReadError::LengthMismatch {
            path: short.path.clone(),
            rows: short.t.len(),
            other: long.path.display().to_string(),
            other_rows: long.t.len(),
        });
    }
    // One sensor's file copied under both names: a steer of zero throughout.
    if frame.q == handlebar.q {
        return Err(ReadError::SameImuRecord {
            path: handlebar.path.clone(),
            other: frame.path.display().to_string(),
        });
    }
    // Same clock: stamps agree to the printed resolution.
    let tol = 0.25 / meta.imu_rate_hz;
    for k in 0..frame.t.len() {
        if (frame.t[k] - handlebar.t[k]).abs() > tol {
            return Err(ReadError::ClockMismatch {
                path: handlebar.path.clone(),
                line: handlebar.lines[k],
                t: handlebar.t[k],
                other: frame.path.display().to_string(),
            });
        }
    }
    Ok((meta, frame, handlebar))
}

/// Highest forward speed read from a log or an eigenvalue table (m/s, 108
/// km/h): faster than a bicycle is ridden for a measurement; a larger
/// value is a fault or other units.
pub const MAX_SPEED_M_S: f64 = 30.0;

/// Lowest speed of a log row (m/s): a wheel sensor at rest reads a little
/// below zero with its noise; riding backwards is no bicycle measurement.
pub const MIN_LOG_SPEED_M_S: f64 = -0.1;

/// Sample period of the TU Delft logs (s): they have no time column.
pub const TUDELFT_PERIOD_S: f64 = 0.01;

/// Read a TU Delft log (13-column CSV with header; columns found by name).
pub fn read_tudelft(path: &Path) -> Result<TudelftLog, ReadError> {
    let tab = read_table(
        path,
        &[
            &["speed", "speed_m_s", "speed_(m/s)"],
            &["lean_angle", "roll_angle", "lean"],
            &["lean_rate", "roll_rate"],
            &["hand_angle", "handlebar_angle", "steer_angle"],
            &["fork_angle"],
        ],
        MAX_LOG_FILE_BYTES,
        true,
    )?;
    if let Some(k) = tab.cols[0]
        .iter()
        .position(|&v| !(MIN_LOG_SPEED_M_S..=MAX_SPEED_M_S).contains(&v))
    {
        return Err(ReadError::ImplausibleSpeed {
            path: path.to_path_buf(),
            line: tab.lines[k],
            speed: tab.cols[0][k],
        });
    }
    let n = tab.lines.len();
    Ok(TudelftLog {
        path: path.to_path_buf(),
        t: (0..n).map(|k| k as f64 * TUDELFT_PERIOD_S).collect(),
        speed: tab.cols[0].clone(),
        roll: tab.cols[1].clone(),
        roll_rate: tab.cols[2].clone(),
        steer: tab.cols[3].clone(),
        fork: tab.cols[4].clone(),
        lines: tab.lines,
    })
}
