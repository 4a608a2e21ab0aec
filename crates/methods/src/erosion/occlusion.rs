//! The from-centre occlusion test (§5), specialised to 2.5D: a *polar occlusion map*.
//!
//! Directions from the eye `S = (S_h, e)` are parametrised by azimuth (N bins over
//! 360°) and, inside a bin, by elevation handled *analytically*. The eroded occluders
//! (an inner raster of the eroded height field, see `erode.rs`) are marched along each
//! bin's wedge in annular sectors; a sector whose every pixel stands at least `h` high
//! gives the bin a *blocker* `(r_a, h)` at its near radius — the *inner* coverage rule,
//! at the *farthest* depth of the sector's entry. Any sight line in that bin whose
//! height at horizontal distance `r_a` is below `h` is blocked there. Because the raster
//! is of the fused height field, shared walls leave no crack.
//!
//! An occludee is tested through its nearest distance `ρ_min` in each bin it touches
//! (the *outer* rule: every touched bin counts, with the nearest depth): a target at
//! height `t` is hidden in the bin iff a blocker with `r_a < ρ_min` and `h > e`
//! satisfies `(t − e)·r_a < (h − e)·ρ_min` (a rising sight line passes below the
//! blocker's top at `r_a`; a descending one always does). Nothing is point-sampled: the
//! answer is conservative at any number of bins, only its tightness depends on it.
//!
//! The eye height `e` is a *query* parameter. This is what makes the map fit the
//! segment erosion of 2.5D scenes (see `mod.rs`): the occludee-dependent eye raise
//! that keeps §3.3 conservative for rising sight lines costs nothing here, whereas a
//! depth buffer would have to be re-rendered per occludee.
//!
//! Blockers of a bin are kept as a Pareto staircase (`r_a` increasing, `h` increasing):
//! a blocker both farther and lower than another never decides anything.

#[cfg(test)]
use super::field::MinPyramid;
use super::field::DM;
use super::tiles::Occluders;
use sightline_geom::{Aabb2, DVec2};
use std::f64::consts::TAU;
use std::sync::Arc;

/// Slack in the conservative direction for distance and height comparisons (m).
const EPS_M: f64 = 1e-6;

/// Why an edge could not be rasterized: it passes through the eye.
#[derive(Debug)]
pub struct ThroughEye;

/// Bin geometry shared by occluders and occludees (cheap to clone: every map of a
/// cell holds one).
#[derive(Clone, Debug)]
pub struct Bins {
    pub n: usize,
    width: f64,
    dirs: Arc<[DVec2]>,
    mids: Arc<[DVec2]>,
}

impl Bins {
    pub fn new(n: usize) -> Self {
        let n = n.max(8);
        let width = TAU / n as f64;
        Bins {
            n,
            width,
            dirs: (0..=n)
                .map(|k| DVec2::from_angle(k as f64 * width))
                .collect::<Vec<_>>()
                .into(),
            mids: (0..n)
                .map(|k| DVec2::from_angle((k as f64 + 0.5) * width))
                .collect::<Vec<_>>()
                .into(),
        }
    }

