//! The SHAP section of a `.pvs` (format version 2): the shape of every cell that is not
//! a box (a convex polyhedron such as a BSP leaf, or a union of voxel boxes of an
//! automatic cell complex). The CELL section keeps every cell's bounding box and the
//! spatial index is built over those boxes, so point location first finds the cells
//! whose box holds the point, then keeps the first whose shape holds it. A file whose
//! cells are all boxes has no SHAP section and is written as version 1, byte for byte
//! as before.

use crate::error::PvsError;
use serde::{Deserialize, Serialize};
use sightline_core::{Cell, CellKind, ConvexCell, HalfSpace, VoxelCell};
use sightline_geom::{DVec3, ViewCell};

const KIND_BOX: u8 = 0;
const KIND_CONVEX: u8 = 1;
const KIND_VOXELS: u8 = 2;

/// Column form of the cells' shapes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct ShapeTable {
    /// Per cell: 0 box, 1 convex polyhedron, 2 voxel boxes.
    pub kinds: Vec<u8>,
    /// Per cell: its number in its source (a BSP leaf, an automatic cell); 0 for a box.
    pub ids: Vec<u32>,
    /// `cells + 1` offsets into `planes` (a convex cell's half-spaces).
    pub plane_offsets: Vec<u32>,
    /// `[nx, ny, nz, d]`: the half-space `n · p <= d`.
    pub planes: Vec<[f64; 4]>,
    /// `cells + 1` offsets into `boxes` (a voxel cell's boxes).
    pub box_offsets: Vec<u32>,
    pub boxes: Vec<[f64; 6]>,
}

impl ShapeTable {
    /// The table of `cells`, or `None` when every cell is a box.
    pub fn of(cells: &[Cell]) -> Option<ShapeTable> {
        if cells.iter().all(|c| c.kind() == CellKind::Box) {
            return None;
        }
        let mut t = ShapeTable {
            kinds: Vec::with_capacity(cells.len()),
            ids: Vec::with_capacity(cells.len()),
            plane_offsets: vec![0],
            planes: Vec::new(),
            box_offsets: vec![0],
            boxes: Vec::new(),
        };
        for c in cells {
            match c {
                Cell::Box(_) => t.kinds.push(KIND_BOX),
                Cell::Convex(c) => {
                    t.kinds.push(KIND_CONVEX);
                    t.planes.extend(
                        c.planes
                            .iter()
                            .map(|h| [h.normal.x, h.normal.y, h.normal.z, h.offset]),
                    );
                }
                Cell::Voxels(c) => {
                    t.kinds.push(KIND_VOXELS);
                    t.boxes.extend(c.boxes.iter().map(|b| b.to_array()));
                }
            }
            t.ids.push(c.id().unwrap_or(0));
            t.plane_offsets.push(t.planes.len() as u32);
            t.box_offsets.push(t.boxes.len() as u32);
        }
        Some(t)
    }

    /// Check a decoded table against the cell count (untrusted input).
    pub fn validate(&self, cell_count: usize) -> Result<(), PvsError> {
        let bad = |m: &str| Err(PvsError::Corrupt(format!("cell shapes: {m}")));
        if self.kinds.len() != cell_count
            || self.ids.len() != cell_count
            || self.plane_offsets.len() != cell_count + 1
            || self.box_offsets.len() != cell_count + 1
        {
            return bad("table sizes do not match the cell count");
        }
        let monotone = |o: &[u32], n: usize| {
            o[0] == 0 && o.windows(2).all(|w| w[0] <= w[1]) && o[o.len() - 1] as usize == n
        };
        if !monotone(&self.plane_offsets, self.planes.len())
            || !monotone(&self.box_offsets, self.boxes.len())
        {
            return bad("offsets are not monotone");
        }
        if self.kinds.iter().any(|&k| k > KIND_VOXELS) {
            return bad("unknown cell kind");
        }
        if self.planes.iter().flatten().any(|v| !v.is_finite()) {
            return bad("a plane is not finite");
        }
        for (i, &k) in self.kinds.iter().enumerate() {
            let nb = self.box_offsets[i + 1] - self.box_offsets[i];
            if k == KIND_VOXELS && nb == 0 {
                return bad("a voxel cell without boxes");
            }
        }
        if self.boxes.iter().any(|b| ViewCell::from_array(*b).is_err()) {
            return bad("a voxel box is not a valid box");
        }
        Ok(())
    }

    /// Cell `i` with its shape; `bounds` is its box from the CELL section.
    pub fn cell(&self, i: usize, bounds: ViewCell) -> Cell {
        let planes = || {
            self.planes[self.plane_offsets[i] as usize..self.plane_offsets[i + 1] as usize]
                .iter()
                .map(|p| HalfSpace {
                    normal: DVec3::new(p[0], p[1], p[2]),
                    offset: p[3],
                })
                .collect()
        };
        match self.kinds[i] {
            KIND_CONVEX => Cell::Convex(ConvexCell::new(self.ids[i], bounds, planes())),
            KIND_VOXELS => {
                let boxes = self.boxes
                    [self.box_offsets[i] as usize..self.box_offsets[i + 1] as usize]
                    .iter()
                    .filter_map(|b| ViewCell::from_array(*b).ok())
                    .collect();
                VoxelCell::new(self.ids[i], boxes).map_or(Cell::Box(bounds), Cell::Voxels)
            }
            _ => Cell::Box(bounds),
        }
    }
}
