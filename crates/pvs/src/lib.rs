//! PVS store of sightline: batch build with a checkpoint journal, the `.pvs` file
//! format (SPEC §6), point queries, shards and merge.
//!
//! * [`build()`](build::build) runs any [`VisibilityMethod`](sightline_methods::VisibilityMethod)
//!   over every viewcell in parallel, appends each finished cell to a checksummed journal
//!   (so `--resume` after a crash recomputes nothing and loses nothing) and writes the
//!   final file atomically.
//! * [`format`] encodes the cells' sets as *delta-PVS* (Durand et al. 2000, §6.1: key
//!   cells stored whole, every other cell as its difference with a neighbouring cell),
//!   roaring bitmaps compressed with zstd in small blocks, a checksum per section and
//!   per block. The layout is documented in `docs/pvs-format.md`.
//! * [`PvsFile`] opens a file, keeps its cell table and spatial index, and decodes only
//!   the cell that is asked for.
//! * [`shard`] builds a deterministic 1/N of the cells and merges shard files into a
//!   file byte-identical to a whole build.
//!
//! ```
//! use sightline_pvs::{format::{encode, Header}, PvsFile};
//! use sightline_geom::{ViewCell, DVec3};
//! let cells: Vec<ViewCell> = vec!["0,0,1.5,10,10,2".parse().unwrap(), "10,0,1.5,20,10,2".parse().unwrap()];
//! let sets = vec![vec![0, 2, 5], vec![0, 2, 6]];
//! let header = Header::new(0xfeed, "all", vec![], 10, cells.len());
//! let bytes = encode(&header, &cells, &[0, 1], &sets).unwrap();
//! let file = PvsFile::from_bytes(bytes).unwrap();
//! let (cell, visible) = file.query(DVec3::new(15.0, 5.0, 1.7)).unwrap().unwrap();
//! assert_eq!(cell, cells[1]);
//! assert_eq!(visible, vec![0, 2, 6]);
//! ```

pub mod build;
mod crc;
pub mod delta;
pub mod format;
pub mod index;
pub mod journal;
pub mod query;
pub mod shard;

pub use build::{build, BuildOptions, BuildStats};
pub use crc::{crc32, Crc32};
pub use format::{Header, FORMAT_VERSION, MAGIC};
pub use query::PvsFile;
pub use shard::{merge, Shard};

use sightline_methods::MethodError;

/// Everything that can go wrong reading, writing or building a `.pvs`.
#[derive(Debug, thiserror::Error)]
pub enum PvsError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("not a sightline .pvs file (bad magic number)")]
    NotPvs,
    #[error("unsupported .pvs format version {0} (this sightline reads version {FORMAT_VERSION})")]
    Version(u16),
    #[error("truncated .pvs file: {0}")]
    Truncated(String),
    #[error("corrupted .pvs file: {0}")]
    Corrupt(String),
    #[error("this PVS was built for another scene (file fingerprint {file:016x}, scene fingerprint {scene:016x})")]
    SceneMismatch { file: u64, scene: u64 },
    #[error("corrupted journal {path}: {message}")]
    Journal { path: String, message: String },
    #[error("cannot merge: {0}")]
    Merge(String),
    #[error("cell {index} {cell:?}: {source}")]
    Method {
        index: usize,
        cell: [f64; 6],
        source: MethodError,
    },
    #[error("{0}")]
    Invalid(String),
}

impl PvsError {
    pub(crate) fn io(path: &std::path::Path, source: std::io::Error) -> Self {
        PvsError::Io {
            path: path.display().to_string(),
            source,
        }
    }
}
