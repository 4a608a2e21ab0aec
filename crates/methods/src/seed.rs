//! Seeding a PVS with objects seen along single rays from a few eyes in the cell,
//! shared by `dual-ray` and the erosion family.
//!
//! On a street cell of a large city many tests answer *visible* (the objects along the
//! streets the cell opens onto), and a visible answer is the most expensive one: for
//! `dual-ray` the whole shaft, kilometres long, is gathered and refined down to the
//! finest rows (§5.2 of Koltun et al. 2001); for erosion the object is tested again in
//! every sub-cell down to the deepest level. Yet most of these objects are seen from
//! almost anywhere in the cell. So before the tests we cast rays from a few eyes on the
//! cell's top face, in many azimuths, through the occluders both methods use
//! (ground-based inner prisms), and accept every object a ray reaches first. The
//! methods then skip the tests of accepted objects (and `dual-ray` those of the kd-nodes
//! that contain one: a node holding a visible object is visible).
//!
//! **Why no PVS changes.** An accepted object `O` is met by a 3D ray from a point of the
//! cell that passes strictly above every ground-based occluder before `O`'s outer prism
//! (2.5D: along an azimuth, an occluder entered at distance `d` with top `h` blocks the
//! elevations below `(h − z) / d`, and nothing else blocks in the methods' model).
//! * `dual-ray`: that ray lies in a vertical plane through both boxes, so no planar
//!   problem of §4 can cover it: both `dual-ray-exact` and `dual-ray` report `O` and
//!   every node above it anyway.
//! * erosion: its occluders are an inner raster of the same prisms (a subset of them),
//!   and Theorems 1 and 2 hide an object only if the occluders block every sight line
//!   from the cell to it; closed courtyards are filled only above the escape height of
//!   every free eye of the cell (`erosion::field`), which such a ray, rising from below
//!   that height, clears too. So every erosion method reports `O` anyway.
//!
//! The seed only spares the proofs. Errors of rounding can only accept an object whose
//! ray grazes an occluder: that object is kept, never dropped, so conservativeness does
//! not depend on this module at all. Tests compare the PVS with and without the seed.
//!
//! `dual-ray` also *aims* single rays of the same march at one box whose test the near
//! occluders did not settle ([`SeedGrid::aim`]): the march stops past the box or once
//! the horizon hides its top, and what it meets first is accepted the same way.
//!
//! Per azimuth the march stops once the running horizon is above what the tallest prism
//! of the scene could reach further on, so azimuths into a facade cost a few buckets and
//! only the ones along open streets run far.
//! Along those, most prisms of a bucket stand beside the ray: a ray missing a prism's
//! (slightly widened) bounding box is passed without testing its edges.

use sightline_geom::{Aabb3, DVec2};
use sightline_scene::occluders::{local_rings, BucketGrid, Occluder, Stamps, GROUND_M};
use sightline_scene::Scene;

/// Candidate eyes per side of the cell's top face.
const CANDIDATES_PER_SIDE: usize = 8;

/// Eyes used, spread over the free candidates.
const MAX_EYES: usize = 8;

/// Uniform azimuths per eye.
const AZIMUTHS: usize = 256;

/// Rays added per eye by bisection, at most, down to this angle (radians).
const REFINE_RAYS: usize = 6000;
const MIN_AZIMUTH_STEP: f64 = 2e-5;

/// Relative margin by which a ray must clear the horizon to count (rounding).
const CLEAR_MARGIN: f64 = 1e-9;

/// Per-thread buffers of [`SeedGrid::mark`].
#[derive(Default)]
pub(crate) struct SeedScratch {
    /// Per prism, the last ray that met it.
    stamps: Stamps,
    /// `(distance, last crossing, prism, as an occluder)`.
    events: Vec<(f64, f64, u32, bool)>,
    /// The objects marked since the last [`SeedGrid::mark`] or [`SeedGrid::aim`] began.
    pub(crate) marked: Vec<u32>,
}

/// Where a march may stop early: beyond distance `t_max`, or once the horizon reaches
/// `slope` (no target is left above it).
#[derive(Clone, Copy, Debug)]
struct Limit {
    t_max: f64,
    slope: f64,
}

impl Limit {
    const NONE: Limit = Limit {
        t_max: f64::INFINITY,
        slope: f64::INFINITY,
    };
}

