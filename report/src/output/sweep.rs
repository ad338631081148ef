//! Parameter sweeps and stability maps: CSV, JSON and terminal tables.

use std::io::Write;
use std::path::Path;

use serde_json::{json, Value};

use bikedyn_runtime::sweep::{CellResult, ParameterSweep, StabilityMap};

use super::*;

const CELL_COLUMNS: [&str; 10] = [
    "weave_speed",
    "capsize_speed",
    "weave_real_pair_merge",
    "stable_width",
    "stable_lo",
    "stable_hi",
    "n_stable_intervals",
    "stable_intervals",
    "open_ended",
    "error",
];

fn cell_fields(c: &CellResult) -> Vec<String> {
    match c {
        Ok(s) => {
            let first = s.first_stable_interval();
            vec![
                opt(s.weave_speed),
                opt(s.capsize_speed),
                opt(s.weave_real_pair_merge),
                num(s.stable_width),
                opt(first.map(|i| i[0])),
                opt(first.map(|i| i[1])),
                s.stable_intervals.len().to_string(),
                s.stable_intervals
                    .iter()
                    .map(|[a, b]| format!("{}:{}", num(*a), num(*b)))
                    .collect::<Vec<_>>()
                    .join(";"),
                s.open_ended.to_string(),
                String::new(),
            ]
        }
        Err(e) => {
            let mut v = vec![String::new(); CELL_COLUMNS.len()];
            v[CELL_COLUMNS.len() - 1] = e.to_string();
            v
        }
    }
}

fn cell_json(c: &CellResult) -> serde_json::Map<String, Value> {
    let mut m = serde_json::Map::new();
    match c {
        Ok(s) => {
            m.insert("weave_speed".into(), json!(s.weave_speed));
            m.insert("capsize_speed".into(), json!(s.capsize_speed));
            m.insert("weave_real_pair_merge".into(), json!(s.weave_real_pair_merge));
            m.insert("stable_intervals".into(), json!(s.stable_intervals));
            m.insert("stable_width".into(), json!(s.stable_width));
            m.insert("open_ended".into(), json!(s.open_ended));
            if s.least_stable_real_part.is_some() {
                m.insert("least_stable_real_part".into(), json!(s.least_stable_real_part));
            }
            m.insert("error".into(), Value::Null);
        }
        Err(e) => {
            for k in [
                "weave_speed",
                "capsize_speed",
                "weave_real_pair_merge",
                "stable_intervals",
                "stable_width",
                "open_ended",
            ] {
                m.insert(k.into(), Value::Null);
            }
            m.insert("error".into(), json!({"stage": e.stage, "message": e.message}));
        }
    }
    m
}

/// Header of the parameter-sweep CSV: the parameter's name, then the cell columns.
pub fn parameter_sweep_csv_header(s: &ParameterSweep) -> Vec<String> {
    std::iter::once(s.param.name.clone())
        .chain(CELL_COLUMNS.iter().map(|c| c.to_string()))
        .collect()
}

/// Write a parameter sweep as CSV, one row per parameter value.
pub fn write_parameter_sweep_csv<W: Write>(w: W, s: &ParameterSweep) -> Result<(), csv::Error> {
    write_parameter_sweep_csv_with(w, s, &[])
}

