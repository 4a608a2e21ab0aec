//! The six projection directions of a cell and the placement of projection planes
//! (Durand et al. 2000, §2.4 and §6.1 "Choice of the projection plane").
//!
//! Every computation for one direction happens in a *local frame* `(w, u, v)`: `w`
//! is the depth axis leaving the cell (its positive direction points away from the
//! cell, §2.3), `u` and `v` are the two axes of the projection plane. A plane is the
//! set `w = x` for some `x` beyond the cell's far face, restricted to a finite
//! rectangle (§2.4), discretised into `n × n` pixels.

use sightline_geom::{Aabb2, DVec2, DVec3};

/// One of the six axis directions along which a cell projects (§2.4: "the projection
/// planes will be restricted to the three directions of the cell").
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Direction {
    PosX,
    NegX,
    PosY,
    NegY,
    PosZ,
    NegZ,
}

impl Direction {
    pub const ALL: [Direction; 6] = [
        Direction::PosX,
        Direction::NegX,
        Direction::PosY,
        Direction::NegY,
        Direction::PosZ,
        Direction::NegZ,
    ];

    /// World point → local `(w, u, v)`.
    pub(crate) fn to_local(self, p: DVec3) -> DVec3 {
        match self {
            Direction::PosX => DVec3::new(p.x, p.y, p.z),
            Direction::NegX => DVec3::new(-p.x, p.y, p.z),
            Direction::PosY => DVec3::new(p.y, p.x, p.z),
            Direction::NegY => DVec3::new(-p.y, p.x, p.z),
            Direction::PosZ => DVec3::new(p.z, p.x, p.y),
            Direction::NegZ => DVec3::new(-p.z, p.x, p.y),
        }
    }

    /// World box → local box.
    pub fn box_to_local(self, min: DVec3, max: DVec3) -> LocalBox {
        let (a, b) = (self.to_local(min), self.to_local(max));
        LocalBox {
            min: a.min(b),
            max: a.max(b),
        }
    }

    /// Whether the depth axis is vertical (the footprints of prisms then lie in the
    /// plane `(u, v)`, otherwise in the plane `(w, u)`).
    pub fn is_vertical(self) -> bool {
        matches!(self, Direction::PosZ | Direction::NegZ)
    }

    /// World `xy` → local 2D coordinates of a footprint: `(w, u)` for horizontal
    /// directions, `(u, v)` for vertical ones.
    pub(crate) fn footprint_to_local(self, p: DVec2) -> DVec2 {
        match self {
            Direction::PosX => DVec2::new(p.x, p.y),
            Direction::NegX => DVec2::new(-p.x, p.y),
            Direction::PosY => DVec2::new(p.y, p.x),
            Direction::NegY => DVec2::new(-p.y, p.x),
            Direction::PosZ | Direction::NegZ => p,
        }
    }

    /// Local depth interval of a world height interval (vertical directions only).
    pub(crate) fn height_to_depth(self, base: f64, top: f64) -> (f64, f64) {
        match self {
            Direction::NegZ => (-top, -base),
            _ => (base, top),
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Direction::PosX => "+x",
            Direction::NegX => "-x",
            Direction::PosY => "+y",
            Direction::NegY => "-y",
            Direction::PosZ => "+z",
            Direction::NegZ => "-z",
        }
    }
}

/// An axis-aligned box in a local frame `(w, u, v)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalBox {
    pub min: DVec3,
    pub max: DVec3,
}

impl LocalBox {
    /// The 8 corners (duplicates for flat boxes are harmless).
    pub(crate) fn corners(&self) -> [DVec3; 8] {
        sightline_geom::Aabb3::new(self.min, self.max).corners()
    }
}

/// A finite projection plane `w = x` of one direction of one cell, with its pixel grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plane {
    pub dir: Direction,
    /// Position of the plane on the depth axis (local `w`).
    pub x: f64,
    /// The finite rectangle in `(u, v)`.
    pub rect: Aabb2,
    /// Pixels per side.
    pub n: usize,
}

