//! The from-centre occlusion test (§5), specialised to 2.5D: a *polar occlusion map*.
//!
//! Directions from the eye `S = (S_h, e)` are parametrised by azimuth (N bins over
//! 360°) and, inside a bin, by elevation handled *analytically*. For a height-field
//! occluder level `(P, h)` (footprint `P` extruded from the ground to `h`), a bin
//! receives a *blocker* `(r_a, h)` when the whole annular sector
//! `{θ ∈ bin, r ∈ [r_a, r_b]}` lies inside `P` — the *inner* coverage rule, at the
//! *farthest* entry depth `r_a` over the bin. Any sight line in that bin whose height
//! at horizontal distance `r_a` is below `h` is blocked there. Because level sets of
//! the fused height field are unions, shared walls leave no crack (NOTES §2).
//!
//! An occludee is tested through its nearest distance `ρ_min` in each bin it touches
//! (the *outer* rule: every touched bin counts, with the nearest depth): a target at
//! height `t` is hidden in the bin iff a blocker with `r_a < ρ_min` and `h > e`
//! satisfies `(t − e)·r_a < (h − e)·ρ_min` (a rising sight line passes below the
//! blocker's top at `r_a`; a descending one always does). Nothing is sampled: the
//! answer is conservative at any number of bins, only its tightness depends on it.
//!
//! The eye height `e` is a *query* parameter. This is what makes the map fit the
//! segment erosion of 2.5D scenes (see `mod.rs`): the occludee-dependent eye raise
//! that keeps §3.3 conservative for rising sight lines costs nothing here, whereas a
//! depth buffer would have to be re-rendered per occludee.
//!
//! Blockers of a bin are kept as a Pareto staircase (`r_a` increasing, `h` increasing):
//! a blocker both farther and lower than another never decides anything.

use sightline_geom::DVec2;
use std::f64::consts::TAU;

/// Annular sectors thinner than this (m) are not used as blockers.
const MIN_SECTOR_M: f64 = 1e-3;
/// Slack in the conservative direction for distance and height comparisons (m).
const EPS_M: f64 = 1e-6;

/// One clipped piece of an edge inside a bin wedge.
#[derive(Clone, Copy, Debug)]
struct Hit {
    bin: usize,
    lo: f64,
    hi: f64,
    crosses_mid: bool,
}

/// Why an edge could not be rasterized: it passes through the eye.
#[derive(Debug)]
pub struct ThroughEye;

/// Bin geometry shared by occluders and occludees.
#[derive(Clone, Debug)]
pub struct Bins {
    pub n: usize,
    width: f64,
    dirs: Vec<DVec2>,
    mids: Vec<DVec2>,
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
                .collect(),
            mids: (0..n)
                .map(|k| DVec2::from_angle((k as f64 + 0.5) * width))
                .collect(),
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
    /// Bins some target will be tested in; occluders are only rasterized there.
    pub needed: Vec<bool>,
    /// Per bin: blockers `(r_a, h)`, `r_a` increasing and `h` increasing.
    stairs: Vec<Vec<(f64, f64)>>,
    scratch: Vec<Hit>,
}

impl PolarMap {
    pub fn new(bins: Bins) -> Self {
        let n = bins.n;
        PolarMap {
            bins,
            needed: vec![false; n],
            stairs: vec![Vec::new(); n],
            scratch: Vec::new(),
        }
    }

    pub fn need(&mut self, t: &Target) {
        for &(b, _) in &t.bins {
            self.needed[b] = true;
        }
    }

    /// Whether some needed bin of the angular range of `corners` (relative to the eye,
    /// of a convex set not containing the eye, at distance ≥ `d_min`, height ≤ `h`)
    /// could still receive a useful blocker.
    pub fn could_improve(&self, corners: &[DVec2], d_min: f64, h: f64) -> bool {
        let mut any_needed = false;
        let mut improve = false;
        let n = corners.len();
        let mut visit = |bin: usize| {
            if self.needed[bin] {
                any_needed = true;
                if !self.stairs[bin]
                    .iter()
                    .any(|&(ra, hh)| ra <= d_min && hh >= h)
                {
                    improve = true;
                }
            }
        };
        // Bins of the convex hull = bins of its edges.
        let mut seen = vec![];
        for i in 0..n {
            if self
                .bins
                .edge(corners[i], corners[(i + 1) % n], |b, _, _, _| seen.push(b))
                .is_err()
            {
                return true;
            }
        }
        seen.sort_unstable();
        seen.dedup();
        for b in seen {
            visit(b);
        }
        any_needed && improve
    }

