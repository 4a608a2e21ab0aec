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
//! * **depth**: the *depth estimation buffer* (DEB), a coarse grid holding for each
//!   block the farthest depth of any occluder face whose screen bounding box meets it.
//!   The occludee must be strictly farther than every DEB block its rectangle meets.
//!
//! Conservative mode (`hom`, the default): opacity is drawn with inner coverage of the
//! *union* of each prism's front faces (a pixel is opaque only if the prism covers it
//! entirely; [`sightline_raster::Framebuffer::draw_screen_union`]), and the threshold is
//! 1.0 (exact counts, no float averaging), so an accepted rectangle is covered pixel by
//! pixel; each covering face meets the pixel's block, so its depth is at most the
//! block's DEB value, which the occludee's nearest depth exceeds. Hidden is hidden.
//!
//! `hom-approx` uses the paper's approximate culling (threshold below 1, e.g. 0.9): it
//! may cull objects seen through small holes; [`Culler::is_conservative`] is false.

use crate::frustum::{box_in_view, clip_project, f32_up, BoxInView, Frustum};
use crate::scene::CullScene;
use crate::{Culler, Frame};
use sightline_raster::{Framebuffer, ScreenVertex};
use std::sync::Arc;

/// DEB block side, in occlusion-map pixels.
const DEB_BLOCK: u32 = 8;

/// Knobs of the HOM culler.
#[derive(Clone, Debug, PartialEq)]
pub struct HomOptions {
    /// Width of the finest occlusion map (pixels); its height keeps the frame's aspect.
    pub width_px: u32,
    /// Opacity threshold: 1.0 is conservative, below is the approximate mode.
    pub opacity_threshold: f64,
}

