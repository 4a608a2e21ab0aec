//! The sections of a `.pvs` as they lie on disk (`docs/pvs-format.md`): the preamble,
//! and the postcard structs of HEAD, CELL, GRID, SHAP and LEAF, with the checks a
//! reader makes on untrusted input. The one definition of the format's structs:
//! `sightline-pvs` writes these and reads through [`crate::Pvs`].

use crate::error::{corrupt, RuntimeError};
use serde::{Deserialize, Serialize};

/// First eight bytes of every `.pvs`.
pub const MAGIC: [u8; 8] = *b"SLPVS\0\r\n";
/// The newest format version read.
pub const FORMAT_VERSION: u16 = 2;
/// The version of a file whose cells are all boxes.
pub const FORMAT_VERSION_BOXES: u16 = 1;

pub const TAG_HEAD: [u8; 4] = *b"HEAD";
pub const TAG_CELL: [u8; 4] = *b"CELL";
pub const TAG_GRID: [u8; 4] = *b"GRID";
pub const TAG_DATA: [u8; 4] = *b"DATA";
pub const TAG_SHAP: [u8; 4] = *b"SHAP";
pub const TAG_LEAF: [u8; 4] = *b"LEAF";
pub const CODEC_RAW: u32 = 0;
pub const CODEC_ZSTD: u32 = 1;
pub const DIR_ENTRY_LEN: usize = 36;
pub const PREAMBLE_FIXED: usize = 12;
/// Decoded sizes above this are treated as corruption, not allocated.
pub const MAX_RAW_SECTION: u64 = 1 << 32;
/// A delta chain is followed at most this far (the writer caps depth at 8).
pub const CHAIN_LIMIT: usize = 8;

/// Cell kinds of the SHAP section.
pub const KIND_BOX: u8 = 0;
pub const KIND_CONVEX: u8 = 1;
pub const KIND_VOXELS: u8 = 2;

/// Shard `index` of `count` of a build (`build --shard I/N`, 0-based): shard `I` of `N`
/// owns the cells whose index is `I mod N` (interleaved, so costly districts are
/// spread over the shards).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

/// Environment variables that name the shard of `--shard auto/N`, in order of preference:
/// a Kubernetes Indexed Job and a Slurm job array.
pub const SHARD_ENV: [&str; 2] = ["JOB_COMPLETION_INDEX", "SLURM_ARRAY_TASK_ID"];

/// What a `.pvs` was computed from: the HEAD section.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Header {
    /// The fingerprint of the scene the sets belong to.
    pub fingerprint: u64,
    /// The name of the method that built the sets (the registry's, `docs/pvs-format.md`).
    pub method: String,
    /// The method's parameters; mesh levels carry `sources` and `source_names`.
    pub params: Vec<(String, String)>,
    /// Number of objects of the scene (every id is below it).
    pub object_count: u32,
    /// Number of cells of the whole build (a shard holds a subset of them).
    pub cell_count: u32,
    /// `Some` for a shard file (`build --shard I/N`), `None` for a complete file.
    pub shard: Option<Shard>,
}

impl Header {
    /// The header of a complete file.
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
pub struct BlockEntry {
    /// Offset inside the DATA section.
    pub offset: u64,
    pub len: u32,
    pub raw_len: u32,
    pub crc: u32,
}

/// The CELL section, column by column (columns compress better than rows).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellTable {
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

/// `sightline_geom::UniformGrid` on the wire (glam's `DVec2` is a 2-tuple).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Buckets {
    pub origin: [f64; 2],
    pub step: [f64; 2],
    pub nx: u32,
    pub ny: u32,
}

/// The GRID section: a uniform 2D grid over the cells' footprints in compressed-row
/// form, each bucket listing the cells whose closed box meets it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GridIndex {
    pub buckets: Buckets,
    /// `nx * ny + 1` offsets into `items`, by bucket id (row-major, `y * nx + x`).
    pub offsets: Vec<u32>,
    /// Cell indices, ascending within each bucket.
    pub items: Vec<u32>,
}