/// More columns of a sweep, one value per point (empty in CSV and `null`
/// in JSON where `None`): e.g. the critical speeds' standard deviations.
pub type SweepColumns<'a> = &'a [(&'a str, Vec<Option<f64>>)];

/// [`write_parameter_sweep_csv`] with `extra` columns after the others.
pub fn write_parameter_sweep_csv_with<W: Write>(
    w: W,
    s: &ParameterSweep,
    extra: SweepColumns<'_>,
) -> Result<(), csv::Error> {
    let mut wr = csv::Writer::from_writer(w);
    let mut header = parameter_sweep_csv_header(s);
    header.extend(extra.iter().map(|(name, _)| name.to_string()));
    wr.write_record(header)?;
    for (i, (p, c)) in s.param.values.iter().zip(&s.points).enumerate() {
        let mut row = vec![num(*p)];
        row.extend(cell_fields(c));
        row.extend(
            extra
                .iter()
                .map(|(_, v)| v.get(i).copied().flatten().map_or(String::new(), num)),
        );
        wr.write_record(&row)?;
    }
    wr.flush()?;
    Ok(())
}

/// JSON value of a parameter sweep:
/// `{"parameter": name, "speed_range": [lo, hi], "points": [{"value": p, ...cell fields}]}`.
pub fn parameter_sweep_json(s: &ParameterSweep) -> Value {
    parameter_sweep_json_with(s, &[])
}

/// [`parameter_sweep_json`] with `extra` fields in each point.
pub fn parameter_sweep_json_with(s: &ParameterSweep, extra: SweepColumns<'_>) -> Value {
    let points: Vec<Value> = s
        .param
        .values
        .iter()
        .zip(&s.points)
        .enumerate()
        .map(|(i, (p, c))| {
            let mut m = serde_json::Map::new();
            m.insert("value".into(), json!(p));
            m.extend(cell_json(c));
            for (name, v) in extra {
                m.insert(name.to_string(), json!(v.get(i).copied().flatten()));
            }
            Value::Object(m)
        })
        .collect();
    json!({"parameter": s.param.name, "speed_range": s.speed_range, "points": points})
}

/// Header of the stability-map CSV: x name, y name, `i`, `j`, then the cell columns.
pub fn stability_map_csv_header(m: &StabilityMap) -> Vec<String> {
    [m.x.name.clone(), m.y.name.clone(), "i".into(), "j".into()]
        .into_iter()
        .chain(CELL_COLUMNS.iter().map(|c| c.to_string()))
        .collect()
}

/// Write a stability map as long-format CSV, one row per cell, row-major.
pub fn write_stability_map_csv<W: Write>(w: W, m: &StabilityMap) -> Result<(), csv::Error> {
    let mut wr = csv::Writer::from_writer(w);
    wr.write_record(stability_map_csv_header(m))?;
    write_stability_map_csv_rows(&mut wr, m, 0)?;
    wr.flush()?;
    Ok(())
}

/// The rows of `m` (no header), its first-parameter index counted from
/// `i0`: a map computed a row (one value of the first parameter) at a time
/// is streamed as one CSV, the same as [`write_stability_map_csv`] gives
/// for the whole map.
pub fn write_stability_map_csv_rows<W: Write>(
    wr: &mut csv::Writer<W>,
    m: &StabilityMap,
    i0: usize,
) -> Result<(), csv::Error> {
    let (nx, ny) = m.shape();
    for i in 0..nx {
        for j in 0..ny {
            let Some(c) = m.cell(i, j) else { continue };
            let mut row = vec![
                num(m.x.values[i]),
                num(m.y.values[j]),
                (i0 + i).to_string(),
                j.to_string(),
            ];
            row.extend(cell_fields(c));
            wr.write_record(&row)?;
        }
    }
    Ok(())
}

/// JSON value of a stability map:
/// `{"x": {"name", "values"}, "y": {..}, "speed_range": [lo, hi], "layout": "row-major",
///   "cells": [{"i", "j", "x", "y", ...cell fields}]}`.
pub fn stability_map_json(m: &StabilityMap) -> Value {
    let (nx, ny) = m.shape();
    let mut cells = Vec::with_capacity(nx * ny);
    for i in 0..nx {
        for j in 0..ny {
            let Some(c) = m.cell(i, j) else { continue };
            let mut o = serde_json::Map::new();
            o.insert("i".into(), json!(i));
            o.insert("j".into(), json!(j));
            o.insert("x".into(), json!(m.x.values[i]));
            o.insert("y".into(), json!(m.y.values[j]));
            o.extend(cell_json(c));
            cells.push(Value::Object(o));
        }
    }
    json!({
        "x": m.x,
        "y": m.y,
        "speed_range": m.speed_range,
        "layout": "row-major: cells[i * len(y.values) + j] is (x.values[i], y.values[j])",
        "cells": cells,
    })
}

/// Atomically save a parameter sweep as CSV.
pub fn save_parameter_sweep_csv(path: impl AsRef<Path>, s: &ParameterSweep) -> Result<(), OutputError> {
    write_atomic(path, |w| write_parameter_sweep_csv(w, s))
}

/// Atomically save a parameter sweep as JSON.
pub fn save_parameter_sweep_json(path: impl AsRef<Path>, s: &ParameterSweep) -> Result<(), OutputError> {
    save_json(path, &parameter_sweep_json(s))
}

/// Atomically save a stability map as CSV.
pub fn save_stability_map_csv(path: impl AsRef<Path>, m: &StabilityMap) -> Result<(), OutputError> {
    write_atomic(path, |w| write_stability_map_csv(w, m))
}

/// Atomically save a stability map as JSON.
pub fn save_stability_map_json(path: impl AsRef<Path>, m: &StabilityMap) -> Result<(), OutputError> {
    save_json(path, &stability_map_json(m))
}

fn short(x: Option<f64>) -> String {
    x.map(|v| format!("{v:.4}")).unwrap_or_else(|| "-".into())
}

fn summary_row(c: &CellResult) -> Vec<String> {
    match c {
        Ok(s) => vec![
            short(s.weave_speed),
            short(s.capsize_speed),
            format!("{:.4}{}", s.stable_width, if s.open_ended { "+" } else { "" }),
            if s.stable_intervals.is_empty() {
                "-".into()
            } else {
                s.stable_intervals
                    .iter()
                    .map(|[a, b]| format!("[{a:.3}, {b:.3}]"))
                    .collect::<Vec<_>>()
                    .join(" ")
            },
        ],
        Err(e) => vec!["-".into(), "-".into(), "-".into(), format!("error: {e}")],
    }
}

/// A parameter column's header with its unit, `c (m)`, from the symbol's
/// description (`describe`: the model's parameter docs, which end in the
/// unit, as `"steer-axis viscous damping coefficient (N m s/rad)"`, or the
/// thesis and benchmark descriptions); a name with no description as it is.
fn parameter_header(symbol: &str, describe: &dyn Fn(&str) -> Option<String>) -> String {
    let doc = describe(symbol);
    match doc.as_deref().and_then(bikedyn_runtime::model::unit_of) {
        Some(u) => format!("{symbol} ({u})"),
        None => symbol.to_string(),
    }
}

/// The description of a parameter symbol: the thesis and benchmark sets'
/// descriptions, else the doc of the parameter in `model` (effect
/// parameters such as `c_steer`). Each ends in its unit in parentheses.
pub fn describe_parameter(symbol: &str, model: Option<&bikedyn_runtime::registry::ModelInfo>) -> Option<String> {
    use bikedyn_runtime::parameters::{BenchmarkParameters, ThesisParameters};
    BenchmarkParameters::describe(symbol)
        .or_else(|| ThesisParameters::describe(symbol))
        .or_else(|| model?.parameter(symbol).map(|p| p.doc))
        .map(str::to_string)
}

const SUMMARY_HEADER: [&str; 4] = ["v_w (m/s)", "v_c (m/s)", "stable width (m/s)", "stable intervals (m/s)"];

/// Aligned plain-text table of a parameter sweep (`+` marks a width cut off
/// at `speed_max`). `describe` gives a parameter's description ending in its
/// unit in parentheses, for the header (see [`describe_parameter`]).
pub fn format_parameter_table(s: &ParameterSweep, describe: &dyn Fn(&str) -> Option<String>) -> String {
    let header: Vec<String> = std::iter::once(parameter_header(&s.param.name, describe))
        .chain(SUMMARY_HEADER.iter().map(|h| h.to_string()))
        .collect();
    let rows: Vec<Vec<String>> = s
        .param
        .values
        .iter()
        .zip(&s.points)
        .map(|(p, c)| {
            std::iter::once(format_fixed(*p, 6, false))
                .chain(summary_row(c))
                .collect()
        })
        .collect();
    format_table(&header, &rows)
}

/// Aligned plain-text table of a stability map, one line per cell
/// (row-major); `describe` as in [`format_parameter_table`].
pub fn format_stability_map_table(m: &StabilityMap, describe: &dyn Fn(&str) -> Option<String>) -> String {
    let header: Vec<String> = [
        parameter_header(&m.x.name, describe),
        parameter_header(&m.y.name, describe),
    ]
    .into_iter()
    .chain(SUMMARY_HEADER.iter().map(|h| h.to_string()))
    .collect();
    let (nx, ny) = m.shape();
    let mut rows = Vec::with_capacity(nx * ny);
    for i in 0..nx {
        for j in 0..ny {
            if let Some(c) = m.cell(i, j) {
                let mut r = vec![
                    format_fixed(m.x.values[i], 6, false),
                    format_fixed(m.y.values[j], 6, false),
                ];
                r.extend(summary_row(c));
                rows.push(r);
            }
        }
    }
    format_table(&header, &rows)
}
