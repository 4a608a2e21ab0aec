//! Discretized planar visibility (§5.2 of Koltun et al. 2001), hierarchical from 16
//! rows to the requested resolution.
//!
//! The paper draws every `T(v)` shrunk by `√2·a` into an `N × N` bitmap and reports
//! visibility when a pixel stays black. Shrinking the pieces one by one leaves cracks
//! along every shared edge of the union; here the coverage of the *union* is
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
//! pixel black, never the reverse. Most rows are decided without the sort of the sweep
//! by two bit-parallel `u128` rows of 128 columns ([`band_covered`]). Hierarchy (§5.2,
//! last paragraph): 16 bands first (here 4, which decides the same, see
//! [`START_LEVEL`]); only bands that are not fully covered are split in two, down to `N`
//! bands. A black band at resolution `N` means "visible".

use super::plane::{Band, Planar, Scratch};

/// Number of bands of the first level of the paper (§5.2: 16² first).
pub(crate) const FIRST_LEVEL: u32 = 16;

/// Number of bands the refinement starts from at resolutions of at least
/// [`FIRST_LEVEL`]. A band covered at a coarse level has every sub-band covered (the
/// blocked intervals only grow as a band narrows, and rounding of `g_p(w)` is monotone
/// in `w`), so starting coarser than 16 decides exactly the same rows and answers the
/// same; it only settles the easy cases — occluders next to the cell, whose `g_p`
/// barely depend on `w` — in a few bands instead of 16.
const START_LEVEL: u32 = 4;

/// Whether the band `[w0, w1]` is fully covered by the union of the pieces and masks.
///
/// Two bit-parallel 128-column rows answer most bands without sorting (the sort of the
/// exact sweep dominated the cost): `full` has a bit for each column lying inside some
/// interval shrunk by `3·eps`, `touch` one for each column meeting some interval grown
/// by `3·eps`. All of `full` set means every point of `[u_lo, u_hi]` lies `3·eps` deep in
/// an interval, which is what [`covers`] accepts; a clear bit of `touch` means a column
/// whose points lie in no interval: a gap. Only rows in between are swept exactly.
pub(crate) fn band_covered(p: &Planar, w0: f64, w1: f64, iv: &mut Vec<(f64, f64)>) -> bool {
    iv.clear();
    p.mask_band(w0, w1, iv);
    let span = p.u_hi - p.u_lo;
    let m = 3.0 * p.eps;
    if span > 64.0 * m {
        let mut row = Rows::new(p.u_lo, span, m, 0);
        for &(lo, hi) in iv.iter() {
            row.add(lo, hi);
        }
        for &i in &p.on_fb {
            let (lo, hi) = p.piece_band(i as usize, w0, w1);
            row.add(lo, hi);
        }
        // The pieces come nearest the cell first: most covered rows fill up early.
        for chunk in p.lines.chunks(8) {
            for l in chunk {
                // NaN lines (pieces on F_B, done above) add nothing: `hi > lo` fails.
                let lo = l[0] - l[1] * w0;
                let lo = if lo < l[2] - l[3] * w0 {
                    lo
                } else {
                    l[2] - l[3] * w0
                };
                let hi = l[4] - l[5] * w1;
                let hi = if hi > l[6] - l[7] * w1 {
                    hi
                } else {
                    l[6] - l[7] * w1
                };
                row.add(lo, hi);
            }
            if row.full == u128::MAX {
                return true;
            }
        }
        if row.full == u128::MAX {
            return true;
        }
        if row.touch != u128::MAX {
            return false;
        }
    }
    for i in 0..p.duals.len() {
        let (lo, hi) = p.piece_band(i, w0, w1);
        if hi > lo && hi > p.u_lo && lo < p.u_hi {
            iv.push((lo, hi));
        }
    }
    covers(iv, p.u_lo, p.u_hi, p.eps)
}

/// The two bit-parallel rows of [`band_covered`].
pub(crate) struct Rows {
    u_lo: f64,
    scale: f64,
    m: f64,
    full: u128,
    touch: u128,
}

impl Rows {
    /// Rows over `[u_lo, u_lo + span]` with margin `m`, both starting as `seed`.
    pub(crate) fn new(u_lo: f64, span: f64, m: f64, seed: u128) -> Self {
        Rows {
            u_lo,
            scale: COLUMNS as f64 / span,
            m,
            full: seed,
            touch: seed,
        }
    }

