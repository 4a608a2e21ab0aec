//! The occluders of a scene as one fused, conservatively rasterized height field
//! (erosion acts on the union of the buildings, and a union drawn piece by piece would
//! crack along shared edges), and the filling of closed courtyards.
//!
//! Occluders are the *inner* bounds of the objects (§4.2) standing on the ground, the
//! ground prisms of the methods' one occluder model (`sightline_scene::occluders`); their
//! union with the ground half-space is a height field `H(x, y)`. It is stored on a
//! square pixel grid as an **inner raster** `G`: `G(q) ≤ H(x)` for every point `x` of
//! pixel `q`. A pixel gets `G(q) = min h_b` over the prisms `b` touching it, if it lies
//! entirely inside the *union* of all footprints, and 0 otherwise: every point of the
//! pixel is then inside some prism touching it, so the bound holds. Because coverage
//! is decided on the union (exact boundary intervals per pixel row), touching buildings
//! fuse with no crack along their party wall, and a low annex does not cut a tall
//! block except in the pixels it touches. Heights are in decimetres, rounded down.
//!
//! **Courtyard filling.** A hole of a level set `{H ≥ h}` (a courtyard) can be filled up
//! to `h` without hiding anything that is visible from an eye below `h` outside the
//! hole: a sight line that passes the filled hole below `h` joins two points below `h`,
//! so it is below `h` where it crosses into the hole, where the walls around it stand.
//! The escape height `F(q)` — the least height one must climb over to go from `q` to
//! the outside, min over 8-connected pixel paths of the max of `G` — gives every hole of
//! every level at once (the "priority flood" of terrain analysis). For a cell whose top
//! is `z1` and whose free pixels escape below `f_c`, the filled field keeps `F(q)` where
//! `F(q) > max(z1, f_c)` and `G(q)` elsewhere (see [`HeightField::filled`]).

use sightline_geom::{boolean, Aabb2, DVec2, Polygon};
use sightline_raster::pyramid::{reduce2x2, Keep, Max, Min};
use sightline_scene::occluders::ground_prisms;
use sightline_scene::Scene;
use std::sync::OnceLock;

/// Pixel size of the height field for ordinary scenes (m).
pub const PIXEL_M: f64 = 0.5;
/// The pixel grows for huge scenes so that one field holds at most this many pixels.
pub const MAX_PIXELS: f64 = 16.0e6;
/// Heights are stored in decimetres.
pub const DM: f64 = 0.1;
/// Fill thresholds are rounded up to multiples of this (decimetres).
const FILL_STEP_DM: u32 = 20;
/// Free pixels kept around the occluders.
const BORDER_PX: i64 = 2;
/// Unions of footprints are computed per square tile of this many pixels.
const TILE_PX: i64 = 256;
/// Slack of index computations, in pixels, always towards the conservative side.
const EPS_PX: f64 = 1e-7;

/// A raster of heights (decimetres) over the pixels `[o + iδ, o + (i+1)δ]`.
/// Reads outside the raster give 0 (free ground).
#[derive(Clone, Debug)]
pub struct Grid {
    /// World position of pixel (0, 0)'s lower corner.
    pub origin: DVec2,
    /// Pixel size (m).
    pub pixel_m: f64,
    pub nx: i64,
    pub ny: i64,
    pub data: Vec<u16>,
}

impl Grid {
    pub fn zeros(origin: DVec2, pixel_m: f64, nx: i64, ny: i64) -> Self {
        Grid {
            origin,
            pixel_m,
            nx,
            ny,
            data: vec![0; (nx * ny) as usize],
        }
    }

    #[inline]
    pub fn get(&self, i: i64, j: i64) -> u16 {
        if i < 0 || j < 0 || i >= self.nx || j >= self.ny {
            0
        } else {
            self.data[(j * self.nx + i) as usize]
        }
    }

