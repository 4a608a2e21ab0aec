//! Discretized planar visibility (§5.2 of Koltun et al. 2001), hierarchical from 16
//! rows to the requested resolution.
//!
//! The paper draws every `T(v)` shrunk by `√2·a` into an `N × N` bitmap and reports
//! visibility when a pixel stays black. Shrinking the pieces one by one leaves cracks
//! along every shared edge of the union (NOTES §2); here the coverage of the *union* is
//! computed exactly per row instead:
//!
//! * a row is a band `[w0, w1]` of `RS` (`N` bands over `[w_lo, w_hi]`);
//! * each convex occluder piece blocks, for every `w` of the band, exactly the rays
//!   `u ∈ [H(w0), G(w1)]` ([`Planar::piece_band`]); rays that miss one of the two boxes
//!   are masked the same way ([`Planar::mask_band`]);
//! * the intervals are merged; a pixel `[u_j, u_j+1] × [w0, w1]` is white iff it lies
//!   inside the merged union, so *some* pixel of the row is black iff the union leaves
//!   any gap in `[u_lo, u_hi]` — the row's bitmap never needs to be materialized, and
//!   the test is exact in `u` at any column resolution.
//!
//! Intervals must overlap by `eps` to count as joined: rounding can only turn a white
//! pixel black, never the reverse. Hierarchy (§5.2, last paragraph): 16 bands first;
//! only bands that are not fully covered are split in two, down to `N` bands. A black
//! band at resolution `N` means "visible".

use super::plane::{Planar, Scratch};

/// Number of bands of the first, coarsest level.
pub(crate) const FIRST_LEVEL: u32 = 16;

/// Whether the band `[w0, w1]` is fully covered by the union of the pieces and masks.
pub(crate) fn band_covered(p: &Planar, w0: f64, w1: f64, iv: &mut Vec<(f64, f64)>) -> bool {
    iv.clear();
    p.mask_band(w0, w1, iv);
    for i in 0..p.duals.len() {
        let (lo, hi) = p.piece_band(i, w0, w1);
        if hi > lo && hi > p.u_lo && lo < p.u_hi {
            iv.push((lo, hi));
        }
    }
    covers(iv, p.u_lo, p.u_hi, p.eps)
}

/// Whether the closed intervals cover `[a, b]`, each joint overlapping by `eps`.
pub(crate) fn covers(iv: &mut [(f64, f64)], a: f64, b: f64, eps: f64) -> bool {
    iv.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
    let mut reach = a;
    for &(lo, hi) in iv.iter() {
        if lo > reach - eps {
            return false;
        }
        if hi > reach {
            reach = hi;
            if reach > b + eps {
                return true;
            }
        }
    }
    false
}

/// §5.2 with hierarchical refinement: `true` when every pixel of the `resolution`-row
/// ray space is covered (the boxes are hidden from each other).
pub(crate) fn hidden(scratch: &mut Scratch, resolution: u32) -> bool {
    let p = &scratch.planar;
    let (w_lo, w_hi) = (p.w_lo, p.w_hi);
    if w_hi.is_nan() || w_lo.is_nan() || w_hi < w_lo {
        return false;
    }
    let first = FIRST_LEVEL.min(resolution.max(1));
    let bands = &mut scratch.bands;
    bands.clear();
    let dw = (w_hi - w_lo) / first as f64;
    for k in (0..first).rev() {
        let w0 = w_lo + dw * k as f64;
        let w1 = if k + 1 == first {
            w_hi
        } else {
            w_lo + dw * (k + 1) as f64
        };
        bands.push((w0, w1, first));
    }
    while let Some((w0, w1, n)) = bands.pop() {
        if band_covered(p, w0, w1, &mut scratch.intervals) {
            continue;
        }
        if n >= resolution {
            return false;
        }
        let wm = 0.5 * (w0 + w1);
        bands.push((wm, w1, n * 2));
        bands.push((w0, wm, n * 2));
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn covers_needs_overlap() {
        let mut iv = vec![(0.5, 1.0), (-1.0, 0.5)];
        assert!(!covers(&mut iv, 0.0, 1.0, 1e-9)); // touching only at 0.5, and ends at b
        let mut iv = vec![(0.4, 1.1), (-1.0, 0.5)];
        assert!(covers(&mut iv, 0.0, 1.0, 1e-9));
        let mut iv = vec![(0.4, 1.1), (0.0, 0.5)];
        assert!(!covers(&mut iv, 0.0, 1.0, 1e-9)); // must start strictly before a
    }
}