/// One prism of the seed: an occludee (an object's outer prism), an occluder (a
/// ground-based inner prism), or both when an object's outer and inner prisms share
/// their footprint (a 2.5D block): its edges are then crossed once per ray.
#[derive(Clone, Copy, Debug)]
struct Prism {
    /// Edges `edges[first..first + len]`.
    first: u32,
    len: u32,
    /// The occludee: base and top of the outer prism of `object`.
    base: f64,
    top: f64,
    /// The object of the occludee; `u32::MAX` for an occluder only.
    object: u32,
    /// The occluder's top; −∞ for an occludee only.
    occ_top: f64,
}

impl Prism {
    fn occludes(&self) -> bool {
        self.occ_top > f64::NEG_INFINITY
    }
    /// Tallest top of either role.
    fn reach(&self) -> f64 {
        self.top.max(self.occ_top)
    }
}

/// The prisms of a scene in a uniform grid, in the method's local frame.
pub(crate) struct SeedGrid {
    prisms: Vec<Prism>,
    edges: Vec<[DVec2; 2]>,
    grid: BucketGrid,
    /// Tallest prism top per bucket.
    bucket_top: Vec<f64>,
    /// Tallest prism top.
    max_top: f64,
    /// Footprint bounds of the prism of each entry of `grid.ids`, as centre and half
    /// extent, slightly widened ([`widened`]): a bucket's boxes lie together.
    bucket_boxes: Vec<(DVec2, DVec2)>,
    /// Whether a prism whose box the ray misses is passed without its edges (off only
    /// to compare).
    pub(crate) cull_boxes: bool,
}

impl SeedGrid {
    /// Occluders (`occ`, local) and the outer prisms of every object of `scene`
    /// (translated by `-origin`).
    pub(crate) fn new(scene: &Scene, origin: DVec2, occ: &[Occluder]) -> Self {
        let mut prisms = Vec::new();
        let mut edges: Vec<[DVec2; 2]> = Vec::new();
        let mut boxes: Vec<(DVec2, DVec2)> = Vec::new();
        let mut push = |rings: &[Vec<DVec2>],
                        (base, top, object): (f64, f64, u32),
                        occ_top: f64,
                        prisms: &mut Vec<Prism>| {
            let first = edges.len() as u32;
            let mut min = DVec2::splat(f64::INFINITY);
            let mut max = DVec2::splat(f64::NEG_INFINITY);
            for r in rings {
                for (i, a) in r.iter().enumerate() {
                    let b = r[(i + 1) % r.len()];
                    edges.push([*a, b]);
                    min = min.min(*a);
                    max = max.max(*a);
                }
            }
            let len = edges.len() as u32 - first;
            // Flat objects on the ground (streets, squares) are never reached above the
            // ground by a ray, nor do they block one: they stay with the tests.
            let top = if top.is_finite() && top > GROUND_M {
                top
            } else {
                f64::NEG_INFINITY
            };
            let object = if top > f64::NEG_INFINITY {
                object
            } else {
                u32::MAX
            };
            if len >= 3 && min.is_finite() && max.is_finite() && top.max(occ_top) > GROUND_M {
                prisms.push(Prism {
                    first,
                    len,
                    base,
                    top,
                    object,
                    occ_top,
                });
                boxes.push((min, max));
            } else {
                edges.truncate(first as usize);
            }
        };
        // Occluders by object (collected in object order).
        let mut by_object: Vec<Vec<usize>> = vec![Vec::new(); scene.objects.len()];
        for (k, o) in occ.iter().enumerate() {
            if let Some(v) = by_object.get_mut(o.object as usize) {
                v.push(k);
            }
        }
        let mut merged = vec![false; occ.len()];
        for (id, o) in scene.objects.iter().enumerate() {
            for p in &o.outer {
                let rings = local_rings(&p.footprint, origin);
                let same = by_object[id]
                    .iter()
                    .copied()
                    .find(|&k| !merged[k] && occ[k].rings == rings);
                let occ_top = match same {
                    Some(k) => {
                        merged[k] = true;
                        occ[k].height
                    }
                    None => f64::NEG_INFINITY,
                };
                push(&rings, (p.base, p.top, id as u32), occ_top, &mut prisms);
            }
        }
        for (k, o) in occ.iter().enumerate() {
            if !merged[k] {
                push(
                    &o.rings,
                    (0.0, f64::NEG_INFINITY, u32::MAX),
                    o.height,
                    &mut prisms,
                );
            }
        }
        // About two prisms per bucket, at most 4096 buckets per side.
        let grid = BucketGrid::from_boxes(&boxes, |ext, n| {
            let per = (ext.x * ext.y / n.max(1) as f64).sqrt() * 1.5;
            per.max(ext.x.max(ext.y) / 4096.0).max(4.0)
        });
        let bucket_top = grid.max_per_bucket(|i| prisms[i as usize].reach());
        let boxes = widened(boxes);
        let bucket_boxes = grid.ids.iter().map(|&i| boxes[i as usize]).collect();
        SeedGrid {
            bucket_boxes,
            max_top: prisms.iter().map(|p| p.reach()).fold(0.0, f64::max),
            prisms,
            edges,
            grid,
            bucket_top,
            cull_boxes: true,
        }
    }

