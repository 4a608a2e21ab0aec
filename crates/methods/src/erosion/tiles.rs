//! Lazy tiled erosion: the eroded occluders of one structuring element, cell shape and
//! fill threshold, eroded tile by tile when the occlusion march first reads a tile.
//!
//! The paper renders every eroded occluder into the occlusion map and notes that once
//! the horizon is closed the rest of the city is hidden whatever it holds (§7 "Scaling
//! to large environments"). The march of [`super::occlusion`] reads the eroded raster
//! only in the bins some test needs, front to back and only until the horizon closes
//! there, so most of a large city is never read: eroding it whole for the first cell of
//! each cell shape and fill threshold was most of that cell's time.
//!
//! **Same values as the whole raster.** The erosion is a chain of min-filters
//! ([`Step`]), each reading at most its reach around a pixel, with zero outside the
//! raster. A tile of `2^T × 2^T` pixels is eroded from the filled height field over the
//! tile and a margin of the chain's summed reach, with every intermediate set to zero
//! outside the whole raster as the whole-raster erosion reads it: every pixel of the
//! tile gets the value of [`super::erode::erode`]. The tile keeps its min- and
//! max-pyramid levels up to its own size; tiles are aligned on the pyramid's blocks,
//! so the texels of [`MinPyramid`]'s levels are those of the tiles (coarser levels are
//! minima over whole tiles). [`TiledErosion::min_over`] returns what
//! [`MinPyramid::min_over`] returns on the whole eroded raster, hence the same blockers
//! and the same PVS.
//!
//! **Upper bounds without eroding.** The march only uses [`TiledErosion::max_at_most`] to
//! skip runs of sectors that cannot give a blocker (any upper bound gives the same
//! blockers, a looser one skips less). Over tiles not eroded yet it bounds the eroded
//! field by the un-eroded one, translated: every step is a minimum over offsets that
//! include a fixed `k`, so `E(p) ≤ F(p + Σk)` with `F` the escape height, which is at
//! least every filled field; the bound is the lesser of two such translations. So a
//! skip over the far city reads two coarse texels and erodes nothing.

use super::erode::{pad_px, steps, Element, Step};
use super::field::{level_for, pyramid_geometry, Grid, HeightField, MinPyramid};
use sightline_geom::{Aabb2, DVec2};
use sightline_raster::pyramid::{reduce2x2, Max, Min};
use std::sync::atomic::{AtomicU16, AtomicUsize, Ordering};
use std::sync::{Arc, OnceLock};

/// Eroded occluders as the occlusion march reads them.
pub trait Occluders {
    /// Pixel size of the base raster (m).
    fn pixel_m(&self) -> f64;
    /// A lower bound of the eroded height (dm) over every pixel meeting `r`.
    fn min_over(&self, r: Aabb2) -> u16;
    /// Whether an upper bound of [`Self::min_over`] for every rectangle inside `r` is
    /// at most `limit` (a looser bound may answer `false` more often).
    fn max_at_most(&self, r: Aabb2, limit: u16) -> bool;
}

impl Occluders for MinPyramid {
    fn pixel_m(&self) -> f64 {
        self.levels[0].pixel_m
    }
    fn min_over(&self, r: Aabb2) -> u16 {
        MinPyramid::min_over(self, r)
    }
    fn max_at_most(&self, r: Aabb2, limit: u16) -> bool {
        MinPyramid::max_over(self, r) <= limit
    }
}

/// Tiles are at least this many pixels on a side (a power of two) …
const MIN_TILE_PX: i64 = 128;
/// … and at most this many: a tile grows with the erosion's margin so that the margin
/// stays a fraction of the work.
const MAX_TILE_PX: i64 = 1024;

/// One eroded tile with its pyramid levels.
struct Tile {
    /// `min[L]`: the level-`L` texels of the tile, `(S >> L)²` row-major, `L = 0..=T`.
    min: Vec<Vec<u16>>,
    /// `max[L − 1]`: the greatest value of each level-`L` block, `L = 1..=T`.
    max: Vec<Vec<u16>>,
}

