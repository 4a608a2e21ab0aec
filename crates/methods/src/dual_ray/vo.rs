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
//! crossings of a plane by segments between two boxes on either side form a convex
//! polygon whose extremes along `y` and `z` are reached at the extremes of the crossing
//! parameter, so four corner combinations bound it ([`VirtualOccluders::hides`]); the
//! union of the rectangles must cover that bound (closed intervals, no gap). Hence a
//! node hidden by the virtual occluders is hidden from every point of the cell, and the
//! PVS keeps its guarantee. It can only shrink: a node is dropped by the virtual
//! occluders or by its own test, whichever comes first.
//!
//! The rectangles are found by a fixed, result-driven subdivision: on each plane a band
//! of the width the cell sees at that distance is proven at a few heights, highest
//! first, and halved where no height holds, down to a minimal width, within a budget of
//! tests per cell. The order of the candidates depends only on the cell, and a planar
//! method that hides more (the exact one) accepts a rectangle at the same or an earlier
//! candidate, so its virtual occluders cover at least as much: `dual-ray` keeps
//! containing `dual-ray-exact`.

use super::occluders::Axis;
use sightline_geom::{Aabb3, DVec3};

/// Distances from the cell to the planes, in metres: near enough that the fused
/// occluders in front of a plane hide most of it, spread so that each plane hides what
/// lies beyond the next.
const PLANE_DISTANCES_M: [f64; 2] = [80.0, 320.0];

/// Heights tried for a rectangle, above the cell's top, highest first (metres).
const HEIGHTS_ABOVE_CELL_M: [f64; 2] = [24.0, 8.0];

/// A band is not halved below this width (metres).
const MIN_WIDTH_M: f64 = 25.0;

/// Box-to-box tests spent on the virtual occluders of one cell, at most.
const MAX_TESTS: usize = 160;

/// Thickness of the thin box proven for a rectangle (metres): any positive value works,
/// the proof covers the whole box.
const THICKNESS_M: f64 = 0.25;

/// Outward margin of a crossing's bounds (metres): rounding must never shrink them.
const MARGIN_M: f64 = 1e-6;

/// A proven rectangle of a plane: across `[y0, y1]`, heights up to `h`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VoRect {
    pub y0: f64,
    pub y1: f64,
    pub h: f64,
}

/// The virtual occluders on one plane `along = c` (along coordinate multiplied by
/// `sign`, so the plane always faces away from the cell in increasing `along`).
#[derive(Clone, Debug)]
pub struct VoPlane {
    axis: Axis,
    sign: f64,
    c: f64,
    /// Lowest height the rectangles' proofs cover.
    floor_z: f64,
    /// Sorted by `y0`.
    rects: Vec<VoRect>,
}

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

impl VoPlane {
    /// The thin box proven for a rectangle `[y0, y1] × (floor_z, h]` of this plane.
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

    /// Whether every segment from `a` (the cell) to `m` crosses this plane inside its
    /// rectangles.
    fn hides(&self, a: &Aabb3, m: &Aabb3) -> bool {
        let (ax0, ax1, ay0, ay1) = span(a, self.axis, self.sign);
        let (mx0, mx1, my0, my1) = span(m, self.axis, self.sign);
        if !(ax1 < self.c && self.c <= mx0) {
            return false;
        }
        // The crossing parameter `t = (c − x_a) / (x_m − x_a)` decreases in both `x_a`
        // and `x_m`: its extremes are at these two corner pairs.
        let t_min = (self.c - ax1) / (mx1 - ax1);
        let t_max = (self.c - ax0) / (mx0 - ax0);
        let mut ylo = f64::INFINITY;
        let mut yhi = f64::NEG_INFINITY;
        let mut zlo = f64::INFINITY;
        let mut zhi = f64::NEG_INFINITY;
        for t in [t_min, t_max] {
            let s = 1.0 - t;
            ylo = ylo.min(s * ay0 + t * my0);
            yhi = yhi.max(s * ay1 + t * my1);
            zlo = zlo.min(s * a.min.z + t * m.min.z);
            zhi = zhi.max(s * a.max.z + t * m.max.z);
        }
        let e = MARGIN_M * (1.0 + ylo.abs().max(yhi.abs()).max(zhi.abs()));
        let (ylo, yhi, zlo, zhi) = (ylo - e, yhi + e, zlo - e, zhi + e);
        if !(zlo >= self.floor_z && ylo.is_finite() && yhi.is_finite() && zhi.is_finite()) {
            return false;
        }
        // Sweep the rectangles tall enough, in order of `y0`, from `ylo` up.
        let mut covered = ylo;
        for r in &self.rects {
            if r.y0 > covered {
                break;
            }
            if r.h >= zhi && r.y1 > covered {
                covered = r.y1;
                if covered >= yhi {
                    return true;
                }
            }
        }
        false
    }
}

