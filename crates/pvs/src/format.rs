//! The `.pvs` file format, versions 1 and 2 (documented in `docs/pvs-format.md`).
//!
//! ```text
//! preamble   magic "SLPVS\0\r\n" | version u16 | section count u16
//!            | directory: count × {tag [u8;4], codec u32, offset u64, len u64, raw_len u64, crc32 u32}
//!            | crc32 of everything above
//! HEAD       postcard(Header): scene fingerprint, method, params, object and cell counts, shard
//! CELL       zstd(postcard(CellTable)): boxes (columns), per-cell reference/block/offset/len/count, blocks
//! GRID       zstd(postcard(Grid)): the spatial index
//! SHAP       (version 2, optional) zstd(postcard(ShapeTable)): cells that are not boxes
//! LEAF       (version 2, optional) zstd(postcard(LeafTable)): each stored cell's visible leaves
//! DATA       zstd frames, one per block of cells; a block is the concatenated roaring payloads
//! ```
//!
//! Little-endian throughout. Every section has a CRC-32 in the directory, every data
//! block its own CRC-32 in the cell table (so a query checks only what it reads).
//! The bytes are a pure function of the header, the cells and their sets.

use crate::crc::crc32;
use crate::delta::{choose_references, MAX_CHAIN};
use crate::error::PvsError;
use crate::index::Grid;
use crate::leaves::LeafTable;
use crate::partition::Shard;
use crate::shapes::ShapeTable;
use rayon::prelude::*;
use roaring::RoaringBitmap;
use serde::{Deserialize, Serialize};
use sightline_core::Cell;
use sightline_geom::ViewCell;

/// First eight bytes of every `.pvs` (the `\r\n` catches text-mode mangling).
pub const MAGIC: [u8; 8] = *b"SLPVS\0\r\n";
/// The newest format version this code writes and reads: version 2 adds the SHAP
/// section (cells that are not boxes). A file whose cells are all boxes is written as
/// version 1, the same bytes as before; both versions are read.
pub const FORMAT_VERSION: u16 = 2;
/// The version of a file whose cells are all boxes.
pub const FORMAT_VERSION_BOXES: u16 = 1;

pub(crate) const TAG_HEAD: [u8; 4] = *b"HEAD";
pub(crate) const TAG_CELL: [u8; 4] = *b"CELL";
pub(crate) const TAG_GRID: [u8; 4] = *b"GRID";
pub(crate) const TAG_DATA: [u8; 4] = *b"DATA";
pub(crate) const TAG_SHAP: [u8; 4] = *b"SHAP";
pub(crate) const TAG_LEAF: [u8; 4] = *b"LEAF";
pub(crate) const CODEC_RAW: u32 = 0;
pub(crate) const CODEC_ZSTD: u32 = 1;
pub(crate) const DIR_ENTRY_LEN: usize = 36;
pub(crate) const PREAMBLE_FIXED: usize = 12;

/// zstd level of the table sections and data blocks.
const ZSTD_LEVEL: i32 = 19;
/// A data block closes after this many cells or this many uncompressed bytes. Large
/// blocks let zstd find what the delta-PVS leaves: the sets of neighbouring cells that
/// are not each other's reference still share whole streets, and a larger block sees
/// more of them; a query that misses the block cache decompresses one block, so the
/// block stays small enough for on-line queries (figures in `docs/pvs-format.md`).
const BLOCK_CELLS: usize = 4096;
const BLOCK_BYTES: usize = 512 * 1024;
/// Decoded sizes above this are treated as corruption, not allocated.
pub(crate) const MAX_RAW_SECTION: u64 = 1 << 32;

/// What a `.pvs` was computed from: the HEAD section.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Header {
    /// `Scene::fingerprint()` of the scene the sets belong to.
    pub fingerprint: u64,
    /// Name of the method that built the sets.
    pub method: String,
    /// The method's parameters (`VisibilityMethod::params`).
    pub params: Vec<(String, String)>,
    /// Number of objects of the scene (every id is below it).
    pub object_count: u32,
    /// Number of cells of the whole build (a shard holds a subset of them).
    pub cell_count: u32,
    /// `Some` for a shard file (`build --shard I/N`), `None` for a complete file.
    pub shard: Option<Shard>,
}