    /// Visit every bin met by the segment `pa → pb` (relative to the eye), with the
    /// radial range of the part of the segment inside the bin's wedge (widened a
    /// little: conservative for both uses) and whether the bin's middle ray crosses it.
    fn edge(
        &self,
        pa: DVec2,
        pb: DVec2,
        mut f: impl FnMut(usize, f64, f64, bool),
    ) -> Result<(), ThroughEye> {
        let d = pb - pa;
        let len2 = d.length_squared();
        // Distance from the eye to the segment.
        let t = if len2 > 0.0 {
            (-pa.dot(d) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let scale = pa.length().max(pb.length()).max(1.0);
        if (pa + d * t).length() <= 1e-9 * scale {
            return Err(ThroughEye);
        }
        let (ta, tb) = (pa.y.atan2(pa.x), pb.y.atan2(pb.x));
        let (lo, mut hi) = if pa.perp_dot(pb) >= 0.0 {
            (ta, tb)
        } else {
            (tb, ta)
        };
        if hi < lo {
            hi += TAU;
        }
        let k0 = (lo / self.width).floor() as i64 - 1;
        let k1 = (hi / self.width).floor() as i64 + 1;
        let k1 = k1.min(k0 + self.n as i64 - 1);
        let tol = 1e-9 * scale;
        for k in k0..=k1 {
            let bin = k.rem_euclid(self.n as i64) as usize;
            let (da, db) = (self.dirs[bin], self.dirs[bin + 1]);
            // s-interval where p(s) = pa + s d is inside the wedge (both half-planes).
            let (mut s0, mut s1) = (0.0f64, 1.0f64);
            for (c0, c1) in [
                (da.perp_dot(pa), da.perp_dot(d)),
                (pa.perp_dot(db), d.perp_dot(db)),
            ] {
                // c0 + s c1 >= -tol
                let c0 = c0 + tol;
                if c1.abs() < 1e-300 {
                    if c0 < 0.0 {
                        s1 = -1.0;
                    }
                } else if c1 > 0.0 {
                    s0 = s0.max(-c0 / c1);
                } else {
                    s1 = s1.min(-c0 / c1);
                }
            }
            if s0 > s1 {
                continue;
            }
            let (q0, q1) = (pa + d * s0, pa + d * s1);
            let hi_r = q0.length().max(q1.length()) + EPS_M;
            let e = q1 - q0;
            let el2 = e.length_squared();
            let u = if el2 > 0.0 {
                (-q0.dot(e) / el2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let lo_r = ((q0 + e * u).length() - EPS_M).max(0.0);
            // Does the middle ray of the bin cross the edge (half-open rule)?
            let m = self.mids[bin];
            let (sa, sb) = (m.perp_dot(pa), m.perp_dot(pb));
            let crosses = if (sa > 0.0) != (sb > 0.0) {
                let u = sa / (sa - sb);
                (pa + d * u).dot(m) > 0.0
            } else {
                false
            };
            f(bin, lo_r, hi_r, crosses);
        }
        Ok(())
    }
}

/// An occludee seen from the eye: its nearest distance in each bin it touches.
#[derive(Clone, Debug, Default)]
pub struct Target {
    /// `(bin, ρ_min)`, one entry per bin, sorted by bin.
    pub bins: Vec<(usize, f64)>,
    /// The eye is inside or on the occludee: it is visible.
    pub at_eye: bool,
}

impl Target {
    /// A target made of closed rings (polygon) or open polylines (`closed = false`),
    /// in coordinates relative to the eye.
    pub fn new(bins: &Bins, parts: &[(Vec<DVec2>, bool)]) -> Self {
        let mut hits: Vec<(usize, f64)> = Vec::new();
        let mut at_eye = false;
        let mut crossings = 0usize;
        for (pts, closed) in parts {
            let n = pts.len();
            if n == 0 {
                continue;
            }
            if n == 1 {
                // A single point: a zero-length segment.
                if bins
                    .edge(pts[0], pts[0], |b, lo, _, _| hits.push((b, lo)))
                    .is_err()
                {
                    at_eye = true;
                }
                continue;
            }
            let m = if *closed { n } else { n - 1 };
            for i in 0..m {
                let (a, b) = (pts[i], pts[(i + 1) % n]);
                let r = bins.edge(a, b, |bin, lo, _, crosses| {
                    hits.push((bin, lo));
                    if *closed && bin == 0 && crosses {
                        crossings += 1;
                    }
                });
                if r.is_err() {
                    at_eye = true;
                }
            }
        }
        // Eye inside a closed part: odd number of crossings of bin 0's middle ray
        // (counted over all closed parts; parts are disjoint pieces of one object).
        if crossings % 2 == 1 {
            at_eye = true;
        }
        hits.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)));
        hits.dedup_by(|later, first| later.0 == first.0);
        Target { bins: hits, at_eye }
    }
}

/// The polar occlusion map of one structuring element, seen from one cell centre.
#[derive(Clone, Debug)]
pub struct PolarMap {
    pub bins: Bins,
    /// Per bin: the farthest nearest-distance of a target tested there (−1: none);
    /// occluders are only marched in those bins, and only that far.
    reach: Vec<f64>,
    /// Per bin: the highest target top, and the lowest and highest eye of the tests
    /// there (a blocker no higher than every eye decides nothing; the early stop must
    /// hold for the highest).
    top: Vec<f64>,
    eye_lo: Vec<f64>,
    eye_hi: Vec<f64>,
    /// Per bin: blockers `(r_a, h)`, `r_a` increasing and `h` increasing.
    stairs: Vec<Vec<(f64, f64)>>,
}

impl PolarMap {
    pub fn new(bins: Bins) -> Self {
        let n = bins.n;
        PolarMap {
            bins,
            reach: vec![-1.0; n],
            top: vec![f64::NEG_INFINITY; n],
            eye_lo: vec![f64::INFINITY; n],
            eye_hi: vec![f64::NEG_INFINITY; n],
            stairs: vec![Vec::new(); n],
        }
    }

