//! Importers (SPEC §1 "Input formats"): the format is chosen by file extension.

use crate::Scene;
use std::path::Path;

/// How to interpret coordinates of inputs that may be geographic.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Crs {
    /// Detect WGS84 lon/lat from the coordinate ranges.
    #[default]
    Auto,
    /// Projected metres, used as they are.
    Projected,
    /// WGS84 longitude/latitude, projected to a local metric frame.
    Wgs84,
}

/// Options of [`load`].
#[derive(Clone, Debug, Default)]
pub struct ImportOptions {
    pub crs: Crs,
}

/// A problem that makes an input unusable, naming the feature and what is wrong.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{0}")]
    Format(String),
    #[error("feature {index}: {message}")]
    Feature { index: usize, message: String },
    #[error("unsupported input format '{0}' (expected .geojson, .json, .city.json, .zip, .osm.pbf, .obj, .gltf, .glb)")]
    Unsupported(String),
}

/// Load a scene from a file, choosing the importer by extension.
pub fn load(path: &Path, opts: &ImportOptions) -> Result<Scene, ImportError> {
    let _ = opts;
    Err(ImportError::Unsupported(path.display().to_string()))
}
