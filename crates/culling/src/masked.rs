//! A masked, tiled, conservative depth buffer in the spirit of Masked Occlusion Culling
//! (Hasselgren, Andersson, Akenine-Möller, HPG 2016).
//!
//! The screen is cut into tiles of [`TILE_W`] × [`TILE_H`] pixels. A tile holds no depth
//! per pixel: one `u32` coverage mask per pixel row and two depth layers (§3 of the
//! paper): the *reference* layer `z1`, an upper bound of the visible depth at every
//! pixel of the tile, and the *working* layer `z0 < z1`, an upper bound at the pixels
//! whose mask bit is set. Triangles are merged in any order (§3.2):
//!
//! * an occluder covering the whole tile at farthest depth `zt < z1` lowers `z1`;
//! * otherwise its mask joins the working layer, whose depth becomes `max(z0, zt)` (a
//!   bound for the old and the new pixels); when the working mask fills the tile, the
//!   working layer becomes the reference layer (`z1 = min(z1, z0)`) and is emptied.
//!
//! Every step keeps "each pixel's visible depth ≤ its layer's depth", so the buffer is
//! a conservative far-depth buffer. Unlike the paper, which rasterizes pixel centres
//! and so is conservative only up to a pixel, a pixel bit is set here only when the
//! polygon covers the pixel entirely (inner coverage: the fully covered x-range of a
//! band `[j, j+1]` of a convex polygon is `chord(j) ∩ chord(j+1)`, since its left side
//! is convex and its right side concave), and the tile's depth `zt` is an upper bound of
//! the polygon's depth over the tile: `w = 1/depth` is affine in screen space, so its
//! minimum over the tile (clipped to the polygon's bounding box) is at a corner, and
//! never below the polygon's smallest vertex `w`.
//!
//! Queries take an occludee's outer screen rectangle at a lower bound of its depth and
//! report it hidden only when that depth is strictly farther than the layer bounding
//! every pixel of the rectangle (ties are visible). A max-depth hierarchy over the tiles'
//! reference layers answers large rectangles at once.

use crate::frustum::f32_up;
use fearless_simd::Level;
use sightline_raster::ScreenVertex;

/// Tile width in pixels (one `u32` mask per row).
pub const TILE_W: u32 = 32;
/// Tile height in pixels.
pub const TILE_H: u32 = 8;
pub(crate) const TH: usize = TILE_H as usize;
/// A partial coverage farther than this factor times the working layer's depth is not
/// merged into it.
const FAR_MERGE: f32 = 1.5;
/// Inner coverage shrinks chords by this much (pixels), towards "not covered".
pub(crate) const EPS_PX: f64 = 1e-7;

#[derive(Clone, Copy, Debug)]
struct Tile {
    mask: [u32; TH],
    z0: f32,
    z1: f32,
}

const EMPTY_TILE: Tile = Tile {
    mask: [0; TH],
    z0: 0.0,
    z1: f32::INFINITY,
};

/// The masked depth buffer of one frame.
#[derive(Clone, Debug)]
pub struct MaskedBuffer {
    pub width: u32,
    pub height: u32,
    tiles_x: u32,
    tiles_y: u32,
    tiles: Vec<Tile>,
    /// Coverage of the current band of tiles, per tile column.
    band: Vec<[u32; TH]>,
    /// Max-depth hierarchy over the tiles' `z1`: `(cols, rows, values)`, level 0 = tiles.
    levels: Vec<(u32, u32, Vec<f32>)>,
    /// Polygons drawn (after near clipping and off-screen rejection).
    pub polygons_drawn: u64,
    path: RasterPath,
    level: Level,
}

/// Which code computes the coverage masks of a band of tile rows. Both give the same
/// buffer bit for bit (the SIMD lanes do the scalar code's `f64` operations in the same
/// order, without fused multiply-adds); a property test holds them to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RasterPath {
    /// One pixel row at a time, scalar `f64` code.
    Scalar,
    /// The eight pixel rows of a tile at once in SIMD lanes ([`crate::masked_simd`]), with
    /// the best instruction set the CPU has, chosen at run time (SSE2 is the x86-64
    /// baseline; AVX2 and AVX-512 when present).
    Simd,
}

