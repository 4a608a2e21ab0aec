//! Reading a `.pvs`: [`PvsFile`] is the runtime's reader ([`sightline_runtime::Pvs`],
//! the code engines link: the same checks on untrusted bytes, the same cells and rows)
//! with the scene-side types of the pipeline (boxes as [`ViewCell`], shapes as
//! [`Cell`], sets as roaring bitmaps) and a pool of query scratches, so any number of
//! threads read at once and each decodes only the data blocks on its cell's delta chain.

use crate::error::PvsError;
use crate::format::Header;
use roaring::RoaringBitmap;
use sightline_core::{Cell, ConvexCell, HalfSpace, VoxelCell};
use sightline_geom::{DVec3, ViewCell};
use sightline_runtime::{CellKind, Pvs, Query};
use sightline_scene::Scene;
use std::path::Path;
use std::sync::Mutex;

/// An open `.pvs` file.
///
/// ```no_run
/// use sightline_pvs::PvsFile;
/// use sightline_geom::DVec3;
/// let file = PvsFile::open("city.pvs")?;
/// if let Some((cell, visible)) = file.query(DVec3::new(120.0, 40.0, 1.7))? {
///     println!("{cell:?}: {} objects", visible.len());
/// }
/// # Ok::<(), sightline_pvs::PvsError>(())
/// ```
pub struct PvsFile {
    pvs: Pvs,
    /// Every cell's box.
    cells: Vec<ViewCell>,
    /// The cells with their shapes, decoded once at open (`None`: every cell a box).
    shapes: Option<Vec<Cell>>,
    /// Query scratches (decoded blocks, buffers): one taken per read, given back after.
    queries: Mutex<Vec<Query>>,
}

impl std::fmt::Debug for PvsFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PvsFile")
            .field("header", self.pvs.header())
            .field("cells", &self.cells.len())
            .finish()
    }
}

impl PvsFile {
    /// Open a file: checks magic, version, section checksums and the tables; data blocks
    /// are checked when they are read.
    pub fn open(path: impl AsRef<Path>) -> Result<PvsFile, PvsError> {
        Self::of(Pvs::open(path)?)
    }

    /// Read a file held in memory.
    pub fn from_bytes(bytes: Vec<u8>) -> Result<PvsFile, PvsError> {
        Self::of(Pvs::from_vec(bytes)?)
    }

