//! Reading a `.pvs`: open once (preamble, header, cell table and spatial index are
//! checked and kept in memory), then answer point queries by decoding only the data
//! blocks on the queried cell's delta chain.

use crate::crc::crc32;
use crate::error::PvsError;
use crate::format::{
    from_postcard, parse_preamble, section_payload, CellTable, Header, Section, CHAIN_LIMIT,
    TAG_CELL, TAG_DATA, TAG_GRID, TAG_HEAD, TAG_LEAF, TAG_SHAP,
};
use crate::index::Grid;
use crate::leaves::LeafTable;
use crate::shapes::ShapeTable;
use roaring::RoaringBitmap;
use sightline_core::Cell;
use sightline_geom::{DVec3, ViewCell};
use sightline_runtime::bitmap;
use sightline_scene::Scene;
use std::fs::File;
use std::os::unix::fs::FileExt;
use std::path::Path;
use std::sync::{Arc, Mutex};

/// Decoded blocks kept for the next queries, oldest dropped first, up to this many
/// decoded bytes: a walk stays in a neighbourhood, and a server answering clients all
/// over a city of 10,000 cells keeps every block of its file.
const BLOCK_CACHE_BYTES: usize = 64 << 20;

enum Source {
    File { file: File, path: String },
    Bytes(Vec<u8>),
}

impl Source {
    fn read_at(&self, offset: u64, len: usize) -> Result<Vec<u8>, PvsError> {
        match self {
            Source::File { file, path } => {
                let mut buf = vec![0u8; len];
                file.read_exact_at(&mut buf, offset).map_err(|e| {
                    if e.kind() == std::io::ErrorKind::UnexpectedEof {
                        PvsError::Truncated(format!("cannot read {len} bytes at {offset}"))
                    } else {
                        PvsError::Io {
                            path: path.clone(),
                            source: e,
                        }
                    }
                })?;
                Ok(buf)
            }
            Source::Bytes(b) => {
                let end = offset
                    .checked_add(len as u64)
                    .filter(|&e| e <= b.len() as u64);
                match end {
                    Some(end) => Ok(b[offset as usize..end as usize].to_vec()),
                    None => Err(PvsError::Truncated(format!(
                        "cannot read {len} bytes at {offset}"
                    ))),
                }
            }
        }
    }
}

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
    header: Header,
    cells: Vec<ViewCell>,
    table: CellTable,
    grid: Grid,
    /// The cells with their shapes, decoded once at open (`None`: every cell a box).
    shapes: Option<Vec<Cell>>,
    /// Each stored cell's visible leaves (LEAF section), in stored order.
    leaves: Option<Vec<Vec<u32>>>,
    data: Section,
    source: Source,
    cache: Mutex<Vec<(u32, Arc<Vec<u8>>)>>,
}

impl std::fmt::Debug for PvsFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PvsFile")
            .field("header", &self.header)
            .field("cells", &self.cells.len())
            .finish()
    }
}

impl PvsFile {
    /// Open a file: checks magic, version, section checksums and the tables; data blocks
    /// are checked when they are read.
    pub fn open(path: impl AsRef<Path>) -> Result<PvsFile, PvsError> {
        let path = path.as_ref();
        let file = File::open(path).map_err(|e| PvsError::io(path, e))?;
        let len = file.metadata().map_err(|e| PvsError::io(path, e))?.len();
        Self::from_source(
            Source::File {
                file,
                path: path.display().to_string(),
            },
            len,
        )
    }

    /// Read a file held in memory.
    pub fn from_bytes(bytes: Vec<u8>) -> Result<PvsFile, PvsError> {
        let len = bytes.len() as u64;
        Self::from_source(Source::Bytes(bytes), len)
    }

