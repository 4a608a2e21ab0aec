//! The tile-level PVS: per viewcell, the tiles holding a potentially visible object and
//! the feature ids of those objects in each tile — the `sightline-pvs.json` sidecar
//! next to `tileset.json` (format field by field in `docs/3d-tiles.md`).
//!
//! Guarantee: it is exactly the image of the object PVS under the object → (tile,
//! feature) placement of the [`Layout`], so if the object PVS is conservative (holds
//! every object visible from the cell) the tile set holds every tile with a visible
//! feature. A client that loads these tiles misses nothing the object PVS would draw.

use crate::layout::Layout;
use crate::TilesError;
use serde::{Deserialize, Serialize};
use sightline_geom::{DVec3, ViewCell};
use std::collections::BTreeMap;

/// File name of the sidecar.
pub const SIDECAR_FILE: &str = "sightline-pvs.json";
/// `format` member of the sidecar.
pub const SIDECAR_FORMAT: &str = "sightline-tile-pvs";
/// The sidecar version this code writes and reads.
pub const SIDECAR_VERSION: u32 = 1;

/// One tile with content, as the sidecar lists it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SidecarTile {
    /// Content URI, relative to `tileset.json`.
    pub uri: String,
    /// Bounding box `[x0, y0, z0, x1, y1, z1]` in the tileset frame (the scene's).
    #[serde(rename = "box")]
    pub bounds: [f64; 6],
    /// Object ids by feature id (`objects[f]` is the object of feature `f`).
    pub objects: Vec<u32>,
}

/// The tile PVS of one viewcell.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SidecarCell {
    /// The cell's index in the `.pvs` it came from.
    pub index: u32,
    /// `[x0, y0, z0, x1, y1, z1]`.
    #[serde(rename = "box")]
    pub bounds: [f64; 6],
    /// Indices into [`Sidecar::tiles`], ascending.
    pub tiles: Vec<u32>,
    /// Per entry of `tiles`, the potentially visible feature ids of that tile, ascending.
    pub features: Vec<Vec<u32>>,
}

/// The whole sidecar.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sidecar {
    pub format: String,
    pub version: u32,
    /// The tileset these tiles belong to, relative to the sidecar.
    pub tileset: String,
    /// `Scene::fingerprint()` (16 hex digits) of the scene of the tileset and the PVS.
    pub scene_fingerprint: String,
    /// Method of the object PVS.
    pub method: String,
    pub objects: u32,
    pub tiles: Vec<SidecarTile>,
    pub cells: Vec<SidecarCell>,
}

impl Sidecar {
    /// The sidecar of `layout` from the object PVS of each cell (`(index, cell, ids)`).
    pub fn build(
        layout: &Layout,
        fingerprint: u64,
        method: &str,
        cells: impl IntoIterator<Item = (usize, ViewCell, Vec<u32>)>,
    ) -> Result<Sidecar, TilesError> {
        // Content tiles get consecutive sidecar indices in layout order.
        let mut sidecar_index = vec![u32::MAX; layout.tiles.len()];
        let mut tiles = Vec::new();
        for t in layout.content_tiles() {
            let tile = &layout.tiles[t];
            sidecar_index[t] = tiles.len() as u32;
            let b = tile.bounds;
            tiles.push(SidecarTile {
                uri: tile.content_uri().unwrap_or_default(),
                bounds: [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z],
                objects: tile.objects.clone(),
            });
        }
        let mut out = Vec::new();
        for (index, cell, ids) in cells {
            let mut by_tile: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
            for id in ids {
                let Some(p) = layout.placement.get(id as usize) else {
                    return Err(TilesError::Refused(format!(
                        "cell {index}: object {id} is not in the scene ({} objects): the PVS belongs to another scene",
                        layout.placement.len()
                    )));
                };
                by_tile
                    .entry(sidecar_index[p.tile as usize])
                    .or_default()
                    .push(p.feature);
            }
            let (tiles, mut features): (Vec<u32>, Vec<Vec<u32>>) = by_tile.into_iter().unzip();
            features.iter_mut().for_each(|f| f.sort_unstable());
            out.push(SidecarCell {
                index: index as u32,
                bounds: cell.to_array(),
                tiles,
                features,
            });
        }
        Ok(Sidecar {
            format: SIDECAR_FORMAT.into(),
            version: SIDECAR_VERSION,
            tileset: crate::export::TILESET_FILE.into(),
            scene_fingerprint: format!("{fingerprint:016x}"),
            method: method.into(),
            objects: layout.placement.len() as u32,
            tiles,
            cells: out,
        })
    }

    /// Parse and check a sidecar: format, version, every index in range.
    pub fn from_slice(bytes: &[u8]) -> Result<Sidecar, TilesError> {
        let s: Sidecar = serde_json::from_slice(bytes)
            .map_err(|e| TilesError::Refused(format!("invalid {SIDECAR_FILE}: {e}")))?;
        if s.format != SIDECAR_FORMAT || s.version != SIDECAR_VERSION {
            return Err(TilesError::Refused(format!(
                "{SIDECAR_FILE}: format '{}' version {} (expected '{SIDECAR_FORMAT}' version {SIDECAR_VERSION})",
                s.format, s.version
            )));
        }
        for c in &s.cells {
            if c.tiles.len() != c.features.len() {
                return Err(TilesError::Refused(format!(
                    "{SIDECAR_FILE}: cell {} lists {} tiles but {} feature lists",
                    c.index,
                    c.tiles.len(),
                    c.features.len()
                )));
            }
            for (&t, f) in c.tiles.iter().zip(&c.features) {
                let Some(tile) = s.tiles.get(t as usize) else {
                    return Err(TilesError::Refused(format!(
                        "{SIDECAR_FILE}: cell {} names tile {t} of {}",
                        c.index,
                        s.tiles.len()
                    )));
                };
                if let Some(bad) = f.iter().find(|&&f| f as usize >= tile.objects.len()) {
                    return Err(TilesError::Refused(format!(
                        "{SIDECAR_FILE}: cell {} names feature {bad} of tile {t}, which has {}",
                        c.index,
                        tile.objects.len()
                    )));
                }
            }
        }
        Ok(s)
    }

    /// The cell containing `p` (the first one, as cells of a grid only share faces).
    pub fn locate(&self, p: DVec3) -> Option<&SidecarCell> {
        self.cells.iter().find(|c| {
            let b = c.bounds;
            (0..3).all(|k| p[k] >= b[k] && p[k] <= b[k + 3])
        })
    }
}