/// The erosion of the filled height field by one element, eroded tile by tile.
pub struct TiledErosion {
    field: Arc<HeightField>,
    fill_dm: u16,
    steps: Vec<Step>,
    /// The eroded raster's pixel `(i, j)` is the field's pixel `(i − pad, j − pad)`.
    pad: i64,
    /// Pixels read around a tile to erode it.
    margin: i64,
    /// The levels of the whole eroded raster's pyramid (geometry only).
    geo: Vec<Grid>,
    /// Tiles are `2^log` pixels on a side.
    log: usize,
    tiles_x: i64,
    tiles: Vec<OnceLock<Tile>>,
    /// Offsets `k` (eroded pixels) with `E(p) ≤ F(p + k − pad)`.
    bound_offsets: [(i64, i64); 2],
    /// Upper bounds per block of `2^k × 2^k` tiles (`k = 0, 1, …`): the bound of the
    /// un-eroded field, lowered to the tile's greatest value once it is eroded (values
    /// only decrease, so a parent recomputed from stale children is still a bound).
    tile_max: Vec<TileLevel>,
    bytes: AtomicUsize,
}

/// One level of [`TiledErosion::tile_max`].
struct TileLevel {
    nx: i64,
    ny: i64,
    v: Vec<AtomicU16>,
}

impl TileLevel {
    #[inline]
    fn get(&self, i: i64, j: i64) -> u16 {
        self.v[(j * self.nx + i) as usize].load(Ordering::Relaxed)
    }
}

impl TiledErosion {
    /// The erosion by `element` for cells of half size `half` of `field` filled above
    /// `fill_dm` ([`HeightField::filled`]); nothing is eroded yet.
    pub fn new(field: Arc<HeightField>, element: Element, half: DVec2, fill_dm: u16) -> Self {
        let g = &field.g;
        let d = g.pixel_m;
        let pad = pad_px(element, half, d);
        let (nx, ny) = (g.nx + 2 * pad, g.ny + 2 * pad);
        let geo = pyramid_geometry(g.origin - DVec2::splat(pad as f64 * d), d, nx, ny);
        let steps = steps(element, half, d);
        let margin = steps.iter().map(Step::reach_px).sum::<i64>() + 1;
        let side = ((2 * margin).max(1) as u64).next_power_of_two() as i64;
        let side = side.clamp(MIN_TILE_PX, MAX_TILE_PX);
        let log = side.trailing_zeros() as usize;
        let tiles_x = (nx + side - 1) / side;
        let tiles_y = (ny + side - 1) / side;
        let mut bound_offsets = [(0, 0); 2];
        for (e, off) in bound_offsets.iter_mut().enumerate() {
            for s in &steps {
                let k = s.end_offsets()[e];
                off.0 += k.0;
                off.1 += k.1;
            }
        }
        let mut t = TiledErosion {
            field,
            fill_dm,
            steps,
            pad,
            margin,
            geo,
            log,
            tiles_x,
            tiles: (0..tiles_x * tiles_y).map(|_| OnceLock::new()).collect(),
            bound_offsets,
            tile_max: Vec::new(),
            bytes: AtomicUsize::new(0),
        };
        // The tile pyramid of bounds, from the un-eroded field.
        let mut level = TileLevel {
            nx: tiles_x,
            ny: tiles_y,
            v: Vec::new(),
        };
        for tj in 0..tiles_y {
            for ti in 0..tiles_x {
                let b = t.bound(
                    (ti * side, ti * side + side - 1),
                    (tj * side, tj * side + side - 1),
                );
                level.v.push(AtomicU16::new(b));
            }
        }
        loop {
            let (nx, ny) = ((level.nx + 1) / 2, (level.ny + 1) / 2);
            let done = level.nx <= 1 && level.ny <= 1;
            let mut next = TileLevel {
                nx,
                ny,
                v: Vec::new(),
            };
            if !done {
                for j in 0..ny {
                    for i in 0..nx {
                        next.v.push(AtomicU16::new(block_max(&level, i, j)));
                    }
                }
            }
            t.tile_max.push(level);
            if done {
                break;
            }
            level = next;
        }
        t
    }

    /// Bytes held by the tiles eroded so far.
    pub fn bytes(&self) -> usize {
        self.bytes.load(Ordering::Relaxed)
    }

    /// Number of tiles eroded so far, and of tiles in all.
    pub fn tiles_eroded(&self) -> (usize, usize) {
        let done = self.tiles.iter().filter(|t| t.get().is_some()).count();
        (done, self.tiles.len())
    }

