//! Extended projection of occluders (Durand et al. 2000, §2.2, §3.2, §3.3).
//!
//! * Definition 1: the *Projection* of an occluder is the intersection of its views
//!   from every point of the cell. For a convex occluder and a convex (box) cell it is
//!   the intersection of the views from the cell's 8 vertices (§3.2, Fig. 6a); each
//!   view of a convex occluder is the convex hull of its projected vertices.
//! * Definition 3: the extended *Depth* of a point of an occluder's Projection is the
//!   maximum depth of the corresponding occluder points; we bound it by the occluder's
//!   farthest depth (a constant per convex piece, larger than or equal to the exact
//!   value, hence conservative).
//! * §3.3 *slicing*: the Projection of a solid lying in the plane is the slice itself;
//!   the slices of a concave occluder are drawn at depth 0.
//!
//! Concave occluders are handled by convex decomposition (see `occluders.rs`) plus
//! slicing; the union-aware inner coverage of `depth_map.rs` then fuses the pieces.

use super::planes::{view, Direction, LocalBox};
use sightline_geom::{DVec2, DVec3};
use sightline_scene::occluders::GROUND_M;

/// Minimum clearance between a clipped occluder and the cell's far face along the
/// depth axis, so every view is a finite central projection.
pub(crate) const FACE_CLEARANCE_M: f64 = 1e-3;

/// How far below the ground a ground-standing prism is extended for the horizontal
/// directions. The ground is opaque (no sight line meets the ground below
/// z = 0), so prism ∪ ground contains the extended prism, which stays convex; without
/// it a plane in front of a wall would lose the rays that pass under the wall's view
/// of its own foot and hit the ground.
pub(crate) const BELOW_GROUND_M: f64 = 100.0;

fn below_ground(base: f64) -> f64 {
    if base <= GROUND_M {
        -BELOW_GROUND_M
    } else {
        base
    }
}

/// A convex occluder in world coordinates.
#[derive(Clone, Debug, PartialEq)]
pub enum ConvexOccluder {
    /// A vertical prism over a convex counter-clockwise footprint.
    Prism {
        footprint: Vec<DVec2>,
        base: f64,
        top: f64,
    },
    /// A planar convex polygon (a mesh triangle: a leaf).
    Planar(Vec<DVec3>),
}

impl ConvexOccluder {
    /// The occluder's vertices in the local frame of `dir`, clipped to the half-space
    /// `w ≥ w_min` (a convex subset of a convex occluder still occludes: conservative).
    pub(crate) fn local_vertices(&self, dir: Direction, w_min: f64) -> Vec<DVec3> {
        match self {
            ConvexOccluder::Prism {
                footprint,
                base,
                top,
            } => {
                if dir.is_vertical() {
                    let (w0, w1) = dir.height_to_depth(*base, *top);
                    let w0 = w0.max(w_min);
                    if w0 >= w1 {
                        return vec![];
                    }
                    let mut out = Vec::with_capacity(footprint.len() * 2);
                    for w in [w0, w1] {
                        out.extend(footprint.iter().map(|p| DVec3::new(w, p.x, p.y)));
                    }
                    out
                } else {
                    let local: Vec<DVec2> = footprint
                        .iter()
                        .map(|p| dir.footprint_to_local(*p))
                        .collect();
                    let clipped = clip_halfplane(&local, DVec2::X, w_min);
                    if clipped.len() < 3 {
                        return vec![];
                    }
                    let mut out = Vec::with_capacity(clipped.len() * 2);
                    for z in [below_ground(*base), *top] {
                        out.extend(clipped.iter().map(|p| DVec3::new(p.x, p.y, z)));
                    }
                    out
                }
            }
            ConvexOccluder::Planar(pts) => {
                let local: Vec<DVec3> = pts.iter().map(|p| dir.to_local(*p)).collect();
                clip_polygon3_w(&local, w_min)
            }
        }
    }