impl Header {
    pub fn new(
        fingerprint: u64,
        method: &str,
        params: Vec<(String, String)>,
        object_count: usize,
        cell_count: usize,
    ) -> Header {
        Header {
            fingerprint,
            method: method.to_string(),
            params,
            object_count: object_count as u32,
            cell_count: cell_count as u32,
            shard: None,
        }
    }
}

/// One zstd frame of the DATA section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct BlockEntry {
    /// Offset inside the DATA section.
    pub offset: u64,
    pub len: u32,
    pub raw_len: u32,
    pub crc: u32,
}

/// The CELL section, column by column (columns compress better than rows).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct CellTable {
    /// x0, y0, z0, x1, y1, z1 of every cell of the build.
    pub boxes: [Vec<f64>; 6],
    /// The cells stored in this file, ascending; `None` = all of them.
    pub present: Option<Vec<u32>>,
    /// Per stored cell (in `present` order): 0 for a key cell, else 1 + the cell
    /// index of its reference.
    pub reference: Vec<u32>,
    pub block: Vec<u32>,
    /// Byte range of the payload inside the decompressed block.
    pub offset: Vec<u32>,
    pub len: Vec<u32>,
    /// Number of ids in the cell's set (checked after decoding).
    pub count: Vec<u32>,
    pub blocks: Vec<BlockEntry>,
}

fn zstd(bytes: &[u8]) -> Result<Vec<u8>, PvsError> {
    zstd::bulk::compress(bytes, ZSTD_LEVEL).map_err(|e| PvsError::Invalid(format!("zstd: {e}")))
}

fn postcard_bytes<T: Serialize>(v: &T) -> Result<Vec<u8>, PvsError> {
    postcard::to_stdvec(v).map_err(|e| PvsError::Invalid(format!("postcard: {e}")))
}

/// Encode a `.pvs`: `cells` are all the cells of the build, `present[k]` the index of
/// the cell whose sorted set is `sets[k]` (ascending; every cell for a complete file).
pub fn encode(
    header: &Header,
    cells: &[ViewCell],
    present: &[u32],
    sets: &[Vec<u32>],
) -> Result<Vec<u8>, PvsError> {
    let bitmaps: Vec<RoaringBitmap> = sets
        .par_iter()
        .map(|s| RoaringBitmap::from_sorted_iter(s.iter().copied()))
        .collect::<Result<_, _>>()
        .map_err(|_| PvsError::Invalid("a set is not sorted without duplicates".into()))?;
    encode_bitmaps(header, cells, present, &bitmaps)
}

/// How to encode (the default is what `build` writes).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EncodeOptions {
    /// Store cells as differences with a neighbour (delta-PVS); `false` stores every
    /// cell whole (for comparison).
    pub delta: bool,
}

impl Default for EncodeOptions {
    fn default() -> Self {
        EncodeOptions { delta: true }
    }
}

/// [`encode`] with the sets already as bitmaps.
pub fn encode_bitmaps(
    header: &Header,
    cells: &[ViewCell],
    present: &[u32],
    sets: &[RoaringBitmap],
) -> Result<Vec<u8>, PvsError> {
    encode_with(header, cells, present, sets, &EncodeOptions::default())
}

/// [`encode_bitmaps`] with explicit options. With `delta`, the delta-PVS is kept only
/// if it is smaller than storing every cell whole: zstd over a block of whole
/// neighbouring sets already finds much of their overlap, and on small or weakly
/// correlated sets it can win.
pub fn encode_with(
    header: &Header,
    cells: &[ViewCell],
    present: &[u32],
    sets: &[RoaringBitmap],
    opts: &EncodeOptions,
) -> Result<Vec<u8>, PvsError> {
    encode_shaped(header, cells, Extra::default(), present, sets, opts)
}

