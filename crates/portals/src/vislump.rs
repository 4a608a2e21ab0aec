//! The visibility lump of a Quake BSP file, written as the engine reads it.
//!
//! * **Rows.** Leaf `l` (`1 ..= visleafs`) has a row of `ceil(visleafs / 8)` bytes, bit
//!   `j` (byte `j / 8`, bit `j % 8`) standing for leaf `j + 1`. A row is stored
//!   compressed: a non-zero byte as itself, a run of `n` zero bytes (1 ≤ n ≤ 255) as
//!   `0, n` (id's `CompressRow`, the engine's `Mod_DecompressVis`). Identical compressed
//!   rows are stored once and shared (first occurrence wins, so the lump is
//!   deterministic).
//! * **Offsets.** Each leaf `1 ..= visleafs` gets its row's offset in `visofs` (the
//!   second `i32` of the leaf record in BSP29, BSP2 and 2PSB alike); leaf 0 and leaves
//!   beyond `visleafs` (brush models' leaves) are left as they are.
//! * **File.** The 15 lumps are written in the order of their offsets in the input
//!   (qbsp's order), each at a 4-byte aligned offset with zero padding; the header's
//!   offsets and lengths are rewritten. Every lump other than the visibility and leaf
//!   lumps is copied byte for byte; the leaf lump differs only in the `visofs` fields.
//!   A BSPX extension block (magic `BSPX` right after the last lump) is moved along and
//!   its lump offsets shifted; trailing zero padding is dropped; any other trailing
//!   data is refused (it could hold offsets we cannot fix).
//!
//! Guarantee: [`write_vis`] never panics; it returns a [`VisLumpError`] for a file whose
//! header, lumps or leaves are malformed, for rows of the wrong number, or for a lump
//! that would exceed the format's limits.

/// BSP format versions that hold a leaf PVS the same way.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BspFormat {
    /// Quake's version 29.
    Bsp29,
    /// `BSP2` (float bounds, 32-bit indices).
    Bsp2,
    /// `2PSB` (RMQ's first 32-bit variant, short bounds).
    Bsp2Rmq,
}

impl BspFormat {
    /// The format of a file from its first four bytes.
    pub fn detect(data: &[u8]) -> Option<BspFormat> {
        match data.get(..4)? {
            [29, 0, 0, 0] => Some(BspFormat::Bsp29),
            b"BSP2" => Some(BspFormat::Bsp2),
            b"2PSB" => Some(BspFormat::Bsp2Rmq),
            _ => None,
        }
    }

    /// Size of a leaf record.
    pub fn leaf_size(self) -> usize {
        match self {
            BspFormat::Bsp29 => 28,
            BspFormat::Bsp2 => 44,
            BspFormat::Bsp2Rmq => 32,
        }
    }

    /// Most leaves the format can index: BSP29 nodes hold a leaf as an `i16` child
    /// `-(leaf + 1) >= -32,768`, so 32,768 leaves; the 32-bit formats, `i32::MAX`.
    pub fn max_leaves(self) -> usize {
        match self {
            BspFormat::Bsp29 => 32_768,
            _ => i32::MAX as usize,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            BspFormat::Bsp29 => "BSP29",
            BspFormat::Bsp2 => "BSP2",
            BspFormat::Bsp2Rmq => "2PSB",
        }
    }
}

const LUMPS: usize = 15;
const VISIBILITY: usize = 4;
const LEAVES: usize = 10;
const MODELS: usize = 14;
const HEADER: usize = 4 + 8 * LUMPS;

/// Why the lump cannot be written.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum VisLumpError {
    #[error("BSP: {0}")]
    Format(String),
    #[error("BSP: {0}")]
    Limit(String),
}

fn fmt_err(m: impl Into<String>) -> VisLumpError {
    VisLumpError::Format(m.into())
}

fn i32_at(d: &[u8], o: usize) -> Option<i32> {
    Some(i32::from_le_bytes(
        d.get(o..o.checked_add(4)?)?.try_into().ok()?,
    ))
}

/// The lump directory of a BSP file: its format and each lump's `(offset, length)`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Lumps {
    pub format: BspFormat,
    pub lumps: [(usize, usize); LUMPS],
}