/// The virtual occluders of one cell.
#[derive(Clone, Debug, Default)]
pub struct VirtualOccluders {
    planes: Vec<VoPlane>,
    /// Box-to-box tests spent building them.
    pub tests: usize,
}

impl VirtualOccluders {
    /// No virtual occluder: hides nothing.
    pub fn none() -> Self {
        VirtualOccluders::default()
    }

    /// The virtual occluders of the cell `a` (local frame), each rectangle proven by
    /// `hidden(a, thin box)`; `floor_z` is at most the lowest point of any occludee.
    pub(crate) fn build(
        a: &Aabb3,
        floor_z: f64,
        mut hidden: impl FnMut(&Aabb3) -> bool,
    ) -> Self {
        let mut out = VirtualOccluders::default();
        // A metre lower: the crossing bounds' margin must not cross it.
        let floor_z = floor_z.min(a.min.z) - 1.0;
        for d in PLANE_DISTANCES_M {
            for axis in [Axis::X, Axis::Y] {
                for sign in [1.0, -1.0] {
                    let (_, ax1, ay0, ay1) = span(a, axis, sign);
                    let mut plane = VoPlane {
                        axis,
                        sign,
                        c: ax1 + d,
                        floor_z,
                        rects: Vec::new(),
                    };
                    // The band the cell sees within 45° of the axis at this distance:
                    // the four axes together cover every direction.
                    let half = d + (ay1 - ay0);
                    let mut stack = vec![(ay0 - half, ay1 + half)];
                    while let Some((y0, y1)) = stack.pop() {
                        let mut proven = false;
                        for dh in HEIGHTS_ABOVE_CELL_M {
                            if out.tests >= MAX_TESTS {
                                break;
                            }
                            out.tests += 1;
                            let h = a.max.z + dh;
                            if hidden(&plane.thin_box(y0, y1, h)) {
                                plane.rects.push(VoRect { y0, y1, h });
                                proven = true;
                                break;
                            }
                        }
                        if !proven && y1 - y0 >= 2.0 * MIN_WIDTH_M && out.tests < MAX_TESTS {
                            let mid = 0.5 * (y0 + y1);
                            // Lower half on top: visited first.
                            stack.push((mid, y1));
                            stack.push((y0, mid));
                        }
                    }
                    if !plane.rects.is_empty() {
                        plane.rects.sort_by(|p, q| p.y0.total_cmp(&q.y0));
                        out.planes.push(plane);
                    }
                }
            }
        }
        out
    }

    /// Whether the virtual occluders hide the box `m` from the cell `a`: every segment
    /// from `a` to `m` crosses one plane inside its rectangles.
    pub fn hides(&self, a: &Aabb3, m: &Aabb3) -> bool {
        self.planes.iter().any(|p| p.hides(a, m))
    }