    /// Pixel index range `[lo, hi]` of the pixels whose closed extent meets the closed
    /// interval `[a, b]` of world x (axis 0) or y (axis 1), widened by a hair.
    #[inline]
    pub fn range(&self, axis: usize, a: f64, b: f64) -> (i64, i64) {
        let o = if axis == 0 {
            self.origin.x
        } else {
            self.origin.y
        };
        let inv = 1.0 / self.pixel_m;
        (floor((a - o) * inv - EPS_PX), floor((b - o) * inv + EPS_PX))
    }

    /// Pixel index range `[lo, hi]` of the fewest closed pixels covering the closed
    /// interval `[a, b]` (a bound on the grid needs no neighbour; ratios within 1e-9
    /// pixel of an integer are that integer).
    #[inline]
    pub fn cover(&self, axis: usize, a: f64, b: f64) -> (i64, i64) {
        let o = if axis == 0 {
            self.origin.x
        } else {
            self.origin.y
        };
        let inv = 1.0 / self.pixel_m;
        let lo = floor(snap((a - o) * inv));
        let hi = -floor(-snap((b - o) * inv)) - 1;
        (lo, hi.max(lo))
    }

    /// The least value over pixels covering the rectangle (0 if one is outside).
    pub fn min_over(&self, r: Aabb2) -> u16 {
        let (i0, i1) = self.cover(0, r.min.x, r.max.x);
        let (j0, j1) = self.cover(1, r.min.y, r.max.y);
        if i0 < 0 || j0 < 0 || i1 >= self.nx || j1 >= self.ny {
            return 0;
        }
        let mut m = u16::MAX;
        for j in j0..=j1 {
            let row = &self.data[(j * self.nx) as usize..((j + 1) * self.nx) as usize];
            for &v in &row[i0 as usize..=i1 as usize] {
                m = m.min(v);
            }
            if m == 0 {
                return 0;
            }
        }
        m
    }
}

/// A raster with its min-pyramid: level `L` holds the least value of each block of
/// `2^L × 2^L` pixels, so that the minimum over a large rectangle costs a few reads
/// (a coarser block covers more pixels: a lower, still conservative bound); and its
/// max-pyramid (the greatest value of each block), an upper bound of every `min_over`
/// inside a rectangle, with which the occlusion march skips in a few reads long runs
/// of sectors that cannot give a blocker.
#[derive(Clone, Debug)]
pub struct MinPyramid {
    pub levels: Vec<Grid>,
    /// `max_levels[L]`: the greatest value of each `2^L × 2^L` block (level 0 is
    /// `levels[0]`, not stored twice).
    pub max_levels: Vec<Grid>,
}

/// The next level of a pyramid: `K` of each 2 × 2 block (reads outside give 0), by the
/// raster crate's one pyramid reduction.
pub(crate) fn reduce<K: Keep<u16>>(last: &Grid) -> Grid {
    let (nx, ny, data) = reduce2x2::<u16, K>(last.nx as usize, last.ny as usize, &last.data, 0);
    Grid {
        origin: last.origin,
        pixel_m: last.pixel_m * 2.0,
        nx: nx as i64,
        ny: ny as i64,
        data,
    }
}

impl MinPyramid {
    pub fn new(base: Grid) -> Self {
        let mut levels = vec![base];
        let mut max_levels: Vec<Grid> = Vec::new();
        while let Some(last) = levels.last() {
            if last.nx <= 1 && last.ny <= 1 || levels.len() >= 12 {
                break;
            }
            let g = reduce::<Min>(last);
            let m = reduce::<Max>(max_levels.last().unwrap_or(&levels[0]));
            levels.push(g);
            max_levels.push(m);
        }
        MinPyramid { levels, max_levels }
    }

    /// Bytes held (for the cache bound).
    pub fn bytes(&self) -> usize {
        self.levels
            .iter()
            .chain(&self.max_levels)
            .map(|l| l.data.len() * 2)
            .sum()
    }