    fn of(pvs: Pvs) -> Result<PvsFile, PvsError> {
        let n = pvs.cell_count();
        let cells = (0..n)
            .map(|c| {
                let b = pvs.cell_box(c).unwrap_or_default();
                ViewCell::from_array(b).map_err(|e| PvsError::Corrupt(format!("cell {c}: {e}")))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let shaped = (0..n).any(|c| pvs.cell_kind(c) != Some(CellKind::Box));
        let shapes = shaped.then(|| {
            (0..n)
                .map(|c| shape(&pvs, c, cells[c as usize]))
                .collect::<Vec<Cell>>()
        });
        Ok(PvsFile {
            pvs,
            cells,
            shapes,
            queries: Mutex::new(Vec::new()),
        })
    }

    /// The runtime reader underneath (what an engine links).
    pub fn runtime(&self) -> &Pvs {
        &self.pvs
    }

    pub fn header(&self) -> &Header {
        self.pvs.header()
    }

    /// All cells of the build (a shard stores the sets of only some of them), as their
    /// bounding boxes ([`PvsFile::cell`] gives a cell's own shape).
    pub fn cells(&self) -> &[ViewCell] {
        &self.cells
    }

    /// Cell `i` with its shape (a box, a convex polyhedron, voxel boxes).
    pub fn cell(&self, i: usize) -> Option<Cell> {
        match &self.shapes {
            Some(s) => s.get(i).cloned(),
            None => self.cells.get(i).map(|b| Cell::Box(*b)),
        }
    }

    /// Every cell with its shape.
    pub fn shaped_cells(&self) -> Vec<Cell> {
        (0..self.cells.len()).filter_map(|i| self.cell(i)).collect()
    }

    /// Indices of the cells whose sets this file stores, ascending.
    pub fn stored(&self) -> Vec<u32> {
        self.pvs.stored_cells().collect()
    }

    /// Whether the file stores each cell's visible leaves (a BSP level's build).
    pub fn has_visible_leaves(&self) -> bool {
        self.pvs.has_visible_leaves()
    }

    /// The sorted visible leaves of stored cell `cell` (the numbers of the cells it
    /// sees in its source, e.g. BSP leaves); `None` when the file has none or does not
    /// store the cell.
    pub fn visible_leaves(&self, cell: usize) -> Option<&[u32]> {
        self.pvs.visible_leaves(u32::try_from(cell).ok()?)
    }

    /// Size of the set of a stored cell, without decoding it.
    pub fn set_len(&self, cell: usize) -> Option<u32> {
        self.pvs.row_len(u32::try_from(cell).ok()?)
    }

    /// Error unless this file was built for `scene`.
    pub fn check_scene(&self, scene: &Scene) -> Result<(), PvsError> {
        let f = scene.fingerprint();
        let h = self.header();
        if f != h.fingerprint || scene.objects.len() as u64 != h.object_count as u64 {
            return Err(PvsError::SceneMismatch {
                file: h.fingerprint,
                scene: f,
            });
        }
        Ok(())
    }

    /// Index of the cell containing `p` (closed cells; the lowest index on shared
    /// faces): the spatial index finds the cells whose box holds `p`, the shape decides.
    pub fn locate(&self, p: DVec3) -> Option<usize> {
        self.pvs.locate(p.to_array()).map(|c| c as usize)
    }

    /// The cell containing `p` and its sorted PVS; `None` if no cell contains `p`.
    pub fn query(&self, p: DVec3) -> Result<Option<(ViewCell, Vec<u32>)>, PvsError> {
        match self.locate(p) {
            None => Ok(None),
            Some(i) => Ok(Some((self.cells[i], self.pvs(i)?))),
        }
    }

    /// The sorted PVS of cell `cell` (an error if this shard does not store it).
    pub fn pvs(&self, cell: usize) -> Result<Vec<u32>, PvsError> {
        let mut out = Vec::new();
        let c = u32::try_from(cell)
            .map_err(|_| PvsError::Invalid(format!("cell {cell} is not stored in this file")))?;
        self.with_query(|pvs, q| pvs.visible_into(q, c, &mut out))?;
        Ok(out)
    }

    /// The PVS of cell `cell` as a roaring bitmap.
    pub fn bitmap(&self, cell: usize) -> Result<RoaringBitmap, PvsError> {
        let set = self.pvs(cell)?;
        RoaringBitmap::from_sorted_iter(set)
            .map_err(|_| PvsError::Corrupt(format!("cell {cell}: decoded set does not match")))
    }

    /// Run `f` with a query scratch of the pool (a new one when every one is in use).
    fn with_query<T>(
        &self,
        f: impl FnOnce(&Pvs, &mut Query) -> Result<T, sightline_runtime::RuntimeError>,
    ) -> Result<T, PvsError> {
        let taken = self.queries.lock().ok().and_then(|mut v| v.pop());
        let mut q = taken.unwrap_or_default();
        let r = f(&self.pvs, &mut q);
        if let Ok(mut v) = self.queries.lock() {
            v.push(q);
        }
        Ok(r?)
    }

    /// Every stored cell with its sorted PVS, in cell order.
    pub fn iter(&self) -> impl Iterator<Item = Result<(usize, ViewCell, Vec<u32>), PvsError>> + '_ {
        self.stored().into_iter().map(move |i| {
            self.pvs(i as usize)
                .map(|v| (i as usize, self.cells[i as usize], v))
        })
    }

    /// Check every checksum and decode every cell.
    pub fn verify(&self) -> Result<(), PvsError> {
        self.with_query(|pvs, q| pvs.verify(q))
    }

    /// Bytes of the data section (the compressed sets) and of the whole file.
    pub fn sizes(&self) -> (u64, u64) {
        let (offset, len) = self.pvs.data_section();
        (len, offset + len)
    }
}

/// Cell `c` of `pvs` with its shape; `bounds` is its box.
fn shape(pvs: &Pvs, c: u32, bounds: ViewCell) -> Cell {
    let id = pvs.cell_source_id(c).unwrap_or(0);
    if let Some(planes) = pvs.cell_planes(c) {
        let planes = planes
            .iter()
            .map(|p| HalfSpace {
                normal: DVec3::new(p[0], p[1], p[2]),
                offset: p[3],
            })
            .collect();
        return Cell::Convex(ConvexCell::new(id, bounds, planes));
    }
    if let Some(boxes) = pvs.cell_voxel_boxes(c) {
        let boxes = boxes
            .iter()
            .filter_map(|b| ViewCell::from_array(*b).ok())
            .collect();
        return VoxelCell::new(id, boxes).map_or(Cell::Box(bounds), Cell::Voxels);
    }
    Cell::Box(bounds)
}
