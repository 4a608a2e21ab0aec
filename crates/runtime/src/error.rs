//! What can go wrong opening or querying a `.pvs`: the same cases, in the same order, as
//! `sightline-pvs`'s reader, as a plain enum (no panics on hostile bytes).

use std::fmt;

/// An error of the runtime: a file that cannot be read or is not a valid `.pvs`, or a
/// query about a cell the file does not have.
#[derive(Debug)]
pub enum RuntimeError {
    /// The file could not be read.
    Io {
        path: String,
        source: std::io::Error,
    },
    /// Wrong magic number.
    NotPvs,
    /// A format version this reader does not know.
    Version { found: u16, supported: u16 },
    /// The file is shorter than its tables say.
    Truncated(String),
    /// A checksum mismatch or a table that refers outside itself.
    Corrupt(String),
    /// A query about a cell the file does not have or does not store.
    Invalid(String),
}

impl fmt::Display for RuntimeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RuntimeError::Io { path, source } => write!(f, "{path}: {source}"),
            RuntimeError::NotPvs => write!(f, "not a sightline .pvs file (bad magic number)"),
            RuntimeError::Version { found, supported } => write!(
                f,
                "unsupported .pvs format version {found} (this sightline reads versions 1 to {supported})"
            ),
            RuntimeError::Truncated(m) => write!(f, "truncated .pvs file: {m}"),
            RuntimeError::Corrupt(m) => write!(f, "corrupted .pvs file: {m}"),
            RuntimeError::Invalid(m) => write!(f, "{m}"),
        }
    }
}

impl std::error::Error for RuntimeError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            RuntimeError::Io { source, .. } => Some(source),
            _ => None,
        }
    }
}

pub(crate) fn corrupt<T>(m: impl Into<String>) -> Result<T, RuntimeError> {
    Err(RuntimeError::Corrupt(m.into()))
}