impl RasterPath {
    /// The path used when none is asked for: [`RasterPath::Simd`].
    pub const DEFAULT: RasterPath = RasterPath::Simd;

    /// Its name in reports (`scalar`, or `simd-` and the instruction set chosen).
    pub fn describe(self) -> String {
        match self {
            RasterPath::Scalar => "scalar".into(),
            RasterPath::Simd => format!("simd-{}", crate::masked_simd::level_name(Level::new())),
        }
    }
}

/// A convex polygon's edge: `(y_lo, y_hi, x at y_lo, dx/dy)`, lower endpoint first; a
/// horizontal edge is `(y, y, x_min, x_max - x_min)`, flagged by `y_lo == y_hi`.
pub(crate) type Edge = (f64, f64, f64, f64);

impl MaskedBuffer {
    /// An empty buffer (every depth `+∞`).
    pub fn new(width: u32, height: u32) -> MaskedBuffer {
        let tiles_x = width.div_ceil(TILE_W);
        let tiles_y = height.div_ceil(TILE_H);
        MaskedBuffer {
            width,
            height,
            tiles_x,
            tiles_y,
            tiles: vec![EMPTY_TILE; (tiles_x * tiles_y) as usize],
            band: vec![[0; TH]; tiles_x as usize],
            levels: Vec::new(),
            polygons_drawn: 0,
            path: RasterPath::DEFAULT,
            level: Level::new(),
        }
    }

    /// An empty buffer drawn by `path`.
    pub fn with_path(width: u32, height: u32, path: RasterPath) -> MaskedBuffer {
        MaskedBuffer {
            path,
            ..MaskedBuffer::new(width, height)
        }
    }

    /// An empty buffer drawn by the SIMD path at `level` (tests compare the levels).
    pub fn with_simd_level(width: u32, height: u32, level: Level) -> MaskedBuffer {
        MaskedBuffer {
            path: RasterPath::Simd,
            level,
            ..MaskedBuffer::new(width, height)
        }
    }

    /// Whether two buffers hold the same tiles (masks and both depth layers).
    pub fn same_tiles(&self, other: &MaskedBuffer) -> bool {
        self.width == other.width
            && self.height == other.height
            && self.tiles.len() == other.tiles.len()
            && self.tiles.iter().zip(&other.tiles).all(|(a, b)| {
                a.mask == b.mask
                    && a.z0.to_bits() == b.z0.to_bits()
                    && a.z1.to_bits() == b.z1.to_bits()
            })
    }

    /// The bits of tile `(tx, ty)`'s row `r` that lie on the screen.
    #[inline]
    fn valid(&self, tx: u32, ty: u32, r: usize) -> u32 {
        if ty * TILE_H + r as u32 >= self.height {
            return 0;
        }
        let cols = (self.width - tx * TILE_W).min(TILE_W);
        if cols == 32 {
            u32::MAX
        } else {
            (1u32 << cols) - 1
        }
    }

    #[inline]
    fn full(&self, tx: u32, ty: u32, m: &[u32; TH]) -> bool {
        if tx + 1 < self.tiles_x && ty + 1 < self.tiles_y {
            return m.iter().all(|&r| r == u32::MAX);
        }
        (0..TH).all(|r| m[r] | !self.valid(tx, ty, r) == u32::MAX)
    }