/// [`encode_with`] for cells of any kind ([`Cell`]: boxes, convex polyhedra, voxel
/// cells). The CELL section and the spatial index hold the cells' bounding boxes, the
/// SHAP section their shapes (module doc of `shapes`); all boxes give the same bytes
/// as [`encode_with`].
pub fn encode_cells(
    header: &Header,
    cells: &[Cell],
    present: &[u32],
    sets: &[RoaringBitmap],
    opts: &EncodeOptions,
) -> Result<Vec<u8>, PvsError> {
    encode_cells_with_leaves(header, cells, present, sets, None, opts)
}

/// [`encode_cells`] with, optionally, each stored cell's visible leaves (`leaves[k]`
/// for `present[k]`, sorted ascending): the numbers of the cells it sees in its source,
/// e.g. a BSP level's leaf PVS next to its face PVS. They go into the LEAF section
/// (format version 2); `None` writes exactly what [`encode_cells`] writes.
pub fn encode_cells_with_leaves(
    header: &Header,
    cells: &[Cell],
    present: &[u32],
    sets: &[RoaringBitmap],
    leaves: Option<&[Vec<u32>]>,
    opts: &EncodeOptions,
) -> Result<Vec<u8>, PvsError> {
    let bounds: Vec<ViewCell> = cells.iter().map(Cell::bounds).collect();
    let shapes = ShapeTable::of(cells);
    let leaves = match leaves {
        Some(l) if l.len() != sets.len() => {
            return Err(PvsError::Invalid(format!(
                "{} visible-leaf sets for {} stored cells",
                l.len(),
                sets.len()
            )))
        }
        Some(l) => Some(LeafTable::of(l)?),
        None => None,
    };
    let extra = Extra {
        shapes: shapes.as_ref(),
        leaves: leaves.as_ref(),
    };
    encode_shaped(header, &bounds, extra, present, sets, opts)
}

/// The optional sections of version 2.
#[derive(Clone, Copy, Default)]
struct Extra<'a> {
    shapes: Option<&'a ShapeTable>,
    leaves: Option<&'a LeafTable>,
}

fn encode_shaped(
    header: &Header,
    cells: &[ViewCell],
    extra: Extra,
    present: &[u32],
    sets: &[RoaringBitmap],
    opts: &EncodeOptions,
) -> Result<Vec<u8>, PvsError> {
    let whole = encode_layout(header, cells, extra, present, sets, false)?;
    if !opts.delta {
        return Ok(whole);
    }
    let delta = encode_layout(header, cells, extra, present, sets, true)?;
    Ok(if delta.len() < whole.len() {
        delta
    } else {
        whole
    })
}

