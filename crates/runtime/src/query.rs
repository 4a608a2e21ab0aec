//! The reusable scratch of queries: decoded data blocks (a walk stays in one
//! neighbourhood, so its cells' blocks are decoded once) and the buffers rows are
//! decoded into. Once warm, a query allocates nothing.

use crate::error::RuntimeError;

/// Decoded blocks kept by default, oldest dropped first, up to this many bytes.
pub const DEFAULT_CACHE_BYTES: usize = 64 << 20;

/// Evicted block buffers kept for reuse.
const MAX_SPARE: usize = 4;

/// Scratch for queries on one [`Pvs`](crate::Pvs) at a time (using it with another
/// file empties its cache). One per thread; cheap to keep, costly only in the blocks it
/// caches.
pub struct Query {
    pub(crate) file: u64,
    pub(crate) blocks: Vec<(u32, Vec<u8>)>,
    /// Buffers of evicted blocks, reused by the next decompression.
    pub(crate) spare: Vec<Vec<u8>>,
    cache_bytes: usize,
    dctx: Option<zstd::bulk::Decompressor<'static>>,
    pub(crate) payload: Vec<u32>,
    pub(crate) xor: Vec<u32>,
    pub(crate) row: Vec<u32>,
    pub(crate) other: Vec<u32>,
    pub(crate) marks: Vec<u64>,
}

impl Default for Query {
    fn default() -> Self {
        Self::new()
    }
}

impl Query {
    /// A scratch that caches up to [`DEFAULT_CACHE_BYTES`] of decoded blocks.
    pub fn new() -> Query {
        Self::with_cache_bytes(DEFAULT_CACHE_BYTES)
    }

    /// A scratch that caches up to `bytes` of decoded blocks (at least one block).
    pub fn with_cache_bytes(bytes: usize) -> Query {
        Query {
            file: 0,
            blocks: Vec::new(),
            spare: Vec::new(),
            cache_bytes: bytes,
            dctx: None,
            payload: Vec::new(),
            xor: Vec::new(),
            row: Vec::new(),
            other: Vec::new(),
            marks: Vec::new(),
        }
    }

    /// Bind the scratch to file `id`, dropping another file's blocks.
    pub(crate) fn attach(&mut self, id: u64) {
        if self.file != id {
            let blocks = std::mem::take(&mut self.blocks);
            self.spare.extend(blocks.into_iter().map(|(_, b)| b));
            self.file = id;
        }
    }

    /// A buffer for a block of `len` bytes, evicting the oldest blocks while the cache
    /// would exceed its budget.
    pub(crate) fn evict_for(&mut self, len: usize) -> Vec<u8> {
        let mut total: usize = self.blocks.iter().map(|(_, b)| b.len()).sum::<usize>() + len;
        while total > self.cache_bytes && !self.blocks.is_empty() {
            let (_, b) = self.blocks.remove(0);
            total -= b.len();
            self.spare.push(b);
        }
        // The spare buffer that fits best: the smallest large enough, else the largest.
        let best = (0..self.spare.len())
            .filter(|&k| self.spare[k].capacity() >= len)
            .min_by_key(|&k| self.spare[k].capacity())
            .or_else(|| (0..self.spare.len()).max_by_key(|&k| self.spare[k].capacity()));
        let buf = match best {
            Some(k) => self.spare.swap_remove(k),
            None => Vec::new(),
        };
        self.spare.truncate(MAX_SPARE);
        buf
    }

    pub(crate) fn dctx(&mut self) -> Result<&mut zstd::bulk::Decompressor<'static>, RuntimeError> {
        if self.dctx.is_none() {
            let d = zstd::bulk::Decompressor::new()
                .map_err(|e| RuntimeError::Invalid(format!("zstd: {e}")))?;
            self.dctx = Some(d);
        }
        // Just set above when it was missing.
        self.dctx
            .as_mut()
            .ok_or_else(|| RuntimeError::Invalid("zstd context".into()))
    }
}
