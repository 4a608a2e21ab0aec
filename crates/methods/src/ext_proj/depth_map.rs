//! The extended depth map of a projection plane and its hierarchical pyramid
//! (Durand et al. 2000, §2.3–2.4), with a conservative *inner* rasterization of the
//! *union* of the occluders' Projections (§3.2; shrinking each piece on its own would leave cracks along every shared edge and lose most of the fusion).
//!
//! A pixel receives depth `d` only when it is entirely covered by the union of the
//! Projections whose depth is at most `d`; its value is the minimum such `d` (the
//! occluder closest to the cell, §2.3). Coverage is computed per pixel row from the
//! pieces' extents at the row's two ordinates, joining pieces that overlap across the
//! whole row (see [`CoverageBuilder::finish`]), so two pieces sharing an edge — even a
//! slanted one — leave no crack (unlike shrinking every piece by a pixel separately).
//!
//! Depths are stored as `f32`, rounded up for occluders; occludee depths are rounded
//! down before the comparison, and ties count as visible.

use sightline_geom::DVec2;
use sightline_raster::pyramid::{reduce2x2, Max};

/// Pieces closer than this (in pixels) count as overlapping: they come from pieces of
/// one decomposed solid whose shared edge was computed twice.
const MERGE_TOL_PX: f64 = 1e-7;

/// Round an occluder depth up to `f32`.
pub(crate) fn depth_up(d: f64) -> f32 {
    let f = d as f32;
    if (f as f64) < d {
        f.next_up()
    } else {
        f
    }
}

/// Round an occludee depth down to `f32`.
pub fn depth_down(d: f64) -> f32 {
    let f = d as f32;
    if (f as f64) > d {
        f.next_down()
    } else {
        f
    }
}

/// Collects the Projections drawn on one plane, then resolves coverage and depth.
pub(crate) struct CoverageBuilder {
    n: usize,
    /// Per row: (left, right, depth) intervals fully covered over the row's height.
    rows: Vec<Vec<Band>>,
}

impl CoverageBuilder {
    pub(crate) fn new(n: usize) -> Self {
        CoverageBuilder {
            n,
            rows: vec![Vec::new(); n],
        }
    }

