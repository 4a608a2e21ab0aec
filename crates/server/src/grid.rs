//! The regular grid of viewcells the on-line source answers for.
//!
//! The dual ray space paper's walkthrough (Koltun et al. 2001, §6) partitions the ground
//! into square viewcells of 100 × 100 m, 2 m high, and keeps the client supplied with the
//! PVS of the cell it stands in and of the adjacent ones. [`CellGrid`] is that partition:
//! square cells of `cell_size_m` covering the scene's bounding rectangle, at eye height
//! `z_range_m` (default 1.5–2.0 m, as `sightline cells`), laid out and numbered as
//! `sightline cells` lays them out ([`grid::cover`]: from the scene's minimum corner
//! rounded down to a multiple of the cell size) and as every grid of sightline
//! ([`UniformGrid`]): a cell's id is `iy * nx + ix`.

use serde::Serialize;
use sightline_geom::{grid, Aabb3, DVec2, DVec3, UniformGrid, ViewCell};

/// Eye-height range of the walking viewcells (the `cells` default).
pub const EYE_Z_M: (f64, f64) = (1.5, 2.0);

/// A cell id on a grid (or an index into a `.pvs` file's cells).
pub type CellId = u32;

/// Most cells a grid may have: ids are `u32` and sessions keep per-cell state.
pub const MAX_CELLS: u64 = 1 << 26;

/// Square viewcells of `cell_size_m` covering `[origin, origin + (nx, ny) * size]`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CellGrid {
    /// South-west corner of cell 0 (the scene's minimum x, y rounded down to a multiple
    /// of the cell size, as `sightline cells`: [`grid::cover`]).
    pub origin: [f64; 2],
    pub cell_size_m: f64,
    pub nx: u32,
    pub ny: u32,
    /// Eye-height range of every cell.
    pub z_range_m: [f64; 2],
    /// Highest z a query point may have (scene top, at least the eye height).
    pub top_m: f64,
}

/// Why a grid cannot be made.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GridError {
    #[error("cell size must be a positive finite number of metres, got {0}")]
    BadSize(f64),
    #[error("the scene is empty: nothing to cover with cells")]
    EmptyScene,
    #[error("{0} cells of {1} m would be needed (at most {MAX_CELLS}): use a larger --cell-size")]
    TooMany(u64, f64),
}

/// Why a point has no cell.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum PointError {
    #[error("coordinates must be finite numbers")]
    NotFinite,
    #[error("point ({0}, {1}, {2}) is outside the scene (x {3}..{4}, y {5}..{6}, z 0..{7})")]
    Outside(f64, f64, f64, f64, f64, f64, f64, f64),
    #[error("point ({0}, {1}, {2}) is in no cell (inside a wall or outside the level)")]
    NoCell(f64, f64, f64),
}

impl CellGrid {
    /// Cover `bounds` (a scene's bounding box) with cells of `cell_size_m`, numbered as
    /// `sightline cells` numbers them ([`grid::cover`]).
    pub fn cover(bounds: &Aabb3, cell_size_m: f64) -> Result<Self, GridError> {
        if !(cell_size_m.is_finite() && cell_size_m > 0.0) {
            return Err(GridError::BadSize(cell_size_m));
        }
        if bounds.is_empty() {
            return Err(GridError::EmptyScene);
        }
        let c = grid::cover(bounds.xy(), cell_size_m);
        let total = c.total();
        // Written so that a NaN total is rejected too.
        if total.is_nan() || total > MAX_CELLS as f64 {
            return Err(GridError::TooMany(total as u64, cell_size_m));
        }
        Ok(CellGrid {
            origin: c.origin.to_array(),
            cell_size_m,
            nx: c.nx as u32,
            ny: c.ny as u32,
            z_range_m: [EYE_Z_M.0, EYE_Z_M.1],
            top_m: bounds.max.z.max(EYE_Z_M.1),
        })
    }

    /// The cells' footprints: the grid arithmetic (ids, a point's cell, a cell's square).
    pub fn squares(&self) -> UniformGrid {
        UniformGrid::square(
            DVec2::from_array(self.origin),
            self.cell_size_m,
            self.nx,
            self.ny,
        )
    }

