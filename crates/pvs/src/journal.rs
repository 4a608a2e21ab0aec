//! The checkpoint journal of a build: an append-only file of finished cells, so that a
//! build killed at any moment (`kill -9`, power loss) resumes without recomputing or
//! losing a finished cell.
//!
//! ```text
//! header   magic "SLJRNL\0\n" | version u16 | key_len u32 | postcard(JournalKey) | crc32(key)
//! record   payload_len u32 | cell u32 | crc32(payload_len, cell) u32 | roaring payload | crc32(payload) u32
//! ```
//!
//! A record is written with one `write` call and the file is `fsync`ed in batches. On
//! resume, a *torn* last record (cut short, or all zeros as left by a power loss) is
//! dropped and the file is truncated before appending; any other damage is an error,
//! since silently dropping finished cells in the middle would hide a real problem.

use crate::crc::{crc32, Crc32};
use crate::error::PvsError;
use crate::format::Header;
use roaring::RoaringBitmap;
use serde::{Deserialize, Serialize};
use std::fs::{File, OpenOptions};
use std::io::{Read, Seek, SeekFrom, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

pub const JOURNAL_MAGIC: [u8; 8] = *b"SLJRNL\0\n";
pub const JOURNAL_VERSION: u16 = 1;
const RECORD_HEAD: usize = 12;
/// A set can never take more than this many bytes (2^32 ids as a roaring bitmap).
const MAX_PAYLOAD: u32 = 1 << 30;

/// What a journal belongs to: resuming with anything else is refused.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct JournalKey {
    pub header: Header,
    /// CRC-32 of the cells' coordinates.
    pub cells_crc: u32,
}

/// The journal of one build, open for appending.
pub struct Journal {
    file: File,
    path: PathBuf,
    unsynced: usize,
    last_sync: Instant,
    sync_every: usize,
    sync_interval: Duration,
}

fn jerr(path: &Path, message: impl Into<String>) -> PvsError {
    PvsError::Journal {
        path: path.display().to_string(),
        message: message.into(),
    }
}

impl Journal {
    /// Start a new journal (replacing any file at `path`).
    pub fn create(path: &Path, key: &JournalKey) -> Result<Journal, PvsError> {
        let mut file = File::create(path).map_err(|e| PvsError::io(path, e))?;
        let key_bytes = postcard::to_stdvec(key).map_err(|e| PvsError::Invalid(e.to_string()))?;
        let mut head = Vec::new();
        head.extend_from_slice(&JOURNAL_MAGIC);
        head.extend_from_slice(&JOURNAL_VERSION.to_le_bytes());
        head.extend_from_slice(&(key_bytes.len() as u32).to_le_bytes());
        head.extend_from_slice(&key_bytes);
        head.extend_from_slice(&crc32(&key_bytes).to_le_bytes());
        file.write_all(&head).map_err(|e| PvsError::io(path, e))?;
        file.sync_all().map_err(|e| PvsError::io(path, e))?;
        Ok(Self::wrap(file, path))
    }

    fn wrap(file: File, path: &Path) -> Journal {
        Journal {
            file,
            path: path.to_path_buf(),
            unsynced: 0,
            last_sync: Instant::now(),
            sync_every: 256,
            sync_interval: Duration::from_secs(2),
        }
    }

    /// Sync after this many records or this much time, whichever comes first.
    pub fn set_sync_policy(&mut self, every: usize, interval: Duration) {
        self.sync_every = every.max(1);
        self.sync_interval = interval;
    }

    /// Open an existing journal of the same build: its finished cells, and the journal
    /// ready to append (a torn last record removed).
    pub fn resume(
        path: &Path,
        key: &JournalKey,
    ) -> Result<(Journal, Vec<(u32, RoaringBitmap)>), PvsError> {
        let mut file = OpenOptions::new()
            .read(true)
            .write(true)
            .open(path)
            .map_err(|e| PvsError::io(path, e))?;
        let mut bytes = Vec::new();
        file.read_to_end(&mut bytes)
            .map_err(|e| PvsError::io(path, e))?;
        let (found, records, good_len) = parse(path, &bytes)?;
        if &found != key {
            return Err(jerr(
                path,
                "it belongs to another build (scene, method, parameters, cells or shard differ); delete it or build without --resume",
            ));
        }
        if good_len < bytes.len() {
            file.set_len(good_len as u64)
                .map_err(|e| PvsError::io(path, e))?;
            file.sync_all().map_err(|e| PvsError::io(path, e))?;
        }
        file.seek(SeekFrom::Start(good_len as u64))
            .map_err(|e| PvsError::io(path, e))?;
        Ok((Self::wrap(file, path), records))
    }

