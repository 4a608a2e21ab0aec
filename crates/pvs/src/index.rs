//! The spatial index of a `.pvs`: a uniform 2D grid over the cells' footprints, each
//! bucket listing the cells whose (closed) box meets it. A point query looks at one
//! bucket and tests the few cells listed there.
//!
//! The buckets are a [`UniformGrid`]: a point's bucket is `floor((p - origin) / step)`,
//! a monotone function of `p`, so a point inside a box always falls in one of the
//! buckets the box was inserted in, even with rounding. The cells themselves need not
//! form a grid: any boxes, overlapping or sparse, are indexed.

use sightline_geom::{DVec2, UniformGrid, ViewCell};
use sightline_runtime::wire::{Buckets, GridIndex};

/// At most this many buckets per cell (keeps the index small for odd cell layouts).
const MAX_BUCKETS_PER_CELL: usize = 4;

/// The index of `cells` (the GRID section): buckets of the median cell footprint, at
/// most [`MAX_BUCKETS_PER_CELL`] per cell, `nx * ny + 1` offsets into the items by
/// bucket id (row-major, `y * nx + x`), cell indices ascending within each bucket.
pub fn grid_index(cells: &[ViewCell]) -> GridIndex {
    let g = buckets(cells);
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
    let mut offsets = vec![0];
    let mut items = Vec::new();
    for b in lists {
        items.extend(b);
        offsets.push(items.len() as u32);
    }
    GridIndex {
        buckets: Buckets {
            origin: g.origin.to_array(),
            step: g.step.to_array(),
            nx: g.nx,
            ny: g.ny,
        },
        offsets,
        items,
    }
}

/// The buckets over the cells' footprints.
fn buckets(cells: &[ViewCell]) -> UniformGrid {
    if cells.is_empty() {
        return UniformGrid::square(DVec2::ZERO, 1.0, 1, 1);
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
    UniformGrid {
        origin: DVec2::new(x0, y0),
        step: DVec2::new(sx, sy),
        nx: ((x1 - x0) / sx).floor() as u32 + 1,
        ny: ((y1 - y0) / sy).floor() as u32 + 1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::format::{encode, Header};
    use crate::PvsFile;
    use sightline_geom::DVec3;

    fn cell(x0: f64, y0: f64, x1: f64, y1: f64) -> ViewCell {
        ViewCell::from_array([x0, y0, 1.5, x1, y1, 2.0]).unwrap()
    }

    /// The cells in a `.pvs`, located as every reader locates them.
    fn file(cells: &[ViewCell]) -> PvsFile {
        let n = cells.len();
        let header = Header::new(0, "all", vec![], 1, n);
        let present: Vec<u32> = (0..n as u32).collect();
        let bytes = encode(&header, cells, &present, &vec![vec![0]; n]).unwrap();
        PvsFile::from_bytes(bytes).unwrap()
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
        let f = file(&cells);
        for (k, c) in cells.iter().enumerate() {
            assert_eq!(f.locate(c.center()), Some(k));
            // The minimum corner is shared with lower-index neighbours except for cell 0.
            let lowest = (0..=k).find(|&m| cells[m].contains(c.min)).unwrap();
            assert_eq!(f.locate(c.min), Some(lowest));
        }
        assert_eq!(f.locate(DVec3::new(-1.0, 5.0, 1.7)), None);
        assert_eq!(f.locate(DVec3::new(5.0, 5.0, 3.0)), None);
        assert_eq!(f.locate(DVec3::new(f64::NAN, 5.0, 1.7)), None);
    }

    #[test]
    fn sparse_and_overlapping_cells() {
        let cells = vec![
            cell(0.0, 0.0, 1.0, 1.0),
            cell(1e6, 1e6, 1e6 + 1.0, 1e6 + 1.0),
            cell(0.5, 0.5, 3.0, 3.0),
        ];
        assert!(grid_index(&cells).offsets.len() <= 4 * 3 + 17);
        let f = file(&cells);
        assert_eq!(f.locate(DVec3::new(0.7, 0.7, 1.6)), Some(0));
        assert_eq!(f.locate(DVec3::new(2.0, 2.0, 1.6)), Some(2));
        assert_eq!(f.locate(DVec3::new(1e6 + 0.5, 1e6, 2.0)), Some(1));
    }
}