    /// Add a convex polygon in continuous pixel coordinates, at extended depth `depth`.
    pub(crate) fn add_convex(&mut self, poly: &[DVec2], depth: f32) {
        if poly.len() < 3 {
            return;
        }
        let (mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in poly {
            ymin = ymin.min(p.y);
            ymax = ymax.max(p.y);
        }
        let j0 = ymin.ceil().max(0.0) as i64;
        let j1 = (ymax.floor() as i64).min(self.n as i64);
        if j1 <= j0 {
            return;
        }
        // Horizontal extent at each integer ordinate j0..=j1.
        let m = (j1 - j0 + 1) as usize;
        let mut span = vec![(f64::INFINITY, f64::NEG_INFINITY); m];
        let k = poly.len();
        for i in 0..k {
            let a = poly[i];
            let b = poly[(i + 1) % k];
            let (lo, hi) = if a.y <= b.y { (a, b) } else { (b, a) };
            let js = lo.y.ceil().max(j0 as f64) as i64;
            let je = (hi.y.floor() as i64).min(j1);
            for j in js..=je {
                let y = j as f64;
                let x = if hi.y > lo.y {
                    lo.x + (hi.x - lo.x) * ((y - lo.y) / (hi.y - lo.y))
                } else {
                    // Horizontal edge on the ordinate: both ends count.
                    let s = &mut span[(j - j0) as usize];
                    s.0 = s.0.min(lo.x.min(hi.x));
                    s.1 = s.1.max(lo.x.max(hi.x));
                    continue;
                };
                let s = &mut span[(j - j0) as usize];
                s.0 = s.0.min(x);
                s.1 = s.1.max(x);
            }
        }
        for j in j0..j1 {
            let (a, b) = (span[(j - j0) as usize], span[(j - j0 + 1) as usize]);
            if (j as usize) < self.n && a.1 >= a.0 && b.1 >= b.0 {
                self.rows[j as usize].push(Band {
                    l0: a.0,
                    r0: a.1,
                    l1: b.0,
                    r1: b.1,
                    depth,
                });
            }
        }
    }

    /// Resolve into a depth map (`+∞` where uncovered).
    ///
    /// Per row, the bands (pieces spanning the row's whole height) are added by
    /// increasing depth and joined into components when they overlap at both of the
    /// row's ordinates — then, the left boundary of a convex piece being convex and
    /// the right one concave, they overlap at every ordinate in between, so the union
    /// of a component is an interval at each ordinate. A component covers the
    /// abscissae `[min L, max R]`, with `L = max(l₀, l₁)` and `R = min(r₀, r₁)` of
    /// its members; a pixel inside it is entirely covered.
    pub(crate) fn finish(mut self) -> DepthMap {
        let n = self.n;
        let mut depth = vec![f32::INFINITY; n * n];
        let mut comps: Vec<Component> = Vec::new();
        let mut hits: Vec<usize> = Vec::new();
        for (j, row) in self.rows.iter_mut().enumerate() {
            if row.is_empty() {
                continue;
            }
            row.sort_by(|a, b| a.depth.total_cmp(&b.depth));
            comps.clear();
            let out = &mut depth[j * n..(j + 1) * n];
            for k in 0..row.len() {
                let b = row[k];
                // The components `b` joins: those with a member overlapping it at both
                // ordinates (their hull at the two ordinates is a cheap first filter).
                hits.clear();
                for (c, comp) in comps.iter().enumerate() {
                    if comp.alive
                        && comp.hull.overlaps(&b)
                        && comp.members.iter().any(|&m| row[m].overlaps(&b))
                    {
                        hits.push(c);
                    }
                }
                let own = (b.l0.max(b.l1), b.r0.min(b.r1));
                let (target, skip) =
                    match hits.iter().copied().max_by_key(|&c| comps[c].members.len()) {
                        None => {
                            comps.push(Component {
                                members: vec![k],
                                hull: b,
                                span: own,
                                alive: true,
                            });
                            (comps.len() - 1, (0.0, -1.0))
                        }
                        Some(t) => {
                            let skip = comps[t].span;
                            for &c in hits.iter().filter(|&&c| c != t) {
                                let other = std::mem::take(&mut comps[c].members);
                                let (h, sp) = (comps[c].hull, comps[c].span);
                                comps[c].alive = false;
                                let tc = &mut comps[t];
                                tc.members.extend(other);
                                tc.hull = tc.hull.hull(&h);
                                tc.span = (tc.span.0.min(sp.0), tc.span.1.max(sp.1));
                            }
                            let tc = &mut comps[t];
                            tc.members.push(k);
                            tc.hull = tc.hull.hull(&b);
                            tc.span = (tc.span.0.min(own.0), tc.span.1.max(own.1));
                            (t, skip)
                        }
                    };
                let (lo, hi) = comps[target].span;
                if !(hi > lo) {
                    continue;
                }
                // Pixels of the largest earlier component were assigned with a smaller
                // depth; the others are assigned only where still uncovered.
                let (s0, s1) = (skip.0.ceil(), skip.1.floor());
                let i0 = lo.ceil().max(0.0) as i64;
                let i1 = (hi.floor() as i64).min(n as i64);
                for i in i0..i1 {
                    let f = i as f64;
                    if f >= s0 && f + 1.0 <= s1 {
                        continue;
                    }
                    let px = &mut out[i as usize];
                    if px.is_infinite() {
                        *px = b.depth;
                    }
                }
            }
        }
        DepthMap::new(n, depth)
    }
}

/// Bands joined into one component of a row: their union is an interval at every
/// ordinate of the row, and it covers the abscissae `span` over the row's height.
struct Component {
    members: Vec<usize>,
    /// The hull of the members' extents at the two ordinates.
    hull: Band,
    span: (f64, f64),
    alive: bool,
}

/// A convex piece's extent along one pixel row `[j, j+1]`: `[l0, r0]` at ordinate `j`,
/// `[l1, r1]` at `j + 1`.
#[derive(Clone, Copy, Debug)]
struct Band {
    l0: f64,
    r0: f64,
    l1: f64,
    r1: f64,
    depth: f32,
}

impl Band {
    /// The smallest band containing both at each ordinate.
    fn hull(&self, o: &Band) -> Band {
        Band {
            l0: self.l0.min(o.l0),
            r0: self.r0.max(o.r0),
            l1: self.l1.min(o.l1),
            r1: self.r1.max(o.r1),
            depth: self.depth.max(o.depth),
        }
    }