impl Lumps {
    /// Read and check the header: every lump inside the file.
    pub fn read(data: &[u8]) -> Result<Lumps, VisLumpError> {
        let format = match BspFormat::detect(data) {
            Some(f) => f,
            None => {
                return Err(match i32_at(data, 0) {
                    None => fmt_err("file too short for a header"),
                    Some(v) => {
                        fmt_err(format!("version {v} is not a Quake BSP (29, BSP2 or 2PSB)"))
                    }
                })
            }
        };
        let mut lumps = [(0, 0); LUMPS];
        for (i, l) in lumps.iter_mut().enumerate() {
            let o = i32_at(data, 4 + 8 * i).ok_or_else(|| fmt_err("truncated lump directory"))?;
            let n = i32_at(data, 8 + 8 * i).ok_or_else(|| fmt_err("truncated lump directory"))?;
            if o < 0 || n < 0 || (o as usize).saturating_add(n as usize) > data.len() {
                return Err(fmt_err(format!(
                    "lump {i} (offset {o}, length {n}) lies outside the file ({} bytes)",
                    data.len()
                )));
            }
            if n > 0 && (o as usize) < HEADER {
                return Err(fmt_err(format!("lump {i} overlaps the header")));
            }
            *l = (o as usize, n as usize);
        }
        Ok(Lumps { format, lumps })
    }

    pub fn lump<'a>(&self, data: &'a [u8], i: usize) -> &'a [u8] {
        let (o, n) = self.lumps[i];
        &data[o..o + n]
    }

    /// `visleafs` of model 0 and the number of leaf records, checked.
    pub fn leaf_counts(&self, data: &[u8]) -> Result<(usize, usize), VisLumpError> {
        let size = self.format.leaf_size();
        let leaves = self.lump(data, LEAVES);
        if !leaves.len().is_multiple_of(size) {
            return Err(fmt_err(format!(
                "the leaf lump has {} bytes, not a multiple of {size}",
                leaves.len()
            )));
        }
        let n = leaves.len() / size;
        let models = self.lump(data, MODELS);
        // visleafs is the 5th i32 after the model's bounds and origin (36 bytes) in
        // every Quake 1 format.
        let visleafs = i32_at(models, 36 + 16).ok_or_else(|| fmt_err("no world model"))?;
        if visleafs < 0 || visleafs as usize >= n.max(1) {
            return Err(fmt_err(format!(
                "model 0 has {visleafs} visleafs but the file has {n} leaves"
            )));
        }
        if n > self.format.max_leaves() {
            return Err(VisLumpError::Limit(format!(
                "{n} leaves exceed {}'s limit of {}",
                self.format.name(),
                self.format.max_leaves()
            )));
        }
        Ok((visleafs as usize, n))
    }
}

/// Bytes of an uncompressed row for `visleafs` leaves.
pub fn row_bytes(visleafs: usize) -> usize {
    visleafs.div_ceil(8)
}

/// Compress a row as Quake does: zero bytes as `0, run` with runs of at most 255.
pub fn compress_row(row: &[u8]) -> Vec<u8> {
    let mut out = Vec::with_capacity(row.len());
    let mut j = 0;
    while j < row.len() {
        let b = row[j];
        out.push(b);
        j += 1;
        if b != 0 {
            continue;
        }
        let mut run = 1u8;
        while j < row.len() && row[j] == 0 && run < 255 {
            run += 1;
            j += 1;
        }
        out.push(run);
    }
    out
}

/// Decompress the row at `offset` of `lump` into `row_bytes` bytes, as the engine's
/// `Mod_DecompressVis` does; `None` if the lump ends first or a run overshoots.
pub fn decompress_row(lump: &[u8], offset: usize, row_bytes: usize) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(row_bytes);
    let mut i = offset;
    while out.len() < row_bytes {
        let b = *lump.get(i)?;
        i += 1;
        if b != 0 {
            out.push(b);
            continue;
        }
        let run = *lump.get(i)? as usize;
        i += 1;
        if run == 0 || out.len() + run > row_bytes {
            return None;
        }
        out.resize(out.len() + run, 0);
    }
    Some(out)
}

