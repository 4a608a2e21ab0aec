//! Visibility witnesses: a single clear ray settles a box-to-box test as "visible"
//! without gathering the whole shaft.
//!
//! Most tests of a street cell in a large city are *visible* (the kd-nodes and objects
//! along the streets it opens onto), and a visible answer of [`super::discrete`] is the
//! most expensive one: every occluder of a shaft kilometres long is gathered, and
//! refinement runs down to the finest rows. A ray `(u, w)` of `RS` that passes strictly
//! through both boxes and strictly misses every occluder piece (exact `orient2d`) makes
//! the same answer certain at every resolution: for each band `[w0, w1] ∋ w` the pieces
//! block at most `[H(w0), G(w1)] ⊆ [H(w), G(w)]`, which leaves `u` free, so no band
//! containing `w` is ever covered (§5.2). The exact algorithm answers "visible" for it
//! too (§5.1). So the witness changes no PVS, only the time to reach it.
//!
//! Candidates come from the occluders gathered first (next to the narrower box): the gaps
//! of their blocked intervals at a few `w`, widest first. Each is verified against the near
//! pieces and then against the rest of the shaft along its own line only
//! ([`Planar::far_ray_clear`]), stopping at the first piece that blocks it.

use super::discrete::{runs, Rows, COLUMNS};
use super::exact::ray_is_clear;
use super::occluders::Decomposition;
use super::plane::{Hidden, Planar, Scratch};

/// Rows of `RS` sampled for candidate gaps: two find nearly every witness that eight
/// would, at a quarter of the cost; one finds far fewer (`docs/methods/dual-ray.md`).
const SAMPLES: u32 = 2;

/// Candidates verified per test, widest gap first (more tries cost more than the full
/// tests they save on the metropolis).
const TRIES: usize = 1;

/// `true` when a verified clear ray joins the two boxes of the planar problem in
/// `scratch`, whose pieces are those of `[ga, gb]` only.
pub(crate) fn visible(scratch: &mut Scratch, decomp: &Decomposition, hidden: Hidden<'_>) -> bool {
    gather_candidates(scratch);
    let mut tried = 0;
    while tried < TRIES {
        let Some((_, u, w)) = scratch.candidates.pop() else {
            return false;
        };
        tried += 1;
        if ray_is_clear(&scratch.planar, u, w)
            && Planar::far_ray_clear(scratch, decomp, hidden, u, w)
        {
            return true;
        }
    }
    false
}

/// Offset of the side candidates of [`gap_visible`], in rows of the finest level.
const GAP_SIDE_ROWS: f64 = 2.0;

/// `true` when the ray the last `discrete::hidden` found in a gap of its finest uncovered
/// band (`Scratch::gap_ray`) is verified clear, as [`visible`]'s candidates. After the
/// pieces at both ends of a shaft are gathered, their gap is far likelier to run clear
/// through the middle than one of the near pieces alone; the rows [`GAP_SIDE_ROWS`]
/// either side of the gap's middle row are tried too, as a gap is rarely straight. A
/// witness only ever proves "visible" along a verified clear ray, so it changes no PVS.
pub(crate) fn gap_visible(
    scratch: &mut Scratch,
    decomp: &Decomposition,
    hidden: Hidden<'_>,
) -> bool {
    let Some((u, w)) = scratch.gap_ray else {
        return false;
    };
    // The gap's middle row, then two rows either side of it (the gap narrows or shifts
    // with `w`; a ray is a witness wherever it was found once verified).
    let dw = GAP_SIDE_ROWS * (scratch.planar.w_hi - scratch.planar.w_lo) / COLUMNS as f64;
    [w, w - dw, w + dw].into_iter().any(|w| {
        ray_is_clear(&scratch.planar, u, w) && Planar::far_ray_clear(scratch, decomp, hidden, u, w)
    })
}

