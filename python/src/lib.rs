//! `bikedyn._bikedyn`: the extension module behind the Python package
//! `bikedyn`. It is a thin layer over the bikedyn library, as the command
//! line is: it parses Python arguments, calls the library and hands back
//! plain values. Arrays cross as little-endian `f64` (or `u8`) buffers that
//! the Python package views as NumPy arrays without a Python loop, so the
//! extension needs no NumPy headers and builds for every CPython >= 3.9
//! (abi3).
//!
//! Errors: every library error becomes an exception of `bikedyn._errors`
//! (a `bikedyn.Error` subclass that is also the matching built-in kind,
//! such as `ValueError`), with the command line's message; a panic is
//! caught and raised as `bikedyn.InternalError`, never as a crash. Long
//! computations run without the GIL, so other Python threads go on.

use bikedyn::bicycle::{Bicycle, BicycleError, Linear};
use bikedyn::fit::{kick_json, plots_into, run_fit, FitOptions, FitOutcome};
use bikedyn::identify::eigen_table::{identify_table, write_table_report, TableOutcome, TableRequest};
use bikedyn::identify::{report as identify_report, run as identify_run, IdentifyRequest, Outcome};
use bikedyn::report::output::{stability_json, write_atomic};
use bikedyn::report::plot::PlotOptions;
use bikedyn::report::staged::{FolderKind, StagedDir};
use bikedyn::runtime::eigen::{critical_speeds_of, eigen_sweep_of, eigenvalues_of, LinearBicycle};
use bikedyn::runtime::experiment::angles::AngleMethod;
use bikedyn::runtime::parameters::ParameterSet;
use bikedyn::runtime::simulate::{
    Events, InitialConditions, Inputs, Kick, PulseShape, PulseTarget, SimOptions, TorquePulse,
};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use rayon::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

/// A failure on the Rust side: the exception class of `bikedyn._errors`
/// and the message. Built without the GIL, raised with it.
struct Failure {
    kind: &'static str,
    message: String,
}

impl Failure {
    fn new(kind: &'static str, message: impl ToString) -> Self {
        Failure {
            kind,
            message: message.to_string(),
        }
    }

    fn into_py(self, py: Python<'_>) -> PyErr {
        let made = py
            .import("bikedyn._errors")
            .and_then(|m| m.getattr(self.kind))
            .and_then(|class| class.call1((self.message.clone(),)));
        match made {
            Ok(exception) => PyErr::from_value(exception),
            Err(e) => e,
        }
    }
}

/// The exception kind of a bicycle error: a model that does not exist or
/// cannot represent the bicycle is a `ModelError`; a parameter file that
/// does not exist is `BicycleNotFoundError` (a `FileNotFoundError`); the
/// rest are the parameters' (`ParameterError`, a `ValueError`).
fn bicycle_failure(e: BicycleError) -> Failure {
    let kind = match &e {
        BicycleError::NotFound { .. } => "NotFoundError",
        BicycleError::UnknownModel { .. }
        | BicycleError::ModelDoesNotFit { .. }
        | BicycleError::NoModelFits { .. }
        | BicycleError::NotCanonical { .. } => "ModelError",
        BicycleError::Linearize { .. } => "ComputationError",
        _ => "ParameterError",
    };
    Failure::new(kind, e)
}

impl From<BicycleError> for Failure {
    fn from(e: BicycleError) -> Self {
        bicycle_failure(e)
    }
}

/// Run `f` without the GIL and with panics caught.
fn detached<T: Send>(py: Python<'_>, f: impl FnOnce() -> Result<T, Failure> + Send) -> PyResult<T> {
    let r = py.detach(move || match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => Err(Failure::new("InternalError", panic_message(payload))),
    });
    r.map_err(|e| e.into_py(py))
}

/// Progress reports of a long call (`fit`, `identify`) passed to a Python
/// callable `progress(step, done, total)`. The pipelines report from their
/// worker threads, so each call takes the interpreter lock itself (the
/// computation runs with it released); calls are serialised, and the first
/// exception the callable raises stops further calls and is raised when
/// the computation returns.
struct PyProgress {
    callback: Option<Py<PyAny>>,
    error: std::sync::Mutex<Option<PyErr>>,
}

impl PyProgress {
    fn new(callback: Option<Py<PyAny>>) -> Self {
        PyProgress {
            callback,
            error: std::sync::Mutex::new(None),
        }
    }

    fn report(&self, p: bikedyn::progress::Progress<'_>) {
        let Some(callback) = &self.callback else { return };
        // The lock is taken before the interpreter's, never the other way.
        let mut error = self.error.lock().unwrap_or_else(|e| e.into_inner());
        if error.is_some() {
            return;
        }
        Python::attach(|py| {
            if let Err(e) = callback.call1(py, (p.step, p.done, p.total)) {
                *error = Some(e);
            }
        });
    }

