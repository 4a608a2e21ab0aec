//! Closed voxel faces: a face of the grid covered by the union of the axis-aligned
//! triangles that lie in its plane. A line through the open face crosses one of them,
//! so no sight line passes there: the face closes. The cover is exact: the square less
//! each triangle in turn, by convex differences, must leave no area (overlapping and
//! duplicate triangles are fine; a crack between two triangles keeps the face open). Where
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
        // The squares each triangle's bounds meet.
        let mut by_square: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
        for (ti, t) in tris.iter().enumerate() {
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in t {
                for d in 0..2 {
                    lo[d] = lo[d].min(p[d]);
                    hi[d] = hi[d].max(p[d]);
                }
            }
            let i0 = lo[0].floor().max(0.0) as usize;
            let j0 = lo[1].floor().max(0.0) as usize;
            let i1 = (hi[0].ceil().max(0.0) as usize).min(grid.dims[a]);
            let j1 = (hi[1].ceil().max(0.0) as usize).min(grid.dims[c]);
            for i in i0..i1 {
                for j in j0..j1 {
                    by_square.entry((i, j)).or_default().push(ti);
                }
            }
        }
        for ((i, j), ts) in by_square {
            let square = vec![
                [i as f64, j as f64],
                [i as f64 + 1.0, j as f64],
                [i as f64 + 1.0, j as f64 + 1.0],
                [i as f64, j as f64 + 1.0],
            ];
            if covered(square, ts.iter().map(|&t| &tris[t])) {
                let mut v = [0usize; 3];
                v[k] = m - 1;
                v[a] = i;
                v[c] = j;
                closed[grid.index(v[0], v[1], v[2])] |= 1 << k;
            }
        }
    }
    closed
}

/// Uncovered area below which a square counts as covered (in squared voxel sides):
/// rounding slivers only; a real crack of 10⁻⁶ of a voxel leaves 10⁻⁶.
const COVER_EPS: f64 = 1e-9;

/// Whether the unit square is covered by the union of the triangles: the square less
/// each triangle in turn (convex differences: exact for overlapping triangles too)
/// leaves no area.
pub(crate) fn covered<'a>(
    square: Vec<[f64; 2]>,
    tris: impl Iterator<Item = &'a [[f64; 2]; 3]>,
) -> bool {
    let mut left = vec![square];
    for t in tris {
        // Counter-clockwise, so that the inside is left of every edge.
        let t = if cross(t[0], t[1], t[2]) < 0.0 {
            [t[0], t[2], t[1]]
        } else {
            *t
        };
        let mut next = Vec::new();
        for mut piece in left {
            for e in 0..3 {
                let (p, q) = (t[e], t[(e + 1) % 3]);
                // Outside this edge: uncovered for good; inside: on to the next edge.
                let outside = clip(&piece, p, q, false);
                if area(&outside) > 0.0 {
                    next.push(outside);
                }
                piece = clip(&piece, p, q, true);
                if piece.len() < 3 {
                    break;
                }
            }
        }
        left = next;
        if left.is_empty() {
            return true;
        }
    }
    left.iter().map(|p| area(p)).sum::<f64>() < COVER_EPS
}

fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// The part of convex `poly` left of the line p → q (`keep_left`) or right of it.
fn clip(poly: &[[f64; 2]], p: [f64; 2], q: [f64; 2], keep_left: bool) -> Vec<[f64; 2]> {
    let side = |x: [f64; 2]| {
        let s = cross(p, q, x);
        if keep_left {
            s
        } else {
            -s
        }
    };
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let (sa, sb) = (side(a), side(b));
        if sa >= 0.0 {
            out.push(a);
        }
        if (sa > 0.0 && sb < 0.0) || (sa < 0.0 && sb > 0.0) {
            let t = sa / (sa - sb);
            out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
        }
    }
    out
}

fn area(poly: &[[f64; 2]]) -> f64 {
    if poly.len() < 3 {
        return 0.0;
    }
    let mut s = 0.0;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        s += a[0] * b[1] - a[1] * b[0];
    }
    (s * 0.5).abs()
}
