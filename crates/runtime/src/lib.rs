//! The read-only runtime of sightline's `.pvs` files, for engines and game code, and the
//! one reader of the format: `sightline-pvs`'s `PvsFile` is built on it, and [`wire`]
//! holds the format's structs that `sightline-pvs` writes. Once a [`Query`] scratch is
//! warm a query allocates nothing.
//!
//! * [`Pvs`] opens a file from bytes or a path (memory-mapped with the `mmap`
//!   feature), checks every table against untrusted bytes, and answers: the
//!   cell holding a point ([`Pvs::locate`], any cell kind: boxes, BSP leaves, voxel
//!   cells; the lowest index on shared faces), a cell's sorted visible ids
//!   ([`Pvs::visible`], delta rows decoded against their references), its visible leaves,
//!   its prefetch neighbours, and a mesh level's source objects.
//! * [`gameplay`] derives cell-to-cell queries from the rows: `can_see`, the cells that
//!   can see a point, the secondary PVS, with the guarantee each gives.
//!
//! Dependencies: zstd, postcard, serde, crc32fast (and memmap2 with `mmap`); no
//! threads, no scene code. The format is documented in `docs/pvs-format.md`.
//!
//! ```
//! # fn demo(bytes: Vec<u8>) -> Result<(), sightline_runtime::RuntimeError> {
//! use sightline_runtime::{Pvs, Query};
//! let pvs = Pvs::from_vec(bytes)?;
//! let mut q = Query::new();
//! let mut row = Vec::new();
//! if let Some(cell) = pvs.locate([15.0, 5.0, 1.7]) {
//!     pvs.visible_into(&mut q, cell, &mut row)?; // no allocation once `row` has grown
//!     let mut around = Vec::new();
//!     pvs.neighbours_into(cell, &mut around);
//!     for &n in &around {
//!         let _prefetch = pvs.visible(&mut q, n)?;
//!     }
//! }
//! # Ok(()) }
//! ```

pub mod bitmap;
mod error;
mod file;
pub mod gameplay;
mod json;
mod query;
pub mod wire;

pub use error::RuntimeError;
pub use file::{CellKind, Pvs};
pub use gameplay::CellRelation;
pub use query::{Query, DEFAULT_CACHE_BYTES};
pub use wire::{Header, Shard, FORMAT_VERSION, FORMAT_VERSION_BOXES, MAGIC, SHARD_ENV};
