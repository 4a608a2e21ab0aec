//! The city method families of sightline and the registry's constructor: [`create`]
//! prepares any method of the registry ([`Method`], in `sightline-core`) for a scene.
//!
//! A method is *prepared* once for a scene — it builds whatever per-scene structures it
//! needs (fused occluders, kd-trees, caches) — and then answers
//! [`VisibilityMethod::pvs`] for any number of viewcells, from any thread.
//!
//! The guarantee of every conservative method: it may report a hidden object as
//! visible, never a visible object as hidden.
//!
//! Families here (each module implements the core trait and depends only downwards:
//! on `sightline-core`, `sightline-scene` — whose `occluders` is the one occluder model
//! of every family — `sightline-raster` and `sightline-geom`, whose `kdtree` is the
//! occludee hierarchy of `dual-ray` and `ext-proj`):
//! * [`erosion`] — Décoret, Debunne & Sillion 2003: `erosion`, `erosion-segment`,
//!   `erosion-cell`, `shrink-sphere` (after Wonka et al. 2000) and `erosion-rays` (§7.1);
//! * [`dual_ray`] — Koltun, Chrysanthou & Cohen-Or 2001: `dual-ray` (§5.2) and
//!   `dual-ray-exact` (§5.1), with the opt-in virtual occluders of Koltun et al. 2000;
//! * [`ext_proj`] — Durand et al. 2000: `ext-proj`, extended projections and the sweep;
//! * `sampled` — the ground truth of `sightline_core::check` as a method (not
//!   conservative); the `all` baseline lives in this file;
//! * `seed` — seed rays of `dual-ray` and erosion, on the shared occluder model.
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

pub mod dual_ray;
pub mod erosion;
pub mod ext_proj;
mod sampled;
mod seed;

/// The registry and the trait, re-exported: what a caller of [`create`] needs.
pub use sightline_core::{
    Cell, IntoMethod, Method, MethodError, MethodOptions, Options, VisibilityMethod, METHOD_NAMES,
};

use sightline_core::Family;
use sightline_geom::ViewCell;
use sightline_scene::Scene;
use std::sync::Arc;

/// Prepare `method` (a [`Method`] or its name) for `scene`, with the user settings
/// `opts` validated into the method's typed options by [`Method::options`].
pub fn create(
    method: impl IntoMethod,
    scene: Arc<Scene>,
    opts: &MethodOptions,
) -> Result<Box<dyn VisibilityMethod>, MethodError> {
    let m = method.into_method()?;
    match (m.family(), m.options(opts)?) {
        (Family::Erosion, Options::Erosion(o)) => erosion::create(m, scene, &o),
        (Family::DualRay, Options::DualRay(o)) => dual_ray::create(m, scene, &o),
        (Family::ExtProj, Options::ExtProj(o)) => ext_proj::create(m, scene, &o),
        (Family::Sampled, Options::Sampled(o)) => sampled::create(scene, &o),
        (Family::Baseline, _) => Ok(Box::new(All { scene })),
        (Family::Portals, _) => Err(MethodError::Other(format!(
            "{m} works on the cells of levels (BSP, mesh): open the scene with sightline_world::World, which prepares it"
        ))),
        (Family::Volumetric, _) => Err(MethodError::Other(format!(
            "{m} works on mesh levels: open the scene with sightline_world::World, which builds its walkable viewcells"
        ))),
        (_, o) => Err(MethodError::Other(format!(
            "{m}: options of another family ({o:?})"
        ))),
    }
}

/// The no-culling baseline: every object.
struct All {
    scene: Arc<Scene>,
}

impl VisibilityMethod for All {
    fn name(&self) -> &'static str {
        Method::All.name()
    }

    fn pvs(&self, _cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        Ok((0..self.scene.objects.len() as u32).collect())
    }
}
