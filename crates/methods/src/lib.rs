//! Visibility methods of sightline, each in its own module behind one trait.
//!
//! A method is *prepared* once for a scene ([`create`]) — it builds whatever
//! per-scene structures it needs (fused occluders, kd-trees, caches) — and then
//! answers [`VisibilityMethod::pvs`] for any number of viewcells, from any thread.
//!
//! The guarantee of every conservative method: it may report a hidden object as
//! visible, never a visible object as hidden.
//!
//! ```
//! use std::sync::Arc;
//! use sightline_methods::{create, MethodOptions};
//! use sightline_scene::{Scene, Object};
//! use sightline_geom::{Polygon, DVec2, ViewCell};
//! let scene = Arc::new(Scene::from_objects(vec![Object::block(
//!     None, Polygon::rect(DVec2::new(20.0, 0.0), DVec2::new(30.0, 10.0)), 0.0, 10.0)]));
//! let all = create("all", scene, &MethodOptions::default()).unwrap();
//! let cell: ViewCell = "0,0,1.5,10,10,2".parse().unwrap();
//! assert_eq!(all.pvs(&cell).unwrap(), vec![0]);
//! ```

// `!(a < b)` is the NaN-safe way to reject bad values in geometric code: keep it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod check;
pub mod dual_ray;
pub mod erosion;
pub mod ext_proj;
pub(crate) mod kdtree;
pub mod sampled;
pub(crate) mod seed;

use serde::{Deserialize, Serialize};
use sightline_geom::ViewCell;
use sightline_scene::Scene;
use std::sync::Arc;

/// Every method name, in the order of the README's method table.
pub const METHOD_NAMES: &[&str] = &[
    "erosion",
    "erosion-segment",
    "erosion-cell",
    "shrink-sphere",
    "erosion-rays",
    "dual-ray",
    "dual-ray-exact",
    "ext-proj",
    "sampled",
    "all",
];

/// Parameters shared by the methods; each reads the ones it understands and records
/// them in [`VisibilityMethod::params`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MethodOptions {
    /// Occlusion-map / ray-space / sampling resolution in pixels (method default if None).
    pub resolution_px: Option<u32>,
    /// `ext-proj`: run the occlusion sweep.
    pub sweep: bool,
    /// `ext-proj --sweep`: number of sweep planes.
    pub planes: Option<u32>,
    /// `sampled`: number of viewpoints per cell.
    pub samples: Option<u32>,
}

/// Why a method could not answer.
#[derive(Debug, thiserror::Error)]
pub enum MethodError {
    #[error("unknown method '{0}' (known: {known})", known = METHOD_NAMES.join(", "))]
    Unknown(String),
    #[error("method '{0}' is not implemented yet")]
    NotImplemented(String),
    #[error("invalid viewcell: {0}")]
    BadCell(String),
    #[error("{0}")]
    Other(String),
}

/// A visibility method prepared for one scene.
pub trait VisibilityMethod: Send + Sync {
    /// The method's name, as selected everywhere (`--method`, the library, the server).
    fn name(&self) -> &'static str;

    /// Whether the result is guaranteed to contain every visible object.
    fn is_conservative(&self) -> bool {
        true
    }

    /// Parameters that determine the output, as `key=value` pairs (stored in `.pvs`).
    fn params(&self) -> Vec<(String, String)> {
        Vec::new()
    }

    /// The PVS of `cell`: object ids, sorted ascending, without duplicates.
    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError>;
}

/// Prepare the method called `name` for `scene`.
pub fn create(
    name: &str,
    scene: Arc<Scene>,
    opts: &MethodOptions,
) -> Result<Box<dyn VisibilityMethod>, MethodError> {
    match name {
        "erosion" => erosion::create("erosion", scene, opts),
        "erosion-segment" => erosion::create("erosion-segment", scene, opts),
        "erosion-cell" => erosion::create("erosion-cell", scene, opts),
        "shrink-sphere" => erosion::create("shrink-sphere", scene, opts),
        "erosion-rays" => erosion::create("erosion-rays", scene, opts),
        "dual-ray" => dual_ray::create("dual-ray", scene, opts),
        "dual-ray-exact" => dual_ray::create("dual-ray-exact", scene, opts),
        "ext-proj" => ext_proj::create("ext-proj", scene, opts),
        "sampled" => sampled::create("sampled", scene, opts),
        "all" => Ok(Box::new(All { scene })),
        n => Err(MethodError::Unknown(n.to_string())),
    }
}

/// The no-culling baseline: every object.
struct All {
    scene: Arc<Scene>,
}

impl VisibilityMethod for All {
    fn name(&self) -> &'static str {
        "all"
    }

    fn pvs(&self, _cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        Ok((0..self.scene.objects.len() as u32).collect())
    }
}
