//! The cell layout a source answers for: a regular [`CellGrid`] (a city), or a free set
//! of cells given by their bounding boxes ([`CellSet`]: the leaves of a BSP level, the
//! automatic cells of a mesh level — whatever cells a `.pvs` file stores).
//!
//! Sessions only need four things of a layout: the box of a cell (sent with its PVS and
//! drawn by the viewer), the cells to prefetch around a cell, those ahead along the
//! motion first (dual ray space paper, Fig. 5), the cell the motion leads into next, and
//! a length scale to tell walking from driving. On a grid these are the grid's own
//! arithmetic, unchanged. On a cell set:
//!
//! * **neighbours** are the cells whose bounding boxes touch or overlap the cell's box
//!   (within a relative tolerance). Two cells that share a face, a portal or a corner
//!   have touching boxes, so every cell a walker can step into next is among them: the
//!   list is a superset of the true adjacency, which is what prefetch needs (a BSP's
//!   portal graph would be tighter, but the server does not know about portals);
//! * the **next cell** along a heading is found by leaving the cell's box along the
//!   heading and locating the point just beyond it (see
//!   [`crate::source::PvsSource::next_cell`]): a hint for the prefetch order only;
//! * the **length scale** is the median of the cells' larger horizontal side.

use crate::grid::{CellGrid, CellId, PointError};
use sightline_geom::{DVec2, DVec3, ViewCell};

/// A source's cells, borrowed.
#[derive(Clone, Copy, Debug)]
pub enum Layout<'a> {
    /// The regular grid of a city (see [`crate::grid`]).
    Grid(&'a CellGrid),
    /// Free cells known by their bounding boxes.
    Cells(&'a CellSet),
}

impl Layout<'_> {
    /// Number of cells (ids are `0..len`).
    pub fn len(&self) -> usize {
        match self {
            Layout::Grid(g) => g.len(),
            Layout::Cells(c) => c.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// `"grid"` or `"cells"` (the `layout` field of `/api/scene`).
    pub fn kind(&self) -> &'static str {
        match self {
            Layout::Grid(_) => "grid",
            Layout::Cells(_) => "cells",
        }
    }

    /// The grid, for a grid layout.
    pub fn grid(&self) -> Option<&CellGrid> {
        match self {
            Layout::Grid(g) => Some(g),
            Layout::Cells(_) => None,
        }
    }

    /// The bounding box of a cell (a grid cell is its box).
    pub fn cell(&self, id: CellId) -> Option<ViewCell> {
        match self {
            Layout::Grid(g) => g.cell(id),
            Layout::Cells(c) => c.bounds(id),
        }
    }

    /// Adjacent cells, those ahead along `heading` first.
    pub fn neighbours(&self, id: CellId, heading: DVec2) -> Vec<CellId> {
        match self {
            Layout::Grid(g) => g.neighbours(id, heading),
            Layout::Cells(c) => c.neighbours(id, heading),
        }
    }

    /// A typical cell width: speeds are measured against it.
    pub fn scale_m(&self) -> f64 {
        match self {
            Layout::Grid(g) => g.cell_size_m,
            Layout::Cells(c) => c.scale_m,
        }
    }

    /// The point coordinates sent to clients are relative to (see [`crate::geometry`]):
    /// a grid's south-west corner at z = 0, or the cells' minimum x, y at z = 0.
    pub fn origin(&self) -> DVec3 {
        match self {
            Layout::Grid(g) => DVec3::new(g.origin[0], g.origin[1], 0.0),
            Layout::Cells(c) => DVec3::new(c.extent.min.x.floor(), c.extent.min.y.floor(), 0.0),
        }
    }
}

/// Cells given by their bounding boxes, with the adjacency of those boxes.
#[derive(Clone, Debug)]
pub struct CellSet {
    boxes: Vec<ViewCell>,
    adjacent: Vec<Vec<CellId>>,
    /// Median of the cells' larger horizontal side.
    pub scale_m: f64,
    /// Box of all cells.
    pub extent: ViewCell,
}

/// Why a cell set cannot be made.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum CellSetError {
    #[error("no cells")]
    Empty,
    #[error("{0} cells (at most {max})", max = crate::grid::MAX_CELLS)]
    TooMany(usize),
}

impl CellSet {
    /// The cells `boxes` (cell `i` has id `i`); boxes that touch or overlap within
    /// `1e-6` of the cells' extent are adjacent.
    pub fn new(boxes: Vec<ViewCell>) -> Result<Self, CellSetError> {
        let first = *boxes.first().ok_or(CellSetError::Empty)?;
        if boxes.len() as u64 > crate::grid::MAX_CELLS {
            return Err(CellSetError::TooMany(boxes.len()));
        }
        let extent = boxes.iter().fold(first, |a, b| ViewCell {
            min: a.min.min(b.min),
            max: a.max.max(b.max),
        });
        let tol = 1e-6 * extent.size().max_element().max(1.0);
        // Sweep along x: boxes sorted by their low x; each box meets only the boxes that
        // start before its high x.
        let mut order: Vec<usize> = (0..boxes.len()).collect();
        order.sort_by(|&a, &b| boxes[a].min.x.total_cmp(&boxes[b].min.x).then(a.cmp(&b)));
        let mut adjacent = vec![Vec::new(); boxes.len()];
        for (k, &i) in order.iter().enumerate() {
            let a = &boxes[i];
            for &j in &order[k + 1..] {
                let b = &boxes[j];
                if b.min.x > a.max.x + tol {
                    break;
                }
                let meet = (1..3).all(|d| b.min[d] <= a.max[d] + tol && a.min[d] <= b.max[d] + tol);
                if meet {
                    adjacent[i].push(j as CellId);
                    adjacent[j].push(i as CellId);
                }
            }
        }
        for a in &mut adjacent {
            a.sort_unstable();
        }
        let mut sides: Vec<f64> = boxes
            .iter()
            .map(|b| (b.max.x - b.min.x).max(b.max.y - b.min.y))
            .collect();
        sides.sort_by(f64::total_cmp);
        let scale_m = sides[sides.len() / 2].max(tol);
        Ok(CellSet {
            boxes,
            adjacent,
            scale_m,
            extent,
        })
    }