    /// Draw a convex screen polygon (vertices in order, `w = 1/depth > 0`) with inner
    /// coverage at an upper bound of its depth per tile.
    pub fn draw_polygon(&mut self, v: &[ScreenVertex]) {
        let n = v.len();
        if n < 3 {
            return;
        }
        let (mut xmin, mut xmax, mut ymin, mut ymax) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        let (mut wmin, mut wmax) = (f64::MAX, 0f64);
        for p in v {
            xmin = xmin.min(p.x);
            xmax = xmax.max(p.x);
            ymin = ymin.min(p.y);
            ymax = ymax.max(p.y);
            wmin = wmin.min(p.w);
            wmax = wmax.max(p.w);
        }
        let (wf, hf) = (self.width as f64, self.height as f64);
        if xmax <= 0.0 || ymax <= 0.0 || xmin >= wf || ymin >= hf || !(wmin > 0.0) {
            return;
        }
        // Early out: if every tile under the polygon's box is already nearer than the
        // polygon's nearest point, no merge could change anything.
        {
            let z_near = (1.0 / wmax) as f32;
            let tx0 = (xmin.max(0.0) as u32 / TILE_W).min(self.tiles_x - 1);
            let tx1 = (xmax.min(wf - 1.0).max(0.0) as u32 / TILE_W).min(self.tiles_x - 1);
            let ty0 = (ymin.max(0.0) as u32 / TILE_H).min(self.tiles_y - 1);
            let ty1 = (ymax.min(hf - 1.0).max(0.0) as u32 / TILE_H).min(self.tiles_y - 1);
            let hidden = (ty0..=ty1).all(|ty| {
                let row = &self.tiles[(ty * self.tiles_x) as usize..][tx0 as usize..=tx1 as usize];
                row.iter().all(|t| t.z1 <= z_near)
            });
            if hidden {
                return;
            }
        }
        // Plane w = w0 - (nx (x - x0) + ny (y - y0)) / nw, by Newell's method in (x, y, w).
        let (mut nx, mut ny, mut nw) = (0.0, 0.0, 0.0);
        for k in 0..n {
            let (a, b) = (v[k], v[(k + 1) % n]);
            nx += (a.y - b.y) * (a.w + b.w);
            ny += (a.w - b.w) * (a.x + b.x);
            nw += (a.x - b.x) * (a.y + b.y);
        }
        // A polygon of less than a pixel of area covers no pixel entirely.
        if !(nw.abs() >= 2.0) {
            return;
        }
        self.polygons_drawn += 1;
        let (gx, gy) = (-nx / nw, -ny / nw);
        let w_at = |x: f64, y: f64| v[0].w + gx * (x - v[0].x) + gy * (y - v[0].y);

        // Bands [j, j+1] inside [ymin, ymax].
        let j0 = ymin.ceil().max(0.0) as i64;
        let j1 = ((ymax.floor() as i64) - 1).min(self.height as i64 - 1);
        if j0 > j1 {
            return;
        }
        // Edges as (y_lo, y_hi, x at y_lo, dx/dy), lower endpoint first; horizontal
        // edges as (y, y, x_min, x_max - x_min) flagged by `y_lo == y_hi`.
        const MAX_EDGES: usize = 16;
        if n > MAX_EDGES {
            // Not produced by prism faces (at most 5 vertices after clipping); leaving an
            // occluder out is conservative.
            return;
        }
        let mut edges: [Edge; MAX_EDGES] = [(0.0, 0.0, 0.0, 0.0); MAX_EDGES];
        for (k, e) in edges.iter_mut().enumerate().take(n) {
            let (a, b) = (v[k], v[(k + 1) % n]);
            let (lo, hi) = if a.y <= b.y { (a, b) } else { (b, a) };
            *e = if hi.y == lo.y {
                (lo.y, hi.y, lo.x.min(hi.x), (lo.x - hi.x).abs())
            } else {
                (lo.y, hi.y, lo.x, (hi.x - lo.x) / (hi.y - lo.y))
            };
        }
        let edges = &edges[..n];
        let tx_lo = (xmin.max(0.0) as u32 / TILE_W).min(self.tiles_x - 1);
        let tx_hi = ((xmax.min(wf - 1.0)).max(0.0) as u32 / TILE_W).min(self.tiles_x - 1);
        debug_assert!(self.band[tx_lo as usize..=tx_hi as usize]
            .iter()
            .all(|b| *b == [0; TH]));
        let ty_lo = j0 as u32 / TILE_H;
        let ty_hi = j1 as u32 / TILE_H;
        for ty in ty_lo..=ty_hi {
            let ja = (ty * TILE_H) as i64;
            let rows = (ja.max(j0), (ja + TH as i64 - 1).min(j1));
            let touched = match self.path {
                RasterPath::Scalar => band_scalar(edges, rows, wf, &mut self.band),
                RasterPath::Simd => {
                    crate::masked_simd::band(self.level, edges, ja, rows, wf, &mut self.band)
                }
            };
            let Some((ctx_lo, ctx_hi)) = touched else {
                continue;
            };
            let y0 = (ty * TILE_H) as f64;
            let (ya, yb) = (y0.max(ymin), (y0 + TILE_H as f64).min(ymax));
            for tx in ctx_lo..=ctx_hi {
                // Taken, leaving the band empty for the next one.
                let cov = std::mem::take(&mut self.band[tx as usize]);
                if cov.iter().all(|&m| m == 0) {
                    continue;
                }
                let x0 = (tx * TILE_W) as f64;
                let (xa, xb) = (x0.max(xmin), (x0 + TILE_W as f64).min(xmax));
                let w = w_at(xa, ya)
                    .min(w_at(xb, ya))
                    .min(w_at(xa, yb))
                    .min(w_at(xb, yb))
                    .max(wmin);
                let zt = f32_up(1.0 / w * (1.0 + 1e-9));
                self.insert(tx, ty, &cov, zt);
            }
        }
    }