    /// Number of rectangles.
    pub fn count(&self) -> usize {
        self.planes.iter().map(|p| p.rects.len()).sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bx(x0: f64, y0: f64, z0: f64, x1: f64, y1: f64, z1: f64) -> Aabb3 {
        Aabb3::new(DVec3::new(x0, y0, z0), DVec3::new(x1, y1, z1))
    }

    fn plane(rects: Vec<VoRect>) -> VoPlane {
        VoPlane {
            axis: Axis::X,
            sign: 1.0,
            c: 100.0,
            floor_z: 0.0,
            rects,
        }
    }

    #[test]
    fn a_wide_tall_rectangle_hides_what_is_behind_it() {
        let p = plane(vec![VoRect {
            y0: -200.0,
            y1: 200.0,
            h: 20.0,
        }]);
        let cell = bx(0.0, 0.0, 1.5, 10.0, 10.0, 2.0);
        assert!(p.hides(&cell, &bx(300.0, 0.0, 0.0, 320.0, 20.0, 30.0)));
        // Too tall: its top seen over the rectangle.
        assert!(!p.hides(&cell, &bx(300.0, 0.0, 0.0, 320.0, 20.0, 200.0)));
        // Straddling the plane, or before it.
        assert!(!p.hides(&cell, &bx(90.0, 0.0, 0.0, 120.0, 20.0, 10.0)));
        // Seen past the rectangle's end.
        assert!(!p.hides(&cell, &bx(300.0, 500.0, 0.0, 320.0, 520.0, 10.0)));
    }

    #[test]
    fn touching_rectangles_cover_together_a_gap_does_not() {
        let r = |y0, y1| VoRect { y0, y1, h: 20.0 };
        let cell = bx(0.0, 0.0, 1.5, 10.0, 10.0, 2.0);
        let m = bx(300.0, 0.0, 0.0, 320.0, 20.0, 10.0);
        assert!(plane(vec![r(-50.0, 5.0), r(5.0, 60.0)]).hides(&cell, &m));
        assert!(!plane(vec![r(-50.0, 5.0), r(5.1, 60.0)]).hides(&cell, &m));
    }

    #[test]
    fn the_crossing_bound_contains_every_segment_crossing() {
        // Brute force: segments between corners and inner points of both boxes.
        let cell = bx(-20.0, -5.0, 1.0, 30.0, 40.0, 3.0);
        let m = bx(150.0, 60.0, 0.0, 400.0, 90.0, 25.0);
        let c = 100.0;
        let pts = |b: &Aabb3| {
            let mut v = Vec::new();
            for i in 0..=4 {
                for j in 0..=4 {
                    for k in 0..=2 {
                        let f = |lo: f64, hi: f64, s: usize, n: usize| {
                            lo + (hi - lo) * s as f64 / n as f64
                        };
                        v.push(DVec3::new(
                            f(b.min.x, b.max.x, i, 4),
                            f(b.min.y, b.max.y, j, 4),
                            f(b.min.z, b.max.z, k, 2),
                        ));
                    }
                }
            }
            v
        };
        let (mut ylo, mut yhi, mut zhi) = (f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
        for p in pts(&cell) {
            for q in pts(&m) {
                let t = (c - p.x) / (q.x - p.x);
                let x = p + (q - p) * t;
                ylo = ylo.min(x.y);
                yhi = yhi.max(x.y);
                zhi = zhi.max(x.z);
            }
        }
        let exact = |y0: f64, y1: f64, h: f64| plane(vec![VoRect { y0, y1, h }]);
        assert!(exact(ylo, yhi, zhi).hides(&cell, &m));
        for shrunk in [
            exact(ylo + 0.01, yhi, zhi),
            exact(ylo, yhi - 0.01, zhi),
            exact(ylo, yhi, zhi - 0.01),
        ] {
            assert!(!shrunk.hides(&cell, &m));
        }
    }

    #[test]
    fn mirrored_planes_face_away_from_the_cell() {
        let p = VoPlane {
            axis: Axis::Y,
            sign: -1.0,
            c: 100.0, // the plane y = -100
            floor_z: 0.0,
            rects: vec![VoRect {
                y0: -300.0,
                y1: 300.0,
                h: 20.0,
            }],
        };
        let cell = bx(0.0, 0.0, 1.5, 10.0, 10.0, 2.0);
        assert!(p.hides(&cell, &bx(0.0, -400.0, 0.0, 20.0, -380.0, 10.0)));
        assert!(!p.hides(&cell, &bx(0.0, 380.0, 0.0, 20.0, 400.0, 10.0)));
        let t = p.thin_box(-1.0, 1.0, 5.0);
        assert_eq!((t.min.y, t.max.y), (-100.0 - THICKNESS_M, -100.0));
    }
}
