//! `hzb`: a hierarchical depth buffer of the occluders, rasterized at a coarse masked
//! tile resolution (Masked Occlusion Culling, Hasselgren et al. HPG 2016; the
//! hierarchical z-buffer of Greene et al. 1993, survey §6 "HZB").
//!
//! Per frame: the occluder prisms inside the frustum, nearest first (the merge rule of
//! [`MaskedBuffer`] keeps more when near occluders come first), draw their front faces
//! with inner coverage at an upper bound of their depth; then every occludee box is
//! classified against the frustum ([`box_in_view`]: outside → hidden, crossing the near
//! plane → visible) and its outer screen rectangle at a lower bound of its depth is
//! tested against the buffer.
//!
//! Guarantee: an object reported hidden is hidden from the eye within the frustum (each
//! step only over-estimates what is visible; ties are visible). Knobs: the frame size.

use crate::frustum::{box_in_view, clip_project, BoxInView, Frustum};
use crate::masked::{MaskedBuffer, RasterPath};
use crate::scene::CullScene;
use crate::{Culler, Frame};
use std::sync::Arc;

/// The `hzb` culler.
#[derive(Clone, Debug)]
pub struct Hzb {
    scene: Arc<CullScene>,
}

impl Hzb {
    pub fn new(scene: Arc<CullScene>) -> Hzb {
        Hzb { scene }
    }
}

/// The occluder prisms of `scene` in the frustum (only those of `allowed` objects when
/// given), nearest first: `(prism index, where its box lies)`.
pub fn occluder_order(
    scene: &CullScene,
    frustum: &Frustum,
    allowed: Option<&[bool]>,
) -> Vec<(u32, BoxInView)> {
    let view = frustum.view();
    let mut order: Vec<(f64, u32, BoxInView)> = Vec::new();
    for (k, o) in scene.occluders.iter().enumerate() {
        if allowed.is_some_and(|a| !a[o.object as usize]) {
            continue;
        }
        let b = box_in_view(view, o.lo, o.hi);
        if b == BoxInView::Outside {
            continue;
        }
        let d = frustum.eye.clamp(o.lo, o.hi).distance_squared(frustum.eye);
        order.push((d, k as u32, b));
    }
    order.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    order.into_iter().map(|(_, k, b)| (k, b)).collect()
}

/// Draw the front faces of the prisms of `order` into `buf`; returns the triangles
/// drawn. With `skip_hidden`, a prism whose box the buffer already hides is not drawn.
pub fn draw_ordered(
    buf: &mut MaskedBuffer,
    scene: &CullScene,
    frustum: &Frustum,
    order: &[(u32, BoxInView)],
    skip_hidden: bool,
) -> u64 {
    let view = frustum.view();
    let mut tris = 0u64;
    let mut scratch = Vec::with_capacity(16);
    for &(k, b) in order {
        // An occluder already hidden hides nothing that is not hidden already: drawn
        // nearest first, most of a street's far prisms are skipped here.
        if let Some(([i0, j0, i1, j1], z_near)) = b.rect() {
            if skip_hidden && buf.rect_occluded(i0, j0, i1, j1, z_near) {
                continue;
            }
        }
        for (f, verts) in scene.front_faces(&scene.occluders[k as usize], frustum.eye) {
            tris += f.tris as u64;
            if clip_project(view, verts, &mut scratch) {
                buf.draw_polygon(&scratch);
            }
        }
    }
    tris
}

/// Draw the occluders of `scene` (only those of `allowed` objects when given) into a
/// masked buffer for `frustum`, nearest first (the merge rule of [`MaskedBuffer`] keeps
/// more when near occluders come first); returns the buffer and the triangles drawn.
/// With `skip_hidden`, a prism whose box the buffer already hides is not drawn. `path`
/// picks the rasterizer's scalar or SIMD code (same buffer either way).
pub fn draw_occluders(
    scene: &CullScene,
    frustum: &Frustum,
    allowed: Option<&[bool]>,
    skip_hidden: bool,
    path: RasterPath,
) -> (MaskedBuffer, u64) {
    let view = frustum.view();
    let mut buf = MaskedBuffer::with_path(view.width_px, view.height_px, path);
    let order = occluder_order(scene, frustum, allowed);
    let tris = draw_ordered(&mut buf, scene, frustum, &order, skip_hidden);
    (buf, tris)
}

impl Culler for Hzb {
    fn name(&self) -> &'static str {
        "hzb"
    }

    fn paper(&self) -> &'static str {
        "Hasselgren et al. 2016 (Masked Occlusion Culling); Greene et al. 1993 (HZB), survey §6"
    }

    fn cull(&self, frustum: &Frustum, candidates: Option<&[u32]>) -> Frame {
        let allowed = candidates.map(|c| crate::mask_of(c, self.scene.objects()));
        let (mut buf, tris) = draw_occluders(
            &self.scene,
            frustum,
            allowed.as_deref(),
            true,
            RasterPath::DEFAULT,
        );
        buf.build_hierarchy();
        let mut frame = Frame::new(self.scene.objects(), candidates);
        frame.occluder_tris = tris;
        crate::for_candidates(self.scene.objects(), candidates, |id| {
            frame.test_box(
                frustum.view(),
                id,
                self.scene.boxes[id as usize],
                |[i0, j0, i1, j1], z| buf.rect_occluded(i0, j0, i1, j1, z),
            );
        });
        frame.finish();
        frame
    }
}