    /// The `touch` row: a clear bit is a column no interval added (grown by `m`) meets.
    pub(crate) fn touch(&self) -> u128 {
        self.touch
    }

    /// Only the `touch` row of [`Rows::add`], for any `lo <= hi` (the caller decides
    /// which intervals count).
    #[inline]
    pub(crate) fn add_touch(&mut self, lo: f64, hi: f64) {
        // Columns j meeting [lo - m, hi + m].
        let k0 = floor_in_row((lo - self.m - self.u_lo) * self.scale);
        let k1 = floor_in_row((hi + self.m - self.u_lo) * self.scale);
        self.touch |= column_mask(k0, k1);
    }

    /// Only the `full` row of [`Rows::add`].
    #[inline]
    fn add_full(&mut self, lo: f64, hi: f64) {
        if hi > lo {
            // Columns j with [u_j, u_j+1] ⊂ [lo + m, hi - m].
            let j0 = ceil_in_row((lo + self.m - self.u_lo) * self.scale);
            let j1 = floor_in_row((hi - self.m - self.u_lo) * self.scale) - 1;
            self.full |= column_mask(j0, j1);
        }
    }

    /// Add the interval `[lo, hi]` (nothing when `hi > lo` fails, NaN included).
    #[inline]
    fn add(&mut self, lo: f64, hi: f64) {
        if hi > lo {
            self.add_full(lo, hi);
            self.add_touch(lo, hi);
        }
    }
}

/// `PREFIX[k]`: the bits `0..k` of a row.
const PREFIX: [u128; COLUMNS as usize + 1] = {
    let mut t = [u128::MAX; COLUMNS as usize + 1];
    let mut k = 0;
    while k < COLUMNS as usize {
        t[k] = (1u128 << k) - 1;
        k += 1;
    }
    t
};

/// `floor(x)` for the column indices of the rows, clamped to `[-2, COLUMNS + 2]` first
/// (inlined: `f64::floor` is a libm call without SSE4.1). `x` must not be NaN: every
/// caller passes the ends of an interval that passed `hi > lo` (or `hi >= lo`), over a
/// finite scale.
#[inline]
fn floor_in_row(x: f64) -> i32 {
    debug_assert!(!x.is_nan());
    let x = x.clamp(-2.0, (COLUMNS + 2) as f64);
    let t = x as i32;
    if t as f64 > x {
        t - 1
    } else {
        t
    }
}

/// `ceil(x)`, clamped like [`floor_in_row`].
#[inline]
fn ceil_in_row(x: f64) -> i32 {
    debug_assert!(!x.is_nan());
    let x = x.clamp(-2.0, (COLUMNS + 2) as f64);
    let t = x as i32;
    if (t as f64) < x {
        t + 1
    } else {
        t
    }
}

/// The bits `j0..=j1` of a row (clamped to the row; `0` when empty), by table.
#[inline]
pub(crate) fn column_mask(j0: i32, j1: i32) -> u128 {
    let (a, b) = (j0.max(0), j1.min(COLUMNS as i32 - 1));
    if a > b {
        return 0;
    }
    PREFIX[(b + 1) as usize] & !PREFIX[a as usize]
}

/// Columns of the bit-parallel rows of [`band_covered`].
pub(crate) const COLUMNS: u32 = 128;

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

