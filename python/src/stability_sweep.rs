//! `sweep`: stability over one or two parameters.

use super::*;
use bikedyn::sweep::{sweep_at_speeds, SweepAtSpeedsError, SweepError, SweepOptions, SweptParameter};

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
        let second = match (param2, ys) {
            (Some(p2), Some(ys)) if !ys.is_empty() => Some(SweptParameter::new(p2, ys)),
            (Some(p2), _) => {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!("values2: no values given for {p2}"),
                ))
            }
            (None, Some(_)) => return Err(Failure::new("InvalidArgumentError", "values2 needs param2")),
            (None, None) => None,
        };
        let ns = speeds.len();
        let designs = xs.len().saturating_mul(second.as_ref().map_or(1, |p| p.values.len()));
        let total = designs.saturating_mul(ns);
        if total > crate::MAX_SWEEP_VALUES {
            return Err(Failure::new(
                "TooLargeError",
                format!(
                    "a sweep of {} x {} designs at {ns} speeds gives {total} values, more than the {} one call returns; split it into several calls",
                    xs.len(),
                    designs / xs.len(),
                    crate::MAX_SWEEP_VALUES
                ),
            ));
        }
        let options = SweepOptions {
            model,
            second,
            ..SweepOptions::new(param, xs)
        };
        let s = sweep_at_speeds(b, &options, &speeds).map_err(|e| match e {
            SweepAtSpeedsError::Sweep(SweepError::Bicycle(e)) => bicycle_failure(e),
            SweepAtSpeedsError::Design { ref source, .. } => Failure::new(bicycle_kind(source), e),
            SweepAtSpeedsError::Eigen { .. } => Failure::new("ComputationError", e),
            e => Failure::new("InvalidArgumentError", e),
        })?;
        Ok((s.model, s.least_stable_real_part, s.weave_speed, s.capsize_speed))
    })?;
    Ok((
        model,
        PyBytes::new(py, &bytes_of(&least)),
        PyBytes::new(py, &bytes_of(&weave)),
        PyBytes::new(py, &bytes_of(&capsize)),
    ))
}
