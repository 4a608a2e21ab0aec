//! Closed voxel faces: a face of the grid that lies inside an axis-aligned polygon of
//! the level's surface (a triangle, or two coplanar triangles sharing an edge whose
//! union is convex: the quads levels are built of). A line through the open face
//! crosses the polygon's inside, so no sight line passes there: the face closes. Where
//! the level is built on a lattice the grid shares (walls on multiples of the voxel
//! size), walls thus stop sight even when they are two faces with air between them;
//! surfaces off the lattice close nothing and stay handled by the voxels alone.

use crate::voxels::Grid;
use sightline_geom::DVec3;
use std::collections::HashMap;

/// Bit `k` of `closed[v]`: the face between voxel `v` and its `+k` neighbour is closed.
pub fn closed_faces(grid: &Grid, tris: &[[DVec3; 3]]) -> Vec<u8> {
    let mut closed = vec![0u8; grid.len()];
    // Axis-aligned triangles on a grid plane, by (axis, plane index), in plane
    // coordinates (the two other axes, in voxel units from the origin).
    let mut planes: HashMap<(usize, usize), Vec<[[f64; 2]; 3]>> = HashMap::new();
    for t in tris {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        let len = n.length();
        if !(len > 0.0 && len.is_finite()) {
            continue;
        }
        let Some(k) = (0..3).find(|&k| n[k].abs() >= len * (1.0 - 1e-12)) else {
            continue;
        };
        let m = (t[0][k] - grid.origin[k]) / grid.size;
        let mi = m.round();
        let tol = 1e-9 * (1.0 + m.abs());
        if (m - mi).abs() > tol
            || t.iter()
                .any(|p| ((p[k] - grid.origin[k]) / grid.size - mi).abs() > tol)
            || mi < 1.0
            || mi >= grid.dims[k] as f64
        {
            continue;
        }
        let (a, c) = ((k + 1) % 3, (k + 2) % 3);
        let q = t.map(|p| {
            [
                (p[a] - grid.origin[a]) / grid.size,
                (p[c] - grid.origin[c]) / grid.size,
            ]
        });
        planes.entry((k, mi as usize)).or_default().push(q);
    }
    for ((k, m), tris) in planes {
        let (a, c) = ((k + 1) % 3, (k + 2) % 3);
        for poly in convex_pieces(&tris) {
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in &poly {
                for d in 0..2 {
                    lo[d] = lo[d].min(p[d]);
                    hi[d] = hi[d].max(p[d]);
                }
            }
            let i0 = lo[0].floor().max(0.0) as usize;
            let j0 = lo[1].floor().max(0.0) as usize;
            let i1 = (hi[0].ceil() as usize).min(grid.dims[a]);
            let j1 = (hi[1].ceil() as usize).min(grid.dims[c]);
            for i in i0..i1 {
                for j in j0..j1 {
                    let corners = [
                        [i as f64, j as f64],
                        [i as f64 + 1.0, j as f64],
                        [i as f64, j as f64 + 1.0],
                        [i as f64 + 1.0, j as f64 + 1.0],
                    ];
                    if corners.iter().all(|p| inside_convex(&poly, *p)) {
                        let mut v = [0usize; 3];
                        v[k] = m - 1;
                        v[a] = i;
                        v[c] = j;
                        closed[grid.index(v[0], v[1], v[2])] |= 1 << k;
                    }
                }
            }
        }
    }
    closed
}

/// The triangles of one plane as convex polygons: each triangle alone, and each pair
/// of triangles sharing an edge whose union is convex (a quad) as one polygon.
fn convex_pieces(tris: &[[[f64; 2]; 3]]) -> Vec<Vec<[f64; 2]>> {
    let key = |p: [f64; 2]| [(p[0] * 1e6).round() as i64, (p[1] * 1e6).round() as i64];
    let mut by_edge: HashMap<([i64; 2], [i64; 2]), Vec<usize>> = HashMap::new();
    for (i, t) in tris.iter().enumerate() {
        for e in 0..3 {
            let (p, q) = (key(t[e]), key(t[(e + 1) % 3]));
            by_edge.entry((p.min(q), p.max(q))).or_default().push(i);
        }
    }
    let mut out: Vec<Vec<[f64; 2]>> = tris.iter().map(|t| t.to_vec()).collect();
    for (_, ts) in by_edge {
        if let [i, j] = ts[..] {
            if let Some(quad) = union_quad(&tris[i], &tris[j]) {
                out.push(quad);
            }
        }
    }
    out
}

/// Two triangles sharing an edge: their union as a convex quad, if it is convex.
fn union_quad(t: &[[f64; 2]; 3], u: &[[f64; 2]; 3]) -> Option<Vec<[f64; 2]>> {
    let same = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).abs() < 1e-9 && (p[1] - q[1]).abs() < 1e-9;
    // The vertex of `u` not on the shared edge, and where the edge sits in `t`.
    let far = u
        .iter()
        .copied()
        .find(|&p| !t.iter().any(|&q| same(p, q)))?;
    let e = (0..3).find(|&e| {
        let (p, q) = (t[e], t[(e + 1) % 3]);
        u.iter().any(|&x| same(x, p)) && u.iter().any(|&x| same(x, q))
    })?;
    let quad = vec![t[e], far, t[(e + 1) % 3], t[(e + 2) % 3]];
    // Convex: every turn has the same sign (strictly: no degenerate corner).
    let turn = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
    };
    let s: Vec<f64> = (0..4)
        .map(|i| turn(quad[i], quad[(i + 1) % 4], quad[(i + 2) % 4]))
        .collect();
    (s.iter().all(|&x| x > 1e-12) || s.iter().all(|&x| x < -1e-12)).then_some(quad)
}

/// Whether `p` lies in the closed convex polygon (either orientation; within 10⁻⁹ of a
/// voxel for coordinates that are exact on the lattice).
fn inside_convex(poly: &[[f64; 2]], p: [f64; 2]) -> bool {
    let (mut pos, mut neg) = (false, false);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let cross = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        let len = (b[0] - a[0]).abs() + (b[1] - a[1]).abs();
        if cross > 1e-9 * len {
            pos = true;
        } else if cross < -1e-9 * len {
            neg = true;
        }
    }
    !(pos && neg)
}
