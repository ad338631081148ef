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
use bikedyn::fit::{plots_into, run_fit, FitOptions, FitOutcome};
use bikedyn::identify::eigen_table::{identify_table, write_table_report, TableOutcome, TableRequest};
use bikedyn::identify::{report as identify_report, run as identify_run, IdentifyRequest, Outcome};
use bikedyn::report::output::write_atomic;
use bikedyn::report::plot::PlotOptions;
use bikedyn::report::staged::{FolderKind, StagedDir};
use bikedyn::runtime::experiment::angles::AngleMethod;
use bikedyn::runtime::parameters::ParameterSet;
use bikedyn::runtime::simulate::{
    Events, InitialConditions, Inputs, Kick, PulseShape, PulseTarget, SimOptions, TorquePulse,
};
use pyo3::prelude::*;
use pyo3::types::PyBytes;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::PathBuf;

mod bicycle;
mod measured;
mod simulation;
mod stability_sweep;

use bicycle::PyBicycle;
use measured::{PyFitResult, PyIdentifyResult, PyTableResult};

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
    Failure::new(bicycle_kind(&e), e)
}

/// The exception kind of a bicycle error ([`bicycle_failure`]).
fn bicycle_kind(e: &BicycleError) -> &'static str {
    match e {
        BicycleError::NotFound { .. } => "NotFoundError",
        BicycleError::UnknownModel { .. }
        | BicycleError::ModelDoesNotFit { .. }
        | BicycleError::NoModelFits { .. }
        | BicycleError::NotCanonical { .. } => "ModelError",
        BicycleError::Linearize { .. } => "ComputationError",
        _ => "ParameterError",
    }
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

/// Most speeds one call takes: an eigen analysis returns about 330 bytes
/// per speed (eigenvalues, eigenvectors, mode codes) and Python copies them
/// once more, so a million speeds stay near a gigabyte; 10^7 speeds peaked
/// at 11.4 GB and aborted the interpreter under a memory limit.
const MAX_SPEEDS: usize = 1_000_000;

/// Most values a sweep returns (cells times speeds, 8 bytes each, held
/// twice while they are gathered): about 800 MB.
pub(crate) const MAX_SWEEP_VALUES: usize = 50_000_000;

fn finite_speeds(speeds: &[f64], what: &str) -> Result<(), Failure> {
    if speeds.is_empty() {
        return Err(Failure::new("InvalidArgumentError", format!("{what}: no speeds given")));
    }
    if speeds.len() > MAX_SPEEDS {
        return Err(Failure::new(
            "TooLargeError",
            format!(
                "{what}: {} speeds, more than the {MAX_SPEEDS} one call takes; split them into several calls",
                speeds.len()
            ),
        ));
    }
    match speeds.iter().position(|v| !v.is_finite()) {
        Some(i) => Err(Failure::new(
            "InvalidArgumentError",
            format!("{what}[{i}] = {} is not a finite speed (m/s)", speeds[i]),
        )),
        None => Ok(()),
    }
}

/// The generated models, as `bikedyn models --json` lists them.
#[pyfunction]
fn models() -> String {
    let list: Vec<bikedyn::models::ModelRecord> = bikedyn::models::models()
        .iter()
        .map(bikedyn::models::ModelRecord::of)
        .collect();
    serde_json::to_string(&list).expect("JSON of plain values")
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
    m.add_function(wrap_pyfunction!(stability_sweep::sweep, m)?)?;
    m.add_function(wrap_pyfunction!(simulation::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(measured::fit, m)?)?;
    m.add_function(wrap_pyfunction!(measured::identify, m)?)?;
    m.add_function(wrap_pyfunction!(measured::identify_eigenvalues, m)?)?;
    m.add_function(wrap_pyfunction!(models, m)?)?;
    m.add_function(wrap_pyfunction!(allow_implausible_units, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_for_tests, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