/// The SHAP section: the shape of every cell, in columns.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShapeTable {
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

/// The LEAF section: gap-coded visible-leaf sets, one per stored cell in stored order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeafTable {
    /// Per stored cell: `[first, gap, gap, ...]`, every gap ≥ 1.
    pub sets: Vec<Vec<u32>>,
}

/// One entry of the section directory.
#[derive(Clone, Copy, Debug)]
pub struct Section {
    pub tag: [u8; 4],
    pub codec: u32,
    pub offset: u64,
    pub len: u64,
    pub raw_len: u64,
    pub crc: u32,
}

/// `bytes[offset..offset + len]`, or "truncated".
pub(crate) fn slice_at(bytes: &[u8], offset: u64, len: usize) -> Result<&[u8], RuntimeError> {
    offset
        .checked_add(len as u64)
        .filter(|&e| e <= bytes.len() as u64)
        .map(|e| &bytes[offset as usize..e as usize])
        .ok_or_else(|| RuntimeError::Truncated(format!("cannot read {len} bytes at {offset}")))
}

/// Parse and check the preamble of a file held in `bytes`.
pub(crate) fn parse_preamble(bytes: &[u8]) -> Result<Vec<Section>, RuntimeError> {
    let file_len = bytes.len() as u64;
    let head = &bytes[..bytes.len().min(PREAMBLE_FIXED)];
    if head.len() < MAGIC.len() && MAGIC.starts_with(head) && !head.is_empty() {
        return Err(RuntimeError::Truncated(format!(
            "{file_len} bytes, shorter than the preamble"
        )));
    }
    if head.len() < MAGIC.len() || head[..8] != MAGIC {
        return Err(RuntimeError::NotPvs);
    }
    if head.len() < PREAMBLE_FIXED {
        return Err(RuntimeError::Truncated(format!(
            "{file_len} bytes, shorter than the preamble"
        )));
    }
    let version = u16::from_le_bytes([head[8], head[9]]);
    if !(FORMAT_VERSION_BOXES..=FORMAT_VERSION).contains(&version) {
        return Err(RuntimeError::Version {
            found: version,
            supported: FORMAT_VERSION,
        });
    }
    let count = u16::from_le_bytes([head[10], head[11]]) as usize;
    let total = PREAMBLE_FIXED + count * DIR_ENTRY_LEN + 4;
    if total as u64 > file_len {
        return Err(RuntimeError::Truncated(format!(
            "{file_len} bytes, shorter than the section directory"
        )));
    }
    let pre = &bytes[..total];
    let stored = u32::from_le_bytes([
        pre[total - 4],
        pre[total - 3],
        pre[total - 2],
        pre[total - 1],
    ]);
    if crc32fast::hash(&pre[..total - 4]) != stored {
        return corrupt("checksum mismatch in the section directory");
    }
    let mut sections = Vec::with_capacity(count);
    for i in 0..count {
        let e = &pre[PREAMBLE_FIXED + i * DIR_ENTRY_LEN..PREAMBLE_FIXED + (i + 1) * DIR_ENTRY_LEN];
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
            return Err(RuntimeError::Truncated(format!(
                "section {name} ends at byte {}, the file has {file_len}",
                s.offset.saturating_add(s.len)
            )));
        }
        if s.offset < total as u64 || s.codec > CODEC_ZSTD || s.raw_len > MAX_RAW_SECTION {
            return corrupt(format!("bad directory entry for section {name}"));
        }
        sections.push(s);
    }
    Ok(sections)
}

/// Check a section's checksum and undo its codec.
pub(crate) fn section_payload(s: &Section, stored: &[u8]) -> Result<Vec<u8>, RuntimeError> {
    let name = String::from_utf8_lossy(&s.tag).into_owned();
    if crc32fast::hash(stored) != s.crc {
        return corrupt(format!("checksum mismatch in section {name}"));
    }
    match s.codec {
        CODEC_RAW => Ok(stored.to_vec()),
        _ => {
            let raw = zstd::bulk::decompress(stored, s.raw_len as usize)
                .map_err(|e| RuntimeError::Corrupt(format!("section {name}: {e}")))?;
            if raw.len() as u64 != s.raw_len {
                return corrupt(format!("section {name}: wrong decoded size"));
            }
            Ok(raw)
        }
    }
}

