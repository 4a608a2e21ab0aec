//! Virtual occluders of a viewcell — Koltun, Chrysanthou & Cohen-Or, *Virtual occluders:
//! an efficient intermediate PVS representation* (EGWR 2000), in the 2.5D setting of
//! `dual-ray`.
//!
//! A **virtual occluder** of a cell `A` is a vertical rectangle `V` on a plane
//! `along = c` (along one axis, beyond the cell), spanning `[y0, y1]` across and every
//! height up to `h`, that is *hidden from `A`*: every segment from the cell to a point of
//! `V` is blocked by the real occluders. It is proven with the very box-to-box test of
//! the kd-nodes (§3–§5 of Koltun et al. 2001) applied to a thin box around `V`; a test
//! decides only from the boxes' tops and the occluders between the two faces, so the
//! proof holds for every point of the box down to any depth. `V` is generally not a
//! face of any building: it stands where the fused occluders in front of it (a row of
//! blocks, the streets between them) hide a whole band of the plane — the paper's
//! "fused near occluders".
//!
//! **Why an occludee hidden by virtual occluders is hidden.** Let `M` lie wholly beyond
//! the plane (the cell wholly before it). Every segment from a point `a` of the cell to
//! a point `m` of `M` crosses the plane at a point `p` of `conv(A ∪ M)`; if every such
//! crossing lies in a virtual occluder, the part `a → p` is blocked, so `a → m` is. The
//! crossing parameter's extremes come from two corner pairs of the boxes, and the
//! crossings within a segment of the plane have their heights bounded at the ends of
//! their parameter interval (`Crossings`); every segment the crossings meet must hold
//! at that height (closed intervals, no gap). Hence a node hidden by the virtual
//! occluders is hidden from every point of the cell, and the PVS keeps its guarantee.
//! It can only shrink: a node is dropped by the virtual occluders or by its own test,
//! whichever comes first.
//!
//! The rectangles are the dyadic segments of a band spanning the scene across each
//! plane, proven **lazily**, at a ladder of heights: a node's query proves (once per
//! cell, memoized) only the segments its crossing bound meets, coarse ones first, halving
//! where a segment does not hold, down to a minimal width. Whether a segment holds at a
//! height is a function of the cell alone, so the answer to a query does not depend on
//! the order of the queries; and a planar method that hides more (the exact one) proves
//! every segment the discretized one proves, so its virtual occluders hide at least as
//! much: `dual-ray` keeps containing `dual-ray-exact`.
//!
//! `dual-ray` builds them for each strip of a cell (`Strips` in the parent module), on
//! planes parallel to the strip just beyond it, when the strips are turned on.

use super::occluders::Axis;
use sightline_geom::{Aabb3, DVec3};
use std::collections::HashMap;

/// Distances from the cell to the planes, in metres: just beyond the cell, where the
/// row of buildings along a street the cell opens onto hides a plane parallel to the
/// street far along it (rays from the street enter the row at grazing angles).
const PLANE_DISTANCES_M: [f64; 2] = [5.0, 20.0];

/// Number of heights of [`HEIGHTS_ABOVE_CELL_M`].
const LEVELS: usize = 4;

/// Heights proven for a segment, above the cell's top (metres), lowest first.
const HEIGHTS_ABOVE_CELL_M: [f64; LEVELS] = [6.0, 12.0, 24.0, 48.0];

/// A segment is not halved below this width (metres).
const MIN_WIDTH_M: f64 = 25.0;

/// A segment is proven only if it is at most this many times as wide as its distance
/// from the cell across (and at most [`NEAR_WIDTH_M`] near the cell): wider ones would
/// need a shaft as wide as the city, their halves are tried instead.
const WIDTH_PER_DISTANCE: f64 = 1.0;
const NEAR_WIDTH_M: f64 = 200.0;

/// Planes whose band would be wider than this (metres) are not built.
const MAX_BAND_M: f64 = 1e7;

/// Thickness of the thin box proven for a segment (metres): any positive value works,
/// the proof covers the whole box.
const THICKNESS_M: f64 = 0.25;

/// Outward margins of a crossing's bounds (metres, and of its parameter): rounding
/// must never shrink them.
const MARGIN_M: f64 = 1e-6;
const MARGIN_T: f64 = 1e-9;

