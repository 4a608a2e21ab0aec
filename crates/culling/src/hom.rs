//! `hom` and `hom-approx`: hierarchical occlusion maps (Zhang, Manocha, Hudson, Hoff,
//! SIGGRAPH 1997; survey §6 and slides "HOM").
//!
//! Occlusion is split into two tests (§3 of the paper):
//!
//! * **overlap**: the occluders are rendered into an *opacity* image at a low resolution
//!   ([`HomOptions::width_px`]); averaging 2 × 2 texels builds the *hierarchical
//!   occlusion map*. An occludee's outer screen rectangle is tested from the level where
//!   it spans about two texels: a texel at least as opaque as the threshold is accepted,
//!   a less opaque one is refined into its children, a finest pixel below it fails.
//! * **depth estimation**: the paper's depth estimation buffer (DEB) keeps, per coarse
//!   block, the *farthest* depth of the occluders projecting there. An occludee that is
//!   itself an occluder (every building of a city) then always has its own far faces in
//!   the DEB and is never culled. Here the depth is estimated by *slices* instead: one
//!   occlusion map per far bound `d_k` ([`slice_far_m`]: 4 m × 1.25^k, built on first
//!   use) holds only the pixels covered
//!   by occluders nearer than `d_k`, and an occludee whose nearest depth is at least
//!   `d_k` is tested in map `k`. Occluder selection: those within
//!   [`HomOptions::occluder_range_m`] of the eye (§5 of the paper selects nearby large
//!   occluders).
//!
//! Conservative mode (`hom`, the default): opacity is drawn with inner coverage of the
//! *union* of each prism's front faces (a pixel is opaque only if the prism covers it
//! entirely; [`sightline_raster::Framebuffer::draw_screen_union`], whose per-pixel depth
//! is an upper bound of the union's), and the threshold is 1.0 (exact counts, no float
//! averaging), so an accepted rectangle is covered pixel by pixel by occluders strictly
//! nearer than the occludee. Hidden is hidden.
//!
//! `hom-approx` uses the paper's approximate culling (threshold below 1, e.g. 0.9): it
//! may cull objects seen through small holes; [`Culler::is_conservative`] is false.

use crate::frustum::{box_in_view, clip_project, BoxInView, Frustum};
use crate::scene::CullScene;
use crate::{Culler, Frame};
use sightline_raster::{Framebuffer, ScreenVertex};
use std::sync::Arc;

/// Far bound of the nearest depth slice (metres).
pub const FIRST_SLICE_M: f64 = 4.0;
/// Ratio of consecutive depth slices' far bounds.
pub const SLICE_RATIO: f64 = 1.25;
/// Number of depth slices (the last reaches past 3 km).
pub const SLICES: usize = 30;

/// Far bound of depth slice `k` (metres): slice `k` holds the occluders nearer than it.
pub fn slice_far_m(k: usize) -> f64 {
    FIRST_SLICE_M * SLICE_RATIO.powi(k as i32)
}

/// Knobs of the HOM culler.
#[derive(Clone, Debug, PartialEq)]
pub struct HomOptions {
    /// Width of the finest occlusion map (pixels); its height keeps the frame's aspect.
    pub width_px: u32,
    /// Opacity threshold: 1.0 is conservative, below is the approximate mode.
    pub opacity_threshold: f64,
    /// Only occluders within this distance of the eye are drawn (metres).
    pub occluder_range_m: f64,
}

impl Default for HomOptions {
    fn default() -> Self {
        HomOptions {
            width_px: 256,
            opacity_threshold: 1.0,
            occluder_range_m: 250.0,
        }
    }
}

impl HomOptions {
    /// The approximate mode of the paper (threshold 0.9).
    pub fn approximate() -> Self {
        HomOptions {
            opacity_threshold: 0.9,
            ..HomOptions::default()
        }
    }
}

/// The `hom` / `hom-approx` culler.
#[derive(Clone, Debug)]
pub struct Hom {
    scene: Arc<CullScene>,
    opts: HomOptions,
}

impl Hom {
    pub fn new(scene: Arc<CullScene>, opts: HomOptions) -> Hom {
        Hom { scene, opts }
    }
}

/// The opacity pyramid: per level `(cols, rows, opaque pixel count, on-screen pixels)`.
struct Pyramid {
    levels: Vec<(u32, u32, Vec<u32>, Vec<u32>)>,
}

impl Pyramid {
    fn new(w: u32, h: u32, opaque: impl Fn(u32, u32) -> bool) -> Pyramid {
        let mut count = Vec::with_capacity((w * h) as usize);
        for j in 0..h {
            for i in 0..w {
                count.push(opaque(i, j) as u32);
            }
        }
        // Exact counts of opaque and on-screen pixels per block, by the raster crate's
        // one pyramid reduction (pixels past the edges count 0 in both).
        let n = count.len();
        let sums = |base: Vec<u32>| {
            sightline_raster::Pyramid::<u32, sightline_raster::Sum>::new(
                w as usize,
                h as usize,
                base,
                0,
                usize::MAX,
            )
            .into_levels()
        };
        let levels = sums(count)
            .into_iter()
            .zip(sums(vec![1; n]))
            .map(|(c, a)| (c.width as u32, c.height as u32, c.data, a.data))
            .collect();
        Pyramid { levels }
    }

