//! Hierarchical max-depth pyramid (hierarchical z-buffer, Greene et al. 1993; survey
//! §6.1): level 0 is the depth buffer, each texel of level `l+1` holds the maximum of its
//! (up to) four children. A screen rectangle is occluded at depth `z` when every pixel
//! of it holds a depth `< z`; one texel of a coarse level whose maximum is `< z` proves
//! it for all its pixels at once.

use crate::coverage::{self, floor_i, for_row_depths, Depth, Prepared};
use crate::view::{fan, ScreenVertex, View};
use crate::MAX_INPUT_VERTS;
use glam::DVec3;

#[derive(Clone, Debug)]
struct Level {
    width: u32,
    height: u32,
    max: Vec<f32>,
}

/// A max-depth pyramid built from a depth buffer (a snapshot: rebuild after drawing;
/// [`crate::Framebuffer::pyramid`]).
#[derive(Clone, Debug)]
pub struct DepthPyramid {
    levels: Vec<Level>,
}

impl DepthPyramid {
    /// Build the pyramid of a `width × height` depth buffer (row-major).
    pub fn from_depth(width: u32, height: u32, depth: &[f32]) -> Self {
        let mut levels = vec![Level {
            width,
            height,
            max: depth.to_vec(),
        }];
        while {
            let l = levels.last().map(|l| (l.width, l.height)).unwrap_or((1, 1));
            l.0 > 1 || l.1 > 1
        } {
            let prev = &levels[levels.len() - 1];
            let (w, h) = (prev.width.div_ceil(2), prev.height.div_ceil(2));
            let mut max = vec![f32::NEG_INFINITY; w as usize * h as usize];
            for y in 0..prev.height {
                let row = &prev.max[(y * prev.width) as usize..((y + 1) * prev.width) as usize];
                let out = &mut max[((y / 2) * w) as usize..((y / 2 + 1) * w) as usize];
                for (x, v) in row.iter().enumerate() {
                    let o = &mut out[x / 2];
                    if *v > *o {
                        *o = *v;
                    }
                }
            }
            levels.push(Level {
                width: w,
                height: h,
                max,
            });
        }
        DepthPyramid { levels }
    }

    /// Width and height of level 0.
    pub fn size(&self) -> (u32, u32) {
        (self.levels[0].width, self.levels[0].height)
    }

    /// Depth of level 0 at pixel `(i, j)`.
    pub fn depth_at(&self, i: u32, j: u32) -> f32 {
        let l = &self.levels[0];
        l.max[(j * l.width + i) as usize]
    }

    /// Whether every pixel of the rectangle `[x0, x1] × [y0, y1]` (inclusive, clamped
    /// to the screen) holds a depth strictly less than `depth` (ties count as visible).
    pub fn rect_occluded(&self, x0: u32, y0: u32, x1: u32, y1: u32, depth: f32) -> bool {
        let (w, h) = self.size();
        let x1 = x1.min(w - 1);
        let y1 = y1.min(h - 1);
        if x0 > x1 || y0 > y1 {
            return true;
        }
        let span = (x1 - x0).max(y1 - y0) + 1;
        let mut level = 0usize;
        while level + 1 < self.levels.len() && (span >> (level + 1)) >= 1 {
            level += 1;
        }
        level = level.saturating_sub(1);
        for ty in (y0 >> level)..=(y1 >> level) {
            for tx in (x0 >> level)..=(x1 >> level) {
                if !self.texel_occluded(level, tx, ty, [x0, y0, x1, y1], depth) {
                    return false;
                }
            }
        }
        true
    }