/// A box's footprint in a plane's frame: `(along0, along1, across0, across1)`.
#[inline]
fn span(b: &Aabb3, axis: Axis, sign: f64) -> (f64, f64, f64, f64) {
    let (a0, a1, c0, c1) = match axis {
        Axis::X => (b.min.x, b.max.x, b.min.y, b.max.y),
        Axis::Y => (b.min.y, b.max.y, b.min.x, b.max.x),
    };
    if sign > 0.0 {
        (a0, a1, c0, c1)
    } else {
        (-a1, -a0, c0, c1)
    }
}

/// The crossings of the plane `along = c` by the segments from a cell `a` to a box `m`
/// (footprints in the plane's frame, `a` wholly before the plane, `m` wholly beyond).
///
/// A crossing has parameter `t = (c − x_a) / (x_m − x_a)`, which decreases in both `x_a`
/// and `x_m`, so `t ∈ [t_min, t_max]` from two corner pairs; at a given `t` its `y` spans
/// `[lo(t), hi(t)]`, both linear in `t`, and its height is at most `(1 − t)·a_top +
/// t·m_top`. So the crossings whose `y` lies in a segment `[s0, s1]` have `t` in an
/// interval, and their heights a bound at its ends ([`Crossings::top_within`]).
#[derive(Clone, Copy, Debug)]
struct Crossings {
    t_min: f64,
    t_max: f64,
    ay: (f64, f64),
    my: (f64, f64),
    a_top: f64,
    m_top: f64,
}

impl Crossings {
    fn new(
        c: f64,
        (ax0, ax1, ay0, ay1): (f64, f64, f64, f64),
        a_top: f64,
        (mx0, mx1, my0, my1): (f64, f64, f64, f64),
        m_top: f64,
    ) -> Self {
        let t_min = ((c - ax1) / (mx1 - ax1) - MARGIN_T).max(0.0);
        let t_max = ((c - ax0) / (mx0 - ax0) + MARGIN_T).min(1.0);
        Crossings {
            t_min,
            t_max,
            ay: (ay0, ay1),
            my: (my0, my1),
            a_top,
            m_top,
        }
    }

    /// The `y` range of all crossings, widened by the rounding margin.
    fn y_range(&self) -> (f64, f64) {
        let mut lo = f64::INFINITY;
        let mut hi = f64::NEG_INFINITY;
        for t in [self.t_min, self.t_max] {
            lo = lo.min((1.0 - t) * self.ay.0 + t * self.my.0);
            hi = hi.max((1.0 - t) * self.ay.1 + t * self.my.1);
        }
        let e = MARGIN_M * (1.0 + lo.abs().max(hi.abs()));
        (lo - e, hi + e)
    }

    /// An upper bound of the heights of the crossings with `y` in `[s0, s1]`, or `None`
    /// when there is none.
    fn top_within(&self, s0: f64, s1: f64) -> Option<f64> {
        let e = MARGIN_M * (1.0 + s0.abs().max(s1.abs()));
        let (s0, s1) = (s0 - e, s1 + e);
        let (mut t0, mut t1) = (self.t_min, self.t_max);
        // lo(t) = ay0 + t (my0 − ay0) <= s1 and hi(t) = ay1 + t (my1 − ay1) >= s0.
        for (base, slope, bound, upper) in [
            (self.ay.0, self.my.0 - self.ay.0, s1, true),
            (self.ay.1, self.my.1 - self.ay.1, s0, false),
        ] {
            // `upper`: base + t·slope <= bound; else base + t·slope >= bound.
            let sg = if upper { slope } else { -slope };
            let room = if upper { bound - base } else { base - bound };
            if sg > 0.0 {
                t1 = t1.min(room / sg + MARGIN_T);
            } else if sg < 0.0 {
                t0 = t0.max(room / sg - MARGIN_T);
            } else if room < 0.0 {
                return None;
            }
        }
        if t0 > t1 {
            return None;
        }
        let z = |t: f64| (1.0 - t) * self.a_top + t * self.m_top;
        let top = z(t0).max(z(t1));
        Some(top + MARGIN_M * (1.0 + top.abs()))
    }
}

