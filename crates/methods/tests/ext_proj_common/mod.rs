//! A small, independent sampled visibility oracle for the ext-proj tests: segments from
//! stratified viewpoints of the cell to stratified points on each object's outer
//! surface, blocked by any triangle of another object. It can only miss
//! visible objects, never invent them, so `sampled ⊆ PVS` must hold.
#![allow(dead_code)]

use sightline_geom::{DVec3, ViewCell};
use sightline_scene::{Geometry, Scene};

fn seg_hits_tri(a: DVec3, b: DVec3, t: &[DVec3; 3]) -> bool {
    let d = b - a;
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return false;
    }
    let inv = 1.0 / det;
    let s = a - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let tt = e2.dot(q) * inv;
    tt > 1e-9 && tt < 1.0 - 1e-9
}

/// Stratified samples of a box's surface (6 faces, `k × k` each), pushed outward by 1 cm.
fn box_surface(min: DVec3, max: DVec3, k: usize) -> Vec<DVec3> {
    let mut out = Vec::new();
    let eps = 0.01;
    for axis in 0..3 {
        for side in 0..2 {
            for i in 0..k {
                for j in 0..k {
                    let fi = (i as f64 + 0.5) / k as f64;
                    let fj = (j as f64 + 0.5) / k as f64;
                    let mut p = DVec3::ZERO;
                    let (a1, a2) = ((axis + 1) % 3, (axis + 2) % 3);
                    p[axis] = if side == 0 {
                        min[axis] - eps
                    } else {
                        max[axis] + eps
                    };
                    p[a1] = min[a1] + (max[a1] - min[a1]) * fi;
                    p[a2] = min[a2] + (max[a2] - min[a2]) * fj;
                    if p.z >= 0.0 {
                        out.push(p);
                    }
                }
            }
        }
    }
    out
}

/// Objects seen by sampling (a lower bound of the visible set).
pub fn sampled_visible(scene: &Scene, cell: &ViewCell, per_axis: usize, k: usize) -> Vec<u32> {
    let all: Vec<u32> = (0..scene.objects.len() as u32).collect();
    sampled_visible_among(scene, cell, per_axis, k, &all)
}

/// Objects of `ids` seen by sampling; pass the complement of a PVS to look only for
/// misses.
pub fn sampled_visible_among(
    scene: &Scene,
    cell: &ViewCell,
    per_axis: usize,
    k: usize,
    ids: &[u32],
) -> Vec<u32> {
    let tris: Vec<(u32, [DVec3; 3])> = scene
        .objects
        .iter()
        .enumerate()
        .flat_map(|(i, o)| o.triangles().into_iter().map(move |t| (i as u32, t)))
        .collect();
    let inside_block = |p: DVec3| {
        scene.objects.iter().any(|o| {
            o.inner
                .iter()
                .any(|pr| p.z > pr.base && p.z < pr.top && pr.footprint.contains(p.truncate()))
        })
    };
    let mut views = Vec::new();
    for i in 0..per_axis {
        for j in 0..per_axis {
            for l in 0..per_axis.min(2) {
                let f = |t: usize, n: usize| {
                    if n == 1 {
                        0.5
                    } else {
                        t as f64 / (n - 1) as f64
                    }
                };
                let p = cell.min
                    + cell.size()
                        * DVec3::new(f(i, per_axis), f(j, per_axis), f(l, per_axis.min(2)));
                if !inside_block(p) {
                    views.push(p);
                }
            }
        }
    }
    let mut vis = Vec::new();
    for (id, o) in scene.objects.iter().enumerate() {
        if ids.binary_search(&(id as u32)).is_err() {
            continue;
        }
        let boxes: Vec<(DVec3, DVec3)> = if o.outer.is_empty() {
            vec![(o.bounds.min, o.bounds.max)]
        } else {
            o.outer
                .iter()
                .map(|p| (p.aabb().min, p.aabb().max))
                .collect()
        };
        let targets: Vec<DVec3> = match &o.geometry {
            // Meshes: points on the triangles themselves (their boxes are not them).
            Geometry::Mesh(m) => m
                .triangles
                .iter()
                .flat_map(|t| {
                    let [a, b, c] = m.triangle(t);
                    [
                        (a + b + c) / 3.0,
                        (a * 4.0 + b + c) / 6.0,
                        (a + b * 4.0 + c) / 6.0,
                        (a + b + c * 4.0) / 6.0,
                    ]
                })
                .filter(|p| !inside_block(*p))
                .collect(),
            _ => boxes
                .iter()
                .flat_map(|(a, b)| box_surface(*a, *b, k))
                .filter(|p| !inside_block(*p))
                .collect(),
        };
        let seen = views.iter().any(|v| {
            targets.iter().any(|t| {
                !tris
                    .iter()
                    .any(|(oid, tri)| *oid != id as u32 && seg_hits_tri(*v, *t, tri))
            })
        });
        if seen {
            vis.push(id as u32);
        }
    }
    vis
}

/// Ids of `sampled` missing from `pvs`.
pub fn missed(sampled: &[u32], pvs: &[u32]) -> Vec<u32> {
    sampled
        .iter()
        .copied()
        .filter(|i| pvs.binary_search(i).is_err())
        .collect()
}
