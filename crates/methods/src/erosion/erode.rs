//! Exact 2D erosion of footprints by convex structuring elements (Décoret et al. 2003,
//! §4.3, equation (1)) and the elements themselves (§3.3, §5.1).
//!
//! `P ⊖ X = P \ (∂P ⊕ −X)` for a convex `X` containing the origin: every edge of `P`
//! is swept by `−X` (the convex hull of its two end points translated by `−X`), the
//! swept hulls are unioned and subtracted from `P`. An element that does not contain
//! the origin (a side of the cell seen from its centre, Fig. 5) is first translated by
//! one of its points `x₀`: `P ⊖ X = (P ⊖ (X − x₀)) − x₀`.
//!
//! Rounding: the booleans snap to the 1 mm grid of [`sightline_geom::boolean`]; every
//! swept hull is grown by [`GRID_MARGIN_M`] so the result stays inside the exact
//! erosion (NOTES §3: occluders are rounded *inward*).

use sightline_geom::{boolean, DVec2, Polygon};

/// Extra inward rounding of eroded occluders: two grid steps of the boolean engine.
pub const GRID_MARGIN_M: f64 = 2.0 * boolean::GRID_M;

/// The horizontal structuring elements used for a box viewcell of half sizes `(a, b)`,
/// all expressed relative to the cell centre `S` (everything is rendered from `S`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Element {
    /// Side `x = x1`: the segment `(a, −b)–(a, b)`. Supports shafts to occludees right of the cell.
    Right,
    /// Side `x = x0`: `(−a, −b)–(−a, b)`.
    Left,
    /// Side `y = y1`: `(−a, b)–(a, b)`.
    Top,
    /// Side `y = y0`: `(−a, −b)–(a, −b)`.
    Bottom,
    /// The diagonal `(−a, b)–(a, −b)`: supports shafts to occludees beyond the upper-right
    /// or lower-left corner.
    AntiDiagonal,
    /// The diagonal `(−a, −b)–(a, b)`: upper-left and lower-right corners.
    Diagonal,
    /// The whole cell footprint (method 2 of §6, `erosion-cell`).
    Cell,
    /// The regular octagon circumscribing the cell's bounding disc (method 1, after
    /// Wonka et al. 2000, `shrink-sphere`).
    Octagon,
}

impl Element {
    pub const SEGMENTS: [Element; 6] = [
        Element::Right,
        Element::Left,
        Element::Top,
        Element::Bottom,
        Element::AntiDiagonal,
        Element::Diagonal,
    ];

    /// The vertices of the (convex) element for half sizes `half = (a, b)`, relative
    /// to the cell centre.
    pub fn vertices(self, half: DVec2) -> Vec<DVec2> {
        let (a, b) = (half.x, half.y);
        let v = DVec2::new;
        match self {
            Element::Right => vec![v(a, -b), v(a, b)],
            Element::Left => vec![v(-a, -b), v(-a, b)],
            Element::Top => vec![v(-a, b), v(a, b)],
            Element::Bottom => vec![v(-a, -b), v(a, -b)],
            Element::AntiDiagonal => vec![v(-a, b), v(a, -b)],
            Element::Diagonal => vec![v(-a, -b), v(a, b)],
            Element::Cell => vec![v(-a, -b), v(a, -b), v(a, b), v(-a, b)],
            Element::Octagon => {
                // Apothem r = radius of the bounding disc: the octagon contains the disc.
                let r = half.length();
                let rv = r / (std::f64::consts::PI / 8.0).cos();
                (0..8)
                    .map(|k| {
                        let t = std::f64::consts::PI / 8.0 + k as f64 * std::f64::consts::PI / 4.0;
                        DVec2::new(rv * t.cos(), rv * t.sin())
                    })
                    .collect()
            }
        }
    }