/// The virtual occluders on one plane `along = c` (along coordinate multiplied by
/// `sign`, so the plane always faces away from the cell in increasing `along`).
#[derive(Clone, Debug)]
struct VoPlane {
    axis: Axis,
    sign: f64,
    c: f64,
    /// Lowest height the segments' proofs cover.
    floor_z: f64,
    /// The band `[b0, b0 + width]` across, halved `depth` times at most.
    b0: f64,
    width: f64,
    depth: u32,
    /// The cell's across range: segments are measured from it.
    cell_y: (f64, f64),
    /// `(depth, index, height level)` → proven hidden.
    memo: HashMap<(u32, u32, u8), bool>,
}

impl VoPlane {
    /// The thin box proven for the segment `[y0, y1]`, heights `(floor_z, h]`.
    fn thin_box(&self, y0: f64, y1: f64, h: f64) -> Aabb3 {
        let (a0, a1) = if self.sign > 0.0 {
            (self.c, self.c + THICKNESS_M)
        } else {
            (-self.c - THICKNESS_M, -self.c)
        };
        let (min, max) = match self.axis {
            Axis::X => (DVec3::new(a0, y0, self.floor_z), DVec3::new(a1, y1, h)),
            Axis::Y => (DVec3::new(y0, a0, self.floor_z), DVec3::new(y1, a1, h)),
        };
        Aabb3::new(min, max)
    }

    /// The segment `index` of `depth`.
    #[inline]
    fn segment(&self, depth: u32, index: u32) -> (f64, f64) {
        let w = self.width / (1u64 << depth) as f64;
        (self.b0 + index as f64 * w, self.b0 + (index + 1) as f64 * w)
    }

    /// Whether the segment holds at height level `k`, proving it with `prove` if
    /// neither it nor a level above (hidden) or below (visible) is known.
    fn holds(
        &mut self,
        depth: u32,
        index: u32,
        k: u8,
        heights: &[f64; LEVELS],
        tests: &mut u64,
        prove: &mut impl FnMut(&Aabb3, Axis) -> bool,
    ) -> bool {
        let levels = heights.len() as u8;
        for j in k..levels {
            if self.memo.get(&(depth, index, j)) == Some(&true) {
                return true;
            }
        }
        for j in 0..=k {
            if self.memo.get(&(depth, index, j)) == Some(&false) {
                return false;
            }
        }
        let (y0, y1) = self.segment(depth, index);
        let far = (y0 - self.cell_y.1).max(self.cell_y.0 - y1).max(0.0);
        let ok = if y1 - y0 > NEAR_WIDTH_M.max(WIDTH_PER_DISTANCE * far) {
            false
        } else {
            *tests += 1;
            prove(&self.thin_box(y0, y1, heights[k as usize]), self.axis)
        };
        self.memo.insert((depth, index, k), ok);
        ok
    }

    /// Whether the segments of the plane hold over every crossing of `q` (each
    /// segment at the height of the crossings within it).
    fn covers(
        &mut self,
        depth: u32,
        index: u32,
        q: &Crossings,
        heights: &[f64; LEVELS],
        tests: &mut u64,
        prove: &mut impl FnMut(&Aabb3, Axis) -> bool,
    ) -> bool {
        let (s0, s1) = self.segment(depth, index);
        let Some(top) = q.top_within(s0, s1) else {
            return true;
        };
        if let Some(k) = heights.iter().position(|h| *h >= top) {
            if self.holds(depth, index, k as u8, heights, tests, prove) {
                return true;
            }
        }
        depth < self.depth
            && self.covers(depth + 1, 2 * index, q, heights, tests, prove)
            && self.covers(depth + 1, 2 * index + 1, q, heights, tests, prove)
    }
}

/// The virtual occluders of one cell, proven on demand.
#[derive(Clone, Debug, Default)]
pub(crate) struct VirtualOccluders {
    cell: Option<Aabb3>,
    planes: Vec<VoPlane>,
    heights: [f64; LEVELS],
    /// Box-to-box tests spent proving segments.
    pub tests: u64,
}