pub(crate) fn from_postcard<'a, T: Deserialize<'a>>(
    bytes: &'a [u8],
    what: &str,
) -> Result<T, RuntimeError> {
    postcard::from_bytes(bytes).map_err(|e| RuntimeError::Corrupt(format!("section {what}: {e}")))
}

/// A valid box: finite, `x0 < x1`, `y0 < y1`, `z0 <= z1` (`ViewCell::from_array`).
pub(crate) fn valid_box(a: &[f64; 6]) -> bool {
    a.iter().all(|v| v.is_finite()) && a[0] < a[3] && a[1] < a[4] && a[2] <= a[5]
}

impl Shard {
    /// Parse `I/N`, or `auto/N` taking `I` from `env(JOB_COMPLETION_INDEX)` or
    /// `env(SLURM_ARRAY_TASK_ID)`; the error is one line naming the flag.
    ///
    /// ```
    /// use sightline_runtime::Shard;
    /// assert_eq!(Shard::parse("2/8", |_| None).unwrap(), Shard { index: 2, count: 8 });
    /// let env = |k: &str| (k == "SLURM_ARRAY_TASK_ID").then(|| "3".to_string());
    /// assert_eq!(Shard::parse("auto/4", env).unwrap(), Shard { index: 3, count: 4 });
    /// assert!(Shard::parse("4/4", |_| None).is_err());
    /// ```
    pub fn parse(s: &str, env: impl Fn(&str) -> Option<String>) -> Result<Shard, RuntimeError> {
        let bad = |m: String| RuntimeError::Invalid(format!("--shard {s}: {m}"));
        let (i, n) = s
            .split_once('/')
            .ok_or_else(|| bad("expected I/N or auto/N".into()))?;
        let count: u32 = n
            .trim()
            .parse()
            .map_err(|_| bad(format!("'{n}' is not a shard count")))?;
        let index: u32 = if i.trim() == "auto" {
            let (var, v) = SHARD_ENV
                .iter()
                .find_map(|k| env(k).map(|v| (*k, v)))
                .ok_or_else(|| {
                    bad(format!(
                        "auto needs {} or {} in the environment",
                        SHARD_ENV[0], SHARD_ENV[1]
                    ))
                })?;
            v.trim()
                .parse()
                .map_err(|_| bad(format!("{var}='{v}' is not a shard index")))?
        } else {
            i.trim()
                .parse()
                .map_err(|_| bad(format!("'{i}' is not a shard index")))?
        };
        let shard = Shard { index, count };
        shard
            .validate()
            .map_err(|_| bad(format!("need 0 <= I < N, got {index}/{count}")))?;
        Ok(shard)
    }

    /// An error unless `0 <= index < count`.
    pub fn validate(&self) -> Result<(), RuntimeError> {
        if self.count == 0 || self.index >= self.count {
            return corrupt(format!("bad shard {}/{}", self.index, self.count));
        }
        Ok(())
    }

    /// Whether cell `cell` belongs to this shard.
    pub fn owns(&self, cell: usize) -> bool {
        cell as u64 % self.count as u64 == self.index as u64
    }
}