    /// The slice of the occluder by the plane `w = x` (§3.3), as a convex polygon in
    /// `(u, v)`; planar occluders have no area in a slice.
    pub fn slice(&self, dir: Direction, x: f64) -> Option<Vec<DVec2>> {
        match self {
            ConvexOccluder::Prism {
                footprint,
                base,
                top,
            } => {
                if dir.is_vertical() {
                    let (w0, w1) = dir.height_to_depth(*base, *top);
                    if w0 < x && x < w1 {
                        return Some(footprint.clone());
                    }
                    return None;
                }
                let mut lo = f64::INFINITY;
                let mut hi = f64::NEG_INFINITY;
                let n = footprint.len();
                for i in 0..n {
                    let a = dir.footprint_to_local(footprint[i]);
                    let b = dir.footprint_to_local(footprint[(i + 1) % n]);
                    if (a.x - x) * (b.x - x) <= 0.0 && a.x != b.x {
                        let t = (x - a.x) / (b.x - a.x);
                        let u = a.y + (b.y - a.y) * t;
                        lo = lo.min(u);
                        hi = hi.max(u);
                    }
                }
                if hi > lo {
                    let base = below_ground(*base);
                    Some(vec![
                        DVec2::new(lo, base),
                        DVec2::new(hi, base),
                        DVec2::new(hi, *top),
                        DVec2::new(lo, *top),
                    ])
                } else {
                    None
                }
            }
            ConvexOccluder::Planar(_) => None,
        }
    }
}

/// The extended projection of a convex occluder given by its local vertices onto the
/// plane `w = x`: the intersection of its views from the cell's vertices (§3.2), with
/// its extended depth bound (farthest depth minus `x`). `None` when void. Valid only
/// for an occluder on one side of the plane (see `plane_safe_projections`).
pub fn extended_projection(
    vertices: &[DVec3],
    cell: &LocalBox,
    x: f64,
) -> Option<(Vec<DVec2>, f64)> {
    if vertices.len() < 3 {
        return None;
    }
    let far = vertices
        .iter()
        .map(|p| p.x)
        .fold(f64::NEG_INFINITY, f64::max);
    let mut acc: Option<Vec<DVec2>> = None;
    let mut pts = Vec::with_capacity(vertices.len());
    for e in cell.corners() {
        pts.clear();
        pts.extend(vertices.iter().map(|p| view(e, *p, x)));
        let hull = convex_hull(&mut pts);
        if hull.len() < 3 {
            return None;
        }
        acc = Some(match acc {
            None => hull,
            Some(a) => {
                let r = intersect_convex(&a, &hull);
                if r.len() < 3 {
                    return None;
                }
                r
            }
        });
    }
    acc.map(|p| (p, far - x))
}

/// The Projections of a convex occluder onto `w = x` that are valid from the whole
/// cell: the occluder's own when it lies on one side of the plane, otherwise those of
/// its parts in front of and behind the plane (each convex, on one side).
///
/// The intersection of the views from the cell's vertices is contained in the view
/// from every point of the cell only when the occluder lies on one side of the plane:
/// for an occluder crossing it, the viewpoints from which a plane point `q` is
/// covered form two cones (through the front part, and through the back part beyond
/// `q`), and a viewpoint between them — a sight line grazing the occluder's side —
/// sees `q` uncovered although every vertex of the cell has it covered. The parts
/// are subsets of the occluder, so their Projections stay conservative; the slice
/// (drawn separately) joins them.
pub(crate) fn plane_safe_projections(
    vertices: &[DVec3],
    cell: &LocalBox,
    x: f64,
) -> Vec<(Vec<DVec2>, f64)> {
    let (near, far) = vertices
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), p| {
            (a.min(p.x), b.max(p.x))
        });
    if far <= x || near >= x {
        return extended_projection(vertices, cell, x).into_iter().collect();
    }
    let (front, back) = split_at(vertices, x);
    [front, back]
        .iter()
        .filter_map(|part| extended_projection(part, cell, x))
        .collect()
}

/// The vertices of the parts `w ≤ x` and `w ≥ x` of the convex hull of `vertices`:
/// the vertices on each side plus the plane's intersections with every segment
/// between two vertices (a superset of the hull's edges, whose extra points lie
/// inside the hull, so each part's hull is exact).
pub(crate) fn split_at(vertices: &[DVec3], x: f64) -> (Vec<DVec3>, Vec<DVec3>) {
    let mut front: Vec<DVec3> = vertices.iter().copied().filter(|p| p.x <= x).collect();
    let mut back: Vec<DVec3> = vertices.iter().copied().filter(|p| p.x >= x).collect();
    for (i, a) in vertices.iter().enumerate() {
        for b in &vertices[i + 1..] {
            if (a.x < x && b.x > x) || (a.x > x && b.x < x) {
                let t = (x - a.x) / (b.x - a.x);
                let mut q = *a + (*b - *a) * t;
                q.x = x;
                front.push(q);
                back.push(q);
            }
        }
    }
    (front, back)
}