    fn prism_edges(&self, p: &Prism) -> &[[DVec2; 2]] {
        &self.edges[p.first as usize..(p.first + p.len) as usize]
    }

    /// Whether `q` is inside or on the boundary of any prism's footprint: an eye there
    /// is inside it or above or below it, where the first edge a ray crosses is not its
    /// entry; such eyes are skipped.
    fn occupied(&self, q: DVec2) -> bool {
        self.grid
            .bucket(self.grid.col(q.x), self.grid.row(q.y))
            .iter()
            .any(|&i| {
                let edges = self.prism_edges(&self.prisms[i as usize]);
                let mut inside = false;
                for [a, b] in edges {
                    if (*b - *a).perp_dot(q - *a) == 0.0
                        && q.x >= a.x.min(b.x)
                        && q.x <= a.x.max(b.x)
                        && q.y >= a.y.min(b.y)
                        && q.y <= a.y.max(b.y)
                    {
                        return true;
                    }
                    if (a.y > q.y) != (b.y > q.y)
                        && q.x < a.x + (q.y - a.y) * (b.x - a.x) / (b.y - a.y)
                    {
                        inside = !inside;
                    }
                }
                inside
            })
    }

    /// Mark in `seen` every object reached first by a ray from one of the eyes on the
    /// top face of `cell` (local frame). Returns the number of objects marked.
    pub(crate) fn mark(&self, cell: &Aabb3, seen: &mut [bool], s: &mut SeedScratch) -> usize {
        self.mark_from(&self.eyes(cell), cell.max.z, seen, s)
    }

    /// [`SeedGrid::mark`] from the given eyes at height `z` (the cell's [`SeedGrid::eyes`]).
    pub(crate) fn mark_from(
        &self,
        eyes: &[DVec2],
        z: f64,
        seen: &mut [bool],
        s: &mut SeedScratch,
    ) -> usize {
        s.marked.clear();
        let mut count = 0;
        for &eye in eyes {
            let mut ray = |a: f64, seen: &mut [bool], s: &mut SeedScratch| {
                let d = DVec2::new(a.cos(), a.sin());
                let (m, sig) = self.march(eye, z, d, Limit::NONE, seen, s);
                count += m;
                sig
            };
            // Uniform azimuths, then bisection between neighbours whose horizons were
            // raised by different occluders (facades along a long street are seen at
            // grazing angles, thinner than any uniform step).
            let step = std::f64::consts::TAU / AZIMUTHS as f64;
            let sigs: Vec<u64> = (0..AZIMUTHS)
                .map(|k| ray(k as f64 * step, seen, s))
                .collect();
            let mut budget = REFINE_RAYS;
            let mut stack: Vec<(f64, u64, f64, u64)> = (0..AZIMUTHS)
                .map(|k| {
                    (
                        k as f64 * step,
                        sigs[k],
                        (k + 1) as f64 * step,
                        sigs[(k + 1) % AZIMUTHS],
                    )
                })
                .collect();
            while let Some((a0, s0, a1, s1)) = stack.pop() {
                if s0 == s1 || a1 - a0 < MIN_AZIMUTH_STEP || budget == 0 {
                    continue;
                }
                budget -= 1;
                let am = 0.5 * (a0 + a1);
                let sm = ray(am, seen, s);
                stack.push((a0, s0, am, sm));
                stack.push((am, sm, a1, s1));
            }
        }
        count
    }

