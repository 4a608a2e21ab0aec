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
use crate::delta::choose_references;
use crate::error::PvsError;
use crate::index::grid_index;
use crate::leaves::leaf_table;
use crate::shapes::shape_table;
use rayon::prelude::*;
use roaring::RoaringBitmap;
use serde::Serialize;
use sightline_core::Cell;
use sightline_geom::ViewCell;
use sightline_runtime::wire::{
    BlockEntry, CellTable, LeafTable, ShapeTable, CODEC_RAW, CODEC_ZSTD, DIR_ENTRY_LEN,
    PREAMBLE_FIXED, TAG_CELL, TAG_DATA, TAG_GRID, TAG_HEAD, TAG_LEAF, TAG_SHAP,
};
/// The format's structs are defined once, in `sightline-runtime` (the reader engines
/// link); this crate writes them. Version 2 adds the SHAP section (cells that are not
/// boxes); a file whose cells are all boxes is written as version 1, the same bytes as
/// before; both versions are read.
pub use sightline_runtime::wire::{Header, FORMAT_VERSION, FORMAT_VERSION_BOXES, MAGIC};

/// zstd level of the table sections and data blocks.
const ZSTD_LEVEL: i32 = 19;
/// A data block closes after this many cells or this many uncompressed bytes. Large
/// blocks let zstd find what the delta-PVS leaves: the sets of neighbouring cells that
/// are not each other's reference still share whole streets, and a larger block sees
/// more of them; a query that misses the block cache decompresses one block, so the
/// block stays small enough for on-line queries (figures in `docs/pvs-format.md`).
const BLOCK_CELLS: usize = 4096;
const BLOCK_BYTES: usize = 512 * 1024;
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
    let shapes = shape_table(cells);
    let leaves = match leaves {
        Some(l) if l.len() != sets.len() => {
            return Err(PvsError::Invalid(format!(
                "{} visible-leaf sets for {} stored cells",
                l.len(),
                sets.len()
            )))
        }
        Some(l) => Some(leaf_table(l)?),
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
    let grid = grid_index(cells);

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
