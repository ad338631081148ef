//! Parameter files: reading and writing a bicycle's parameters in the
//! formats researchers keep them in. A file format is the application's,
//! not the runtime's: the runtime holds the parameter sets themselves
//! (`bikedyn_runtime::parameters`: both forms, validation, conversion),
//! and this module turns files into them and back.
//!
//! - [`ParameterFile`]: TOML of either form, read ([`load`](ParameterFile::load),
//!   [`from_toml_str`](ParameterFile::from_toml_str)) and written
//!   ([`to_toml_string`](ParameterFile::to_toml_string)), for
//!   [`ThesisParameters`], [`BenchmarkParameters`] and [`ParameterSet`]
//!   (format in [`toml_file`]).
//! - [`ParameterSetFile`]: a file of either format with effect parameters
//!   and a `[feedback]` controller beside the bicycle ([`LoadedSet`]).
//! - [`MeasuredBenchmark`]: the benchmark text files of BicycleParameters
//!   and HumanControl, keeping their `+/-` uncertainties ([`text_file`]).
//!
//! A set written by [`ParameterFile::to_toml_string`] reads back to exactly
//! itself (`tests/parameter_files`, on the reference bicycles and on random
//! sets, bit for bit).

pub mod text_file;
pub mod toml_file;

use std::collections::BTreeMap;
use std::path::Path;

use bikedyn_runtime::feedback::GainSchedule;
#[cfg(doc)]
use bikedyn_runtime::parameters::{BenchmarkParameters, ThesisParameters};
use bikedyn_runtime::parameters::{ParameterError, ParameterSet, ParameterWarning};

pub use text_file::{MeasuredBenchmark, EXTRA_TEXT_FIELDS};
pub use toml_file::feedback_from_toml_str;

/// A parameter set read from and written to TOML (see [`toml_file`]).
pub trait ParameterFile: Sized {
    /// Read and validate a parameter file; the set and its warnings.
    fn load(path: impl AsRef<Path>) -> Result<(Self, Vec<ParameterWarning>), ParameterError>;
    /// Parse and validate TOML text; `path` is only used in messages.
    fn from_toml_str(text: &str, path: impl AsRef<Path>) -> Result<(Self, Vec<ParameterWarning>), ParameterError>;
    /// TOML text (`form = "..."`, one commented `symbol = value` line per
    /// symbol, shortest round-trip float representation): reads back exactly.
    fn to_toml_string(&self) -> String;
}

/// A parameter file of either format with what it holds beside the
/// bicycle: effect parameters, uncertainties and a controller.
pub trait ParameterSetFile: Sized {
    /// Like [`ParameterFile::from_toml_str`], also accepting the symbols in
    /// `extra` (e.g. effect parameters such as `c_steer`), which are
    /// returned by name. Any other unknown symbol is still an error naming
    /// the file and line.
    fn from_toml_str_with_extra(
        text: &str,
        path: impl AsRef<Path>,
        extra: &[&str],
    ) -> Result<(Self, BTreeMap<String, f64>, Vec<ParameterWarning>), ParameterError>;
    /// Read and validate a parameter file, accepting the `extra` symbols
    /// (effect parameters) in TOML and text files alike.
    fn load_with_extra(path: impl AsRef<Path>, extra: &[&str]) -> Result<LoadedSet, ParameterError>;
    /// [`load_with_extra`](Self::load_with_extra) of a file's text already
    /// read; `path` names it in messages.
    fn from_file_text_with_extra(
        text: &str,
        path: impl AsRef<Path>,
        extra: &[&str],
    ) -> Result<LoadedSet, ParameterError>;
    /// Parse and validate a benchmark text file (uncertainties dropped).
    fn from_text_str(text: &str, path: impl AsRef<Path>) -> Result<(Self, Vec<ParameterWarning>), ParameterError>;
}

/// A parameter file as read by [`ParameterSetFile::load_with_extra`].
#[derive(Clone, Debug)]
pub struct LoadedSet {
    pub set: ParameterSet,
    /// Effect parameters given, by symbol.
    pub effects: BTreeMap<String, f64>,
    /// Standard deviations given as `value+/-std`, by symbol.
    pub uncertainties: BTreeMap<String, f64>,
    pub warnings: Vec<ParameterWarning>,
    /// The controller a TOML file declares in its `[feedback]` table.
    pub feedback: Option<GainSchedule>,
}

/// The text of the parameter file at `path`.
fn read(path: &Path) -> Result<String, ParameterError> {
    // Capped: a parameter file is kilobytes; `--bike /dev/zero` must not
    // grow without end.
    crate::capped::read_text_capped(path, crate::capped::MAX_TEXT_FILE_BYTES).map_err(|source| ParameterError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The error for absent required fields: all of them at once.
pub(crate) fn missing_all(path: &Path, absent: &[&str]) -> Option<ParameterError> {
    match absent {
        [] => None,
        [one] => Some(missing(path, one)),
        many => Some(ParameterError::MissingFields {
            path: path.to_path_buf(),
            fields: many.iter().map(|s| s.to_string()).collect(),
        }),
    }
}

pub(super) fn missing(path: &Path, field: &str) -> ParameterError {
    ParameterError::MissingField {
        path: path.to_path_buf(),
        field: field.to_string(),
    }
}
