//! Eigen sweeps: the eigenvalue order, mode shapes, JSON and CSV (whole or
//! streamed) and the terminal table.

use std::io::Write;
use std::path::Path;

use nalgebra::Complex;
use serde_json::{json, Value};

use bikedyn_runtime::eigen::{EigenPoint, EigenSweep, Mode};

use super::*;

fn mode_rank(m: Mode) -> u32 {
    m.rank() as u32
}

/// Indices of a point's eigenvalues in the stable output order: by mode
/// (weave, capsize, castering, merged pairs, other), then descending imaginary
/// part, then descending real part.
pub fn ordered_indices(p: &EigenPoint) -> [usize; 4] {
    output_order(&p.modes, &p.eigenvalues)
}

/// [`ordered_indices`] of eigenvalues and their modes.
pub fn output_order(modes: &[Mode; 4], eigenvalues: &[Complex<f64>; 4]) -> [usize; 4] {
    let mut idx = [0usize, 1, 2, 3];
    // Inline (it runs at every speed of a diagram), as `sort_by` sorts.
    bikedyn_runtime::small_sort::sort4_by(&mut idx, |&a, &b| {
        mode_rank(modes[a])
            .cmp(&mode_rank(modes[b]))
            .then(eigenvalues[b].im.total_cmp(&eigenvalues[a].im))
            .then(eigenvalues[b].re.total_cmp(&eigenvalues[a].re))
    });
    idx
}

/// The eigenvalues of a point with their modes, in the stable output order
/// ([`ordered_indices`]).
pub fn ordered_eigenvalues(p: &EigenPoint) -> [(Complex<f64>, Mode); 4] {
    ordered_indices(p).map(|k| (p.eigenvalues[k], p.modes[k]))
}

/// Roll and steer components of an eigenvector (a mode shape), normalised so
/// that the roll component is 1 (amplitude 1, phase 0), as the eigenvector
/// components of the benchmark are presented (Meijaard et al. 2007, Fig. 4:
/// components relative to the roll angle); a mode without roll (roll
/// amplitude below `1e-12` of steer) is normalised on the steer component
/// instead. Phases in rad, in `(-pi, pi]`; for a real eigenvalue the phase is
/// 0 or pi (steer in or against the roll direction). Benchmark sign
/// convention (roll right, steer right positive).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ModeShape {
    /// Roll amplitude (1 unless the mode has no roll).
    pub roll_amplitude: f64,
    /// Roll phase (rad).
    pub roll_phase: f64,
    /// Steer amplitude relative to roll (rad per rad).
    pub steer_amplitude: f64,
    /// Steer phase relative to roll (rad).
    pub steer_phase: f64,
}

/// The [`ModeShape`] of an eigenvector `x = [phi, delta, phi', delta']`.
pub fn mode_shape(x: &[Complex<f64>; 4]) -> ModeShape {
    let (roll, steer) = (x[0], x[1]);
    let reference = if roll.norm() > 1e-12 * steer.norm() {
        roll
    } else {
        steer
    };
    if !(reference.norm() > 0.0) {
        return ModeShape {
            roll_amplitude: 0.0,
            roll_phase: 0.0,
            steer_amplitude: 0.0,
            steer_phase: 0.0,
        };
    }
    let phase = |z: Complex<f64>| if z.norm() == 0.0 { 0.0 } else { z.im.atan2(z.re) + 0.0 };
    let (r, d) = (roll / reference, steer / reference);
    ModeShape {
        roll_amplitude: r.norm(),
        roll_phase: phase(r),
        steer_amplitude: d.norm(),
        steer_phase: phase(d),
    }
}

/// JSON object of one speed point: `{"v", "eigenvalues", "modes",
/// "mode_shapes"}` (see [`eigen_sweep_json`]).
pub fn eigen_point_json(p: &EigenPoint) -> Value {
    let idx = ordered_indices(p);
    let mut v = json!({
        "v": p.v,
        "eigenvalues": idx.iter().map(|&k| [p.eigenvalues[k].re, p.eigenvalues[k].im]).collect::<Vec<_>>(),
        "modes": idx.iter().map(|&k| p.modes[k].name()).collect::<Vec<_>>(),
        "mode_shapes": idx.iter().map(|&k| mode_shape(&p.eigenvectors[k])).collect::<Vec<_>>(),
    });
    // A model with extra states (tyre forces) adds its other modes.
    if !p.extra_eigenvalues.is_empty() {
        v["extra_eigenvalues"] = json!(p.extra_eigenvalues.iter().map(|z| [z.re, z.im]).collect::<Vec<_>>());
    }
    v
}

/// JSON value of an eigen sweep: `[{"v": .., "eigenvalues": [[re, im], ..],
/// "modes": ["weave", ..], "mode_shapes": [{"roll_amplitude", "roll_phase",
/// "steer_amplitude", "steer_phase"}, ..]}, ..]` (see [`ModeShape`]), and
/// `"extra_eigenvalues": [[re, im], ..]` for a model with extra states.
pub fn eigen_sweep_json(sweep: &EigenSweep) -> Value {
    Value::Array(sweep.points.iter().map(eigen_point_json).collect())
}

