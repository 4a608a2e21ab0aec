//! Occludee shrinking (§4.4) and the choice of the shaft-supporting segment (§3.3).
//!
//! Two facts about height-field occluders (the fused inner bounds, see `levels.rs`)
//! shape everything here. (1) Raising either end of a sight line only lifts it, so
//! if a point of an occludee's facade is visible, the top of that facade column is
//! visible from the same eye: an occludee is represented by its *top faces* (the
//! outer prisms' footprints at their top heights), and only the top face of the cell
//! (`z = z1`) is a viewpoint that matters. (2) The same monotonicity repairs §3.3 in
//! 3D, see [`eye_raise`].
//!
//! An occludee footprint is cut by the lines `x = x0`, `x = x1`, `y = y0`, `y = y1`
//! of the cell into up to nine *pieces* (this handles the degenerate shafts, §4.4's "second precaution":
//! an occludee overlapping the cell's x or y range is split instead of being tested
//! with a wrong segment):
//! * a *side* piece (e.g. `x ≥ x1`, `y0 ≤ y ≤ y1`): every sight line from the cell
//!   crosses the side `x = x1` inside the cell, so the side is the supporting segment.
//!   Every vertical chord of the piece lies in `[y0, y1]`, so the segment
//!   `{(x − a, y_c)}` over the piece's x-range is a valid shrunk occludee `R`
//!   (`O ⊂ R ⊕ X`): the shrinking collapses the piece onto the cell's axis — the
//!   analytic sweep of Fig. 7 where every chord is shorter than `|X|`;
//! * a *corner* piece (e.g. `x ≥ x1`, `y ≥ y1`): the diagonal through the two other
//!   corners supports the shaft; the piece is used unshrunk (`0 ∈ X`), or shrunk by
//!   the same sweep along the diagonal ([`shrunk_corner`]);
//! * the *centre* piece (overlapping the cell's footprint): visible.
//!
//! **Any valid shrinking will do.** Theorem 1 holds for every `R` with `O ⊂ R ⊕ X`,
//! and a corner piece has several: the piece itself (`0 ∈ X`) and, along the
//! diagonal, the segments of both extreme placements ([`shrunk_corner`]). They hide
//! different things — a shrunk occludee moved sideways may look down an open street
//! the piece itself is hidden from, and the other way round — so a piece is hidden as
//! soon as *one* of them is (the `erosion` method tests the three on the same
//! occlusion map: a tighter PVS with the same guarantee). The same holds across a side
//! (the collapsed segment may sit anywhere its length still covers the piece), but
//! there the extra tests cost far more than they hide.

use super::erode::Element;
use sightline_geom::polygon::ring_signed_area;
use sightline_geom::{Aabb2, DVec2};

/// Sutherland–Hodgman clip of a ring to the box `[lo, hi]` (infinite bounds allowed).
/// The result covers the intersection (it may contain zero-width bridges, which only
/// make an occludee larger).
pub fn clip_ring(ring: &[DVec2], lo: DVec2, hi: DVec2) -> Vec<DVec2> {
    let mut pts = ring.to_vec();
    // (axis, bound, keep_greater)
    let planes = [
        (0, lo.x, true),
        (0, hi.x, false),
        (1, lo.y, true),
        (1, hi.y, false),
    ];
    for (axis, bound, greater) in planes {
        if !bound.is_finite() || pts.is_empty() {
            continue;
        }
        let inside = |p: DVec2| {
            let v = if axis == 0 { p.x } else { p.y };
            if greater {
                v >= bound
            } else {
                v <= bound
            }
        };
        let mut out = Vec::with_capacity(pts.len() + 4);
        let n = pts.len();
        for i in 0..n {
            let (p, q) = (pts[i], pts[(i + 1) % n]);
            let (ip, iq) = (inside(p), inside(q));
            if ip {
                out.push(p);
            }
            if ip != iq {
                let (vp, vq) = if axis == 0 { (p.x, q.x) } else { (p.y, q.y) };
                let s = (bound - vp) / (vq - vp);
                let mut x = p + (q - p) * s;
                if axis == 0 {
                    x.x = bound;
                } else {
                    x.y = bound;
                }
                out.push(x);
            }
        }
        pts = out;
    }
    pts
}

/// Where a piece lies relative to the cell.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Region {
    Centre,
    /// A side region, with its side as the supporting segment.
    Side(Element),
    /// A corner region, with the diagonal supporting its shafts.
    Corner(Element),
}

