//! Batch build: every viewcell through a [`VisibilityMethod`], in parallel, each finished
//! cell appended to the [`journal`](crate::journal) before the final `.pvs` is written
//! atomically (temporary file, `fsync`, rename).
//!
//! The output depends only on the scene, the method, its parameters, the cells and the
//! shard: the journal's order (thread scheduling, interruptions) never reaches the file,
//! so a resumed build is byte-identical to an uninterrupted one.

use crate::crc::Crc32;
use crate::error::PvsError;
use crate::format::{encode_bitmaps, Header};
use crate::journal::{Journal, JournalKey};
use rayon::prelude::*;
use roaring::RoaringBitmap;
use sightline_geom::ViewCell;
use sightline_methods::{MethodError, VisibilityMethod};
use sightline_runtime::Shard;
use sightline_scene::Scene;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Options of [`build`].
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// Continue from the journal of an interrupted build (a fresh build when there is none).
    pub resume: bool,
    /// Build only this shard of the cells.
    pub shard: Option<Shard>,
    /// `fsync` the journal after this many cells...
    pub sync_every: usize,
    /// ...or after this much time.
    pub sync_interval: Duration,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            resume: false,
            shard: None,
            sync_every: 256,
            sync_interval: Duration::from_secs(2),
        }
    }
}

/// What a build did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildStats {
    /// Cells of this build (of the shard, if any).
    pub cells: usize,
    /// Cells taken from the journal.
    pub resumed: usize,
    /// Cells computed now.
    pub computed: usize,
    /// Size of the written file.
    pub bytes: u64,
    pub compute_seconds: f64,
    pub encode_seconds: f64,
}

/// The journal kept next to `out` while it is being built.
pub fn journal_path(out: &Path) -> PathBuf {
    let mut s = out.as_os_str().to_owned();
    s.push(".journal");
    PathBuf::from(s)
}

fn temp_path(out: &Path) -> PathBuf {
    let mut s = out.as_os_str().to_owned();
    s.push(".tmp");
    PathBuf::from(s)
}

fn cells_crc(cells: &[ViewCell]) -> u32 {
    cells
        .iter()
        .fold(Crc32::new(), |c, cell| {
            cell.to_array()
                .iter()
                .fold(c, |c, v| c.update(&v.to_le_bytes()))
        })
        .finish()
}