    pub fn len(&self) -> usize {
        self.squares().len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The far corner of the grid.
    pub fn max(&self) -> DVec2 {
        self.squares().max()
    }

    /// The cell whose column contains `p` (cells are closed at their low side, and the
    /// last row/column also at its high side).
    pub fn locate(&self, p: DVec3) -> Result<CellId, PointError> {
        if !p.is_finite() {
            return Err(PointError::NotFinite);
        }
        let squares = self.squares();
        let (min, max) = (squares.origin, squares.max());
        let inside = squares.bounds().contains(p.truncate()) && p.z >= 0.0 && p.z <= self.top_m;
        if !inside {
            return Err(PointError::Outside(
                p.x, p.y, p.z, min.x, max.x, min.y, max.y, self.top_m,
            ));
        }
        let (ix, iy) = squares.cell_of(p.truncate());
        Ok(squares.id(ix, iy))
    }

    /// Grid coordinates of a cell.
    pub fn coords(&self, id: CellId) -> Option<(u32, u32)> {
        self.squares().coords(id)
    }

    /// The box of a cell.
    pub fn cell(&self, id: CellId) -> Option<ViewCell> {
        let squares = self.squares();
        let (ix, iy) = squares.coords(id)?;
        let r = squares.rect_from_corner(ix, iy);
        ViewCell::from_rect(r, self.z_range_m[0], self.z_range_m[1]).ok()
    }

    /// The (up to) 8 cells adjacent to `id`, ordered so that those lying ahead along
    /// `heading` come first (dual ray space paper, Fig. 5: the client will next enter one
    /// of the cells in front of it). A zero heading keeps the ring order.
    pub fn neighbours(&self, id: CellId, heading: DVec2) -> Vec<CellId> {
        let squares = self.squares();
        let Some((ix, iy)) = squares.coords(id) else {
            return vec![];
        };
        let h = heading.normalize_or_zero();
        let mut out: Vec<(f64, CellId)> = Vec::with_capacity(8);
        for dy in -1i64..=1 {
            for dx in -1i64..=1 {
                if dx == 0 && dy == 0 {
                    continue;
                }
                if let Some(n) = squares.neighbour(ix, iy, dx, dy) {
                    let along = DVec2::new(dx as f64, dy as f64).normalize().dot(h);
                    out.push((along, n));
                }
            }
        }
        // Stable: equal scores keep the ring order.
        out.sort_by(|a, b| b.0.total_cmp(&a.0));
        out.into_iter().map(|(_, c)| c).collect()
    }

    /// The cell a client at `p` moving along `heading` enters next: the neighbour of `p`'s
    /// cell across the side (or corner) its ray leaves through. `None` when standing still,
    /// outside the grid, or leaving the grid.
    pub fn next_cell(&self, p: DVec2, heading: DVec2) -> Option<CellId> {
        let h = heading.normalize_or_zero();
        if h == DVec2::ZERO || !p.is_finite() {
            return None;
        }
        let id = self.locate(DVec3::new(p.x, p.y, self.z_range_m[0])).ok()?;
        let squares = self.squares();
        let (ix, iy) = squares.coords(id)?;
        let r = squares.rect_from_corner(ix, iy);
        // Distance along the ray to the side crossed in x and in y.
        let t = exit_distance;
        let (tx, ty) = (t(p.x, r.min.x, r.max.x, h.x), t(p.y, r.min.y, r.max.y, h.y));
        let eps = 1e-9 * self.cell_size_m;
        let dx = if tx <= ty + eps {
            h.x.signum() as i64
        } else {
            0
        };
        let dy = if ty <= tx + eps {
            h.y.signum() as i64
        } else {
            0
        };
        if (dx, dy) == (0, 0) {
            return None;
        }
        squares.neighbour(ix, iy, dx, dy)
    }

    /// The cell `steps` cells ahead of `id` along `heading` (rounded to the nearest of the
    /// 8 directions), if inside the grid: what a fast client reaches after the neighbour.
    pub fn ahead(&self, id: CellId, heading: DVec2, steps: u32) -> Option<CellId> {
        let squares = self.squares();
        let (ix, iy) = squares.coords(id)?;
        let h = heading.normalize_or_zero();
        if h == DVec2::ZERO {
            return None;
        }
        let (dx, dy) = (h.x.round() as i64, h.y.round() as i64);
        squares.neighbour(ix, iy, dx * steps as i64, dy * steps as i64)
    }
}

/// Distance along a ray from coordinate `pc` with direction component `hc` to the side
/// of the interval `[lo, hi]` it leaves by (infinite when `hc` is 0).
pub(crate) fn exit_distance(pc: f64, lo: f64, hi: f64, hc: f64) -> f64 {
    if hc > 0.0 {
        (hi - pc) / hc
    } else if hc < 0.0 {
        (lo - pc) / hc
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn next_cell_is_across_the_side_the_ray_leaves_through() {
        let g = grid(); // 4 × 2 cells of 100 m from (-100, 0)
        let p = DVec2::new(-50.0, 50.0); // cell 0, centre
        assert_eq!(g.next_cell(p, DVec2::new(1.0, 0.0)), Some(1));
        assert_eq!(g.next_cell(p, DVec2::new(0.0, 1.0)), Some(4));
        assert_eq!(g.next_cell(p, DVec2::new(1.0, 1.0)), Some(5)); // through the corner
        assert_eq!(g.next_cell(p, DVec2::new(-1.0, 0.0)), None); // leaves the grid
        assert_eq!(g.next_cell(p, DVec2::ZERO), None);
        // Near the top side, heading mostly east: the top side comes first.
        assert_eq!(
            g.next_cell(DVec2::new(-50.0, 95.0), DVec2::new(1.0, 0.2)),
            Some(4)
        );
        assert_eq!(
            g.next_cell(DVec2::new(-50.0, 5.0), DVec2::new(1.0, 0.2)),
            Some(1)
        );
        assert_eq!(
            g.next_cell(DVec2::new(1e6, 0.0), DVec2::new(1.0, 0.0)),
            None
        );
    }

    fn grid() -> CellGrid {
        let b = Aabb3::new(DVec3::new(-50.0, 0.0, 0.0), DVec3::new(250.0, 180.0, 30.0));
        CellGrid::cover(&b, 100.0).unwrap()
    }

    #[test]
    fn covers_the_scene_rectangle() {
        let g = grid();
        // From (-50, 0) rounded down to a multiple of 100 m: (-100, 0), as `cells`.
        assert_eq!(g.origin, [-100.0, 0.0]);
        assert_eq!((g.nx, g.ny), (4, 2));
        assert_eq!(g.top_m, 30.0);
        assert_eq!(
            g.cell(5).unwrap().to_array(),
            [0.0, 100.0, 1.5, 100.0, 200.0, 2.0]
        );
        assert!(g.cell(8).is_none());
    }

    #[test]
    fn locates_points_and_rejects_outside_ones() {
        let g = grid();
        assert_eq!(g.locate(DVec3::new(-50.0, 0.0, 1.7)), Ok(0));
        assert_eq!(g.locate(DVec3::new(60.0, 150.0, 1.7)), Ok(5));
        // The far border belongs to the last cell.
        assert_eq!(g.locate(DVec3::new(300.0, 200.0, 0.0)), Ok(7));
        assert!(matches!(
            g.locate(DVec3::new(-100.1, 0.0, 1.7)),
            Err(PointError::Outside(..))
        ));
        assert!(matches!(
            g.locate(DVec3::new(0.0, 0.0, 31.0)),
            Err(PointError::Outside(..))
        ));
        assert_eq!(
            g.locate(DVec3::new(f64::NAN, 0.0, 1.0)),
            Err(PointError::NotFinite)
        );
    }

    #[test]
    fn neighbours_ahead_come_first() {
        let b = Aabb3::new(DVec3::ZERO, DVec3::new(300.0, 300.0, 10.0));
        let g = CellGrid::cover(&b, 100.0).unwrap();
        let n = g.neighbours(4, DVec2::new(1.0, 0.0));
        assert_eq!(n.len(), 8);
        assert_eq!(n[0], 5, "straight ahead first");
        let mut front: Vec<_> = n[1..3].to_vec();
        front.sort();
        assert_eq!(front, vec![2, 8], "then the two front diagonals");
        assert_eq!(n[7], 3, "straight behind last");
        // A corner cell has 3 neighbours.
        assert_eq!(g.neighbours(0, DVec2::ZERO).len(), 3);
        assert_eq!(g.ahead(4, DVec2::new(0.1, 0.9), 1), Some(7));
        assert_eq!(g.ahead(4, DVec2::new(1.0, 0.0), 2), None);
    }

    #[test]
    fn rejects_bad_sizes() {
        let b = Aabb3::new(DVec3::ZERO, DVec3::new(10.0, 10.0, 10.0));
        assert!(matches!(
            CellGrid::cover(&b, 0.0),
            Err(GridError::BadSize(_))
        ));
        assert!(matches!(
            CellGrid::cover(&b, f64::NAN),
            Err(GridError::BadSize(_))
        ));
        assert!(matches!(
            CellGrid::cover(&b, 1e-9),
            Err(GridError::TooMany(..))
        ));
        assert_eq!(
            CellGrid::cover(&Aabb3::EMPTY, 1.0),
            Err(GridError::EmptyScene)
        );
    }
}