/// The rays `(u, w)` of `RS` the pieces may leave free, as a hull `[u0, u1] × [w0, w1]`
/// (`None`: the shaft is too narrow for the rows, or nothing is left free at `level`).
///
/// Over `level` equal bands, a column not `full` in a band that is not covered holds
/// every ray a finer band or a larger set of pieces can leave free: a finer band only
/// sees the intervals grow (`full` bits only appear), and a column that is `full` is
/// covered `3·eps` deep, so no gap of the exact sweep lies in it. The hull is widened
/// by a column and `3·eps` on each side in `u` and by `eps` in `w`. A piece whose
/// interval meets no such column for the band of a free ray adds nothing to the
/// coverage of that band, so a gathering restricted to the rays of the hull
/// ([`super::plane::Planar::extend`]) covers exactly the rows the unrestricted one (the
/// same parts, cut at the same lines) covers.
pub(crate) fn free_hull(scratch: &Scratch, level: u32) -> Option<[f64; 4]> {
    let p = &scratch.planar;
    let (w_lo, w_hi) = (p.w_lo, p.w_hi);
    let span = p.u_hi - p.u_lo;
    let m = 3.0 * p.eps;
    if !(w_lo < w_hi) || !(span > 64.0 * m) {
        return None;
    }
    let col = span / COLUMNS as f64;
    let mut iv = Vec::new();
    let mut hull: Option<[f64; 4]> = None;
    for (w0, w1) in super::plane::bands_rev(w_lo, w_hi, level.max(1) as usize) {
        let mut row = Rows::new(p.u_lo, span, m, 0);
        iv.clear();
        p.mask_band(w0, w1, &mut iv);
        for &(lo, hi) in &iv {
            row.add(lo, hi);
        }
        for i in 0..p.duals.len() {
            let (lo, hi) = p.piece_band_fast(i, w0, w1);
            row.add(lo, hi);
        }
        if row.full == u128::MAX {
            continue;
        }
        let free = !row.full;
        let j0 = free.trailing_zeros() as f64;
        let j1 = (COLUMNS - 1 - free.leading_zeros()) as f64;
        let b = [
            p.u_lo + (j0 - 1.0) * col - m,
            p.u_lo + (j1 + 2.0) * col + m,
            w0 - p.eps,
            w1 + p.eps,
        ];
        hull = Some(match hull {
            None => b,
            Some(h) => [
                h[0].min(b[0]),
                h[1].max(b[1]),
                h[2].min(b[2]),
                h[3].max(b[3]),
            ],
        });
    }
    hull
}

const ALL: u32 = u32::MAX;

