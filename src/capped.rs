//! Reading a file whole with a cap on its size, checked before reading:
//! every reader of the user's files (runs, logs, tables, parameters) goes
//! through it, so no input grows memory without end.

use std::path::Path;

/// The largest file of a thesis-style run read: two hours of 1 kHz IMU
/// samples at about 70 bytes a row (time and a quaternion printed to 7
/// decimals) are 504 MB. Anything larger is not a run's record, and
/// reading it whole would exhaust memory (the rows are parsed into
/// several arrays as large as the text).
pub const MAX_DATA_FILE_BYTES: u64 = 512 << 20;

/// The largest TU Delft log read: its rows are 100 Hz samples of 13
/// columns, about 150 bytes each, so 128 MiB hold over two hours of
/// riding, far more than one session of kicks.
pub const MAX_LOG_FILE_BYTES: u64 = 128 << 20;

/// The largest metadata, parameter or eigenvalue-table file read: these
/// are kilobytes (a table of one row per speed, a few dozen parameters).
pub const MAX_TEXT_FILE_BYTES: u64 = 16 << 20;

/// `limit` bytes in words (MiB).
fn mib(limit: u64) -> String {
    format!("{} MiB", limit >> 20)
}

/// Read at most `limit` bytes of `path`. A regular file larger than the
/// cap is refused from its size, before a byte is read; a folder or a
/// device (`/dev/zero` never ends) is refused as not a file; a pipe
/// (`/dev/stdin`, `<(...)`) is read through a bounded reader, so memory
/// stays below the cap whatever arrives.
pub fn read_capped(path: &Path, limit: u64) -> std::io::Result<Vec<u8>> {
    use std::io::{Error, ErrorKind, Read};
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    let kind = meta.file_type();
    if kind.is_dir() {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "is a folder, not a file: give the file in it",
        ));
    }
    if kind.is_file() && meta.len() > limit {
        return Err(Error::new(
            ErrorKind::InvalidData,
            format!(
                "{} bytes, more than the {} bikedyn reads of such a file: not an input of this kind (a longer record: split it into files below the cap)",
                meta.len(),
                mib(limit)
            ),
        ));
    }
    if is_device(&kind) {
        return Err(Error::new(
            ErrorKind::InvalidInput,
            "is a device, not a file: give a file (or a pipe)",
        ));
    }
    // Even a regular file may grow while it is read: never more than the cap.
    let mut out = Vec::new();
    file.take(limit + 1).read_to_end(&mut out)?;
    if out.len() as u64 > limit {
        return Err(Error::new(
            ErrorKind::InvalidData,
            format!("larger than {}: not a file this reads", mib(limit)),
        ));
    }
    Ok(out)
}

/// A character or block device (`/dev/zero`, `/dev/urandom`, a disk).
#[cfg(unix)]
fn is_device(kind: &std::fs::FileType) -> bool {
    use std::os::unix::fs::FileTypeExt;
    kind.is_char_device() || kind.is_block_device()
}

/// Other systems: only folders and regular files are told apart.
#[cfg(not(unix))]
fn is_device(_: &std::fs::FileType) -> bool {
    false
}

/// [`read_capped`] as text (invalid UTF-8 is an error).
pub fn read_text_capped(path: &Path, limit: u64) -> std::io::Result<String> {
    String::from_utf8(read_capped(path, limit)?)
        .map_err(|_| std::io::Error::new(std::io::ErrorKind::InvalidData, "stream did not contain valid UTF-8"))
}
