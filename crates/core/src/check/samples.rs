//! Where the ground truth samples: stratified viewpoints in a box, random points on
//! faces, edges and roof lines, and a per-cell seed.

use sightline_geom::{DVec3, ViewCell};
use sightline_stats::Rng;

pub(super) fn polygon_area3(v: &[DVec3]) -> (DVec3, f64) {
    let mut n = DVec3::ZERO;
    for k in 1..v.len().saturating_sub(1) {
        n += (v[k] - v[0]).cross(v[k + 1] - v[0]);
    }
    let len = n.length();
    (if len > 0.0 { n / len } else { DVec3::Z }, 0.5 * len)
}

/// `p` (on the boundary of the planar polygon `v`) moved 1 mm (at most a thousandth of
/// its distance) towards the centroid, into the face: the witness ray then meets the
/// face inside, not at its edge.
pub(super) fn nudge_inward(p: DVec3, v: &[DVec3]) -> DVec3 {
    let c = v.iter().copied().sum::<DVec3>() / v.len().max(1) as f64;
    let d = c - p;
    let len = d.length();
    if len > 0.0 {
        p + d * (1e-3f64.min(1e-3 * len) / len)
    } else {
        p
    }
}

/// A uniform point on the highest edge of the polygon `v` (largest mean height of its
/// ends; the top edge of a wall).
pub(super) fn random_top_edge_point(v: &[DVec3], rng: &mut Rng) -> DVec3 {
    let n = v.len();
    let k = (0..n)
        .max_by(|&a, &b| {
            let za = v[a].z + v[(a + 1) % n].z;
            let zb = v[b].z + v[(b + 1) % n].z;
            za.total_cmp(&zb)
        })
        .unwrap_or(0);
    let (a, b) = (v[k], v[(k + 1) % n]);
    a + (b - a) * rng.f64()
}

/// A uniform point on the boundary of the polygon `v` (length-weighted edge).
pub(super) fn random_edge_point(v: &[DVec3], rng: &mut Rng) -> DVec3 {
    let n = v.len();
    let total: f64 = (0..n).map(|k| (v[(k + 1) % n] - v[k]).length()).sum();
    let mut pick = rng.f64() * total;
    let t = rng.f64();
    for k in 0..n {
        let (a, b) = (v[k], v[(k + 1) % n]);
        let len = (b - a).length();
        if pick <= len || k + 1 == n {
            return a + (b - a) * t;
        }
        pick -= len;
    }
    v[0]
}

pub(super) fn random_point(v: &[DVec3], rng: &mut Rng) -> DVec3 {
    // Fan triangles, area-weighted.
    let areas: Vec<f64> = (1..v.len() - 1)
        .map(|k| 0.5 * (v[k] - v[0]).cross(v[k + 1] - v[0]).length())
        .collect();
    let total: f64 = areas.iter().sum();
    let mut pick = rng.f64() * total;
    let mut k = 0;
    while k + 1 < areas.len() && pick > areas[k] {
        pick -= areas[k];
        k += 1;
    }
    let (mut r1, mut r2) = (rng.f64(), rng.f64());
    if r1 + r2 > 1.0 {
        r1 = 1.0 - r1;
        r2 = 1.0 - r2;
    }
    v[0] + (v[k + 1] - v[0]) * r1 + (v[k + 2] - v[0]) * r2
}

pub(super) fn cell_hash(cell: &ViewCell) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for v in cell.to_array() {
        h = (h ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// Stratified viewpoints in the box `[lo, hi]`: its 8 corners, points along its 12
/// edges, jittered points on its 6 faces and jittered strata of its interior, about `n`
/// in all (duplicates of degenerate boxes removed).
pub(super) fn stratified(lo: DVec3, hi: DVec3, n: usize, rng: &mut Rng) -> Vec<DVec3> {
    let at = |u: DVec3| lo + (hi - lo) * u;
    let mut pts: Vec<DVec3> = Vec::with_capacity(n + 8);
    for c in 0..8 {
        pts.push(at(DVec3::new(
            (c & 1) as f64,
            ((c >> 1) & 1) as f64,
            ((c >> 2) & 1) as f64,
        )));
    }
    let rest = n.saturating_sub(8);
    let per_edge = (rest / 4) / 12;
    let per_face = (rest / 4) / 6;
    let interior = rest.saturating_sub(12 * per_edge + 6 * per_face);
    // Edges: along axis `a`, the other two coordinates at 0/1.
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for corner in 0..4 {
            for k in 0..per_edge {
                let mut u = DVec3::ZERO;
                u[a] = (k as f64 + 0.5 + (rng.f64() - 0.5) * 0.5) / per_edge as f64;
                u[b] = (corner & 1) as f64;
                u[c] = ((corner >> 1) & 1) as f64;
                pts.push(at(u));
            }
        }
    }
    // Faces: normal axis `a` at 0/1, jittered strata over the other two.
    let side = (per_face as f64).sqrt().ceil() as usize;
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for s in 0..2 {
            for k in 0..per_face {
                let (i, j) = (k % side.max(1), k / side.max(1));
                let mut u = DVec3::ZERO;
                u[a] = s as f64;
                u[b] = (i as f64 + rng.f64()) / side.max(1) as f64;
                u[c] = ((j % side.max(1)) as f64 + rng.f64()) / side.max(1) as f64;
                pts.push(at(u));
            }
        }
    }
    // Interior: jittered strata of a grid with about `interior` cells.
    let side = (interior as f64).cbrt().ceil() as usize;
    for k in 0..interior {
        let s = side.max(1);
        let (i, j, l) = (k % s, (k / s) % s, (k / (s * s)) % s);
        pts.push(at(DVec3::new(
            (i as f64 + rng.f64()) / s as f64,
            (j as f64 + rng.f64()) / s as f64,
            (l as f64 + rng.f64()) / s as f64,
        )));
    }
    let mut out: Vec<DVec3> = Vec::with_capacity(pts.len());
    for p in pts {
        if !out.contains(&p) {
            out.push(p);
        }
    }
    out
}
