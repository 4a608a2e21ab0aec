//! Viewcells of every kind: a box (cities, `--cell`), a convex polyhedron (a BSP leaf) or
//! a cell of an automatic cell complex (a union of voxel boxes). Each has a bounding box
//! (which every method can answer for, conservatively), a point-in-cell test (point
//! location, `query --at`) and a way for the ground truth to sample viewpoints inside it.
//!
//! ```
//! use sightline_core::{Cell, ConvexCell, HalfSpace};
//! use sightline_geom::{DVec3, ViewCell};
//! // The half of the unit cube below the plane x + y = 1.
//! let bounds: ViewCell = "0,0,0,1,1,1".parse().unwrap();
//! let wedge = Cell::Convex(ConvexCell::new(3, bounds, vec![
//!     HalfSpace { normal: DVec3::new(1.0, 1.0, 0.0), offset: 1.0 },
//! ]));
//! assert!(wedge.contains(DVec3::new(0.2, 0.2, 0.5)));
//! assert!(!wedge.contains(DVec3::new(0.9, 0.9, 0.5)));
//! assert_eq!(wedge.id(), Some(3));
//! assert!(wedge.sample(64, 7).iter().all(|p| wedge.contains(*p)));
//! ```

use serde::{Deserialize, Serialize};
use sightline_geom::{DVec3, ViewCell};
use sightline_stats::Rng;

/// The half-space `normal · p <= offset`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HalfSpace {
    pub normal: DVec3,
    pub offset: f64,
}

impl HalfSpace {
    /// Whether `p` is inside, allowing `slack` (in units of `normal`'s length).
    pub fn contains(&self, p: DVec3, slack: f64) -> bool {
        self.normal.dot(p) <= self.offset + slack
    }
}

/// A convex polyhedron: the intersection of its half-spaces and its bounding box.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ConvexCell {
    /// The cell's number in its source (a BSP leaf number).
    pub id: u32,
    pub bounds: ViewCell,
    pub planes: Vec<HalfSpace>,
}

impl ConvexCell {
    pub fn new(id: u32, bounds: ViewCell, planes: Vec<HalfSpace>) -> Self {
        ConvexCell { id, bounds, planes }
    }
}

/// A cell of an automatic cell complex: a union of boxes (voxel runs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct VoxelCell {
    /// The cell's number in its complex.
    pub id: u32,
    pub bounds: ViewCell,
    pub boxes: Vec<ViewCell>,
}

impl VoxelCell {
    /// The cell made of `boxes` (at least one).
    pub fn new(id: u32, boxes: Vec<ViewCell>) -> Option<Self> {
        let first = *boxes.first()?;
        let bounds = boxes.iter().fold(first, |acc, b| ViewCell {
            min: acc.min.min(b.min),
            max: acc.max.max(b.max),
        });
        Some(VoxelCell { id, bounds, boxes })
    }
}

/// Which kind a viewcell is (stored in `.pvs` files).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CellKind {
    Box,
    Convex,
    Voxels,
}

/// A viewcell: a region a viewer can stand in.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Cell {
    Box(ViewCell),
    Convex(ConvexCell),
    Voxels(VoxelCell),
}

impl From<ViewCell> for Cell {
    fn from(b: ViewCell) -> Self {
        Cell::Box(b)
    }
}

/// Relative slack of the point-in-cell test: a point on a shared face belongs to both
/// cells (point location then picks one; the truth samples from both).
const SLACK: f64 = 1e-9;

impl Cell {
    pub fn kind(&self) -> CellKind {
        match self {
            Cell::Box(_) => CellKind::Box,
            Cell::Convex(_) => CellKind::Convex,
            Cell::Voxels(_) => CellKind::Voxels,
        }
    }

    /// The cell's number in its source (BSP leaf, automatic cell); none for a box.
    pub fn id(&self) -> Option<u32> {
        match self {
            Cell::Box(_) => None,
            Cell::Convex(c) => Some(c.id),
            Cell::Voxels(c) => Some(c.id),
        }
    }

    /// The axis-aligned box around the cell.
    pub fn bounds(&self) -> ViewCell {
        match self {
            Cell::Box(b) => *b,
            Cell::Convex(c) => c.bounds,
            Cell::Voxels(c) => c.bounds,
        }
    }