    /// Record that `t` will be tested with eye height `eye` and top height `top`.
    pub fn need(&mut self, t: &Target, eye: f64, top: f64) {
        for &(b, rho) in &t.bins {
            self.reach[b] = self.reach[b].max(rho);
            self.top[b] = self.top[b].max(top);
            self.eye_lo[b] = self.eye_lo[b].min(eye);
            self.eye_hi[b] = self.eye_hi[b].max(eye);
        }
    }

    /// A map whose bins start with the blockers of `coarse`, a map of the same
    /// occluders from the same eye with `factor` times fewer bins: a coarse blocker's
    /// sector spans its whole wedge, hence the wedge of each of the `factor` bins
    /// nested in it, so it is a valid blocker there. The march of the finer map then
    /// only looks for closer or higher blockers than those.
    pub fn seeded(bins: Bins, coarse: &PolarMap) -> Self {
        let mut m = PolarMap::new(bins);
        if coarse.bins.n > 0 && m.bins.n.is_multiple_of(coarse.bins.n) {
            let factor = m.bins.n / coarse.bins.n;
            for (b, st) in m.stairs.iter_mut().enumerate() {
                st.clone_from(&coarse.stairs[b / factor]);
            }
        }
        m
    }

    /// Fill the needed bins from an eroded occluder raster (decimetres) seen from
    /// `eye` (horizontal position): each bin's wedge is cut radially into annular
    /// sectors about a pixel long; a sector becomes a blocker at its near radius with
    /// a lower bound of the height of every pixel it meets — the *inner* rule: the
    /// whole sector stands at least that high, so any sight line of the bin that enters
    /// it lower is blocked. A bin stops at its farthest target, or once a blocker hides
    /// the highest target from the highest eye tested there at any distance beyond (an
    /// early stop only costs tightness: fewer blockers never hide more).
    ///
    /// A sector gives a blocker only if it stands higher than every eye tested in the
    /// bin and than the blockers already found no farther. So a run of consecutive
    /// sectors is skipped at once when an *upper* bound of the raster over the run's
    /// bounding box ([`Occluders::max_at_most`]) is no higher: no sector of the run could
    /// have given a blocker. Runs double while they succeed, halve at each failure and
    /// restart at one sector after a new blocker; the sectors are those of the one-by-one march, and the early
    /// stop is checked at the end of a skipped run (its condition only grows with the
    /// radius and no blocker was added inside), so the blockers are exactly those of the
    /// one-by-one march (`march_one_by_one`, kept for the tests).
    pub fn march<R: Occluders>(&mut self, grid: &R, eye: DVec2) {
        let radii = self.radii(grid.pixel_m());
        let w = self.bins.width;
        let bulge_k = 1.0 - w.cos();
        let sector_box = |da: DVec2, db: DVec2, r: f64, r1: f64| {
            let bulge = r1 * bulge_k + 1e-9;
            let pts = [da * r, db * r, da * r1, db * r1];
            let mut bb = Aabb2::from_points(&pts).expand(bulge);
            bb.min += eye;
            bb.max += eye;
            bb
        };
        for bin in 0..self.bins.n {
            let reach = self.reach[bin];
            if reach < 0.0 {
                continue;
            }
            // Sectors 0..n_sec are those with a near radius below the reach.
            let n_sec = radii.partition_point(|&r| r < reach);
            let (top, e_lo, e) = (self.top[bin], self.eye_lo[bin], self.eye_hi[bin]);
            let (da, db) = (self.bins.dirs[bin], self.bins.dirs[bin + 1]);
            let stairs = &mut self.stairs[bin];
            let mut run = 1usize;
            let mut k = 0usize;
            while k < n_sec {
                let r = radii[k];
                // The blocker a new one must beat: the highest no farther than it.
                let best = best_at(stairs, r + EPS_M);
                let floor_h = best.map_or(e_lo, |(_, hb)| hb.max(e_lo));
                let stop =
                    |r1: f64| best.is_some_and(|(ra, h)| h > e && (top - e) * ra < (h - e) * r1);
                if run >= 2 {
                    let end = (k + run).min(n_sec);
                    if end - k >= 2 {
                        let r_end = radii[end];
                        let skip = dm_at_most(floor_h)
                            .is_some_and(|lim| grid.max_at_most(sector_box(da, db, r, r_end), lim));
                        if skip {
                            if stop(r_end) {
                                break;
                            }
                            k = end;
                            run = (run * 2).min(1 << 12);
                            continue;
                        }
                        // Shorter runs from here on (halved at each failure).
                        run /= 2;
                    }
                }
                // One sector, as the one-by-one march.
                let r1 = radii[k + 1];
                let h = grid.min_over(sector_box(da, db, r, r1)) as f64 * DM;
                let mut best = best;
                if h > e_lo && best.is_none_or(|(_, hb)| h > hb) {
                    insert_blocker(stairs, r + EPS_M, h);
                    best = Some((r + EPS_M, h));
                    run = 1;
                } else {
                    run = run.max(2);
                }
                if let Some((ra, h)) = best {
                    if h > e && (top - e) * ra < (h - e) * r1 {
                        break;
                    }
                }
                k += 1;
            }
        }
    }

