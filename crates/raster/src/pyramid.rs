//! Hierarchical pyramids over a 2D raster, generic over what each level keeps of its
//! 2 × 2 blocks ([`Keep`]: the maximum, the minimum or the mean opacity), and the
//! max-depth pyramid of the hierarchical z-buffer built on it (Greene et al. 1993;
//! survey §6.1): level 0 is the depth buffer, each texel of level `l+1` holds the
//! maximum of its (up to) four children. A screen rectangle is occluded at depth `z`
//! when every pixel of it holds a depth `< z`; one texel of a coarse level whose
//! maximum is `< z` proves it for all its pixels at once.
//!
//! The same reduction serves every pyramid of the engine (the erosion method's min and
//! max pyramids, the extended projections' depth map, the from-point cullers' depth and
//! opacity hierarchies), so a level is always the same function of the level below.

use crate::coverage::{self, floor_i, for_row_depths, Depth, Prepared};
use crate::view::{fan, ScreenVertex, View};
use crate::MAX_INPUT_VERTS;
use glam::DVec3;
use std::marker::PhantomData;

/// What a pyramid level keeps of each 2 × 2 block of the level below: `combine` is
/// applied as `combine(combine(a, b), combine(c, d))` over the block's rows.
pub trait Keep<T: Copy> {
    fn combine(a: T, b: T) -> T;
}

/// The greatest value of a block (a max-depth pyramid: an upper bound of every pixel).
#[derive(Clone, Copy, Debug, Default)]
pub struct Max;
/// The least value of a block (a lower bound of every pixel).
#[derive(Clone, Copy, Debug, Default)]
pub struct Min;
/// The mean of a block (a hierarchical occlusion map's opacity, Zhang et al. 1997).
#[derive(Clone, Copy, Debug, Default)]
pub struct Mean;
/// The sum of a block (exact opacity as counts of opaque pixels; outside gives 0).
#[derive(Clone, Copy, Debug, Default)]
pub struct Sum;

impl Keep<f32> for Max {
    #[inline(always)]
    fn combine(a: f32, b: f32) -> f32 {
        a.max(b)
    }
}
impl Keep<f32> for Min {
    #[inline(always)]
    fn combine(a: f32, b: f32) -> f32 {
        a.min(b)
    }
}
impl Keep<f32> for Mean {
    #[inline(always)]
    fn combine(a: f32, b: f32) -> f32 {
        0.5 * (a + b)
    }
}
impl Keep<u32> for Sum {
    #[inline(always)]
    fn combine(a: u32, b: u32) -> u32 {
        a + b
    }
}
impl Keep<u16> for Max {
    #[inline(always)]
    fn combine(a: u16, b: u16) -> u16 {
        a.max(b)
    }
}
impl Keep<u16> for Min {
    #[inline(always)]
    fn combine(a: u16, b: u16) -> u16 {
        a.min(b)
    }
}

/// The next level of a `width × height` row-major raster: `K` of each 2 × 2 block;
/// reads past the raster's right or top edge give `outside`. Returns the level's
/// width, height and values (`⌈width / 2⌉ × ⌈height / 2⌉`).
pub fn reduce2x2<T: Copy, K: Keep<T>>(
    width: usize,
    height: usize,
    data: &[T],
    outside: T,
) -> (usize, usize, Vec<T>) {
    let (w, h) = (width.div_ceil(2), height.div_ceil(2));
    let mut out = Vec::with_capacity(w * h);
    let pair = |row: &[T], i: usize| {
        let a = row[2 * i];
        let b = if 2 * i + 1 < width {
            row[2 * i + 1]
        } else {
            outside
        };
        K::combine(a, b)
    };
    for j in 0..h {
        let r0 = &data[2 * j * width..(2 * j + 1) * width];
        if 2 * j + 1 < height {
            let r1 = &data[(2 * j + 1) * width..(2 * j + 2) * width];
            out.extend((0..w).map(|i| K::combine(pair(r0, i), pair(r1, i))));
        } else {
            let o = K::combine(outside, outside);
            out.extend((0..w).map(|i| K::combine(pair(r0, i), o)));
        }
    }
    (w, h, out)
}

/// One level of a [`Pyramid`].
#[derive(Clone, Debug)]
pub struct Level<T> {
    pub width: usize,
    pub height: usize,
    pub data: Vec<T>,
}

impl<T: Copy> Level<T> {
    /// The value of texel `(i, j)`.
    #[inline]
    pub fn at(&self, i: usize, j: usize) -> T {
        self.data[j * self.width + i]
    }
}

/// A pyramid of levels over a raster: level 0 is the raster, each level above keeps
/// `K` of the 2 × 2 blocks of the level below (reads past the edges give `outside`),
/// up to a 1 × 1 level or `max_levels` levels in all.
#[derive(Clone, Debug)]
pub struct Pyramid<T, K> {
    levels: Vec<Level<T>>,
    keep: PhantomData<K>,
}

impl<T: Copy, K: Keep<T>> Pyramid<T, K> {
    /// Build the pyramid of a `width × height` row-major raster.
    pub fn new(width: usize, height: usize, base: Vec<T>, outside: T, max_levels: usize) -> Self {
        let mut levels = vec![Level {
            width,
            height,
            data: base,
        }];
        while levels.len() < max_levels.max(1) {
            let l = &levels[levels.len() - 1];
            if l.width <= 1 && l.height <= 1 {
                break;
            }
            let (width, height, data) = reduce2x2::<T, K>(l.width, l.height, &l.data, outside);
            levels.push(Level {
                width,
                height,
                data,
            });
        }
        Pyramid {
            levels,
            keep: PhantomData,
        }
    }