    /// The callable's first exception, if it raised one.
    fn raised(self) -> PyResult<()> {
        match self.error.into_inner().unwrap_or_else(|e| e.into_inner()) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

fn panic_message(payload: Box<dyn std::any::Any + Send>) -> String {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".to_string());
    format!("internal error in bikedyn (please report it): {what}")
}

/// `f64`s from a buffer of native-endian doubles (NumPy's `tobytes()`).
fn doubles(buf: &[u8], what: &str) -> Result<Vec<f64>, Failure> {
    if buf.len() % 8 != 0 {
        return Err(Failure::new(
            "InternalError",
            format!("{what}: buffer of {} bytes", buf.len()),
        ));
    }
    Ok(buf
        .chunks_exact(8)
        .map(|c| f64::from_ne_bytes(c.try_into().expect("8 bytes")))
        .collect())
}

fn bytes_of(xs: &[f64]) -> Vec<u8> {
    xs.iter().flat_map(|x| x.to_ne_bytes()).collect()
}

fn finite_speeds(speeds: &[f64], what: &str) -> Result<(), Failure> {
    if speeds.is_empty() {
        return Err(Failure::new("InvalidArgumentError", format!("{what}: no speeds given")));
    }
    match speeds.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(Failure::new(
            "InvalidArgumentError",
            format!("{what}[{i}] = {} is not a finite speed (m/s)", speeds[i]),
        )),
        None => Ok(()),
    }
}

/// A bicycle: its parameters (thesis or benchmark form), effect
/// parameters and uncertainties, resolved against the built-in models.
#[pyclass(name = "_Bicycle", module = "bikedyn._bikedyn", frozen)]
struct PyBicycle {
    inner: Bicycle,
}

impl PyBicycle {
    fn linear(&self, model: Option<&str>) -> Result<Linear, Failure> {
        Ok(self.inner.linear_with(model)?)
    }
}

#[pymethods]
impl PyBicycle {
    /// A built-in bicycle (`thesis`, `benchmark`) or a parameter file.
    #[new]
    fn new(py: Python<'_>, spec: String) -> PyResult<Self> {
        detached(py, move || {
            Ok(PyBicycle {
                inner: Bicycle::resolve(&spec)?,
            })
        })
    }

    /// From `(symbol, value, standard deviation or None)` triples.
    #[staticmethod]
    fn from_values(py: Python<'_>, name: String, values: Vec<(String, f64, Option<f64>)>) -> PyResult<Self> {
        detached(py, move || {
            Ok(PyBicycle {
                inner: Bicycle::from_values(&name, &values)?,
            })
        })
    }

    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// `thesis` or `benchmark`: the form the parameters were given in.
    #[getter]
    fn form(&self) -> &'static str {
        match self.inner.parameters {
            ParameterSet::Thesis(_) => "thesis",
            ParameterSet::Benchmark(_) => "benchmark",
        }
    }

    /// `(symbol, value)` of the parameters in their form, then the effect
    /// parameters set.
    fn parameters(&self) -> Vec<(String, f64)> {
        let set = &self.inner.parameters;
        let symbols: Vec<&str> = match set {
            ParameterSet::Thesis(_) => bikedyn::runtime::parameters::ThesisParameters::SYMBOLS.to_vec(),
            ParameterSet::Benchmark(_) => bikedyn::runtime::parameters::BenchmarkParameters::SYMBOLS.to_vec(),
        };
        let mut out: Vec<(String, f64)> = symbols
            .into_iter()
            .filter_map(|s| set.get(s).map(|v| (s.to_string(), v)))
            .collect();
        out.extend(self.inner.effects.iter().map(|(k, v)| (k.clone(), *v)));
        out
    }

    /// Value of any thesis, benchmark or effect symbol (`None`: not set).
    fn value(&self, symbol: &str) -> Option<f64> {
        self.inner
            .effects
            .get(symbol)
            .copied()
            .or_else(|| self.inner.value(symbol))
    }

    /// `(symbol, standard deviation)` the file or dict gave.
    fn uncertainties(&self) -> Vec<(String, f64)> {
        self.inner.uncertainties.iter().map(|(k, v)| (k.clone(), *v)).collect()
    }

