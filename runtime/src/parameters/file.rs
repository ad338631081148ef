//! What both parameter-file formats ([`super::load`], [`super::text`])
//! share: the file's text, read whole, and the error for absent fields.

use super::ParameterError;
use std::path::Path;

/// The text of the parameter file at `path`.
pub(crate) fn read(path: &Path) -> Result<String, ParameterError> {
    // Capped: a parameter file is kilobytes; `--bike /dev/zero` must not
    // grow without end.
    crate::experiment::read::read_text_capped(path, crate::experiment::read::MAX_TEXT_FILE_BYTES).map_err(|source| {
        ParameterError::Io {
            path: path.to_path_buf(),
            source,
        }
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