fn encode_layout(
    header: &Header,
    cells: &[ViewCell],
    extra: Extra,
    present: &[u32],
    sets: &[RoaringBitmap],
    delta: bool,
) -> Result<Vec<u8>, PvsError> {
    if cells.len() != header.cell_count as usize {
        return Err(PvsError::Invalid(format!(
            "header says {} cells, {} given",
            header.cell_count,
            cells.len()
        )));
    }
    if present.len() != sets.len()
        || present.windows(2).any(|w| w[0] >= w[1])
        || present.last().is_some_and(|&p| p as usize >= cells.len())
    {
        return Err(PvsError::Invalid(
            "present cells must be ascending cell indices, one per set".into(),
        ));
    }
    if let Some(s) = sets
        .iter()
        .position(|s| s.max().is_some_and(|m| m >= header.object_count))
    {
        return Err(PvsError::Invalid(format!(
            "cell {}: object id beyond the scene's {} objects",
            present[s], header.object_count
        )));
    }
    let complete = present.len() == cells.len();
    if header.shard.is_none() && !complete {
        return Err(PvsError::Invalid(
            "a complete file must hold every cell".into(),
        ));
    }

    // Delta-PVS: references among the stored cells.
    let stored_cells: Vec<ViewCell> = present.iter().map(|&p| cells[p as usize]).collect();
    let refs = if delta {
        choose_references(&stored_cells, sets)
    } else {
        vec![None; sets.len()]
    };

    // Storage order: depth-first from each key cell, children by index, so a chain's
    // cells tend to share a block.
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); present.len()];
    for (k, r) in refs.iter().enumerate() {
        if let Some(p) = r {
            children[*p].push(k);
        }
    }
    let mut order = Vec::with_capacity(present.len());
    let mut stack = Vec::new();
    for key in (0..present.len()).filter(|&k| refs[k].is_none()) {
        stack.push(key);
        while let Some(v) = stack.pop() {
            order.push(v);
            stack.extend(children[v].iter().rev());
        }
    }

    let payloads: Vec<Vec<u8>> = order
        .par_iter()
        .map(|&k| {
            let delta = match refs[k] {
                Some(p) => &sets[k] ^ &sets[p],
                None => sets[k].clone(),
            };
            let mut v = Vec::with_capacity(delta.serialized_size());
            delta.serialize_into(&mut v).map(|_| v)
        })
        .collect::<Result<_, _>>()
        .map_err(|e| PvsError::Invalid(format!("roaring: {e}")))?;

    // Group into blocks.
    let n = present.len();
    let (mut block, mut offset, mut len) = (vec![0u32; n], vec![0u32; n], vec![0u32; n]);
    let mut raw_blocks: Vec<Vec<u8>> = Vec::new();
    let mut current: Vec<u8> = Vec::new();
    let mut in_block = 0;
    for (pos, &k) in order.iter().enumerate() {
        let p = &payloads[pos];
        if in_block > 0 && (in_block >= BLOCK_CELLS || current.len() + p.len() > BLOCK_BYTES) {
            raw_blocks.push(std::mem::take(&mut current));
            in_block = 0;
        }
        block[k] = raw_blocks.len() as u32;
        offset[k] = current.len() as u32;
        len[k] = p.len() as u32;
        current.extend_from_slice(p);
        in_block += 1;
    }
    if in_block > 0 {
        raw_blocks.push(current);
    }
    let compressed: Vec<Vec<u8>> = raw_blocks
        .par_iter()
        .map(|b| zstd(b))
        .collect::<Result<_, _>>()?;
    let mut data = Vec::new();
    let mut blocks = Vec::with_capacity(compressed.len());
    for (raw, c) in raw_blocks.iter().zip(&compressed) {
        blocks.push(BlockEntry {
            offset: data.len() as u64,
            len: c.len() as u32,
            raw_len: raw.len() as u32,
            crc: crc32(c),
        });
        data.extend_from_slice(c);
    }

    let table = CellTable {
        boxes: std::array::from_fn(|a| cells.iter().map(|c| c.to_array()[a]).collect()),
        present: (!complete).then(|| present.to_vec()),
        reference: refs
            .iter()
            .map(|r| r.map_or(0, |p| present[p] + 1))
            .collect(),
        block,
        offset,
        len,
        count: sets.iter().map(|s| s.len() as u32).collect(),
        blocks,
    };
    let grid = Grid::build(cells);

    let head_raw = postcard_bytes(header)?;
    let cell_raw = postcard_bytes(&table)?;
    let grid_raw = postcard_bytes(&grid)?;
    let mut sections: Vec<([u8; 4], u32, Vec<u8>, u64)> = vec![
        (TAG_HEAD, CODEC_RAW, head_raw.clone(), head_raw.len() as u64),
        (
            TAG_CELL,
            CODEC_ZSTD,
            zstd(&cell_raw)?,
            cell_raw.len() as u64,
        ),
        (
            TAG_GRID,
            CODEC_ZSTD,
            zstd(&grid_raw)?,
            grid_raw.len() as u64,
        ),
    ];
    if let Some(t) = extra.shapes {
        let raw = postcard_bytes(t)?;
        sections.push((TAG_SHAP, CODEC_ZSTD, zstd(&raw)?, raw.len() as u64));
    }
    if let Some(t) = extra.leaves {
        let raw = postcard_bytes(t)?;
        sections.push((TAG_LEAF, CODEC_ZSTD, zstd(&raw)?, raw.len() as u64));
    }
    sections.push((TAG_DATA, CODEC_RAW, data, 0));
    let version = if extra.shapes.is_some() || extra.leaves.is_some() {
        FORMAT_VERSION
    } else {
        FORMAT_VERSION_BOXES
    };
    let preamble_len = PREAMBLE_FIXED + DIR_ENTRY_LEN * sections.len() + 4;
    let mut out =
        Vec::with_capacity(preamble_len + sections.iter().map(|s| s.2.len()).sum::<usize>());
    out.extend_from_slice(&MAGIC);
    out.extend_from_slice(&version.to_le_bytes());
    out.extend_from_slice(&(sections.len() as u16).to_le_bytes());
    let mut offset = preamble_len as u64;
    for (tag, codec, bytes, raw_len) in &sections {
        let raw_len = if *codec == CODEC_RAW {
            bytes.len() as u64
        } else {
            *raw_len
        };
        out.extend_from_slice(tag);
        out.extend_from_slice(&codec.to_le_bytes());
        out.extend_from_slice(&offset.to_le_bytes());
        out.extend_from_slice(&(bytes.len() as u64).to_le_bytes());
        out.extend_from_slice(&raw_len.to_le_bytes());
        out.extend_from_slice(&crc32(bytes).to_le_bytes());
        offset += bytes.len() as u64;
    }
    let c = crc32(&out);
    out.extend_from_slice(&c.to_le_bytes());
    for (_, _, bytes, _) in &sections {
        out.extend_from_slice(bytes);
    }
    Ok(out)
}