/// One piece of an occludee's top face.
#[derive(Clone, Debug)]
pub struct Piece {
    pub region: Region,
    pub ring: Vec<DVec2>,
    pub bbox: Aabb2,
}

/// Cut `ring` by the cell footprint's lines into pieces (empty pieces dropped).
pub fn pieces(ring: &[DVec2], cell: Aabb2) -> Vec<Piece> {
    let inf = f64::INFINITY;
    let xs = [
        (-inf, cell.min.x),
        (cell.min.x, cell.max.x),
        (cell.max.x, inf),
    ];
    let ys = [
        (-inf, cell.min.y),
        (cell.min.y, cell.max.y),
        (cell.max.y, inf),
    ];
    let bb = Aabb2::from_points(ring);
    let mut out = Vec::new();
    for (ix, &(xl, xh)) in xs.iter().enumerate() {
        if bb.max.x < xl || bb.min.x > xh {
            continue;
        }
        for (iy, &(yl, yh)) in ys.iter().enumerate() {
            if bb.max.y < yl || bb.min.y > yh {
                continue;
            }
            let clipped = clip_ring(ring, DVec2::new(xl, yl), DVec2::new(xh, yh));
            // A zero-area piece lies on a dividing line, which belongs (closed) to the
            // neighbouring pieces as well: drop it.
            if clipped.is_empty() || ring_signed_area(&clipped).abs() <= 1e-12 {
                continue;
            }
            let region = match (ix, iy) {
                (1, 1) => Region::Centre,
                (2, 1) => Region::Side(Element::Right),
                (0, 1) => Region::Side(Element::Left),
                (1, 2) => Region::Side(Element::Top),
                (1, 0) => Region::Side(Element::Bottom),
                (2, 2) | (0, 0) => Region::Corner(Element::AntiDiagonal),
                _ => Region::Corner(Element::Diagonal),
            };
            let bbox = Aabb2::from_points(&clipped);
            out.push(Piece {
                region,
                ring: clipped,
                bbox,
            });
        }
    }
    out
}

/// The shrunk occludee `R` of a side piece for the `erosion` method: a segment on the
/// cell's axis (absolute coordinates), such that `piece ⊂ R ⊕ X`.
pub fn shrunk_side(side: Element, piece: &Piece, cell: Aabb2) -> [DVec2; 2] {
    let half = cell.size() * 0.5;
    let c = cell.center();
    let bb = piece.bbox;
    match side {
        Element::Right => [
            DVec2::new(bb.min.x - half.x, c.y),
            DVec2::new(bb.max.x - half.x, c.y),
        ],
        Element::Left => [
            DVec2::new(bb.min.x + half.x, c.y),
            DVec2::new(bb.max.x + half.x, c.y),
        ],
        Element::Top => [
            DVec2::new(c.x, bb.min.y - half.y),
            DVec2::new(c.x, bb.max.y - half.y),
        ],
        _ => [
            DVec2::new(c.x, bb.min.y + half.y),
            DVec2::new(c.x, bb.max.y + half.y),
        ],
    }
}