/// The middles of the runs of columns left clear by the gathered pieces and the box
/// masks at `SAMPLES` rows (the bit-parallel rows of [`super::discrete`]), sorted by
/// increasing width (the widest is popped first).
fn gather_candidates(scratch: &mut Scratch) {
    let p = &scratch.planar;
    let cands = &mut scratch.candidates;
    cands.clear();
    let (w_lo, w_hi) = (p.w_lo, p.w_hi);
    let span = p.u_hi - p.u_lo;
    let m = 3.0 * p.eps;
    if !(w_lo < w_hi) || !(span > 64.0 * m) {
        return;
    }
    let col = span / COLUMNS as f64;
    let iv = &mut scratch.intervals;
    for k in 0..SAMPLES {
        let w = w_lo + (w_hi - w_lo) * ((k as f64 + 0.5) / SAMPLES as f64);
        iv.clear();
        p.mask_band(w, w, iv);
        let mut row = Rows::new(p.u_lo, span, m, 0);
        for &(lo, hi) in iv.iter() {
            row.add_touch(lo, hi);
        }
        for i in 0..p.duals.len() {
            let (lo, hi) = p.piece_band_fast(i, w, w);
            if hi >= lo {
                row.add_touch(lo, hi);
            }
        }
        for (j, run) in runs(!row.touch()) {
            let u = p.u_lo + col * (j as f64 + 0.5 * run as f64);
            cands.push((run as f64, u, w));
        }
    }
    cands.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
}

#[cfg(test)]
mod tests {
    use super::super::occluders::Axis;
    use super::super::plane::{orient, Oriented, Planar, Scratch};
    use super::super::{discrete, exact, DualRay, Planarity};
    use super::*;
    use sightline_geom::{Aabb3, DVec3};
    use sightline_scene::generate::{city, metropolis};
    use std::sync::Arc;

    /// Whenever a witness is found from the near pieces, or in the gap the test of the
    /// near and far-end pieces left ([`gap_visible`]), the full shaft is not hidden for
    /// the discretized method at any resolution nor for the exact one: the witness
    /// changes no answer.
    fn witness_never_contradicts(scene: sightline_scene::Scene, cells: &[[f64; 6]]) {
        let m = DualRay::new("dual-ray", Arc::new(scene), Planarity::Exact);
        let o3 = m.origin.extend(0.0);
        let mut scratch = Scratch::default();
        let (mut witnessed, mut tried, mut gaps) = (0, 0, 0);
        let full_is_visible = |scratch: &mut Scratch, pair: &Oriented, c: &[f64; 6], axis| {
            Planar::build(scratch, m.decomposition(axis), pair, None, Hidden::NONE);
            for res in [16, 128] {
                assert!(!discrete::hidden(scratch, res), "{c:?} {pair:?} {res}");
            }
            assert!(!exact::hidden(scratch), "{c:?} {pair:?} exact");
        };
        for c in cells {
            let a = Aabb3::new(
                DVec3::new(c[0], c[1], c[2]) - o3,
                DVec3::new(c[3], c[4], c[5]) - o3,
            );
            for (_, b) in m.tree.items.iter().step_by(3) {
                for axis in [Axis::X, Axis::Y] {
                    let Some(pair) = orient(&a, b, axis) else {
                        continue; // not separated along this axis
                    };
                    let decomp = m.decomposition(axis);
                    let len = pair.len();
                    let near = if pair.cell_low { 0.3 * len } else { -0.3 * len };
                    Planar::build(&mut scratch, decomp, &pair, Some(near), Hidden::NONE);
                    tried += 1;
                    if visible(&mut scratch, decomp, Hidden::NONE) {
                        witnessed += 1;
                        full_is_visible(&mut scratch, &pair, c, axis);
                    }
                    Planar::build(&mut scratch, decomp, &pair, Some(near), Hidden::NONE);
                    Planar::extend_other_end(&mut scratch, decomp, Hidden::NONE, 0.1 * len, None);
                    if !discrete::hidden(&mut scratch, 128)
                        && gap_visible(&mut scratch, decomp, Hidden::NONE)
                    {
                        gaps += 1;
                        full_is_visible(&mut scratch, &pair, c, axis);
                    }
                }
            }
        }
        assert!(
            witnessed > 10 && witnessed < tried && gaps > 10 && gaps < tried,
            "{witnessed} and {gaps} of {tried}"
        );
    }

    #[test]
    fn witnesses_agree_with_full_tests_in_a_city() {
        witness_never_contradicts(
            city(7, 300),
            &[
                [0.0, 0.0, 1.5, 20.0, 20.0, 2.0],
                [150.0, -80.0, 0.0, 250.0, 20.0, 2.0],
            ],
        );
    }

    #[test]
    fn witnesses_agree_with_full_tests_in_a_grid_metropolis() {
        // Street crossings of the 110 m grid: long, grazing sight lines.
        witness_never_contradicts(
            metropolis(3, 600),
            &[
                [210.0, 210.0, 0.0, 230.0, 230.0, 2.0],
                [300.0, 400.0, 0.0, 360.0, 460.0, 2.0],
            ],
        );
    }
}