    pub fn len(&self) -> usize {
        self.boxes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.boxes.is_empty()
    }

    /// The bounding box of cell `id`.
    pub fn bounds(&self, id: CellId) -> Option<ViewCell> {
        self.boxes.get(id as usize).copied()
    }

    /// Every cell's bounding box.
    pub fn boxes(&self) -> &[ViewCell] {
        &self.boxes
    }

    /// The cells whose boxes touch or overlap `id`'s, those whose centre lies ahead
    /// along `heading` first (a zero heading keeps ascending ids).
    pub fn neighbours(&self, id: CellId, heading: DVec2) -> Vec<CellId> {
        let (Some(adj), Some(c)) = (self.adjacent.get(id as usize), self.bounds(id)) else {
            return vec![];
        };
        let h = heading.normalize_or_zero();
        let here = c.center().truncate();
        let mut out: Vec<(f64, CellId)> = adj
            .iter()
            .map(|&n| {
                let d = self.boxes[n as usize].center().truncate() - here;
                (d.normalize_or_zero().dot(h), n)
            })
            .collect();
        // Stable: equal scores keep ascending ids.
        out.sort_by(|a, b| b.0.total_cmp(&a.0));
        out.into_iter().map(|(_, n)| n).collect()
    }

    /// The point just beyond the box of cell `id` along `heading` from `p` (at `p`'s
    /// height): where the next cell along the motion is looked for. `None` when standing
    /// still or for an unknown cell.
    pub fn exit_point(&self, id: CellId, p: DVec3, heading: DVec2) -> Option<DVec3> {
        let b = self.bounds(id)?;
        let h = heading.normalize_or_zero();
        if h == DVec2::ZERO || !p.is_finite() {
            return None;
        }
        let t = crate::grid::exit_distance;
        let exit = t(p.x, b.min.x, b.max.x, h.x)
            .min(t(p.y, b.min.y, b.max.y, h.y))
            .max(0.0);
        let step = exit + 1e-3 * self.scale_m;
        Some(DVec3::new(p.x + h.x * step, p.y + h.y * step, p.z))
    }

    /// The first cell (lowest id) whose box holds `p`: point location when the cells are
    /// their boxes.
    pub fn locate_box(&self, p: DVec3) -> Result<CellId, PointError> {
        if !p.is_finite() {
            return Err(PointError::NotFinite);
        }
        self.boxes
            .iter()
            .position(|b| b.contains(p))
            .map(|i| i as CellId)
            .ok_or(PointError::NoCell(p.x, p.y, p.z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b(a: [f64; 6]) -> ViewCell {
        ViewCell::from_array(a).unwrap()
    }

    /// Three boxes in a row along x (0, 1, 2), one above box 1 (3), one far away (4).
    fn set() -> CellSet {
        CellSet::new(vec![
            b([0.0, 0.0, 0.0, 10.0, 10.0, 5.0]),
            b([10.0, 0.0, 0.0, 20.0, 10.0, 5.0]),
            b([20.0, 0.0, 0.0, 30.0, 10.0, 5.0]),
            b([10.0, 0.0, 5.0, 20.0, 10.0, 9.0]),
            b([100.0, 100.0, 0.0, 110.0, 110.0, 5.0]),
        ])
        .unwrap()
    }

    #[test]
    fn boxes_that_touch_are_neighbours() {
        let s = set();
        let mut n1 = s.neighbours(1, DVec2::ZERO);
        n1.sort();
        assert_eq!(n1, vec![0, 2, 3]);
        // 0 and 3 touch along an edge (x = 10, z = 5).
        assert_eq!(s.neighbours(0, DVec2::ZERO), vec![1, 3]);
        assert!(s.neighbours(4, DVec2::ZERO).is_empty());
        assert!(s.neighbours(9, DVec2::ZERO).is_empty());
        assert_eq!(s.scale_m, 10.0);
    }

    #[test]
    fn neighbours_ahead_come_first() {
        let s = set();
        let east = s.neighbours(1, DVec2::new(1.0, 0.0));
        assert_eq!(east[0], 2);
        assert_eq!(*east.last().unwrap(), 0, "behind last");
        let west = s.neighbours(1, DVec2::new(-1.0, 0.0));
        assert_eq!(west[0], 0);
    }

    #[test]
    fn exit_points_leave_the_box_along_the_heading() {
        let s = set();
        let p = DVec3::new(15.0, 5.0, 2.0);
        let q = s.exit_point(1, p, DVec2::new(1.0, 0.0)).unwrap();
        assert!(q.x > 20.0 && q.x < 20.1 && q.y == 5.0 && q.z == 2.0, "{q}");
        assert_eq!(s.locate_box(q), Ok(2));
        assert_eq!(s.exit_point(1, p, DVec2::ZERO), None);
        assert_eq!(
            s.locate_box(DVec3::new(50.0, 5.0, 1.0)),
            Err(PointError::NoCell(50.0, 5.0, 1.0))
        );
        assert_eq!(
            s.locate_box(DVec3::new(f64::NAN, 5.0, 1.0)),
            Err(PointError::NotFinite)
        );
    }

    #[test]
    fn an_empty_set_is_refused() {
        assert_eq!(CellSet::new(vec![]).err(), Some(CellSetError::Empty));
    }
}