    /// The near radii of the march's sectors (sector `k` is `[radii[k], radii[k+1]]`),
    /// up to the farthest reach: half a pixel near the eye, so that a wall two pixels
    /// thick holds a whole sector; about square sectors farther out.
    fn radii(&self, d: f64) -> Vec<f64> {
        let w = self.bins.width;
        let far = self.reach.iter().copied().fold(-1.0f64, f64::max);
        let mut radii = vec![0.0f64];
        let mut r = 0.0f64;
        while r < far {
            r += (0.5 * d).max(r * w);
            radii.push(r);
        }
        radii.push(r + (0.5 * d).max(r * w));
        radii
    }

    /// The march one sector at a time (the reference of `march`).
    #[cfg(test)]
    fn march_one_by_one(&mut self, grid: &MinPyramid, eye: DVec2) {
        let d = grid.levels[0].pixel_m;
        let w = self.bins.width;
        let bulge_k = 1.0 - w.cos();
        for bin in 0..self.bins.n {
            let reach = self.reach[bin];
            if reach < 0.0 {
                continue;
            }
            let (top, e_lo, e) = (self.top[bin], self.eye_lo[bin], self.eye_hi[bin]);
            let (da, db) = (self.bins.dirs[bin], self.bins.dirs[bin + 1]);
            let stairs = &mut self.stairs[bin];
            let mut r = 0.0f64;
            while r < reach {
                let r1 = r + (0.5 * d).max(r * w);
                let bulge = r1 * bulge_k + 1e-9;
                let pts = [da * r, db * r, da * r1, db * r1];
                let mut bb = Aabb2::from_points(&pts).expand(bulge);
                bb.min += eye;
                bb.max += eye;
                let h = grid.min_over(bb) as f64 * DM;
                let best = best_at(stairs, r + EPS_M);
                if h > e_lo && best.is_none_or(|(_, hb)| h > hb) {
                    insert_blocker(stairs, r + EPS_M, h);
                }
                if let Some((ra, h)) = best_at(stairs, r + EPS_M) {
                    if h > e && (top - e) * ra < (h - e) * r1 {
                        break;
                    }
                }
                r = r1;
            }
        }
    }

    /// Whether the target (top face at height `t`, eye height `e`) is hidden in every
    /// bin it touches.
    pub fn hidden(&self, target: &Target, e: f64, t: f64) -> bool {
        if target.at_eye || target.bins.is_empty() {
            return false;
        }
        target
            .bins
            .iter()
            .all(|&(bin, rho)| bin_hidden(&self.stairs[bin], rho, e, t))
    }
}

/// The greatest height `v` (dm) with `v · DM ≤ h` in floating point (None if none):
/// `max ≤ v` decides exactly as `max · DM ≤ h`.
fn dm_at_most(h: f64) -> Option<u16> {
    if !(h >= 0.0) {
        return None;
    }
    let mut v = (h / DM).floor().min(u16::MAX as f64) as u16;
    while v < u16::MAX && f64::from(v + 1) * DM <= h {
        v += 1;
    }
    while v > 0 && f64::from(v) * DM > h {
        v -= 1;
    }
    (f64::from(v) * DM <= h).then_some(v)
}

fn bin_hidden(stairs: &[(f64, f64)], rho: f64, e: f64, t: f64) -> bool {
    for &(ra, h) in stairs {
        if ra >= rho - EPS_M {
            break;
        }
        if h <= e + EPS_M {
            continue;
        }
        if t <= e || (t - e + EPS_M) * ra < (h - e - EPS_M) * rho {
            return true;
        }
    }
    false
}

/// The highest blocker at a radius no greater than `r` (the staircase's `h` grows with
/// its radius: the last such one).
fn best_at(stairs: &[(f64, f64)], r: f64) -> Option<(f64, f64)> {
    let n = stairs.partition_point(|&(ra, _)| ra <= r);
    n.checked_sub(1).map(|i| stairs[i])
}

fn insert_blocker(stairs: &mut Vec<(f64, f64)>, ra: f64, h: f64) {
    if stairs.iter().any(|&(r, hh)| r <= ra && hh >= h) {
        return;
    }
    stairs.retain(|&(r, hh)| !(ra <= r && h >= hh));
    let pos = stairs.partition_point(|&(r, _)| r < ra);
    stairs.insert(pos, (ra, h));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::erosion::field::Grid;

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
        vec![
            DVec2::new(x0, y0),
            DVec2::new(x1, y0),
            DVec2::new(x1, y1),
            DVec2::new(x0, y1),
        ]
    }

