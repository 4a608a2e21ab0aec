//! Writing a tileset folder: `tileset.json`, `tiles/L-X-Y.glb`, and optionally the
//! tile-level PVS sidecar ([`crate::pvs`]).
//!
//! The folder is built next to its destination under a temporary name and renamed into
//! place at the end, so a failed or interrupted export never leaves a half-written
//! tileset. An existing destination is replaced only if it is empty or holds a
//! `tileset.json` (a previous export); anything else is refused.

use crate::glb::tile_glb;
use crate::layout::{Layout, Tile};
use crate::TilesError;
use serde_json::{json, Value};
use sightline_scene::Scene;
use std::path::{Path, PathBuf};

/// File name of the tileset.
pub const TILESET_FILE: &str = "tileset.json";

/// What an export wrote.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ExportStats {
    pub tiles: usize,
    pub content_tiles: usize,
    pub features: usize,
    /// Bytes of every file written (tileset, contents, sidecar).
    pub bytes: u64,
    /// Bytes of each content tile, by tile index (0 for tiles without content).
    #[serde(skip)]
    pub content_bytes: Vec<u64>,
}

/// The `tileset.json` of a layout (scene frame = tileset frame: no root transform, the
/// scene has no geographic placement).
pub fn tileset_json(layout: &Layout) -> Value {
    fn tile(layout: &Layout, t: &Tile) -> Value {
        let c = t.bounds.center();
        let h = t.bounds.size() / 2.0;
        let mut v = json!({
            "boundingVolume": { "box": [c.x, c.y, c.z, h.x, 0.0, 0.0, 0.0, h.y, 0.0, 0.0, 0.0, h.z] },
            "geometricError": t.geometric_error,
            "refine": "ADD",
        });
        if let Some(uri) = t.content_uri() {
            v["content"] = json!({ "uri": uri });
        }
        if !t.children.is_empty() {
            v["children"] = Value::Array(
                t.children
                    .iter()
                    .map(|&c| tile(layout, &layout.tiles[c]))
                    .collect(),
            );
        }
        v
    }
    let root = &layout.tiles[0];
    json!({
        "asset": { "version": "1.1", "generator": "sightline" },
        "geometricError": root.geometric_error,
        "root": tile(layout, root),
    })
}

/// Write the tileset of `scene` (tiled by `layout`) to the folder `out`, plus the
/// `extra` files (name, bytes) such as the PVS sidecar.
pub fn write(
    scene: &Scene,
    layout: &Layout,
    out: &Path,
    extra: &[(&str, Vec<u8>)],
) -> Result<ExportStats, TilesError> {
    let io = |path: &Path| {
        let p = path.display().to_string();
        move |source| TilesError::Io { path: p, source }
    };
    if out.exists() && !replaceable(out) {
        return Err(TilesError::Refused(format!(
            "{} exists and is not a tileset folder (no {TILESET_FILE}); not overwriting it",
            out.display()
        )));
    }
    let tmp = sibling(out, "tmp");
    if tmp.exists() {
        std::fs::remove_dir_all(&tmp).map_err(io(&tmp))?;
    }
    let result = (|| {
        std::fs::create_dir_all(tmp.join("tiles")).map_err(io(&tmp))?;
        let mut stats = ExportStats {
            tiles: layout.tiles.len(),
            content_tiles: 0,
            features: 0,
            bytes: 0,
            content_bytes: vec![0; layout.tiles.len()],
        };
        for t in layout.content_tiles() {
            let tile = &layout.tiles[t];
            let Some(uri) = tile.content_uri() else {
                continue;
            };
            let glb = tile_glb(scene, &tile.objects, tile.bounds.center());
            let path = tmp.join(&uri);
            std::fs::write(&path, &glb).map_err(io(&path))?;
            stats.content_tiles += 1;
            stats.features += tile.objects.len();
            stats.content_bytes[t] = glb.len() as u64;
            stats.bytes += glb.len() as u64;
        }
        let json = serde_json::to_vec_pretty(&tileset_json(layout))
            .map_err(|e| TilesError::Refused(format!("cannot encode {TILESET_FILE}: {e}")))?;
        let path = tmp.join(TILESET_FILE);
        std::fs::write(&path, &json).map_err(io(&path))?;
        stats.bytes += json.len() as u64;
        for (name, bytes) in extra {
            let path = tmp.join(name);
            std::fs::write(&path, bytes).map_err(io(&path))?;
            stats.bytes += bytes.len() as u64;
        }
        Ok(stats)
    })();
    let stats = match result {
        Ok(s) => s,
        Err(e) => {
            let _ = std::fs::remove_dir_all(&tmp);
            return Err(e);
        }
    };
    // Swap in: the old folder moves aside first, so `out` is always either the old or
    // the new tileset.
    let old = sibling(out, "old");
    if out.exists() {
        if old.exists() {
            std::fs::remove_dir_all(&old).map_err(io(&old))?;
        }
        std::fs::rename(out, &old).map_err(io(out))?;
    }
    std::fs::rename(&tmp, out).map_err(io(out))?;
    if old.exists() {
        std::fs::remove_dir_all(&old).map_err(io(&old))?;
    }
    Ok(stats)
}

fn replaceable(dir: &Path) -> bool {
    dir.is_dir()
        && (dir.join(TILESET_FILE).is_file()
            || std::fs::read_dir(dir).is_ok_and(|mut d| d.next().is_none()))
}

/// `out` with `.{what}{pid}` appended to its last component (same parent: rename works).
fn sibling(out: &Path, what: &str) -> PathBuf {
    let name = out
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "tileset".into());
    out.with_file_name(format!(".{name}.{what}{}", std::process::id()))
}