impl VirtualOccluders {
    /// The (not yet proven) virtual occluders of the cell `a` (local frame) on planes
    /// normal to `axes`, on both sides, in a scene whose occludees lie in `scene`
    /// (`scene.min.z` at most their lowest point).
    pub(crate) fn new(a: &Aabb3, scene: &Aabb3, axes: &[Axis]) -> Self {
        // A metre lower: the crossing bounds' margin must not cross it.
        let floor_z = scene.min.z.min(a.min.z) - 1.0;
        let all = scene.union(*a);
        let mut planes = Vec::new();
        for d in PLANE_DISTANCES_M {
            for &axis in axes {
                for sign in [1.0, -1.0] {
                    let (_, ax1, ay0, ay1) = span(a, axis, sign);
                    let (_, _, b0, b1) = span(&all, axis, sign);
                    let (b0, b1) = (b0 - 1.0, b1 + 1.0);
                    if !((b1 - b0).is_finite() && b1 - b0 <= MAX_BAND_M) {
                        continue; // a cell or scene beyond any city: no plane
                    }
                    let depth = ((b1 - b0) / MIN_WIDTH_M).log2().ceil().clamp(0.0, 24.0) as u32;
                    planes.push(VoPlane {
                        axis,
                        sign,
                        c: ax1 + d,
                        floor_z,
                        b0,
                        width: b1 - b0,
                        depth,
                        cell_y: (ay0, ay1),
                        memo: HashMap::new(),
                    });
                }
            }
        }
        VirtualOccluders {
            cell: Some(*a),
            planes,
            heights: HEIGHTS_ABOVE_CELL_M.map(|h| a.max.z + h),
            tests: 0,
        }
    }

    /// Whether the virtual occluders hide the box `m` from the cell: every segment from
    /// the cell to `m` crosses one plane inside its proven segments. Segments are proven
    /// on demand with `prove(thin box, plane normal)`.
    pub(crate) fn hides(&mut self, m: &Aabb3, mut prove: impl FnMut(&Aabb3, Axis) -> bool) -> bool {
        let Some(a) = self.cell else {
            return false;
        };
        let heights = self.heights;
        for p in &mut self.planes {
            let sa = span(&a, p.axis, p.sign);
            let sm = span(m, p.axis, p.sign);
            if !(sa.1 < p.c && p.c <= sm.0) {
                continue;
            }
            // Crossings are no lower than the lower of the two boxes' bottoms.
            if a.min.z.min(m.min.z) < p.floor_z + 0.5 {
                continue;
            }
            let q = Crossings::new(p.c, sa, a.max.z, sm, m.max.z);
            let (ylo, yhi) = q.y_range();
            if !(ylo >= p.b0 && yhi <= p.b0 + p.width) {
                continue;
            }
            if p.covers(0, 0, &q, &heights, &mut self.tests, &mut prove) {
                return true;
            }
        }
        false
    }

