//! The spatial index of a `.pvs`: a uniform 2D grid over the cells' footprints, each
//! bucket listing the cells whose (closed) box meets it. A point query looks at one
//! bucket and tests the few cells listed there.
//!
//! The buckets are a [`UniformGrid`]: a point's bucket is `floor((p - origin) / step)`,
//! a monotone function of `p`, so a point inside a box always falls in one of the
//! buckets the box was inserted in, even with rounding. The cells themselves need not
//! form a grid: any boxes, overlapping or sparse, are indexed.

use crate::error::PvsError;
use serde::{Deserialize, Serialize};
use sightline_geom::{DVec2, DVec3, UniformGrid, ViewCell};

/// At most this many buckets per cell (keeps the index small for odd cell layouts).
const MAX_BUCKETS_PER_CELL: usize = 4;

/// A uniform grid of buckets in compressed-row form.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Grid {
    /// The buckets over the cells' footprints.
    pub buckets: UniformGrid,
    /// `nx * ny + 1` offsets into `items`, by bucket id (row-major, `y * nx + x`).
    pub offsets: Vec<u32>,
    /// Cell indices, ascending within each bucket.
    pub items: Vec<u32>,
}

impl Grid {
    /// Index `cells`; the bucket size is the median cell footprint.
    pub fn build(cells: &[ViewCell]) -> Grid {
        if cells.is_empty() {
            return Grid {
                buckets: UniformGrid::square(DVec2::ZERO, 1.0, 1, 1),
                offsets: vec![0, 0],
                items: vec![],
            };
        }
        let (mut x0, mut y0, mut x1, mut y1) = (f64::MAX, f64::MAX, f64::MIN, f64::MIN);
        for c in cells {
            x0 = x0.min(c.min.x);
            y0 = y0.min(c.min.y);
            x1 = x1.max(c.max.x);
            y1 = y1.max(c.max.y);
        }
        let median = |f: &dyn Fn(&ViewCell) -> f64| {
            let mut v: Vec<f64> = cells.iter().map(f).collect();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let mut sx = median(&|c| c.max.x - c.min.x).max((x1 - x0) / 65536.0);
        let mut sy = median(&|c| c.max.y - c.min.y).max((y1 - y0) / 65536.0);
        let limit = (cells.len() * MAX_BUCKETS_PER_CELL).max(16) as f64;
        while ((x1 - x0) / sx + 1.0) * ((y1 - y0) / sy + 1.0) > limit {
            sx *= 2.0;
            sy *= 2.0;
        }
        let nx = ((x1 - x0) / sx).floor() as u32 + 1;
        let ny = ((y1 - y0) / sy).floor() as u32 + 1;
        let mut grid = Grid {
            buckets: UniformGrid {
                origin: DVec2::new(x0, y0),
                step: DVec2::new(sx, sy),
                nx,
                ny,
            },
            offsets: vec![],
            items: vec![],
        };
        let g = grid.buckets;
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); g.len()];
        for (i, c) in cells.iter().enumerate() {
            let (bx0, by0) = g.cell_of(c.min.truncate());
            let (bx1, by1) = g.cell_of(c.max.truncate());
            for by in by0..=by1 {
                for bx in bx0..=bx1 {
                    lists[g.id(bx, by) as usize].push(i as u32);
                }
            }
        }
        grid.offsets.push(0);
        for b in lists {
            grid.items.extend(b);
            grid.offsets.push(grid.items.len() as u32);
        }
        grid
    }

    /// The lowest-index cell whose closed box contains `p`.
    pub fn locate(&self, cells: &[ViewCell], p: DVec3) -> Option<usize> {
        self.locate_where(cells, p, |_| true)
    }

    /// The lowest-index cell whose closed box contains `p` and for which `keep` holds
    /// (a cell's shape inside its box).
    pub fn locate_where(
        &self,
        cells: &[ViewCell],
        p: DVec3,
        keep: impl Fn(usize) -> bool,
    ) -> Option<usize> {
        if !(p.x.is_finite() && p.y.is_finite() && p.z.is_finite()) {
            return None;
        }
        let (bx, by) = self.buckets.cell_of(p.truncate());
        let b = self.buckets.id(bx, by) as usize;
        let (s, e) = (self.offsets[b] as usize, self.offsets[b + 1] as usize);
        self.items[s..e]
            .iter()
            .map(|&i| i as usize)
            .find(|&i| cells[i].contains(p) && keep(i))
    }

    /// Check a decoded grid against the cell count (untrusted input).
    pub fn validate(&self, cell_count: usize) -> Result<(), PvsError> {
        let bad = |m: &str| Err(PvsError::Corrupt(format!("spatial index: {m}")));
        let g = &self.buckets;
        let all_finite = g.origin.is_finite() && g.step.is_finite();
        if !all_finite || g.step.x <= 0.0 || g.step.y <= 0.0 {
            return bad("bad origin or step");
        }
        let n = (g.nx as u64) * (g.ny as u64);
        if g.nx == 0 || g.ny == 0 || self.offsets.len() as u64 != n + 1 {
            return bad("bucket count does not match the grid size");
        }
        if self.offsets[0] != 0
            || self.offsets.windows(2).any(|w| w[0] > w[1])
            || *self.offsets.last().unwrap_or(&0) as usize != self.items.len()
        {
            return bad("bucket offsets are not monotone");
        }
        if self.items.iter().any(|&i| i as usize >= cell_count) {
            return bad("bucket refers to a cell that does not exist");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cell(x0: f64, y0: f64, x1: f64, y1: f64) -> ViewCell {
        ViewCell::from_array([x0, y0, 1.5, x1, y1, 2.0]).unwrap()
    }

    #[test]
    fn locates_points_on_shared_faces_in_the_lowest_cell() {
        let cells: Vec<ViewCell> = (0..10)
            .flat_map(|j| (0..10).map(move |i| (i, j)))
            .map(|(i, j)| {
                cell(
                    i as f64 * 7.3,
                    j as f64 * 7.3,
                    (i + 1) as f64 * 7.3,
                    (j + 1) as f64 * 7.3,
                )
            })
            .collect();
        let g = Grid::build(&cells);
        g.validate(cells.len()).unwrap();
        for (k, c) in cells.iter().enumerate() {
            assert_eq!(g.locate(&cells, c.center()), Some(k));
            // The minimum corner is shared with lower-index neighbours except for cell 0.
            let lowest = (0..=k).find(|&m| cells[m].contains(c.min)).unwrap();
            assert_eq!(g.locate(&cells, c.min), Some(lowest));
        }
        assert_eq!(g.locate(&cells, DVec3::new(-1.0, 5.0, 1.7)), None);
        assert_eq!(g.locate(&cells, DVec3::new(5.0, 5.0, 3.0)), None);
        assert_eq!(g.locate(&cells, DVec3::new(f64::NAN, 5.0, 1.7)), None);
    }

    #[test]
    fn sparse_and_overlapping_cells() {
        let cells = vec![
            cell(0.0, 0.0, 1.0, 1.0),
            cell(1e6, 1e6, 1e6 + 1.0, 1e6 + 1.0),
            cell(0.5, 0.5, 3.0, 3.0),
        ];
        let g = Grid::build(&cells);
        assert!(g.offsets.len() <= 4 * 3 + 17);
        assert_eq!(g.locate(&cells, DVec3::new(0.7, 0.7, 1.6)), Some(0));
        assert_eq!(g.locate(&cells, DVec3::new(2.0, 2.0, 1.6)), Some(2));
        assert_eq!(g.locate(&cells, DVec3::new(1e6 + 0.5, 1e6, 2.0)), Some(1));
    }
}