    /// A lower bound of the values of every base pixel meeting `r`, from the finest
    /// level where `r` spans at most about two texels per axis.
    pub fn min_over(&self, r: Aabb2) -> u16 {
        let level = level_for(r, self.levels[0].pixel_m, self.levels.len() - 1);
        self.levels[level].min_over(r)
    }

    /// An upper bound of the values of every base pixel meeting `r` (closed, widened
    /// by a hair), hence of `min_over(s)` for every rectangle `s ⊂ r`: each texel read
    /// by `min_over(s)` holds the least value of its block, which contains a base
    /// pixel meeting `s`. Pixels outside the raster are 0.
    pub fn max_over(&self, r: Aabb2) -> u16 {
        let level = level_for(r, self.levels[0].pixel_m, self.max_levels.len());
        let g = if level == 0 {
            &self.levels[0]
        } else {
            &self.max_levels[level - 1]
        };
        let (i0, i1) = g.range(0, r.min.x, r.max.x);
        let (j0, j1) = g.range(1, r.min.y, r.max.y);
        let (i0, i1) = (i0.max(0), i1.min(g.nx - 1));
        let (j0, j1) = (j0.max(0), j1.min(g.ny - 1));
        let mut m = 0;
        for j in j0..=j1 {
            if i0 > i1 {
                break;
            }
            let row = &g.data[(j * g.nx) as usize..((j + 1) * g.nx) as usize];
            for &v in &row[i0 as usize..=i1 as usize] {
                m = m.max(v);
            }
        }
        m
    }
}

/// The pyramid level a query over `r` reads: the least `L` with `span / 2^L ≤ 2`
/// pixels of `pixel_m` (capped at the coarsest level `top`).
pub(crate) fn level_for(r: Aabb2, pixel_m: f64, top: usize) -> usize {
    let span = r.size().max_element() / pixel_m;
    let mut level = 0;
    let mut reach = 2.0;
    while span > reach && level < top {
        level += 1;
        reach *= 2.0;
    }
    level
}

/// The geometry (no data) of the levels of the pyramid [`MinPyramid::new`] builds on a
/// raster of `nx × ny` pixels at `origin`.
pub(crate) fn pyramid_geometry(origin: DVec2, pixel_m: f64, nx: i64, ny: i64) -> Vec<Grid> {
    let mut levels = vec![Grid {
        origin,
        pixel_m,
        nx,
        ny,
        data: Vec::new(),
    }];
    while let Some(last) = levels.last() {
        if last.nx <= 1 && last.ny <= 1 || levels.len() >= 12 {
            break;
        }
        let next = Grid {
            origin,
            pixel_m: last.pixel_m * 2.0,
            nx: (last.nx + 1) / 2,
            ny: (last.ny + 1) / 2,
            data: Vec::new(),
        };
        levels.push(next);
    }
    levels
}

/// `⌊x⌋` without a libm call (hot in the occlusion-map march); saturating.
#[inline]
fn floor(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t - 1
    } else {
        t
    }
}

/// The fused occluder height field of a scene (see the module doc).
#[derive(Debug)]
pub struct HeightField {
    /// Inner raster `G`.
    pub g: Grid,
    /// Escape heights `F ≥ G` (priority flood from the raster's border).
    pub escape: Grid,
    /// Pixels touched by some occluder footprint (1) or not (0).
    touched: Vec<bool>,
    /// Max-pyramid of `escape` above its base (built on first use).
    escape_max: OnceLock<Vec<Grid>>,
}

/// Per-row boundary intervals and centre-line crossings of a set of rings.
struct RowScan {
    /// Per row: x-intervals covered by the boundary inside the row's closed band.
    bounds: Vec<Vec<(f64, f64)>>,
    /// Per row: the same for the boundary inside the open band (what can meet a
    /// pixel's interior).
    open: Vec<Vec<(f64, f64)>>,
    /// Per row: x of the crossings of the band's centre line (unsorted).
    cross: Vec<Vec<f64>>,
}