    fn from_source(source: Source, file_len: u64) -> Result<PvsFile, PvsError> {
        let sections = parse_preamble(file_len, &|o, l| source.read_at(o, l))?;
        let find = |tag: [u8; 4]| {
            sections
                .iter()
                .find(|s| s.tag == tag)
                .copied()
                .ok_or_else(|| {
                    PvsError::Corrupt(format!("missing section {}", String::from_utf8_lossy(&tag)))
                })
        };
        let end = sections.iter().map(|s| s.offset + s.len).max().unwrap_or(0);
        if end != file_len {
            return Err(PvsError::Corrupt(format!(
                "{} bytes after the last section",
                file_len.saturating_sub(end)
            )));
        }
        let load = |tag| -> Result<Vec<u8>, PvsError> {
            let s = find(tag)?;
            section_payload(&s, &source.read_at(s.offset, s.len as usize)?)
        };
        let header: Header = from_postcard(&load(TAG_HEAD)?, "HEAD")?;
        let table: CellTable = from_postcard(&load(TAG_CELL)?, "CELL")?;
        let grid: Grid = from_postcard(&load(TAG_GRID)?, "GRID")?;
        let shapes: Option<ShapeTable> = match sections.iter().any(|s| s.tag == TAG_SHAP) {
            true => Some(from_postcard(&load(TAG_SHAP)?, "SHAP")?),
            false => None,
        };
        let leaves: Option<LeafTable> = match sections.iter().any(|s| s.tag == TAG_LEAF) {
            true => Some(from_postcard(&load(TAG_LEAF)?, "LEAF")?),
            false => None,
        };
        let data = find(TAG_DATA)?;
        table.validate(&header, data.len)?;
        let stored = table
            .present
            .as_ref()
            .map_or(header.cell_count as usize, Vec::len);
        let leaves = leaves.map(|t| t.decode(stored)).transpose()?;
        grid.validate(header.cell_count as usize)?;
        if let Some(t) = &shapes {
            t.validate(header.cell_count as usize)?;
        }
        if let Some(s) = header.shard {
            s.validate()?;
        }
        let cells = table.cells()?;
        let shapes = shapes.map(|t| {
            (0..cells.len())
                .map(|i| t.cell(i, cells[i]))
                .collect::<Vec<Cell>>()
        });
        Ok(PvsFile {
            header,
            cells,
            table,
            grid,
            shapes,
            leaves,
            data,
            source,
            cache: Mutex::new(Vec::new()),
        })
    }

    pub fn header(&self) -> &Header {
        &self.header
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
        match &self.table.present {
            Some(p) => p.clone(),
            None => (0..self.cells.len() as u32).collect(),
        }
    }

    /// Whether the file stores each cell's visible leaves (a BSP level's build).
    pub fn has_visible_leaves(&self) -> bool {
        self.leaves.is_some()
    }

    /// The sorted visible leaves of stored cell `cell` (the numbers of the cells it
    /// sees in its source, e.g. BSP leaves); `None` when the file has none or does not
    /// store the cell.
    pub fn visible_leaves(&self, cell: usize) -> Option<&[u32]> {
        let rank = self.rank(cell)?;
        self.leaves.as_ref()?.get(rank).map(Vec::as_slice)
    }

    /// Size of the set of a stored cell, without decoding it.
    pub fn set_len(&self, cell: usize) -> Option<u32> {
        self.rank(cell).map(|r| self.table.count[r])
    }

    /// Error unless this file was built for `scene`.
    pub fn check_scene(&self, scene: &Scene) -> Result<(), PvsError> {
        let f = scene.fingerprint();
        if f != self.header.fingerprint
            || scene.objects.len() as u64 != self.header.object_count as u64
        {
            return Err(PvsError::SceneMismatch {
                file: self.header.fingerprint,
                scene: f,
            });
        }
        Ok(())
    }

    /// Index of the cell containing `p` (closed cells; the lowest index on shared
    /// faces): the spatial index finds the cells whose box holds `p`, the shape decides.
    pub fn locate(&self, p: DVec3) -> Option<usize> {
        match &self.shapes {
            None => self.grid.locate(&self.cells, p),
            Some(shapes) => self
                .grid
                .locate_where(&self.cells, p, |i| shapes[i].contains(p)),
        }
    }

    /// The cell containing `p` and its sorted PVS; `None` if no cell contains `p`.
    pub fn query(&self, p: DVec3) -> Result<Option<(ViewCell, Vec<u32>)>, PvsError> {
        match self.locate(p) {
            None => Ok(None),
            Some(i) => Ok(Some((self.cells[i], self.pvs(i)?))),
        }
    }

    fn rank(&self, cell: usize) -> Option<usize> {
        match &self.table.present {
            None => (cell < self.cells.len()).then_some(cell),
            Some(p) => p.binary_search(&(cell as u32)).ok(),
        }
    }

