//! Simple polygons with holes: the footprints of blocks and the shapes of flat objects.

use crate::aabb::Aabb2;
use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// An open ring of vertices (the closing vertex is not repeated).
pub type Ring = Vec<DVec2>;

/// A polygon with holes. Invariants after [`Polygon::normalized`]: the exterior is
/// counter-clockwise, holes are clockwise, rings are open (first ≠ last) and have at
/// least 3 vertices.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Polygon {
    pub exterior: Ring,
    pub holes: Vec<Ring>,
}

/// Signed area of a ring (positive when counter-clockwise), by the shoelace formula.
pub fn ring_signed_area(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    if n < 3 {
        return 0.0;
    }
    // Centre on the first vertex: large absolute coordinates would cancel badly.
    let o = ring[0];
    let mut s = 0.0;
    for i in 1..n - 1 {
        let a = ring[i] - o;
        let b = ring[i + 1] - o;
        s += a.perp_dot(b);
    }
    0.5 * s
}

/// Even-odd point-in-ring test. Points on the boundary may go either way.
fn ring_contains(ring: &[DVec2], p: DVec2) -> bool {
    let mut inside = false;
    let n = ring.len();
    let mut j = n.wrapping_sub(1);
    for i in 0..n {
        let (a, b) = (ring[i], ring[j]);
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) / (b.y - a.y) * (b.x - a.x);
            if p.x < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

impl Polygon {
    pub fn new(exterior: Ring, holes: Vec<Ring>) -> Self {
        Polygon { exterior, holes }
    }

    /// Axis-aligned rectangle, counter-clockwise.
    pub fn rect(min: DVec2, max: DVec2) -> Self {
        Polygon {
            exterior: vec![min, DVec2::new(max.x, min.y), max, DVec2::new(min.x, max.y)],
            holes: vec![],
        }
    }

    /// The same polygon with the exterior counter-clockwise and holes clockwise.
    pub fn normalized(mut self) -> Self {
        if ring_signed_area(&self.exterior) < 0.0 {
            self.exterior.reverse();
        }
        for h in &mut self.holes {
            if ring_signed_area(h) > 0.0 {
                h.reverse();
            }
        }
        self
    }

    /// Area (exterior minus holes), assuming the holes lie inside the exterior.
    pub fn area(&self) -> f64 {
        ring_signed_area(&self.exterior).abs()
            - self
                .holes
                .iter()
                .map(|h| ring_signed_area(h).abs())
                .sum::<f64>()
    }

    pub fn bbox(&self) -> Aabb2 {
        Aabb2::from_points(&self.exterior)
    }

    /// Whether `p` is inside (exterior and not in a hole). Boundary points may go either way.
    pub fn contains(&self, p: DVec2) -> bool {
        ring_contains(&self.exterior, p) && !self.holes.iter().any(|h| ring_contains(h, p))
    }

    /// All rings, exterior first.
    pub fn rings(&self) -> impl Iterator<Item = &Ring> {
        std::iter::once(&self.exterior).chain(self.holes.iter())
    }

    /// All boundary edges of all rings, as `(a, b)` with the interior on the left
    /// once normalized.
    pub fn edges(&self) -> impl Iterator<Item = (DVec2, DVec2)> + '_ {
        self.rings().flat_map(|r| {
            let n = r.len();
            (0..n).map(move |i| (r[i], r[(i + 1) % n]))
        })
    }

    pub fn vertex_count(&self) -> usize {
        self.rings().map(|r| r.len()).sum()
    }

    pub fn translated(&self, d: DVec2) -> Self {
        Polygon {
            exterior: self.exterior.iter().map(|p| *p + d).collect(),
            holes: self
                .holes
                .iter()
                .map(|h| h.iter().map(|p| *p + d).collect())
                .collect(),
        }
    }

    /// Triangulation (ear clipping with hole bridging), as triangles of 2D points,
    /// counter-clockwise.
    pub fn triangulate(&self) -> Vec<[DVec2; 3]> {
        let mut data: Vec<[f64; 2]> = Vec::with_capacity(self.vertex_count());
        let mut hole_idx: Vec<u32> = Vec::with_capacity(self.holes.len());
        for (k, r) in self.rings().enumerate() {
            if k > 0 {
                hole_idx.push(data.len() as u32);
            }
            data.extend(r.iter().map(|p| [p.x, p.y]));
        }
        let mut out: Vec<u32> = Vec::new();
        earcut::Earcut::new().earcut(data.iter().copied(), &hole_idx, &mut out);
        out.chunks_exact(3)
            .map(|t| {
                let p = |i: u32| DVec2::from(data[i as usize]);
                let (a, b, c) = (p(t[0]), p(t[1]), p(t[2]));
                if (b - a).perp_dot(c - a) < 0.0 {
                    [a, c, b]
                } else {
                    [a, b, c]
                }
            })
            .collect()
    }

    /// Triangles of the polygon lying in the horizontal plane at height `z`.
    pub fn triangulate_at(&self, z: f64) -> Vec<[DVec3; 3]> {
        self.triangulate()
            .into_iter()
            .map(|t| t.map(|p| p.extend(z)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn l_shape() -> Polygon {
        Polygon::new(
            vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(8.0, 0.0),
                DVec2::new(8.0, 4.0),
                DVec2::new(4.0, 4.0),
                DVec2::new(4.0, 8.0),
                DVec2::new(0.0, 8.0),
            ],
            vec![],
        )
    }

    #[test]
    fn area_orientation_and_triangulation() {
        let l = l_shape();
        assert_eq!(l.area(), 48.0);
        let rev = Polygon::new(l.exterior.iter().rev().copied().collect(), vec![]).normalized();
        assert!(ring_signed_area(&rev.exterior) > 0.0);
        let tri_area: f64 = l
            .triangulate()
            .iter()
            .map(|t| 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]))
            .sum();
        assert!((tri_area - 48.0).abs() < 1e-9);
    }

    #[test]
    fn holes_are_excluded() {
        let mut p = Polygon::rect(DVec2::ZERO, DVec2::splat(10.0));
        p.holes
            .push(Polygon::rect(DVec2::splat(4.0), DVec2::splat(6.0)).exterior);
        let p = p.normalized();
        assert_eq!(p.area(), 96.0);
        assert!(!p.contains(DVec2::splat(5.0)));
        assert!(p.contains(DVec2::new(1.0, 1.0)));
        let tri_area: f64 = p
            .triangulate()
            .iter()
            .map(|t| 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]))
            .sum();
        assert!((tri_area - 96.0).abs() < 1e-9);
    }
}