    #[inline]
    fn slot(&self, ti: i64, tj: i64) -> &OnceLock<Tile> {
        &self.tiles[(tj * self.tiles_x + ti) as usize]
    }

    #[inline]
    fn tile(&self, ti: i64, tj: i64) -> &Tile {
        self.slot(ti, tj).get_or_init(|| {
            let tile = self.erode_tile(ti, tj);
            let top = tile.max.last().map_or(tile.min[0][0], |l| l[0]);
            self.lower_bound_of(ti, tj, top);
            tile
        })
    }

    /// Lower the tile pyramid's bound of tile `(ti, tj)` to its greatest value `top`.
    fn lower_bound_of(&self, ti: i64, tj: i64, top: u16) {
        let (mut i, mut j) = (ti, tj);
        let l0 = &self.tile_max[0];
        l0.v[(j * l0.nx + i) as usize].fetch_min(top, Ordering::Relaxed);
        for k in 1..self.tile_max.len() {
            let below = &self.tile_max[k - 1];
            (i, j) = (i / 2, j / 2);
            let level = &self.tile_max[k];
            level.v[(j * level.nx + i) as usize]
                .fetch_min(block_max(below, i, j), Ordering::Relaxed);
        }
    }

    /// Erode tile `(ti, tj)` (module doc) and build its pyramid levels.
    fn erode_tile(&self, ti: i64, tj: i64) -> Tile {
        let s = 1i64 << self.log;
        let m = self.margin;
        let (nx, ny) = (self.geo[0].nx, self.geo[0].ny);
        let g = &self.field.g;
        let f = &self.field.escape;
        let w = s + 2 * m;
        // Eroded-raster pixel of the work grid's pixel (0, 0).
        let (x0, y0) = (ti * s - m, tj * s - m);
        let mut work = Grid::zeros(DVec2::ZERO, g.pixel_m, w, w);
        let t = self.fill_dm;
        for j in 0..w {
            let gj = y0 + j - self.pad;
            if gj < 0 || gj >= g.ny {
                continue;
            }
            let (gi0, gi1) = ((x0 - self.pad).max(0), (x0 - self.pad + w).min(g.nx));
            if gi0 >= gi1 {
                continue;
            }
            let src = (gj * g.nx) as usize;
            let dst = (j * w + gi0 - (x0 - self.pad)) as usize;
            let (gs, fs) = (
                &g.data[src + gi0 as usize..src + gi1 as usize],
                &f.data[src + gi0 as usize..src + gi1 as usize],
            );
            for ((o, &gv), &fv) in work.data[dst..dst + (gi1 - gi0) as usize]
                .iter_mut()
                .zip(gs)
                .zip(fs)
            {
                *o = if fv > t { fv } else { gv };
            }
        }
        // Zero outside the whole eroded raster, as its erosion reads there.
        let outside = |work: &mut Grid| {
            for j in 0..w {
                let ej = y0 + j;
                let row = &mut work.data[(j * w) as usize..((j + 1) * w) as usize];
                if ej < 0 || ej >= ny {
                    row.fill(0);
                    continue;
                }
                let lo = (-x0).clamp(0, w) as usize;
                let hi = (nx - x0).clamp(0, w) as usize;
                row[..lo].fill(0);
                row[hi.max(lo)..].fill(0);
            }
        };
        for step in &self.steps {
            work = step.apply(&work);
            outside(&mut work);
        }
        let mut base = vec![0u16; (s * s) as usize];
        for j in 0..s {
            let at = ((j + m) * w + m) as usize;
            base[(j * s) as usize..((j + 1) * s) as usize]
                .copy_from_slice(&work.data[at..at + s as usize]);
        }
        let mut min = vec![base];
        let mut max: Vec<Vec<u16>> = Vec::new();
        for level in 1..=self.log {
            // The level below is `2n × 2n` with `n = s >> level` (s a power of two).
            let n = 2 * (s >> level) as usize;
            let lo = reduce2x2::<u16, Min>(n, n, &min[level - 1], 0).2;
            let hi = reduce2x2::<u16, Max>(n, n, max.last().unwrap_or(&min[0]), 0).2;
            min.push(lo);
            max.push(hi);
        }
        let bytes: usize = min.iter().chain(&max).map(|l| l.len() * 2).sum();
        self.bytes.fetch_add(bytes, Ordering::Relaxed);
        Tile { min, max }
    }

