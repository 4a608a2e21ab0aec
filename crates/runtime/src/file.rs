//! An open `.pvs`: the tables decoded and checked once, the data section kept as bytes
//! (owned, or a memory map with the `mmap` feature), and point location, rows, leaves,
//! neighbours and the source mapping answered without allocating.

use crate::bitmap::{decode_into, decode_with, symmetric_difference};
use crate::error::{corrupt, RuntimeError};
use crate::query::Query;
use crate::wire::{
    from_postcard, parse_preamble, section_payload, slice_at, CellTable, GridIndex, Header,
    LeafTable, Section, ShapeTable, CHAIN_LIMIT, KIND_CONVEX, KIND_VOXELS, TAG_CELL, TAG_DATA,
    TAG_GRID, TAG_HEAD, TAG_LEAF, TAG_SHAP,
};
use std::path::Path;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::OnceLock;

/// Relative slack of the point-in-shape test (`sightline_core::Cell::contains`): a point
/// on a shared face belongs to both cells, and location picks the lower index.
const SLACK: f64 = 1e-9;

/// Gives every open file its own number, so a [`Query`] knows whose blocks it caches.
static NEXT_FILE_ID: AtomicU64 = AtomicU64::new(1);

/// The kind of a cell, as the SHAP section stores it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CellKind {
    /// An axis-aligned box (cities, `--cell`).
    Box,
    /// A convex polyhedron: its planes cut its box (a BSP leaf).
    Convex,
    /// A union of voxel boxes (an automatic cell of a mesh level).
    Voxels,
}

pub(crate) enum Bytes {
    Owned(Vec<u8>),
    #[cfg(feature = "mmap")]
    Mapped(memmap2::Mmap),
}

impl std::ops::Deref for Bytes {
    type Target = [u8];
    fn deref(&self) -> &[u8] {
        match self {
            Bytes::Owned(v) => v,
            #[cfg(feature = "mmap")]
            Bytes::Mapped(m) => m,
        }
    }
}

/// An open `.pvs`, read-only and shareable between threads (each thread queries with
/// its own [`Query`]).
///
/// ```no_run
/// use sightline_runtime::{Pvs, Query};
/// let pvs = Pvs::open("city.pvs")?;
/// let mut q = Query::new();
/// if let Some(cell) = pvs.locate([120.0, 40.0, 1.7]) {
///     let visible: &[u32] = pvs.visible(&mut q, cell)?;
///     println!("cell {cell}: {} objects", visible.len());
/// }
/// # Ok::<(), sightline_runtime::RuntimeError>(())
/// ```
pub struct Pvs {
    pub(crate) id: u64,
    header: Header,
    boxes: Vec<[f64; 6]>,
    table: CellTable,
    /// Per cell: its rank among the stored cells, `u32::MAX` when not stored.
    rank: Vec<u32>,
    grid: GridIndex,
    shapes: Option<ShapeTable>,
    /// Per cell of a SHAP file: the box a voxel cell's boxes span (its shape's bounds).
    voxel_bounds: Vec<[f64; 6]>,
    /// LEAF section: `stored + 1` offsets into `leaves`.
    leaf_offsets: Option<Vec<u32>>,
    leaves: Vec<u32>,
    sources: Option<Vec<u32>>,
    source_names: Option<Vec<String>>,
    data: Section,
    bytes: Bytes,
    pub(crate) gameplay: OnceLock<Result<crate::gameplay::Index, String>>,
    /// `(source id, cell)` sorted, for files with a LEAF section.
    pub(crate) by_source_id: Vec<(u32, u32)>,
}

impl std::fmt::Debug for Pvs {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Pvs")
            .field("header", &self.header)
            .field("cells", &self.boxes.len())
            .finish()
    }
}

impl Pvs {
    /// Open a file: read into memory, or memory-mapped with the `mmap` feature.
    pub fn open(path: impl AsRef<Path>) -> Result<Pvs, RuntimeError> {
        let path = path.as_ref();
        let io = |e| RuntimeError::Io {
            path: path.display().to_string(),
            source: e,
        };
        #[cfg(feature = "mmap")]
        {
            let file = std::fs::File::open(path).map_err(io)?;
            // SAFETY: the map is read-only and every read is bounds-checked against its
            // length; the caller must not truncate the file while it is open (a mapped
            // page past the end of a shrunk file faults, as with any memory map).
            let map = unsafe { memmap2::Mmap::map(&file) }.map_err(io)?;
            Self::from_storage(Bytes::Mapped(map))
        }
        #[cfg(not(feature = "mmap"))]
        {
            let bytes = std::fs::read(path).map_err(io)?;
            Self::from_storage(Bytes::Owned(bytes))
        }
    }