impl RowScan {
    /// Scan `rings` (closed, any orientation) over rows `j0..j1` of `grid`'s rows.
    fn new(grid: &Grid, j0: i64, j1: i64, rings: &[&[DVec2]]) -> Self {
        let n = (j1 - j0).max(0) as usize;
        let mut bounds = vec![Vec::new(); n];
        let mut open = vec![Vec::new(); n];
        let mut cross = vec![Vec::new(); n];
        let d = grid.pixel_m;
        for ring in rings {
            let m = ring.len();
            for k in 0..m {
                let (p, q) = (ring[k], ring[(k + 1) % m]);
                let (ylo, yhi) = (p.y.min(q.y), p.y.max(q.y));
                let (ja, jb) = grid.range(1, ylo, yhi);
                for j in ja.max(j0)..=jb.min(j1 - 1) {
                    let y0 = grid.origin.y + j as f64 * d;
                    let (y1, yc) = (y0 + d, y0 + 0.5 * d);
                    // The part of the edge inside the closed band [y0, y1].
                    let r = (j - j0) as usize;
                    if (q.y - p.y).abs() < 1e-12 {
                        let (xa, xb) = (p.x.min(q.x), p.x.max(q.x));
                        bounds[r].push((xa, xb));
                        let v = (p.y - grid.origin.y) / d;
                        if snap(v).fract() != 0.0 {
                            // Not on a pixel edge: inside the open band.
                            open[r].push((xa, xb));
                        }
                    } else {
                        let at = |y: f64| p.x + (q.x - p.x) * ((y - p.y) / (q.y - p.y));
                        let (ya, yb) = (ylo.max(y0), yhi.min(y1));
                        let (u, v) = (at(ya), at(yb));
                        bounds[r].push((u.min(v), u.max(v)));
                        if yb > ya {
                            open[r].push((u.min(v), u.max(v)));
                        }
                    }
                    // Half-open crossing rule on the centre line.
                    if (p.y <= yc) != (q.y <= yc) {
                        cross[r].push(p.x + (q.x - p.x) * ((yc - p.y) / (q.y - p.y)));
                    }
                }
            }
        }
        RowScan {
            bounds,
            open,
            cross,
        }
    }

    /// Visit the pixels of row `r` (index relative to `j0`): `f(i, inner)` for every
    /// pixel meeting the rings' region, `inner` when it lies entirely inside it (its
    /// interior meets no boundary and its centre is inside).
    fn visit(&mut self, grid: &Grid, r: usize, mut f: impl FnMut(i64, bool)) {
        let cross = &mut self.cross[r];
        cross.sort_by(f64::total_cmp);
        let o = grid.origin.x;
        let d = grid.pixel_m;
        // Pixels whose interior meets the boundary: i with iδ < b and (i+1)δ > a.
        let bpix: Vec<(i64, i64)> = merge(
            self.open[r]
                .iter()
                .map(|&(a, b)| {
                    let (a, b) = (snap((a - o) / d), snap((b - o) / d));
                    (a.floor() as i64, b.ceil() as i64 - 1)
                })
                // A vertical edge lying exactly on a pixel edge meets no interior: (n, n − 1).
                .filter(|&(lo, hi)| lo <= hi),
        );
        let mut bi = 0;
        for pair in cross.chunks_exact(2) {
            // Pixels whose centre lies in [pair[0], pair[1]].
            let lo = ((pair[0] - o) / d - 0.5).ceil() as i64;
            let hi = ((pair[1] - o) / d - 0.5).floor() as i64;
            let mut i = lo;
            while i <= hi {
                while bi < bpix.len() && bpix[bi].1 < i {
                    bi += 1;
                }
                let next = if bi < bpix.len() {
                    bpix[bi].0
                } else {
                    i64::MAX
                };
                if next <= i {
                    i = bpix[bi].1 + 1;
                    continue;
                }
                let end = hi.min(next - 1);
                for k in i..=end {
                    f(k, true);
                }
                i = end + 1;
            }
        }
        // Pixels meeting the boundary (closed): touched, not inner.
        let touched = merge(self.bounds[r].iter().map(|&(a, b)| grid.range(0, a, b)));
        for (lo, hi) in touched {
            for k in lo..=hi {
                f(k, false);
            }
        }
    }
}