    /// Whether the texel `(x, y)` of level `l`, restricted to the pixel rectangle, is
    /// opaque enough.
    fn opaque(&self, l: usize, x: u32, y: u32, rect: [u32; 4], threshold: f64) -> bool {
        let (c, _, ref cnt, ref area) = self.levels[l];
        let k = (y * c + x) as usize;
        let full = if threshold >= 1.0 {
            cnt[k] == area[k]
        } else {
            cnt[k] as f64 >= threshold * area[k] as f64
        };
        if full {
            return true;
        }
        if l == 0 {
            return false;
        }
        let (cc, cr, _, _) = self.levels[l - 1];
        let [i0, j0, i1, j1] = rect;
        let s = l - 1;
        for cy in 2 * y..(2 * y + 2).min(cr) {
            for cx in 2 * x..(2 * x + 2).min(cc) {
                // Children outside the rectangle do not matter.
                if ((cx + 1) << s) <= i0
                    || (cx << s) > i1
                    || ((cy + 1) << s) <= j0
                    || (cy << s) > j1
                {
                    continue;
                }
                if !self.opaque(s, cx, cy, rect, threshold) {
                    return false;
                }
            }
        }
        true
    }

    fn rect_opaque(&self, rect: [u32; 4], threshold: f64) -> bool {
        let [i0, j0, i1, j1] = rect;
        let mut l = 0;
        while l + 1 < self.levels.len() && ((i1 >> l) - (i0 >> l) > 1 || (j1 >> l) - (j0 >> l) > 1)
        {
            l += 1;
        }
        for y in j0 >> l..=j1 >> l {
            for x in i0 >> l..=i1 >> l {
                if !self.opaque(l, x, y, rect, threshold) {
                    return false;
                }
            }
        }
        true
    }
}

impl Culler for Hom {
    fn name(&self) -> &'static str {
        if self.opts.opacity_threshold >= 1.0 {
            "hom"
        } else {
            "hom-approx"
        }
    }

    fn paper(&self) -> &'static str {
        "Zhang et al. 1997 (Visibility culling using hierarchical occlusion maps), survey §6"
    }

    fn is_conservative(&self) -> bool {
        self.opts.opacity_threshold >= 1.0
    }

    fn cull(&self, frustum: &Frustum, candidates: Option<&[u32]>) -> Frame {
        let fw = frustum.width_px as f64;
        let w = self.opts.width_px.clamp(1, frustum.width_px);
        let h = ((w as f64 * frustum.height_px as f64 / fw).round() as u32).max(1);
        let view = frustum.view_at(w, h);
        let allowed = candidates.map(|c| crate::mask_of(c, self.scene.objects()));
        let mut fb = Framebuffer::new(w, h);
        let mut frame = Frame::new(self.scene.objects(), candidates);
        let mut pieces: Vec<Vec<ScreenVertex>> = Vec::new();
        let mut scratch = Vec::with_capacity(16);
        let range2 = self.opts.occluder_range_m * self.opts.occluder_range_m;
        for o in &self.scene.occluders {
            if allowed.as_ref().is_some_and(|a| !a[o.object as usize]) {
                continue;
            }
            // Occluder selection by distance (Zhang et al. §5: nearby large occluders).
            if frustum.eye.clamp(o.lo, o.hi).distance_squared(frustum.eye) > range2 {
                continue;
            }
            if box_in_view(&view, o.lo, o.hi) == BoxInView::Outside {
                continue;
            }
            pieces.clear();
            for (f, verts) in self.scene.front_faces(o, frustum.eye) {
                frame.occluder_tris += f.tris as u64;
                if clip_project(&view, verts, &mut scratch) {
                    pieces.push(scratch.clone());
                }
            }
            let refs: Vec<&[ScreenVertex]> = pieces.iter().map(|p| p.as_slice()).collect();
            fb.draw_screen_union(&refs, o.object);
        }
        // One occlusion map per depth slice: pixel opaque in slice k when covered by
        // occluders all nearer than slice_far_m(k) (the pixel's inner-union depth is
        // an upper bound of them).
        // Built on first use: an occludee needs only the slice just in front of it.
        let mut pyramids: Vec<Option<Pyramid>> = (0..SLICES).map(|_| None).collect();
        crate::for_candidates(self.scene.objects(), candidates, |id| {
            frame.test_box(&view, id, self.scene.boxes[id as usize], |rect, z_near| {
                // The farthest slice entirely in front of the occludee.
                let k = (0..SLICES).rev().find(|&k| slice_far_m(k) <= z_near as f64);
                k.is_some_and(|k| {
                    let d = slice_far_m(k);
                    pyramids[k]
                        .get_or_insert_with(|| {
                            Pyramid::new(w, h, |i, j| (fb.depth_at(i, j) as f64) < d)
                        })
                        .rect_opaque(rect, self.opts.opacity_threshold)
                })
            });
        });
        frame.finish();
        frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pyramid_accepts_a_fully_opaque_rectangle_only() {
        let p = Pyramid::new(20, 10, |i, _| i < 12);
        assert!(p.rect_opaque([0, 0, 11, 9], 1.0));
        assert!(p.rect_opaque([3, 2, 7, 5], 1.0));
        assert!(!p.rect_opaque([3, 2, 12, 5], 1.0));
        assert!(!p.rect_opaque([12, 0, 19, 9], 1.0));
    }
}
