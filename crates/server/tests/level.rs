//! A level served on its own cells ([`FileSource::cells`]): Quake's dm1, every open leaf a
//! convex cell, as `build dm1.bsp` stores them. The server knows nothing of portals, so
//! the `.pvs` here is built from the level's own visibility lump (the faces of the leaves
//! `vis` says a leaf sees): the sets differ from `portals-fast`'s, the cells and the
//! point location are the same.

mod common;

use common::*;
use sightline_core::Cell;
use sightline_geom::{DVec2, DVec3};
use sightline_pvs::format::{encode_cells_with_leaves, EncodeOptions};
use sightline_pvs::{Header, PvsFile};
use sightline_scene::import::bsp::{load_bsp, BspLevel};
use sightline_scene::Scene;
use sightline_server::source::{FileSource, PvsSource, SharedSource};
use sightline_server::{ServerConfig, ViewSettings};
use std::sync::Arc;

fn dm1() -> BspLevel {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../data/quake/dm1.bsp");
    load_bsp(std::path::Path::new(path)).unwrap()
}

struct Dm1 {
    level: BspLevel,
    scene: Arc<Scene>,
    cells: Vec<Cell>,
    file: PvsFile,
}

/// dm1 with the `.pvs` of its `vis` lump, held in memory.
fn dm1_served() -> (Dm1, FileSource) {
    let level = dm1();
    let scene = Arc::new(level.to_scene());
    let cells = sightline_portals::leaf_cells(&level);
    let leaves: Vec<Vec<u32>> = cells
        .iter()
        .map(|c| level.reference_row(c.id().unwrap()))
        .collect();
    let sets: Vec<roaring::RoaringBitmap> = leaves
        .iter()
        .map(|row| {
            row.iter()
                .flat_map(|&l| level.leaves[l as usize].faces.iter().copied())
                .collect()
        })
        .collect();
    let header = Header::new(scene.fingerprint(), "vis", vec![], scene.len(), cells.len());
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    let bytes = encode_cells_with_leaves(
        &header,
        &cells,
        &present,
        &sets,
        Some(&leaves),
        &EncodeOptions::default(),
    )
    .unwrap();
    let src = FileSource::cells(PvsFile::from_bytes(bytes.clone()).unwrap(), &scene)
        .unwrap()
        .in_memory();
    let file = PvsFile::from_bytes(bytes).unwrap();
    (
        Dm1 {
            level,
            scene,
            cells,
            file,
        },
        src,
    )
}

/// Points of open space on a coarse lattice over the level, with their leaf.
fn open_points(level: &BspLevel, step: f64) -> Vec<(DVec3, u32)> {
    let b = level.bounds;
    let mut out = vec![];
    let mut z = b.min.z + step / 2.0;
    while z < b.max.z {
        let mut y = b.min.y + step / 2.0;
        while y < b.max.y {
            let mut x = b.min.x + step / 2.0;
            while x < b.max.x {
                let p = DVec3::new(x, y, z);
                let leaf = level.point_leaf(p.to_array());
                if level.is_view_leaf(leaf) {
                    out.push((p, leaf));
                }
                x += step;
            }
            y += step;
        }
        z += step;
    }
    out
}

#[test]
fn points_are_located_in_the_leaf_the_tree_finds() {
    let (d, src) = dm1_served();
    assert_eq!(src.layout().kind(), "cells");
    assert_eq!(src.layout().len(), d.cells.len());
    assert_eq!(src.info().kind, "memory");
    let points = open_points(&d.level, 48.0);
    assert!(points.len() > 500, "{} open points", points.len());
    for (p, leaf) in points {
        let id = src.locate(p).unwrap();
        // Points on a face shared by two leaves may go to either: check the shape.
        let cell = &d.cells[id as usize];
        assert!(cell.contains(p), "{p} not in the cell it was located in");
        if cell.id() != Some(leaf) {
            let own = d.cells.iter().find(|c| c.id() == Some(leaf)).unwrap();
            assert!(own.contains(p));
        }
        assert_eq!(src.cell(id), Some(cell.bounds()));
    }
    // In a wall, outside, not finite.
    assert!(src.locate(DVec3::new(1e5, 0.0, 0.0)).is_err());
    assert!(src.locate(DVec3::new(f64::NAN, 0.0, 0.0)).is_err());
}

#[test]
fn a_step_across_a_cell_boundary_lands_in_a_neighbour() {
    let (d, src) = dm1_served();
    let mut crossings = 0;
    for (p, _) in open_points(&d.level, 64.0) {
        let a = src.locate(p).unwrap();
        let n = src.neighbours(a, DVec2::ZERO);
        assert!(!n.contains(&a));
        for dir in [DVec3::X, DVec3::Y, DVec3::NEG_X, DVec3::NEG_Y, DVec3::Z] {
            for k in 1..=8 {
                let q = p + dir * (4.0 * k as f64);
                let Ok(b) = src.locate(q) else { break };
                if b != a {
                    assert!(n.contains(&b), "cell {b} at {q} is not a neighbour of {a}");
                    crossings += 1;
                    break;
                }
            }
        }
    }
    assert!(crossings > 200, "{crossings} crossings");
    // Ahead first: the neighbours of a cell along +x start with one east of it.
    let (p, _) = open_points(&d.level, 64.0)[0];
    let a = src.locate(p).unwrap();
    let east = src.neighbours(a, DVec2::X);
    let here = src.cell(a).unwrap().center();
    if let Some(&first) = east.first() {
        let c = src.cell(first).unwrap().center();
        let last = src.cell(*east.last().unwrap()).unwrap().center();
        assert!(c.x - here.x >= last.x - here.x);
    }
}

