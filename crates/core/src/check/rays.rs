//! The exact ray caster of the ground truth, independent of the rasterizer: prisms and
//! triangles in a uniform 2D grid, segments tested exactly, grazing contacts (closer
//! than [`GRAZE_M`]) counted as blocked.

use sightline_geom::{DVec2, DVec3, Polygon};

/// A targeted ray passing closer than this to another object does not count (metres).
pub const GRAZE_M: f64 = 1e-6;

/// A ray-casting occluder: an exact prism or a mesh triangle, of object `id`.
#[derive(Clone, Debug)]
pub(super) enum Occluder {
    Prism {
        footprint: Polygon,
        base: f64,
        top: f64,
    },
    Triangle([DVec3; 3]),
}

#[derive(Clone, Debug)]
pub(super) struct Item {
    pub(super) id: u32,
    pub(super) lo: DVec3,
    pub(super) hi: DVec3,
    pub(super) occ: Occluder,
}

/// Uniform grid over the xy plane holding item indices.
pub(super) struct Grid {
    pub(super) origin: DVec2,
    pub(super) cell: f64,
    pub(super) nx: usize,
    pub(super) ny: usize,
    pub(super) cells: Vec<Vec<u32>>,
}

impl Grid {
    pub(super) fn new(items: &[Item]) -> Grid {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for it in items {
            lo = lo.min(it.lo.truncate());
            hi = hi.max(it.hi.truncate());
        }
        if items.is_empty() {
            lo = DVec2::ZERO;
            hi = DVec2::ONE;
        }
        let size = (hi - lo).max(DVec2::splat(1.0));
        let cell = ((size.x * size.y) / (items.len().max(1) as f64))
            .sqrt()
            .max(1.0)
            * 1.5;
        let nx = ((size.x / cell).ceil() as usize).clamp(1, 4096);
        let ny = ((size.y / cell).ceil() as usize).clamp(1, 4096);
        let cell = (size.x / nx as f64).max(size.y / ny as f64);
        let mut g = Grid {
            origin: lo,
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
        };
        for (k, it) in items.iter().enumerate() {
            let (x0, y0) = g.index(it.lo.truncate());
            let (x1, y1) = g.index(it.hi.truncate());
            for y in y0..=y1 {
                for x in x0..=x1 {
                    g.cells[y * nx + x].push(k as u32);
                }
            }
        }
        g
    }

    pub(super) fn index(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.origin) / self.cell;
        (
            (q.x.floor().max(0.0) as usize).min(self.nx - 1),
            (q.y.floor().max(0.0) as usize).min(self.ny - 1),
        )
    }

    /// Visit the grid cells the 2D segment `a → b` passes through (Amanatides–Woo), in
    /// order, until `f` returns true. Returns whether it did.
    pub(super) fn walk(&self, a: DVec2, b: DVec2, mut f: impl FnMut(&[u32]) -> bool) -> bool {
        let (mut x, mut y) = self.index(a);
        let (xe, ye) = self.index(b);
        let d = b - a;
        let step_x: i64 = if d.x > 0.0 { 1 } else { -1 };
        let step_y: i64 = if d.y > 0.0 { 1 } else { -1 };
        let next_bound =
            |i: usize, s: i64, o: f64| o + (i as f64 + if s > 0 { 1.0 } else { 0.0 }) * self.cell;
        let mut t_max_x = if d.x != 0.0 {
            (next_bound(x, step_x, self.origin.x) - a.x) / d.x
        } else {
            f64::INFINITY
        };
        let mut t_max_y = if d.y != 0.0 {
            (next_bound(y, step_y, self.origin.y) - a.y) / d.y
        } else {
            f64::INFINITY
        };
        let t_dx = if d.x != 0.0 {
            self.cell / d.x.abs()
        } else {
            f64::INFINITY
        };
        let t_dy = if d.y != 0.0 {
            self.cell / d.y.abs()
        } else {
            f64::INFINITY
        };
        let limit = self.nx + self.ny + 4;
        for _ in 0..limit {
            if f(&self.cells[y * self.nx + x]) {
                return true;
            }
            if x == xe && y == ye {
                return false;
            }
            if t_max_x < t_max_y {
                let nx = x as i64 + step_x;
                if nx < 0 || nx >= self.nx as i64 || t_max_x > 1.0 {
                    break;
                }
                x = nx as usize;
                t_max_x += t_dx;
            } else {
                let ny = y as i64 + step_y;
                if ny < 0 || ny >= self.ny as i64 || t_max_y > 1.0 {
                    break;
                }
                y = ny as usize;
                t_max_y += t_dy;
            }
        }
        // Fell off the walk (rounding at a cell corner): visit the end cell too.
        f(&self.cells[ye * self.nx + xe])
    }
}

/// Distance from `p` to the boundary of `poly`.
pub(super) fn dist_to_boundary(poly: &Polygon, p: DVec2) -> f64 {
    poly.edges()
        .map(|(a, b)| point_segment_dist(p, a, b))
        .fold(f64::INFINITY, f64::min)
}

pub(super) fn point_segment_dist(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - p).length()
}

pub(super) fn segments_dist(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> f64 {
    let o = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    if ((d1 > 0.0) != (d2 > 0.0) || d1 == 0.0 || d2 == 0.0)
        && ((d3 > 0.0) != (d4 > 0.0) || d3 == 0.0 || d4 == 0.0)
        && d1.signum() * d2.signum() <= 0.0
        && d3.signum() * d4.signum() <= 0.0
    {
        return 0.0;
    }
    point_segment_dist(a, c, d)
        .min(point_segment_dist(b, c, d))
        .min(point_segment_dist(c, a, b))
        .min(point_segment_dist(d, a, b))
}

/// Segment `a → b` against an occluder expanded by GRAZE_M.
pub(super) fn segment_meets(a: DVec3, b: DVec3, it: &Item) -> bool {
    let g = GRAZE_M;
    // Slab test against the item's box.
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        let (lo, hi) = (it.lo[k] - g, it.hi[k] + g);
        if d[k].abs() < 1e-300 {
            if a[k] < lo || a[k] > hi {
                return false;
            }
        } else {
            let (mut u, mut v) = ((lo - a[k]) / d[k], (hi - a[k]) / d[k]);
            if u > v {
                std::mem::swap(&mut u, &mut v);
            }
            t0 = t0.max(u);
            t1 = t1.min(v);
            if t0 > t1 {
                return false;
            }
        }
    }
    match &it.occ {
        Occluder::Prism { footprint, .. } => {
            // Within the z-slab already (the box's z-range is [base, top]).
            let p = (a + d * t0).truncate();
            let q = (a + d * t1).truncate();
            if footprint.contains(p) || footprint.contains(q) {
                return true;
            }
            footprint
                .edges()
                .any(|(e0, e1)| segments_dist(p, q, e0, e1) <= g)
        }
        Occluder::Triangle(tri) => segment_triangle(a, b, tri, g),
    }
}

/// Möller–Trumbore segment/triangle test with barycentric slack `eps` (metres, roughly).
pub(super) fn segment_triangle(a: DVec3, b: DVec3, t: &[DVec3; 3], eps: f64) -> bool {
    let d = b - a;
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-18 {
        return false;
    }
    let inv = 1.0 / det;
    let s = a - t[0];
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    let tt = e2.dot(q) * inv;
    let slack = eps / e1.length().max(e2.length()).max(1e-12);
    u >= -slack && v >= -slack && u + v <= 1.0 + slack && (0.0..=1.0).contains(&tt)
}