    /// Read a file held in memory (copied).
    pub fn from_bytes(bytes: &[u8]) -> Result<Pvs, RuntimeError> {
        Self::from_storage(Bytes::Owned(bytes.to_vec()))
    }

    /// Read a file held in memory.
    pub fn from_vec(bytes: Vec<u8>) -> Result<Pvs, RuntimeError> {
        Self::from_storage(Bytes::Owned(bytes))
    }

    /// Every check of a file from untrusted bytes: preamble, sections, tables, index.
    fn from_storage(bytes: Bytes) -> Result<Pvs, RuntimeError> {
        let sections = parse_preamble(&bytes)?;
        let file_len = bytes.len() as u64;
        let find = |tag: [u8; 4]| {
            sections
                .iter()
                .find(|s| s.tag == tag)
                .copied()
                .ok_or_else(|| {
                    RuntimeError::Corrupt(format!(
                        "missing section {}",
                        String::from_utf8_lossy(&tag)
                    ))
                })
        };
        let end = sections.iter().map(|s| s.offset + s.len).max().unwrap_or(0);
        if end != file_len {
            return corrupt(format!(
                "{} bytes after the last section",
                file_len.saturating_sub(end)
            ));
        }
        let load = |tag| -> Result<Vec<u8>, RuntimeError> {
            let s = find(tag)?;
            section_payload(&s, slice_at(&bytes, s.offset, s.len as usize)?)
        };
        let header: Header = from_postcard(&load(TAG_HEAD)?, "HEAD")?;
        let table: CellTable = from_postcard(&load(TAG_CELL)?, "CELL")?;
        let grid: GridIndex = from_postcard(&load(TAG_GRID)?, "GRID")?;
        let shapes: Option<ShapeTable> = match sections.iter().any(|s| s.tag == TAG_SHAP) {
            true => Some(from_postcard(&load(TAG_SHAP)?, "SHAP")?),
            false => None,
        };
        let leaf_table: Option<LeafTable> = match sections.iter().any(|s| s.tag == TAG_LEAF) {
            true => Some(from_postcard(&load(TAG_LEAF)?, "LEAF")?),
            false => None,
        };
        let data = find(TAG_DATA)?;
        table.validate(&header, data.len)?;
        let n = header.cell_count as usize;
        let stored = table.present.as_ref().map_or(n, Vec::len);
        let (leaf_offsets, leaves) = match leaf_table.map(|t| t.decode(stored)).transpose()? {
            Some((o, l)) => (Some(o), l),
            None => (None, Vec::new()),
        };
        grid.validate(n)?;
        if let Some(t) = &shapes {
            t.validate(n)?;
        }
        if let Some(s) = header.shard {
            s.validate()?;
        }
        let boxes = table.cells()?;

        let mut rank = vec![u32::MAX; n];
        match &table.present {
            None => rank.iter_mut().enumerate().for_each(|(i, r)| *r = i as u32),
            Some(p) => p
                .iter()
                .enumerate()
                .for_each(|(k, &c)| rank[c as usize] = k as u32),
        }
        let voxel_bounds = match &shapes {
            None => Vec::new(),
            Some(t) => (0..n)
                .map(|i| {
                    let bs = &t.boxes[t.box_offsets[i] as usize..t.box_offsets[i + 1] as usize];
                    bs.iter()
                        .skip(1)
                        .fold(bs.first().copied().unwrap_or(boxes[i]), |acc, b| {
                            std::array::from_fn(|k| {
                                if k < 3 {
                                    acc[k].min(b[k])
                                } else {
                                    acc[k].max(b[k])
                                }
                            })
                        })
                })
                .collect(),
        };
        let (sources, source_names) = source_params(&header.params);
        let by_source_id = match (&leaf_offsets, &shapes) {
            (None, _) => Vec::new(),
            (Some(_), Some(t)) => {
                let mut v: Vec<(u32, u32)> = t
                    .ids
                    .iter()
                    .enumerate()
                    .map(|(i, &id)| (id, i as u32))
                    .collect();
                v.sort_unstable();
                v
            }
            (Some(_), None) => (0..n as u32).map(|i| (i, i)).collect(),
        };
        Ok(Pvs {
            id: NEXT_FILE_ID.fetch_add(1, Ordering::Relaxed),
            header,
            boxes,
            table,
            rank,
            grid,
            shapes,
            voxel_bounds,
            leaf_offsets,
            leaves,
            sources,
            source_names,
            data,
            bytes,
            gameplay: OnceLock::new(),
            by_source_id,
        })
    }