/// Area of the intersection of two convex polygons' bounding ranges is not needed;
/// this is the signed area of a polygon (positive when counter-clockwise).
pub(crate) fn polygon_area(p: &[DVec2]) -> f64 {
    if p.len() < 3 {
        return 0.0;
    }
    let o = p[0];
    let mut s = 0.0;
    for i in 1..p.len() - 1 {
        s += (p[i] - o).perp_dot(p[i + 1] - o);
    }
    0.5 * s
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, without collinear points.
/// Sorts `pts` in place.
pub(crate) fn convex_hull(pts: &mut [DVec2]) -> Vec<DVec2> {
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    let n = pts.len();
    if n < 3 {
        return pts.to_vec();
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut h: Vec<DVec2> = Vec::with_capacity(2 * n);
    for &p in pts.iter() {
        while h.len() >= 2 && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
            h.pop();
        }
        h.push(p);
    }
    let lower = h.len() + 1;
    for &p in pts.iter().rev().skip(1) {
        while h.len() >= lower && cross(h[h.len() - 2], h[h.len() - 1], p) <= 0.0 {
            h.pop();
        }
        h.push(p);
    }
    h.pop();
    h
}

/// The part of a convex polygon where `n · p ≥ c` (Sutherland–Hodgman, one edge).
pub(crate) fn clip_halfplane(poly: &[DVec2], n: DVec2, c: f64) -> Vec<DVec2> {
    let k = poly.len();
    let mut out = Vec::with_capacity(k + 1);
    for i in 0..k {
        let a = poly[i];
        let b = poly[(i + 1) % k];
        let da = n.dot(a) - c;
        let db = n.dot(b) - c;
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            out.push(a + (b - a) * t);
        }
    }
    out
}

/// Clip a planar convex 3D polygon (local frame) to `w ≥ w_min`.
fn clip_polygon3_w(poly: &[DVec3], w_min: f64) -> Vec<DVec3> {
    let k = poly.len();
    let mut out = Vec::with_capacity(k + 1);
    for i in 0..k {
        let a = poly[i];
        let b = poly[(i + 1) % k];
        let (da, db) = (a.x - w_min, b.x - w_min);
        if da >= 0.0 {
            out.push(a);
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            out.push(a + (b - a) * t);
        }
    }
    out
}