    /// An upper bound of the eroded raster over its pixels `[i0, i1] × [j0, j1]`,
    /// without eroding (module doc).
    fn bound(&self, (i0, i1): (i64, i64), (j0, j1): (i64, i64)) -> u16 {
        self.bound_offsets
            .iter()
            .map(|&(kx, ky)| {
                let (dx, dy) = (kx - self.pad, ky - self.pad);
                self.field
                    .escape_max_over((i0 + dx, i1 + dx), (j0 + dy, j1 + dy))
            })
            .min()
            .unwrap_or(u16::MAX)
    }

    /// [`Occluders::max_at_most`] over the pixels `x × y` inside node `(i, j)` of level
    /// `k` of the tile pyramid, reading tiles at texel level `tl`.
    fn node_at_most(
        &self,
        k: usize,
        (i, j): (i64, i64),
        x: (i64, i64),
        y: (i64, i64),
        tl: usize,
        limit: u16,
    ) -> bool {
        let level = &self.tile_max[k];
        if i >= level.nx || j >= level.ny || level.get(i, j) <= limit {
            return true;
        }
        let span = 1i64 << (self.log + k);
        let (x0, y0) = (i * span, j * span);
        let (a0, a1) = (x.0.max(x0), x.1.min(x0 + span - 1));
        let (b0, b1) = (y.0.max(y0), y.1.min(y0 + span - 1));
        if a0 > a1 || b0 > b1 {
            return true;
        }
        if k > 0 {
            return (0..2).all(|dj| {
                (0..2).all(|di| {
                    self.node_at_most(
                        k - 1,
                        (2 * i + di, 2 * j + dj),
                        (a0, a1),
                        (b0, b1),
                        tl,
                        limit,
                    )
                })
            });
        }
        self.tile_at_most(i, j, (a0, a1), (b0, b1), tl, limit)
    }

    /// [`Occluders::max_at_most`] over the pixels `x × y` inside tile `(i, j)`, read at
    /// texel level `tl` (module doc: a tile not eroded yet answers by bounds first).
    #[inline]
    fn tile_at_most(
        &self,
        i: i64,
        j: i64,
        x: (i64, i64),
        y: (i64, i64),
        tl: usize,
        limit: u16,
    ) -> bool {
        let tile = match self.slot(i, j).get() {
            Some(tile) => tile,
            None => {
                if self.tile_max[0].get(i, j) <= limit {
                    return true;
                }
                let s = 1i64 << self.log;
                let (a0, a1) = (x.0.max(i * s), x.1.min(i * s + s - 1));
                let (b0, b1) = (y.0.max(j * s), y.1.min(j * s + s - 1));
                if self.bound((a0, a1), (b0, b1)) <= limit {
                    return true;
                }
                self.tile(i, j)
            }
        };
        let texels = if tl == 0 {
            &tile.min[0]
        } else {
            &tile.max[tl - 1]
        };
        let sh = self.log - tl;
        let side = 1i64 << sh;
        // The texel range of the tile, clamped to it.
        let (ai, bj) = (i << sh, j << sh);
        let (a0, a1) = (
            (x.0 >> tl).max(ai) - ai,
            (x.1 >> tl).min(ai + side - 1) - ai,
        );
        let (b0, b1) = (
            (y.0 >> tl).max(bj) - bj,
            (y.1 >> tl).min(bj + side - 1) - bj,
        );
        (b0..=b1).all(|b| {
            let row = (b * side) as usize;
            texels[row + a0 as usize..=row + a1 as usize]
                .iter()
                .all(|&v| v <= limit)
        })
    }

