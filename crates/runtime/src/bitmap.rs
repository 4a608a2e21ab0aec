//! Decoding a serialized roaring bitmap ([RoaringFormatSpec], both cookies: with and
//! without run containers) straight into a sorted `u32` list, and the symmetric
//! difference of two sorted lists: a row of a `.pvs` decodes with no allocation once
//! the caller's buffers have grown to the row's size.
//!
//! The checks are those of `roaring::RoaringBitmap::deserialize_from`: known cookie, at
//! most 65,536 containers, container keys ascending, array containers strictly
//! ascending, a bitmap container's population equal to its stated cardinality, run
//! containers non-empty, non-overlapping and not adjacent. Trailing bytes are ignored.
//!
//! [RoaringFormatSpec]: https://github.com/RoaringBitmap/RoaringFormatSpec

const SERIAL_COOKIE_NO_RUNCONTAINER: u32 = 12346;
const SERIAL_COOKIE: u16 = 12347;
const NO_OFFSET_THRESHOLD: usize = 4;
const ARRAY_LIMIT: usize = 4096;
const BITMAP_BYTES: usize = 8192;

/// Why a payload is not a roaring bitmap.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadBitmap(pub &'static str);

impl std::fmt::Display for BadBitmap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0)
    }
}

struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], BadBitmap> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.bytes.len())
            .ok_or(BadBitmap("failed to fill whole buffer"))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u16(&mut self) -> Result<u16, BadBitmap> {
        let b = self.take(2)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }
    fn u32(&mut self) -> Result<u32, BadBitmap> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
}

/// The ids of the serialized bitmap `bytes` into `out` (cleared first), ascending.
pub fn decode_into(bytes: &[u8], out: &mut Vec<u32>) -> Result<(), BadBitmap> {
    out.clear();
    decode_with(bytes, |v| out.push(v))
}

/// Call `f` with each id of the serialized bitmap `bytes`, ascending (on an error, `f`
/// may have seen some of them).
pub fn decode_with(bytes: &[u8], mut f: impl FnMut(u32)) -> Result<(), BadBitmap> {
    let mut r = Reader { bytes, at: 0 };
    let cookie = r.u32()?;
    let (size, has_offsets, runs) = if cookie == SERIAL_COOKIE_NO_RUNCONTAINER {
        (r.u32()? as usize, true, None)
    } else if cookie as u16 == SERIAL_COOKIE {
        let size = ((cookie >> 16) + 1) as usize;
        let runs = r.take(size.div_ceil(8))?;
        (size, size >= NO_OFFSET_THRESHOLD, Some(runs))
    } else {
        return Err(BadBitmap("unknown cookie value"));
    };
    if size > u16::MAX as usize + 1 {
        return Err(BadBitmap("size is greater than supported"));
    }
    let descriptions = r.take(size * 4)?;
    if has_offsets {
        r.take(size * 4)?;
    }
    let mut last_key: Option<u16> = None;
    for i in 0..size {
        let d = &descriptions[i * 4..i * 4 + 4];
        let key = u16::from_le_bytes([d[0], d[1]]);
        if last_key.replace(key).is_some_and(|last| key <= last) {
            return Err(BadBitmap("container keys are not sorted"));
        }
        let cardinality = u16::from_le_bytes([d[2], d[3]]) as usize + 1;
        let high = (key as u32) << 16;
        let is_run = runs.is_some_and(|bm| bm[i / 8] & (1 << (i % 8)) != 0);
        if is_run {
            let n = r.u16()? as usize;
            if n == 0 {
                return Err(BadBitmap("run container with zero runs"));
            }
            let runs = r.take(n * 4)?;
            let mut last_end: Option<u16> = None;
            for k in 0..n {
                let s = u16::from_le_bytes([runs[4 * k], runs[4 * k + 1]]);
                let len = u16::from_le_bytes([runs[4 * k + 2], runs[4 * k + 3]]);
                let end = s.checked_add(len).ok_or(BadBitmap("bad run"))?;
                if last_end
                    .replace(end)
                    .is_some_and(|last| s <= last.saturating_add(1))
                {
                    return Err(BadBitmap("runs overlap or touch"));
                }
                (s as u32..=end as u32).for_each(|v| f(high | v));
            }
        } else if cardinality <= ARRAY_LIMIT {
            let values = r.take(cardinality * 2)?;
            let mut prev: Option<u16> = None;
            for v in values.chunks_exact(2) {
                let v = u16::from_le_bytes([v[0], v[1]]);
                if prev.replace(v).is_some_and(|p| v <= p) {
                    return Err(BadBitmap("array container is not strictly ascending"));
                }
                f(high | v as u32);
            }
        } else {
            let words = r.take(BITMAP_BYTES)?;
            let word = |b: &[u8]| u64::from_le_bytes(std::array::from_fn(|k| b[k]));
            let ones: usize = words
                .chunks_exact(8)
                .map(|b| word(b).count_ones() as usize)
                .sum();
            if ones != cardinality {
                return Err(BadBitmap("bitmap cardinality does not match"));
            }
            for (w, b) in words.chunks_exact(8).enumerate() {
                let mut bits = word(b);
                while bits != 0 {
                    f(high | (w as u32 * 64 + bits.trailing_zeros()));
                    bits &= bits - 1;
                }
            }
        }
    }
    Ok(())
}

/// `out = a xor b` for sorted lists without duplicates (`out` cleared first).
pub fn symmetric_difference(a: &[u32], b: &[u32], out: &mut Vec<u32>) {
    out.clear();
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => {
                out.push(a[i]);
                i += 1;
            }
            std::cmp::Ordering::Greater => {
                out.push(b[j]);
                j += 1;
            }
            std::cmp::Ordering::Equal => {
                i += 1;
                j += 1;
            }
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
}