/// Sort and merge integer ranges (adjacent ones joined).
fn merge(ranges: impl Iterator<Item = (i64, i64)>) -> Vec<(i64, i64)> {
    let mut v: Vec<(i64, i64)> = ranges.collect();
    v.sort_unstable();
    let mut out: Vec<(i64, i64)> = Vec::with_capacity(v.len());
    for (lo, hi) in v {
        match out.last_mut() {
            Some(last) if lo <= last.1 + 1 => last.1 = last.1.max(hi),
            _ => out.push((lo, hi)),
        }
    }
    out
}

impl HeightField {
    /// Rasterize the ground prisms of `scene` (`sightline_scene::occluders::ground_prisms`).
    pub fn build(scene: &Scene) -> Self {
        let mut prisms: Vec<(&Polygon, u16, Aabb2)> = Vec::new();
        for (_, p) in ground_prisms(scene) {
            if !(p.footprint.area() > 0.0) {
                continue;
            }
            let h = (p.top / DM).floor().min(u16::MAX as f64 - 1.0) as u16;
            if h > 0 {
                prisms.push((&p.footprint, h, p.footprint.bbox()));
            }
        }
        let bounds = prisms.iter().fold(Aabb2::EMPTY, |b, p| b.union(p.2));
        if bounds.is_empty() {
            let g = Grid::zeros(DVec2::ZERO, PIXEL_M, 1, 1);
            return HeightField {
                escape: g.clone(),
                g,
                touched: vec![false],
                escape_max: OnceLock::new(),
            };
        }
        let size = bounds.size();
        let pixel_m = PIXEL_M.max(((size.x + 8.0) * (size.y + 8.0) / MAX_PIXELS).sqrt());
        let origin = bounds.min - DVec2::splat(BORDER_PX as f64 * pixel_m);
        let nx = (size.x / pixel_m).ceil() as i64 + 2 * BORDER_PX + 1;
        let ny = (size.y / pixel_m).ceil() as i64 + 2 * BORDER_PX + 1;
        let mut g = Grid::zeros(origin, pixel_m, nx, ny);
        // The grid's geometry alone, for the scans while `g` is written.
        let geo = Grid {
            data: Vec::new(),
            ..g.clone()
        };
        // Lowest height touching each pixel (u16::MAX: none).
        let mut low = vec![u16::MAX; (nx * ny) as usize];
        for (poly, h, bb) in &prisms {
            let (j0, j1) = g.range(1, bb.min.y, bb.max.y);
            let (j0, j1) = (j0.max(0), (j1 + 1).min(ny));
            let rings: Vec<&[DVec2]> = poly.rings().map(|r| r.as_slice()).collect();
            let mut scan = RowScan::new(&geo, j0, j1, &rings);
            for j in j0..j1 {
                scan.visit(&geo, (j - j0) as usize, |i, _| {
                    if (0..nx).contains(&i) {
                        let c = &mut low[(j * nx + i) as usize];
                        *c = (*c).min(*h);
                    }
                });
            }
        }
        // Inner coverage of the union, tile by tile.
        let tree = rstar::RTree::bulk_load(
            prisms
                .iter()
                .enumerate()
                .map(|(k, p)| {
                    rstar::primitives::GeomWithData::new(
                        rstar::primitives::Rectangle::from_corners(
                            [p.2.min.x, p.2.min.y],
                            [p.2.max.x, p.2.max.y],
                        ),
                        k,
                    )
                })
                .collect(),
        );
        for tj in (0..ny).step_by(TILE_PX as usize) {
            for ti in (0..nx).step_by(TILE_PX as usize) {
                let (tj1, ti1) = ((tj + TILE_PX).min(ny), (ti + TILE_PX).min(nx));
                let lo = origin + DVec2::new(ti as f64, tj as f64) * pixel_m;
                let hi = origin + DVec2::new(ti1 as f64, tj1 as f64) * pixel_m;
                let window = Aabb2::new(lo, hi).expand(pixel_m);
                let env = rstar::AABB::from_corners(
                    [window.min.x, window.min.y],
                    [window.max.x, window.max.y],
                );
                let members: Vec<Polygon> = tree
                    .locate_in_envelope_intersecting(env)
                    .map(|it| prisms[it.data].0.clone())
                    .collect();
                if members.is_empty() {
                    continue;
                }
                let union = boolean::intersection(
                    &boolean::union(&members),
                    &[Polygon::rect(window.min, window.max)],
                );
                let rings: Vec<&[DVec2]> = union
                    .iter()
                    .flat_map(|p| p.rings().map(|r| r.as_slice()))
                    .collect();
                let mut scan = RowScan::new(&geo, tj, tj1, &rings);
                for j in tj..tj1 {
                    scan.visit(&geo, (j - tj) as usize, |i, inner| {
                        if inner && (ti..ti1).contains(&i) {
                            let k = (j * nx + i) as usize;
                            if low[k] != u16::MAX {
                                g.data[k] = low[k];
                            }
                        }
                    });
                }
            }
        }
        let touched = low.iter().map(|&v| v != u16::MAX).collect();
        let escape = priority_flood(&g);
        HeightField {
            g,
            escape,
            touched,
            escape_max: OnceLock::new(),
        }
    }