/// Header of the eigen-sweep CSV: `v`, then per eigenvalue `k`: `re_k, im_k,
/// mode_k, roll_amp_k, roll_phase_k, steer_amp_k, steer_phase_k`.
pub fn eigen_sweep_csv_header() -> Vec<String> {
    eigen_sweep_csv_header_with(0)
}

/// [`eigen_sweep_csv_header`] with `extra` more eigenvalues (a model with
/// extra states): `re_extra_k, im_extra_k` each.
pub fn eigen_sweep_csv_header_with(extra: usize) -> Vec<String> {
    let mut h = vec!["v".to_string()];
    for k in 1..=4 {
        for c in ["re", "im", "mode", "roll_amp", "roll_phase", "steer_amp", "steer_phase"] {
            h.push(format!("{c}_{k}"));
        }
    }
    for k in 1..=extra {
        h.push(format!("re_extra_{k}"));
        h.push(format!("im_extra_{k}"));
    }
    h
}

/// One CSV row of a speed point (columns of [`eigen_sweep_csv_header`]).
pub fn eigen_point_csv_row(p: &EigenPoint) -> Vec<String> {
    let mut row = vec![num(p.v)];
    for k in ordered_indices(p) {
        let (s, m, shape) = (p.eigenvalues[k], p.modes[k], mode_shape(&p.eigenvectors[k]));
        row.push(num(s.re));
        row.push(num(s.im));
        row.push(m.name().to_string());
        row.push(num(shape.roll_amplitude));
        row.push(num(shape.roll_phase));
        row.push(num(shape.steer_amplitude));
        row.push(num(shape.steer_phase));
    }
    for z in &p.extra_eigenvalues {
        row.push(num(z.re));
        row.push(num(z.im));
    }
    row
}

/// [`eigen_sweep_csv_header_with`] with, when `standard_deviations`, the
/// columns `re_sd_k, im_sd_k` of the four eigenvalues after the others.
pub fn eigen_csv_header(extra: usize, standard_deviations: bool) -> Vec<String> {
    let mut header = eigen_sweep_csv_header_with(extra);
    if standard_deviations {
        for k in 1..=4 {
            header.push(format!("re_sd_{k}"));
            header.push(format!("im_sd_{k}"));
        }
    }
    header
}

/// [`eigen_point_csv_row`] with the standard deviations `[re, im]` (1/s)
/// of the point's eigenvalues in the output order ([`ordered_indices`]),
/// when given (columns of [`eigen_csv_header`]).
pub fn eigen_point_csv_row_with(p: &EigenPoint, standard_deviations: Option<&[[f64; 2]]>) -> Vec<String> {
    let mut row = eigen_point_csv_row(p);
    for sd in standard_deviations.unwrap_or_default() {
        row.push(num(sd[0]));
        row.push(num(sd[1]));
    }
    row
}

/// Write an eigen sweep as CSV (see the module docs for the columns).
pub fn write_eigen_sweep_csv<W: Write>(w: W, sweep: &EigenSweep) -> Result<(), csv::Error> {
    let mut wr = csv::Writer::from_writer(w);
    let extra = sweep.points.first().map_or(0, |p| p.extra_eigenvalues.len());
    wr.write_record(eigen_sweep_csv_header_with(extra))?;
    for p in &sweep.points {
        wr.write_record(eigen_point_csv_row(p))?;
    }
    wr.flush()?;
    Ok(())
}

/// Machine-readable formats of [`stream_eigen_sweep`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamFormat {
    /// CSV, as [`write_eigen_sweep_csv`].
    Csv,
    /// JSON, as [`eigen_sweep_json`] (one point object per line).
    Json,
}

/// Speeds per block of [`stream_eigen_sweep`].
pub const STREAM_BLOCK: usize = 4096;

/// Compute and write the eigen sweep of `c` at the `n` speeds `speed(0)`,
/// ..., `speed(n - 1)` block by block ([`STREAM_BLOCK`] speeds at a time), so
/// memory stays flat in `n` (issue 10, point 5). Labels are the same as those
/// of one [`bikedyn_runtime::eigen::eigen_sweep`] over all speeds, because every speed
/// is labelled by continuation from the bicycle's anchor speed, independent
/// of the other requested speeds.
pub fn stream_eigen_sweep(
    c: &dyn bikedyn_runtime::eigen::LinearBicycle,
    n: usize,
    speed: impl Fn(usize) -> f64,
    format: StreamFormat,
    w: &mut dyn Write,
) -> Result<(), BoxError> {
    stream_eigen_sweep_with(c, n, speed, format, w, None)
}

/// The standard deviations `[re, im]` (1/s) of a point's eigenvalues given
/// at its speed in the order given ([`ordered_indices`]).
pub type EigenSpread<'a> = &'a dyn Fn(f64, &[[f64; 2]]) -> Vec<[f64; 2]>;

