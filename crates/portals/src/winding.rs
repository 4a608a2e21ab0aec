//! Convex polygons ("windings", as qbsp and vis call them) and their clipping by planes.
//!
//! Clipping keeps points within [`ON_EPSILON`] of the plane on the kept side, so a
//! winding is never made smaller than the exact half-space would make it: sightline's
//! portal code errs towards keeping (a sliver too many costs a little tightness, a
//! sliver too few is a missed view).

use sightline_geom::DVec3;

/// Margin (Quake units) that the portal flow's clipping keeps behind each plane: a
/// tenth of qbsp's and vis's 0.1, still ten times the touching tolerance.
pub const ON_EPSILON: f64 = 0.01;

/// Distance below which a winding only touches a plane (float noise of the level's
/// float32 coordinates, 0.0005 at 4,000 units): a winding with no point further than
/// this in front of a plane has nothing in front of it, only an edge or a point on it,
/// which lines graze (grazing lines do not make anything visible, SPEC §3).
pub const TOUCH_EPSILON: f64 = 0.001;

/// The plane `normal · p = dist`; its front is where `normal · p > dist`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub normal: DVec3,
    pub dist: f64,
}

impl Plane {
    pub fn new(normal: DVec3, dist: f64) -> Self {
        Plane { normal, dist }
    }

    /// Signed distance of `p` (in units of the normal's length).
    #[inline]
    pub fn distance(&self, p: DVec3) -> f64 {
        self.normal.dot(p) - self.dist
    }

    /// The same plane facing the other way.
    pub fn flipped(&self) -> Plane {
        Plane {
            normal: -self.normal,
            dist: -self.dist,
        }
    }
}

/// A convex polygon, its points in order.
#[derive(Clone, Debug, PartialEq)]
pub struct Winding {
    pub points: Vec<DVec3>,
}

impl Winding {
    pub fn new(points: Vec<DVec3>) -> Self {
        Winding { points }
    }

    /// A square of half-size `size` in `plane`, centred on the plane's point nearest
    /// the origin (qbsp's `BaseWindingForPlane`).
    pub fn base_for_plane(plane: &Plane, size: f64) -> Winding {
        let n = plane.normal.normalize();
        let axis = if n.z.abs() > n.x.abs().max(n.y.abs()) {
            DVec3::X
        } else {
            DVec3::Z
        };
        let u = axis.cross(n).normalize() * size;
        let v = n.cross(u).normalize() * size;
        let o = n * (plane.dist / plane.normal.length());
        Winding::new(vec![o - u + v, o + u + v, o + u - v, o - u - v])
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    pub fn area(&self) -> f64 {
        let mut s = DVec3::ZERO;
        for i in 1..self.points.len().saturating_sub(1) {
            s += (self.points[i] - self.points[0]).cross(self.points[i + 1] - self.points[0]);
        }
        0.5 * s.length()
    }

    pub fn center(&self) -> DVec3 {
        self.points.iter().copied().sum::<DVec3>() / self.points.len().max(1) as f64
    }

    /// The part of the winding on the front of `plane`, points within `eps` behind it
    /// kept; `None` when no point is more than [`TOUCH_EPSILON`] in front. A winding
    /// with no point more than `eps` behind is returned whole, one lying in the plane
    /// included: ties are kept.
    pub fn clip(&self, plane: &Plane, eps: f64) -> Option<Winding> {
        let n = self.points.len();
        let mut buf = [0.0f64; 64];
        let mut heap = Vec::new();
        let d: &mut [f64] = if n <= buf.len() {
            &mut buf[..n]
        } else {
            heap.resize(n, 0.0);
            &mut heap
        };
        let (mut any_out, mut any_in) = (false, false);
        for (di, p) in d.iter_mut().zip(&self.points) {
            *di = plane.distance(*p);
            any_out |= *di < -eps;
            any_in |= *di > TOUCH_EPSILON;
        }
        if !any_out {
            return Some(self.clone());
        }
        if !any_in {
            return None;
        }
        let mut out = Vec::with_capacity(n + 2);
        for i in 0..n {
            let (p, dp) = (self.points[i], d[i]);
            if dp >= -eps {
                out.push(p);
            }
            let j = if i + 1 == n { 0 } else { i + 1 };
            let dq = d[j];
            // The edge crosses the kept boundary `d = -eps`.
            if (dp >= -eps) != (dq >= -eps) {
                let t = (dp + eps) / (dp - dq);
                out.push(p + (self.points[j] - p) * t);
            }
        }
        if out.len() < 3 {
            return None;
        }
        Some(Winding::new(out))
    }

    /// Both parts of the winding (front, back), each keeping the points within `eps`
    /// of the plane, so that the two overlap. A side gets a part only if some point is
    /// more than [`TOUCH_EPSILON`] on it (a winding that only touches the plane along
    /// an edge has nothing on the other side); a winding lying in the plane goes to
    /// both.
    pub fn split(&self, plane: &Plane, eps: f64) -> (Option<Winding>, Option<Winding>) {
        let front = self.any_front(plane, TOUCH_EPSILON);
        let back = self.any_back(plane, TOUCH_EPSILON);
        if !front && !back {
            return (Some(self.clone()), Some(self.clone()));
        }
        (
            front.then(|| self.clip(plane, eps)).flatten(),
            back.then(|| self.clip(&plane.flipped(), eps)).flatten(),
        )
    }

    /// Whether some point is more than `eps` in front of `plane`.
    pub fn any_front(&self, plane: &Plane, eps: f64) -> bool {
        self.points.iter().any(|p| plane.distance(*p) > eps)
    }

    /// Whether some point is more than `eps` behind `plane`.
    pub fn any_back(&self, plane: &Plane, eps: f64) -> bool {
        self.points.iter().any(|p| plane.distance(*p) < -eps)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_square_in_half() {
        let w = Winding::new(vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(10.0, 10.0, 0.0),
            DVec3::new(0.0, 10.0, 0.0),
        ]);
        let half = w.clip(&Plane::new(DVec3::X, 5.0), 0.0).unwrap();
        assert!((half.area() - 50.0).abs() < 1e-9);
        let (f, b) = w.split(&Plane::new(DVec3::X, 5.0), ON_EPSILON);
        assert!((f.unwrap().area() - (50.0 + 10.0 * ON_EPSILON)).abs() < 1e-9);
        assert!((b.unwrap().area() - (50.0 + 10.0 * ON_EPSILON)).abs() < 1e-9);
        assert!(w.clip(&Plane::new(DVec3::X, 11.0), ON_EPSILON).is_none());
        // In the plane: kept whole on both sides.
        let (f, b) = w.split(&Plane::new(DVec3::Z, 0.0), ON_EPSILON);
        assert_eq!((f.unwrap().len(), b.unwrap().len()), (4, 4));
    }
}