    fn texel_occluded(&self, level: usize, tx: u32, ty: u32, r: [u32; 4], depth: f32) -> bool {
        let l = &self.levels[level];
        if l.max[(ty * l.width + tx) as usize] < depth {
            return true;
        }
        if level == 0 {
            return false;
        }
        let c = &self.levels[level - 1];
        let s = level - 1;
        for cy in (2 * ty)..(2 * ty + 2).min(c.height) {
            for cx in (2 * tx)..(2 * tx + 2).min(c.width) {
                // Child texel's pixel extent must meet the rectangle.
                let (px0, py0) = (cx << s, cy << s);
                let (px1, py1) = (((cx + 1) << s) - 1, ((cy + 1) << s) - 1);
                if px1 < r[0] || px0 > r[2] || py1 < r[1] || py0 > r[3] {
                    continue;
                }
                if !self.texel_occluded(s, cx, cy, r, depth) {
                    return false;
                }
            }
        }
        true
    }

    /// Whether a convex world polygon (e.g. a triangle of an occludee), drawn with the
    /// outer rule at its nearest depth, is hidden in `view` (see
    /// [`crate::framebuffer::Framebuffer::polygon_occluded`] for the exact semantics).
    pub fn polygon_occluded(&self, view: &View, poly: &[DVec3]) -> bool {
        let (w, h) = self.size();
        occluded_test(view, poly, w, h, &self.levels[0].max, Some(self))
    }

    /// Whether a world triangle is hidden in `view`.
    pub fn triangle_occluded(&self, view: &View, tri: &[DVec3; 3]) -> bool {
        self.polygon_occluded(view, tri)
    }

    /// Screen-space version of [`DepthPyramid::polygon_occluded`].
    pub fn screen_polygon_occluded(&self, poly: &[ScreenVertex]) -> bool {
        let (w, h) = self.size();
        screen_occluded(poly, w, h, &self.levels[0].max, Some(self))
    }
}

/// Shared occlusion test: outer coverage, nearest depth, strict comparison.
pub(crate) fn occluded_test(
    view: &View,
    poly: &[DVec3],
    width: u32,
    height: u32,
    depth: &[f32],
    pyramid: Option<&DepthPyramid>,
) -> bool {
    if poly.len() > MAX_INPUT_VERTS {
        return fan(poly)
            .iter()
            .all(|c| occluded_test(view, c, width, height, depth, pyramid));
    }
    if poly.iter().any(|p| view.to_camera(*p).z < view.near) {
        return false;
    }
    let mut sv = Vec::with_capacity(MAX_INPUT_VERTS);
    if view.clip_project(poly, &mut sv) < 3 {
        return false;
    }
    screen_occluded(&sv, width, height, depth, pyramid)
}

/// `depth` is the level-0 depth buffer (`width × height`, row-major).
pub(crate) fn screen_occluded(
    sv: &[ScreenVertex],
    width: u32,
    height: u32,
    depth: &[f32],
    pyramid: Option<&DepthPyramid>,
) -> bool {
    let Some(p) = Prepared::new(sv) else {
        return false;
    };
    if p.off_screen(width, height) {
        return true;
    }
    if let Some(pyr) = pyramid {
        let x0 = floor_i(p.xmin - coverage::EPS_PX).max(0) as u32;
        let y0 = floor_i(p.ymin - coverage::EPS_PX).max(0) as u32;
        let x1 = floor_i(p.xmax + coverage::EPS_PX)
            .min(width as i64 - 1)
            .max(0) as u32;
        let y1 = floor_i(p.ymax + coverage::EPS_PX)
            .min(height as i64 - 1)
            .max(0) as u32;
        if pyr.rect_occluded(x0, y0, x1, y1, p.min_depth()) {
            return true;
        }
    }
    let w = width as usize;
    let visible = coverage::outer(&p, width, height, |j, i0, i1| {
        let k0 = j as usize * w + i0 as usize;
        let row = &depth[k0..=k0 + (i1 - i0) as usize];
        let mut seen = false;
        for_row_depths(&p, Depth::Near, j, i0, row.len(), |k, z| {
            seen |= row[k] >= z;
        });
        seen
    });
    !visible
}
