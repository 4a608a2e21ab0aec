//! Everything that can go wrong reading, writing or building a `.pvs`.

use sightline_methods::MethodError;

/// Everything that can go wrong reading, writing or building a `.pvs`.
#[derive(Debug, thiserror::Error)]
pub enum PvsError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("not a sightline .pvs file (bad magic number)")]
    NotPvs,
    #[error(
        "unsupported .pvs format version {found} (this sightline reads versions 1 to {supported})"
    )]
    Version { found: u16, supported: u16 },
    #[error("truncated .pvs file: {0}")]
    Truncated(String),
    #[error("corrupted .pvs file: {0}")]
    Corrupt(String),
    #[error("this PVS was built for another scene (file fingerprint {file:016x}, scene fingerprint {scene:016x})")]
    SceneMismatch { file: u64, scene: u64 },
    #[error("corrupted journal {path}: {message}")]
    Journal { path: String, message: String },
    #[error("cannot merge: {0}")]
    Merge(String),
    #[error("cell {index} {cell:?}: {source}")]
    Method {
        index: usize,
        cell: [f64; 6],
        source: MethodError,
    },
    #[error("{0}")]
    Invalid(String),
}

impl PvsError {
    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        PvsError::Io {
            path: path.display().to_string(),
            source,
        }
    }
}

/// The runtime reads every `.pvs` (`PvsFile` is built on it): its errors are ours, case
/// for case and word for word.
impl From<sightline_runtime::RuntimeError> for PvsError {
    fn from(e: sightline_runtime::RuntimeError) -> Self {
        use sightline_runtime::RuntimeError as R;
        match e {
            R::Io { path, source } => PvsError::Io { path, source },
            R::NotPvs => PvsError::NotPvs,
            R::Version { found, supported } => PvsError::Version { found, supported },
            R::Truncated(m) => PvsError::Truncated(m),
            R::Corrupt(m) => PvsError::Corrupt(m),
            R::Invalid(m) => PvsError::Invalid(m),
        }
    }
}