impl Default for HomOptions {
    fn default() -> Self {
        HomOptions {
            width_px: 256,
            opacity_threshold: 1.0,
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

/// `w(x, y)` of a planar screen polygon (Newell's method in `(x, y, w)`), if it has area.
fn screen_plane(v: &[ScreenVertex]) -> Option<impl Fn(f64, f64) -> f64> {
    let n = v.len();
    let (mut nx, mut ny, mut nw) = (0.0, 0.0, 0.0);
    for k in 0..n {
        let (a, b) = (v[k], v[(k + 1) % n]);
        nx += (a.y - b.y) * (a.w + b.w);
        ny += (a.w - b.w) * (a.x + b.x);
        nw += (a.x - b.x) * (a.y + b.y);
    }
    // Under a pixel of area, no pixel is covered entirely: the plane is not needed.
    if !(nw.abs() >= 2.0) {
        return None;
    }
    let (gx, gy, o) = (-nx / nw, -ny / nw, v[0]);
    Some(move |x: f64, y: f64| o.w + gx * (x - o.x) + gy * (y - o.y))
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
        let mut levels = vec![(w, h, count, vec![1; (w * h) as usize])];
        loop {
            let (c, r, ref cnt, ref area) = *levels.last().expect("level 0");
            if c <= 1 && r <= 1 {
                break;
            }
            let (nc, nr) = (c.div_ceil(2), r.div_ceil(2));
            let mut ncnt = vec![0u32; (nc * nr) as usize];
            let mut narea = vec![0u32; (nc * nr) as usize];
            for y in 0..r {
                for x in 0..c {
                    let k = ((y / 2) * nc + x / 2) as usize;
                    ncnt[k] += cnt[(y * c + x) as usize];
                    narea[k] += area[(y * c + x) as usize];
                }
            }
            levels.push((nc, nr, ncnt, narea));
        }
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
        let (bw, bh) = (w.div_ceil(DEB_BLOCK), h.div_ceil(DEB_BLOCK));
        let mut deb = vec![0f32; (bw * bh) as usize];
        let mut frame = Frame::new(candidates.map_or(self.scene.objects(), |c| c.len()));
        let mut pieces: Vec<Vec<ScreenVertex>> = Vec::new();
        let mut scratch = Vec::with_capacity(16);
        for o in &self.scene.occluders {
            if allowed.as_ref().is_some_and(|a| !a[o.object as usize]) {
                continue;
            }
            if box_in_view(&view, o.lo, o.hi) == BoxInView::Outside {
                continue;
            }
            pieces.clear();
            for f in o.front_faces(frustum.eye) {
                frame.occluder_tris += f.tris as u64;
                if !clip_project(&view, &f.verts, &mut scratch) {
                    continue;
                }
                let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
                let mut wmin = f64::MAX;
                for p in &scratch {
                    x0 = x0.min(p.x);
                    x1 = x1.max(p.x);
                    y0 = y0.min(p.y);
                    y1 = y1.max(p.y);
                    wmin = wmin.min(p.w);
                }
                if x1 < 0.0 || y1 < 0.0 || x0 > w as f64 || y0 > h as f64 {
                    continue;
                }
                // The face's farthest depth within each block it may touch: `w` is
                // affine on screen, so its minimum over the block (clipped to the face's
                // box) is at a corner, and never below the face's smallest vertex `w`
                // (Zhang et al. take the farthest depth of the whole occluder; this is
                // the same bound, per block).
                let plane = screen_plane(&scratch);
                let bx = |x: f64| ((x.max(0.0) as u32).min(w - 1) / DEB_BLOCK).min(bw - 1);
                let by = |y: f64| ((y.max(0.0) as u32).min(h - 1) / DEB_BLOCK).min(bh - 1);
                for yb in by(y0)..=by(y1) {
                    for xb in bx(x0)..=bx(x1) {
                        let wb = match plane {
                            Some(ref pl) => {
                                let (xa, xb2) = (
                                    ((xb * DEB_BLOCK) as f64).max(x0),
                                    (((xb + 1) * DEB_BLOCK) as f64).min(x1),
                                );
                                let (ya, yb2) = (
                                    ((yb * DEB_BLOCK) as f64).max(y0),
                                    (((yb + 1) * DEB_BLOCK) as f64).min(y1),
                                );
                                pl(xa, ya)
                                    .min(pl(xb2, ya))
                                    .min(pl(xa, yb2))
                                    .min(pl(xb2, yb2))
                                    .max(wmin)
                            }
                            None => wmin,
                        };
                        let far = f32_up(1.0 / wb * (1.0 + 1e-9));
                        let d = &mut deb[(yb * bw + xb) as usize];
                        *d = d.max(far);
                    }
                }
                pieces.push(scratch.clone());
            }
            let refs: Vec<&[ScreenVertex]> = pieces.iter().map(|p| p.as_slice()).collect();
            fb.draw_screen_union(&refs, o.object);
        }
        let pyramid = Pyramid::new(w, h, |i, j| fb.depth_at(i, j) < f32::INFINITY);
        crate::for_candidates(self.scene.objects(), candidates, |id| {
            let (lo, hi) = self.scene.boxes[id as usize];
            match box_in_view(&view, lo, hi) {
                BoxInView::Outside => frame.frustum_culled += 1,
                BoxInView::CrossesNear => frame.visible.push(id),
                BoxInView::Rect {
                    i0,
                    j0,
                    i1,
                    j1,
                    z_near,
                } => {
                    let behind = (j0 / DEB_BLOCK..=j1 / DEB_BLOCK).all(|yb| {
                        (i0 / DEB_BLOCK..=i1 / DEB_BLOCK)
                            .all(|xb| z_near > deb[(yb * bw + xb) as usize])
                    });
                    if behind && pyramid.rect_opaque([i0, j0, i1, j1], self.opts.opacity_threshold)
                    {
                        frame.occlusion_culled += 1;
                    } else {
                        frame.visible.push(id);
                    }
                }
            }
        });
        frame.finish();
        frame
    }
}
