//! Exact analytic planar visibility (§5.1 of Koltun et al. 2001), robust.
//!
//! The paper computes the union of all `T(v)` in the dual ray space and looks for a point
//! outside it. We decide the same question without building the arrangement:
//!
//! * **hidden** certificates are the band coverages of [`super::discrete`] — a band
//!   `[w0, w1]` whose rays are all blocked — refined without a resolution limit;
//! * **visible** certificates are single rays: at the middle `w` of an uncovered band the
//!   blocked set is a union of intervals `[H(w), G(w)]`; the middle of each gap is a
//!   candidate ray, accepted only if Shewchuk's exact `orient2d` puts every vertex of
//!   every piece strictly on one side of it and strictly separates the corners of both
//!   boxes. A ray strictly clear of finitely many closed convex pieces has an open
//!   neighbourhood of clear rays: the boxes see each other robustly.
//!
//! Only where neither certificate appears down to bands of width `2^-MAX_DEPTH` of the
//! ray space (a single grazing ray between two occluders, or a crossing of two pieces
//! exactly on a pixel line) is the answer "visible" by default, which stays
//! conservative. Since the refinement visits the bands of the discretized method first,
//! a pair hidden for `dual-ray` at any resolution is hidden here too.

use super::discrete::{band_covered, FIRST_LEVEL};
use super::occluders::Rect;
use super::plane::{ray_misses_piece, Planar, Scratch};
use sightline_geom::{orient2d, DVec2, Orientation};

/// Deepest refinement, as a power of two of the number of first-level bands.
const MAX_DEPTH: u32 = 36;

/// Candidate gaps tried per band.
const MAX_CANDIDATES: usize = 4;

/// `true` when the planar problem in `scratch` has no clear ray.
pub(crate) fn hidden(scratch: &mut Scratch) -> bool {
    let p = &scratch.planar;
    let (w_lo, w_hi) = (p.w_lo, p.w_hi);
    if w_hi.is_nan() || w_lo.is_nan() || w_hi < w_lo {
        return false;
    }
    let bands = &mut scratch.bands;
    bands.clear();
    for (w0, w1) in super::plane::bands_rev(w_lo, w_hi, FIRST_LEVEL as usize) {
        bands.push((w0, w1, 0));
    }
    while let Some((w0, w1, depth)) = bands.pop() {
        if band_covered(p, w0, w1, &mut scratch.intervals) {
            continue;
        }
        let wm = 0.5 * (w0 + w1);
        if witness(p, wm, &mut scratch.intervals) {
            return false;
        }
        if depth >= MAX_DEPTH || !(w0 < wm && wm < w1) {
            return false; // no certificate either way: stay conservative
        }
        bands.push((wm, w1, depth + 1));
        bands.push((w0, wm, depth + 1));
    }
    true
}

/// Look for a clear ray `(u, w)`: candidates in the gaps of the blocked intervals at
/// `w`, each verified exactly.
fn witness(p: &Planar, w: f64, iv: &mut Vec<(f64, f64)>) -> bool {
    iv.clear();
    for i in 0..p.duals.len() {
        let (lo, hi) = p.piece_band(i, w, w);
        if hi >= lo && hi >= p.u_lo && lo <= p.u_hi {
            iv.push((lo, hi));
        }
    }
    iv.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    let mut reach = p.u_lo;
    let mut tried = 0;
    let mut candidates = [0.0f64; MAX_CANDIDATES];
    for &(lo, hi) in iv.iter() {
        if lo > reach && tried < MAX_CANDIDATES {
            candidates[tried] = 0.5 * (reach + lo.min(p.u_hi));
            tried += 1;
        }
        reach = reach.max(hi);
        if reach >= p.u_hi {
            break;
        }
    }
    if reach < p.u_hi && tried < MAX_CANDIDATES {
        candidates[tried] = 0.5 * (reach + p.u_hi);
        tried += 1;
    }
    candidates[..tried]
        .iter()
        .any(|&u| u > p.u_lo && u < p.u_hi && ray_is_clear(p, u, w))
}

/// The ray from `(0, u)` to `(len, w)`: strictly through both boxes and strictly clear of
/// every piece, decided with exact predicates.
pub(crate) fn ray_is_clear(p: &Planar, u: f64, w: f64) -> bool {
    let a = DVec2::new(0.0, u);
    let b = DVec2::new(p.len, w);
    if !crosses_rect(a, b, &p.lo) || !crosses_rect(a, b, &p.hi) {
        return false;
    }
    p.pieces.iter().all(|q| ray_misses_piece(a, b, q))
}

/// Whether the line `a b` passes through the interior of `r` (corners strictly on both
/// sides). A rectangle of zero width in `x` is a segment, crossed strictly.
fn crosses_rect(a: DVec2, b: DVec2, r: &Rect) -> bool {
    let corners = [
        DVec2::new(r.x0, r.y0),
        DVec2::new(r.x1, r.y0),
        DVec2::new(r.x0, r.y1),
        DVec2::new(r.x1, r.y1),
    ];
    let mut left = false;
    let mut right = false;
    for c in corners {
        match orient2d(a, b, c) {
            Orientation::Left => left = true,
            Orientation::Right => right = true,
            Orientation::Collinear => {}
        }
    }
    left && right
}