    /// Validation warnings (triangle inequality of inertias, extra names).
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings.iter().map(|w| w.to_string()).collect()
    }

    /// Name of the model that represents this bicycle (`model`: by name).
    fn model(&self, model: Option<&str>) -> PyResult<String> {
        self.inner
            .model(model)
            .map(|m| m.name.to_string())
            .map_err(|e| Python::attach(|py| bicycle_failure(e).into_py(py)))
    }

    /// `(symbol, value, unit, meaning)` of the derived geometry.
    fn geometry(&self, py: Python<'_>) -> PyResult<Vec<(String, f64, String, String)>> {
        let p = &self.inner.parameters;
        detached(py, || {
            let b = p.to_benchmark().map_err(|e| Failure::new("ParameterError", e))?;
            Ok(bikedyn::runtime::geometry::DerivedGeometry::of(&b)
                .rows()
                .into_iter()
                .map(|(s, v, u, w)| (s.to_string(), v, u.to_string(), w.to_string()))
                .collect())
        })
    }

    /// The same bicycle with one parameter changed.
    fn with_parameter(&self, py: Python<'_>, symbol: String, value: f64) -> PyResult<Self> {
        let b = &self.inner;
        detached(py, move || {
            Ok(PyBicycle {
                inner: b.with_parameter(&symbol, value)?,
            })
        })
    }

    /// The parameter file text (TOML in the bicycle's form, effects after).
    fn to_toml(&self) -> String {
        let mut text = self.inner.parameters.to_toml_string();
        let effects = self.inner.effects_toml();
        if !effects.is_empty() {
            text.push_str(&format!("\n# Effect parameters of {}:\n{effects}", self.inner.name));
        }
        text
    }

    /// `(model, [M0, C1, K0, K2])`, each row-major `[m11, m12, m21, m22]`.
    fn canonical(&self, py: Python<'_>, model: Option<String>) -> PyResult<(String, Vec<[f64; 4]>)> {
        detached(py, move || {
            let lin = self.linear(model.as_deref())?;
            let c = match &lin.canonical {
                Some(c) => *c,
                None => {
                    let why = self
                        .inner
                        .canonical_with(model.as_deref())
                        .err()
                        .map(|e| e.to_string())
                        .unwrap_or_else(|| "no canonical form".into());
                    return Err(Failure::new("ModelError", why));
                }
            };
            let flat = |m: &nalgebra::Matrix2<f64>| [m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]];
            Ok((
                lin.model.to_string(),
                vec![flat(&c.m0), flat(&c.c1), flat(&c.k0), flat(&c.k2)],
            ))
        })
    }

    /// State-space matrices at each speed: `(model, n, states, inputs, A
    /// bytes (speeds, n, n), B bytes (speeds, n, 2) or None)`.
    #[allow(clippy::type_complexity)]
    fn state_space<'py>(
        &self,
        py: Python<'py>,
        speeds: &[u8],
        model: Option<String>,
    ) -> PyResult<(
        String,
        usize,
        Vec<String>,
        Vec<String>,
        Bound<'py, PyBytes>,
        Option<Bound<'py, PyBytes>>,
    )> {
        let speeds = doubles(speeds, "speeds").map_err(|e| e.into_py(py))?;
        let (name, n, states, a, b) = detached(py, || {
            finite_speeds(&speeds, "speeds")?;
            let lin = self.linear(model.as_deref())?;
            let eig = |e: bikedyn::runtime::eigen::EigenError| Failure::new("ComputationError", e);
            if let Some(first) = lin.first_order() {
                let mut a = Vec::new();
                let mut names = Vec::new();
                let mut n = 0;
                for &v in &speeds {
                    let ls = first.lateral_states(v).map_err(eig)?;
                    n = ls.a.nrows();
                    names = ls.names.clone();
                    for i in 0..n {
                        for j in 0..n {
                            a.push(ls.a[(i, j)]);
                        }
                    }
                }
                return Ok((lin.model, n, names, a, None));
            }
            let mut a = Vec::with_capacity(16 * speeds.len());
            let mut b = Vec::with_capacity(8 * speeds.len());
            for &v in &speeds {
                let m = lin.at_speed(v).map_err(eig)?;
                let (am, minv) = m
                    .state_matrix()
                    .zip(m.mass.try_inverse())
                    .ok_or_else(|| Failure::new("ComputationError", format!("singular mass matrix at {v} m/s")))?;
                for i in 0..4 {
                    for j in 0..4 {
                        a.push(am[(i, j)]);
                    }
                }
                b.extend([
                    0.0,
                    0.0,
                    0.0,
                    0.0,
                    minv[(0, 0)],
                    minv[(0, 1)],
                    minv[(1, 0)],
                    minv[(1, 1)],
                ]);
            }
            let names = ["roll", "steer", "roll_rate", "steer_rate"].map(String::from).to_vec();
            Ok((lin.model, 4, names, a, Some(b)))
        })?;
        Ok((
            name.to_string(),
            n,
            states,
            vec!["roll_torque".into(), "steer_torque".into()],
            PyBytes::new(py, &bytes_of(&a)),
            b.map(|b| PyBytes::new(py, &bytes_of(&b))),
        ))
    }

    /// Eigenvalues and modes at each speed: `(model, k, eigenvalues bytes
    /// (speeds, k) complex, mode codes bytes (speeds, 4), mode names,
    /// eigenvectors bytes (speeds, 4, 4) complex)`; the first four
    /// eigenvalues are the bicycle's modes, the rest the extra states'
    /// (NaN where a speed has fewer).
    #[allow(clippy::type_complexity)]
    fn eig<'py>(
        &self,
        py: Python<'py>,
        speeds: &[u8],
        model: Option<String>,
    ) -> PyResult<(
        String,
        usize,
        Bound<'py, PyBytes>,
        Bound<'py, PyBytes>,
        Vec<&'static str>,
        Bound<'py, PyBytes>,
    )> {
        let speeds = doubles(speeds, "speeds").map_err(|e| e.into_py(py))?;
        let (name, k, values, codes, names, vectors) = detached(py, || {
            finite_speeds(&speeds, "speeds")?;
            let lin = self.linear(model.as_deref())?;
            let sweep = eigen_sweep_of(&lin, &speeds).map_err(|e| Failure::new("ComputationError", e))?;
            let k = 4 + sweep
                .points
                .iter()
                .map(|p| p.extra_eigenvalues.len())
                .max()
                .unwrap_or(0);
            let mut values = Vec::with_capacity(2 * k * speeds.len());
            let mut vectors = Vec::with_capacity(32 * speeds.len());
            let mut codes = Vec::with_capacity(4 * speeds.len());
            let mut names: Vec<&'static str> = Vec::new();
            for p in &sweep.points {
                for z in p.eigenvalues.iter().chain(&p.extra_eigenvalues) {
                    values.extend([z.re, z.im]);
                }
                for _ in 4 + p.extra_eigenvalues.len()..k {
                    values.extend([f64::NAN, f64::NAN]);
                }
                for m in &p.modes {
                    let code = match names.iter().position(|n| *n == m.name()) {
                        Some(i) => i,
                        None => {
                            names.push(m.name());
                            names.len() - 1
                        }
                    };
                    codes.push(code as u8);
                }
                // Row i of the (4, 4) block: component i (roll, steer and
                // their rates) of each mode's vector, as bicycleparameters
                // stores its eigenvectors (one mode per column).
                for i in 0..4 {
                    for vector in &p.eigenvectors {
                        vectors.extend([vector[i].re, vector[i].im]);
                    }
                }
            }
            Ok((lin.model, k, values, codes, names, vectors))
        })?;
        Ok((
            name.to_string(),
            k,
            PyBytes::new(py, &bytes_of(&values)),
            PyBytes::new(py, &codes),
            names,
            PyBytes::new(py, &bytes_of(&vectors)),
        ))
    }

    /// Eigenvalues only, at each speed, in parallel over the speeds: `(model,
    /// k, eigenvalues bytes (speeds, k) complex)`, each row by descending
    /// real part (no mode labels, no vectors: the fast path for large
    /// speed grids).
    fn eigenvalues<'py>(
        &self,
        py: Python<'py>,
        speeds: &[u8],
        model: Option<String>,
    ) -> PyResult<(String, usize, Bound<'py, PyBytes>)> {
        let speeds = doubles(speeds, "speeds").map_err(|e| e.into_py(py))?;
        let (name, k, values) = detached(py, || {
            finite_speeds(&speeds, "speeds")?;
            let lin = self.linear(model.as_deref())?;
            let fail = |e: bikedyn::runtime::eigen::EigenError| Failure::new("ComputationError", e);
            let sort = |z: &mut Vec<nalgebra::Complex<f64>>| {
                z.sort_by(|a, b| b.re.total_cmp(&a.re).then(b.im.total_cmp(&a.im)));
            };
            if lin.first_order().is_some() {
                // Extra states: the sweep's spectrum, which includes them.
                let sweep = eigen_sweep_of(&lin, &speeds).map_err(fail)?;
                let k = 4 + sweep
                    .points
                    .iter()
                    .map(|p| p.extra_eigenvalues.len())
                    .max()
                    .unwrap_or(0);
                let mut values = Vec::with_capacity(2 * k * speeds.len());
                for p in &sweep.points {
                    let mut z: Vec<_> = p.eigenvalues.iter().chain(&p.extra_eigenvalues).copied().collect();
                    sort(&mut z);
                    z.resize(k, nalgebra::Complex::new(f64::NAN, f64::NAN));
                    values.extend(z.iter().flat_map(|z| [z.re, z.im]));
                }
                return Ok((lin.model, k, values));
            }
            const CHUNK: usize = 1024;
            let rows: Vec<Result<Vec<f64>, Failure>> = speeds
                .par_chunks(CHUNK)
                .map(|chunk| {
                    let mut out = Vec::with_capacity(8 * chunk.len());
                    for &v in chunk {
                        let mut z = eigenvalues_of(&lin, v).map_err(fail)?.to_vec();
                        sort(&mut z);
                        out.extend(z.iter().flat_map(|z| [z.re, z.im]));
                    }
                    Ok(out)
                })
                .collect();
            let mut values = Vec::with_capacity(8 * speeds.len());
            for r in rows {
                values.extend(r?);
            }
            Ok((lin.model, 4, values))
        })?;
        Ok((name.to_string(), k, PyBytes::new(py, &bytes_of(&values))))
    }

    /// The standard deviations `[re, im]` (1/s) of `eigenvalues` (`[re,
    /// im]` pairs, four per speed, as `eig` orders them) from the file's
    /// +/- values, flat; `None` when the file gives none (see
    /// `bikedyn eig --format json`'s `standard_deviations`).
    fn eigenvalue_spread(
        &self,
        py: Python<'_>,
        speeds: Vec<f64>,
        eigenvalues: Vec<f64>,
        model: Option<String>,
    ) -> PyResult<Option<Vec<f64>>> {
        detached(py, move || {
            if eigenvalues.len() != speeds.len() * 8 {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!(
                        "{} eigenvalue numbers for {} speeds: expected four [re, im] pairs per speed",
                        eigenvalues.len(),
                        speeds.len()
                    ),
                ));
            }
            let Some(spread) = bikedyn::sensitivity::EigenvalueSpread::of(&self.inner, model.as_deref())
                .map_err(|e| Failure::new("ModelError", e))?
            else {
                return Ok(None);
            };
            let mut out = Vec::with_capacity(eigenvalues.len());
            for (v, z) in speeds.iter().zip(eigenvalues.chunks(8)) {
                let pairs: Vec<[f64; 2]> = z.chunks(2).map(|p| [p[0], p[1]]).collect();
                out.extend(spread.of_eigenvalues(*v, &pairs).into_iter().flatten());
            }
            Ok(Some(out))
        })
    }

    /// Stability between `speed_min` and `speed_max` (m/s) as the JSON of
    /// `bikedyn stability --json`.
    #[pyo3(signature = (speed_min, speed_max, model, monte_carlo = None, seed = 1))]
    fn stability(
        &self,
        py: Python<'_>,
        speed_min: f64,
        speed_max: f64,
        model: Option<String>,
        monte_carlo: Option<usize>,
        seed: u64,
    ) -> PyResult<String> {
        detached(py, move || {
            if !(speed_min.is_finite() && speed_max.is_finite() && speed_min >= 0.0 && speed_max > speed_min) {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!("speed range [{speed_min}, {speed_max}] m/s: expected 0 <= speed_min < speed_max, finite"),
                ));
            }
            let lin = self.linear(model.as_deref())?;
            let crit =
                critical_speeds_of(&lin, speed_min, speed_max).map_err(|e| Failure::new("ComputationError", e))?;
            let mut v = stability_json(&self.inner.name, &crit);
            v["model"] = serde_json::json!(lin.model);
            // The speeds' standard deviations from the file's +/- values,
            // as `bikedyn stability --json` gives them (none where the file
            // gives none or no exact derivative exists).
            let options = bikedyn::sensitivity::SensitivityOptions {
                model: model.clone(),
                speed_max,
                ..Default::default()
            };
            let first_order = if speed_min == 0.0 {
                bikedyn::sensitivity::speed_uncertainties(&self.inner, &options)
                    .ok()
                    .flatten()
            } else {
                None
            };
            // The Monte Carlo check, as `bikedyn stability --monte-carlo N`.
            let sampled = match monte_carlo {
                None => None,
                Some(draws) => {
                    if draws < 2 {
                        return Err(Failure::new(
                            "InvalidArgumentError",
                            format!("monte_carlo = {draws}: at least 2 draws"),
                        ));
                    }
                    let options = bikedyn::monte_carlo::MonteCarloOptions {
                        draws,
                        seed,
                        model: model.clone(),
                        speed_max,
                    };
                    match bikedyn::monte_carlo::monte_carlo_speeds(&self.inner, &options)
                        .map_err(|e| Failure::new("ModelError", e))?
                    {
                        Some(m) => Some(m),
                        None => {
                            return Err(Failure::new(
                                "InvalidArgumentError",
                                format!(
                                    "monte_carlo draws about the file's +/- standard deviations, and `{}` gives none",
                                    self.inner.name
                                ),
                            ))
                        }
                    }
                }
            };
            bikedyn::monte_carlo::add_spread_json(&mut v, first_order.as_ref(), sampled.as_ref())
                .map_err(|e| Failure::new("InternalError", e))?;
            Ok(v.to_string())
        })
    }

    /// The exact sensitivities of the weave and capsize speeds (and, at
    /// `speed`, of the eigenvalues) to every parameter, as the JSON of
    /// `bikedyn sensitivity --format json`. `form`: `benchmark`, `thesis`
    /// or `None` (the bicycle's own).
    #[pyo3(signature = (speed, speed_max, form, model))]
    fn sensitivity(
        &self,
        py: Python<'_>,
        speed: Option<f64>,
        speed_max: f64,
        form: Option<String>,
        model: Option<String>,
    ) -> PyResult<String> {
        use bikedyn::runtime::parameters::Form;
        use bikedyn::sensitivity::{sensitivity, SensitivityError as E, SensitivityOptions};
        detached(py, move || {
            let form = match form.as_deref() {
                None => None,
                Some("benchmark") => Some(Form::Benchmark),
                Some("thesis") => Some(Form::Thesis),
                Some(f) => {
                    return Err(Failure::new(
                        "InvalidArgumentError",
                        format!("form {f:?}: expected \"benchmark\", \"thesis\" or None"),
                    ))
                }
            };
            let s = sensitivity(
                &self.inner,
                &SensitivityOptions {
                    model,
                    form,
                    speed,
                    speed_max,
                },
            )
            .map_err(|e| match e {
                E::Bicycle(b) => bicycle_failure(b),
                E::NotCanonical { .. } => Failure::new("ModelError", e),
                E::NonFiniteSpeed { .. } | E::BadSpeedMax { .. } | E::NoCrossing { .. } => {
                    Failure::new("InvalidArgumentError", e)
                }
                e => Failure::new("ComputationError", e),
            })?;
            serde_json::to_string(&s).map_err(|e| Failure::new("InternalError", e))
        })
    }

    /// The frequency response at `speed` (roll and steer torques to roll
    /// and steer angles) on `points` log-spaced angular frequencies, as
    /// the JSON of `bikedyn bode --format json`.
    #[pyo3(signature = (speed, omega_min, omega_max, points, model))]
    fn bode(
        &self,
        py: Python<'_>,
        speed: f64,
        omega_min: f64,
        omega_max: f64,
        points: usize,
        model: Option<String>,
    ) -> PyResult<String> {
        use bikedyn::frequency::{frequency_response, FrequencyOptions, FrequencyResponseError as E};
        use bikedyn::runtime::frequency::FrequencyError as F;
        detached(py, move || {
            let r = frequency_response(
                &self.inner,
                &FrequencyOptions {
                    model,
                    speed,
                    omega_min,
                    omega_max,
                    points,
                },
            )
            .map_err(|e| match e {
                E::Bicycle(b) => bicycle_failure(b),
                E::NonFiniteSpeed { .. }
                | E::Points { .. }
                | E::Frequency {
                    source: F::BadFrequencies { .. },
                    ..
                } => Failure::new("InvalidArgumentError", e),
                E::Frequency {
                    source: F::FirstOrder { .. },
                    ..
                } => Failure::new("ModelError", e),
                e => Failure::new("ComputationError", e),
            })?;
            serde_json::to_string(&r).map_err(|e| Failure::new("InternalError", e))
        })
    }
}