    /// A raster around the eye at the origin with the given walls (world = eye frame).
    fn grid(walls: &[(f64, f64, f64, f64, f64)]) -> Grid {
        let mut g = Grid::zeros(DVec2::splat(-50.0), 0.25, 400, 400);
        for j in 0..400 {
            for i in 0..400 {
                let (x, y) = (-50.0 + i as f64 * 0.25, -50.0 + j as f64 * 0.25);
                for &(x0, y0, x1, y1, h) in walls {
                    if x >= x0 && x + 0.25 <= x1 && y >= y0 && y + 0.25 <= y1 {
                        g.data[(j * 400 + i) as usize] = (h / DM) as u16;
                    }
                }
            }
        }
        g
    }

    fn map_with(walls: &[(f64, f64, f64, f64, f64)], t: &Target, bins: Bins) -> PolarMap {
        let mut m = PolarMap::new(bins);
        m.need(t, 2.0, 50.0);
        m.march(&MinPyramid::new(grid(walls)), DVec2::ZERO);
        m
    }

    fn target(bins: &Bins, r: Vec<DVec2>) -> Target {
        Target::new(bins, &[(r, true)])
    }

    #[test]
    fn wall_hides_low_block_not_tower() {
        let bins = Bins::new(512);
        let behind = target(&bins, rect(20.0, -5.0, 30.0, 5.0));
        let m = map_with(&[(10.0, -30.0, 11.0, 30.0, 10.0)], &behind, bins);
        // Eye at 2 m: a 9 m block 20 m away behind a 10 m wall 10 m away is hidden...
        assert!(m.hidden(&behind, 2.0, 9.0));
        // ... a 40 m tower is not ((40-2)/20 > (10-2)/10).
        assert!(!m.hidden(&behind, 2.0, 40.0));
        // A street (t = 0) behind is hidden.
        assert!(m.hidden(&behind, 2.0, 0.0));
    }

    #[test]
    fn gap_between_walls_is_open() {
        let bins = Bins::new(512);
        let behind = target(&bins, rect(20.0, -5.0, 30.0, 5.0));
        let walls = [
            (10.0, -30.0, 11.0, -0.5, 10.0),
            (10.0, 0.5, 11.0, 30.0, 10.0),
        ];
        let m = map_with(&walls, &behind, bins);
        assert!(!m.hidden(&behind, 2.0, 0.0));
    }

    #[test]
    fn eye_inside_occluder_blocks_everything() {
        let bins = Bins::new(64);
        let far = target(&bins, rect(20.0, -5.0, 30.0, 5.0));
        let m = map_with(&[(-5.0, -5.0, 5.0, 5.0, 10.0)], &far, bins);
        assert!(m.hidden(&far, 2.0, 9.0));
    }

    #[test]
    fn target_around_eye_is_visible() {
        let bins = Bins::new(64);
        let t = target(&bins, rect(-5.0, -5.0, 5.0, 5.0));
        assert!(t.at_eye);
        let m = map_with(&[(-1.0, -1.0, 1.0, 1.0, 10.0)], &t, bins);
        assert!(!m.hidden(&t, 2.0, 0.0));
    }