fn level_config() -> ServerConfig {
    ServerConfig {
        view: ViewSettings {
            kind: "level",
            eye_height: 46.0,
            start: Some([-48.0, 1060.0, 142.0]),
        },
        ..Default::default()
    }
}

#[tokio::test]
async fn the_api_answers_the_file_on_the_levels_cells() {
    let (d, src) = dm1_served();
    let source: SharedSource = Arc::new(src);
    let s = TestServer::start(d.scene.clone(), source, level_config()).await;
    let (code, _, body) = http_get(s.addr, "/api/scene").await;
    assert_eq!(code, 200);
    let v: serde_json::Value = serde_json::from_slice(&body).unwrap();
    assert_eq!(v["layout"], "cells");
    assert_eq!(v["cells"], d.cells.len());
    assert!(v["grid"].is_null());
    assert_eq!(v["kind"], "level");
    assert_eq!(v["eye_height"], 46.0);
    assert_eq!(v["start"], serde_json::json!([-48.0, 1060.0, 142.0]));
    assert_eq!(v["source"], "memory");
    assert_eq!(v["method"], "vis");
    assert!(v["cell_scale"].as_f64().unwrap() > 10.0);

    // The player start: the PVS of its cell, as the file answers it.
    let p = DVec3::new(-48.0, 1060.0, 142.0);
    let (code, _, body) = http_get(s.addr, "/api/pvs?at=-48,1060,142").await;
    assert_eq!(code, 200, "{}", String::from_utf8_lossy(&body));
    let v: serde_json::Value = serde_json::from_slice(&body).unwrap();
    let i = d.file.locate(p).unwrap();
    assert_eq!(v["cell_id"], i);
    assert_eq!(d.cells[i].id(), Some(d.level.point_leaf(p.to_array())));
    let visible: Vec<u32> = serde_json::from_value(v["visible"].clone()).unwrap();
    assert_eq!(visible, d.file.pvs(i).unwrap());
    assert!(!visible.is_empty() && visible.len() < d.scene.len());

    // Inside a wall: a 400 with a JSON error.
    let (code, _, body) = http_get(s.addr, "/api/pvs?at=100000,0,0").await;
    assert_eq!(code, 400);
    assert!(String::from_utf8_lossy(&body).contains("no cell"));
    s.stop().await.unwrap();
}

#[tokio::test]
async fn a_walk_session_follows_the_walker_from_leaf_to_leaf() {
    let (d, src) = dm1_served();
    let source: SharedSource = Arc::new(src);
    let s = TestServer::start(d.scene.clone(), source, level_config()).await;
    let mut ws = ws_connect(s.addr, "").await;
    let mut client = ClientState::default();
    let welcome = ws_next(&mut ws).await.unwrap().unwrap();
    assert_eq!(welcome["layout"], "cells");
    // A walk through the level's open points in a row, one position report each.
    let walk: Vec<DVec3> = open_points(&d.level, 48.0)
        .into_iter()
        .map(|(p, _)| p)
        .filter(|p| (p.z - 72.0).abs() < 30.0)
        .take(40)
        .collect();
    assert!(walk.len() >= 10);
    let mut cells_seen = std::collections::BTreeSet::new();
    for (seq, p) in walk.iter().enumerate() {
        let want = d.file.locate(*p).unwrap() as u32;
        ws_send(
            &mut ws,
            serde_json::json!({"type": "pos", "x": p.x, "y": p.y, "z": p.z, "seq": seq}),
        )
        .await;
        // Until the ack, then until the cell's PVS is held.
        loop {
            let m = ws_next(&mut ws).await.expect("session open");
            if client.apply(&m) == "ack" {
                let v = m.unwrap();
                assert_eq!(v["cell"], want, "at {p}");
                break;
            }
        }
        while !client.cells.contains_key(&want) {
            let m = ws_next(&mut ws).await.expect("session open");
            client.apply(&m);
        }
        let held: Vec<u32> = client.cells[&want].iter().copied().collect();
        assert_eq!(held, d.file.pvs(want as usize).unwrap());
        assert!(held.iter().all(|id| client.geometry.contains(id)));
        cells_seen.insert(want);
    }
    assert!(cells_seen.len() >= 5, "{} cells", cells_seen.len());
    // A position in a wall: an error naming the position's seq; the session goes on.
    ws_send(
        &mut ws,
        serde_json::json!({"type": "pos", "x": 1e5, "y": 0, "z": 0, "seq": 999}),
    )
    .await;
    loop {
        let m = ws_next(&mut ws).await.expect("session open");
        if let Ok(v) = &m {
            if v["type"] == "error" {
                assert_eq!(v["seq"], 999);
                break;
            }
        }
        client.apply(&m);
    }
    assert!(client.errors.iter().all(|e| e.contains("no cell")));
    s.stop().await.unwrap();
}

#[test]
fn a_file_of_another_scene_is_refused() {
    let (d, _) = dm1_served();
    let other = Scene::from_objects(d.scene.objects[..10].to_vec());
    let err = FileSource::cells(d.file, &other).err().unwrap();
    assert!(
        matches!(err, sightline_server::source::FileSourceError::Pvs(_)),
        "{err}"
    );
}