/// §5.2 with hierarchical refinement: `true` when every pixel of the `resolution`-row
/// ray space is covered (the boxes are hidden from each other).
///
/// A sub-band only sees the intervals of its parent grow (`[H(w0'), G(w1')] ⊇
/// [H(w0), G(w1)]`), so each band hands its children its `full` row as a start, and
/// only the pieces whose intervals can still reach a column it left uncovered: over any
/// sub-band a piece blocks at most its hull `[H(w1), G(w0)]`. A piece whose hull lies in
/// covered columns adds nothing the children do not already have (to `full` nor to
/// `touch`, whose clear bits are then still gaps). Deep rows thus test a few pieces
/// instead of all.
///
/// Above the finest level a band not `full` is split without looking for the gaps of
/// its `touch` row or sweeping it: its sub-bands see the same intervals grown, so the
/// finest level decides every ray alike, and a coarse band computes half the column
/// bounds.
///
/// A shaft gathered in steps ([`Planar::extend`]) is tested after each: the bands found
/// covered are kept (`Scratch::covered`) and skipped by the next test of the same shaft,
/// whose pieces are a superset: a band covered by fewer pieces stays covered by more.
pub(crate) fn hidden(scratch: &mut Scratch, resolution: u32) -> bool {
    scratch.gap_ray = None;
    let p = &scratch.planar;
    let (w_lo, w_hi) = (p.w_lo, p.w_hi);
    if w_hi.is_nan() || w_lo.is_nan() || w_hi < w_lo {
        return false;
    }
    let first = if resolution >= FIRST_LEVEL {
        START_LEVEL
    } else {
        resolution.max(1)
    };
    let span = p.u_hi - p.u_lo;
    let m = 3.0 * p.eps;
    if !(span > 64.0 * m) {
        return hidden_plain(scratch, first, resolution);
    }
    let scale = COLUMNS as f64 / span;
    let bands = &mut scratch.refine;
    let lists = &mut scratch.lists;
    let iv = &mut scratch.intervals;
    // The bands an earlier call on this shaft found covered, and those this call finds
    // (both ascending: bands are taken in ascending `w`).
    let prev = &scratch.covered;
    let found = &mut scratch.covered_next;
    let mut k_prev = 0;
    found.clear();
    bands.clear();
    lists.clear();
    for (w0, w1) in super::plane::bands_rev(w_lo, w_hi, first as usize) {
        bands.push(Band {
            w0,
            w1,
            n: first,
            first: 0,
            len: ALL,
            seed: 0,
        });
    }
    let n_pieces = p.duals.len() as u32;
    while let Some(b) = bands.pop() {
        while k_prev < prev.len() && prev[k_prev].1 <= b.w0 {
            k_prev += 1;
        }
        if prev
            .get(k_prev)
            .is_some_and(|&(w0, w1)| w0 <= b.w0 && b.w1 <= w1)
        {
            push_band(found, b.w0, b.w1);
            continue;
        }
        // Lists after this band's belong to finished bands.
        let (s, l) = if b.len == ALL {
            lists.clear();
            (0, n_pieces)
        } else {
            lists.truncate((b.first + b.len) as usize);
            (b.first, b.len)
        };
        let piece = |lists: &[u32], k: u32| if b.len == ALL { k } else { lists[k as usize] };
        let mut row = Rows::new(p.u_lo, span, m, b.seed);
        iv.clear();
        p.mask_band(b.w0, b.w1, iv);
        for &(lo, hi) in iv.iter() {
            row.add(lo, hi);
        }
        let mut covered = false;
        let finest = b.n >= resolution;
        for k in s..s + l {
            let (lo, hi) = p.piece_band_fast(piece(lists, k) as usize, b.w0, b.w1);
            if finest {
                row.add(lo, hi);
            } else {
                row.add_full(lo, hi);
            }
            if k % 8 == 7 && row.full == u128::MAX {
                covered = true;
                break;
            }
        }
        if covered || row.full == u128::MAX {
            push_band(found, b.w0, b.w1);
            continue;
        }
        if finest && row.touch == u128::MAX {
            // Undecided by the rows: the exact sweep, over the band's pieces and the
            // parent's covered columns (a subset of the blocked rays).
            for k in s..s + l {
                let (lo, hi) = p.piece_band_fast(piece(lists, k) as usize, b.w0, b.w1);
                if hi > lo && hi > p.u_lo && lo < p.u_hi {
                    iv.push((lo, hi));
                }
            }
            for (j, run) in runs(b.seed) {
                // A run of full columns lies `m = 3·eps` deep in the blocked rays.
                iv.push((
                    p.u_lo + j as f64 / scale - 2.0 * p.eps,
                    p.u_lo + (j + run) as f64 / scale + 2.0 * p.eps,
                ));
            }
            if covers(iv, p.u_lo, p.u_hi, p.eps) {
                push_band(found, b.w0, b.w1);
                continue;
            }
        }
        if b.n >= resolution {
            // A candidate witness: the middle of the widest run of columns no interval
            // meets, at the band's middle row.
            scratch.gap_ray = widest_run(!row.touch).map(|(j, run)| {
                (
                    p.u_lo + (j as f64 + 0.5 * run as f64) / scale,
                    0.5 * (b.w0 + b.w1),
                )
            });
            // The bands after this one that the earlier calls found covered stay so.
            found.extend_from_slice(&prev[k_prev..]);
            std::mem::swap(&mut scratch.covered, &mut scratch.covered_next);
            return false;
        }
        // The pieces whose hull over the band meets a column left uncovered.
        let start = lists.len() as u32;
        for k in s..s + l {
            let i = piece(lists, k);
            let (lo, hi) = p.piece_band_fast(i as usize, b.w1, b.w0);
            if hi > lo {
                let k0 = floor_in_row((lo - m - p.u_lo) * scale);
                let k1 = floor_in_row((hi + m - p.u_lo) * scale);
                if column_mask(k0, k1) & !row.full != 0 {
                    lists.push(i);
                }
            }
        }
        let len = lists.len() as u32 - start;
        let wm = 0.5 * (b.w0 + b.w1);
        for (w0, w1) in [(wm, b.w1), (b.w0, wm)] {
            bands.push(Band {
                w0,
                w1,
                n: b.n * 2,
                first: start,
                len,
                seed: row.full,
            });
        }
    }
    true
}

/// The runs of set bits of a row, ascending: `(first column, length)`.
pub(crate) fn runs(mut bits: u128) -> impl Iterator<Item = (u32, u32)> {
    let mut j = 0u32;
    std::iter::from_fn(move || {
        if bits == 0 {
            return None;
        }
        let skip = bits.trailing_zeros();
        bits >>= skip;
        j += skip;
        let (start, run) = (j, (!bits).trailing_zeros());
        bits = if run >= 128 { 0 } else { bits >> run };
        j += run;
        Some((start, run))
    })
}

/// The longest run of set bits of `bits` (the first of equal ones; `None` for none).
fn widest_run(bits: u128) -> Option<(u32, u32)> {
    runs(bits).reduce(|best, r| if r.1 > best.1 { r } else { best })
}

/// Append the covered band `[w0, w1]` to `found`, joined to the last one it touches.
fn push_band(found: &mut Vec<(f64, f64)>, w0: f64, w1: f64) {
    match found.last_mut() {
        Some(last) if last.1 == w0 => last.1 = w1,
        _ => found.push((w0, w1)),
    }
}