    /// Whether `p` lies in the cell (closed: its boundary included).
    pub fn contains(&self, p: DVec3) -> bool {
        let in_box = |b: &ViewCell| {
            let s = (b.max - b.min).max_element().max(1.0) * SLACK;
            p.cmpge(b.min - s).all() && p.cmple(b.max + s).all()
        };
        match self {
            Cell::Box(b) => in_box(b),
            Cell::Convex(c) => {
                let scale = (c.bounds.max - c.bounds.min).max_element().max(1.0);
                in_box(&c.bounds)
                    && c.planes
                        .iter()
                        .all(|h| h.contains(p, h.normal.length() * scale * SLACK))
            }
            Cell::Voxels(c) => in_box(&c.bounds) && c.boxes.iter().any(in_box),
        }
    }

    /// About `n` viewpoints inside the cell, deterministic for `seed`: uniform points of
    /// the bounding box kept when inside (a box keeps them all). May return fewer than
    /// `n` for a sliver of its box; never a point outside the cell.
    pub fn sample(&self, n: usize, seed: u64) -> Vec<DVec3> {
        let b = self.bounds();
        let mut rng = Rng::new(seed);
        let mut out = Vec::with_capacity(n);
        let mut tries = 0;
        while out.len() < n && tries < n.saturating_mul(64).max(64) {
            tries += 1;
            let p = match self {
                Cell::Voxels(c) => {
                    // A box chosen by volume, then a point in it: no rejection.
                    let vol =
                        |v: &ViewCell| (v.max - v.min).max(DVec3::splat(1e-12)).element_product();
                    let total: f64 = c.boxes.iter().map(vol).sum();
                    let mut r = rng.f64() * total;
                    let mut pick = &c.boxes[0];
                    for v in &c.boxes {
                        pick = v;
                        r -= vol(v);
                        if r <= 0.0 {
                            break;
                        }
                    }
                    pick.min + (pick.max - pick.min) * DVec3::new(rng.f64(), rng.f64(), rng.f64())
                }
                _ => b.min + (b.max - b.min) * DVec3::new(rng.f64(), rng.f64(), rng.f64()),
            };
            if self.contains(p) {
                out.push(p);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn bx(a: [f64; 6]) -> ViewCell {
        ViewCell::from_array(a).unwrap()
    }

    #[test]
    fn voxel_cells_contain_their_boxes_only() {
        let c = Cell::Voxels(
            VoxelCell::new(
                5,
                vec![
                    bx([0.0, 0.0, 0.0, 1.0, 1.0, 1.0]),
                    bx([1.0, 0.0, 0.0, 2.0, 1.0, 3.0]),
                ],
            )
            .unwrap(),
        );
        assert_eq!(c.bounds().to_array(), [0.0, 0.0, 0.0, 2.0, 1.0, 3.0]);
        assert!(c.contains(DVec3::new(1.5, 0.5, 2.5)));
        assert!(!c.contains(DVec3::new(0.5, 0.5, 2.5)));
        let pts = c.sample(200, 1);
        assert_eq!(pts.len(), 200);
        assert!(pts.iter().all(|p| c.contains(*p)));
        assert!(VoxelCell::new(0, vec![]).is_none());
    }

    proptest! {
        // Samples of a random convex cell (a box cut by random planes through its
        // centre's neighbourhood) all lie in the cell, far from the origin too.
        #[test]
        fn samples_lie_inside(
            off in -1e5f64..1e5,
            n in proptest::collection::vec((-1f64..1.0, -1f64..1.0, -1f64..1.0, 0.0f64..0.5), 0..6),
        ) {
            let b = bx([off, off, 0.0, off + 10.0, off + 10.0, 10.0]);
            let c = b.center();
            let planes = n.into_iter()
                .map(|(x, y, z, d)| {
                    let normal = DVec3::new(x, y, z);
                    HalfSpace { normal, offset: normal.dot(c) + d * 10.0 * normal.length() }
                })
                .collect();
            let cell = Cell::Convex(ConvexCell::new(1, b, planes));
            prop_assert!(cell.contains(c));
            for p in cell.sample(50, 9) {
                prop_assert!(cell.contains(p));
            }
        }
    }
}
