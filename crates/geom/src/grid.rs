//! A uniform grid of rectangles over the plane: `nx × ny` cells of `step` from
//! `origin`, numbered row by row (`id = j * nx + i`).
//!
//! One arithmetic for every grid of sightline: the viewcells of `sightline cells`, the
//! walkthrough server's cells and the buckets of a `.pvs` file's spatial index. A cell
//! `(i, j)` spans `origin + (i, j) * step ..= origin + (i + 1, j + 1) * step`, so
//! neighbouring cells share their sides exactly ([`UniformGrid::rect`]; or, exactly
//! `step` wide, [`UniformGrid::rect_from_corner`]); a point's cell is
//! `floor((p - origin) / step)`, a monotone function of `p`, so a point inside a box
//! always falls in one of the cells between those of the box's corners, even with
//! rounding.
//!
//! ```
//! use sightline_geom::{grid::UniformGrid, DVec2};
//! let g = UniformGrid::square(DVec2::new(-50.0, 0.0), 100.0, 3, 2);
//! assert_eq!(g.cell_of(DVec2::new(60.0, 150.0)), (1, 1));
//! assert_eq!(g.id(1, 1), 4);
//! assert_eq!(g.rect(1, 1).min, DVec2::new(50.0, 100.0));
//! assert_eq!(g.neighbour(1, 1, 2, 0), None); // past the last column
//! ```

use crate::aabb::Aabb2;
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// `nx × ny` rectangles of `step` from `origin`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UniformGrid {
    /// Minimum corner of cell `(0, 0)`.
    pub origin: DVec2,
    /// Width and height of a cell.
    pub step: DVec2,
    pub nx: u32,
    pub ny: u32,
}

/// Cells of side `size` needed along one axis from `lo` to reach `hi` (at least one),
/// as `f64` so that a caller can refuse a count too large before converting it.
pub fn cells_to_cover(lo: f64, hi: f64, size: f64) -> f64 {
    ((hi - lo) / size).ceil().max(1.0)
}

/// The square cells of side `size_m` covering a rectangle: the one numbering of cells
/// shared by `sightline cells` and the walkthrough server's on-line grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cover {
    /// Minimum corner of cell 0: the rectangle's minimum corner rounded down to a
    /// multiple of `size_m`, so cells sit on round coordinates whatever the scene.
    pub origin: DVec2,
    pub size_m: f64,
    /// Columns and rows, as `f64` so that a caller can refuse a grid too large before
    /// converting ([`Cover::total`]).
    pub nx: f64,
    pub ny: f64,
}

impl Cover {
    /// Number of cells (NaN or huge for a degenerate input: callers compare it to their
    /// limit before [`Cover::grid`]).
    pub fn total(&self) -> f64 {
        self.nx * self.ny
    }

    /// The cells as a [`UniformGrid`] (counts saturated to `u32`).
    pub fn grid(&self) -> UniformGrid {
        UniformGrid::square(self.origin, self.size_m, self.nx as u32, self.ny as u32)
    }
}

/// Cover `bounds` with square cells of side `size_m` (a positive finite number, checked
/// by the caller), row by row from `bounds.min` rounded down to a multiple of `size_m`;
/// the last row and column may stick out.
///
/// ```
/// use sightline_geom::{grid, Aabb2, DVec2};
/// let c = grid::cover(Aabb2::new(DVec2::new(-50.0, 12.0), DVec2::new(250.0, 180.0)), 100.0);
/// assert_eq!(c.origin, DVec2::new(-100.0, 0.0));
/// assert_eq!((c.nx, c.ny), (4.0, 2.0));
/// ```
pub fn cover(bounds: Aabb2, size_m: f64) -> Cover {
    let origin = (bounds.min / size_m).floor() * size_m;
    Cover {
        origin,
        size_m,
        nx: cells_to_cover(origin.x, bounds.max.x, size_m),
        ny: cells_to_cover(origin.y, bounds.max.y, size_m),
    }
}

