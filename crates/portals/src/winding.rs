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

/// Distance within which [`Winding::split`] takes a point to lie on the cutting plane
/// (f64 rounding of points built from the level's planes, far below [`TOUCH_EPSILON`]):
/// it spares the cut pieces near-duplicate points.
pub const ON_PLANE: f64 = 1e-6;

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
        let mut out = Vec::new();
        clip_into(&self.points, plane, eps, &mut out).then(|| Winding::new(out))
    }

    /// Both parts of the winding (front, back), cut exactly at `plane` as qbsp's
    /// `DivideWinding` cuts: a point within [`ON_PLANE`] of the plane goes to both parts,
    /// and an edge is cut only between points clearly on opposite sides, so the two
    /// parts share their cut edge and never overlap. `normal` is the winding's own
    /// plane's unit normal.
    ///
    /// A side gets a part only if the winding reaches more than [`TOUCH_EPSILON`] into
    /// it, measured in the winding's plane (a distance `d` from `plane` is `d / sin θ`
    /// there, `θ` the angle between the planes): a part thinner than that is float
    /// noise, or an edge or corner the winding only touches, which lines graze (SPEC §3).
    /// A winding lying in the plane goes to both sides.
    pub fn split(&self, plane: &Plane, normal: DVec3) -> (Option<Winding>, Option<Winding>) {
        let n = self.points.len();
        let d: Vec<f64> = self.points.iter().map(|p| plane.distance(*p)).collect();
        let sin = normal.cross(plane.normal).length() / plane.normal.length();
        let reach = TOUCH_EPSILON * sin;
        let front = d.iter().any(|&x| x > reach);
        let back = d.iter().any(|&x| x < -reach);
        if !front && !back {
            return (Some(self.clone()), Some(self.clone()));
        }
        if !back {
            return (Some(self.clone()), None);
        }
        if !front {
            return (None, Some(self.clone()));
        }
        let side = |x: f64| {
            if x > ON_PLANE {
                1
            } else if x < -ON_PLANE {
                -1
            } else {
                0
            }
        };
        let mut f = Vec::with_capacity(n + 2);
        let mut b = Vec::with_capacity(n + 2);
        for i in 0..n {
            let (p, sp) = (self.points[i], side(d[i]));
            if sp >= 0 {
                f.push(p);
            }
            if sp <= 0 {
                b.push(p);
            }
            let j = if i + 1 == n { 0 } else { i + 1 };
            let sq = side(d[j]);
            if sp != 0 && sq != 0 && sp != sq {
                let t = d[i] / (d[i] - d[j]);
                let m = p + (self.points[j] - p) * t;
                f.push(m);
                b.push(m);
            }
        }
        let piece = |v: Vec<DVec3>| (v.len() >= 3).then(|| Winding::new(v));
        (piece(f), piece(b))
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

/// [`Winding::clip`] on the points `w`, written into `out` (cleared first) without
/// allocating once `out` has grown: whether anything is left.
pub fn clip_into(w: &[DVec3], plane: &Plane, eps: f64, out: &mut Vec<DVec3>) -> bool {
    match clip_cut(w, plane, eps, out) {
        Clip::Whole => {
            out.clear();
            out.extend_from_slice(w);
            true
        }
        Clip::Cut => true,
        Clip::Empty => false,
    }
}

/// [`clip_into`] in place: `w` becomes its part in front of `plane` (`tmp` is scratch
/// space); whether anything is left (when not, `w` is left unspecified).
pub fn clip_in_place(w: &mut Vec<DVec3>, tmp: &mut Vec<DVec3>, plane: &Plane, eps: f64) -> bool {
    match clip_cut(w, plane, eps, tmp) {
        Clip::Whole => true,
        Clip::Cut => {
            std::mem::swap(w, tmp);
            true
        }
        Clip::Empty => false,
    }
}

/// What [`clip_cut`] did.
enum Clip {
    /// Nothing to cut: the winding is its own front part (`out` untouched).
    Whole,
    /// The front part is in `out`.
    Cut,
    /// Nothing clearly in front.
    Empty,
}

/// The clipping of [`Winding::clip`], writing the cut part into `out` only when the
/// winding is cut.
fn clip_cut(w: &[DVec3], plane: &Plane, eps: f64, out: &mut Vec<DVec3>) -> Clip {
    let n = w.len();
    // Portals have 3 to 8 points, a few more once clipped: a small buffer, as zeroing
    // a large one on every clip cost 7 % of the flow (callgrind, dm1).
    let mut buf = [0.0f64; 16];
    let mut heap = Vec::new();
    let d: &mut [f64] = if n <= buf.len() {
        &mut buf[..n]
    } else {
        heap.resize(n, 0.0);
        &mut heap
    };
    let (mut any_out, mut any_in) = (false, false);
    for (di, p) in d.iter_mut().zip(w) {
        *di = plane.distance(*p);
        any_out |= *di < -eps;
        any_in |= *di > TOUCH_EPSILON;
    }
    if !any_out {
        return Clip::Whole;
    }
    if !any_in {
        return Clip::Empty;
    }
    out.clear();
    for i in 0..n {
        let (p, dp) = (w[i], d[i]);
        if dp >= -eps {
            out.push(p);
        }
        let j = if i + 1 == n { 0 } else { i + 1 };
        let dq = d[j];
        // The edge crosses the kept boundary `d = -eps`.
        if (dp >= -eps) != (dq >= -eps) {
            let t = (dp + eps) / (dp - dq);
            out.push(p + (w[j] - p) * t);
        }
    }
    if out.len() >= 3 {
        Clip::Cut
    } else {
        Clip::Empty
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
        assert!(w.clip(&Plane::new(DVec3::X, 11.0), ON_EPSILON).is_none());
    }

    #[test]
    fn split_is_exact_and_drops_what_only_touches() {
        let w = Winding::new(vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(10.0, 0.0, 0.0),
            DVec3::new(10.0, 10.0, 0.0),
            DVec3::new(0.0, 10.0, 0.0),
        ]);
        // Exact halves, sharing their cut edge.
        let (f, b) = w.split(&Plane::new(DVec3::X, 5.0), DVec3::Z);
        assert!((f.unwrap().area() - 50.0).abs() < 1e-9);
        assert!((b.unwrap().area() - 50.0).abs() < 1e-9);
        // Through an edge: all of it on one side, nothing on the other.
        let (f, b) = w.split(&Plane::new(DVec3::X, 10.0), DVec3::Z);
        assert!(f.is_none());
        assert_eq!(b.unwrap().len(), 4);
        // A sliver of float noise beyond the plane is no part.
        let (f, b) = w.split(&Plane::new(DVec3::X, 10.0 - TOUCH_EPSILON / 2.0), DVec3::Z);
        assert!(f.is_none() && b.is_some());
        // A plane at a shallow angle: a tiny distance is a wide part in the square's
        // plane, which lines pass through, and is kept.
        let tilted = Plane::new(DVec3::new(1.0, 0.0, 1000.0).normalize(), 0.0);
        let (f, b) = w.split(&tilted, DVec3::Z);
        assert!(
            b.is_none() && f.unwrap().len() == 4,
            "in front, one edge on it"
        );
        let shifted = Plane::new(tilted.normal, tilted.normal.dot(DVec3::new(9.5, 0.0, 0.0)));
        let (f, b) = w.split(&shifted, DVec3::Z);
        assert!((f.unwrap().area() - 5.0).abs() < 1e-6 && b.is_some());
        // In the plane: kept whole on both sides.
        let (f, b) = w.split(&Plane::new(DVec3::Z, 0.0), DVec3::Z);
        assert_eq!((f.unwrap().len(), b.unwrap().len()), (4, 4));
    }
}