    /// One ray from `eye` (at height `z`) through the point `at` of `target`'s
    /// footprint (local frame), stopping past the target or once the horizon hides its
    /// top: every object it reaches first is marked in `seen` (as by
    /// [`SeedGrid::mark`], with the same guarantee) and listed in `s.marked`. Returns
    /// their number.
    pub(crate) fn aim(
        &self,
        eye: DVec2,
        z: f64,
        target: &Aabb3,
        at: DVec2,
        seen: &mut [bool],
        s: &mut SeedScratch,
    ) -> usize {
        s.marked.clear();
        let (lo, hi) = (target.min.truncate(), target.max.truncate());
        let to = at - eye;
        let len = to.length();
        if !(len > 0.0) || !len.is_finite() {
            return 0;
        }
        let near = eye.clamp(lo, hi).distance(eye);
        let far = (eye - lo).abs().max((eye - hi).abs()).length();
        let top = target.max.z - z;
        let slope = if top >= 0.0 {
            if near > 0.0 {
                top / near
            } else {
                f64::INFINITY
            }
        } else {
            top / far
        };
        let limit = Limit { t_max: far, slope };
        self.march(eye, z, to / len, limit, seen, s).0
    }

    /// Up to [`MAX_EYES`] points of the top face of `cell` outside every footprint,
    /// spread out (farthest point first, starting next to the centre).
    pub(crate) fn eyes(&self, cell: &Aabb3) -> Vec<DVec2> {
        let n = CANDIDATES_PER_SIDE;
        let f = |k: usize| (k as f64 + 0.5) / n as f64;
        let mut free: Vec<DVec2> = (0..n * n)
            .map(|k| {
                DVec2::new(
                    cell.min.x + (cell.max.x - cell.min.x) * f(k % n),
                    cell.min.y + (cell.max.y - cell.min.y) * f(k / n),
                )
            })
            .filter(|q| q.is_finite() && !self.occupied(*q))
            .collect();
        let centre = cell.center().truncate();
        let mut eyes = Vec::new();
        let mut dist: Vec<f64> = free.iter().map(|q| -q.distance(centre)).collect();
        while eyes.len() < MAX_EYES && !free.is_empty() {
            let (i, _) = dist
                .iter()
                .enumerate()
                .max_by(|a, b| a.1.total_cmp(b.1))
                .expect("non-empty");
            let e = free.swap_remove(i);
            dist.swap_remove(i);
            for (q, d) in free.iter().zip(dist.iter_mut()) {
                let to_e = q.distance(e);
                *d = if eyes.is_empty() { to_e } else { d.min(to_e) };
            }
            eyes.push(e);
        }
        eyes
    }

