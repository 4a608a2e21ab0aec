//! The independent ground truth of one frame: an item buffer of the objects' *real*
//! geometry (block prisms, flat polygons, mesh triangles) at full resolution, sampled at
//! pixel centres with a depth test ([`sightline_raster::Coverage::Standard`]). Every id
//! it shows is truly visible from the eye within the frustum (`docs/methods/sampled.md`: the
//! sampled set is a lower bound), so a culler that reports one of them hidden is wrong.
//!
//! It shares nothing with the cullers but the frustum: not the inner/outer bounds, not
//! the masked buffer, not the coverage rules.

use crate::frustum::{box_in_view, BoxInView, Frustum};
use glam::DVec3;
use sightline_raster::{prism_faces, Coverage, Framebuffer};
use sightline_scene::{Geometry, Scene};

/// A scene prepared for the ground truth.
#[derive(Clone, Debug)]
pub struct FrameTruth {
    /// Faces of each object.
    faces: Vec<Vec<Vec<DVec3>>>,
    boxes: Vec<(DVec3, DVec3)>,
}

impl FrameTruth {
    pub fn new(scene: &Scene) -> FrameTruth {
        let mut faces = Vec::with_capacity(scene.objects.len());
        for o in &scene.objects {
            let mut f: Vec<Vec<DVec3>> = Vec::new();
            match &o.geometry {
                Geometry::Blocks(prisms) => {
                    for p in prisms.iter().filter(|p| p.top > p.base) {
                        f.extend(prism_faces(&p.footprint, p.base, p.top));
                    }
                }
                Geometry::Flat(polys) => {
                    for p in polys {
                        f.extend(p.triangulate_at(0.0).iter().map(|t| t.to_vec()));
                    }
                }
                Geometry::Mesh(m) => {
                    f.extend(m.triangles.iter().map(|t| m.triangle(t).to_vec()));
                }
            }
            faces.push(f);
        }
        let boxes = scene
            .objects
            .iter()
            .map(|o| (o.bounds.min, o.bounds.max))
            .collect();
        FrameTruth { faces, boxes }
    }

    /// The ids seen in the frame's item buffer, sorted.
    pub fn visible(&self, frustum: &Frustum) -> Vec<u32> {
        let view = frustum.view();
        let mut fb = Framebuffer::for_view(view);
        for (id, faces) in self.faces.iter().enumerate() {
            let (lo, hi) = self.boxes[id];
            if box_in_view(view, lo, hi) == BoxInView::Outside {
                continue;
            }
            for f in faces {
                fb.draw_polygon(view, f, id as u32, Coverage::Standard);
            }
        }
        fb.ids_seen()
    }
}
