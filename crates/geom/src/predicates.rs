//! Robust orientation predicates (Shewchuk's adaptive arithmetic via the `robust` crate).

use glam::DVec2;

/// Side of a point relative to a directed line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Orientation {
    /// Counter-clockwise: `c` is left of `a → b`.
    Left,
    /// Clockwise: `c` is right of `a → b`.
    Right,
    Collinear,
}

/// Exact sign of the orientation of `(a, b, c)`.
pub fn orient2d(a: DVec2, b: DVec2, c: DVec2) -> Orientation {
    let d = robust::orient2d(
        robust::Coord { x: a.x, y: a.y },
        robust::Coord { x: b.x, y: b.y },
        robust::Coord { x: c.x, y: c.y },
    );
    if d > 0.0 {
        Orientation::Left
    } else if d < 0.0 {
        Orientation::Right
    } else {
        Orientation::Collinear
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_on_nearly_collinear_points() {
        let a = DVec2::new(0.5, 0.5);
        let b = DVec2::new(12.0, 12.0);
        let c = DVec2::new(24.0, 24.0);
        assert_eq!(orient2d(a, b, c), Orientation::Collinear);
        let c_up = DVec2::new(24.0, f64::from_bits(24.0f64.to_bits() + 1));
        assert_eq!(orient2d(a, b, c_up), Orientation::Left);
    }
}
