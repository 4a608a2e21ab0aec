//! The SHAP section of a `.pvs` (format version 2): the shape of every cell that is not
//! a box (a convex polyhedron such as a BSP leaf, or a union of voxel boxes of an
//! automatic cell complex). The CELL section keeps every cell's bounding box and the
//! spatial index is built over those boxes, so point location first finds the cells
//! whose box holds the point, then keeps the first whose shape holds it. A file whose
//! cells are all boxes has no SHAP section and is written as version 1, byte for byte
//! as before.

use sightline_core::{Cell, CellKind};
use sightline_runtime::wire::{ShapeTable, KIND_BOX, KIND_CONVEX, KIND_VOXELS};

/// The table of `cells`, or `None` when every cell is a box.
pub(crate) fn shape_table(cells: &[Cell]) -> Option<ShapeTable> {
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
