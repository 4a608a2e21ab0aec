//! From-point occlusion culling: an object reported hidden is hidden from that point
//! (conservative; ties count as visible).
//!
//! Given an eye, a view [`Frustum`], the scene's occluders (the faces of the objects'
//! inner prisms) and occludees (the objects' outer boxes), a [`Culler`] answers which
//! objects may be visible in that frame. Methods, each in its own module citing its
//! paper:
//!
//! * [`hzb`]: a masked, tiled hierarchical depth buffer (Masked Occlusion Culling,
//!   Hasselgren et al. 2016; HZB, Greene et al. 1993);
//! * [`hom`]: hierarchical occlusion maps (Zhang et al. 1997), conservative with
//!   opacity threshold 1.0; `hom-approx` (threshold below 1) is not conservative;
//! * [`cplp`]: prioritized front-to-back traversal of a grid of cells with solidity
//!   (PLP, Klosowski & Silva 2000), made conservative as cPLP (2001) by testing what the
//!   traversal reaches against the [`hzb`] buffer.
//!
//! [`truth`] is the independent ground truth: a full-resolution item buffer of the
//! objects' real geometry, rendered with pixel-centre sampling.
//!
//! ```
//! use sightline_culling::{method, CullScene, Frustum};
//! use sightline_scene::{Object, Scene};
//! use glam::DVec3;
//! use std::sync::Arc;
//! // A wall 3 m high, 10 m ahead, hides a low block behind it, not a tower.
//! let scene = Scene::from_objects(vec![
//!     Object::rect_block(-20.0, 10.0, 20.0, 11.0, 3.0),
//!     Object::rect_block(-2.0, 20.0, 2.0, 24.0, 3.0),
//!     Object::rect_block(-2.0, 30.0, 2.0, 34.0, 60.0),
//! ]);
//! let culler = method("hzb", Arc::new(CullScene::new(&scene))).unwrap();
//! let f = Frustum::new(DVec3::new(0.0, 0.0, 1.7), DVec3::Y, 60.0, 320, 180).unwrap();
//! assert_eq!(culler.cull(&f, None).visible, vec![0, 2]);
//! ```

// `!(a < b)` is the NaN-safe way to reject bad values in geometric code: keep it.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod cplp;
pub mod frustum;
pub mod hom;
pub mod hzb;
pub mod masked;
pub mod masked_simd;
pub mod measure;
pub mod scene;
pub mod truth;
pub mod walk;

pub use frustum::{box_in_view, BoxInView, Frustum};
pub use scene::CullScene;
use serde::Serialize;
use std::sync::Arc;

/// Names of the cullers, as selected by `--method`.
pub const CULLER_NAMES: &[&str] = &["hzb", "hom", "hom-approx", "cplp"];

/// Why a frame could not be culled.
#[derive(Debug, thiserror::Error)]
pub enum CullError {
    #[error("bad frustum: {0}")]
    BadFrustum(String),
    #[error("unknown culling method '{0}' (known: {known})", known = CULLER_NAMES.join(", "))]
    UnknownMethod(String),
}

/// The answer for one frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Frame {
    /// Ids that may be visible, sorted ascending.
    pub visible: Vec<u32>,
    /// Objects considered (all, or the candidates given, e.g. a cell's PVS).
    pub candidates: usize,
    /// Candidates outside the frustum.
    pub frustum_culled: usize,
    /// Candidates in the frustum found hidden behind occluders.
    pub occlusion_culled: usize,
    /// Occluder triangles rasterized (a wall quad counts 2).
    pub occluder_tris: u64,
}

impl Frame {
    /// An empty answer over `candidates` (ids out of `0..objects` are ignored).
    fn new(objects: usize, candidates: Option<&[u32]>) -> Frame {
        let candidates = candidates.map_or(objects, |c| {
            c.iter().filter(|&&i| (i as usize) < objects).count()
        });
        Frame {
            candidates,
            ..Frame::default()
        }
    }

    fn finish(&mut self) {
        self.visible.sort_unstable();
        self.visible.dedup();
    }

    /// Record occludee `id` (its box `[lo, hi]`) as culled by the frustum, visible
    /// (crossing the near plane), or, on screen, as `hidden(rect, z_near)` decides from
    /// its outer screen rectangle `[i0, j0, i1, j1]` and the lower bound of its depth.
    fn test_box(
        &mut self,
        view: &sightline_raster::View,
        id: u32,
        (lo, hi): (glam::DVec3, glam::DVec3),
        hidden: impl FnOnce([u32; 4], f32) -> bool,
    ) {
        let b = frustum::box_in_view(view, lo, hi);
        match b.rect() {
            _ if b == frustum::BoxInView::Outside => self.frustum_culled += 1,
            Some((rect, z_near)) if hidden(rect, z_near) => self.occlusion_culled += 1,
            _ => self.visible.push(id),
        }
    }

    /// Percentage of the candidates culled (frustum and occlusion).
    pub fn culled_pct(&self) -> f64 {
        if self.candidates == 0 {
            return 0.0;
        }
        100.0 * (self.candidates - self.visible.len()) as f64 / self.candidates as f64
    }
}

/// A from-point culler prepared for one scene; any number of frames, from any thread.
pub trait Culler: Send + Sync {
    /// The method's name (`hzb`, `hom`, `hom-approx`, `cplp`).
    fn name(&self) -> &'static str;
    /// The paper(s) it follows.
    fn paper(&self) -> &'static str;
    /// Whether a hidden answer is guaranteed (see the crate doc).
    fn is_conservative(&self) -> bool {
        true
    }
    /// Cull one frame. `candidates` (sorted or not, no duplicates) restricts both the
    /// occludees and the occluders to those objects (e.g. the PVS of the eye's cell:
    /// fewer occluders only make more visible, so the answer stays conservative).
    fn cull(&self, frustum: &Frustum, candidates: Option<&[u32]>) -> Frame;
}

/// The culler named `name` on `scene`.
pub fn method(name: &str, scene: Arc<CullScene>) -> Result<Box<dyn Culler>, CullError> {
    Ok(match name {
        "hzb" => Box::new(hzb::Hzb::new(scene)),
        "hom" => Box::new(hom::Hom::new(scene, hom::HomOptions::default())),
        "hom-approx" => Box::new(hom::Hom::new(scene, hom::HomOptions::approximate())),
        "cplp" => Box::new(cplp::Cplp::new(scene, cplp::CplpOptions::default())),
        other => return Err(CullError::UnknownMethod(other.to_string())),
    })
}

/// `flags[id]` set for the ids of `ids` (ids out of range are ignored).
pub(crate) fn mask_of(ids: &[u32], n: usize) -> Vec<bool> {
    let mut m = vec![false; n];
    for &i in ids {
        if let Some(b) = m.get_mut(i as usize) {
            *b = true;
        }
    }
    m
}

/// Call `f` for every candidate id in range (all ids when `None`).
pub(crate) fn for_candidates(n: usize, candidates: Option<&[u32]>, mut f: impl FnMut(u32)) {
    match candidates {
        None => (0..n as u32).for_each(f),
        Some(c) => c.iter().filter(|&&i| (i as usize) < n).for_each(|&i| f(i)),
    }
}