    /// The sorted PVS of cell `cell` (an error if this shard does not store it).
    pub fn pvs(&self, cell: usize) -> Result<Vec<u32>, PvsError> {
        self.sorted(cell)
    }

    /// The PVS of cell `cell` as a roaring bitmap.
    pub fn bitmap(&self, cell: usize) -> Result<RoaringBitmap, PvsError> {
        let set = self.sorted(cell)?;
        RoaringBitmap::from_sorted_iter(set)
            .map_err(|_| PvsError::Corrupt(format!("cell {cell}: decoded set does not match")))
    }

    /// The sorted PVS of cell `cell`: its payload and those of its references decoded
    /// and XORed by `sightline-runtime`, the code engines read rows with.
    fn sorted(&self, cell: usize) -> Result<Vec<u32>, PvsError> {
        let Some(rank) = self.rank(cell) else {
            return Err(PvsError::Invalid(format!(
                "cell {cell} is not stored in this file"
            )));
        };
        let (mut set, mut payload, mut xor) = (Vec::new(), Vec::new(), Vec::new());
        let mut r = rank;
        for _ in 0..CHAIN_LIMIT {
            self.payload(r, &mut payload)?;
            bitmap::symmetric_difference(&set, &payload, &mut xor);
            std::mem::swap(&mut set, &mut xor);
            match self.table.reference[r] {
                0 => {
                    if set.len() != self.table.count[rank] as usize
                        || set.last().is_some_and(|&m| m >= self.header.object_count)
                    {
                        return Err(PvsError::Corrupt(format!(
                            "cell {cell}: decoded set does not match"
                        )));
                    }
                    return Ok(set);
                }
                reference => {
                    r = self.rank(reference as usize - 1).ok_or_else(|| {
                        PvsError::Corrupt(format!("cell {cell}: reference to a cell not stored"))
                    })?;
                }
            }
        }
        Err(PvsError::Corrupt(format!(
            "cell {cell}: delta chain too long or cyclic"
        )))
    }

    fn payload(&self, rank: usize, out: &mut Vec<u32>) -> Result<(), PvsError> {
        let block = self.block(self.table.block[rank])?;
        let (o, l) = (
            self.table.offset[rank] as usize,
            self.table.len[rank] as usize,
        );
        let bytes = block
            .get(o..o + l)
            .ok_or_else(|| PvsError::Corrupt("payload outside its block".into()))?;
        bitmap::decode_into(bytes, out).map_err(|e| PvsError::Corrupt(format!("bad bitmap: {e}")))
    }

    fn block(&self, b: u32) -> Result<Arc<Vec<u8>>, PvsError> {
        if let Ok(cache) = self.cache.lock() {
            if let Some((_, v)) = cache.iter().find(|(k, _)| *k == b) {
                return Ok(v.clone());
            }
        }
        let be = &self.table.blocks[b as usize];
        let stored = self
            .source
            .read_at(self.data.offset + be.offset, be.len as usize)?;
        if crc32(&stored) != be.crc {
            return Err(PvsError::Corrupt(format!(
                "checksum mismatch in data block {b}"
            )));
        }
        let raw = zstd::bulk::decompress(&stored, be.raw_len as usize)
            .map_err(|e| PvsError::Corrupt(format!("data block {b}: {e}")))?;
        if raw.len() != be.raw_len as usize {
            return Err(PvsError::Corrupt(format!(
                "data block {b}: wrong decoded size"
            )));
        }
        let raw = Arc::new(raw);
        if let Ok(mut cache) = self.cache.lock() {
            let mut total: usize = cache.iter().map(|(_, v)| v.len()).sum::<usize>() + raw.len();
            while total > BLOCK_CACHE_BYTES && !cache.is_empty() {
                total -= cache.remove(0).1.len();
            }
            cache.push((b, raw.clone()));
        }
        Ok(raw)
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
        let stored = self
            .source
            .read_at(self.data.offset, self.data.len as usize)?;
        section_payload(&self.data, &stored)?;
        for r in self.iter() {
            r?;
        }
        Ok(())
    }

    /// Bytes of the data section (the compressed sets) and of the whole file.
    pub fn sizes(&self) -> (u64, u64) {
        (self.data.len, self.data.offset + self.data.len)
    }
}