    /// The HEAD section: fingerprint, method, parameters, counts, shard.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// Number of cells of the build.
    pub fn cell_count(&self) -> u32 {
        self.boxes.len() as u32
    }

    /// Number of objects of the scene (every visible id is below it).
    pub fn object_count(&self) -> u32 {
        self.header.object_count
    }

    /// The bounding box `[x0, y0, z0, x1, y1, z1]` of cell `cell`.
    pub fn cell_box(&self, cell: u32) -> Option<[f64; 6]> {
        self.boxes.get(cell as usize).copied()
    }

    /// The kind of cell `cell`.
    pub fn cell_kind(&self, cell: u32) -> Option<CellKind> {
        let i = cell as usize;
        if i >= self.boxes.len() {
            return None;
        }
        Some(match self.shapes.as_ref().map(|t| t.kinds[i]) {
            Some(KIND_CONVEX) => CellKind::Convex,
            Some(KIND_VOXELS) => CellKind::Voxels,
            _ => CellKind::Box,
        })
    }

    /// The cell's number in its source (a BSP leaf, an automatic cell); `None` for a box.
    pub fn cell_source_id(&self, cell: u32) -> Option<u32> {
        match self.cell_kind(cell)? {
            CellKind::Box => None,
            _ => self.shapes.as_ref().map(|t| t.ids[cell as usize]),
        }
    }

    /// The half-spaces `[nx, ny, nz, d]` (`n · p <= d`) of a convex cell (a BSP leaf);
    /// `None` for a cell of another kind.
    pub fn cell_planes(&self, cell: u32) -> Option<&[[f64; 4]]> {
        let t = self.shapes.as_ref()?;
        let i = cell as usize;
        (self.cell_kind(cell)? == CellKind::Convex)
            .then(|| &t.planes[t.plane_offsets[i] as usize..t.plane_offsets[i + 1] as usize])
    }

    /// The boxes `[x0, y0, z0, x1, y1, z1]` of a voxel cell (an automatic cell of a mesh
    /// level); `None` for a cell of another kind.
    pub fn cell_voxel_boxes(&self, cell: u32) -> Option<&[[f64; 6]]> {
        let t = self.shapes.as_ref()?;
        let i = cell as usize;
        (self.cell_kind(cell)? == CellKind::Voxels)
            .then(|| &t.boxes[t.box_offsets[i] as usize..t.box_offsets[i + 1] as usize])
    }