    /// Overlap at both ordinates (hence at every ordinate between, by convexity).
    fn overlaps(&self, o: &Band) -> bool {
        let t = MERGE_TOL_PX;
        self.r0 >= o.l0 - t && o.r0 >= self.l0 - t && self.r1 >= o.l1 - t && o.r1 >= self.l1 - t
    }
}

/// An extended depth map with its max-depth pyramid (the Hierarchical Depth Map of
/// §2.4, after Greene et al.): level 0 is the full map, each level above keeps the
/// maximum of 2×2 children, so a node whose maximum is below an occludee's depth
/// proves the whole node hidden.
pub struct DepthMap {
    pub n: usize,
    levels: Vec<(usize, Vec<f32>)>,
    /// The covered (finite-depth) pixels, for the "fully visible" test of §6.1.
    covered: SummedArea,
}

impl DepthMap {
    /// `n` must be a power of two.
    pub(crate) fn new(n: usize, depth: Vec<f32>) -> Self {
        let covered = SummedArea::new(n, |k| depth[k].is_finite());
        let mut levels: Vec<(usize, Vec<f32>)> = Vec::new();
        let mut cur = (n, depth);
        while cur.0 > 1 {
            let (m, prev) = (cur.0, &cur.1);
            let h = m / 2;
            let next = reduce2x2::<f32, Max>(m, m, prev, f32::INFINITY).2;
            levels.push(std::mem::replace(&mut cur, (h, next)));
        }
        levels.push(cur);
        DepthMap { n, levels, covered }
    }

    /// Depth of pixel `(i, j)`.
    pub fn at(&self, i: usize, j: usize) -> f32 {
        self.levels[0].1[j * self.n + i]
    }

    /// Number of covered pixels.
    pub fn covered(&self) -> usize {
        self.covered.count()
    }

    /// Whether some pixel of the inclusive range is covered.
    pub(crate) fn any_covered(&self, r: [usize; 4]) -> bool {
        self.covered.count_in(r) > 0
    }

    /// Whether every pixel of the inclusive range `[i0, i1] × [j0, j1]` has a depth
    /// strictly below `d`.
    pub(crate) fn all_below(&self, i0: usize, j0: usize, i1: usize, j1: usize, d: f32) -> bool {
        let top = self.levels.len() - 1;
        self.node_below(top, 0, 0, [i0, j0, i1, j1], d)
    }

    fn node_below(&self, level: usize, i: usize, j: usize, r: [usize; 4], d: f32) -> bool {
        let (m, ref data) = self.levels[level];
        if data[j * m + i] < d {
            return true;
        }
        if level == 0 {
            return false;
        }
        let span = self.n / m; // pixels per node at this level
        let half = span / 2;
        for (ci, cj) in [
            (2 * i, 2 * j),
            (2 * i + 1, 2 * j),
            (2 * i, 2 * j + 1),
            (2 * i + 1, 2 * j + 1),
        ] {
            let (x0, y0) = (ci * half, cj * half);
            let (x1, y1) = (x0 + half - 1, y0 + half - 1);
            if x1 < r[0] || x0 > r[2] || y1 < r[1] || y0 > r[3] {
                continue;
            }
            if !self.node_below(level - 1, ci, cj, r, d) {
                return false;
            }
        }
        true
    }
}

/// The pixels a closed rectangle (continuous pixel coordinates) touches, as an
/// inclusive range, or `None` when it leaves the map (it cannot be proven hidden).
pub fn pixel_range(min: DVec2, max: DVec2, n: usize) -> Option<[usize; 4]> {
    if !(min.x >= 0.0 && min.y >= 0.0 && max.x <= n as f64 && max.y <= n as f64) {
        return None;
    }
    // Pixel i covers [i, i+1]; touching counts (a point on a pixel border needs both).
    let i0 = (min.x.ceil() as i64 - 1).max(0) as usize;
    let j0 = (min.y.ceil() as i64 - 1).max(0) as usize;
    let i1 = (max.x.floor() as usize).min(n - 1);
    let j1 = (max.y.floor() as usize).min(n - 1);
    Some([i0.min(i1), j0.min(j1), i1, j1])
}

/// A summed-area table of a binary `n × n` map: the number of set pixels in any
/// rectangle in O(1).
#[derive(Clone)]
pub(crate) struct SummedArea {
    n: usize,
    sat: Vec<u32>,
}

impl SummedArea {
    pub(crate) fn new(n: usize, set: impl Fn(usize) -> bool) -> Self {
        let w = n + 1;
        let mut sat = vec![0u32; w * w];
        for j in 0..n {
            let mut row = 0u32;
            for i in 0..n {
                row += set(j * n + i) as u32;
                sat[(j + 1) * w + i + 1] = sat[j * w + i + 1] + row;
            }
        }
        SummedArea { n, sat }
    }