/// Stability over one or two parameters: for every design (cell) the
/// least-stable real part at each speed, and the weave and capsize speeds
/// in the speeds' range. Cells run in parallel on every core.
#[pyfunction]
#[pyo3(signature = (bike, param, values, speeds, param2=None, values2=None, model=None))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn sweep<'py>(
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

/// A simulation's output: `(model, column names, columns bytes (columns,
/// samples), samples, stop reason, statistics JSON)`, the columns those of
/// `bikedyn simulate --out`'s CSV.
type SimulationOut<'py> = (
    String,
    Vec<String>,
    Bound<'py, PyBytes>,
    usize,
    String,
    String,
    Vec<(&'static str, String)>,
);

/// Nonlinear simulation (SI units: rad, rad/s, m/s, N m, N s).
#[pyfunction]
#[pyo3(signature = (bike, duration, initial, kicks, pulses, model=None, free_speed=false, rtol=1e-8, atol=1e-10, method="dop853".to_string(), dt=0.01, roll_limit=None, steer_limit=None))]
#[allow(clippy::too_many_arguments)]
fn simulate<'py>(
    py: Python<'py>,
    bike: &PyBicycle,
    duration: f64,
    initial: (f64, f64, f64, f64, f64, f64),
    kicks: Vec<(f64, f64, Option<f64>, Option<f64>)>,
    pulses: Vec<(String, f64, f64, f64, String)>,
    model: Option<String>,
    free_speed: bool,
    rtol: f64,
    atol: f64,
    method: String,
    dt: f64,
    roll_limit: Option<f64>,
    steer_limit: Option<f64>,
) -> PyResult<SimulationOut<'py>> {
    let b = &bike.inner;
    let (model, header, columns, samples, stop, stats, roles) = detached(py, move || {
        let (roll, steer, roll_rate, steer_rate, speed, yaw) = initial;
        for (name, x) in [
            ("roll", roll),
            ("steer", steer),
            ("roll_rate", roll_rate),
            ("steer_rate", steer_rate),
            ("speed", speed),
            ("yaw", yaw),
            ("duration", duration),
            ("dt", dt),
            ("rtol", rtol),
            ("atol", atol),
        ] {
            if !x.is_finite() {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!("{name} = {x} is not a finite number"),
                ));
            }
        }
        let mut kick_list = Vec::new();
        for (k, &(time, impulse, ahead, height)) in kicks.iter().enumerate() {
            let mut kick = Kick::at_saddle(time, impulse);
            if let (Some(a), Some(h)) = (ahead, height) {
                kick.ahead = a;
                kick.height = h;
            }
            if ![kick.time, kick.impulse, kick.ahead, kick.height]
                .iter()
                .all(|x| x.is_finite())
            {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!("kicks[{k}]: every number must be finite"),
                ));
            }
            kick_list.push(kick);
        }
        let mut pulse_list = Vec::new();
        for (k, (target, start, length, amplitude, shape)) in pulses.iter().enumerate() {
            let target = match target.as_str() {
                "roll" => PulseTarget::Roll,
                "steer" => PulseTarget::Steer,
                other => {
                    return Err(Failure::new(
                        "InvalidArgumentError",
                        format!("pulses[{k}]: target `{other}` is neither roll nor steer"),
                    ))
                }
            };
            let shape = match shape.as_str() {
                "rect" | "rectangular" => PulseShape::Rectangular,
                "halfsine" | "half-sine" => PulseShape::HalfSine,
                other => {
                    return Err(Failure::new(
                        "InvalidArgumentError",
                        format!("pulses[{k}]: shape `{other}` is neither rect nor halfsine"),
                    ))
                }
            };
            if !(length.is_finite() && *length > 0.0 && start.is_finite() && amplitude.is_finite()) {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!("pulses[{k}]: start and amplitude must be finite and the duration positive"),
                ));
            }
            pulse_list.push(TorquePulse {
                target,
                shape,
                start: *start,
                duration: *length,
                amplitude: *amplitude,
            });
        }
        let method = method.parse().map_err(|e| Failure::new("InvalidArgumentError", e))?;
        let opts = SimOptions {
            rtol,
            atol,
            method,
            output_interval: dt,
            events: Events {
                roll_limit,
                steer_limit,
            },
        };
        let info = bikedyn::simulate::choose_model(b, model.as_deref(), free_speed).map_err(sim_failure)?;
        let ic = InitialConditions {
            roll,
            steer,
            roll_rate,
            steer_rate,
            speed,
            yaw,
            ..InitialConditions::default()
        };
        let inputs = Inputs {
            kicks: kick_list,
            pulses: pulse_list,
        };
        let sim = bikedyn::simulate::run(b, info, &ic, &inputs, duration, &opts).map_err(sim_failure)?;
        let header = bikedyn::report::simulate::simulation_csv_header(&sim);
        let n = sim.t.len();
        let mut columns: Vec<f64> = Vec::with_capacity(header.len() * n);
        columns.extend(&sim.t);
        for j in 0..sim.coordinates.len() {
            columns.extend(sim.p.iter().map(|row| row[j]));
        }
        for j in 0..sim.coordinates.len() {
            columns.extend(sim.dp.iter().map(|row| row[j]));
        }
        for c in [
            &sim.speed,
            &sim.kinetic_energy,
            &sim.potential_energy,
            &sim.constraint_residual,
        ] {
            columns.extend(c.iter());
        }
        for j in 0..sim.states.len() {
            columns.extend(sim.z.iter().map(|row| row[j]));
        }
        if columns.len() != header.len() * n {
            return Err(Failure::new(
                "InternalError",
                "simulation columns do not match the CSV header",
            ));
        }
        let stats = serde_json::json!({
            "rhs_evaluations": sim.stats.rhs_evaluations,
            "accepted_steps": sim.stats.accepted_steps,
            "rejected_steps": sim.stats.rejected_steps,
            "max_constraint_residual": sim.max_constraint_residual(),
            "max_velocity_residual": sim.max_velocity_residual(),
            "relative_energy_change": sim.relative_energy_drift(),
            "free_speed": info.free_speed,
        });
        let roles = sim
            .roles
            .iter()
            .map(|&(role, i)| (role_name(role), sim.coordinates[i].to_string()))
            .collect();
        Ok((
            sim.model.to_string(),
            header,
            columns,
            n,
            sim.stop.to_string(),
            stats.to_string(),
            roles,
        ))
    })?;
    Ok((
        model,
        header,
        PyBytes::new(py, &bytes_of(&columns)),
        samples,
        stop,
        stats,
        roles,
    ))
}

