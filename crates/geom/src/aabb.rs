//! Axis-aligned boxes in 2D and 3D.

use glam::{DVec2, DVec3};
use serde::{Deserialize, Serialize};

/// An axis-aligned rectangle. `min <= max` component-wise unless [`Aabb2::EMPTY`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb2 {
    pub min: DVec2,
    pub max: DVec2,
}

impl Aabb2 {
    /// The empty box: the identity of [`Aabb2::union`].
    pub const EMPTY: Aabb2 = Aabb2 {
        min: DVec2::splat(f64::INFINITY),
        max: DVec2::splat(f64::NEG_INFINITY),
    };

    pub fn new(min: DVec2, max: DVec2) -> Self {
        Aabb2 { min, max }
    }

    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a DVec2>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(*p))
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y)
    }

    pub fn grow(self, p: DVec2) -> Self {
        Aabb2 {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn union(self, o: Aabb2) -> Self {
        Aabb2 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn size(&self) -> DVec2 {
        self.max - self.min
    }

    pub fn center(&self) -> DVec2 {
        (self.min + self.max) * 0.5
    }

    /// Closed-box containment.
    pub fn contains(&self, p: DVec2) -> bool {
        p.x >= self.min.x && p.x <= self.max.x && p.y >= self.min.y && p.y <= self.max.y
    }

    /// Closed-box overlap (touching boxes intersect).
    pub fn intersects(&self, o: &Aabb2) -> bool {
        self.min.x <= o.max.x
            && o.min.x <= self.max.x
            && self.min.y <= o.max.y
            && o.min.y <= self.max.y
    }

    pub fn expand(&self, d: f64) -> Self {
        Aabb2 {
            min: self.min - DVec2::splat(d),
            max: self.max + DVec2::splat(d),
        }
    }
}

/// An axis-aligned box. `min <= max` component-wise unless [`Aabb3::EMPTY`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Aabb3 {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb3 {
    /// The empty box: the identity of [`Aabb3::union`].
    pub const EMPTY: Aabb3 = Aabb3 {
        min: DVec3::splat(f64::INFINITY),
        max: DVec3::splat(f64::NEG_INFINITY),
    };

    pub fn new(min: DVec3, max: DVec3) -> Self {
        Aabb3 { min, max }
    }

    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a DVec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(*p))
    }

    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    pub fn grow(self, p: DVec3) -> Self {
        Aabb3 {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn union(self, o: Aabb3) -> Self {
        Aabb3 {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }

    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    /// Closed-box containment.
    pub fn contains(&self, p: DVec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Closed-box overlap (touching boxes intersect).
    pub fn intersects(&self, o: &Aabb3) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }

    /// The horizontal footprint.
    pub fn xy(&self) -> Aabb2 {
        Aabb2::new(self.min.truncate(), self.max.truncate())
    }

    /// The 8 corners, x varying fastest.
    pub fn corners(&self) -> [DVec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            DVec3::new(a.x, a.y, a.z),
            DVec3::new(b.x, a.y, a.z),
            DVec3::new(a.x, b.y, a.z),
            DVec3::new(b.x, b.y, a.z),
            DVec3::new(a.x, a.y, b.z),
            DVec3::new(b.x, a.y, b.z),
            DVec3::new(a.x, b.y, b.z),
            DVec3::new(b.x, b.y, b.z),
        ]
    }
}