    /// One azimuth: walk the buckets along the ray from `eye` in direction `d`, in order,
    /// keeping the horizon (the highest blocked slope) of the occluders entered so far.
    fn march(
        &self,
        eye: DVec2,
        z: f64,
        d: DVec2,
        limit: Limit,
        seen: &mut [bool],
        s: &mut SeedScratch,
    ) -> (usize, u64) {
        let mut sig: u64 = 0xcbf2_9ce4_8422_2325;
        let gen = s.stamps.next(self.prisms.len());
        let mut marked = 0;
        let mut horizon = f64::NEG_INFINITY;
        // Start where the ray enters the grid (an eye may stand outside it).
        let hi = self.grid.origin
            + DVec2::new(self.grid.nx as f64, self.grid.ny as f64) * self.grid.cell_m;
        let (mut t_in, mut t_out) = (0.0f64, f64::INFINITY);
        for (p, dd, lo, hi) in [
            (eye.x, d.x, self.grid.origin.x, hi.x),
            (eye.y, d.y, self.grid.origin.y, hi.y),
        ] {
            if dd == 0.0 {
                if p < lo || p >= hi {
                    return (0, sig);
                }
            } else {
                let (a, b) = ((lo - p) / dd, (hi - p) / dd);
                t_in = t_in.max(a.min(b));
                t_out = t_out.min(a.max(b));
            }
        }
        if t_in >= t_out {
            return (0, sig);
        }
        let start = eye + d * t_in;
        let (mut c, mut r) = (self.grid.col(start.x) as i64, self.grid.row(start.y) as i64);
        let n = DVec2::new(-d.y, d.x);
        let step_c: i64 = if d.x > 0.0 { 1 } else { -1 };
        let step_r: i64 = if d.y > 0.0 { 1 } else { -1 };
        let next = |idx: i64, step: i64, o: f64, p: f64, dd: f64| -> f64 {
            if dd == 0.0 {
                return f64::INFINITY;
            }
            let edge = o + (idx + i64::from(step > 0)) as f64 * self.grid.cell_m;
            ((edge - p) / dd).max(0.0)
        };
        let mut t_c = next(c, step_c, self.grid.origin.x, eye.x, d.x);
        let mut t_r = next(r, step_r, self.grid.origin.y, eye.y, d.y);
        let dt_c = if d.x == 0.0 {
            f64::INFINITY
        } else {
            self.grid.cell_m / d.x.abs()
        };
        let dt_r = if d.y == 0.0 {
            f64::INFINITY
        } else {
            self.grid.cell_m / d.y.abs()
        };
        let mut t0 = t_in;
        loop {
            let t1 = t_c.min(t_r);
            // Nothing further can rise above the horizon (a prism under the eye has a
            // negative slope, below a horizon ≥ 0).
            if t0 > 0.0 && horizon >= 0.0 && horizon * t0 >= self.max_top - z {
                break;
            }
            if t0 > limit.t_max || horizon >= limit.slope {
                break;
            }
            let events = &mut s.events;
            events.clear();
            let b = r as usize * self.grid.nx + c as usize;
            // A bucket whose tallest prism stays under the horizon changes nothing (the
            // slope to a top under the eye is highest at the bucket's far end).
            let top = self.bucket_top[b] - z;
            let reach = if top >= 0.0 { top / t0 } else { top / t1 };
            let entries = if t0 > 0.0 && horizon >= reach {
                0..0
            } else {
                self.grid.start[b] as usize..self.grid.start[b + 1] as usize
            };
            for k in entries {
                // Most prisms of a bucket stand beside the ray: their box, stored with
                // the bucket, says so at once.
                if self.cull_boxes && misses_box(self.bucket_boxes[k], eye, n) {
                    continue;
                }
                let i = self.grid.ids[k];
                if s.stamps.marks[i as usize] == gen {
                    continue;
                }
                let p = &self.prisms[i as usize];
                let occludee = p.object != u32::MAX && !seen[p.object as usize];
                if !occludee && !p.occludes() {
                    continue;
                }
                let crossed = crossings(self.prism_edges(p), eye, d);
                let Some((t, t_last)) = crossed else {
                    s.stamps.marks[i as usize] = gen; // the ray never enters it
                    continue;
                };
                // A prism is handled in the first bucket reached at or after the ray's
                // entry into it (an entry rounded into the previous bucket comes late).
                if t < t1 {
                    s.stamps.marks[i as usize] = gen;
                    if occludee {
                        events.push((t, t_last, i, false));
                    }
                    if p.occludes() {
                        events.push((t, t_last, i, true));
                    }
                }
            }
            // Occludees before occluders at the same distance: an object's own inner
            // prism does not hide its outer wall.
            events.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then_with(|| a.3.cmp(&b.3)));
            for &(t, t_last, i, as_occluder) in events.iter() {
                let p = &self.prisms[i as usize];
                if as_occluder {
                    // An occluder below the eye blocks the descending rays that reach
                    // its top anywhere over it: up to the slope to its far side.
                    let slope_top = if p.occ_top < z {
                        (p.occ_top - z) / t_last
                    } else {
                        (p.occ_top - z) / t
                    };
                    if slope_top > horizon {
                        horizon = slope_top;
                        sig = (sig ^ u64::from(i)).wrapping_mul(0x0100_0000_01b3);
                    }
                    continue;
                }
                let slope_top = (p.top - z) / t;
                let low = horizon.max((p.base - z) / t).max(-z / t);
                if slope_top > low + CLEAR_MARGIN * (1.0 + low.abs()) && !seen[p.object as usize] {
                    seen[p.object as usize] = true;
                    s.marked.push(p.object);
                    marked += 1;
                }
            }
            if !t1.is_finite() {
                break;
            }
            if t_c < t_r {
                c += step_c;
                t_c += dt_c;
            } else {
                r += step_r;
                t_r += dt_r;
            }
            if c < 0 || r < 0 || c >= self.grid.nx as i64 || r >= self.grid.ny as i64 {
                break;
            }
            t0 = t1;
        }
        (marked, sig)
    }
}