/// The snake-case name of a coordinate's role (what `Simulation.roles` maps
/// to the model's own coordinate names).
fn role_name(role: bikedyn::runtime::model::CoordinateRole) -> &'static str {
    use bikedyn::runtime::model::CoordinateRole as R;
    match role {
        R::RearContactX => "rear_contact_x",
        R::RearContactY => "rear_contact_y",
        R::Yaw => "yaw",
        R::Roll => "roll",
        R::Pitch => "pitch",
        R::Steer => "steer",
        R::RearWheelRotation => "rear_wheel_rotation",
        R::FrontWheelRotation => "front_wheel_rotation",
        R::FrontContactRimAngle => "front_contact_rim_angle",
    }
}

fn sim_failure(e: bikedyn::simulate::SimulationError) -> Failure {
    use bikedyn::simulate::SimulationError as E;
    match e {
        E::Bicycle(b) => bicycle_failure(b),
        E::NoFreeSpeedVariant { .. } => Failure::new("ModelError", e),
        E::Linearize(_) => Failure::new("ParameterError", e),
        E::Simulate(_) => Failure::new("ComputationError", e),
    }
}

/// The measured-run pipeline's result (`bikedyn fit`).
#[pyclass(name = "_FitResult", module = "bikedyn._bikedyn", frozen)]
struct PyFitResult {
    outcome: FitOutcome,
    json: String,
    /// The figures' subject (the bicycle), as the command line titles them.
    subject: Option<String>,
}