    /// Append one finished cell (one `write` call; synced in batches).
    pub fn append(&mut self, cell: u32, set: &RoaringBitmap) -> Result<(), PvsError> {
        let mut rec = Vec::with_capacity(RECORD_HEAD + set.serialized_size() + 4);
        rec.extend_from_slice(&(set.serialized_size() as u32).to_le_bytes());
        rec.extend_from_slice(&cell.to_le_bytes());
        let hc = crc32(&rec);
        rec.extend_from_slice(&hc.to_le_bytes());
        set.serialize_into(&mut rec)
            .map_err(|e| PvsError::io(&self.path, e))?;
        let pc = crc32(&rec[RECORD_HEAD..]);
        rec.extend_from_slice(&pc.to_le_bytes());
        self.file
            .write_all(&rec)
            .map_err(|e| PvsError::io(&self.path, e))?;
        self.unsynced += 1;
        if self.unsynced >= self.sync_every || self.last_sync.elapsed() >= self.sync_interval {
            self.sync()?;
        }
        Ok(())
    }

    /// Flush finished records to disk.
    pub fn sync(&mut self) -> Result<(), PvsError> {
        if self.unsynced > 0 {
            self.file
                .sync_data()
                .map_err(|e| PvsError::io(&self.path, e))?;
            self.unsynced = 0;
        }
        self.last_sync = Instant::now();
        Ok(())
    }
}

/// A parsed journal: its key, its finished cells, and the length of its intact prefix.
pub type Parsed = (JournalKey, Vec<(u32, RoaringBitmap)>, usize);

/// Parse a whole journal.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<Parsed, PvsError> {
    if bytes.len() < 14 || bytes[..8] != JOURNAL_MAGIC {
        return Err(jerr(
            path,
            "not a sightline build journal (bad magic or too short)",
        ));
    }
    let version = u16::from_le_bytes([bytes[8], bytes[9]]);
    if version != JOURNAL_VERSION {
        return Err(jerr(path, format!("unsupported journal version {version}")));
    }
    let key_len = u32::from_le_bytes([bytes[10], bytes[11], bytes[12], bytes[13]]) as usize;
    let key_end = 14usize.saturating_add(key_len);
    if key_end.saturating_add(4) > bytes.len() {
        return Err(jerr(path, "truncated journal header"));
    }
    let key_bytes = &bytes[14..key_end];
    let stored = u32::from_le_bytes([
        bytes[key_end],
        bytes[key_end + 1],
        bytes[key_end + 2],
        bytes[key_end + 3],
    ]);
    if crc32(key_bytes) != stored {
        return Err(jerr(path, "checksum mismatch in the journal header"));
    }
    let key: JournalKey = postcard::from_bytes(key_bytes)
        .map_err(|e| jerr(path, format!("bad journal header: {e}")))?;
    let mut records = Vec::new();
    let mut pos = key_end + 4;
    while pos < bytes.len() {
        let rest = &bytes[pos..];
        if rest.len() < RECORD_HEAD {
            break; // torn header
        }
        let len = u32::from_le_bytes([rest[0], rest[1], rest[2], rest[3]]);
        let cell = u32::from_le_bytes([rest[4], rest[5], rest[6], rest[7]]);
        let hc = u32::from_le_bytes([rest[8], rest[9], rest[10], rest[11]]);
        if Crc32::new().update(&rest[..8]).finish() != hc || len > MAX_PAYLOAD {
            if rest.iter().all(|&b| b == 0) {
                break; // zero-filled tail of a power loss
            }
            return Err(jerr(
                path,
                format!("checksum mismatch in the record at byte {pos}"),
            ));
        }
        let end = RECORD_HEAD + len as usize + 4;
        if rest.len() < end {
            break; // torn payload
        }
        let payload = &rest[RECORD_HEAD..RECORD_HEAD + len as usize];
        let pc = u32::from_le_bytes(rest[end - 4..end].try_into().unwrap_or([0; 4]));
        let last = rest.len() == end;
        if crc32(payload) != pc {
            if last {
                break; // a damaged last record is recomputed
            }
            return Err(jerr(
                path,
                format!("checksum mismatch in the record of cell {cell} at byte {pos}"),
            ));
        }
        let set = RoaringBitmap::deserialize_from(payload).map_err(|e| {
            jerr(
                path,
                format!("bad record of cell {cell} at byte {pos}: {e}"),
            )
        })?;
        if cell >= key.header.cell_count || set.max().is_some_and(|m| m >= key.header.object_count)
        {
            return Err(jerr(path, format!("record at byte {pos} is out of range")));
        }
        records.push((cell, set));
        pos += end;
    }
    Ok((key, records, pos))
}
