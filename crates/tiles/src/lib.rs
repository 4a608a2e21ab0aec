//! OGC 3D Tiles 1.1 for sightline: a scene as a tileset whose features are the scene's
//! objects, and the object PVS of each viewcell turned into the tiles a client must
//! load there (documented in `docs/3d-tiles.md`).
//!
//! * [`layout`] — the explicit quadtree of tiles, one object per feature of one tile;
//! * [`glb`] — the GLB content of a tile (`EXT_mesh_features` feature ids,
//!   `EXT_structural_metadata` object ids and names);
//! * [`export`] — the tileset folder, written atomically;
//! * [`pvs`] — the tile-level PVS sidecar `sightline-pvs.json`;
//! * [`sse`] — the screen-space-error refinement a plain 3D Tiles client does, as a
//!   model for benchmarks.
//!
//! Reading tilesets back into a scene is a scene importer
//! ([`sightline_scene::import::tileset`]), so every command loads a `tileset.json`.
//!
//! ```
//! use sightline_scene::{Object, Scene};
//! use sightline_tiles::layout::Layout;
//! let scene = Scene::from_objects((0..10).map(|i| {
//!     let x = 20.0 * i as f64;
//!     Object::rect_block(x, 0.0, x + 10.0, 10.0, 8.0)
//! }).collect());
//! let layout = Layout::build(&scene, 4).unwrap();
//! assert!(layout.content_tiles().all(|t| layout.tiles[t].objects.len() <= 4));
//! let json = sightline_tiles::export::tileset_json(&layout);
//! assert_eq!(json["asset"]["version"], "1.1");
//! ```

pub mod export;
pub mod glb;
pub mod layout;
pub mod pvs;
pub mod sse;

pub use sightline_scene::import::tileset as import;

/// Why a tileset or sidecar cannot be written or read.
#[derive(Debug, thiserror::Error)]
pub enum TilesError {
    #[error("{path}: {source}")]
    Io {
        path: String,
        source: std::io::Error,
    },
    #[error("{0}")]
    Refused(String),
    #[error(transparent)]
    Pvs(#[from] sightline_pvs::PvsError),
}

/// The sidecar of `layout` from every stored cell of a `.pvs` built for `scene`.
pub fn sidecar_from_pvs(
    scene: &sightline_scene::Scene,
    layout: &layout::Layout,
    file: &sightline_pvs::PvsFile,
) -> Result<pvs::Sidecar, TilesError> {
    file.check_scene(scene)?;
    let cells = file.iter().collect::<Result<Vec<_>, _>>()?;
    pvs::Sidecar::build(layout, scene.fingerprint(), &file.header().method, cells)
}
