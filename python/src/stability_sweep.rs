//! `sweep`: stability over one or two parameters.

use super::*;

/// Stability over one or two parameters: for every design (cell) the
/// least-stable real part at each speed, and the weave and capsize speeds
/// in the speeds' range. Cells run in parallel on every core.
#[pyfunction]
#[pyo3(signature = (bike, param, values, speeds, param2=None, values2=None, model=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
pub(crate) fn sweep<'py>(
    py: Python<'py>,
    bike: &PyBicycle,
    param: String,
    values: &[u8],
    speeds: &[u8],
    param2: Option<String>,
    values2: Option<&[u8]>,
    model: Option<String>,
) -> PyResult<(String, Bound<'py, PyBytes>, Bound<'py, PyBytes>, Bound<'py, PyBytes>)> {
    let xs = doubles(values, "values").map_err(|e| e.into_py(py))?;
    let ys = match values2 {
        Some(v) => Some(doubles(v, "values2").map_err(|e| e.into_py(py))?),
        None => None,
    };
    let speeds = doubles(speeds, "speeds").map_err(|e| e.into_py(py))?;
    let b = &bike.inner;
    let (model, least, weave, capsize) = detached(py, move || {
        finite_speeds(&speeds, "speeds")?;
        if xs.is_empty() {
            return Err(Failure::new(
                "InvalidArgumentError",
                "values: no parameter values given",
            ));
        }
        if param2.as_deref().is_some_and(|p2| p2.trim() == param.trim()) {
            // The second value would overwrite the first in every cell.
            return Err(Failure::new(
                "InvalidArgumentError",
                format!("param and param2 both name `{param}`: a map needs two different parameters (for one, leave out param2 and values2)"),
            ));
        }
        let ys: Vec<Option<f64>> = match (&param2, ys) {
            (Some(_), Some(ys)) if !ys.is_empty() => ys.into_iter().map(Some).collect(),
            (Some(p2), _) => {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!("values2: no values given for {p2}"),
                ))
            }
            (None, Some(_)) => return Err(Failure::new("InvalidArgumentError", "values2 needs param2")),
            (None, None) => vec![None],
        };
        let design = |x: f64, y: Option<f64>| -> Result<Bicycle, BicycleError> {
            let b = b.with_parameter(&param, x)?;
            match (&param2, y) {
                (Some(p2), Some(y)) => b.with_parameter(p2, y),
                _ => Ok(b),
            }
        };
        // One model for every cell, as `bikedyn sweep` chooses it: the one
        // that represents the design at the first non-zero values.
        let model = match model {
            Some(m) => m,
            None => {
                let first = |v: &[f64]| v.iter().copied().find(|&v| v != 0.0).unwrap_or(v[0]);
                let y0 = ys[0].map(|_| {
                    let finite: Vec<f64> = ys.iter().flatten().copied().collect();
                    first(&finite)
                });
                design(first(&xs), y0)?.model(None)?.name.to_string()
            }
        };
        let (v_min, v_max) = speeds
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| (a.min(v), b.max(v)));
        let ns = speeds.len();
        let total = xs.len().saturating_mul(ys.len()).saturating_mul(ns);
        if total > crate::MAX_SWEEP_VALUES {
            return Err(Failure::new(
                "TooLargeError",
                format!(
                    "a sweep of {} x {} designs at {ns} speeds gives {total} values, more than the {} one call returns; split it into several calls",
                    xs.len(),
                    ys.len(),
                    crate::MAX_SWEEP_VALUES
                ),
            ));
        }
        let cells: Vec<(f64, Option<f64>)> = xs.iter().flat_map(|&x| ys.iter().map(move |&y| (x, y))).collect();
        let results: Vec<Result<(Vec<f64>, f64, f64), Failure>> = cells
            .par_iter()
            .map(|&(x, y)| {
                let at = || match (&param2, y) {
                    (Some(p2), Some(y)) => format!("{param} = {x}, {p2} = {y}"),
                    _ => format!("{param} = {x}"),
                };
                let lin = design(x, y).and_then(|b| b.linear_with(Some(&model))).map_err(|e| {
                    let f = bicycle_failure(e);
                    Failure::new(f.kind, format!("at {}: {}", at(), f.message))
                })?;
                let eig = |e: bikedyn::runtime::eigen::EigenError| {
                    Failure::new("ComputationError", format!("at {}: {e}", at()))
                };
                let mut least = Vec::with_capacity(ns);
                if lin.first_order().is_some() {
                    let s = eigen_sweep_of(&lin, &speeds).map_err(eig)?;
                    for p in &s.points {
                        let m = p
                            .eigenvalues
                            .iter()
                            .chain(&p.extra_eigenvalues)
                            .map(|z| z.re)
                            .fold(f64::NEG_INFINITY, f64::max);
                        least.push(m);
                    }
                } else {
                    for &v in &speeds {
                        let z = eigenvalues_of(&lin, v).map_err(eig)?;
                        least.push(z.iter().map(|z| z.re).fold(f64::NEG_INFINITY, f64::max));
                    }
                }
                let (weave, capsize) = if v_max > v_min {
                    let c = critical_speeds_of(&lin, v_min.max(0.0), v_max).map_err(eig)?;
                    (c.weave_speed.unwrap_or(f64::NAN), c.capsize_speed.unwrap_or(f64::NAN))
                } else {
                    (f64::NAN, f64::NAN)
                };
                Ok((least, weave, capsize))
            })
            .collect();
        let mut least = Vec::with_capacity(cells.len() * ns);
        let mut weave = Vec::with_capacity(cells.len());
        let mut capsize = Vec::with_capacity(cells.len());
        for r in results {
            let (l, w, c) = r?;
            least.extend(l);
            weave.push(w);
            capsize.push(c);
        }
        Ok((model, least, weave, capsize))
    })?;
    Ok((
        model,
        PyBytes::new(py, &bytes_of(&least)),
        PyBytes::new(py, &bytes_of(&weave)),
        PyBytes::new(py, &bytes_of(&capsize)),
    ))
}
