//! Test support for the erosion methods: fixture scenes and an exact sampled
//! visibility oracle (segment vs. prism interiors), a lower bound of the visible set.
#![allow(dead_code)]

use sightline_geom::{DVec2, DVec3, Polygon, ViewCell};
use sightline_scene::{Object, Prism, Scene};

pub const METHODS: [&str; 5] = [
    "erosion",
    "erosion-segment",
    "erosion-cell",
    "shrink-sphere",
    "erosion-rays",
];

pub fn street(x0: f64, y0: f64, x1: f64, y1: f64) -> Object {
    Object::flat(
        None,
        vec![Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1))],
    )
}

pub fn cell(x0: f64, y0: f64, x1: f64, y1: f64) -> ViewCell {
    ViewCell::from_array([x0, y0, 1.5, x1, y1, 2.0]).expect("valid cell")
}

/// Does the open segment `a → b` pass through the interior of the prism?
fn segment_hits_prism(a: DVec3, b: DVec3, p: &Prism) -> bool {
    if p.top <= p.base {
        return false;
    }
    // Parameter range where base < z < top.
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let dz = b.z - a.z;
    if dz.abs() < 1e-15 {
        if !(a.z > p.base && a.z < p.top) {
            return false;
        }
    } else {
        let (u0, u1) = ((p.base - a.z) / dz, (p.top - a.z) / dz);
        let (lo, hi) = if u0 < u1 { (u0, u1) } else { (u1, u0) };
        t0 = t0.max(lo);
        t1 = t1.min(hi);
    }
    if t1 - t0 <= 1e-12 {
        return false;
    }
    let (a2, b2) = (a.truncate(), b.truncate());
    let pa = a2 + (b2 - a2) * t0;
    let pb = a2 + (b2 - a2) * t1;
    // Split [pa, pb] at the crossings with the footprint's edges, test midpoints.
    let d = pb - pa;
    let mut cuts = vec![0.0, 1.0];
    for (e0, e1) in p.footprint.edges() {
        let e = e1 - e0;
        let den = d.perp_dot(e);
        if den.abs() < 1e-15 {
            continue;
        }
        let s = (e0 - pa).perp_dot(e) / den;
        let u = (e0 - pa).perp_dot(d) / den;
        if (0.0..=1.0).contains(&s) && (-1e-12..=1.0 + 1e-12).contains(&u) {
            cuts.push(s);
        }
    }
    cuts.sort_by(f64::total_cmp);
    cuts.windows(2).any(|w| {
        w[1] - w[0] > 1e-9 && {
            let m = pa + d * (0.5 * (w[0] + w[1]));
            strictly_inside(&p.footprint, m)
        }
    })
}

fn strictly_inside(p: &Polygon, m: DVec2) -> bool {
    // Inside and not within 1e-7 of the boundary (grazing sight lines do not count).
    if !p.contains(m) {
        return false;
    }
    p.edges().all(|(a, b)| {
        let e = b - a;
        let t = ((m - a).dot(e) / e.length_squared()).clamp(0.0, 1.0);
        (a + e * t - m).length() > 1e-7
    })
}

/// Inner prisms of an object as blockers (what "the interior of another object" is
/// for block scenes: the blocks themselves).
fn blockers(o: &Object) -> &[Prism] {
    &o.inner
}

/// Sample points on an object's outer bound: facade grid and roof.
pub fn surface_samples(o: &Object, per_edge: usize, levels: usize) -> Vec<DVec3> {
    let mut out = Vec::new();
    for p in &o.outer {
        let c =
            p.footprint.exterior.iter().copied().sum::<DVec2>() / p.footprint.exterior.len() as f64;
        for (a, b) in p.footprint.edges() {
            for i in 0..per_edge {
                let q = a + (b - a) * ((i as f64 + 0.5) / per_edge as f64);
                // Nudge towards the inside of the footprint so the point is on the
                // object, not on a neighbour's shared wall.
                let q = q + (c - q) * 1e-6;
                if p.top > p.base {
                    for l in 0..levels {
                        let z = p.base + (p.top - p.base) * ((l as f64 + 0.5) / levels as f64);
                        out.push(q.extend(z));
                    }
                }
                out.push(q.extend(p.top));
            }
        }
        out.push(c.extend(p.top));
        // Interior samples of the top face.
        let bb = p.footprint.bbox();
        for i in 0..8 {
            for j in 0..8 {
                let q =
                    bb.min + bb.size() * DVec2::new((i as f64 + 0.5) / 8.0, (j as f64 + 0.5) / 8.0);
                if p.footprint.contains(q) {
                    out.push(q.extend(p.top));
                }
            }
        }
    }
    out
}

/// Sampled visible set: viewpoints on a grid of the cell (corners included) outside
/// every block, target samples on every object.
pub fn sampled_visible(scene: &Scene, cell: &ViewCell, grid: usize) -> Vec<u32> {
    let mut eyes = Vec::new();
    for i in 0..grid {
        for j in 0..grid {
            for k in 0..2 {
                let f = |n: usize, lo: f64, hi: f64| {
                    lo + (hi - lo) * (n as f64 / (grid - 1).max(1) as f64)
                };
                let e = DVec3::new(
                    f(i, cell.min.x, cell.max.x),
                    f(j, cell.min.y, cell.max.y),
                    if k == 0 { cell.min.z } else { cell.max.z },
                );
                let inside = scene.objects.iter().any(|o| {
                    o.inner
                        .iter()
                        .any(|p| e.z > p.base && e.z < p.top && p.footprint.contains(e.truncate()))
                });
                if !inside {
                    eyes.push(e);
                }
            }
        }
    }
    let mut vis = Vec::new();
    for (id, o) in scene.objects.iter().enumerate() {
        let samples = surface_samples(o, 6, 4);
        let seen = samples.iter().any(|&r| {
            eyes.iter().any(|&e| {
                r.z >= 0.0
                    && scene.objects.iter().enumerate().all(|(j, other)| {
                        j == id || !blockers(other).iter().any(|p| segment_hits_prism(e, r, p))
                    })
            })
        });
        if seen {
            vis.push(id as u32);
        }
    }
    vis
}

/// Missed objects of a PVS against the sampled visible set.
pub fn missed(pvs: &[u32], vs: &[u32]) -> Vec<u32> {
    vs.iter()
        .filter(|v| pvs.binary_search(v).is_err())
        .copied()
        .collect()
}