impl Plane {
    /// The plane at depth `x` for `cell` (local): the cell's cross-section grown by
    /// 45° from the cell's near... far face (the frustum of the direction), then
    /// extended by `extension` about its centre for the corner directions (§6.1).
    pub fn new(dir: Direction, cell: &LocalBox, x: f64, n: usize, extension: f64) -> Plane {
        let grow = (x - cell.min.x).max(0.0);
        let c = DVec2::new(
            0.5 * (cell.min.y + cell.max.y),
            0.5 * (cell.min.z + cell.max.z),
        );
        let half = DVec2::new(
            0.5 * (cell.max.y - cell.min.y) + grow,
            0.5 * (cell.max.z - cell.min.z) + grow,
        ) * extension;
        Plane {
            dir,
            x,
            rect: Aabb2::new(c - half, c + half),
            n,
        }
    }

    /// Size of a pixel in plane units.
    pub(crate) fn pixel_size(&self) -> DVec2 {
        self.rect.size() / self.n as f64
    }

    /// Plane coordinates → continuous pixel coordinates (pixel `(i, j)` covers
    /// `[i, i+1] × [j, j+1]`).
    pub fn to_px(&self, p: DVec2) -> DVec2 {
        (p - self.rect.min) / self.pixel_size()
    }

    /// Continuous pixel coordinates → plane coordinates.
    pub fn from_px(&self, p: DVec2) -> DVec2 {
        self.rect.min + p * self.pixel_size()
    }
}

/// The *view* of local point `p` from viewpoint `e` on the plane `w = x` (§2.1: a
/// perspective projection from a point onto the shared projection plane). Requires
/// `p.x > e.x`.
#[inline]
pub(crate) fn view(e: DVec3, p: DVec3, x: f64) -> DVec2 {
    let t = (x - e.x) / (p.x - e.x);
    DVec2::new(e.y + (p.y - e.y) * t, e.z + (p.z - e.z) * t)
}

/// Candidate plane positions for the placement heuristic: "we place a candidate
/// plane just behind each occluder" (§6.1). `far_depths` are the occluders' far
/// depths; at most `max` evenly spread candidates are kept, nearest first.
pub(crate) fn candidate_positions(far_depths: &[f64], max: usize) -> Vec<f64> {
    let mut c: Vec<f64> = far_depths
        .iter()
        .copied()
        .filter(|d| d.is_finite())
        .collect();
    c.sort_by(f64::total_cmp);
    c.dedup_by(|a, b| (*a - *b).abs() < 0.05);
    if c.len() <= max || max == 0 {
        return c;
    }
    let step = c.len() as f64 / max as f64;
    (0..max).map(|i| c[(i as f64 * step) as usize]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn local_frames_are_consistent() {
        let p = DVec3::new(1.0, 2.0, 3.0);
        assert_eq!(Direction::NegY.to_local(p), DVec3::new(-2.0, 1.0, 3.0));
        for d in Direction::ALL {
            let b = d.box_to_local(DVec3::ZERO, p);
            assert!(b.min.cmple(b.max).all());
            let f = d.footprint_to_local(DVec2::new(1.0, 2.0));
            if !d.is_vertical() {
                let l = d.to_local(p);
                assert_eq!(f, DVec2::new(l.x, l.y));
            }
        }
    }

    #[test]
    fn plane_grows_with_distance_and_extension() {
        let cell = Direction::PosX.box_to_local(DVec3::ZERO, DVec3::new(10.0, 10.0, 2.0));
        let p = Plane::new(Direction::PosX, &cell, 20.0, 64, 1.0);
        assert_eq!(p.rect.min.x, 5.0 - 5.0 - 20.0);
        let q = Plane::new(Direction::PosX, &cell, 20.0, 64, 1.5);
        assert!(q.rect.size().x > p.rect.size().x * 1.49);
        assert_eq!(
            p.to_px(p.from_px(DVec2::new(3.0, 7.0))),
            DVec2::new(3.0, 7.0)
        );
    }

    #[test]
    fn view_is_a_central_projection() {
        let e = DVec3::new(0.0, 0.0, 0.0);
        let p = DVec3::new(10.0, 5.0, 2.0);
        assert_eq!(view(e, p, 20.0), DVec2::new(10.0, 4.0));
        assert_eq!(view(e, p, 5.0), DVec2::new(2.5, 1.0));
    }
}
