//! `_Bicycle`: a bicycle's linear analysis, stability and uncertainties.

use super::*;
use bikedyn::bicycle::files::ParameterFile;
use bikedyn::eigen::{eigenvalues, EigenJob, EigenOptions, EigenSweepError, Speeds};
use bikedyn::runtime::eigen::EigenPoint;

/// The exception kind of an eigen-analysis error.
fn eigen_failure(e: EigenSweepError) -> Failure {
    match e {
        EigenSweepError::Bicycle(e) => Failure::from(e),
        EigenSweepError::Eigen(e) => Failure::new("ComputationError", e),
        e @ (EigenSweepError::NoSpeeds | EigenSweepError::Speed { .. } | EigenSweepError::Step(_)) => {
            Failure::new("InvalidArgumentError", e)
        }
    }
}

/// A bicycle: its parameters (thesis or benchmark form), effect
/// parameters and uncertainties, resolved against the built-in models.
#[pyclass(name = "_Bicycle", module = "bikedyn._bikedyn", frozen)]
pub(crate) struct PyBicycle {
    pub(crate) inner: Bicycle,
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

    /// Standard deviations of the canonical matrices' entries (M0, C1, K0,
    /// K2, each row-major) that the file's `+/-` values imply (first
    /// order, exact derivatives), or `None` for a file without them.
    fn canonical_standard_deviations(&self, py: Python<'_>, model: Option<String>) -> PyResult<Option<Vec<[f64; 4]>>> {
        detached(py, move || {
            let sd = bikedyn::sensitivity::canonical_uncertainties(&self.inner, model.as_deref())
                .map_err(|e| Failure::new("ModelError", e))?;
            let flat = |m: &nalgebra::Matrix2<f64>| [m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]];
            Ok(sd.map(|c| vec![flat(&c.m0), flat(&c.c1), flat(&c.k0), flat(&c.k2)]))
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
        let ss = detached(py, || {
            finite_speeds(&speeds, "speeds")?;
            bikedyn::canonical::state_space(&self.inner, model.as_deref(), &speeds).map_err(|e| match e {
                bikedyn::canonical::CanonicalError::Bicycle(e) => Failure::from(e),
                e => Failure::new("ComputationError", e),
            })
        })?;
        let n = ss.states.len();
        let a: Vec<f64> = ss.at.iter().flat_map(|at| at.a.iter().flatten().copied()).collect();
        let b: Option<Vec<f64>> = ss
            .at
            .iter()
            .map(|at| at.b.as_ref().map(|b| b.iter().flatten().copied().collect::<Vec<f64>>()))
            .collect::<Option<Vec<_>>>()
            .filter(|_| !ss.inputs.is_empty())
            .map(|rows| rows.concat());
        Ok((
            ss.model,
            n,
            ss.states,
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
            let job = EigenJob::new(
                &self.inner,
                &EigenOptions {
                    model,
                    speeds: Speeds::List(speeds.clone()),
                    standard_deviations: false,
                    critical_speeds: false,
                },
            )
            .map_err(eigen_failure)?;
            // The solver's order, with the eigenvectors: as the arrays have
            // always been.
            let points: Vec<EigenPoint> = job
                .points()
                .map(|p| p.map(|p| p.point))
                .collect::<Result<_, _>>()
                .map_err(eigen_failure)?;
            let k = 4 + points.iter().map(|p| p.extra_eigenvalues.len()).max().unwrap_or(0);
            let mut values = Vec::with_capacity(2 * k * speeds.len());
            let mut vectors = Vec::with_capacity(32 * speeds.len());
            let mut codes = Vec::with_capacity(4 * speeds.len());
            let mut names: Vec<&'static str> = Vec::new();
            for p in &points {
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
            Ok((job.model, k, values, codes, names, vectors))
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
        let e = detached(py, || {
            finite_speeds(&speeds, "speeds")?;
            eigenvalues(&self.inner, model.as_deref(), &speeds).map_err(eigen_failure)
        })?;
        let values: Vec<f64> = e.values.iter().flatten().copied().collect();
        Ok((e.model, e.per_speed, PyBytes::new(py, &bytes_of(&values))))
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
        use bikedyn::stability::{stability, StabilityError as E, StabilityOptions};
        detached(py, move || {
            let report = stability(
                &self.inner,
                &StabilityOptions {
                    model,
                    speed_min,
                    speed_max,
                    monte_carlo: monte_carlo.map(|draws| (draws, seed)),
                    label: None,
                },
            )
            .map_err(|e| match e {
                E::Bicycle(e) => Failure::from(e),
                E::Eigen(e) => Failure::new("ComputationError", e),
                E::Sensitivity(e) => Failure::new("ModelError", e),
                e @ (E::SpeedRange(..) | E::TooFewDraws(_) | E::NoUncertainties(_)) => {
                    Failure::new("InvalidArgumentError", e)
                }
            })?;
            serde_json::to_string(&report).map_err(|e| Failure::new("InternalError", e))
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