    /// An upper bound of the escape height `F` — hence of every filled field
    /// ([`Self::filled`]) — over the pixels `[i0, i1] × [j0, j1]` of `g` (0 outside).
    pub fn escape_max_over(&self, (i0, i1): (i64, i64), (j0, j1): (i64, i64)) -> u16 {
        let (i0, i1) = (i0.max(0), i1.min(self.g.nx - 1));
        let (j0, j1) = (j0.max(0), j1.min(self.g.ny - 1));
        if i0 > i1 || j0 > j1 {
            return 0;
        }
        let levels = self.escape_max.get_or_init(|| {
            let mut out: Vec<Grid> = Vec::new();
            loop {
                let last = out.last().unwrap_or(&self.escape);
                if last.nx <= 1 && last.ny <= 1 {
                    break;
                }
                let next = reduce::<Max>(last);
                out.push(next);
            }
            out
        });
        // The finest level where the range spans at most two texels per axis.
        let mut level = 0usize;
        while level < levels.len()
            && ((i1 >> level) - (i0 >> level) > 1 || (j1 >> level) - (j0 >> level) > 1)
        {
            level += 1;
        }
        let g = if level == 0 {
            &self.escape
        } else {
            &levels[level - 1]
        };
        let mut m = 0;
        for j in (j0 >> level)..=(j1 >> level).min(g.ny - 1) {
            for i in (i0 >> level)..=(i1 >> level).min(g.nx - 1) {
                m = m.max(g.data[(j * g.nx + i) as usize]);
            }
        }
        m
    }

    /// Whether some occluder footprint may meet the rectangle (conservative: true when
    /// a footprint only comes within a pixel).
    pub fn meets_rect(&self, r: Aabb2) -> bool {
        let (i0, i1) = self.g.range(0, r.min.x, r.max.x);
        let (j0, j1) = self.g.range(1, r.min.y, r.max.y);
        (j0.max(0)..=j1.min(self.g.ny - 1)).any(|j| {
            (i0.max(0)..=i1.min(self.g.nx - 1)).any(|i| self.touched[(j * self.g.nx + i) as usize])
        })
    }