    /// Segments proven hidden so far (at any height).
    pub(crate) fn count(&self) -> usize {
        self.planes
            .iter()
            .map(|p| p.memo.values().filter(|v| **v).count())
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bx(x0: f64, y0: f64, z0: f64, x1: f64, y1: f64, z1: f64) -> Aabb3 {
        Aabb3::new(DVec3::new(x0, y0, z0), DVec3::new(x1, y1, z1))
    }

    #[test]
    fn crossing_heights_within_a_segment_bound_every_segment_crossing() {
        // Brute force: segments between grid points of both boxes, crossings binned by
        // their `y` into segments of 20 m.
        let cell = bx(-20.0, -5.0, 1.0, 30.0, 40.0, 3.0);
        let m = bx(150.0, 60.0, 0.0, 400.0, 90.0, 25.0);
        let c = 100.0;
        let pts = |b: &Aabb3| {
            let f = |lo: f64, hi: f64, s: usize, n: usize| lo + (hi - lo) * s as f64 / n as f64;
            let mut v = Vec::new();
            for i in 0..=6 {
                for j in 0..=6 {
                    for k in 0..=2 {
                        v.push(DVec3::new(
                            f(b.min.x, b.max.x, i, 6),
                            f(b.min.y, b.max.y, j, 6),
                            f(b.min.z, b.max.z, k, 2),
                        ));
                    }
                }
            }
            v
        };
        let q = Crossings::new(
            c,
            span(&cell, Axis::X, 1.0),
            3.0,
            span(&m, Axis::X, 1.0),
            25.0,
        );
        let (ylo, yhi) = q.y_range();
        let mut seen_top = [f64::NEG_INFINITY; 10];
        for p in pts(&cell) {
            for r in pts(&m) {
                let x = p + (r - p) * ((c - p.x) / (r.x - p.x));
                assert!(x.y >= ylo && x.y <= yhi, "{x} outside {ylo}..{yhi}");
                let s0 = -20.0 + 20.0 * ((x.y + 20.0) / 20.0).floor();
                let top = q
                    .top_within(s0, s0 + 20.0)
                    .expect("a crossing in this segment");
                assert!(x.z <= top, "{x}: above {top}");
                let i = ((x.y + 20.0) / 20.0).floor() as usize;
                seen_top[i.min(9)] = seen_top[i.min(9)].max(x.z);
            }
        }
        // Tight enough to matter: the nearest segment's bound is far under the top.
        let first = (0..10)
            .find(|i| seen_top[*i] > f64::NEG_INFINITY)
            .expect("crossings");
        let s0 = -20.0 + 20.0 * first as f64;
        assert!(q.top_within(s0, s0 + 20.0).expect("crossings") < 15.0);
        assert!(q.top_within(500.0, 520.0).is_none());
    }

    /// Every thin box below `limit` within `x ∈ [12, 2000]`, `y ∈ [y0, y1]` is "hidden".
    fn oracle(y0: f64, y1: f64, limit: f64) -> impl FnMut(&Aabb3, Axis) -> bool {
        move |b, _| {
            b.min.x >= 12.0
                && b.max.x <= 2000.0
                && b.min.y >= y0
                && b.max.y <= y1
                && b.max.z <= limit
        }
    }

    #[test]
    fn a_node_is_hidden_only_where_proven_segments_cover_its_crossings() {
        let cell = bx(0.0, 0.0, 1.5, 10.0, 10.0, 2.0);
        let scene = bx(-2000.0, -2000.0, 0.0, 2000.0, 2000.0, 100.0);
        let mut vo = VirtualOccluders::new(&cell, &scene, &[Axis::X, Axis::Y]);
        let low = bx(300.0, 0.0, 0.0, 320.0, 20.0, 20.0);
        assert!(vo.hides(&low, oracle(-500.0, 500.0, 30.0)));
        assert!(vo.count() > 0 && vo.tests > 0);
        // Too tall for the proven heights; straddling the planes; past the proven band.
        let mut vo = VirtualOccluders::new(&cell, &scene, &[Axis::X, Axis::Y]);
        assert!(!vo.hides(
            &bx(300.0, 0.0, 0.0, 320.0, 20.0, 2000.0),
            oracle(-500.0, 500.0, 30.0)
        ));
        assert!(!vo.hides(
            &bx(5.0, 0.0, 0.0, 1900.0, 20.0, 10.0),
            oracle(-500.0, 500.0, 30.0)
        ));
        assert!(!vo.hides(
            &bx(300.0, 400.0, 0.0, 320.0, 420.0, 10.0),
            oracle(-50.0, 5.0, 30.0)
        ));
    }

    #[test]
    fn mirrored_planes_face_away_from_the_cell() {
        let cell = bx(0.0, 0.0, 1.5, 10.0, 10.0, 2.0);
        let scene = bx(-2000.0, -2000.0, 0.0, 2000.0, 2000.0, 100.0);
        // Only boxes below y = 0 are "hidden": a node below is hidden, one above is not.
        let below = |b: &Aabb3, _: Axis| b.max.y <= 0.0 && b.max.z <= 30.0;
        let mut vo = VirtualOccluders::new(&cell, &scene, &[Axis::X, Axis::Y]);
        assert!(vo.hides(&bx(0.0, -400.0, 0.0, 20.0, -380.0, 10.0), below));
        let mut vo = VirtualOccluders::new(&cell, &scene, &[Axis::X, Axis::Y]);
        assert!(!vo.hides(&bx(0.0, 380.0, 0.0, 20.0, 400.0, 10.0), below));
    }
}