/// Build the `.pvs` of `cells` with `method` into `out`. `progress(done, total)` is
/// called once at the start and after every finished cell (from worker threads).
pub fn build(
    scene: &Scene,
    method: &dyn VisibilityMethod,
    cells: &[ViewCell],
    out: &Path,
    opts: &BuildOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<BuildStats, PvsError> {
    if cells.is_empty() {
        return Err(PvsError::Invalid("no cells to build".into()));
    }
    let objects = u32::try_from(scene.objects.len())
        .map_err(|_| PvsError::Invalid("more than 2^32 objects".into()))?;
    let cell_count =
        u32::try_from(cells.len()).map_err(|_| PvsError::Invalid("more than 2^32 cells".into()))?;
    let mut header = Header::new(
        scene.fingerprint(),
        method.name(),
        method.params(),
        objects as usize,
        cell_count as usize,
    );
    header.shard = opts.shard;
    let key = JournalKey {
        header: header.clone(),
        cells_crc: cells_crc(cells),
    };
    let mine: Vec<usize> = (0..cells.len())
        .filter(|&i| opts.shard.is_none_or(|s| s.owns(i)))
        .collect();
    if mine.is_empty() {
        return Err(PvsError::Invalid(
            "this shard has no cells (more shards than cells)".into(),
        ));
    }

    // The journal: resume it or start afresh.
    let jpath = journal_path(out);
    let mut results: Vec<Option<RoaringBitmap>> = vec![None; cells.len()];
    let mut resumed = 0;
    let mut journal = if opts.resume && jpath.exists() {
        let (j, records) = Journal::resume(&jpath, &key)?;
        for (cell, set) in records {
            let slot = &mut results[cell as usize];
            if mine.binary_search(&(cell as usize)).is_err() {
                return Err(PvsError::Journal {
                    path: jpath.display().to_string(),
                    message: format!("cell {cell} does not belong to this build"),
                });
            }
            if slot.is_none() {
                resumed += 1;
            }
            *slot = Some(set);
        }
        j
    } else if jpath.exists() {
        return Err(PvsError::Invalid(format!(
            "{} exists (an interrupted build): pass --resume to continue it, or delete it",
            jpath.display()
        )));
    } else {
        Journal::create(&jpath, &key)?
    };
    journal.set_sync_policy(opts.sync_every, opts.sync_interval);

    let pending: Vec<usize> = mine
        .iter()
        .copied()
        .filter(|&i| results[i].is_none())
        .collect();
    let total = mine.len();
    let done = AtomicUsize::new(total - pending.len());
    progress(total - pending.len(), total);

    let t0 = Instant::now();
    let journal = Mutex::new(journal);
    let slots: Vec<Mutex<Option<RoaringBitmap>>> = results.into_iter().map(Mutex::new).collect();
    let outcome = pending.par_iter().try_for_each(|&i| -> Result<(), PvsError> {
        let method_err = |source: MethodError| PvsError::Method {
            index: i,
            cell: cells[i].to_array(),
            source,
        };
        let ids = method.pvs(&cells[i]).map_err(method_err)?;
        let set = RoaringBitmap::from_sorted_iter(ids.iter().copied())
            .ok()
            .filter(|s| s.max().is_none_or(|m| m < objects))
            .ok_or_else(|| {
                method_err(MethodError::Other(format!(
                    "method {} returned ids that are unsorted, repeated or beyond the {objects} objects",
                    method.name()
                )))
            })?;
        journal
            .lock()
            .map_err(|_| PvsError::Invalid("journal lock poisoned".into()))?
            .append(i as u32, &set)?;
        if let Ok(mut slot) = slots[i].lock() {
            *slot = Some(set);
        }
        progress(done.fetch_add(1, Ordering::Relaxed) + 1, total);
        Ok(())
    });
    let mut journal = journal
        .into_inner()
        .map_err(|_| PvsError::Invalid("journal lock poisoned".into()))?;
    journal.sync()?;
    outcome?;
    let compute_seconds = t0.elapsed().as_secs_f64();

    let t1 = Instant::now();
    let mut sets = Vec::with_capacity(mine.len());
    for &i in &mine {
        let set = slots[i]
            .lock()
            .ok()
            .and_then(|mut s| s.take())
            .ok_or_else(|| PvsError::Invalid(format!("cell {i} has no result")))?;
        sets.push(set);
    }
    let present: Vec<u32> = mine.iter().map(|&i| i as u32).collect();
    let bytes = encode_bitmaps(&header, cells, &present, &sets)?;
    write_atomic(out, &bytes)?;
    drop(journal);
    std::fs::remove_file(&jpath).map_err(|e| PvsError::io(&jpath, e))?;
    Ok(BuildStats {
        cells: mine.len(),
        resumed,
        computed: pending.len(),
        bytes: bytes.len() as u64,
        compute_seconds,
        encode_seconds: t1.elapsed().as_secs_f64(),
    })
}

/// Write `bytes` to `out` so that `out` is either absent/old or complete: a temporary
/// file in the same folder, `fsync`, rename, `fsync` of the folder.
pub fn write_atomic(out: &Path, bytes: &[u8]) -> Result<(), PvsError> {
    let tmp = temp_path(out);
    let mut f = std::fs::File::create(&tmp).map_err(|e| PvsError::io(&tmp, e))?;
    f.write_all(bytes).map_err(|e| PvsError::io(&tmp, e))?;
    f.sync_all().map_err(|e| PvsError::io(&tmp, e))?;
    drop(f);
    std::fs::rename(&tmp, out).map_err(|e| PvsError::io(out, e))?;
    let dir = out
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}