    /// The texels `[i0, i1] × [j0, j1]` of level `level ≤ log`, tile by tile:
    /// `f(tile index, local column range, local row range, texels per tile side)`.
    fn by_tile(
        &self,
        level: usize,
        (i0, i1): (i64, i64),
        (j0, j1): (i64, i64),
        mut f: impl FnMut((i64, i64), (i64, i64), (i64, i64), i64) -> bool,
    ) {
        let sh = self.log - level;
        let side = 1i64 << sh;
        for tj in (j0 >> sh)..=(j1 >> sh) {
            let (b0, b1) = ((j0 - (tj << sh)).max(0), (j1 - (tj << sh)).min(side - 1));
            for ti in (i0 >> sh)..=(i1 >> sh) {
                let (a0, a1) = ((i0 - (ti << sh)).max(0), (i1 - (ti << sh)).min(side - 1));
                if !f((ti, tj), (a0, a1), (b0, b1), side) {
                    return;
                }
            }
        }
    }
}

impl Occluders for TiledErosion {
    fn pixel_m(&self) -> f64 {
        self.geo[0].pixel_m
    }

    /// [`MinPyramid::min_over`] of the whole eroded raster (module doc).
    fn min_over(&self, r: Aabb2) -> u16 {
        let level = level_for(r, self.geo[0].pixel_m, self.geo.len() - 1);
        let g = &self.geo[level];
        let (i0, i1) = g.cover(0, r.min.x, r.max.x);
        let (j0, j1) = g.cover(1, r.min.y, r.max.y);
        if i0 < 0 || j0 < 0 || i1 >= g.nx || j1 >= g.ny {
            return 0;
        }
        let mut m = u16::MAX;
        if level <= self.log {
            let sh = self.log - level;
            let (ti, tj) = (i0 >> sh, j0 >> sh);
            if ti == i1 >> sh && tj == j1 >> sh {
                // Most reads fall inside one tile.
                let side = 1i64 << sh;
                let texels = &self.tile(ti, tj).min[level];
                let (a0, a1) = (i0 - (ti << sh), i1 - (ti << sh));
                for b in j0 - (tj << sh)..=j1 - (tj << sh) {
                    let row = (b * side) as usize;
                    for &v in &texels[row + a0 as usize..=row + a1 as usize] {
                        m = m.min(v);
                    }
                }
                return m;
            }
            self.by_tile(
                level,
                (i0, i1),
                (j0, j1),
                |(ti, tj), (a0, a1), (b0, b1), side| {
                    let texels = &self.tile(ti, tj).min[level];
                    for b in b0..=b1 {
                        let row = (b * side) as usize;
                        for &v in &texels[row + a0 as usize..=row + a1 as usize] {
                            m = m.min(v);
                        }
                    }
                    m > 0
                },
            );
            return m;
        }
        // A texel coarser than a tile: the least of its tiles, 0 if its block leaves
        // the raster (as the pyramid's reduction reads there).
        let (nx, ny) = (self.geo[0].nx, self.geo[0].ny);
        let sh = level - self.log;
        for j in j0..=j1 {
            for i in i0..=i1 {
                if (i + 1) << level > nx || (j + 1) << level > ny {
                    return 0;
                }
                for tj in j << sh..(j + 1) << sh {
                    for ti in i << sh..(i + 1) << sh {
                        m = m.min(self.tile(ti, tj).min[self.log][0]);
                        if m == 0 {
                            return 0;
                        }
                    }
                }
            }
        }
        m
    }

    /// Whether the eroded raster is at most `limit` over every pixel meeting `r`
    /// (closed, widened by a hair), read at the level [`MinPyramid::max_over`] reads.
    /// A tile not eroded yet first answers by its bound, then by the bound of the
    /// un-eroded field over its part of `r`, and is eroded only if both exceed `limit`:
    /// the answer is that of the whole raster where it matters, and the far city is
    /// bounded without eroding it. Texels coarser than a tile are the tile pyramid's
    /// bounds, refined into their children where they exceed `limit`.
    fn max_at_most(&self, r: Aabb2, limit: u16) -> bool {
        let level = level_for(r, self.geo[0].pixel_m, self.geo.len() - 1);
        let g = &self.geo[0];
        let (i0, i1) = g.range(0, r.min.x, r.max.x);
        let (j0, j1) = g.range(1, r.min.y, r.max.y);
        let (i0, i1) = (i0.max(0), i1.min(g.nx - 1));
        let (j0, j1) = (j0.max(0), j1.min(g.ny - 1));
        if i0 > i1 || j0 > j1 {
            return true;
        }
        if level <= self.log {
            let (t0, t1) = (i0 >> self.log, i1 >> self.log);
            return (j0 >> self.log..=j1 >> self.log).all(|tj| {
                (t0..=t1).all(|ti| self.tile_at_most(ti, tj, (i0, i1), (j0, j1), level, limit))
            });
        }
        let k = (level - self.log).min(self.tile_max.len() - 1);
        let sh = self.log + k;
        (j0 >> sh..=j1 >> sh).all(|j| {
            (i0 >> sh..=i1 >> sh).all(|i| {
                self.node_at_most(k, (i, j), (i0, i1), (j0, j1), level.min(self.log), limit)
            })
        })
    }
}