    /// Set pixels in the inclusive range `[i0, i1] × [j0, j1]`.
    pub(crate) fn count_in(&self, r: [usize; 4]) -> usize {
        let w = self.n + 1;
        let [i0, j0, i1, j1] = r;
        (self.sat[(j1 + 1) * w + i1 + 1] + self.sat[j0 * w + i0]
            - self.sat[j0 * w + i1 + 1]
            - self.sat[(j1 + 1) * w + i0]) as usize
    }

    /// Set pixels in the whole map.
    pub(crate) fn count(&self) -> usize {
        self.sat[(self.n + 1) * (self.n + 1) - 1] as usize
    }
}

/// The pixels a closed rectangle (continuous pixel coordinates) touches, clipped to
/// the map, or `None` when it misses the map.
pub(crate) fn clipped_pixel_range(min: DVec2, max: DVec2, n: usize) -> Option<[usize; 4]> {
    let nf = n as f64;
    if !(max.x >= 0.0 && max.y >= 0.0 && min.x <= nf && min.y <= nf) {
        return None;
    }
    pixel_range(min.max(DVec2::ZERO), max.min(DVec2::splat(nf)), n)
}

/// A binary occlusion map with a summed-area table, for the occlusion sweep (§5):
/// "we only keep the black pixels".
#[derive(Clone)]
pub struct OcclusionMap {
    pub n: usize,
    pub black: Vec<bool>,
    sat: SummedArea,
}

impl OcclusionMap {
    pub(crate) fn new(n: usize, black: Vec<bool>) -> Self {
        let sat = SummedArea::new(n, |k| black[k]);
        OcclusionMap { n, black, sat }
    }

    /// Whether every pixel of the inclusive range is black.
    pub(crate) fn all_black(&self, r: [usize; 4]) -> bool {
        let [i0, j0, i1, j1] = r;
        self.sat.count_in(r) == (i1 + 1 - i0) * (j1 + 1 - j0)
    }

    /// Whether some pixel of the inclusive range is black.
    pub(crate) fn any_black(&self, r: [usize; 4]) -> bool {
        self.sat.count_in(r) > 0
    }

    pub fn count(&self) -> usize {
        self.sat.count()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
        vec![
            DVec2::new(x0, y0),
            DVec2::new(x1, y0),
            DVec2::new(x1, y1),
            DVec2::new(x0, y1),
        ]
    }

    #[test]
    fn inner_coverage_keeps_only_full_pixels() {
        let mut b = CoverageBuilder::new(8);
        b.add_convex(&rect(1.5, 1.0, 4.0, 3.2), 1.0);
        let m = b.finish();
        assert!(m.at(1, 1).is_infinite()); // half covered
        assert_eq!(m.at(2, 1), 1.0);
        assert_eq!(m.at(3, 2), 1.0);
        assert!(m.at(3, 3).is_infinite()); // 0.2 covered in y
        assert_eq!(m.covered(), 4);
    }

    /// Two triangles sharing a diagonal cover the square without a crack.
    #[test]
    fn union_of_pieces_has_no_crack() {
        let mut b = CoverageBuilder::new(8);
        b.add_convex(
            &[
                DVec2::new(0.0, 0.0),
                DVec2::new(8.0, 0.0),
                DVec2::new(8.0, 8.0),
            ],
            2.0,
        );
        b.add_convex(
            &[
                DVec2::new(0.0, 0.0),
                DVec2::new(8.0, 8.0),
                DVec2::new(0.0, 8.0),
            ],
            1.0,
        );
        let m = b.finish();
        assert_eq!(m.covered(), 64);
        // Pixels wholly inside the nearer piece keep its depth; mixed ones the larger.
        assert_eq!(m.at(0, 7), 1.0);
        assert_eq!(m.at(3, 3), 2.0);
        assert_eq!(m.at(7, 0), 2.0);
    }

