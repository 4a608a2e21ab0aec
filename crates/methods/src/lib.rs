//! Visibility methods of sightline, each in its own module behind one trait.
//!
//! A method ([`Method`], or its name) is *prepared* once for a scene ([`create`]) — it builds whatever
//! per-scene structures it needs (fused occluders, kd-trees, caches) — and then
//! answers [`VisibilityMethod::pvs`] for any number of viewcells, from any thread.
//!
//! The guarantee of every conservative method: it may report a hidden object as
//! visible, never a visible object as hidden.
//!
//! Architecture (imports go one way, from the methods down to the shared leaves):
//! * [`erosion`] — Décoret, Debunne & Sillion 2003: `erosion`, `erosion-segment`,
//!   `erosion-cell`, `shrink-sphere` (after Wonka et al. 2000) and `erosion-rays` (§7.1);
//! * [`dual_ray`] — Koltun, Chrysanthou & Cohen-Or 2001: `dual-ray` (§5.2) and
//!   `dual-ray-exact` (§5.1), with the opt-in virtual occluders of Koltun et al. 2000;
//! * [`ext_proj`] — Durand et al. 2000: `ext-proj`, extended projections and the sweep;
//! * `sampled` — the ground truth of [`check`] as a method (not conservative); the `all`
//!   baseline lives in this file;
//! * shared leaves: `occluders` (the one occluder model of every method: the inner
//!   prisms, those standing on the ground, and a bucket grid; `dual-ray` fuses them into
//!   slabs, erosion into a raster, `ext-proj` by levels into convex pieces), `seed`
//!   (seed rays of `dual-ray` and erosion, on `occluders`), `kdtree` (the occludee
//!   hierarchy of `dual-ray` and `ext-proj`) and [`check`] (ground truth and
//!   comparison, apart from `occluders` on purpose).
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
mod kdtree;
mod occluders;
mod sampled;
mod seed;

use serde::{Deserialize, Serialize};
use sightline_geom::ViewCell;
use sightline_scene::Scene;
use std::sync::Arc;

/// The methods, selected by name everywhere (`--method`, the library, the server, the
/// `.pvs` header).
///
/// ```
/// use sightline_methods::Method;
/// let m: Method = "dual-ray".parse().unwrap();
/// assert_eq!(m, Method::DualRay);
/// assert_eq!(m.name(), "dual-ray");
/// assert!(!Method::Sampled.is_conservative());
/// assert!("dual_ray".parse::<Method>().unwrap_err().to_string().contains("known: erosion"));
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Erosion of the fused occluders by the shaft-supporting segment, occludees shrunk
    /// (Décoret et al. 2003, method 4).
    Erosion,
    /// Occluders eroded by the supporting segments, occludees as they are (method 3).
    ErosionSegment,
    /// Occluders eroded by the whole cell (method 2).
    ErosionCell,
    /// Occluders shrunk by the cell's bounding disc (Wonka et al. 2000; method 1).
    ShrinkSphere,
    /// `erosion` with X-sampling of the cell (erosion paper §7.1).
    ErosionRays,
    /// Hierarchical cell-to-cell tests in a discretized dual ray space (Koltun et al. 2001).
    DualRay,
    /// The exact analytic planar algorithm of the same paper (§5.1).
    DualRayExact,
    /// Extended projections with extended depth maps (Durand et al. 2000).
    ExtProj,
    /// The sampled visible set: aggressive, NOT conservative (the ground truth).
    Sampled,
    /// Every object: the no-culling baseline.
    All,
}

impl Method {
    /// Every method, in the order of the README's method table.
    pub const ALL: [Method; 10] = [
        Method::Erosion,
        Method::ErosionSegment,
        Method::ErosionCell,
        Method::ShrinkSphere,
        Method::ErosionRays,
        Method::DualRay,
        Method::DualRayExact,
        Method::ExtProj,
        Method::Sampled,
        Method::All,
    ];

    /// The name the method is selected by.
    pub const fn name(self) -> &'static str {
        match self {
            Method::Erosion => "erosion",
            Method::ErosionSegment => "erosion-segment",
            Method::ErosionCell => "erosion-cell",
            Method::ShrinkSphere => "shrink-sphere",
            Method::ErosionRays => "erosion-rays",
            Method::DualRay => "dual-ray",
            Method::DualRayExact => "dual-ray-exact",
            Method::ExtProj => "ext-proj",
            Method::Sampled => "sampled",
            Method::All => "all",
        }
    }

    /// Whether the method's PVS always contains every visible object (`all` trivially
    /// does; `sampled` does not).
    pub const fn is_conservative(self) -> bool {
        !matches!(self, Method::Sampled)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for Method {
    type Err = MethodError;
    fn from_str(s: &str) -> Result<Self, MethodError> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| MethodError::Unknown(s.to_string()))
    }
}

/// Every method name, in the order of [`Method::ALL`].
pub const METHOD_NAMES: &[&str] = &NAMES;

const NAMES: [&str; 10] = {
    let mut names = [""; 10];
    let mut i = 0;
    while i < 10 {
        names[i] = Method::ALL[i].name();
        i += 1;
    }
    names
};

/// What [`create`] accepts: a [`Method`], or its name.
pub trait IntoMethod {
    fn into_method(self) -> Result<Method, MethodError>;
}

impl IntoMethod for Method {
    fn into_method(self) -> Result<Method, MethodError> {
        Ok(self)
    }
}

impl<T: AsRef<str> + ?Sized> IntoMethod for &T {
    fn into_method(self) -> Result<Method, MethodError> {
        self.as_ref().parse()
    }
}

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

/// Prepare `method` (a [`Method`] or its name) for `scene`.
pub fn create(
    method: impl IntoMethod,
    scene: Arc<Scene>,
    opts: &MethodOptions,
) -> Result<Box<dyn VisibilityMethod>, MethodError> {
    let m = method.into_method()?;
    let name = m.name();
    match m {
        Method::Erosion
        | Method::ErosionSegment
        | Method::ErosionCell
        | Method::ShrinkSphere
        | Method::ErosionRays => erosion::create(name, scene, opts),
        Method::DualRay | Method::DualRayExact => dual_ray::create(name, scene, opts),
        Method::ExtProj => ext_proj::create(name, scene, opts),
        Method::Sampled => sampled::create(name, scene, opts),
        Method::All => Ok(Box::new(All { scene })),
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