/// [`stream_eigen_sweep`] with each eigenvalue's standard deviation from
/// `spread`: CSV columns `re_sd_k, im_sd_k` after the others, JSON
/// `"standard_deviations": [[re, im], ..]` in the order of `eigenvalues`.
pub fn stream_eigen_sweep_with(
    c: &dyn bikedyn_runtime::eigen::LinearBicycle,
    n: usize,
    speed: impl Fn(usize) -> f64,
    format: StreamFormat,
    w: &mut dyn Write,
    spread: Option<EigenSpread<'_>>,
) -> Result<(), BoxError> {
    let sd_of = |p: &EigenPoint| -> Option<Vec<[f64; 2]>> {
        let f = spread?;
        let z: Vec<[f64; 2]> = ordered_indices(p)
            .iter()
            .map(|&k| [p.eigenvalues[k].re, p.eigenvalues[k].im])
            .collect();
        Some(f(p.v, &z))
    };
    // Fail before writing anything if the bicycle has no eigen analysis;
    // the first point also says how many extra eigenvalues each row has.
    let extra = if n > 0 {
        bikedyn_runtime::eigen::eigen_sweep_of(c, &[speed(0)])?.points[0]
            .extra_eigenvalues
            .len()
    } else {
        0
    };
    let for_each_point = |f: &mut dyn FnMut(usize, &EigenPoint) -> Result<(), BoxError>| -> Result<(), BoxError> {
        let mut speeds = Vec::with_capacity(STREAM_BLOCK.min(n));
        let mut start = 0;
        while start < n {
            let end = (start + STREAM_BLOCK).min(n);
            speeds.clear();
            speeds.extend((start..end).map(&speed));
            let sweep = bikedyn_runtime::eigen::eigen_sweep_of(c, &speeds)?;
            for (i, p) in sweep.points.iter().enumerate() {
                f(start + i, p)?;
            }
            start = end;
        }
        Ok(())
    };
    match format {
        StreamFormat::Csv => {
            let mut wr = csv::Writer::from_writer(w);
            wr.write_record(eigen_csv_header(extra, spread.is_some()))?;
            for_each_point(&mut |_, p| Ok(wr.write_record(eigen_point_csv_row_with(p, sd_of(p).as_deref()))?))?;
            wr.flush()?;
        }
        StreamFormat::Json => {
            w.write_all(b"[")?;
            for_each_point(&mut |i, p| {
                w.write_all(if i == 0 { b"\n  " } else { b",\n  " })?;
                let mut v = eigen_point_json(p);
                if let Some(sd) = sd_of(p) {
                    let sd: Vec<[Option<f64>; 2]> = sd.iter().map(|s| s.map(|x| x.is_finite().then_some(x))).collect();
                    v["standard_deviations"] = json!(sd);
                }
                serde_json::to_writer(&mut *w, &v)?;
                Ok(())
            })?;
            w.write_all(b"\n]\n")?;
        }
    }
    Ok(())
}

/// Atomically save an eigen sweep as CSV.
pub fn save_eigen_sweep_csv(path: impl AsRef<Path>, sweep: &EigenSweep) -> Result<(), OutputError> {
    write_atomic(path, |w| write_eigen_sweep_csv(w, sweep))
}

/// Atomically save an eigen sweep as pretty-printed JSON.
pub fn save_eigen_sweep_json(path: impl AsRef<Path>, sweep: &EigenSweep) -> Result<(), OutputError> {
    save_json(path, &eigen_sweep_json(sweep))
}

/// Aligned plain-text table of an eigen sweep for terminals. Columns are
/// titled by mode when every row has the same mode sequence, else `lambda_k`
/// with the mode in each cell.
pub fn format_eigen_table(sweep: &EigenSweep) -> String {
    let rows: Vec<[(Complex<f64>, Mode); 4]> = sweep.points.iter().map(ordered_eigenvalues).collect();
    let uniform = rows.windows(2).all(|w| w[0].iter().zip(&w[1]).all(|(a, b)| a.1 == b.1));
    let mut header = vec!["v (m/s)".to_string()];
    for k in 0..4 {
        header.push(match rows.first() {
            Some(r) if uniform => r[k].1.name().to_string(),
            _ => format!("lambda_{} (1/s)", k + 1),
        });
    }
    // A model with extra states: its other modes after the bicycle's.
    let extra = sweep
        .points
        .iter()
        .map(|p| p.extra_eigenvalues.len())
        .max()
        .unwrap_or(0);
    header.extend((1..=extra).map(|k| format!("extra {k}")));
    let complex = |s: &Complex<f64>| {
        format!(
            "{} {} {}i",
            format_fixed(s.re, 5, true),
            if s.im < 0.0 { '-' } else { '+' },
            format_fixed(s.im.abs(), 5, false)
        )
    };
    let body = sweep
        .points
        .iter()
        .zip(&rows)
        .map(|(p, r)| {
            let mut row = vec![format!("{:.3}", p.v)];
            for (s, m) in r {
                let z = complex(s);
                row.push(if uniform { z } else { format!("{z} {}", m.name()) });
            }
            row.extend(p.extra_eigenvalues.iter().map(complex));
            row
        })
        .collect::<Vec<_>>();
    format_table(&header, &body)
}