impl UniformGrid {
    /// Square cells of side `size_m`.
    pub fn square(origin: DVec2, size_m: f64, nx: u32, ny: u32) -> Self {
        UniformGrid {
            origin,
            step: DVec2::splat(size_m),
            nx,
            ny,
        }
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.nx as usize * self.ny as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Id of cell `(i, j)`.
    pub fn id(&self, i: u32, j: u32) -> u32 {
        j * self.nx + i
    }

    /// Column and row of cell `id`, if it is on the grid.
    pub fn coords(&self, id: u32) -> Option<(u32, u32)> {
        ((id as usize) < self.len()).then(|| (id % self.nx, id / self.nx))
    }

    /// The far corner of the grid.
    pub fn max(&self) -> DVec2 {
        self.origin + DVec2::new(self.nx as f64, self.ny as f64) * self.step
    }

    /// The closed rectangle covered by the grid.
    pub fn bounds(&self) -> Aabb2 {
        Aabb2::new(self.origin, self.max())
    }

    /// The minimum corner of cell `(i, j)`.
    pub fn corner(&self, i: u32, j: u32) -> DVec2 {
        self.origin + DVec2::new(i as f64, j as f64) * self.step
    }

    /// The rectangle of cell `(i, j)`, from its corner to the next cell's: neighbouring
    /// cells share their sides exactly.
    pub fn rect(&self, i: u32, j: u32) -> Aabb2 {
        Aabb2::new(self.corner(i, j), self.corner(i + 1, j + 1))
    }

    /// The rectangle `corner(i, j) ..= corner(i, j) + step`: exactly `step` wide, while
    /// its far sides may miss the next cell's near sides by a rounding (the walkthrough
    /// server's cells and the street cells are these).
    pub fn rect_from_corner(&self, i: u32, j: u32) -> Aabb2 {
        let lo = self.corner(i, j);
        Aabb2::new(lo, lo + self.step)
    }

    /// Column and row of the cell containing `p`, clamped to the grid (a point below the
    /// origin, or NaN, goes to the first column or row, one past the far side to the
    /// last). Cells are closed at their low side, the last row and column also at their
    /// high side.
    pub fn cell_of(&self, p: DVec2) -> (u32, u32) {
        let along = |v: f64, o: f64, s: f64, n: u32| {
            let b = ((v - o) / s).floor();
            if b.is_nan() || b < 0.0 {
                0
            } else {
                (b as u64).min(n as u64 - 1) as u32
            }
        };
        (
            along(p.x, self.origin.x, self.step.x, self.nx),
            along(p.y, self.origin.y, self.step.y, self.ny),
        )
    }

    /// Id of the cell `(i + di, j + dj)`, if it is on the grid.
    pub fn neighbour(&self, i: u32, j: u32, di: i64, dj: i64) -> Option<u32> {
        let (ni, nj) = (i as i64 + di, j as i64 + dj);
        let inside = (0..self.nx as i64).contains(&ni) && (0..self.ny as i64).contains(&nj);
        inside.then(|| self.id(ni as u32, nj as u32))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_coords_and_rects_agree() {
        let g = UniformGrid {
            origin: DVec2::new(-18.2, 70.0),
            step: DVec2::new(13.7, 6.1),
            nx: 23,
            ny: 21,
        };
        assert_eq!(g.len(), 483);
        for id in 0..g.len() as u32 {
            let (i, j) = g.coords(id).unwrap();
            assert_eq!(g.id(i, j), id);
            let r = g.rect(i, j);
            assert_eq!(g.cell_of(r.center()), (i, j));
            if i + 1 < g.nx {
                assert_eq!(r.max.x, g.rect(i + 1, j).min.x, "shared side");
            }
            let q = g.rect_from_corner(i, j);
            assert_eq!((q.min, q.max), (r.min, r.min + g.step));
        }
        assert_eq!(g.coords(483), None);
        assert_eq!(g.cell_of(g.max()), (22, 20));
        assert_eq!(g.cell_of(DVec2::new(f64::NAN, -1e9)), (0, 0));
        assert_eq!(g.neighbour(0, 0, -1, 0), None);
        assert_eq!(g.neighbour(0, 0, 1, 1), Some(24));
    }

    #[test]
    fn cover_counts_at_least_one_cell() {
        assert_eq!(cells_to_cover(0.0, 250.0, 100.0), 3.0);
        assert_eq!(cells_to_cover(0.0, 200.0, 100.0), 2.0);
        assert_eq!(cells_to_cover(5.0, 5.0, 100.0), 1.0);
        assert_eq!(cells_to_cover(0.0, 1.0, f64::NAN), 1.0);
    }
}