    /// The cells whose rows this file stores, ascending (every cell but in a shard).
    pub fn stored_cells(&self) -> impl Iterator<Item = u32> + '_ {
        (0..self.cell_count()).filter(|&c| self.is_stored(c))
    }

    /// The byte offset and length of the DATA section (the compressed rows).
    pub fn data_section(&self) -> (u64, u64) {
        (self.data.offset, self.data.len)
    }

    /// Check the DATA section's checksum and decode every stored row (what `open`
    /// leaves to the queries).
    pub fn verify(&self, q: &mut Query) -> Result<(), RuntimeError> {
        let stored = slice_at(&self.bytes, self.data.offset, self.data.len as usize)?;
        section_payload(&self.data, stored)?;
        let mut row = Vec::new();
        for c in self.stored_cells() {
            self.visible_into(q, c, &mut row)?;
        }
        Ok(())
    }

    /// Cell `c`'s number in the SHAP section (any kind), or `c` in a file without one.
    pub(crate) fn source_number(&self, c: u32) -> u32 {
        match &self.shapes {
            Some(t) => t.ids[c as usize],
            None => c,
        }
    }

    /// Whether this file stores the row of `cell` (a shard stores some cells only).
    pub fn is_stored(&self, cell: u32) -> bool {
        self.rank.get(cell as usize).is_some_and(|&r| r != u32::MAX)
    }

    /// The size of the row of a stored cell, without decoding it.
    pub fn row_len(&self, cell: u32) -> Option<u32> {
        let r = self.stored_rank(cell)?;
        Some(self.table.count[r])
    }

    pub(crate) fn stored_rank(&self, cell: u32) -> Option<usize> {
        match self.rank.get(cell as usize) {
            Some(&r) if r != u32::MAX => Some(r as usize),
            _ => None,
        }
    }

    /// The cell containing `p` (closed cells; a point on a shared face belongs to the
    /// lowest index), `None` when no cell does: the spatial index's bucket of `p`, then
    /// the first listed cell whose box, and shape, hold `p`.
    pub fn locate(&self, p: [f64; 3]) -> Option<u32> {
        if !p.iter().all(|v| v.is_finite()) {
            return None;
        }
        let (bx, by) = self.grid.bucket_of(p[0], p[1]);
        self.grid
            .bucket(bx, by)
            .iter()
            .copied()
            .find(|&i| box_contains(&self.boxes[i as usize], p) && self.shape_contains(i, p))
    }

    /// Whether `p` lies in the shape of cell `i` (`sightline_core::Cell::contains`).
    fn shape_contains(&self, i: u32, p: [f64; 3]) -> bool {
        let Some(t) = &self.shapes else {
            return true;
        };
        let i = i as usize;
        match t.kinds[i] {
            KIND_CONVEX => {
                let b = &self.boxes[i];
                let scale = extent(b).max(1.0);
                in_box_slack(b, p)
                    && t.planes[t.plane_offsets[i] as usize..t.plane_offsets[i + 1] as usize]
                        .iter()
                        .all(|h| {
                            let dot = h[0] * p[0] + h[1] * p[1] + h[2] * p[2];
                            let len = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
                            dot <= h[3] + len * scale * SLACK
                        })
            }
            KIND_VOXELS => {
                in_box_slack(&self.voxel_bounds[i], p)
                    && t.boxes[t.box_offsets[i] as usize..t.box_offsets[i + 1] as usize]
                        .iter()
                        .any(|b| in_box_slack(b, p))
            }
            _ => in_box_slack(&self.boxes[i], p),
        }
    }

    /// The sorted visible ids of cell `cell`, decoded into `q`'s buffers (valid until
    /// the next query with `q`). An error when the file does not store the cell or a
    /// block on its delta chain is corrupt.
    pub fn visible<'q>(&self, q: &'q mut Query, cell: u32) -> Result<&'q [u32], RuntimeError> {
        let mut row = std::mem::take(&mut q.row);
        let r = self.visible_into(q, cell, &mut row);
        q.row = row;
        r.map(|_| q.row.as_slice())
    }

    /// The sorted visible ids of cell `cell` into `out` (cleared first).
    pub fn visible_into(
        &self,
        q: &mut Query,
        cell: u32,
        out: &mut Vec<u32>,
    ) -> Result<(), RuntimeError> {
        out.clear();
        let Some(rank) = self.stored_rank(cell) else {
            return Err(RuntimeError::Invalid(format!(
                "cell {cell} is not stored in this file"
            )));
        };
        q.attach(self.id);
        let words = (self.header.object_count as usize).div_ceil(64);
        if words <= 2 * self.table.count[rank] as usize + 64
            && self.dense_row(q, rank, words, out)?
        {
            return Ok(());
        }
        let mut r = rank;
        for _ in 0..CHAIN_LIMIT {
            self.decode_payload(q, r)?;
            symmetric_difference(out, &q.payload, &mut q.xor);
            std::mem::swap(out, &mut q.xor);
            match self.table.reference[r] {
                0 => return self.check_row(cell, rank, out),
                reference => match self.stored_rank(reference - 1) {
                    Some(next) => r = next,
                    None => {
                        out.clear();
                        return corrupt(format!("cell {cell}: reference to a cell not stored"));
                    }
                },
            }
        }
        out.clear();
        corrupt(format!("cell {cell}: delta chain too long or cyclic"))
    }

    /// The final check of a decoded row: its stated size, ids below the object count.
    fn check_row(&self, cell: u32, rank: usize, out: &mut Vec<u32>) -> Result<(), RuntimeError> {
        if out.len() != self.table.count[rank] as usize
            || out.last().is_some_and(|&m| m >= self.header.object_count)
        {
            out.clear();
            return corrupt(format!("cell {cell}: decoded set does not match"));
        }
        Ok(())
    }

    /// The row of stored cell `rank` XORed into a bitset of the objects (`words` words),
    /// then read out: cheaper than merging sorted lists when the bitset is small next
    /// to the row. `Ok(false)` leaves the row to the merging path: a payload holds an
    /// id beyond the object count (only a corrupt file's XOR could cancel it, and the
    /// merging path decides exactly as `sightline-pvs` does) or the chain is not
    /// well-formed (the merging path reports the error).
    fn dense_row(
        &self,
        q: &mut Query,
        rank: usize,
        words: usize,
        out: &mut Vec<u32>,
    ) -> Result<bool, RuntimeError> {
        q.marks.clear();
        q.marks.resize(words, 0);
        let limit = self.header.object_count;
        let mut r = rank;
        for _ in 0..CHAIN_LIMIT {
            let slot = self.block(q, self.table.block[r])?;
            let (o, l) = (self.table.offset[r] as usize, self.table.len[r] as usize);
            let Some(bytes) = q.blocks[slot].1.get(o..o + l) else {
                return Ok(false);
            };
            let marks = &mut q.marks;
            let mut beyond = false;
            let decoded = decode_with(bytes, |v| {
                if v < limit {
                    marks[v as usize / 64] ^= 1 << (v % 64);
                } else {
                    beyond = true;
                }
            });
            if decoded.is_err() || beyond {
                return Ok(false);
            }
            match self.table.reference[r] {
                0 => {
                    out.clear();
                    for (w, &bits) in q.marks.iter().enumerate() {
                        let mut bits = bits;
                        while bits != 0 {
                            out.push(w as u32 * 64 + bits.trailing_zeros());
                            bits &= bits - 1;
                        }
                    }
                    if out.len() != self.table.count[rank] as usize {
                        out.clear();
                        return Ok(false);
                    }
                    return Ok(true);
                }
                reference => match self.stored_rank(reference - 1) {
                    Some(next) => r = next,
                    None => return Ok(false),
                },
            }
        }
        Ok(false)
    }

    /// Decode the payload of stored cell `rank` into `q.payload`.
    fn decode_payload(&self, q: &mut Query, rank: usize) -> Result<(), RuntimeError> {
        let b = self.table.block[rank];
        let slot = self.block(q, b)?;
        let (o, l) = (
            self.table.offset[rank] as usize,
            self.table.len[rank] as usize,
        );
        let bytes = q.blocks[slot]
            .1
            .get(o..o + l)
            .ok_or_else(|| RuntimeError::Corrupt("payload outside its block".into()))?;
        decode_into(bytes, &mut q.payload)
            .map_err(|e| RuntimeError::Corrupt(format!("bad bitmap: {e}")))
    }

    /// The slot of `q`'s cache holding data block `b`, decompressing it on a miss.
    fn block(&self, q: &mut Query, b: u32) -> Result<usize, RuntimeError> {
        if let Some(slot) = q.blocks.iter().position(|(k, _)| *k == b) {
            return Ok(slot);
        }
        let be = &self.table.blocks[b as usize];
        let stored = slice_at(
            &self.bytes,
            self.data.offset.saturating_add(be.offset),
            be.len as usize,
        )?;
        if crc32fast::hash(stored) != be.crc {
            return corrupt(format!("checksum mismatch in data block {b}"));
        }
        let raw_len = be.raw_len as usize;
        let mut buf = q.evict_for(raw_len);
        buf.clear();
        buf.reserve(raw_len);
        let r = q
            .dctx()?
            .decompress_to_buffer(stored, &mut buf)
            .map_err(|e| RuntimeError::Corrupt(format!("data block {b}: {e}")));
        if let Err(e) = r {
            q.spare.push(buf);
            return Err(e);
        }
        if buf.len() != raw_len {
            q.spare.push(buf);
            return corrupt(format!("data block {b}: wrong decoded size"));
        }
        q.blocks.push((b, buf));
        Ok(q.blocks.len() - 1)
    }

    /// Whether the file stores visible leaves (the LEAF section of a BSP level's build).
    pub fn has_visible_leaves(&self) -> bool {
        self.leaf_offsets.is_some()
    }

    /// The sorted visible leaves of stored cell `cell` (numbers in the cells' source, as
    /// [`Pvs::cell_source_id`]); `None` when the file has none or does not store it.
    pub fn visible_leaves(&self, cell: u32) -> Option<&[u32]> {
        let o = self.leaf_offsets.as_ref()?;
        let r = self.stored_rank(cell)?;
        Some(&self.leaves[o[r] as usize..o[r + 1] as usize])
    }

    /// The cells whose closed boxes touch or overlap cell `cell`'s (itself excluded),
    /// ascending, into `out`: the rows a walking client prefetches. Found through the
    /// spatial index on each call (nothing is precomputed at open, so a hostile file of
    /// overlapping cells costs only the calls that ask); empty for an unknown cell.
    pub fn neighbours_into(&self, cell: u32, out: &mut Vec<u32>) {
        out.clear();
        let Some(b) = self.boxes.get(cell as usize) else {
            return;
        };
        let tol = extent(b).max(1.0) * SLACK;
        let (x0, y0) = self.grid.bucket_of(b[0] - tol, b[1] - tol);
        let (x1, y1) = self.grid.bucket_of(b[3] + tol, b[4] + tol);
        for by in y0..=y1 {
            for bx in x0..=x1 {
                out.extend(
                    self.grid
                        .bucket(bx, by)
                        .iter()
                        .copied()
                        .filter(|&j| j != cell && touch(b, &self.boxes[j as usize], tol)),
                );
            }
        }
        out.sort_unstable();
        out.dedup();
    }

    /// The mesh level's cluster → source object map (parameter `sources`), if any.
    pub fn sources(&self) -> Option<&[u32]> {
        self.sources.as_deref()
    }

    /// The names of the source objects (parameter `source_names`), if any.
    pub fn source_names(&self) -> Option<&[String]> {
        self.source_names.as_deref()
    }

    /// The sorted source objects of the ids `visible` (what `query` reports as
    /// `visible_sources`) into `out`; `false` (and `out` empty) when the file has no map.
    pub fn visible_sources_into(&self, visible: &[u32], out: &mut Vec<u32>) -> bool {
        out.clear();
        let Some(map) = &self.sources else {
            return false;
        };
        out.extend(visible.iter().filter_map(|&c| map.get(c as usize).copied()));
        out.sort_unstable();
        out.dedup();
        true
    }
}

