//! Terminal tables and printed numbers, and the stability JSON.

use std::fmt::Write as _;

use super::*;

/// A number in a CSV cell: Rust's shortest round-trip representation.
pub(crate) fn num(x: f64) -> String {
    format!("{x:?}")
}

/// An optional number in a CSV cell, empty when absent.
pub(crate) fn opt(x: Option<f64>) -> String {
    x.map(num).unwrap_or_default()
}

/// Aligned plain-text table: a header, a rule, then the rows; every column is
/// right-aligned to its widest entry, two spaces between columns.
pub fn format_table(header: &[String], rows: &[Vec<String>]) -> String {
    let ncol = header.len().max(rows.iter().map(Vec::len).max().unwrap_or(0));
    let mut width = vec![0usize; ncol];
    for r in std::iter::once(header).chain(rows.iter().map(Vec::as_slice)) {
        for (k, s) in r.iter().enumerate() {
            width[k] = width[k].max(s.chars().count());
        }
    }
    let mut out = String::new();
    let line = |r: &[String], out: &mut String| {
        let cells: Vec<String> = (0..ncol)
            .map(|k| {
                let s = r.get(k).map(String::as_str).unwrap_or("");
                format!("{s:>w$}", w = width[k])
            })
            .collect();
        let _ = writeln!(out, "{}", cells.join("  ").trim_end());
    };
    line(header, &mut out);
    let rule: Vec<String> = width.iter().map(|w| "-".repeat(*w)).collect();
    line(&rule, &mut out);
    for r in rows {
        line(r, &mut out);
    }
    out
}

// Printed numbers (issue 10, point 8). JSON and CSV keep full precision
// (shortest round-trip representation); text for people has a fixed number
// of significant digits and never a negative zero.

/// The entries of a matrix with `digits` significant digits relative to its
/// largest entry (all entries get the same number of decimals, so columns
/// align and an entry that is zero to that precision prints as zero without
/// a sign); scientific notation when the largest entry is below `1e-4` or at
/// least `1e12`.
pub fn format_matrix_entries(entries: &[f64], digits: usize) -> Vec<String> {
    let max = entries.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    if max == 0.0 || !max.is_finite() {
        return entries.iter().map(|&x| format_significant(x, digits)).collect();
    }
    let e = max.log10().floor() as i32;
    if !(-4..12).contains(&e) {
        return entries.iter().map(|&x| format_significant(x, digits)).collect();
    }
    let decimals = (digits as i32 - 1 - e).max(0) as usize;
    entries.iter().map(|&x| format_fixed(x, decimals, false)).collect()
}

/// The stability of a bicycle as JSON (`bikedyn stability --json`, the
/// Python package's `Bicycle.stability()`): weave, capsize and real-pair
/// merge speeds (m/s), the self-stable intervals and every crossing of a
/// mode's real part through zero, with its frequency (rad/s).
pub fn stability_json(name: &str, c: &bikedyn_runtime::eigen::CriticalSpeeds) -> serde_json::Value {
    serde_json::json!({
        "bike": name,
        "weave_speed": c.weave_speed,
        "capsize_speed": c.capsize_speed,
        "weave_real_pair_merge_speed": c.weave_real_pair_merge,
        "stable_intervals": c.stable_intervals,
        "crossings": c.crossings.iter().map(|x| serde_json::json!({
            "speed": x.speed, "mode": x.mode.name(), "direction": format!("{:?}", x.direction).to_lowercase(),
            "kind": match x.kind { bikedyn_runtime::eigen::CrossingKind::RealRoot => "real_root", bikedyn_runtime::eigen::CrossingKind::ComplexPair => "complex_pair" },
            "frequency": x.frequency
        })).collect::<Vec<_>>(),
    })
}