/// [`hidden`] without the rows (a shaft too narrow in `u` for 128 columns).
fn hidden_plain(scratch: &mut Scratch, first: u32, resolution: u32) -> bool {
    let p = &scratch.planar;
    let (w_lo, w_hi) = (p.w_lo, p.w_hi);
    let bands = &mut scratch.bands;
    bands.clear();
    for (w0, w1) in super::plane::bands_rev(w_lo, w_hi, first as usize) {
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
    use super::super::occluders::Axis;
    use super::super::plane::{orient, Hidden};
    use super::super::{DualRay, Planarity};
    use super::*;
    use sightline_geom::{Aabb3, DVec3};
    use sightline_scene::generate::{city, metropolis};
    use std::sync::Arc;

    proptest::proptest! {
        /// The column bounds are `floor` and `ceil` (clamped), the masks the bits between.
        #[test]
        fn column_bounds_and_masks(x in -300.0f64..300.0, k in -4i32..134, j in -4i32..134) {
            for x in [x, k as f64, k as f64 + 1e-12, k as f64 - 1e-12] {
                let c = |v: f64| v.clamp(-2.0, 130.0) as i32;
                proptest::prop_assert_eq!(floor_in_row(x), c(x.floor()));
                proptest::prop_assert_eq!(ceil_in_row(x), c(x.ceil()));
            }
            let m = column_mask(k, j);
            for bit in 0..128 {
                let inside = k <= bit && bit <= j;
                proptest::prop_assert_eq!(m >> bit & 1 == 1, inside);
            }
        }
    }

    /// The refinement with piece lists and seeded rows answers exactly as the plain one
    /// (every band over every piece) on the shafts of a random city and a grid city.
    #[test]
    fn refinement_with_piece_lists_answers_as_the_plain_one() {
        let mut counts = [0usize; 2];
        for (scene, cell) in [
            (city(11, 300), [0.0, 0.0, 1.5, 20.0, 20.0, 2.0]),
            (metropolis(5, 600), [210.0, 210.0, 0.0, 230.0, 230.0, 2.0]),
        ] {
            let m = DualRay::new("dual-ray", Arc::new(scene), Planarity::Exact);
            let o3 = m.origin.extend(0.0);
            let a = Aabb3::new(
                DVec3::new(cell[0], cell[1], cell[2]) - o3,
                DVec3::new(cell[3], cell[4], cell[5]) - o3,
            );
            let mut scratch = Scratch::default();
            for (_, b) in &m.tree.items {
                for axis in [Axis::X, Axis::Y] {
                    let Some(pair) = orient(&a, b, axis) else {
                        continue; // not separated along this axis
                    };
                    let decomp = m.decomposition(axis);
                    Planar::build(&mut scratch, decomp, &pair, None, Hidden::NONE);
                    for res in [16, 64, 256] {
                        let h = hidden(&mut scratch, res);
                        let plain = hidden_plain(&mut scratch, START_LEVEL, res);
                        assert_eq!(h, plain, "{cell:?} {b:?} {axis:?} {res}");
                        counts[h as usize] += 1;
                    }
                }
            }
        }
        assert!(counts[0] > 100 && counts[1] > 100, "{counts:?}");
    }

    /// A shaft gathered near one box, then extended in steps — to a larger part, to the
    /// whole shaft, or to the other end's part and then the middle — only over the rays
    /// the pieces gathered so far may leave free ([`free_hull`]), answers as the same
    /// steps over every ray, at every resolution; and is hidden only if the shaft
    /// gathered whole is (a piece cut at a step's line `x = const` blocks the same rays
    /// but covers less of a band on its own: §5.2's rows are per piece).
    #[test]
    fn extension_over_the_free_rays_answers_as_the_whole_shaft() {
        #[derive(Clone, Copy)]
        enum Step {
            To(Option<f64>),
            OtherEnd(f64),
        }
        let mut counts = [0usize; 2];
        for (scene, cell) in [
            (city(11, 300), [0.0, 0.0, 1.5, 20.0, 20.0, 2.0]),
            (metropolis(5, 600), [210.0, 210.0, 0.0, 230.0, 230.0, 2.0]),
            (metropolis(9, 900), [300.0, 400.0, 0.0, 360.0, 460.0, 2.0]),
        ] {
            let m = DualRay::new("dual-ray", Arc::new(scene), Planarity::Exact);
            let o3 = m.origin.extend(0.0);
            let a = Aabb3::new(
                DVec3::new(cell[0], cell[1], cell[2]) - o3,
                DVec3::new(cell[3], cell[4], cell[5]) - o3,
            );
            let mut scratch = Scratch::default();
            for (_, b) in &m.tree.items {
                for axis in [Axis::X, Axis::Y] {
                    let Some(pair) = orient(&a, b, axis) else {
                        continue; // not separated along this axis
                    };
                    let decomp = m.decomposition(axis);
                    let side = |d: f64| if pair.narrow_lo() { d } else { -d };
                    let len = pair.len();
                    for (fraction, level) in [(0.1, 16), (0.3, 4)] {
                        let near = side(fraction * len);
                        for res in [16, 128] {
                            Planar::build(&mut scratch, decomp, &pair, None, Hidden::NONE);
                            let whole = hidden(&mut scratch, res);
                            for steps in [
                                &[Step::To(None)][..],
                                &[Step::To(Some(3.0 * near))],
                                &[Step::OtherEnd(0.5 * fraction * len), Step::To(None)],
                            ] {
                                // Unrestricted, restricted, restricted with a test after
                                // every step (the covered bands carried over, as in
                                // `DualRay::hidden_first`).
                                let mut answers = [false; 3];
                                for (variant, answer) in answers.iter_mut().enumerate() {
                                    let s = &mut scratch;
                                    Planar::build(s, decomp, &pair, Some(near), Hidden::NONE);
                                    for &step in steps {
                                        if variant == 2 {
                                            hidden(s, res);
                                        }
                                        let rays =
                                            (variant >= 1).then(|| free_hull(s, level)).flatten();
                                        match step {
                                            Step::To(to) => {
                                                Planar::extend(s, decomp, Hidden::NONE, to, rays)
                                            }
                                            Step::OtherEnd(o) => Planar::extend_other_end(
                                                s,
                                                decomp,
                                                Hidden::NONE,
                                                o,
                                                rays,
                                            ),
                                        }
                                    }
                                    *answer = hidden(s, res);
                                }
                                assert_eq!(answers[0], answers[1], "{cell:?} {b:?} {axis:?} {res}");
                                assert_eq!(answers[1], answers[2], "{cell:?} {b:?} {axis:?} {res}");
                                assert!(!answers[0] || whole, "{cell:?} {b:?} {axis:?} {res}");
                                counts[answers[0] as usize] += 1;
                            }
                        }
                    }
                }
            }
        }
        assert!(counts[0] > 1000 && counts[1] > 1000, "{counts:?}");
    }

    #[test]
    fn floors() {
        for x in [-1.5, -1.0, -0.5, 0.0, 0.25, 1.0, 3.7, 127.9, 128.0] {
            assert_eq!(floor_in_row(x), x.floor() as i32, "{x}");
            assert_eq!(ceil_in_row(x), x.ceil() as i32, "{x}");
        }
        assert_eq!(ceil_in_row(1e300), 130);
        assert_eq!(ceil_in_row(-1e300), -2);
        assert_eq!(floor_in_row(-1e300), -2);
        assert_eq!(floor_in_row(f64::INFINITY), 130);
    }

    #[test]
    fn runs_of_a_row() {
        assert_eq!(runs(0).count(), 0);
        assert_eq!(runs(u128::MAX).collect::<Vec<_>>(), vec![(0, 128)]);
        let bits = 0b1110_0110u128 | (0b11u128 << 126);
        assert_eq!(
            runs(bits).collect::<Vec<_>>(),
            vec![(1, 2), (5, 3), (126, 2)]
        );
        assert_eq!(widest_run(bits), Some((5, 3)));
        assert_eq!(widest_run(0b1101), Some((2, 2)));
        assert_eq!(widest_run(0b1011), Some((0, 2)));
        assert_eq!(widest_run(0), None);
    }

    #[test]
    fn column_masks() {
        assert_eq!(column_mask(0, 0), 1);
        assert_eq!(column_mask(2, 3), 0b1100);
        assert_eq!(column_mask(-5, 500), u128::MAX);
        assert_eq!(column_mask(3, 2), 0);
        assert_eq!(column_mask(127, 130), 1u128 << 127);
        assert_eq!(column_mask(-2, -1), 0);
    }

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