fn extent(b: &[f64; 6]) -> f64 {
    (b[3] - b[0]).max((b[4] - b[1]).max(b[5] - b[2]))
}

/// Closed-box containment, no slack (the spatial index's test).
fn box_contains(b: &[f64; 6], p: [f64; 3]) -> bool {
    p[0] >= b[0] && p[1] >= b[1] && p[2] >= b[2] && p[0] <= b[3] && p[1] <= b[4] && p[2] <= b[5]
}

/// Containment with the relative slack of a shape's test.
fn in_box_slack(b: &[f64; 6], p: [f64; 3]) -> bool {
    let s = extent(b).max(1.0) * SLACK;
    p[0] >= b[0] - s
        && p[1] >= b[1] - s
        && p[2] >= b[2] - s
        && p[0] <= b[3] + s
        && p[1] <= b[4] + s
        && p[2] <= b[5] + s
}

fn touch(a: &[f64; 6], b: &[f64; 6], tol: f64) -> bool {
    (0..3).all(|k| a[k] <= b[k + 3] + tol && b[k] <= a[k + 3] + tol)
}

/// `sources` (comma-separated ids) and `source_names` (a JSON array of strings) of a
/// mesh level's parameters; a malformed value reads as absent, as in the CLI.
fn source_params(params: &[(String, String)]) -> (Option<Vec<u32>>, Option<Vec<String>>) {
    let get = |k: &str| params.iter().find(|(key, _)| key == k).map(|(_, v)| v);
    let sources = get("sources").and_then(|s| {
        s.split(',')
            .filter(|x| !x.is_empty())
            .map(|x| x.parse().ok())
            .collect::<Option<Vec<u32>>>()
    });
    let names = get("source_names").and_then(|s| crate::json::string_array(s));
    (sources, names)
}