#[pymethods]
impl PyFitResult {
    /// The result as JSON: kicks (`bikedyn fit --json`'s records), skipped
    /// runs with the reason, the calibration and the prediction model.
    fn json(&self) -> String {
        self.json.clone()
    }

    /// Write `kicks.json` and the fit plots (SVG and PNG) into `dir`.
    fn write_report(&self, py: Python<'_>, dir: PathBuf) -> PyResult<()> {
        let out = &self.outcome;
        let json = &self.json;
        detached(py, move || {
            // Written whole beside `dir` and moved in, as `bikedyn fit
            // --plot` does; only a folder of earlier plots is replaced.
            let staged = StagedDir::new(&dir, FolderKind::FitPlots).map_err(|e| Failure::new("OutputError", e))?;
            write_atomic(staged.path().join("kicks.json"), |w| w.write_all(json.as_bytes()))
                .map_err(|e| Failure::new("OutputError", e))?;
            let opts = PlotOptions {
                subject: self.subject.clone(),
                ..PlotOptions::default()
            };
            plots_into(out, staged.path(), &opts).map_err(|e| Failure::new("OutputError", e))?;
            staged.commit().map_err(|e| Failure::new("OutputError", e))
        })
    }
}

/// Run `bikedyn fit` on run folders, set folders or logs.
#[pyfunction]
#[pyo3(signature = (inputs, calibration=None, bike=None, angles="direct".to_string(), nominal_clock=false, progress=None))]
fn fit(
    py: Python<'_>,
    inputs: Vec<PathBuf>,
    calibration: Option<PathBuf>,
    bike: Option<String>,
    angles: String,
    nominal_clock: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<PyFitResult> {
    let progress = PyProgress::new(progress);
    let result = detached(py, || {
        let angles = match angles.as_str() {
            "direct" => AngleMethod::Direct,
            "thesis" => AngleMethod::Thesis,
            other => {
                return Err(Failure::new(
                    "InvalidArgumentError",
                    format!("angles = {other:?}: expected \"direct\" or \"thesis\""),
                ))
            }
        };
        let opts = FitOptions {
            inputs,
            calibration,
            bike,
            angles,
            nominal_clock,
        };
        let outcome = run_fit(&opts, &|p| progress.report(p)).map_err(|e| Failure::new("DataError", e))?;
        // Nothing fitted and something skipped: the reasons are the answer
        // (as `bikedyn fit` exits 1), not an empty result.
        if outcome.reports.iter().all(|r| r.kicks.is_empty()) && !outcome.errors.is_empty() {
            return Err(Failure::new(
                "DataError",
                format!("no kick was fitted: {}", outcome.errors.join("; ")),
            ));
        }
        // The figures name the bicycle (given, or the thesis default).
        let subject = Some(bikedyn::report::plot::subject(&outcome.bike, None));
        let linear = &outcome.linear as &dyn LinearBicycle;
        let kicks: Vec<serde_json::Value> = outcome
            .reports
            .iter()
            .flat_map(|r| r.kicks.iter())
            .map(|k| kick_json(k, linear))
            .collect();
        let json = serde_json::json!({
            "kicks": kicks,
            "skipped": outcome.errors,
            "notes": outcome.reports.iter().flat_map(|r| r.notes.iter().map(move |n| format!("{}: {n}", r.run.display()))).collect::<Vec<_>>(),
            "calibration": bikedyn::fit::calibration_text(&outcome),
            "prediction_model": outcome.linear.model,
        });
        Ok(PyFitResult {
            json: serde_json::to_string_pretty(&json).expect("JSON of plain values"),
            outcome,
            subject,
        })
    });
    progress.raised()?;
    result
}

/// What identification found (`bikedyn identify`).
#[pyclass(name = "_IdentifyResult", module = "bikedyn._bikedyn", unsendable)]
struct PyIdentifyResult {
    outcome: Outcome,
    request: IdentifyRequest,
    json: String,
    summary: String,
}

#[pymethods]
impl PyIdentifyResult {
    /// `bikedyn identify --json`.
    fn json(&self) -> String {
        self.json.clone()
    }
    /// The console summary of `bikedyn identify`.
    fn summary(&self) -> String {
        self.summary.clone()
    }
    /// Write the report (report.md, report.json, plots, tables) into `dir`,
    /// replacing a previous report as a whole.
    fn write_report(&self, py: Python<'_>, dir: PathBuf) -> PyResult<()> {
        let r = catch_unwind(AssertUnwindSafe(|| {
            identify_report::write_report(&self.outcome, &self.request, &dir, &PlotOptions::default())
        }));
        match r {
            Ok(Ok(())) => Ok(()),
            Ok(Err(e)) => Err(Failure::new("OutputError", e).into_py(py)),
            Err(p) => Err(Failure::new("InternalError", panic_message(p)).into_py(py)),
        }
    }
}

/// Run `bikedyn identify` on run folders, set folders or logs.
#[pyfunction]
#[pyo3(signature = (inputs, calibration=None, bike=None, effects=Vec::new(), folds=4, corrections=None, progress=None))]
fn identify(
    py: Python<'_>,
    inputs: Vec<PathBuf>,
    calibration: Option<PathBuf>,
    bike: Option<String>,
    effects: Vec<String>,
    folds: usize,
    corrections: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<PyIdentifyResult> {
    if !(2..=1000).contains(&folds) {
        return Err(Failure::new("InvalidArgumentError", format!("folds = {folds}: expected 2 to 1000")).into_py(py));
    }
    let request = IdentifyRequest {
        inputs,
        calibration,
        bike,
        effects,
        folds,
        corrections,
    };
    let progress = PyProgress::new(progress);
    let outcome = detached(py, || {
        identify_run(&request, &|p| progress.report(p)).map_err(|e| Failure::new("DataError", e))
    });
    progress.raised()?;
    let outcome = outcome?;
    let json = serde_json::to_string_pretty(&identify_report::outcome_json(&outcome)).expect("JSON of plain values");
    let summary = identify_report::summary(&outcome);
    Ok(PyIdentifyResult {
        outcome,
        request,
        json,
        summary,
    })
}

/// What identification from a measured eigenvalue table found.
#[pyclass(name = "_TableResult", module = "bikedyn._bikedyn", frozen)]
struct PyTableResult {
    outcome: TableOutcome,
}

#[pymethods]
impl PyTableResult {
    /// `bikedyn identify --eigenvalues ... --json`.
    fn json(&self) -> String {
        serde_json::to_string_pretty(&self.outcome).expect("JSON of plain values")
    }
    /// The console summary.
    fn summary(&self) -> String {
        bikedyn::identify::eigen_table::table_summary(&self.outcome)
    }
    /// Write the report into `dir`.
    fn write_report(&self, py: Python<'_>, dir: PathBuf) -> PyResult<()> {
        let o = &self.outcome;
        detached(py, move || {
            write_table_report(o, &dir).map_err(|e| Failure::new("OutputError", e))
        })
    }
}

/// Run `bikedyn identify --eigenvalues TABLE`.
#[pyfunction]
#[pyo3(signature = (table, bike=None, effects=Vec::new(), corrections=None))]
fn identify_eigenvalues(
    py: Python<'_>,
    table: PathBuf,
    bike: Option<String>,
    effects: Vec<String>,
    corrections: Option<usize>,
) -> PyResult<PyTableResult> {
    detached(py, move || {
        // A table is no thesis-format run: its bicycle must be named.
        let bike = bike.ok_or_else(|| {
            Failure::new(
                "InvalidArgumentError",
                bikedyn::fit::BikeRequired {
                    inputs: vec![table.clone()],
                },
            )
        })?;
        let outcome = identify_table(&TableRequest {
            path: table,
            bike,
            effects,
            corrections,
        })
        .map_err(|e| Failure::new("DataError", e))?;
        Ok(PyTableResult { outcome })
    })
}

/// The generated models, as `bikedyn models --json` lists them.
#[pyfunction]
fn models() -> String {
    let list: Vec<serde_json::Value> = bikedyn::models::models()
        .iter()
        .map(bikedyn::models::model_json)
        .collect();
    serde_json::Value::Array(list).to_string()
}

/// Panic inside the guard every call runs in, for the test that a panic
/// reaches Python as `bikedyn.InternalError` (not part of the API).
#[pyfunction]
fn _panic_for_tests(py: Python<'_>) -> PyResult<()> {
    detached(py, || -> Result<(), Failure> {
        panic!("a deliberate panic (test of the guard)")
    })
}

/// Accept parameter files whose lengths look like millimetres.
#[pyfunction]
fn allow_implausible_units(allow: bool) {
    bikedyn::bicycle::allow_implausible_units(allow);
}

#[pymodule]
fn _bikedyn(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyBicycle>()?;
    m.add_class::<PyFitResult>()?;
    m.add_class::<PyIdentifyResult>()?;
    m.add_class::<PyTableResult>()?;
    m.add_function(wrap_pyfunction!(sweep, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(fit, m)?)?;
    m.add_function(wrap_pyfunction!(identify, m)?)?;
    m.add_function(wrap_pyfunction!(identify_eigenvalues, m)?)?;
    m.add_function(wrap_pyfunction!(models, m)?)?;
    m.add_function(wrap_pyfunction!(allow_implausible_units, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_for_tests, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