/// `boxes` widened by a millionth of the scene's extent, far above the rounding of
/// [`crossings`] and of [`misses_box`] (a ray missing a widened box crosses none of its
/// edges), as centre and half extent.
fn widened(boxes: Vec<(DVec2, DVec2)>) -> Vec<(DVec2, DVec2)> {
    let reach = boxes
        .iter()
        .map(|(a, b)| a.abs().max(b.abs()).max_element())
        .fold(1.0, f64::max);
    let margin = DVec2::splat(1e-6 * reach);
    boxes
        .into_iter()
        .map(|(a, b)| (0.5 * (a + b), 0.5 * (b - a) + margin))
        .collect()
}

/// Whether the line through `eye` with normal `n` (the ray's direction turned by a
/// right angle) misses the box of centre `c` and half extent `h`: the box's distance to
/// the line exceeds its half width across it. A box behind the eye may pass; its edges
/// are then tested ([`crossings`] keeps only `t > 0`).
#[inline]
fn misses_box((c, h): (DVec2, DVec2), eye: DVec2, n: DVec2) -> bool {
    (c - eye).dot(n).abs() > h.dot(n.abs())
}

/// Distances along the ray `eye + t·d` (t > 0) to the first and the last crossing of an
/// edge.
fn crossings(edges: &[[DVec2; 2]], eye: DVec2, d: DVec2) -> Option<(f64, f64)> {
    let mut best = f64::INFINITY;
    let mut last = f64::NEG_INFINITY;
    for [a, b] in edges {
        let e = *b - *a;
        let den = d.perp_dot(e);
        if den == 0.0 {
            continue;
        }
        let w = *a - eye;
        let t = w.perp_dot(e) / den;
        let s = w.perp_dot(d) / den;
        if t > 0.0 && (0.0..=1.0).contains(&s) {
            best = best.min(t);
            last = last.max(t);
        }
    }
    best.is_finite().then_some((best, last))
}

#[cfg(test)]
mod tests {
    use super::*;
    use sightline_geom::{DVec3, Polygon};
    use sightline_scene::occluders::collect_occluders;
    use sightline_scene::Object;

    fn marks(scene: &Scene, cell: Aabb3) -> Vec<bool> {
        let occ = collect_occluders(scene, DVec2::ZERO);
        let g = SeedGrid::new(scene, DVec2::ZERO, &occ);
        let mut seen = vec![false; scene.objects.len()];
        g.mark(&cell, &mut seen, &mut SeedScratch::default());
        seen
    }

    #[test]
    fn a_wall_hides_the_low_house_behind_it_but_not_the_tower() {
        let r = |x0, y0, x1, y1| Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1));
        let scene = Scene::from_objects(vec![
            Object::block(None, r(20.0, -50.0, 22.0, 50.0), 0.0, 10.0),
            Object::block(None, r(40.0, 0.0, 50.0, 10.0), 0.0, 6.0),
            Object::block(None, r(40.0, 20.0, 50.0, 30.0), 0.0, 40.0),
        ]);
        let cell = Aabb3::new(DVec3::new(0.0, 0.0, 1.5), DVec3::new(10.0, 10.0, 2.0));
        assert_eq!(marks(&scene, cell), vec![true, false, true]);
    }

    #[test]
    fn an_eye_inside_the_grid_sees_along_the_street_only() {
        let r = |x0, y0, x1, y1| Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1));
        // A street along x between two rows; a far house in the street's axis, one
        // behind the north row.
        let scene = Scene::from_objects(vec![
            Object::block(None, r(-100.0, 10.0, 300.0, 30.0), 0.0, 20.0),
            Object::block(None, r(-100.0, -30.0, 300.0, -10.0), 0.0, 20.0),
            Object::block(None, r(400.0, -5.0, 410.0, 5.0), 0.0, 5.0),
            Object::block(None, r(100.0, 40.0, 110.0, 50.0), 0.0, 5.0),
        ]);
        let cell = Aabb3::new(DVec3::new(0.0, -5.0, 1.5), DVec3::new(10.0, 5.0, 2.0));
        assert_eq!(marks(&scene, cell), vec![true, true, true, false]);
    }

    #[test]
    fn a_wall_under_the_eye_hides_what_stands_low_behind_it() {
        // Eyes at 2 m look down over a 1.5 m wall 3 m thick: a 1.3 m shed 1 m behind it
        // is hidden (every ray over the wall's far edge is still above 1.3 m there); a
        // 1.8 m one further on is seen.
        let r = |x0, y0, x1, y1| Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1));
        let scene = Scene::from_objects(vec![
            Object::block(None, r(10.0, -50.0, 13.0, 50.0), 0.0, 1.5),
            Object::block(None, r(14.0, -1.0, 15.0, 1.0), 0.0, 1.3),
            Object::block(None, r(40.0, -1.0, 41.0, 1.0), 0.0, 1.8),
        ]);
        let cell = Aabb3::new(DVec3::new(0.0, -2.0, 1.5), DVec3::new(5.0, 2.0, 2.0));
        assert_eq!(marks(&scene, cell), vec![true, false, true]);
    }
}

