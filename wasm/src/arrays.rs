//! The `eig` answer with its points as columns of numbers (`arrays: true`,
//! the explorer's diagram over speed): the numbers go to the page as the
//! bytes of `f64` arrays, not as JSON text.
//!
//! Why: for a 1,000-speed diagram, writing 8,000 eigenvalues as JSON text
//! (shortest round-trip digits), decoding that text in the page and parsing
//! it back into numbers took more time than computing them (about 0.7 ms
//! of writing and 1.7 ms of decoding and parsing against 2.6 ms of
//! computing, 2026-11-29). The bytes are the same `f64` values, bit for
//! bit.
//!
//! The JSON answer names each array by its place in the answer's `f64`
//! buffer (`bikedyn_arrays_ptr`): `"arrays": {"v": [offset, length], ...}`
//! in elements of 8 bytes; `bikedyn.js` replaces each pair by a
//! `Float64Array` (copied out of the module's memory).

use bikedyn::eigen::{EigenJob, EigenSweepError};
use bikedyn::report::output::output_order;
use bikedyn::runtime::eigen::Mode;
use serde::Serialize;
use std::collections::BTreeMap;

/// The answer's JSON part.
#[derive(Serialize)]
pub struct EigArrays {
    model: String,
    /// Number of speeds.
    count: usize,
    /// Extra eigenvalues (tyre states) per speed: 0 for models without
    /// extra states.
    extra_per_speed: usize,
    /// The modes' names; the array `modes` holds indices into it.
    mode_names: Vec<&'static str>,
    /// Each array's `[offset, length]` in the answer's `f64` buffer:
    /// `v` (m/s, per speed); `eigenvalues` (1/s, per speed its four in
    /// the order of `bikedyn eig --format json`, `re, im` each, so 8 per
    /// speed); `modes` (4 per speed, indices into `mode_names`);
    /// `extra_eigenvalues` (1/s, `re, im`, `extra_per_speed` per speed).
    arrays: BTreeMap<&'static str, [usize; 2]>,
    weave_speed: Option<f64>,
    capsize_speed: Option<f64>,
    weave_real_pair_merge_speed: Option<f64>,
}

/// The `eig` job's eigenvalues and modes as columns: the JSON part, and
/// the `f64` buffer it points into (written to `data`, cleared first).
/// Mode shapes and standard deviations are not computed.
///
/// The columns are written straight from the eigen analysis's points
/// ([`EigenJob::labelled_eigenvalues`], each speed's in the output order
/// of [`EigenJob::eigenvalues_and_modes`]), and a mode's index is looked up
/// by its label, its name compared only when a label first appears: the
/// same numbers as through `eigenvalues_and_modes`, whose copy of every
/// speed and comparison of names as text took a tenth of the explorer's
/// request (2026-12-02).
pub fn eig_arrays(job: &EigenJob, data: &mut Vec<f64>) -> Result<EigArrays, EigenSweepError> {
    let points = job.labelled_eigenvalues()?;
    let n = points.len();
    let extra = points.iter().map(|p| p.extra_eigenvalues.len()).max().unwrap_or(0);
    let order: Vec<[usize; 4]> = points.iter().map(|p| output_order(&p.modes, &p.eigenvalues)).collect();
    data.clear();
    data.reserve(n * (1 + 8 + 4 + 2 * extra));
    let mut arrays = BTreeMap::new();
    let mut column = |name: &'static str, data: &mut Vec<f64>, fill: &mut dyn FnMut(&mut Vec<f64>)| {
        let start = data.len();
        fill(data);
        arrays.insert(name, [start, data.len() - start]);
    };
    column("v", data, &mut |d| d.extend(points.iter().map(|p| p.v)));
    column("eigenvalues", data, &mut |d| {
        for (p, idx) in points.iter().zip(&order) {
            for &k in idx {
                d.push(p.eigenvalues[k].re);
                d.push(p.eigenvalues[k].im);
            }
        }
    });
    // `mode_names` in the order the names are first met (as before);
    // `seen` the index of each label met so far.
    let mut mode_names: Vec<&'static str> = Vec::new();
    let mut seen: Vec<(Mode, usize)> = Vec::new();
    column("modes", data, &mut |d| {
        for (p, idx) in points.iter().zip(&order) {
            for &k in idx {
                let m = p.modes[k];
                let i = match seen.iter().find(|(x, _)| *x == m) {
                    Some(&(_, i)) => i,
                    None => {
                        let name = m.name();
                        let i = mode_names.iter().position(|x| *x == name).unwrap_or_else(|| {
                            mode_names.push(name);
                            mode_names.len() - 1
                        });
                        seen.push((m, i));
                        i
                    }
                };
                d.push(i as f64);
            }
        }
    });
    column("extra_eigenvalues", data, &mut |d| {
        for p in &points {
            // A speed with fewer (none: the models give the same number at
            // every speed) is padded with NaN.
            for z in &p.extra_eigenvalues {
                d.push(z.re);
                d.push(z.im);
            }
            d.extend(std::iter::repeat_n(f64::NAN, 2 * (extra - p.extra_eigenvalues.len())));
        }
    });
    Ok(EigArrays {
        model: job.model.to_string(),
        count: n,
        extra_per_speed: extra,
        mode_names,
        arrays,
        weave_speed: job.critical.as_ref().and_then(|c| c.weave_speed),
        capsize_speed: job.critical.as_ref().and_then(|c| c.capsize_speed),
        weave_real_pair_merge_speed: job.critical.as_ref().and_then(|c| c.weave_real_pair_merge),
    })
}