    /// A random city-like raster around the eye: blocks of random heights, some
    /// touching, with streets between (deterministic xorshift).
    fn random_grid(seed: u64, pixel_m: f64) -> Grid {
        let mut x = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let n = (100.0 / pixel_m) as i64;
        let mut g = Grid::zeros(DVec2::splat(-50.0), pixel_m, n, n);
        for _ in 0..40 {
            let (i0, j0) = ((next() % n as u64) as i64, (next() % n as u64) as i64);
            let (w, h) = (1 + (next() % 30) as i64, 1 + (next() % 30) as i64);
            let z = (next() % 400) as u16;
            for j in j0..(j0 + h).min(n) {
                for i in i0..(i0 + w).min(n) {
                    // Keep the eye's pixels free.
                    if (i - n / 2).abs() > 2 || (j - n / 2).abs() > 2 {
                        g.data[(j * n + i) as usize] = z;
                    }
                }
            }
        }
        g
    }

    /// A map needing every bin up to 60 m, with eyes 1.5..2.5 m and targets up to 30 m.
    fn needy(bins: Bins) -> PolarMap {
        let mut m = PolarMap::new(bins);
        for b in 0..m.bins.n {
            m.reach[b] = 60.0;
            m.top[b] = 30.0;
            m.eye_lo[b] = 1.5;
            m.eye_hi[b] = 2.5;
        }
        m
    }

    #[test]
    fn max_over_bounds_every_min_inside() {
        for seed in 1..6u64 {
            let p = MinPyramid::new(random_grid(seed, 0.5));
            let mut x = seed;
            for k in 0..500 {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                let c = DVec2::new(
                    ((x >> 33) % 90) as f64 - 45.0,
                    ((x >> 13) % 90) as f64 - 45.0,
                ) + DVec2::splat(0.13 * (k % 7) as f64);
                let big = Aabb2::new(
                    c,
                    c + DVec2::new(1.0 + (k % 23) as f64, 0.7 + (k % 17) as f64),
                );
                let hmax = p.max_over(big);
                for f in [0.0, 0.25, 0.5, 0.9] {
                    let lo = big.min + big.size() * f;
                    let small = Aabb2::new(lo, lo + (big.max - lo) * 0.3);
                    assert!(p.min_over(small) <= hmax, "{small:?} in {big:?}");
                }
                assert!(p.min_over(big) <= hmax);
            }
        }
    }

    /// The skipping march finds exactly the blockers of the one-by-one march, at a
    /// coarse and a fine number of bins and two pixel sizes.
    #[test]
    fn skipping_march_equals_one_by_one() {
        for seed in 1..9u64 {
            for (n, px) in [(64, 0.5), (512, 0.5), (2048, 0.25)] {
                let p = MinPyramid::new(random_grid(seed, px));
                let eye = DVec2::new(0.1 * seed as f64, -0.07 * seed as f64);
                let mut fast = needy(Bins::new(n));
                let mut slow = fast.clone();
                fast.march(&p, eye);
                slow.march_one_by_one(&p, eye);
                assert_eq!(fast.stairs, slow.stairs, "seed {seed}, {n} bins");
                assert!(fast.stairs.iter().any(|s| !s.is_empty()));
            }
        }
    }

    /// A map seeded with the blockers of a coarser map hides every target the unseeded
    /// map hides (its soundness against the ground truth is the methods' tests').
    #[test]
    fn seeded_map_hides_at_least_the_unseeded() {
        for seed in 1..7u64 {
            let p = MinPyramid::new(random_grid(seed, 0.5));
            let mut coarse = needy(Bins::new(256));
            coarse.march(&p, DVec2::ZERO);
            let mut plain = needy(Bins::new(2048));
            let mut seeded = PolarMap::seeded(Bins::new(2048), &coarse);
            for b in 0..2048 {
                seeded.reach[b] = 60.0;
                seeded.top[b] = 30.0;
                seeded.eye_lo[b] = 1.5;
                seeded.eye_hi[b] = 2.5;
            }
            plain.march(&p, DVec2::ZERO);
            seeded.march(&p, DVec2::ZERO);
            let bins = Bins::new(2048);
            let mut hidden = 0;
            for k in 0..400 {
                let a = k as f64 * 0.0157;
                let c = DVec2::from_angle(a) * (8.0 + (k % 50) as f64);
                let t = target(&bins, rect(c.x, c.y, c.x + 0.8, c.y + 0.6));
                for z in [0.0, 6.0, 15.0, 28.0] {
                    let by_plain = plain.hidden(&t, 2.0, z);
                    let by_seeded = seeded.hidden(&t, 2.0, z);
                    assert!(!by_plain || by_seeded, "seed {seed} target {k} z {z}");
                    if by_seeded {
                        hidden += 1;
                    }
                }
            }
            assert!(hidden > 0);
        }
    }
}