#[cfg(test)]
mod cull_props {
    use super::*;
    use proptest::prelude::*;
    use sightline_geom::{DVec3, Polygon};
    use sightline_scene::occluders::collect_occluders;
    use sightline_scene::Object;

    /// `(x, y, w, d)` on a 5 m raster and a height.
    type Building = (i32, i32, i32, i32, f64);
    /// `(x, y, size)` of a cell, in metres.
    type Cell = (i32, i32, i32);

    /// Blocks on a 5 m raster, many touching, low sheds under the eye and a few towers,
    /// some rotated (edges off the axes), and a few cells in and around them.
    fn city() -> impl Strategy<Value = (Vec<(Building, bool)>, Vec<Cell>)> {
        let height = prop_oneof![
            6 => 2u32..30,
            2 => 1u32..3,
            1 => 60u32..300,
        ];
        let building = (
            (0i32..60, 0i32..60, 1i32..5, 1i32..5, height),
            any::<bool>(),
        )
            .prop_map(|((x, y, w, d, h), rot)| ((x, y, w, d, f64::from(h) * 0.5), rot));
        let cell = (-20i32..320, -20i32..320, 2i32..40);
        (
            prop::collection::vec(building, 8..80),
            prop::collection::vec(cell, 1..4),
        )
    }

    fn footprint((x, y, w, d, _): Building, rotated: bool) -> Polygon {
        let (x, y) = (f64::from(x) * 5.0, f64::from(y) * 5.0);
        let (w, d) = (f64::from(w) * 5.0, f64::from(d) * 5.0);
        if rotated {
            // A diamond in the same box.
            let (cx, cy) = (x + 0.5 * w, y + 0.5 * d);
            Polygon::new(
                vec![
                    DVec2::new(cx, y),
                    DVec2::new(x + w, cy),
                    DVec2::new(cx, y + d),
                    DVec2::new(x, cy),
                ],
                vec![],
            )
        } else {
            Polygon::rect(DVec2::new(x, y), DVec2::new(x + w, y + d))
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 32, ..ProptestConfig::default() })]

        /// Passing the prisms whose box a ray misses marks exactly what testing every
        /// edge marks.
        #[test]
        fn box_culling_changes_no_mark((buildings, cells) in city()) {
            let scene = Scene::from_objects(
                buildings
                    .iter()
                    .map(|&(b, rot)| Object::block(None, footprint(b, rot), 0.0, b.4))
                    .collect(),
            );
            let occ = collect_occluders(&scene, DVec2::ZERO);
            let mut g = SeedGrid::new(&scene, DVec2::ZERO, &occ);
            for (x, y, s) in cells {
                let (x, y, s) = (f64::from(x) + 0.3, f64::from(y) + 0.6, f64::from(s));
                let cell = Aabb3::new(DVec3::new(x, y, 1.5), DVec3::new(x + s, y + s, 2.0));
                let mut marks = [Vec::new(), Vec::new()];
                for (on, m) in [true, false].into_iter().zip(&mut marks) {
                    g.cull_boxes = on;
                    *m = vec![false; scene.objects.len()];
                    g.mark(&cell, m, &mut SeedScratch::default());
                }
                prop_assert_eq!(&marks[0], &marks[1]);
            }
        }
    }
}
