//! Property: clipping keeps every point of the kept side, and drops nothing that is
//! more than nothing in front.

use proptest::prelude::*;
use sightline_geom::DVec3;
use sightline_portals::winding::{Plane, Winding, ON_EPSILON};

fn convex_polygon(n: usize, r: f64, phase: f64, z: f64) -> Winding {
    Winding::new(
        (0..n)
            .map(|i| {
                let a = phase + i as f64 * std::f64::consts::TAU / n as f64;
                DVec3::new(r * a.cos(), r * a.sin(), z)
            })
            .collect(),
    )
}

proptest! {
    #[test]
    fn clip_keeps_the_kept_side(
        n in 3usize..12, r in 0.01f64..500.0, phase in 0.0f64..6.3, z in -10.0f64..10.0,
        nx in -1.0f64..1.0, ny in -1.0f64..1.0, nz in -1.0f64..1.0, d in -600.0f64..600.0,
        s in 0.0f64..1.0, t in 0.0f64..1.0,
    ) {
        let normal = DVec3::new(nx, ny, nz);
        prop_assume!(normal.length() > 0.1);
        let plane = Plane::new(normal.normalize(), d);
        let w = convex_polygon(n, r, phase, z);
        // A point of the polygon: a blend of a vertex, its neighbour and the centre.
        let i = ((s * n as f64) as usize).min(n - 1);
        let a = w.points[i];
        let b = w.points[(i + 1) % n];
        let p = (a + (b - a) * t) * (1.0 - s) + w.center() * s;
        let clipped = w.clip(&plane, ON_EPSILON);
        if plane.distance(p) >= 0.0 {
            let c = clipped.clone().expect("a winding with a point in front survives");
            // p lies inside c: on the inner side of every edge (in the polygon's plane).
            let m = c.points.len();
            for k in 0..m {
                let e = c.points[(k + 1) % m] - c.points[k];
                let inward = DVec3::Z.cross(e);
                prop_assert!(inward.dot(p - c.points[k]) >= -1e-6 * (1.0 + r),
                    "point {p} left outside edge {k} of {:?}", c.points);
            }
        }
        if let Some(c) = clipped {
            for q in &c.points {
                prop_assert!(plane.distance(*q) >= -ON_EPSILON - 1e-9);
            }
        }
    }
}
