//! A parameter set of either form ([`ParameterSet`], [`Form`]): its
//! symbols, validation and conversion between the two forms.

use super::{BenchmarkParameters, ParameterError, ParameterWarning, ThesisParameters};

/// Which parameterization a set uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Form {
    /// [`ThesisParameters`] (Martin Recuero 2009).
    Thesis,
    /// [`BenchmarkParameters`] (Meijaard et al. 2007, Table 1).
    Benchmark,
}

impl Form {
    /// `"thesis"` or `"benchmark"` (the values of the TOML key `form`).
    pub fn name(self) -> &'static str {
        match self {
            Form::Thesis => "thesis",
            Form::Benchmark => "benchmark",
        }
    }

    /// The symbols of this form.
    pub fn symbols(self) -> &'static [&'static str] {
        match self {
            Form::Thesis => &ThesisParameters::SYMBOLS,
            Form::Benchmark => &BenchmarkParameters::SYMBOLS,
        }
    }

    /// The form named `name` (`"thesis"`, `"benchmark"`).
    pub fn from_name(name: &str) -> Option<Form> {
        match name {
            "thesis" => Some(Form::Thesis),
            "benchmark" => Some(Form::Benchmark),
            _ => None,
        }
    }
}

/// A parameter set of either form.
///
/// Its files (TOML of either form, the benchmark text files, Moore's
/// parameters) are read and written by the application
/// (`bikedyn::bicycle::files`).
///
/// ```
/// use bikedyn_runtime::parameters::{Form, ParameterSet, ThesisParameters};
/// let set = ParameterSet::Thesis(ThesisParameters::thesis_bicycle());
/// assert_eq!(set.form(), Form::Thesis);
/// let bench = set.to_benchmark().unwrap();
/// assert!((bench.steer_axis_tilt - 0.315).abs() < 0.01);
/// assert_eq!(set.validate().unwrap().len(), 2); // handlebar and front wheel triangle inequality
/// ```
#[derive(Clone, Debug, PartialEq)]
pub enum ParameterSet {
    /// Thesis form.
    Thesis(ThesisParameters),
    /// Benchmark form.
    Benchmark(BenchmarkParameters),
}

impl ParameterSet {
    /// The form of this set.
    pub fn form(&self) -> Form {
        match self {
            ParameterSet::Thesis(_) => Form::Thesis,
            ParameterSet::Benchmark(_) => Form::Benchmark,
        }
    }

    /// Value by symbol of this set's form.
    pub fn get(&self, symbol: &str) -> Option<f64> {
        match self {
            ParameterSet::Thesis(p) => p.get(symbol),
            ParameterSet::Benchmark(p) => p.get(symbol),
        }
    }

    /// Validate (see [`ThesisParameters::validate`],
    /// [`BenchmarkParameters::validate`]).
    pub fn validate(&self) -> Result<Vec<ParameterWarning>, ParameterError> {
        match self {
            ParameterSet::Thesis(p) => p.validate(),
            ParameterSet::Benchmark(p) => p.validate(),
        }
    }

    /// The thesis form, converting a benchmark set
    /// ([`BenchmarkParameters::to_thesis`]).
    pub fn to_thesis(&self) -> Result<ThesisParameters, ParameterError> {
        match self {
            ParameterSet::Thesis(p) => Ok(*p),
            ParameterSet::Benchmark(p) => p.to_thesis(),
        }
    }

    /// The benchmark form, converting a thesis set
    /// ([`ThesisParameters::to_benchmark`]).
    pub fn to_benchmark(&self) -> Result<BenchmarkParameters, ParameterError> {
        match self {
            ParameterSet::Thesis(p) => p.to_benchmark(),
            ParameterSet::Benchmark(p) => Ok(*p),
        }
    }
}
