//! Measured runs: `fit`, `identify` and `identify_eigenvalues`, and their results.

use super::*;

/// The measured-run pipeline's result (`bikedyn fit`).
#[pyclass(name = "_FitResult", module = "bikedyn._bikedyn", frozen)]
pub(crate) struct PyFitResult {
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
pub(crate) fn fit(
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
        Ok(PyFitResult {
            json: serde_json::to_string_pretty(&bikedyn::fit::FitRecord::of(&outcome)).expect("JSON of plain values"),
            outcome,
            subject,
        })
    });
    progress.raised()?;
    result
}

/// What identification found (`bikedyn identify`).
#[pyclass(name = "_IdentifyResult", module = "bikedyn._bikedyn", unsendable)]
pub(crate) struct PyIdentifyResult {
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
#[pyo3(signature = (inputs, calibration=None, bike=None, effects=Vec::new(), folds=4, corrections=None, progress=None, discover=true, max_fits_per_step=None, family_wise_bar=false))]
pub(crate) fn identify(
    py: Python<'_>,
    inputs: Vec<PathBuf>,
    calibration: Option<PathBuf>,
    bike: Option<String>,
    effects: Vec<String>,
    folds: usize,
    corrections: Option<usize>,
    progress: Option<Py<PyAny>>,
    discover: bool,
    max_fits_per_step: Option<usize>,
    family_wise_bar: bool,
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
        discover,
        max_fits_per_step,
        family_wise_bar,
    };
    let progress = PyProgress::new(progress);
    let outcome = detached(py, || {
        identify_run(&request, &|p| progress.report(p)).map_err(|e| Failure::new("DataError", e))
    });
    progress.raised()?;
    let outcome = outcome?;
    let json = serde_json::to_string_pretty(&identify_report::result(&outcome)).expect("JSON of plain values");
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
pub(crate) struct PyTableResult {
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
#[pyo3(signature = (table, bike=None, effects=Vec::new(), corrections=None, discover=true))]
pub(crate) fn identify_eigenvalues(
    py: Python<'_>,
    table: PathBuf,
    bike: Option<String>,
    effects: Vec<String>,
    corrections: Option<usize>,
    discover: bool,
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
            discover,
        })
        .map_err(|e| Failure::new("DataError", e))?;
        Ok(PyTableResult { outcome })
    })
}
