//! Viewcells: axis-aligned boxes a viewer can stand in.

use crate::aabb::{Aabb2, Aabb3};
use glam::DVec3;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::fmt;
use std::str::FromStr;

/// An axis-aligned viewcell `[x0,y0,z0,x1,y1,z1]`, with `x0 < x1`, `y0 < y1`, `z0 <= z1`
/// (a cell may be flat in z: a walking plane). Serialized as a 6-number array.
///
/// ```
/// use sightline_geom::ViewCell;
/// let c: ViewCell = "-5,2,1.5,5,12,2".parse().unwrap();
/// assert_eq!(c.to_array(), [-5.0, 2.0, 1.5, 5.0, 12.0, 2.0]);
/// assert!("5,2,1.5,-5,12,2".parse::<ViewCell>().is_err()); // inverted
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewCell {
    pub min: DVec3,
    pub max: DVec3,
}

/// Why a box string or array is not a valid viewcell.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ParseBoxError {
    #[error("expected 6 comma-separated numbers x0,y0,z0,x1,y1,z1, got {0}")]
    Count(usize),
    #[error("'{0}' is not a number")]
    Number(String),
    #[error("coordinates must be finite")]
    NotFinite,
    #[error("inverted or empty box: need x0 < x1, y0 < y1, z0 <= z1")]
    Inverted,
}

impl ViewCell {
    pub fn new(min: DVec3, max: DVec3) -> Result<Self, ParseBoxError> {
        Self::from_array([min.x, min.y, min.z, max.x, max.y, max.z])
    }

    pub fn from_array(a: [f64; 6]) -> Result<Self, ParseBoxError> {
        if a.iter().any(|v| !v.is_finite()) {
            return Err(ParseBoxError::NotFinite);
        }
        if !(a[0] < a[3] && a[1] < a[4] && a[2] <= a[5]) {
            return Err(ParseBoxError::Inverted);
        }
        Ok(ViewCell {
            min: DVec3::new(a[0], a[1], a[2]),
            max: DVec3::new(a[3], a[4], a[5]),
        })
    }

    /// The box `rect × [z0, z1]`.
    pub fn from_rect(rect: Aabb2, z0: f64, z1: f64) -> Result<Self, ParseBoxError> {
        Self::from_array([rect.min.x, rect.min.y, z0, rect.max.x, rect.max.y, z1])
    }

    pub fn to_array(&self) -> [f64; 6] {
        [
            self.min.x, self.min.y, self.min.z, self.max.x, self.max.y, self.max.z,
        ]
    }

    pub fn center(&self) -> DVec3 {
        (self.min + self.max) * 0.5
    }

    pub fn size(&self) -> DVec3 {
        self.max - self.min
    }

    pub fn aabb(&self) -> Aabb3 {
        Aabb3::new(self.min, self.max)
    }

    /// Closed containment of a point.
    pub fn contains(&self, p: DVec3) -> bool {
        self.aabb().contains(p)
    }
}

impl FromStr for ViewCell {
    type Err = ParseBoxError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let parts: Vec<&str> = s.split(',').map(str::trim).collect();
        if parts.len() != 6 {
            return Err(ParseBoxError::Count(parts.len()));
        }
        let mut a = [0.0; 6];
        for (v, p) in a.iter_mut().zip(&parts) {
            *v = p
                .parse()
                .map_err(|_| ParseBoxError::Number(p.to_string()))?;
        }
        Self::from_array(a)
    }
}

impl fmt::Display for ViewCell {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.to_array();
        write!(f, "{},{},{},{},{},{}", a[0], a[1], a[2], a[3], a[4], a[5])
    }
}

impl Serialize for ViewCell {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.to_array().serialize(s)
    }
}

impl<'de> Deserialize<'de> for ViewCell {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let a = <[f64; 6]>::deserialize(d)?;
        ViewCell::from_array(a).map_err(serde::de::Error::custom)
    }
}