/// The greatest of the (up to four) entries of `level` under entry `(i, j)` of the
/// next level.
fn block_max(level: &TileLevel, i: i64, j: i64) -> u16 {
    let mut m = 0;
    for b in 2 * j..(2 * j + 2).min(level.ny) {
        for a in 2 * i..(2 * i + 2).min(level.nx) {
            m = m.max(level.get(a, b));
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::erosion::erode::erode;
    use sightline_scene::{Object, Scene};

    /// A small city: rows of touching houses, a courtyard block, a tower.
    fn field() -> Arc<HeightField> {
        let mut objs = Vec::new();
        for row in 0..4 {
            for k in 0..9 {
                let (x, y) = (k as f64 * 7.3, row as f64 * 31.0);
                objs.push(Object::rect_block(
                    x,
                    y,
                    x + 7.3,
                    y + 12.0,
                    6.0 + (k * 5 % 17) as f64,
                ));
            }
        }
        objs.push(Object::rect_block(80.0, 0.0, 120.0, 10.0, 18.0));
        objs.push(Object::rect_block(80.0, 30.0, 120.0, 40.0, 18.0));
        objs.push(Object::rect_block(80.0, 10.0, 90.0, 30.0, 15.0));
        objs.push(Object::rect_block(110.0, 10.0, 120.0, 30.0, 21.0));
        objs.push(Object::rect_block(95.0, 60.0, 101.0, 66.0, 60.0));
        Arc::new(HeightField::build(&Scene::from_objects(objs)))
    }

    /// Every `min_over` of the tiled erosion equals the whole raster's, and every
    /// `max_at_most` answer holds of its pixels, before and after the tiles are eroded.
    #[test]
    fn tiled_reads_equal_the_whole_raster() {
        let f = field();
        for el in Element::ALL {
            for (half, fill) in [(DVec2::new(12.5, 12.5), 20), (DVec2::new(1.6, 3.1), 0)] {
                let whole = MinPyramid::new(erode(&f.filled(fill), el, half));
                let tiled = TiledErosion::new(f.clone(), el, half, fill);
                let mut x = 0x9E37_79B9_7F4A_7C15u64;
                for k in 0..3000 {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    let c = DVec2::new(
                        (x % 1700) as f64 * 0.1 - 20.0,
                        ((x >> 20) % 1300) as f64 * 0.1 - 20.0,
                    );
                    let size = DVec2::new(
                        0.05 + ((x >> 40) % 400) as f64 * 0.11,
                        0.05 + ((x >> 50) % 300) as f64 * 0.13,
                    );
                    // One query in ten spans more than a tile (the coarse levels).
                    let r = Aabb2::new(c, c + size * if k % 10 == 0 { 6.0 } else { 1.0 });
                    let limit = (x >> 30) as u16 % 400;
                    if tiled.max_at_most(r, limit) {
                        // The true greatest value over the pixels meeting `r`.
                        let b = &whole.levels[0];
                        let (i0, i1) = b.range(0, r.min.x, r.max.x);
                        let (j0, j1) = b.range(1, r.min.y, r.max.y);
                        let top = (j0..=j1)
                            .flat_map(|j| (i0..=i1).map(move |i| (i, j)))
                            .map(|(i, j)| b.get(i, j))
                            .max()
                            .unwrap_or(0);
                        assert!(top <= limit, "{el:?} max at {r:?}");
                    }
                    assert_eq!(
                        tiled.min_over(r),
                        whole.min_over(r),
                        "{el:?} min at {r:?}, query {k}"
                    );
                }
                assert!(tiled.tiles_eroded().0 > 0);
            }
        }
    }
}