/// The row of a set of visible leaves (`1 ..= visleafs`; others ignored).
pub fn row_of(leaves: impl IntoIterator<Item = u32>, visleafs: usize) -> Vec<u8> {
    let mut row = vec![0u8; row_bytes(visleafs)];
    for l in leaves {
        if l >= 1 && (l as usize) <= visleafs {
            let j = l as usize - 1;
            row[j >> 3] |= 1 << (j & 7);
        }
    }
    row
}

/// A new visibility lump from uncompressed rows (`rows[l - 1]` for leaf `l`), and each
/// leaf's offset into it. Identical compressed rows are shared.
pub fn build_lump(rows: &[Vec<u8>]) -> (Vec<u8>, Vec<i32>) {
    let mut lump = Vec::new();
    let mut offsets = Vec::with_capacity(rows.len());
    let mut seen: std::collections::HashMap<Vec<u8>, i32> = std::collections::HashMap::new();
    for row in rows {
        let c = compress_row(row);
        let o = *seen.entry(c).or_insert_with_key(|c| {
            let o = lump.len() as i32;
            lump.extend_from_slice(c);
            o
        });
        offsets.push(o);
    }
    (lump, offsets)
}

/// `data` (a BSP file) with its visibility lump replaced by `rows` (one uncompressed
/// row of `ceil(visleafs / 8)` bytes per leaf `1 ..= visleafs`) and the leaves'
/// `visofs` pointing into it; see the module doc for what is kept byte for byte.
pub fn write_vis(data: &[u8], rows: &[Vec<u8>]) -> Result<Vec<u8>, VisLumpError> {
    let dir = Lumps::read(data)?;
    let (visleafs, _) = dir.leaf_counts(data)?;
    if rows.len() != visleafs {
        return Err(fmt_err(format!(
            "{} rows for {visleafs} visleafs",
            rows.len()
        )));
    }
    let rb = row_bytes(visleafs);
    if let Some(r) = rows.iter().position(|r| r.len() != rb) {
        return Err(fmt_err(format!(
            "row of leaf {} has {} bytes, expected {rb}",
            r + 1,
            rows[r].len()
        )));
    }
    let (vis, offsets) = build_lump(rows);
    if vis.len() > i32::MAX as usize / 2 {
        return Err(VisLumpError::Limit(format!(
            "a visibility lump of {} bytes is too large",
            vis.len()
        )));
    }
    let mut leaves = dir.lump(data, LEAVES).to_vec();
    let size = dir.format.leaf_size();
    for (k, o) in offsets.iter().enumerate() {
        let at = (k + 1) * size + 4;
        leaves[at..at + 4].copy_from_slice(&o.to_le_bytes());
    }

    // Lumps in their order in the input file; at one offset, empty lumps first, then
    // by index (so that writing the output again keeps its order).
    let mut order: Vec<usize> = (0..LUMPS).collect();
    order.sort_by_key(|&i| (dir.lumps[i].0, dir.lumps[i].1 > 0, i));
    let end = dir
        .lumps
        .iter()
        .map(|&(o, n)| o + n)
        .max()
        .unwrap_or(HEADER)
        .max(HEADER);
    let bspx_at = end.next_multiple_of(4);
    let trailing = data.get(bspx_at..).unwrap_or(&[]);
    let bspx = if data.len() > end && !data[end..bspx_at.min(data.len())].iter().all(|&b| b == 0) {
        return Err(fmt_err(
            "unknown data between the last lump and the end of the file",
        ));
    } else if trailing.iter().all(|&b| b == 0) {
        None // nothing, or padding
    } else if trailing.starts_with(b"BSPX") {
        Some(trailing)
    } else {
        return Err(fmt_err(format!(
            "{} bytes of unknown data after the last lump (not a BSPX block)",
            trailing.len()
        )));
    };

    let mut out = vec![0u8; HEADER];
    out[..4].copy_from_slice(&data[..4]);
    let mut new_dir = [(0usize, 0usize); LUMPS];
    for &i in &order {
        let bytes: &[u8] = match i {
            VISIBILITY => &vis,
            LEAVES => &leaves,
            _ => dir.lump(data, i),
        };
        let at = out.len();
        new_dir[i] = (at, bytes.len());
        out.extend_from_slice(bytes);
        out.resize(out.len().next_multiple_of(4), 0);
    }
    if let Some(b) = bspx {
        let shift = out.len() as i64 - bspx_at as i64;
        let moved = shift_bspx(b, bspx_at, shift)?;
        out.extend_from_slice(&moved);
    }
    if out.len() > i32::MAX as usize {
        return Err(VisLumpError::Limit("the file would exceed 2 GiB".into()));
    }
    for (i, (o, n)) in new_dir.iter().enumerate() {
        out[4 + 8 * i..8 + 8 * i].copy_from_slice(&(*o as i32).to_le_bytes());
        out[8 + 8 * i..12 + 8 * i].copy_from_slice(&(*n as i32).to_le_bytes());
    }
    Ok(out)
}