    /// The levels, finest (the raster) first.
    pub fn levels(&self) -> &[Level<T>] {
        &self.levels
    }

    /// Level `l` (0 = the raster).
    pub fn level(&self, l: usize) -> &Level<T> {
        &self.levels[l]
    }

    /// Take the levels out.
    pub fn into_levels(self) -> Vec<Level<T>> {
        self.levels
    }
}

/// A max-depth pyramid built from a depth buffer (a snapshot: rebuild after drawing;
/// [`crate::Framebuffer::pyramid`]).
#[derive(Clone, Debug)]
pub struct DepthPyramid {
    levels: Pyramid<f32, Max>,
}

impl DepthPyramid {
    /// Build the pyramid of a `width × height` depth buffer (row-major).
    pub fn from_depth(width: u32, height: u32, depth: &[f32]) -> Self {
        DepthPyramid {
            levels: Pyramid::new(
                width as usize,
                height as usize,
                depth.to_vec(),
                f32::NEG_INFINITY,
                usize::MAX,
            ),
        }
    }

    /// Width and height of level 0.
    pub fn size(&self) -> (u32, u32) {
        let l = self.levels.level(0);
        (l.width as u32, l.height as u32)
    }

    /// Depth of level 0 at pixel `(i, j)`.
    pub fn depth_at(&self, i: u32, j: u32) -> f32 {
        self.levels.level(0).at(i as usize, j as usize)
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
        while level + 1 < self.levels.levels().len() && (span >> (level + 1)) >= 1 {
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
        let l = self.levels.level(level);
        if l.at(tx as usize, ty as usize) < depth {
            return true;
        }
        if level == 0 {
            return false;
        }
        let c = self.levels.level(level - 1);
        let (cw, ch) = (c.width as u32, c.height as u32);
        let s = level - 1;
        for cy in (2 * ty)..(2 * ty + 2).min(ch) {
            for cx in (2 * tx)..(2 * tx + 2).min(cw) {
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
        occluded_test(view, poly, w, h, &self.levels.level(0).data, Some(self))
    }

    /// Whether a world triangle is hidden in `view`.
    pub fn triangle_occluded(&self, view: &View, tri: &[DVec3; 3]) -> bool {
        self.polygon_occluded(view, tri)
    }

    /// Screen-space version of [`DepthPyramid::polygon_occluded`].
    pub fn screen_polygon_occluded(&self, poly: &[ScreenVertex]) -> bool {
        let (w, h) = self.size();
        screen_occluded(poly, w, h, &self.levels.level(0).data, Some(self))
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The block of level-`l` texel `(i, j)` in level-0 pixels, values outside the
    /// raster reading `outside`.
    fn naive<T: Copy, K: Keep<T>>(
        w: usize,
        h: usize,
        data: &[T],
        outside: T,
        l: usize,
        i: usize,
        j: usize,
    ) -> T {
        if l == 0 {
            return if i < w && j < h {
                data[j * w + i]
            } else {
                outside
            };
        }
        let v = |a, b| naive::<T, K>(w, h, data, outside, l - 1, a, b);
        K::combine(
            K::combine(v(2 * i, 2 * j), v(2 * i + 1, 2 * j)),
            K::combine(v(2 * i, 2 * j + 1), v(2 * i + 1, 2 * j + 1)),
        )
    }

    proptest! {
        #[test]
        fn levels_are_the_blocks_reduction(
            w in 1usize..20,
            h in 1usize..20,
            seed in any::<u64>(),
        ) {
            let mut x = seed | 1;
            let data: Vec<u16> = (0..w * h)
                .map(|_| {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    (x % 1000) as u16
                })
                .collect();
            let p = Pyramid::<u16, Min>::new(w, h, data.clone(), 0, usize::MAX);
            let top = p.level(p.levels().len() - 1);
            prop_assert_eq!((top.width, top.height), (1, 1));
            for (l, level) in p.levels().iter().enumerate() {
                prop_assert_eq!(level.width, w.div_ceil(1 << l));
                for j in 0..level.height {
                    for i in 0..level.width {
                        prop_assert_eq!(level.at(i, j), naive::<u16, Min>(w, h, &data, 0, l, i, j));
                    }
                }
            }
            let q = Pyramid::<u16, Max>::new(w, h, data.clone(), 0, 3);
            prop_assert!(q.levels().len() <= 3);
            let all = data.iter().copied().max().unwrap_or(0);
            if w <= 4 && h <= 4 {
                prop_assert_eq!(q.level(q.levels().len() - 1).at(0, 0), all);
            }
        }
    }

    #[test]
    fn mean_is_the_opacity_of_the_block() {
        let p = Pyramid::<f32, Mean>::new(2, 2, vec![1.0, 1.0, 0.0, 1.0], 0.0, usize::MAX);
        assert_eq!(p.level(1).at(0, 0), 0.75);
        // Outside the map counts as transparent.
        let p = Pyramid::<f32, Mean>::new(1, 1, vec![1.0], 0.0, 2);
        assert_eq!(p.levels().len(), 1);
        let (w, h, v) = reduce2x2::<f32, Mean>(3, 1, &[1.0, 1.0, 1.0], 0.0);
        assert_eq!((w, h), (2, 1));
        assert_eq!(v, vec![0.5, 0.25]);
    }
}
