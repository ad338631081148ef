//! Reading a measured eigenvalue table (format in the parent module's doc).

use crate::capped::{read_text_capped, MAX_TEXT_FILE_BYTES};
use crate::identify::result::EigenPoint;
use crate::identify::IdentifyError;
use crate::runs::MAX_SPEED_M_S;
use std::path::Path;

/// Read a measured eigenvalue table (see the module doc).
///
/// Refused, naming the line: a speed outside `(0, 30]` m/s
/// ([`MAX_SPEED_M_S`]: no bicycle is measured faster; a larger value is a
/// typing slip or other units, and one such row pulls the corrections to
/// non-physical values); rows of 3 and 5 fields mixed (a column shifted, or
/// standard errors for some speeds only); a row repeating another's speed
/// and eigenvalue (it would count twice). The file is read whole only
/// below [`MAX_TEXT_FILE_BYTES`] (checked from its size first).
pub fn read_eigen_table(path: &Path) -> Result<Vec<EigenPoint>, IdentifyError> {
    let bad = |line: usize, message: String| IdentifyError::EigenTable {
        path: path.to_path_buf(),
        line,
        message,
    };
    let text = read_text_capped(path, MAX_TEXT_FILE_BYTES).map_err(|e| bad(0, e.to_string()))?;
    let mut points: Vec<EigenPoint> = Vec::new();
    // The first row's field count, with its line: every row has the same.
    let mut width: Option<(usize, usize)> = None;
    let mut seen_row = false;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let l = raw.trim().trim_start_matches('\u{feff}');
        if l.is_empty() || l.starts_with('#') {
            continue;
        }
        let fields: Vec<&str> = l
            .split(|c: char| c == ',' || c == ';' || c.is_whitespace())
            .filter(|f| !f.is_empty())
            .collect();
        let numbers: Vec<Option<f64>> = fields.iter().map(|f| f.parse::<f64>().ok()).collect();
        if !seen_row && numbers.iter().any(|x| x.is_none()) {
            // The header, in the authors' words.
            seen_row = true;
            continue;
        }
        seen_row = true;
        let Some(v) = numbers.iter().copied().collect::<Option<Vec<f64>>>() else {
            return Err(bad(
                line,
                format!("`{l}`: every field after the header must be a number"),
            ));
        };
        if v.len() != 3 && v.len() != 5 {
            return Err(bad(
                line,
                format!(
                    "{} fields; expected 3 (speed m/s, real 1/s, imaginary rad/s) or 5 (and their two standard errors)",
                    v.len()
                ),
            ));
        }
        match width {
            Some((w, first)) if w != v.len() => {
                return Err(bad(
                    line,
                    format!(
                        "{} fields, but line {first} has {w}: every row gives the same columns (standard errors for every speed or for none)",
                        v.len()
                    ),
                ))
            }
            Some(_) => {}
            None => width = Some((v.len(), line)),
        }
        if v.iter().any(|x| !x.is_finite()) {
            return Err(bad(line, format!("`{l}`: not a finite number")));
        }
        if !(v[0] > 0.0 && v[0] <= MAX_SPEED_M_S) {
            return Err(bad(
                line,
                format!(
                    "speed (first field) {} m/s is not a bicycle's speed (above 0, at most {MAX_SPEED_M_S} m/s): check the row and that speeds are in m/s",
                    v[0]
                ),
            ));
        }
        if let Some(p) = points.iter().find(|p| p.speed == v[0] && p.eigenvalue == [v[1], v[2]]) {
            return Err(bad(
                line,
                format!(
                    "repeats line {} (speed {} m/s, the same eigenvalue): a repeated row would count twice; give each measurement once",
                    p.line, v[0]
                ),
            ));
        }
        if !(v[2] > 0.0) {
            return Err(bad(
                line,
                format!("imaginary part {}: a weave eigenvalue is oscillatory (give the one with a positive imaginary part)", v[2]),
            ));
        }
        let stderr = (v.len() == 5).then(|| [v[3], v[4]]);
        if stderr.is_some_and(|s| !(s[0] > 0.0 && s[1] > 0.0)) {
            return Err(bad(line, "standard errors must be positive".into()));
        }
        points.push(EigenPoint {
            line,
            speed: v[0],
            eigenvalue: [v[1], v[2]],
            stderr,
        });
    }
    if points.len() < 3 {
        return Err(bad(0, format!("{} rows; at least 3 speeds are needed", points.len())));
    }
    Ok(points)
}