    /// Whether the cell `rect` with top `z1` may hold a free viewpoint: some pixel of it
    /// is not entirely inside occluders higher than `z1` (points inside blocks are not
    /// viewpoints).
    pub fn has_free_space(&self, rect: Aabb2, z1: f64) -> bool {
        let top = (z1 / DM).floor().clamp(0.0, u16::MAX as f64) as u16;
        let (i0, i1) = self.g.range(0, rect.min.x, rect.max.x);
        let (j0, j1) = self.g.range(1, rect.min.y, rect.max.y);
        (j0..=j1).any(|j| (i0..=i1).any(|i| self.g.get(i, j) <= top))
    }

    /// The fill threshold (decimetres) for a cell of footprint `rect` and top `z1`:
    /// `max(z1, f_c)` where `f_c` is the greatest escape height of the cell's pixels
    /// that may hold a free viewpoint (`G ≤ z1`).
    pub fn fill_threshold(&self, rect: Aabb2, z1: f64) -> u16 {
        let z1_dm = (z1 / DM).ceil().clamp(0.0, u16::MAX as f64) as u16;
        let top = (z1 / DM).floor().clamp(0.0, u16::MAX as f64) as u16;
        let (i0, i1) = self.g.range(0, rect.min.x, rect.max.x);
        let (j0, j1) = self.g.range(1, rect.min.y, rect.max.y);
        let mut fc = 0;
        for j in j0..=j1 {
            for i in i0..=i1 {
                if self.g.get(i, j) <= top {
                    fc = fc.max(self.escape.get(i, j));
                }
            }
        }
        // Rounded up to a multiple of FILL_STEP_DM (filling less is always safe) so that
        // courtyard cells share a few filled fields.
        let t = z1_dm.max(fc) as u32;
        (t.div_ceil(FILL_STEP_DM) * FILL_STEP_DM).min(u16::MAX as u32) as u16
    }

    /// The occluders with every courtyard whose walls rise above `threshold_dm` filled
    /// (module doc): `F(q)` where `F(q) > threshold`, `G(q)` elsewhere.
    pub fn filled(&self, threshold_dm: u16) -> Grid {
        let mut out = self.g.clone();
        for (o, &f) in out.data.iter_mut().zip(&self.escape.data) {
            if f > threshold_dm {
                *o = f;
            }
        }
        out
    }
}

/// Escape heights: `F(q) = min over 8-connected paths from q to the border of the max
/// of G along the path`, by a bucket-queue priority flood (heights are small integers).
fn priority_flood(g: &Grid) -> Grid {
    let (nx, ny) = (g.nx, g.ny);
    let n = (nx * ny) as usize;
    let top = g.data.iter().copied().max().unwrap_or(0) as usize;
    let mut f = g.clone();
    let mut done = vec![false; n];
    let mut buckets: Vec<Vec<u32>> = vec![Vec::new(); top + 1];
    for j in 0..ny {
        for i in 0..nx {
            if i == 0 || j == 0 || i == nx - 1 || j == ny - 1 {
                let k = (j * nx + i) as usize;
                done[k] = true;
                buckets[g.data[k] as usize].push(k as u32);
            }
        }
    }
    for level in 0..=top {
        while let Some(k) = buckets[level].pop() {
            let (i, j) = (k as i64 % nx, k as i64 / nx);
            for dj in -1..=1 {
                for di in -1..=1 {
                    let (a, b) = (i + di, j + dj);
                    if a < 0 || b < 0 || a >= nx || b >= ny {
                        continue;
                    }
                    let q = (b * nx + a) as usize;
                    if done[q] {
                        continue;
                    }
                    done[q] = true;
                    let v = g.data[q].max(level as u16);
                    f.data[q] = v;
                    buckets[v as usize].push(q as u32);
                }
            }
        }
    }
    f
}

