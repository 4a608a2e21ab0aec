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
    /// The middle direction of bin 0.
    mid0: DVec2,
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
            mid0: DVec2::from_angle(0.5 * width),
        }
    }

    /// Visit every bin met by the segment `pa → pb` (relative to the eye), with the
    /// nearest distance of the part of the segment inside the bin's wedge (lowered a
    /// little: conservative) and, in bin 0, whether its middle ray crosses the segment
    /// (the inside test of closed rings).
    ///
    /// Each end comes with its azimuth (`atan2`), computed once per vertex by the caller.
    fn edge(
        &self,
        (pa, ta): (DVec2, f64),
        (pb, tb): (DVec2, f64),
        mut f: impl FnMut(usize, f64, bool),
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
            let e = q1 - q0;
            let el2 = e.length_squared();
            let u = if el2 > 0.0 {
                (-q0.dot(e) / el2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let lo_r = ((q0 + e * u).length() - EPS_M).max(0.0);
            // Does the middle ray of bin 0 cross the edge (half-open rule)?
            let crosses = bin == 0 && {
                let m = self.mid0;
                let (sa, sb) = (m.perp_dot(pa), m.perp_dot(pb));
                (sa > 0.0) != (sb > 0.0) && (pa + d * (sa / (sa - sb))).dot(m) > 0.0
            };
            f(bin, lo_r, crosses);
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
    pub fn new(bins: &Bins, parts: &[(&[DVec2], bool)]) -> Self {
        NEAREST.with_borrow_mut(|near| {
            near.start(bins.n);
            let mut at_eye = false;
            let mut crossings = 0usize;
            for &(pts, closed) in parts {
                let n = pts.len();
                if n == 0 {
                    continue;
                }
                if n == 1 {
                    // A single point: a zero-length segment.
                    let p = pts[0];
                    let a = p.y.atan2(p.x);
                    if bins
                        .edge((p, a), (p, a), |b, lo, _| near.hit(b, lo))
                        .is_err()
                    {
                        at_eye = true;
                    }
                    continue;
                }
                let angle = |p: DVec2| p.y.atan2(p.x);
                let m = if closed { n } else { n - 1 };
                let mut a = (pts[0], angle(pts[0]));
                for i in 0..m {
                    let q = pts[(i + 1) % n];
                    let b = (q, angle(q));
                    let r = bins.edge(a, b, |bin, lo, crosses| {
                        near.hit(bin, lo);
                        if closed && crosses {
                            crossings += 1;
                        }
                    });
                    if r.is_err() {
                        at_eye = true;
                    }
                    a = b;
                }
            }
            // Eye inside a closed part: odd number of crossings of bin 0's middle ray
            // (counted over all closed parts; parts are disjoint pieces of one object).
            if crossings % 2 == 1 {
                at_eye = true;
            }
            Target {
                bins: near.finish(),
                at_eye,
            }
        })
    }
}

/// Per-thread scratch of [`Target::new`]: the nearest distance met in each bin so far
/// (∞: none) and the bins met, so that a target's bins come out sorted and deduplicated
/// without sorting its hits.
#[derive(Default)]
struct Nearest {
    rho: Vec<f64>,
    met: Vec<u32>,
}

thread_local! {
    static NEAREST: std::cell::RefCell<Nearest> = std::cell::RefCell::new(Nearest::default());
}

impl Nearest {
    fn start(&mut self, n: usize) {
        if self.rho.len() < n {
            self.rho.resize(n, f64::INFINITY);
        }
        self.met.clear();
    }

    #[inline]
    fn hit(&mut self, bin: usize, rho: f64) {
        let r = &mut self.rho[bin];
        if *r == f64::INFINITY {
            self.met.push(bin as u32);
        }
        *r = r.min(rho);
    }

    /// `(bin, nearest)` of every bin met, by bin; the scratch is left clean.
    fn finish(&mut self) -> Vec<(usize, f64)> {
        self.met.sort_unstable();
        self.met
            .iter()
            .map(|&b| {
                let rho = std::mem::replace(&mut self.rho[b as usize], f64::INFINITY);
                (b as usize, rho)
            })
            .collect()
    }
}

/// The polar occlusion map of one structuring element, seen from one cell centre,
/// marched *lazily*: each bin is marched front to back only as far as the tests asked
/// of it so far need, and a test stops as soon as it has its answer.
///
/// A bin's blockers are a deterministic sequence of sectors (see [`PolarMap::hidden`]);
/// a test of a target at nearest distance `ρ` only uses the blockers nearer than `ρ`,
/// so marching the bin up to `ρ` answers it exactly as a march of the whole bin would,
/// and once a blocker hides the target the rest of the bin cannot change the answer
/// (a target is hidden in a bin if *one* blocker hides it). A target is hidden only if
/// it is hidden in every bin it touches: the first bin where it is visible ends its
/// test, and the bins after it are not marched for it. This is §7 "Scaling"'s
/// front-to-back rendering with the horizon closing, asked per sight-line bundle: most
/// of a visible object's bins and most of the city behind a hidden one are never read.
#[derive(Clone, Debug)]
pub struct PolarMap {
    pub bins: Bins,
    /// Per bin: the farthest nearest-distance of a target tested there (−1: none);
    /// the sector radii are laid out that far.
    reach: Vec<f64>,
    /// Per bin: the lowest eye of the tests there (a blocker no higher decides
    /// nothing).
    eye_lo: Vec<f64>,
    /// Near radii of the sectors, laid out at the first test (see [`Self::radii`]).
    radii: Vec<f64>,
    /// Per bin: its blockers and how far it is marched.
    march: Vec<BinMarch>,
    /// The map of the same occluders from the same eye with fewer bins, whose blockers
    /// seed this one's ([`Self::seeded`]).
    coarse: Option<Box<PolarMap>>,
    /// The bins written since the map was made (`dirty` per bin): [`Self::recycle`]
    /// resets only those.
    touched: Vec<u32>,
    dirty: Vec<bool>,
}

/// Maps kept per thread by [`PolarMap::recycle`] for the next [`PolarMap::new`]: a
/// decision holds at most one map per element and pass (9 + 9), ≈ 2.4 MB per thread
/// with 4,096 bins.
const POOL_MAPS: usize = 20;

thread_local! {
    static POOL: std::cell::RefCell<Vec<PolarMap>> = const { std::cell::RefCell::new(Vec::new()) };
}

/// The state of one bin's lazy march.
#[derive(Clone, Debug, Default)]
struct BinMarch {
    /// Blockers `(r_a, h)`, `r_a` increasing and `h` increasing.
    stairs: Vec<(f64, f64)>,
    /// Sectors `0..next` are read (or skipped: they cannot give a blocker).
    next: usize,
    /// Length of the next attempt to skip a run of sectors.
    run: usize,
    /// Blockers of the coarse map's bin merged into `stairs` so far (a prefix of its
    /// staircase: an unseeded map's only grows at the end).
    seeded: usize,
}

impl PolarMap {
    /// An empty map: one the thread recycled with as many bins if there is one (a cell's
    /// tests make up to 18 maps of 4,096 bins, mostly for a few targets each; resetting
    /// the bins they wrote is cheaper than allocating and filling whole arrays), else a
    /// new one. Either is the same empty map.
    pub fn new(bins: Bins) -> Self {
        let n = bins.n;
        let pooled = POOL.with_borrow_mut(|pool| {
            let k = pool.iter().position(|m| m.bins.n == n)?;
            Some(pool.swap_remove(k))
        });
        if let Some(mut m) = pooled {
            m.bins = bins;
            return m;
        }
        PolarMap {
            bins,
            reach: vec![-1.0; n],
            eye_lo: vec![f64::INFINITY; n],
            radii: Vec::new(),
            march: vec![BinMarch::default(); n],
            coarse: None,
            touched: Vec::new(),
            dirty: vec![false; n],
        }
    }

    /// Give the map back to this thread's pool, emptied (and its coarse map with it).
    pub fn recycle(mut self) {
        if let Some(c) = self.coarse.take() {
            c.recycle();
        }
        for &b in &self.touched {
            let b = b as usize;
            self.reach[b] = -1.0;
            self.eye_lo[b] = f64::INFINITY;
            // A default bin march that keeps its staircase's allocation.
            let st = &mut self.march[b];
            let mut stairs = std::mem::take(&mut st.stairs);
            stairs.clear();
            *st = BinMarch {
                stairs,
                ..BinMarch::default()
            };
            self.dirty[b] = false;
        }
        self.touched.clear();
        self.radii.clear();
        POOL.with_borrow_mut(|pool| {
            if pool.len() < POOL_MAPS {
                pool.push(self);
            }
        });
    }

    #[inline]
    fn touch(&mut self, b: usize) {
        if !self.dirty[b] {
            self.dirty[b] = true;
            self.touched.push(b as u32);
        }
    }

    /// Record that `t` will be tested with eye height `eye` (the top height does not
    /// bound anything a lazy march needs).
    pub fn need(&mut self, t: &Target, eye: f64) {
        for &(b, rho) in &t.bins {
            self.touch(b);
            self.reach[b] = self.reach[b].max(rho);
            self.eye_lo[b] = self.eye_lo[b].min(eye);
        }
    }

    /// A map whose bins are seeded with the blockers of `coarse`, a map of the same
    /// occluders from the same eye with a divisor of this map's bins: a coarse
    /// blocker's sector spans its whole wedge, hence the wedge of each bin nested in
    /// it, so it is a valid blocker there. The coarse bin is marched (lazily, as far as
    /// the finer test needs) before the finer one, whose march then only looks for
    /// closer or higher blockers.
    ///
    /// The blockers a bin ends with do not depend on when the seeds arrive: a sector
    /// is kept iff it is higher than every blocker no farther, and the staircase keeps
    /// the blockers no other is both nearer and higher than — the Pareto front of the
    /// seeds and the kept sectors, whatever the order of insertion.
    ///
    /// `coarse` must not be seeded itself (else it is not used): an unseeded map marches
    /// each bin outwards, so its staircase only grows at the end, and the finer bin
    /// merges only the blockers appended since it last looked (`BinMarch::seeded`).
    pub fn seeded(bins: Bins, coarse: PolarMap) -> Self {
        let mut m = PolarMap::new(bins);
        if coarse.coarse.is_none() && coarse.bins.n > 0 && m.bins.n.is_multiple_of(coarse.bins.n) {
            m.coarse = Some(Box::new(coarse));
        } else {
            coarse.recycle();
        }
        m
    }

    /// Whether the target (top face at height `t`, eye height `e`) is hidden in every
    /// bin it touches, from the eroded occluders `grid` seen from `eye` (horizontal
    /// position). The bins are tested from the `first`-th of the target's (modulo
    /// their number) on: the caller's guess of where it is visible.
    ///
    /// Each bin's wedge is cut radially into annular sectors about a pixel long; a
    /// sector becomes a blocker at its near radius with a lower bound of the height of
    /// every pixel it meets — the *inner* rule: the whole sector stands at least that
    /// high, so any sight line of the bin that enters it lower is blocked.
    pub fn hidden<R: Occluders>(
        &mut self,
        grid: &R,
        eye: DVec2,
        target: &Target,
        e: f64,
        t: f64,
        first: usize,
    ) -> bool {
        if target.at_eye || target.bins.is_empty() {
            return false;
        }
        let n = target.bins.len();
        (0..n).all(|k| {
            let (bin, rho) = target.bins[(first + k) % n];
            self.bin_hidden_at(grid, eye, bin, rho, Some((e, t)))
        })
    }

    /// The index of the first bin of `target` in which a test with `e`, `t` would not
    /// be hidden by the blockers found so far (a guess for [`Self::hidden`]'s `first`).
    pub fn open_bin(&self, target: &Target, e: f64, t: f64) -> Option<usize> {
        target
            .bins
            .iter()
            .position(|&(b, rho)| !bin_hidden(&self.march[b].stairs, rho, e, t))
    }

    /// March `bin` until a blocker nearer than `rho` hides the target `(e, t)` (true)
    /// or every sector nearer than `rho` is read (false); with no target, only the
    /// latter.
    fn bin_hidden_at<R: Occluders>(
        &mut self,
        grid: &R,
        eye: DVec2,
        bin: usize,
        rho: f64,
        target: Option<(f64, f64)>,
    ) -> bool {
        if self.radii.is_empty() {
            self.lay_out_radii(grid.pixel_m());
        }
        self.touch(bin);
        if let Some(coarse) = self.coarse.as_deref_mut() {
            let cb = bin / (self.bins.n / coarse.bins.n);
            coarse.bin_hidden_at(grid, eye, cb, rho, None);
            let st = &mut self.march[bin];
            for &(ra, h) in &coarse.march[cb].stairs[st.seeded..] {
                insert_blocker(&mut st.stairs, ra, h);
            }
            st.seeded = coarse.march[cb].stairs.len();
        }
        let decides = |(ra, h): (f64, f64)| target.is_some_and(|(e, t)| hides(ra, h, rho, e, t));
        let st = &mut self.march[bin];
        if target.is_some_and(|(e, t)| bin_hidden(&st.stairs, rho, e, t)) {
            return true;
        }
        let radii = &self.radii;
        // Sectors 0..n_sec are those with a near radius below `rho`.
        let n_sec = radii.partition_point(|&r| r < rho).min(radii.len() - 1);
        if st.next >= n_sec {
            return false;
        }
        let e_lo = self.eye_lo[bin];
        let w = self.bins.width;
        let bulge_k = 1.0 - w.cos();
        let (da, db) = (self.bins.dirs[bin], self.bins.dirs[bin + 1]);
        let sector_box = |r: f64, r1: f64| {
            let bulge = r1 * bulge_k + 1e-9;
            let pts = [da * r, db * r, da * r1, db * r1];
            let mut bb = Aabb2::from_points(&pts).expand(bulge);
            bb.min += eye;
            bb.max += eye;
            bb
        };
        let (mut k, mut run) = (st.next, st.run.max(1));
        let mut found = false;
        while k < n_sec {
            let r = radii[k];
            // The blocker a new one must beat: the highest no farther than it.
            let best = best_at(&st.stairs, r + EPS_M);
            let floor_h = best.map_or(e_lo, |(_, hb)| hb.max(e_lo));
            if run >= 2 {
                let end = (k + run).min(n_sec);
                if end - k >= 2 {
                    let skip = dm_at_most(floor_h)
                        .is_some_and(|lim| grid.max_at_most(sector_box(r, radii[end]), lim));
                    if skip {
                        k = end;
                        run = (run * 2).min(1 << 12);
                        continue;
                    }
                    // Shorter runs from here on (halved at each failure).
                    run /= 2;
                }
            }
            // One sector.
            let h = grid.min_over(sector_box(r, radii[k + 1])) as f64 * DM;
            k += 1;
            if h > e_lo && best.is_none_or(|(_, hb)| h > hb) {
                insert_blocker(&mut st.stairs, r + EPS_M, h);
                run = 1;
                if decides((r + EPS_M, h)) {
                    found = true;
                    break;
                }
            } else {
                run = run.max(2);
            }
        }
        st.next = k;
        st.run = run;
        found
    }

    /// The near radii of the march's sectors (sector `k` is `[radii[k], radii[k+1]]`),
    /// up to the farthest reach: half a pixel near the eye, so that a wall two pixels
    /// thick holds a whole sector; about square sectors farther out.
    fn lay_out_radii(&mut self, d: f64) {
        let w = self.bins.width;
        let far = self.reach.iter().copied().fold(-1.0f64, f64::max);
        let radii = &mut self.radii;
        radii.clear();
        radii.push(0.0);
        let mut r = 0.0f64;
        while r < far {
            r += (0.5 * d).max(r * w);
            radii.push(r);
        }
        radii.push(r + (0.5 * d).max(r * w));
    }

    /// March every needed bin as far as its farthest target (the whole map).
    #[cfg(test)]
    fn march_all<R: Occluders>(&mut self, grid: &R, eye: DVec2) {
        for bin in 0..self.bins.n {
            if self.reach[bin] >= 0.0 {
                self.bin_hidden_at(grid, eye, bin, self.reach[bin], None);
            }
        }
    }

    /// The march one sector at a time (the reference of the skipping march).
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
            let e_lo = self.eye_lo[bin];
            let (da, db) = (self.bins.dirs[bin], self.bins.dirs[bin + 1]);
            let stairs = &mut self.march[bin].stairs;
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
                r = r1;
            }
        }
    }
}