    /// Merge a coverage mask at depth `zt` into tile `(tx, ty)` (the update rule of the
    /// module doc).
    #[inline]
    fn insert(&mut self, tx: u32, ty: u32, cov: &[u32; TH], zt: f32) {
        let k = (ty * self.tiles_x + tx) as usize;
        let mut t = self.tiles[k];
        if !(zt < t.z1) {
            return;
        }
        if self.full(tx, ty, cov) {
            t.z1 = zt;
            if t.z0 >= t.z1 {
                t.mask = [0; TH];
            }
        } else {
            let empty = t.mask.iter().all(|&m| m == 0);
            let mut merged = t.mask;
            for (m, c) in merged.iter_mut().zip(cov) {
                *m |= c;
            }
            if empty {
                t.mask = *cov;
                t.z0 = zt;
            } else if self.full(tx, ty, &merged) {
                // The two layers fill the tile: the farther depth bounds every pixel, and
                // the nearer of the two stays as the working layer.
                t.z1 = t.z0.max(zt);
                if zt < t.z0 {
                    t.mask = *cov;
                    t.z0 = zt;
                } else if !(t.z0 < t.z1) {
                    t.mask = [0; TH];
                }
            } else if zt <= t.z0 {
                t.mask = merged;
            } else if zt <= FAR_MERGE * t.z0 {
                t.mask = merged;
                t.z0 = zt;
            }
            // Else the new coverage is far behind the working layer: merging would push
            // the whole layer back (the discard heuristic of §3.2); it is dropped.
        }
        self.tiles[k] = t;
    }

