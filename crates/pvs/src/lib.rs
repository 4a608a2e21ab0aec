//! PVS store of sightline: batch build with a checkpoint journal, the `.pvs` file
//! format, point queries, shards and merge.
//!
//! * [`build()`](build::build) runs any [`VisibilityMethod`](sightline_methods::VisibilityMethod)
//!   over every viewcell in parallel, appends each finished cell to a checksummed journal
//!   (so `--resume` after a crash recomputes nothing and loses nothing) and writes the
//!   final file atomically.
//! * [`mod@format`] encodes the cells' sets as *delta-PVS* (Durand et al. 2000, §6.1: key
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

//!
//! Modules depend on each other in one direction only: `crc`, `error` and `index` are
//! leaves; `delta` → `format` → `journal`, `query` → `shard` (merge),
//! `stored` and `build`.

pub mod build;
mod crc;
pub mod delta;
mod error;
pub mod format;
pub mod index;
pub mod journal;
mod leaves;
pub mod query;
mod shapes;
pub mod shard;
mod stored;

pub use build::{build, BuildOptions, BuildStats};
pub use crc::{crc32, Crc32};
pub use error::PvsError;
pub use format::{Header, FORMAT_VERSION, FORMAT_VERSION_BOXES, MAGIC};
pub use query::PvsFile;
pub use shard::merge;
pub use sightline_runtime::{Shard, SHARD_ENV};
pub use stored::StoredPvs;