    /// Midpoint of the element (the translation that centres it).
    pub fn midpoint(self, half: DVec2) -> DVec2 {
        let vs = self.vertices(half);
        vs.iter().copied().sum::<DVec2>() / vs.len() as f64
    }
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, without collinear points.
pub fn convex_hull(mut pts: Vec<DVec2>) -> Vec<DVec2> {
    pts.sort_by(|p, q| p.x.total_cmp(&q.x).then(p.y.total_cmp(&q.y)));
    pts.dedup();
    if pts.len() < 3 {
        return pts;
    }
    let cross = |o: DVec2, a: DVec2, b: DVec2| (a - o).perp_dot(b - o);
    let mut lower: Vec<DVec2> = Vec::with_capacity(pts.len());
    for &p in &pts {
        while lower.len() >= 2 && cross(lower[lower.len() - 2], lower[lower.len() - 1], p) <= 0.0 {
            lower.pop();
        }
        lower.push(p);
    }
    let mut upper: Vec<DVec2> = Vec::with_capacity(pts.len());
    for &p in pts.iter().rev() {
        while upper.len() >= 2 && cross(upper[upper.len() - 2], upper[upper.len() - 1], p) <= 0.0 {
            upper.pop();
        }
        upper.push(p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// `polys ⊖ X` for a convex element given by its vertices (equation (1)), rounded inward
/// by `margin` metres (the result lies inside the exact erosion by `X ⊕ B(margin)`
/// for the square `B`, hence inside `polys ⊖ X` after snapping).
///
/// `polys` must be interior-disjoint (e.g. the output of a union): the erosion of
/// their union is what is computed.
pub fn erode(polys: &[Polygon], element: &[DVec2], margin: f64) -> Vec<Polygon> {
    if polys.is_empty() || element.is_empty() {
        return polys.to_vec();
    }
    // Make the element contain the origin: X' = X − x₀.
    let x0 = element[0];
    let mut xs: Vec<DVec2> = Vec::with_capacity(element.len() * 4);
    for &x in element {
        let x = x - x0;
        for d in [
            DVec2::new(-margin, -margin),
            DVec2::new(margin, -margin),
            DVec2::new(margin, margin),
            DVec2::new(-margin, margin),
        ] {
            xs.push(x + d);
        }
    }
    let mut band: Vec<Polygon> = Vec::new();
    for p in polys {
        for (a, b) in p.edges() {
            let mut pts = Vec::with_capacity(xs.len() * 2);
            for &x in &xs {
                pts.push(a - x);
                pts.push(b - x);
            }
            let hull = convex_hull(pts);
            if hull.len() >= 3 {
                band.push(Polygon::new(hull, vec![]));
            }
        }
    }
    let eroded = boolean::difference(polys, &band);
    // Undo the translation: P ⊖ X = (P ⊖ X') − x₀.
    if x0 == DVec2::ZERO {
        eroded
    } else {
        eroded.iter().map(|p| p.translated(-x0)).collect()
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

    fn area(ps: &[Polygon]) -> f64 {
        ps.iter().map(Polygon::area).sum()
    }

    #[test]
    fn erosion_of_l_by_square_and_segment() {
        // DEPS.md reference values: L of area 64 (here 48: 8x8 minus 4x4) — compute by hand:
        // eroding by [-1,1]^2 keeps [1,7]x[1,3] ∪ [1,3]x[1,7] = 12 + 12 - 4 = 20.
        let sq = Element::Cell.vertices(DVec2::new(1.0, 1.0));
        let e = erode(&[l_shape()], &sq, 0.0);
        assert!((area(&e) - 20.0).abs() < 1e-3, "{}", area(&e));
        // Segment (−1,0)–(1,0): [1,7]x[0,4] ∪ [1,3]x[0,8] = 24 + 16 - 8 = 32.
        let seg = vec![DVec2::new(-1.0, 0.0), DVec2::new(1.0, 0.0)];
        let e = erode(&[l_shape()], &seg, 0.0);
        assert!((area(&e) - 32.0).abs() < 1e-3, "{}", area(&e));
    }

    #[test]
    fn erosion_by_an_element_off_the_origin_translates() {
        // Right side of a 2x2 cell: X = {(1, t) : t ∈ [-1, 1]}. A 10x10 square eroded:
        // V + X ⊂ P ⇔ V.x + 1 ∈ [0,10], V.y ± 1 ∈ [0,10] → [-1, 9] x [1, 9].
        let p = Polygon::rect(DVec2::ZERO, DVec2::splat(10.0));
        let e = erode(&[p], &Element::Right.vertices(DVec2::ONE), 0.0);
        assert_eq!(e.len(), 1);
        let bb = e[0].bbox();
        assert!((bb.min - DVec2::new(-1.0, 1.0)).length() < 1e-3, "{bb:?}");
        assert!((bb.max - DVec2::new(9.0, 9.0)).length() < 1e-3, "{bb:?}");
    }

    #[test]
    fn union_erodes_more_than_pieces() {
        // Two touching 4x4 squares eroded by a 2x2 cell: the union keeps a 6x2 strip,
        // the pieces only two 2x2 squares.
        let a = Polygon::rect(DVec2::ZERO, DVec2::new(4.0, 4.0));
        let b = Polygon::rect(DVec2::new(4.0, 0.0), DVec2::new(8.0, 4.0));
        let x = Element::Cell.vertices(DVec2::ONE);
        let fused = erode(&boolean::union(&[a.clone(), b.clone()]), &x, 0.0);
        let pieces = [erode(&[a], &x, 0.0), erode(&[b], &x, 0.0)].concat();
        assert!((area(&fused) - 12.0).abs() < 1e-3);
        assert!((area(&pieces) - 8.0).abs() < 1e-3);
    }

    #[test]
    fn octagon_contains_the_cell() {
        let half = DVec2::new(3.0, 1.0);
        let oct = Element::Octagon.vertices(half);
        let poly = Polygon::new(oct, vec![]);
        for c in Element::Cell.vertices(half) {
            assert!(poly.contains(c * 0.999));
        }
    }
}