/// Intersection of two convex counter-clockwise polygons (clip `a` by every edge of `b`).
pub(crate) fn intersect_convex(a: &[DVec2], b: &[DVec2]) -> Vec<DVec2> {
    let mut out = a.to_vec();
    let k = b.len();
    for i in 0..k {
        if out.len() < 3 {
            return vec![];
        }
        let p = b[i];
        let q = b[(i + 1) % k];
        let e = q - p;
        // Inside = left of p → q.
        let n = DVec2::new(-e.y, e.x);
        out = clip_halfplane(&out, n, n.dot(p));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sq(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<DVec2> {
        vec![
            DVec2::new(x0, y0),
            DVec2::new(x1, y0),
            DVec2::new(x1, y1),
            DVec2::new(x0, y1),
        ]
    }

    #[test]
    fn hull_and_intersection() {
        let mut pts = vec![
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(0.5, 0.5),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        let h = convex_hull(&mut pts);
        assert_eq!(h.len(), 4);
        assert!((polygon_area(&h) - 1.0).abs() < 1e-12);
        let i = intersect_convex(&sq(0.0, 0.0, 2.0, 2.0), &sq(1.0, 1.0, 3.0, 3.0));
        assert!((polygon_area(&i) - 1.0).abs() < 1e-12);
        assert!(intersect_convex(&sq(0.0, 0.0, 1.0, 1.0), &sq(2.0, 2.0, 3.0, 3.0)).is_empty());
    }

    /// A wall parallel to the plane, seen from a point cell, projects to its view; from
    /// a wide cell it shrinks by the cell's width scaled by Thales' ratio.
    #[test]
    fn projection_of_a_wall_shrinks_with_the_cell() {
        let wall = ConvexOccluder::Prism {
            footprint: sq(10.0, -10.0, 11.0, 10.0),
            base: 0.0,
            top: 10.0,
        };
        let dir = Direction::PosX;
        let cell = dir.box_to_local(DVec3::new(-1.0, -1.0, 1.0), DVec3::new(1.0, 1.0, 1.0));
        let v = wall.local_vertices(dir, cell.max.x + FACE_CLEARANCE_M);
        let (poly, depth) = extended_projection(&v, &cell, 11.0).unwrap();
        assert!((depth - 0.0).abs() < 1e-12);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for p in &poly {
            lo = lo.min(p.x);
            hi = hi.max(p.x);
        }
        // From e = (±1, ±1), the wall's front face at x=10 spans u ∈ [-10, 10]; on the
        // plane x = 11: views of the front face from (1, 1): 1 + (±10 - 1) * 10/9.
        // Intersection: u ∈ [-10 - ..., ...] bounded by the worst corners.
        assert!(lo > -11.0 && hi < 11.0 && hi - lo > 18.0, "{lo} {hi}");
        // A wall far from a wide cell: void Projection.
        let cell = dir.box_to_local(DVec3::new(-50.0, -50.0, 1.0), DVec3::new(1.0, 50.0, 1.0));
        let small = ConvexOccluder::Prism {
            footprint: sq(10.0, 0.0, 11.0, 1.0),
            base: 0.0,
            top: 1.0,
        };
        let v = small.local_vertices(dir, cell.max.x + FACE_CLEARANCE_M);
        assert!(extended_projection(&v, &cell, 20.0).is_none());
    }

    fn contains(poly: &[DVec2], q: DVec2) -> bool {
        (0..poly.len()).all(|i| (poly[(i + 1) % poly.len()] - poly[i]).perp_dot(q - poly[i]) >= 0.0)
    }

    /// The demo city's witness (cell 50..100 × 200..250, +y): a sight line from
    /// (84.03, 239.58, 1.73) grazes the right side of a block that crosses the plane
    /// y = 302.61. Every vertex of the cell sees the plane point (91.05, 1.115)
    /// covered, through the block's front part or through its back part, but that
    /// viewpoint sees it uncovered; the split Projections must leave it out.
    #[test]
    fn occluder_crossing_the_plane_is_split() {
        let block = ConvexOccluder::Prism {
            footprint: vec![
                DVec2::new(94.05295287323024, 331.82866543997267),
                DVec2::new(76.8571739168166, 320.6184172168177),
                DVec2::new(69.28879563931282, 277.4786610350459),
                DVec2::new(82.7562043586291, 267.43633896648885),
            ],
            base: 0.0,
            top: 13.0,
        };
        let dir = Direction::PosY;
        let cell = dir.box_to_local(DVec3::new(50.0, 200.0, 1.5), DVec3::new(100.0, 250.0, 2.0));
        let v = block.local_vertices(dir, cell.max.x + FACE_CLEARANCE_M);
        let (x, q) = (302.61, DVec2::new(91.05, 1.115));
        let (whole, _) = extended_projection(&v, &cell, x).unwrap();
        assert!(
            contains(&whole, q),
            "the unsplit Projection covers the point"
        );
        // The witness viewpoint's view does not contain it.
        let e = dir.to_local(DVec3::new(84.031, 239.576, 1.727));
        let mut pts: Vec<DVec2> = v.iter().map(|p| view(e, *p, x)).collect();
        assert!(!contains(&convex_hull(&mut pts), q));
        let parts = plane_safe_projections(&v, &cell, x);
        assert!(!parts.is_empty());
        for (poly, _) in &parts {
            assert!(!contains(poly, q), "{poly:?}");
        }
        // One side of the plane: unchanged.
        for x in [262.0, 340.0] {
            let one: Vec<_> = extended_projection(&v, &cell, x).into_iter().collect();
            assert_eq!(plane_safe_projections(&v, &cell, x), one);
        }
    }

    #[test]
    fn split_parts_are_exact() {
        let cube: Vec<DVec3> = sightline_geom::Aabb3::new(DVec3::ZERO, DVec3::splat(2.0))
            .corners()
            .to_vec();
        let (f, b) = split_at(&cube, 0.5);
        assert!(f.iter().all(|p| p.x <= 0.5) && b.iter().all(|p| p.x >= 0.5));
        assert_eq!(
            f.iter().filter(|p| p.x == 0.5).count(),
            b.iter().filter(|p| p.x == 0.5).count()
        );
        assert!(f.iter().filter(|p| p.x == 0.5).count() >= 4);
    }

    #[test]
    fn slices_of_prisms() {
        let p = ConvexOccluder::Prism {
            footprint: vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(4.0, 0.0),
                DVec2::new(0.0, 4.0),
            ],
            base: 0.0,
            top: 3.0,
        };
        let s = p.slice(Direction::PosX, 1.0).unwrap();
        assert!((polygon_area(&s) - 3.0 * (3.0 + BELOW_GROUND_M)).abs() < 1e-9);
        assert!(p.slice(Direction::PosX, 5.0).is_none());
        assert!(p.slice(Direction::PosZ, 1.0).is_some());
        assert!(p.slice(Direction::NegZ, -1.0).is_some());
        assert!(p.slice(Direction::NegZ, 1.0).is_none());
    }
}
