//! Measurements shared by the `frames_bench` example and `sightline bench`: occluder
//! rasterization by the masked tiles (scalar and SIMD paths) and by the full-resolution
//! inner-union rasterizer of `sightline-raster` on the same faces, and what a
//! full-resolution depth buffer of the same occluders culls (the reference of Masked
//! Occlusion Culling's "culled %", Hasselgren et al. 2016, §5).

use crate::frustum::{box_in_view, clip_project, Frustum};
use crate::hzb::{draw_ordered, occluder_order};
use crate::masked::{MaskedBuffer, RasterPath};
use crate::scene::CullScene;
use sightline_raster::{Framebuffer, ScreenVertex};
use std::time::Instant;

/// Occluder triangles drawn and seconds taken.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Throughput {
    pub tris: u64,
    pub seconds: f64,
}

impl Throughput {
    /// Triangles per second (0 when nothing was timed).
    pub fn tris_per_s(&self) -> f64 {
        if self.seconds > 0.0 {
            self.tris as f64 / self.seconds
        } else {
            0.0
        }
    }
}

/// Draw every front face of every occluder in the frustum (no skipping of hidden
/// prisms: the same faces [`full_res`] draws) into the masked buffer by `path`. Timed:
/// projection, near clipping and rasterization of the faces (what Masked Occlusion
/// Culling's triangle rates cover); not the frustum test and ordering of the prisms nor
/// the buffer's allocation, which [`full_res`] does not time either.
pub fn masked_throughput(cs: &CullScene, f: &Frustum, path: RasterPath) -> Throughput {
    let view = f.view();
    let order = occluder_order(cs, f, None);
    let mut buf = MaskedBuffer::with_path(view.width_px, view.height_px, path);
    let t0 = Instant::now();
    let tris = draw_ordered(&mut buf, cs, f, &order, false);
    Throughput {
        tris,
        seconds: t0.elapsed().as_secs_f64(),
    }
}

/// The full-resolution reference: every in-frustum prism's front faces drawn as one
/// inner union into a per-pixel depth buffer (`sightline-raster`), nearest first, timed
/// as [`masked_throughput`] is.
pub fn full_res(cs: &CullScene, f: &Frustum) -> (Framebuffer, Throughput) {
    let view = f.view();
    let mut fb = Framebuffer::for_view(view);
    let order = occluder_order(cs, f, None);
    let t0 = Instant::now();
    let mut tris = 0;
    let mut scratch = Vec::new();
    let mut pieces: Vec<Vec<ScreenVertex>> = Vec::new();
    for &(k, _) in &order {
        let o = &cs.occluders[k as usize];
        pieces.clear();
        for (face, verts) in cs.front_faces(o, f.eye) {
            tris += face.tris as u64;
            if clip_project(view, verts, &mut scratch) {
                pieces.push(scratch.clone());
            }
        }
        let refs: Vec<&[ScreenVertex]> = pieces.iter().map(|p| p.as_slice()).collect();
        fb.draw_screen_union(&refs, o.object);
    }
    let th = Throughput {
        tris,
        seconds: t0.elapsed().as_secs_f64(),
    };
    (fb, th)
}

/// How many occludee boxes the full-resolution depth buffer `fb` of frame `f` hides
/// (outer screen rectangle at the lower bound of the box's depth, as `hzb` tests them).
pub fn full_res_occluded(cs: &CullScene, f: &Frustum, fb: &Framebuffer) -> usize {
    let pyr = fb.pyramid();
    cs.boxes
        .iter()
        .filter(|(lo, hi)| {
            box_in_view(f.view(), *lo, *hi)
                .rect()
                .is_some_and(|([i0, j0, i1, j1], z)| pyr.rect_occluded(i0, j0, i1, j1, z))
        })
        .count()
}