/// One entry of the section directory.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Section {
    pub tag: [u8; 4],
    pub codec: u32,
    pub offset: u64,
    pub len: u64,
    pub raw_len: u64,
    pub crc: u32,
}

/// Parse and check the preamble, reading through `read_at(offset, len)` from a file of
/// `file_len` bytes.
pub(crate) fn parse_preamble(
    file_len: u64,
    read_at: &dyn Fn(u64, usize) -> Result<Vec<u8>, PvsError>,
) -> Result<Vec<Section>, PvsError> {
    let head = read_at(0, (file_len as usize).min(PREAMBLE_FIXED))?;
    if head.len() < MAGIC.len() && MAGIC.starts_with(&head) && !head.is_empty() {
        return Err(PvsError::Truncated(format!(
            "{file_len} bytes, shorter than the preamble"
        )));
    }
    if head.len() < MAGIC.len() || head[..8] != MAGIC {
        return Err(PvsError::NotPvs);
    }
    if head.len() < PREAMBLE_FIXED {
        return Err(PvsError::Truncated(format!(
            "{file_len} bytes, shorter than the preamble"
        )));
    }
    let version = u16::from_le_bytes([head[8], head[9]]);
    if !(FORMAT_VERSION_BOXES..=FORMAT_VERSION).contains(&version) {
        return Err(PvsError::Version {
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    let count = u16::from_le_bytes([head[10], head[11]]) as usize;
    let total = PREAMBLE_FIXED + count * DIR_ENTRY_LEN + 4;
    if total as u64 > file_len {
        return Err(PvsError::Truncated(format!(
            "{file_len} bytes, shorter than the section directory"
        )));
    }
    let bytes = read_at(0, total)?;
    let stored = u32::from_le_bytes([
        bytes[total - 4],
        bytes[total - 3],
        bytes[total - 2],
        bytes[total - 1],
    ]);
    if crc32(&bytes[..total - 4]) != stored {
        return Err(PvsError::Corrupt(
            "checksum mismatch in the section directory".into(),
        ));
    }
    let mut sections = Vec::with_capacity(count);
    for i in 0..count {
        let e =
            &bytes[PREAMBLE_FIXED + i * DIR_ENTRY_LEN..PREAMBLE_FIXED + (i + 1) * DIR_ENTRY_LEN];
        let u32_at = |o: usize| u32::from_le_bytes([e[o], e[o + 1], e[o + 2], e[o + 3]]);
        let u64_at = |o: usize| u64::from_le_bytes(std::array::from_fn(|k| e[o + k]));
        let s = Section {
            tag: [e[0], e[1], e[2], e[3]],
            codec: u32_at(4),
            offset: u64_at(8),
            len: u64_at(16),
            raw_len: u64_at(24),
            crc: u32_at(32),
        };
        let name = String::from_utf8_lossy(&s.tag).into_owned();
        let end = s.offset.checked_add(s.len);
        if end.is_none_or(|end| end > file_len) {
            return Err(PvsError::Truncated(format!(
                "section {name} ends at byte {}, the file has {file_len}",
                s.offset.saturating_add(s.len)
            )));
        }
        if s.offset < total as u64 || s.codec > CODEC_ZSTD || s.raw_len > MAX_RAW_SECTION {
            return Err(PvsError::Corrupt(format!(
                "bad directory entry for section {name}"
            )));
        }
        sections.push(s);
    }
    Ok(sections)
}

/// Check a section's checksum and undo its codec.
pub(crate) fn section_payload(s: &Section, stored: &[u8]) -> Result<Vec<u8>, PvsError> {
    let name = String::from_utf8_lossy(&s.tag).into_owned();
    if crc32(stored) != s.crc {
        return Err(PvsError::Corrupt(format!(
            "checksum mismatch in section {name}"
        )));
    }
    match s.codec {
        CODEC_RAW => Ok(stored.to_vec()),
        _ => {
            let raw = zstd::bulk::decompress(stored, s.raw_len as usize)
                .map_err(|e| PvsError::Corrupt(format!("section {name}: {e}")))?;
            if raw.len() as u64 != s.raw_len {
                return Err(PvsError::Corrupt(format!(
                    "section {name}: wrong decoded size"
                )));
            }
            Ok(raw)
        }
    }
}

pub(crate) fn from_postcard<'a, T: Deserialize<'a>>(
    bytes: &'a [u8],
    what: &str,
) -> Result<T, PvsError> {
    postcard::from_bytes(bytes).map_err(|e| PvsError::Corrupt(format!("section {what}: {e}")))
}

impl CellTable {
    /// Check a decoded table against the header (untrusted input).
    pub(crate) fn validate(&self, header: &Header, data_len: u64) -> Result<(), PvsError> {
        let bad = |m: String| Err(PvsError::Corrupt(format!("cell table: {m}")));
        let n = header.cell_count as usize;
        if self.boxes.iter().any(|c| c.len() != n) {
            return bad("box count differs from the header's cell count".into());
        }
        let stored = match &self.present {
            None => n,
            Some(p) => {
                if p.windows(2).any(|w| w[0] >= w[1]) || p.last().is_some_and(|&l| l as usize >= n)
                {
                    return bad("present cells are not ascending cell indices".into());
                }
                p.len()
            }
        };
        if header.shard.is_none() && stored != n {
            return bad("a complete file lacks cells".into());
        }
        for col in [
            &self.reference,
            &self.block,
            &self.offset,
            &self.len,
            &self.count,
        ] {
            if col.len() != stored {
                return bad("column lengths differ".into());
            }
        }
        if self.count.iter().any(|&c| c > header.object_count) {
            return bad("a set is larger than the scene".into());
        }
        for (k, &b) in self.block.iter().enumerate() {
            let Some(be) = self.blocks.get(b as usize) else {
                return bad(format!("cell refers to block {b} of {}", self.blocks.len()));
            };
            if self.offset[k] as u64 + self.len[k] as u64 > be.raw_len as u64 {
                return bad("payload outside its block".into());
            }
        }
        for be in &self.blocks {
            if be.offset + be.len as u64 > data_len {
                return bad("block outside the data section".into());
            }
        }
        for r in &self.reference {
            if *r as usize > n {
                return bad("reference to a cell that does not exist".into());
            }
        }
        Ok(())
    }

    pub(crate) fn cells(&self) -> Result<Vec<ViewCell>, PvsError> {
        let n = self.boxes[0].len();
        (0..n)
            .map(|i| {
                ViewCell::from_array(std::array::from_fn(|a| self.boxes[a][i]))
                    .map_err(|e| PvsError::Corrupt(format!("cell {i}: {e}")))
            })
            .collect()
    }
}

/// A stored cell's chain is followed at most this far before the file is declared corrupt.
pub(crate) const CHAIN_LIMIT: usize = MAX_CHAIN;
