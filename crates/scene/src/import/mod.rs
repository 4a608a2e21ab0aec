//! Importers. The format is chosen by file extension; a
//! `.json` file is GeoJSON or CityJSON according to its `"type"`.
//!
//! Every importer validates and repairs its input ([`validate`]): each repair is a
//! counted [`crate::Warning`] in [`Scene::warnings`], and what cannot be repaired is an
//! [`ImportError`] naming the feature and the problem. Nothing panics on bad input.
//! See `docs/import.md` for the formats, conventions and warning kinds.

pub mod bsp;
pub mod cityjson;
pub mod geojson;
pub mod gltf;
pub mod height;
pub mod mesh_bounds;
pub mod obj;
pub mod osm;
pub mod project;
pub mod tileset;
pub mod validate;

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
    /// Abort on the first feature that cannot be used instead of skipping it with a
    /// counted `skipped-feature` warning (see [`validate::Diagnostics`]).
    pub strict: bool,
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
    #[error("unsupported input format '{0}' (expected .geojson, .json, .city.json, .zip, .osm.pbf, .obj, .gltf, .glb, .bsp)")]
    Unsupported(String),
}

fn read(path: &Path) -> Result<Vec<u8>, ImportError> {
    std::fs::read(path).map_err(|source| ImportError::Io {
        path: path.display().to_string(),
        source,
    })
}

/// Load a scene from a file, choosing the importer by extension.
pub fn load(path: &Path, opts: &ImportOptions) -> Result<Scene, ImportError> {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let ext = name.rsplit('.').next().unwrap_or("");
    match ext {
        "geojson" => geojson::parse(&read(path)?, opts),
        "json" => {
            let root: serde_json::Value = serde_json::from_slice(&read(path)?)
                .map_err(|e| ImportError::Format(format!("invalid JSON: {e}")))?;
            if root.get("type").and_then(serde_json::Value::as_str) == Some("CityJSON") {
                cityjson::from_value(&root, opts)
            } else if tileset::is_tileset(&root) {
                tileset::from_value(&root, path)
            } else {
                geojson::from_value(&root, opts)
            }
        }
        "zip" => cityjson::parse_zip(&read(path)?, opts),
        "obj" => obj::parse(&read(path)?, opts),
        "pbf" => osm::parse(&read(path)?, opts),
        "gltf" | "glb" => gltf::parse(&read(path)?, path.parent(), opts),
        "bsp" => bsp::parse(&read(path)?),
        _ => Err(ImportError::Unsupported(path.display().to_string())),
    }
}
