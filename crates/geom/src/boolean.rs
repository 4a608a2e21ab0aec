//! Polygon booleans on a fixed 1 mm integer grid (i_overlay, i64 engine).
//!
//! i_overlay snap-rounds every vertex to the grid `GRID_M`; a result can move by up to
//! about one grid step across its boundary. Callers that need a conservative answer
//! (eroded occluders must not grow, occludees must not shrink) compensate by one
//! extra grid step in the safe direction (a conservative occluder must stay inside the true one).

use crate::polygon::{ring_signed_area, Polygon};
use glam::DVec2;
use i_overlay::core::fill_rule::FillRule;
use i_overlay::core::overlay_rule::OverlayRule;
use i_overlay::float::scale::FixedScaleFloatOverlay;

/// Grid step of the integer snapping, in metres.
pub const GRID_M: f64 = 1e-3;

type Shapes = Vec<Vec<Vec<[f64; 2]>>>;

fn to_shapes(polys: &[Polygon]) -> Shapes {
    polys
        .iter()
        .map(|p| {
            p.rings()
                .map(|r| r.iter().map(|v| [v.x, v.y]).collect())
                .collect()
        })
        .collect()
}

fn from_shapes(shapes: Shapes) -> Vec<Polygon> {
    shapes
        .into_iter()
        .filter_map(|shape| {
            let mut rings = shape
                .into_iter()
                .map(|r| r.into_iter().map(DVec2::from).collect::<Vec<_>>())
                .filter(|r| r.len() >= 3 && ring_signed_area(r) != 0.0);
            let exterior = rings.next()?;
            Some(Polygon::new(exterior, rings.collect()).normalized())
        })
        .collect()
}

fn overlay(subject: &[Polygon], clip: &[Polygon], rule: OverlayRule) -> Vec<Polygon> {
    let (s, c) = (to_shapes(subject), to_shapes(clip));
    match s.overlay_with_fixed_scale_as::<i64>(&c, rule, FillRule::NonZero, 1.0 / GRID_M) {
        Ok(shapes) => from_shapes(shapes),
        // Only fails for coordinates beyond ±2^62 mm: impossible after import validation.
        Err(_) => Vec::new(),
    }
}

/// Union of any number of polygons (overlapping or touching), non-zero fill.
pub fn union(polys: &[Polygon]) -> Vec<Polygon> {
    overlay(polys, &[], OverlayRule::Subject)
}

/// `a \ b`.
pub fn difference(a: &[Polygon], b: &[Polygon]) -> Vec<Polygon> {
    overlay(a, b, OverlayRule::Difference)
}

/// `a ∩ b`.
pub fn intersection(a: &[Polygon], b: &[Polygon]) -> Vec<Polygon> {
    overlay(a, b, OverlayRule::Intersect)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sq(x: f64, y: f64, s: f64) -> Polygon {
        Polygon::rect(DVec2::new(x, y), DVec2::new(x + s, y + s))
    }

    #[test]
    fn union_fuses_touching_squares() {
        let u = union(&[sq(0.0, 0.0, 2.0), sq(2.0, 0.0, 2.0), sq(10.0, 10.0, 1.0)]);
        assert_eq!(u.len(), 2);
        let total: f64 = u.iter().map(Polygon::area).sum();
        assert!((total - 9.0).abs() < 1e-6);
    }

    #[test]
    fn difference_makes_a_hole() {
        let d = difference(&[sq(0.0, 0.0, 10.0)], &[sq(4.0, 4.0, 2.0)]);
        assert_eq!(d.len(), 1);
        assert_eq!(d[0].holes.len(), 1);
        assert!((d[0].area() - 96.0).abs() < 1e-6);
    }
}
