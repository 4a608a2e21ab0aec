//! The PVS-driven 3D Tiles viewer (`sightline serve SCENE [PVS] --tiles DIR`): the
//! tileset folder written by `sightline tiles`, a page on 3DTilesRendererJS that loads
//! only the tiles of the current cell's tile-level PVS, and the endpoint it asks.
//!
//! * `GET /tiles/` — the viewer (`web/tiles/index.html`, bundle `web/tiles/viewer.bundle.js`
//!   built from npm `3d-tiles-renderer` and `three` by `crates/server/tiles-web`);
//! * `GET /tiles/data/PATH` — a file of the tileset folder. PATH is made of plain names
//!   (letters, digits, `.`, `-`, `_`), never `..`, and must resolve inside the folder
//!   after symbolic links: nothing else of the file system can be read;
//! * `GET /tiles/pvs?at=X,Y,Z` — the tile PVS of the cell holding the point, from the
//!   sidecar `sightline-pvs.json`: `{cell, box, tiles, features, neighbours}` (content
//!   URIs relative to `tileset.json`; `neighbours` are the tiles of the cells sharing a
//!   face, edge or corner, not already in `tiles`, to prefetch).
//!
//! The data and PVS routes go through the same token and rate-limit guard as `/api`.

use crate::limits::{guard, json_error};
use crate::AppState;
use axum::extract::{Path as UrlPath, RawQuery, State};
use axum::http::{header, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::routing::get;
use axum::{Json, Router};
use serde_json::json;
use sightline_geom::DVec3;
use sightline_tiles::pvs::{Sidecar, SIDECAR_FILE};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

const INDEX_HTML: &str = include_str!("../web/tiles/index.html");
const BUNDLE_JS: &str = include_str!("../web/tiles/viewer.bundle.js");

/// A served tileset folder and its tile PVS.
pub struct TilesState {
    /// Canonical folder of `tileset.json`.
    pub dir: PathBuf,
    pub sidecar: Option<Sidecar>,
}

impl TilesState {
    /// Open the folder `dir` (it must hold `tileset.json`); the sidecar, if present, must
    /// belong to the scene of `fingerprint`.
    pub fn open(dir: &Path, fingerprint: u64) -> Result<TilesState, String> {
        let dir = dir
            .canonicalize()
            .map_err(|e| format!("{}: {e}", dir.display()))?;
        if !dir.join("tileset.json").is_file() {
            return Err(format!("{}: no tileset.json", dir.display()));
        }
        let side = dir.join(SIDECAR_FILE);
        let sidecar = if side.is_file() {
            let bytes = std::fs::read(&side).map_err(|e| format!("{}: {e}", side.display()))?;
            let s = Sidecar::from_slice(&bytes).map_err(|e| e.to_string())?;
            let want = format!("{fingerprint:016x}");
            if s.scene_fingerprint != want {
                return Err(format!(
                    "{}: built for another scene (fingerprint {}, the served scene has {want})",
                    side.display(),
                    s.scene_fingerprint
                ));
            }
            Some(s)
        } else {
            None
        };
        Ok(TilesState { dir, sidecar })
    }

    /// The file of a request path, if it is a plain path inside the folder.
    pub fn file(&self, path: &str) -> Option<PathBuf> {
        let plain = |c: &str| {
            !c.is_empty()
                && c != "."
                && c != ".."
                && c.bytes()
                    .all(|b| b.is_ascii_alphanumeric() || b"._-".contains(&b))
        };
        if !path.split('/').all(plain) {
            return None;
        }
        let full = self.dir.join(path).canonicalize().ok()?;
        (full.starts_with(&self.dir) && full.is_file()).then_some(full)
    }
}

/// The `/tiles` routes (merge into [`crate::Server::router`] with
/// [`crate::Server::merge_routes`]).
pub fn router(app: Arc<AppState>, tiles: Arc<TilesState>) -> Router {
    let guarded = Router::new()
        .route("/tiles/data/{*path}", get(data))
        .route("/tiles/pvs", get(pvs))
        .with_state(tiles)
        .layer(axum::middleware::from_fn_with_state(app, guard));
    Router::new()
        .route(
            "/tiles/",
            get(|| async {
                (
                    [(header::CONTENT_TYPE, "text/html; charset=utf-8")],
                    INDEX_HTML,
                )
            }),
        )
        .route(
            "/tiles/viewer.bundle.js",
            get(|| async {
                (
                    [(header::CONTENT_TYPE, "text/javascript; charset=utf-8")],
                    BUNDLE_JS,
                )
            }),
        )
        .merge(guarded)
}

async fn data(State(t): State<Arc<TilesState>>, UrlPath(path): UrlPath<String>) -> Response {
    let Some(file) = t.file(&path) else {
        return json_error(StatusCode::NOT_FOUND, "no such tileset file");
    };
    let kind = match file.extension().and_then(|e| e.to_str()) {
        Some("json") => "application/json",
        Some("glb") => "model/gltf-binary",
        _ => "application/octet-stream",
    };
    match tokio::fs::read(&file).await {
        Ok(bytes) => ([(header::CONTENT_TYPE, kind)], bytes).into_response(),
        Err(_) => json_error(StatusCode::NOT_FOUND, "no such tileset file"),
    }
}

async fn pvs(State(t): State<Arc<TilesState>>, RawQuery(q): RawQuery) -> Response {
    let Some(sc) = &t.sidecar else {
        return json_error(
            StatusCode::NOT_FOUND,
            format!("the tileset has no {SIDECAR_FILE} (export it with `sightline tiles --pvs`)"),
        );
    };
    let Some(at) = crate::api::query_param(q.as_deref(), "at") else {
        return json_error(StatusCode::BAD_REQUEST, "missing parameter 'at=X,Y,Z'");
    };
    let v: Vec<f64> = at
        .split(',')
        .filter_map(|p| p.trim().parse().ok())
        .collect();
    let [x, y, z] = v[..] else {
        return json_error(StatusCode::BAD_REQUEST, "'at' must be X,Y,Z (3 numbers)");
    };
    let p = DVec3::new(x, y, z);
    if !p.is_finite() {
        return json_error(StatusCode::BAD_REQUEST, "'at' must be finite");
    }
    match cell_tiles(sc, p) {
        Some(v) => Json(v).into_response(),
        None => json_error(
            StatusCode::NOT_FOUND,
            format!("no cell of the tile PVS holds {x},{y},{z}"),
        ),
    }
}

/// The `/tiles/pvs` answer for the cell holding `p` (`None` outside every cell).
pub fn cell_tiles(sc: &Sidecar, p: DVec3) -> Option<serde_json::Value> {
    let cell = sc.locate(p)?;
    let own: BTreeSet<u32> = cell.tiles.iter().copied().collect();
    let b = cell.bounds;
    // Cells sharing a face, an edge or a corner in plan.
    let touches = |o: &[f64; 6]| (0..2).all(|k| o[k] <= b[k + 3] + 1e-6 && b[k] <= o[k + 3] + 1e-6);
    let neighbours: BTreeSet<u32> = sc
        .cells
        .iter()
        .filter(|c| c.index != cell.index && touches(&c.bounds))
        .flat_map(|c| c.tiles.iter().copied())
        .filter(|t| !own.contains(t))
        .collect();
    let uri = |t: &u32| sc.tiles[*t as usize].uri.clone();
    Some(json!({
        "cell": cell.index,
        "box": cell.bounds,
        "tiles": cell.tiles.iter().map(uri).collect::<Vec<_>>(),
        "features": cell.features,
        "neighbours": neighbours.iter().map(uri).collect::<Vec<_>>(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_plain_paths_inside_the_folder_are_served() {
        let d = tempfile::tempdir().unwrap();
        std::fs::create_dir(d.path().join("ts")).unwrap();
        std::fs::create_dir(d.path().join("ts/tiles")).unwrap();
        std::fs::write(d.path().join("ts/tileset.json"), "{}").unwrap();
        std::fs::write(d.path().join("ts/tiles/0-0-0.glb"), "x").unwrap();
        std::fs::write(d.path().join("secret"), "s").unwrap();
        let t = TilesState::open(&d.path().join("ts"), 0).unwrap();
        assert!(t.file("tileset.json").is_some());
        assert!(t.file("tiles/0-0-0.glb").is_some());
        for bad in [
            "../secret",
            "tiles/../../secret",
            "/etc/passwd",
            "tiles//x",
            "",
            "tiles",
            "a%2f..",
            "./tileset.json",
        ] {
            assert!(t.file(bad).is_none(), "{bad}");
        }
        #[cfg(unix)]
        {
            std::os::unix::fs::symlink(d.path().join("secret"), d.path().join("ts/link")).unwrap();
            assert!(t.file("link").is_none());
        }
        assert!(
            TilesState::open(d.path(), 0).is_err(),
            "a folder without tileset.json"
        );
    }

    #[test]
    fn a_cell_answers_its_tiles_and_its_neighbours_tiles() {
        use sightline_geom::ViewCell;
        use sightline_scene::{Object, Scene};
        let scene = Scene::from_objects(
            (0..6)
                .map(|i| {
                    let x = 30.0 * i as f64;
                    Object::rect_block(x, 0.0, x + 10.0, 10.0, 5.0)
                })
                .collect(),
        );
        let layout = sightline_tiles::layout::Layout::build(&scene, 1).unwrap();
        let cell = |x: f64| {
            ViewCell::new(DVec3::new(x, 20.0, 1.5), DVec3::new(x + 10.0, 30.0, 2.0)).unwrap()
        };
        // Three cells in a row: 0 sees objects 0 and 1, 1 sees 2, 2 (not touching 0) sees 5.
        let sc = Sidecar::build(
            &layout,
            scene.fingerprint(),
            "test",
            vec![
                (0, cell(0.0), vec![0, 1]),
                (1, cell(10.0), vec![2]),
                (2, cell(20.0), vec![5]),
            ],
        )
        .unwrap();
        let uri = |o: usize| {
            layout.tiles[layout.placement[o].tile as usize]
                .content_uri()
                .unwrap()
        };
        let v = cell_tiles(&sc, DVec3::new(5.0, 25.0, 1.7)).unwrap();
        assert_eq!(v["cell"], 0);
        assert_eq!(v["tiles"].as_array().unwrap().len(), 2);
        assert_eq!(v["neighbours"], json!([uri(2)]));
        let v = cell_tiles(&sc, DVec3::new(15.0, 25.0, 1.7)).unwrap();
        let mut n: Vec<String> = serde_json::from_value(v["neighbours"].clone()).unwrap();
        n.sort();
        let mut want = vec![uri(0), uri(1), uri(5)];
        want.sort();
        assert_eq!(n, want);
        assert!(cell_tiles(&sc, DVec3::new(500.0, 25.0, 1.7)).is_none());
    }
}