    /// Build the max-depth hierarchy over the tiles (call after drawing, before
    /// [`MaskedBuffer::rect_occluded`] for fast answers on large rectangles).
    pub fn build_hierarchy(&mut self) {
        self.levels.clear();
        let base: Vec<f32> = self.tiles.iter().map(|t| t.z1).collect();
        self.levels.push((self.tiles_x, self.tiles_y, base));
        loop {
            let (c, r, ref v) = *self.levels.last().expect("level 0 pushed");
            if c <= 1 && r <= 1 {
                break;
            }
            let (nc, nr) = (c.div_ceil(2), r.div_ceil(2));
            let mut out = vec![0f32; (nc * nr) as usize];
            for y in 0..nr {
                for x in 0..nc {
                    let mut m = 0f32;
                    for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                        let (sx, sy) = (2 * x + dx, 2 * y + dy);
                        if sx < c && sy < r {
                            m = m.max(v[(sy * c + sx) as usize]);
                        }
                    }
                    out[(y * nc + x) as usize] = m;
                }
            }
            self.levels.push((nc, nr, out));
        }
    }

    /// Whether everything in the pixel rectangle `[i0, i1] × [j0, j1]` (inclusive, on
    /// the screen) at depth `z_near` or farther is hidden: `z_near` strictly beyond the
    /// bound of every pixel (ties visible).
    pub fn rect_occluded(&self, i0: u32, j0: u32, i1: u32, j1: u32, z_near: f32) -> bool {
        let (tx0, tx1) = (i0 / TILE_W, i1 / TILE_W);
        let (ty0, ty1) = (j0 / TILE_H, j1 / TILE_H);
        // Coarse accept: the level where the rectangle spans at most 2 × 2 cells.
        if !self.levels.is_empty() {
            let mut l = 0;
            while l + 1 < self.levels.len()
                && ((tx1 >> l) - (tx0 >> l) > 1 || (ty1 >> l) - (ty0 >> l) > 1)
            {
                l += 1;
            }
            let (c, _, ref v) = self.levels[l];
            let mut all = true;
            'coarse: for y in ty0 >> l..=ty1 >> l {
                for x in tx0 >> l..=tx1 >> l {
                    if !(z_near > v[(y * c + x) as usize]) {
                        all = false;
                        break 'coarse;
                    }
                }
            }
            if all {
                return true;
            }
        }
        for ty in ty0..=ty1 {
            for tx in tx0..=tx1 {
                let t = &self.tiles[(ty * self.tiles_x + tx) as usize];
                if z_near > t.z1 {
                    continue;
                }
                if !(z_near > t.z0) {
                    return false;
                }
                // Only the working layer can hide it: every pixel of the rectangle in this
                // tile must be in its mask.
                let a = i0.max(tx * TILE_W) - tx * TILE_W;
                let b = i1.min(tx * TILE_W + TILE_W - 1) - tx * TILE_W;
                let bits = (u32::MAX >> (31 - b)) & (u32::MAX << a);
                let ra = j0.max(ty * TILE_H) - ty * TILE_H;
                let rb = j1.min(ty * TILE_H + TILE_H - 1) - ty * TILE_H;
                for r in ra..=rb {
                    if bits & !t.mask[r as usize] != 0 {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// An upper bound of the visible depth at pixel `(i, j)` (`+∞` where nothing is
    /// known), for tests and the comparison with a full-resolution buffer.
    pub fn depth_bound(&self, i: u32, j: u32) -> f32 {
        let (tx, ty) = (i / TILE_W, j / TILE_H);
        let t = &self.tiles[(ty * self.tiles_x + tx) as usize];
        if t.mask[(j % TILE_H) as usize] >> (i % TILE_W) & 1 == 1 {
            t.z0.min(t.z1)
        } else {
            t.z1
        }
    }
}

/// The x-range `(left, right)` of the polygon of `edges` on the line `y` (`left > right`
/// when the line misses it).
#[inline]
fn chord(edges: &[Edge], y: f64) -> (f64, f64) {
    let (mut l, mut r) = (f64::MAX, f64::MIN);
    for &(ylo, yhi, x0, d) in edges {
        if ylo <= y && y <= yhi {
            if yhi == ylo {
                l = l.min(x0);
                r = r.max(x0 + d);
            } else {
                let x = x0 + (y - ylo) * d;
                l = l.min(x);
                r = r.max(x);
            }
        }
    }
    (l, r)
}

/// Inner coverage of the pixel rows `rows.0 ..= rows.1` (one band of tiles) by the
/// convex polygon of `edges`, one row at a time: the bits of the pixels of band `[j,
/// j+1]` lying inside both chords `j` and `j + 1` (shrunk by [`EPS_PX`]) are or-ed into
/// `band[tx][j % TILE_H]`. Returns the tile columns touched, if any.
fn band_scalar(
    edges: &[Edge],
    rows: (i64, i64),
    wf: f64,
    band: &mut [[u32; TH]],
) -> Option<(u32, u32)> {
    let (mut ctx_lo, mut ctx_hi) = (u32::MAX, 0u32);
    let mut below = chord(edges, rows.0 as f64);
    for j in rows.0..=rows.1 {
        let above = chord(edges, (j + 1) as f64);
        let l = below.0.max(above.0) + EPS_PX;
        let r = below.1.min(above.1) - EPS_PX;
        below = above;
        if !(l <= r) {
            continue;
        }
        let i0 = l.ceil().max(0.0);
        let i1 = (r.floor() - 1.0).min(wf - 1.0);
        if i0 > i1 {
            continue;
        }
        let (i0, i1) = (i0 as u32, i1 as u32);
        let row = (j as u32 % TILE_H) as usize;
        for tx in i0 / TILE_W..=i1 / TILE_W {
            let a = i0.max(tx * TILE_W) - tx * TILE_W;
            let b = i1.min(tx * TILE_W + TILE_W - 1) - tx * TILE_W;
            band[tx as usize][row] |= (u32::MAX >> (31 - b)) & (u32::MAX << a);
        }
        ctx_lo = ctx_lo.min(i0 / TILE_W);
        ctx_hi = ctx_hi.max(i1 / TILE_W);
    }
    (ctx_lo <= ctx_hi).then_some((ctx_lo, ctx_hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sv(x: f64, y: f64, w: f64) -> ScreenVertex {
        ScreenVertex { x, y, w }
    }

    #[test]
    fn a_full_screen_quad_hides_what_is_behind_it_and_not_what_is_in_front() {
        let mut b = MaskedBuffer::new(100, 50);
        let q = [
            sv(-1.0, -1.0, 0.1),
            sv(101.0, -1.0, 0.1),
            sv(101.0, 51.0, 0.1),
            sv(-1.0, 51.0, 0.1),
        ];
        b.draw_polygon(&q);
        b.build_hierarchy();
        assert!(b.rect_occluded(0, 0, 99, 49, 10.5));
        assert!(!b.rect_occluded(0, 0, 99, 49, 10.0), "a tie is visible");
        assert!(!b.rect_occluded(3, 3, 5, 5, 9.0));
    }

    #[test]
    fn partly_covered_pixels_stay_open() {
        let mut b = MaskedBuffer::new(64, 16);
        // Covers x in [0.5, 40.5]: pixels 1..=39 fully.
        let q = [
            sv(0.5, 0.0, 1.0),
            sv(40.5, 0.0, 1.0),
            sv(40.5, 16.0, 1.0),
            sv(0.5, 16.0, 1.0),
        ];
        b.draw_polygon(&q);
        assert_eq!(b.depth_bound(0, 3), f32::INFINITY);
        // An upper bound, rounded up a hair.
        assert!((1.0..1.001).contains(&b.depth_bound(1, 3)));
        assert!((1.0..1.001).contains(&b.depth_bound(39, 3)));
        assert_eq!(b.depth_bound(40, 3), f32::INFINITY);
        assert!(b.rect_occluded(1, 0, 39, 15, 2.0));
        assert!(!b.rect_occluded(1, 0, 40, 15, 2.0));
    }

    #[test]
    fn two_halves_fuse_into_the_reference_layer() {
        let mut b = MaskedBuffer::new(32, 8);
        // Overlapping by half a pixel: an edge exactly on a pixel border loses the pixel
        // (inner coverage is shrunk by a hair).
        b.draw_polygon(&[
            sv(-0.5, -0.5, 0.5),
            sv(16.5, -0.5, 0.5),
            sv(16.5, 8.5, 0.5),
            sv(-0.5, 8.5, 0.5),
        ]);
        b.draw_polygon(&[
            sv(15.5, -0.5, 0.25),
            sv(32.5, -0.5, 0.25),
            sv(32.5, 8.5, 0.25),
            sv(15.5, 8.5, 0.25),
        ]);
        b.build_hierarchy();
        assert!(b.rect_occluded(0, 0, 31, 7, 4.5));
        assert!(!b.rect_occluded(0, 0, 31, 7, 4.0));
    }
}