    /// Random convex pieces, many overlapping: every pixel given depth `d` must lie
    /// inside the union of the pieces of depth ≤ `d` (checked on a grid of points of
    /// the pixel, its border included), and a chain of pieces each overlapping the
    /// next fuses into one component.
    #[test]
    fn union_coverage_is_conservative() {
        let mut s = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let n = 32;
        for _ in 0..20 {
            let mut b = CoverageBuilder::new(n);
            let mut polys: Vec<(Vec<DVec2>, f32)> = Vec::new();
            for _ in 0..12 {
                let c = DVec2::new(rnd() * 32.0, rnd() * 32.0);
                let r = 2.0 + rnd() * 8.0;
                let a0 = rnd() * 6.3;
                let poly: Vec<DVec2> = (0..5)
                    .map(|k| {
                        let a = a0 + k as f64 * std::f64::consts::TAU / 5.0;
                        c + DVec2::new(a.cos(), a.sin()) * r
                    })
                    .collect();
                let d = (rnd() * 4.0) as f32;
                b.add_convex(&poly, d);
                polys.push((poly, d));
            }
            let m = b.finish();
            let inside = |poly: &[DVec2], q: DVec2| {
                (0..poly.len()).all(|i| {
                    let (a, c) = (poly[i], poly[(i + 1) % poly.len()]);
                    (c - a).perp_dot(q - a) >= -1e-9
                })
            };
            for j in 0..n {
                for i in 0..n {
                    let d = m.at(i, j);
                    if !d.is_finite() {
                        continue;
                    }
                    for sj in 0..=4 {
                        for si in 0..=4 {
                            let q =
                                DVec2::new(i as f64 + si as f64 / 4.0, j as f64 + sj as f64 / 4.0);
                            assert!(
                                polys.iter().any(|(p, pd)| *pd <= d && inside(p, q)),
                                "pixel ({i}, {j}) at depth {d}: {q:?} uncovered"
                            );
                        }
                    }
                }
            }
        }
        // A chain of three overlapping squares, the middle one farthest.
        let mut b = CoverageBuilder::new(16);
        b.add_convex(&rect(0.0, 0.0, 6.0, 16.0), 1.0);
        b.add_convex(&rect(5.0, 0.0, 11.0, 16.0), 3.0);
        b.add_convex(&rect(10.0, 0.0, 16.0, 16.0), 2.0);
        let m = b.finish();
        assert_eq!(m.covered(), 256);
        assert_eq!((m.at(0, 3), m.at(7, 3), m.at(15, 3)), (1.0, 3.0, 2.0));
    }

    #[test]
    fn pyramid_range_queries() {
        let mut b = CoverageBuilder::new(16);
        b.add_convex(&rect(0.0, 0.0, 16.0, 8.0), 1.0);
        b.add_convex(&rect(0.0, 8.0, 8.0, 16.0), 3.0);
        let m = b.finish();
        assert!(m.all_below(0, 0, 15, 7, 1.5));
        assert!(!m.all_below(0, 0, 15, 8, 1.5));
        assert!(m.all_below(0, 0, 7, 15, 3.5));
        assert!(!m.all_below(0, 0, 8, 15, 3.5));
        assert!(!m.all_below(0, 0, 0, 0, 1.0)); // ties are visible
    }

    #[test]
    fn pixel_ranges_include_touched_pixels() {
        assert_eq!(
            pixel_range(DVec2::new(1.0, 1.5), DVec2::new(2.0, 1.5), 8),
            Some([0, 1, 2, 1])
        );
        assert_eq!(
            pixel_range(DVec2::new(-0.1, 0.0), DVec2::new(1.0, 1.0), 8),
            None
        );
    }

    #[test]
    fn summed_area_all_black() {
        let mut black = vec![false; 16];
        for j in 1..3 {
            for i in 1..4 {
                black[j * 4 + i] = true;
            }
        }
        let m = OcclusionMap::new(4, black);
        assert!(m.all_black([1, 1, 3, 2]));
        assert!(!m.all_black([0, 1, 3, 2]));
        assert!(m.any_black([0, 0, 1, 1]) && !m.any_black([0, 0, 3, 0]));
        assert_eq!(m.count(), 6);
    }

    #[test]
    fn clipped_ranges_and_covered_pixels() {
        let n = 8;
        assert_eq!(
            clipped_pixel_range(DVec2::new(-3.0, 2.5), DVec2::new(2.5, 20.0), n),
            Some([0, 2, 2, 7])
        );
        assert_eq!(
            clipped_pixel_range(DVec2::new(9.0, 0.0), DVec2::new(12.0, 4.0), n),
            None
        );
        let mut depth = vec![f32::INFINITY; n * n];
        depth[3 * n + 5] = 1.0;
        let m = DepthMap::new(n, depth);
        assert!(m.any_covered([5, 3, 5, 3]) && m.any_covered([0, 0, 7, 7]));
        assert!(!m.any_covered([0, 0, 4, 7]) && !m.any_covered([5, 4, 7, 7]));
        assert_eq!(m.covered(), 1);
    }
}