impl CellTable {
    /// Check a decoded table against the header (untrusted input).
    pub(crate) fn validate(&self, header: &Header, data_len: u64) -> Result<(), RuntimeError> {
        let bad = |m: String| corrupt(format!("cell table: {m}"));
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
            if be.offset.saturating_add(be.len as u64) > data_len {
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

    /// Every cell's box, checked.
    pub(crate) fn cells(&self) -> Result<Vec<[f64; 6]>, RuntimeError> {
        let n = self.boxes[0].len();
        (0..n)
            .map(|i| {
                let a: [f64; 6] = std::array::from_fn(|k| self.boxes[k][i]);
                if valid_box(&a) {
                    Ok(a)
                } else if a.iter().any(|v| !v.is_finite()) {
                    corrupt(format!("cell {i}: coordinates must be finite"))
                } else {
                    corrupt(format!(
                        "cell {i}: box is inverted (need x0<x1, y0<y1, z0<=z1)"
                    ))
                }
            })
            .collect()
    }
}

impl GridIndex {
    /// Check a decoded grid against the cell count (untrusted input).
    pub(crate) fn validate(&self, cell_count: usize) -> Result<(), RuntimeError> {
        let bad = |m: &str| corrupt(format!("spatial index: {m}"));
        let g = &self.buckets;
        let all_finite = g.origin.iter().chain(&g.step).all(|v| v.is_finite());
        if !all_finite || g.step[0] <= 0.0 || g.step[1] <= 0.0 {
            return bad("bad origin or step");
        }
        let n = (g.nx as u64) * (g.ny as u64);
        if g.nx == 0 || g.ny == 0 || self.offsets.len() as u64 != n + 1 {
            return bad("bucket count does not match the grid size");
        }
        if self.offsets[0] != 0
            || self.offsets.windows(2).any(|w| w[0] > w[1])
            || *self.offsets.last().unwrap_or(&0) as usize != self.items.len()
        {
            return bad("bucket offsets are not monotone");
        }
        if self.items.iter().any(|&i| i as usize >= cell_count) {
            return bad("bucket refers to a cell that does not exist");
        }
        Ok(())
    }

    /// The bucket of `(x, y)`: `floor((p - origin) / step)`, clamped to the grid.
    pub(crate) fn bucket_of(&self, x: f64, y: f64) -> (u32, u32) {
        let g = &self.buckets;
        let along = |v: f64, o: f64, s: f64, n: u32| {
            let b = ((v - o) / s).floor();
            if b.is_nan() || b < 0.0 {
                0
            } else {
                (b as u64).min(n as u64 - 1) as u32
            }
        };
        (
            along(x, g.origin[0], g.step[0], g.nx),
            along(y, g.origin[1], g.step[1], g.ny),
        )
    }

    /// The cells listed in bucket `(bx, by)`, ascending.
    pub(crate) fn bucket(&self, bx: u32, by: u32) -> &[u32] {
        let b = (by * self.buckets.nx + bx) as usize;
        &self.items[self.offsets[b] as usize..self.offsets[b + 1] as usize]
    }
}

impl ShapeTable {
    /// Check a decoded table against the cell count (untrusted input).
    pub(crate) fn validate(&self, cell_count: usize) -> Result<(), RuntimeError> {
        let bad = |m: &str| corrupt(format!("cell shapes: {m}"));
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
        if self.boxes.iter().any(|b| !valid_box(b)) {
            return bad("a voxel box is not a valid box");
        }
        Ok(())
    }
}

impl LeafTable {
    /// Decode every set into one flat array with `stored + 1` offsets, checking it
    /// against the stored cell count (untrusted input).
    pub(crate) fn decode(&self, stored: usize) -> Result<(Vec<u32>, Vec<u32>), RuntimeError> {
        let bad = |m: &str| RuntimeError::Corrupt(format!("visible leaves: {m}"));
        if self.sets.len() != stored {
            return Err(bad("one set per stored cell expected"));
        }
        let mut offsets = Vec::with_capacity(stored + 1);
        let mut flat = Vec::with_capacity(self.sets.iter().map(Vec::len).sum());
        offsets.push(0u32);
        for gaps in &self.sets {
            let mut prev = 0u32;
            for (i, &g) in gaps.iter().enumerate() {
                if i > 0 && g == 0 {
                    return Err(bad("a set is not strictly ascending"));
                }
                prev = if i == 0 {
                    g
                } else {
                    prev.checked_add(g)
                        .ok_or_else(|| bad("a leaf number overflows"))?
                };
                flat.push(prev);
            }
            let end = u32::try_from(flat.len()).map_err(|_| bad("too many leaves"))?;
            offsets.push(end);
        }
        Ok((offsets, flat))
    }
}