/// The shrunk occludee `R` of a corner piece for the `erosion` method: segments such
/// that `piece ⊂ R ⊕ X` for the diagonal `X` of `corner` (absolute coordinates).
///
/// The analytic shrinking of §4.4 (Fig. 7) for a segment element, on the piece's
/// bounding box in the frame of the diagonal: with `u` along `X` (half length `n`) and
/// `v` across it, a box `[s0, s1] × [w0, w1]` no longer than `2n` along `u` is covered
/// by `R ⊕ X` for `R` the segment `{c u + w v : w ∈ [w0, w1]}` with `c` anywhere in
/// `[s1 − n, s0 + n]`; a longer box is cut along `u` into strips no longer than `2n`,
/// one segment each. Both extreme choices of `c` are returned: each is a valid `R`.
pub fn shrunk_corner(corner: Element, piece: &Piece, cell: Aabb2) -> [Vec<[DVec2; 2]>; 2] {
    let half = cell.size() * 0.5;
    let c = cell.center();
    let dir = match corner {
        Element::AntiDiagonal => DVec2::new(half.x, -half.y),
        _ => DVec2::new(half.x, half.y),
    };
    let n = dir.length();
    if !(n > 0.0) || piece.ring.is_empty() {
        return [Vec::new(), Vec::new()];
    }
    let u = dir / n;
    let v = u.perp();
    let (mut s0, mut s1, mut w0, mut w1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for p in &piece.ring {
        let (s, w) = ((*p - c).dot(u), (*p - c).dot(v));
        (s0, s1, w0, w1) = (s0.min(s), s1.max(s), w0.min(w), w1.max(w));
    }
    // Strips a hair shorter than 2n, so that rounding never leaves a gap.
    let strip = 2.0 * n * (1.0 - 1e-9);
    let k = ((s1 - s0) / strip).ceil().max(1.0);
    if !k.is_finite() || k > 1e4 {
        return [Vec::new(), Vec::new()];
    }
    let width = (s1 - s0) / k;
    let at = |end: usize| -> Vec<[DVec2; 2]> {
        (0..k as usize)
            .map(|i| {
                let (lo, hi) = (s0 + i as f64 * width, s0 + (i + 1) as f64 * width);
                let x = if end == 0 { hi - n } else { lo + n };
                [c + u * x + v * w0, c + u * x + v * w1]
            })
            .collect()
    };
    [at(0), at(1)]
}

/// How much the eye must be raised above the cell top `z1` for an occludee piece of
/// top height `t` tested with a segment element.
///
/// §3.3 reduces the cell to the shaft-supporting segment `[PQ]` by a top-view argument:
/// every sight line `c → r` meets `[PQ]` at some `p` (forward, or on its backward
/// extension inside the cell for the diagonals) and `[p, r]` is then a sight line from
/// the segment containing `[c, r]`'s part outside the cell. In 3D that point is *not*
/// at the cell's height: for a rising line it is up to `λ·(t − z1)` above `z1`, where
/// `λ` bounds the fraction `|cp| / |cr|` of the horizontal path; for a descending
/// line met on its backward extension, up to `μ·(z1 − t)` with `μ ≥ |pc| / |cr|`.
/// Seen from the segment's height a low wall near the cell hides a tower that the
/// back of the cell sees over it, so the literal §3.3 is not conservative. Looking
/// from `[PQ]` raised by the returned amount is: that sight line lies above `[p, r]`
/// everywhere, and a height field blocks a line only if it blocks every lower one.
pub fn eye_raise(piece: &Piece, cell: Aabb2, t: f64, z1: f64) -> f64 {
    let size = cell.size();
    let bb = piece.bbox;
    let ratio = |num: f64, den: f64| {
        let r = num / den;
        if r.is_finite() && r >= 0.0 {
            r
        } else {
            f64::INFINITY
        }
    };
    match piece.region {
        Region::Side(side) => {
            if t <= z1 {
                return 0.0;
            }
            let lambda = match side {
                Element::Right => ratio(size.x, bb.min.x - cell.min.x),
                Element::Left => ratio(size.x, cell.max.x - bb.max.x),
                Element::Top => ratio(size.y, bb.min.y - cell.min.y),
                _ => ratio(size.y, cell.max.y - bb.max.y),
            };
            lambda.min(1.0) * (t - z1)
        }
        _ => {
            let dx = (bb.min.x - cell.max.x).max(cell.min.x - bb.max.x).max(0.0);
            let dy = (bb.min.y - cell.max.y).max(cell.min.y - bb.max.y).max(0.0);
            let d = (dx * dx + dy * dy).sqrt();
            let diag = size.length();
            if t > z1 {
                ratio(diag, diag + d).min(1.0) * (t - z1)
            } else if t < z1 {
                ratio(diag, d) * (z1 - t)
            } else {
                0.0
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell() -> Aabb2 {
        Aabb2::new(DVec2::ZERO, DVec2::new(10.0, 10.0))
    }

    #[test]
    fn a_long_building_beside_the_cell_is_cut_in_three() {
        // x from 12 to 20, y from -20 to 30: lower-right corner, right side, upper-right.
        let ring = vec![
            DVec2::new(12.0, -20.0),
            DVec2::new(20.0, -20.0),
            DVec2::new(20.0, 30.0),
            DVec2::new(12.0, 30.0),
        ];
        let ps = pieces(&ring, cell());
        let regions: Vec<Region> = ps.iter().map(|p| p.region).collect();
        assert_eq!(ps.len(), 3, "{regions:?}");
        assert!(regions.contains(&Region::Side(Element::Right)));
        assert!(regions.contains(&Region::Corner(Element::AntiDiagonal)));
        assert!(regions.contains(&Region::Corner(Element::Diagonal)));
        let total: f64 = ps
            .iter()
            .map(|p| sightline_geom::polygon::ring_signed_area(&p.ring).abs())
            .sum();
        assert!((total - 400.0).abs() < 1e-9);
    }

    #[test]
    fn side_shrink_covers_the_piece() {
        // R ⊕ X ⊇ piece: R = segment at y = 5 from x-range shifted by -5, X = right side.
        let ring = vec![
            DVec2::new(12.0, 1.0),
            DVec2::new(20.0, 2.0),
            DVec2::new(18.0, 9.0),
        ];
        let ps = pieces(&ring, cell());
        assert_eq!(ps.len(), 1);
        let [a, b] = shrunk_side(Element::Right, &ps[0], cell());
        assert_eq!(a, DVec2::new(7.0, 5.0));
        assert_eq!(b, DVec2::new(15.0, 5.0));
        // Every vertex v: v - (5, t) on R for some t ∈ [-5, 5].
        for v in &ring {
            let x = v.x - 5.0;
            assert!(x >= a.x && x <= b.x && (v.y - 5.0).abs() <= 5.0);
        }
    }

    /// Every point of a piece lies in `R ⊕ X` for each shrunk occludee `R` of a corner
    /// piece (both choices, short and long pieces).
    #[test]
    fn shrunk_corners_cover_the_piece() {
        let cell = Aabb2::new(DVec2::new(0.0, 0.0), DVec2::new(10.0, 6.0));
        let (a, b) = (5.0, 3.0);
        // X as a set of vectors from the cell centre: the segment p → q.
        let covered = |segs: &[[DVec2; 2]], p: DVec2, q: DVec2, o: DVec2| {
            segs.iter().any(|&[r0, r1]| {
                // o − x ∈ [r0, r1] for some x on [p, q]: sample both segments finely.
                (0..=200).any(|i| {
                    let x = p + (q - p) * (i as f64 / 200.0);
                    let y = o - x;
                    let d = r1 - r0;
                    let t = if d.length_squared() > 0.0 {
                        ((y - r0).dot(d) / d.length_squared()).clamp(0.0, 1.0)
                    } else {
                        0.0
                    };
                    (r0 + d * t).distance(y) < 0.06
                })
            })
        };
        let rings = [
            // Upper right, small and long along the anti-diagonal.
            vec![
                DVec2::new(12.0, 8.0),
                DVec2::new(15.0, 8.5),
                DVec2::new(13.0, 11.0),
            ],
            vec![
                DVec2::new(10.5, 30.0),
                DVec2::new(40.0, 6.5),
                DVec2::new(41.0, 8.0),
                DVec2::new(12.0, 31.0),
            ],
            // Lower right (diagonal).
            vec![
                DVec2::new(11.0, -2.0),
                DVec2::new(20.0, -9.0),
                DVec2::new(14.0, -1.0),
            ],
        ];
        for ring in &rings {
            let ps = pieces(ring, cell);
            assert_eq!(ps.len(), 1);
            let Region::Corner(el) = ps[0].region else {
                panic!("{:?}", ps[0].region)
            };
            let [p, q] = [
                el.vertices(DVec2::new(a, b))[0],
                el.vertices(DVec2::new(a, b))[1],
            ];
            for segs in shrunk_corner(el, &ps[0], cell) {
                assert!(!segs.is_empty());
                for o in ring {
                    assert!(covered(&segs, p, q, *o), "{el:?} {o:?} {segs:?}");
                }
            }
        }
    }

    #[test]
    fn eye_raise_shrinks_with_distance() {
        let near = Piece {
            region: Region::Side(Element::Right),
            ring: vec![],
            bbox: Aabb2::new(DVec2::new(15.0, 2.0), DVec2::new(20.0, 8.0)),
        };
        let far = Piece {
            bbox: Aabb2::new(DVec2::new(190.0, 2.0), DVec2::new(200.0, 8.0)),
            ..near.clone()
        };
        let (rn, rf) = (
            eye_raise(&near, cell(), 42.0, 2.0),
            eye_raise(&far, cell(), 42.0, 2.0),
        );
        assert!((rn - 40.0 * 10.0 / 15.0).abs() < 1e-9);
        assert!((rf - 40.0 * 10.0 / 190.0).abs() < 1e-9);
        assert_eq!(eye_raise(&near, cell(), 1.0, 2.0), 0.0);
    }
}