/// The greatest height `v` (dm) with `v · DM ≤ h` in floating point (None if none):
/// `max ≤ v` decides exactly as `max · DM ≤ h`.
fn dm_at_most(h: f64) -> Option<u16> {
    if !(h >= 0.0) {
        return None;
    }
    // A first guess (the saturating cast truncates: a floor for h ≥ 0), made exact below.
    let mut v = (h * (1.0 / DM)) as u16;
    while v < u16::MAX && f64::from(v + 1) * DM <= h {
        v += 1;
    }
    while v > 0 && f64::from(v) * DM > h {
        v -= 1;
    }
    (f64::from(v) * DM <= h).then_some(v)
}

/// Whether a blocker of the staircase hides a target at nearest distance `rho`, top
/// height `t`, from the eye height `e`.
fn bin_hidden(stairs: &[(f64, f64)], rho: f64, e: f64, t: f64) -> bool {
    stairs
        .iter()
        .take_while(|&&(ra, _)| ra < rho - EPS_M)
        .any(|&(ra, h)| hides(ra, h, rho, e, t))
}

/// Whether the blocker `(ra, h)` hides a target at nearest distance `rho` (beyond
/// `ra`), top height `t`, from the eye height `e`: the sight line rises less than the
/// blocker's top by `ra` (a descending one always does), with slack towards visible.
#[inline]
fn hides(ra: f64, h: f64, rho: f64, e: f64, t: f64) -> bool {
    ra < rho - EPS_M && h > e + EPS_M && (t <= e || (t - e + EPS_M) * ra < (h - e - EPS_M) * rho)
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

    /// A map of `walls` seen from the origin, to test `t` with an eye at 2 m.
    fn map_with(
        walls: &[(f64, f64, f64, f64, f64)],
        t: &Target,
        bins: Bins,
    ) -> (PolarMap, MinPyramid) {
        let mut m = PolarMap::new(bins);
        m.need(t, 2.0);
        (m, MinPyramid::new(grid(walls)))
    }

    fn target(bins: &Bins, r: Vec<DVec2>) -> Target {
        Target::new(bins, &[(&r, true)])
    }

    #[test]
    fn wall_hides_low_block_not_tower() {
        let bins = Bins::new(512);
        let behind = target(&bins, rect(20.0, -5.0, 30.0, 5.0));
        let (mut m, p) = map_with(&[(10.0, -30.0, 11.0, 30.0, 10.0)], &behind, bins);
        let o = DVec2::ZERO;
        // Eye at 2 m: a 9 m block 20 m away behind a 10 m wall 10 m away is hidden...
        assert!(m.hidden(&p, o, &behind, 2.0, 9.0, 0));
        // ... a 40 m tower is not ((40-2)/20 > (10-2)/10).
        assert!(!m.hidden(&p, o, &behind, 2.0, 40.0, 0));
        // A street (t = 0) behind is hidden.
        assert!(m.hidden(&p, o, &behind, 2.0, 0.0, 0));
    }

    #[test]
    fn gap_between_walls_is_open() {
        let bins = Bins::new(512);
        let behind = target(&bins, rect(20.0, -5.0, 30.0, 5.0));
        let walls = [
            (10.0, -30.0, 11.0, -0.5, 10.0),
            (10.0, 0.5, 11.0, 30.0, 10.0),
        ];
        let (mut m, p) = map_with(&walls, &behind, bins);
        assert!(!m.hidden(&p, DVec2::ZERO, &behind, 2.0, 0.0, 0));
    }

    #[test]
    fn eye_inside_occluder_blocks_everything() {
        let bins = Bins::new(64);
        let far = target(&bins, rect(20.0, -5.0, 30.0, 5.0));
        let (mut m, p) = map_with(&[(-5.0, -5.0, 5.0, 5.0, 10.0)], &far, bins);
        assert!(m.hidden(&p, DVec2::ZERO, &far, 2.0, 9.0, 0));
    }

    #[test]
    fn target_around_eye_is_visible() {
        let bins = Bins::new(64);
        let t = target(&bins, rect(-5.0, -5.0, 5.0, 5.0));
        assert!(t.at_eye);
        let (mut m, p) = map_with(&[(-1.0, -1.0, 1.0, 1.0, 10.0)], &t, bins);
        assert!(!m.hidden(&p, DVec2::ZERO, &t, 2.0, 0.0, 0));
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

    /// A map needing every bin up to 60 m, with eyes from 1.5 m.
    fn needy(m: PolarMap) -> PolarMap {
        let mut m = m;
        for b in 0..m.bins.n {
            m.reach[b] = 60.0;
            m.eye_lo[b] = 1.5;
        }
        m
    }

    /// Whether the blockers found so far hide the target in every bin (no marching).
    fn hidden_by_stairs(m: &PolarMap, target: &Target, e: f64, t: f64) -> bool {
        !target.at_eye && !target.bins.is_empty() && m.open_bin(target, e, t).is_none()
    }

    /// Small targets all around the eye, 8 to 58 m away.
    fn ring_of_targets(bins: &Bins) -> Vec<Target> {
        (0..400)
            .map(|k| {
                let a = k as f64 * 0.0157;
                let c = DVec2::from_angle(a) * (8.0 + (k % 50) as f64);
                target(bins, rect(c.x, c.y, c.x + 0.8, c.y + 0.6))
            })
            .collect()
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
                let mut fast = needy(PolarMap::new(Bins::new(n)));
                let mut slow = fast.clone();
                fast.march_all(&p, eye);
                slow.march_one_by_one(&p, eye);
                let stairs = |m: &PolarMap| -> Vec<Vec<(f64, f64)>> {
                    m.march.iter().map(|b| b.stairs.clone()).collect()
                };
                assert_eq!(stairs(&fast), stairs(&slow), "seed {seed}, {n} bins");
                assert!(fast.march.iter().any(|b| !b.stairs.is_empty()));
            }
        }
    }

    /// The lazy test of each target, in any order and from any first bin, answers as
    /// the whole map marched first: laziness changes no answer.
    #[test]
    fn lazy_answers_equal_the_whole_march() {
        for seed in 1..7u64 {
            let p = MinPyramid::new(random_grid(seed, 0.5));
            let bins = Bins::new(1024);
            let mut whole = needy(PolarMap::new(bins.clone()));
            whole.march_all(&p, DVec2::ZERO);
            let mut lazy = needy(PolarMap::new(bins.clone()));
            let mut hidden = 0;
            for (k, t) in ring_of_targets(&bins).iter().enumerate().rev() {
                for z in [0.0, 6.0, 15.0, 28.0] {
                    let by_whole = hidden_by_stairs(&whole, t, 2.0, z);
                    let by_lazy = lazy.hidden(&p, DVec2::ZERO, t, 2.0, z, k % 5);
                    assert_eq!(by_whole, by_lazy, "seed {seed} target {k} z {z}");
                    hidden += usize::from(by_lazy);
                }
            }
            assert!(hidden > 0);
        }
    }

    /// A recycled map comes back empty: the same answers as a new one.
    #[test]
    fn recycled_map_is_empty() {
        let p = MinPyramid::new(random_grid(3, 0.5));
        let bins = Bins::new(1024);
        let targets = ring_of_targets(&bins);
        let answers = |m: &mut PolarMap| -> Vec<bool> {
            for t in &targets {
                m.need(t, 2.0);
            }
            targets
                .iter()
                .map(|t| m.hidden(&p, DVec2::ZERO, t, 2.0, 6.0, 0))
                .collect()
        };
        let fresh = answers(&mut PolarMap::new(bins.clone()));
        // Dirty a map far more than the second use will, then recycle it.
        let mut used = PolarMap::new(bins.clone());
        for t in &targets {
            used.need(t, 0.5);
        }
        for t in &targets {
            used.hidden(&p, DVec2::new(3.0, -2.0), t, 0.5, 30.0, 0);
        }
        used.recycle();
        let mut again = PolarMap::new(bins.clone());
        assert!(again.touched.is_empty());
        assert!(again.reach.iter().all(|&r| r == -1.0));
        assert!(again
            .march
            .iter()
            .all(|b| b.stairs.is_empty() && b.next == 0));
        assert_eq!(answers(&mut again), fresh);
    }

    /// A map seeded with the blockers of a coarser map hides every target the unseeded
    /// map hides (its soundness against the ground truth is the methods' tests').
    #[test]
    fn seeded_map_hides_at_least_the_unseeded() {
        for seed in 1..7u64 {
            let p = MinPyramid::new(random_grid(seed, 0.5));
            let coarse = needy(PolarMap::new(Bins::new(256)));
            let mut plain = needy(PolarMap::new(Bins::new(2048)));
            let mut seeded = needy(PolarMap::seeded(Bins::new(2048), coarse));
            let bins = Bins::new(2048);
            let mut hidden = 0;
            for (k, t) in ring_of_targets(&bins).iter().enumerate() {
                for z in [0.0, 6.0, 15.0, 28.0] {
                    let by_plain = plain.hidden(&p, DVec2::ZERO, t, 2.0, z, 0);
                    let by_seeded = seeded.hidden(&p, DVec2::ZERO, t, 2.0, z, 0);
                    assert!(!by_plain || by_seeded, "seed {seed} target {k} z {z}");
                    hidden += usize::from(by_seeded);
                }
            }
            assert!(hidden > 0);
        }
    }
}