/// `x`, or the nearest integer if it is within 1e-9 of it.
#[inline]
pub(crate) fn snap(x: f64) -> f64 {
    // Nearest integer without a libm call (hot in the occlusion-map march).
    let t = (x + 0.5) as i64;
    let r = if (t as f64) > x + 0.5 { t - 1 } else { t } as f64;
    if (x - r).abs() < 1e-9 {
        r
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sightline_scene::Object;

    fn field(objs: Vec<Object>) -> HeightField {
        HeightField::build(&Scene::from_objects(objs))
    }

    fn at(f: &Grid, x: f64, y: f64) -> u16 {
        let (i, _) = f.range(0, x, x);
        let (j, _) = f.range(1, y, y);
        f.get(i, j)
    }

    #[test]
    fn touching_blocks_fuse_without_a_crack() {
        // Two blocks sharing the wall x = 10.2 (not on a pixel edge), heights 20 and 15.
        let f = field(vec![
            Object::rect_block(0.0, 0.0, 10.2, 10.0, 20.0),
            Object::rect_block(10.2, 0.0, 20.0, 10.0, 15.0),
        ]);
        assert_eq!(at(&f.g, 5.0, 5.0), 200);
        assert_eq!(at(&f.g, 15.0, 5.0), 150);
        // The pixel straddling the party wall is inside the union: min of the two.
        assert_eq!(at(&f.g, 10.2, 5.1), 150);
        // Outside and boundary pixels are free.
        assert_eq!(at(&f.g, 20.1, 5.0), 0);
        assert_eq!(at(&f.g, -0.1, 5.0), 0);
    }

    #[test]
    fn inner_raster_never_exceeds_the_height_field() {
        let f = field(vec![
            Object::rect_block(0.3, 0.7, 7.9, 5.2, 12.0),
            Object::rect_block(7.9, 1.0, 9.0, 3.0, 30.0),
        ]);
        for j in 0..f.g.ny {
            for i in 0..f.g.nx {
                let v = f.g.get(i, j);
                if v == 0 {
                    continue;
                }
                let lo = f.g.origin + DVec2::new(i as f64, j as f64) * f.g.pixel_m;
                for (u, w) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0), (0.5, 0.5)] {
                    let p = lo + DVec2::new(u, w) * f.g.pixel_m;
                    let inside = (0.3..=7.9).contains(&p.x) && (0.7..=5.2).contains(&p.y)
                        || (7.9..=9.0).contains(&p.x) && (1.0..=3.0).contains(&p.y);
                    assert!(inside, "pixel ({i},{j}) = {v} has {p:?} outside");
                }
            }
        }
    }

    #[test]
    fn courtyard_escape_height_is_the_lowest_wall() {
        // A ring of buildings 10 m deep around a 20 m courtyard, one wing lower (12 m).
        let f = field(vec![
            Object::rect_block(0.0, 0.0, 40.0, 10.0, 20.0),
            Object::rect_block(0.0, 30.0, 40.0, 40.0, 20.0),
            Object::rect_block(0.0, 10.0, 10.0, 30.0, 20.0),
            Object::rect_block(30.0, 10.0, 40.0, 30.0, 12.0),
        ]);
        assert_eq!(at(&f.g, 20.0, 20.0), 0);
        assert_eq!(at(&f.escape, 20.0, 20.0), 120);
        let filled = f.filled(20);
        assert_eq!(at(&filled, 20.0, 20.0), 120);
        // A cell inside the courtyard: its own pixels escape at 12 m, nothing is filled.
        let r = Aabb2::new(DVec2::new(15.0, 15.0), DVec2::new(25.0, 25.0));
        assert_eq!(f.fill_threshold(r, 2.0), 120);
        assert_eq!(f.fill_threshold(r, 13.0), 140);
        assert_eq!(at(&f.filled(120), 20.0, 20.0), 0);
    }
}