    /// Rasterize one occluder level: the interior-disjoint polygons `rings` (each a
    /// list of rings: exterior and holes, relative to the eye) extruded from the ground
    /// to `h`. A polygon with an edge through the eye is skipped (conservative).
    pub fn add_level(&mut self, polys: &[Vec<Vec<DVec2>>], h: f64) {
        for rings in polys {
            self.scratch.clear();
            let mut ok = true;
            let needed = &self.needed;
            let scratch = &mut self.scratch;
            for ring in rings {
                let n = ring.len();
                for i in 0..n {
                    let r = self
                        .bins
                        .edge(ring[i], ring[(i + 1) % n], |bin, lo, hi, c| {
                            if needed[bin] {
                                scratch.push(Hit {
                                    bin,
                                    lo,
                                    hi,
                                    crosses_mid: c,
                                })
                            }
                        });
                    if r.is_err() {
                        ok = false;
                    }
                }
            }
            if !ok {
                continue;
            }
            let mut hits = std::mem::take(&mut self.scratch);
            hits.sort_by(|a, b| a.bin.cmp(&b.bin).then(a.lo.total_cmp(&b.lo)));
            let mut i = 0;
            while i < hits.len() {
                let bin = hits[i].bin;
                let mut j = i;
                while j < hits.len() && hits[j].bin == bin {
                    j += 1;
                }
                self.bin_sectors(bin, &hits[i..j], h);
                i = j;
            }
            self.scratch = hits;
        }
    }

    /// Merge the radial ranges of the boundary in one bin into clusters; the gaps are
    /// boundary-free annular sectors, inside the polygon iff the middle ray crosses the
    /// boundary an odd number of times beyond them.
    fn bin_sectors(&mut self, bin: usize, hits: &[Hit], h: f64) {
        // clusters: (lo, hi, parity)
        let mut clusters: Vec<(f64, f64, bool)> = Vec::new();
        for hit in hits {
            match clusters.last_mut() {
                Some(c) if hit.lo <= c.1 => {
                    c.1 = c.1.max(hit.hi);
                    c.2 ^= hit.crosses_mid;
                }
                _ => clusters.push((hit.lo, hit.hi, hit.crosses_mid)),
            }
        }
        let mut inside = false;
        for idx in (0..clusters.len()).rev() {
            inside ^= clusters[idx].2;
            if inside {
                let ra = if idx == 0 { 0.0 } else { clusters[idx - 1].1 };
                let rb = clusters[idx].0;
                if rb - ra > MIN_SECTOR_M {
                    insert_blocker(&mut self.stairs[bin], ra + EPS_M, h);
                }
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

    fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<Vec<DVec2>> {
        vec![vec![
            DVec2::new(x0, y0),
            DVec2::new(x1, y0),
            DVec2::new(x1, y1),
            DVec2::new(x0, y1),
        ]]
    }

    fn target(bins: &Bins, r: Vec<Vec<DVec2>>) -> Target {
        Target::new(bins, &[(r[0].clone(), true)])
    }

    fn map_with(polys: &[Vec<Vec<DVec2>>], h: f64, t: &Target) -> PolarMap {
        let mut m = PolarMap::new(Bins::new(512));
        m.need(t);
        m.add_level(polys, h);
        m
    }

    #[test]
    fn wall_hides_low_block_not_tower() {
        let bins = Bins::new(512);
        let wall = rect(10.0, -30.0, 11.0, 30.0);
        let behind = target(&bins, rect(20.0, -5.0, 30.0, 5.0));
        let m = map_with(&[wall], 10.0, &behind);
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
        let walls = [rect(10.0, -30.0, 11.0, -0.5), rect(10.0, 0.5, 11.0, 30.0)];
        let behind = target(&bins, rect(20.0, -5.0, 30.0, 5.0));
        let m = map_with(&walls, 10.0, &behind);
        assert!(!m.hidden(&behind, 2.0, 0.0));
    }

    #[test]
    fn eye_inside_occluder_blocks_everything() {
        let bins = Bins::new(64);
        let around = rect(-5.0, -5.0, 5.0, 5.0);
        let far = target(&bins, rect(20.0, -5.0, 30.0, 5.0));
        let m = map_with(&[around], 10.0, &far);
        assert!(m.hidden(&far, 2.0, 9.0));
    }

    #[test]
    fn target_around_eye_is_visible() {
        let bins = Bins::new(64);
        let t = target(&bins, rect(-5.0, -5.0, 5.0, 5.0));
        assert!(t.at_eye);
        let m = map_with(&[rect(-1.0, -1.0, 1.0, 1.0)], 10.0, &t);
        assert!(!m.hidden(&t, 2.0, 0.0));
    }
}