/// A BSPX block (`"BSPX"`, `u32 count`, then `count` × {name [24], u32 offset, u32
/// length}, offsets absolute in the file) that moved by `shift` bytes from `at`: its
/// lump offsets shifted. Every BSPX lump must lie after the block's start.
fn shift_bspx(b: &[u8], at: usize, shift: i64) -> Result<Vec<u8>, VisLumpError> {
    let mut out = b.to_vec();
    let n = i32_at(b, 4).ok_or_else(|| fmt_err("truncated BSPX header"))? as u32 as usize;
    if n > b.len() / 32 {
        return Err(fmt_err(format!("BSPX block claims {n} lumps")));
    }
    for k in 0..n {
        let e = 8 + 32 * k;
        let o = i32_at(b, e + 24).ok_or_else(|| fmt_err("truncated BSPX header"))? as u32;
        let len = i32_at(b, e + 28).ok_or_else(|| fmt_err("truncated BSPX header"))? as u32;
        let (o, len) = (o as usize, len as usize);
        if o < at || o.saturating_add(len) > at + b.len() {
            return Err(fmt_err(format!(
                "BSPX lump {k} lies outside the BSPX block"
            )));
        }
        let new = (o as i64 + shift) as u32;
        out[e + 24..e + 28].copy_from_slice(&new.to_le_bytes());
    }
    Ok(out)
}

/// The leaves' `visofs` and the visibility lump of a BSP file (any of the three
/// formats): what an engine reads back. Row `l - 1` is leaf `l`'s decompressed row, or
/// `None` when its offset is negative or does not decode.
pub fn read_rows(data: &[u8]) -> Result<Vec<Option<Vec<u8>>>, VisLumpError> {
    let dir = Lumps::read(data)?;
    let (visleafs, _) = dir.leaf_counts(data)?;
    let leaves = dir.lump(data, LEAVES);
    let vis = dir.lump(data, VISIBILITY);
    let size = dir.format.leaf_size();
    let rb = row_bytes(visleafs);
    Ok((1..=visleafs)
        .map(|l| {
            let o = i32_at(leaves, l * size + 4)?;
            usize::try_from(o)
                .ok()
                .and_then(|o| decompress_row(vis, o, rb))
        })
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_compress_as_quake_does() {
        assert_eq!(compress_row(&[1, 0, 0, 0, 2]), vec![1, 0, 3, 2]);
        assert_eq!(compress_row(&[0]), vec![0, 1]);
        let long = vec![0u8; 300];
        assert_eq!(compress_row(&long), vec![0, 255, 0, 45]);
        for row in [vec![0u8; 300], vec![1, 0, 0, 7, 0], vec![255; 3]] {
            let c = compress_row(&row);
            assert_eq!(decompress_row(&c, 0, row.len()).unwrap(), row);
        }
        assert_eq!(decompress_row(&[0, 9], 0, 3), None);
        assert_eq!(decompress_row(&[0, 0], 0, 3), None);
    }

    #[test]
    fn identical_rows_are_shared() {
        let (lump, offs) = build_lump(&[vec![1, 0], vec![2, 0], vec![1, 0]]);
        assert_eq!(lump, vec![1, 0, 1, 2, 0, 1]);
        assert_eq!(offs, vec![0, 3, 0]);
    }

    #[test]
    fn row_bits_are_leaf_minus_one() {
        assert_eq!(row_of([1, 8, 9, 0, 100], 9), vec![0b1000_0001, 0b1]);
    }
}
