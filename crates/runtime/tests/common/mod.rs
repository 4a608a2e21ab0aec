//! Real `.pvs` files for the runtime's tests, built with the `sightline-pvs` API, each
//! with the rows it was written from: a generated city's grid (erosion), Quake's dm1
//! (`portals-fast`, convex leaves and a LEAF section), a level of voxel cells with a
//! source map, and a shard file.
#![allow(dead_code)]

use sightline_core::{Cell, VoxelCell};
use sightline_geom::ViewCell;
use sightline_pvs::format::{encode_cells, encode_cells_with_leaves, EncodeOptions};
use sightline_pvs::{Header, Shard};
use std::path::PathBuf;
use std::sync::Arc;

/// A `.pvs` and, per cell, the sorted row it was written with (`None`: not stored).
pub struct Written {
    pub bytes: Vec<u8>,
    pub rows: Vec<Option<Vec<u32>>>,
}

fn rows_of(sets: &[roaring::RoaringBitmap]) -> Vec<Option<Vec<u32>>> {
    sets.iter().map(|s| Some(s.iter().collect())).collect()
}

/// A small generated city, its 20 m grid at eye height, built with `erosion`.
pub fn city() -> Written {
    let scene = Arc::new(sightline_scene::generate::city(7, 60));
    let cells = sightline_scene::cells::grid_cells(&scene, 20.0, 1.5, 2.0).unwrap();
    assert!(cells.len() >= 20, "{} cells", cells.len());
    let method = sightline_methods::create(
        "erosion",
        scene.clone(),
        &sightline_methods::MethodOptions::default(),
    )
    .unwrap();
    let dir = std::env::temp_dir().join(format!("sightline-runtime-city-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("city.pvs");
    sightline_pvs::build(
        &scene,
        &*method,
        &cells,
        &out,
        &sightline_pvs::BuildOptions::default(),
        &|_, _| {},
    )
    .unwrap();
    let bytes = std::fs::read(&out).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let rows = cells.iter().map(|c| Some(method.pvs(c).unwrap())).collect();
    Written { bytes, rows }
}

pub fn dm1_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/quake/dm1.bsp")
}

/// Quake's dm1 built as `sightline build dm1.bsp --method portals-fast` builds it.
pub fn dm1() -> Written {
    let level = sightline_scene::import::bsp::load_bsp(&dm1_path()).unwrap();
    let scene = level.to_scene();
    let portals = sightline_portals::Portals::build(&level).unwrap();
    let cells = sightline_portals::leaf_cells(&level);
    let all = portals.solve_all(sightline_portals::Mode::Fast);
    let of = |c: &Cell| all.get(c.id().unwrap_or(0) as usize);
    let sets: Vec<roaring::RoaringBitmap> = cells
        .iter()
        .map(|c| {
            of(c)
                .map(|p| p.faces.iter().copied().collect())
                .unwrap_or_default()
        })
        .collect();
    let leaves: Vec<Vec<u32>> = cells
        .iter()
        .map(|c| of(c).map(|p| p.leaves.clone()).unwrap_or_default())
        .collect();
    let header = Header::new(
        scene.fingerprint(),
        "portals-fast",
        vec![],
        scene.objects.len(),
        cells.len(),
    );
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
    Written {
        bytes,
        rows: rows_of(&sets),
    }
}

fn rng(seed: u64) -> impl FnMut() -> f64 {
    let mut x = seed | 1;
    move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn bx(a: [f64; 6]) -> ViewCell {
    ViewCell::from_array(a).unwrap()
}

/// An indoor level of automatic cells (unions of voxel boxes, some L-shaped and
/// interleaved) with clusters mapped to source objects, as a mesh level's build stores.
pub fn voxels() -> Written {
    let mut cells = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            let (x, y) = (i as f64 * 4.0, j as f64 * 4.0);
            let mut boxes = vec![bx([x, y, 0.0, x + 4.0, y + 2.0, 3.0])];
            if (i + j) % 2 == 0 {
                boxes.push(bx([x, y + 2.0, 0.0, x + 2.0, y + 4.0, 3.0]));
            }
            cells.push(Cell::Voxels(
                VoxelCell::new(100 + cells.len() as u32, boxes).unwrap(),
            ));
        }
    }
    // The remaining quarter-squares: cells of their own, numbered after.
    for j in 0..4 {
        for i in 0..4 {
            if (i + j) % 2 == 0 {
                let (x, y) = (i as f64 * 4.0 + 2.0, j as f64 * 4.0 + 2.0);
                let b = vec![bx([x, y, 0.0, x + 2.0, y + 2.0, 3.0])];
                cells.push(Cell::Voxels(
                    VoxelCell::new(100 + cells.len() as u32, b).unwrap(),
                ));
            } else {
                let (x, y) = (i as f64 * 4.0, j as f64 * 4.0 + 2.0);
                cells.push(Cell::Box(bx([x, y, 0.0, x + 4.0, y + 2.0, 3.0])));
            }
        }
    }
    let objects = 40u32;
    let mut r = rng(3);
    let sets: Vec<roaring::RoaringBitmap> = (0..cells.len())
        .map(|k| {
            (0..objects)
                .filter(|&o| (o as usize % 7 == k % 7) || r() < 0.3)
                .collect()
        })
        .collect();
    let sources: Vec<String> = (0..objects).map(|o| (o / 3).to_string()).collect();
    let names: Vec<String> = (0..=objects / 3)
        .map(|s| format!("\"obj \\\"{s}\\\"\""))
        .collect();
    let header = Header::new(
        0xabc,
        "portals",
        vec![
            ("sources".into(), sources.join(",")),
            ("source_names".into(), format!("[{}]", names.join(", "))),
        ],
        objects as usize,
        cells.len(),
    );
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    let bytes = encode_cells(&header, &cells, &present, &sets, &EncodeOptions::default()).unwrap();
    Written {
        bytes,
        rows: rows_of(&sets),
    }
}

/// Shard 1 of 3 of a grid of 60 boxes with PVS-like sets (delta chains inside the shard).
pub fn shard() -> Written {
    let cells: Vec<ViewCell> = (0..60)
        .map(|k| {
            let (i, j) = ((k % 10) as f64 * 10.0, (k / 10) as f64 * 10.0);
            bx([i, j, 1.5, i + 10.0, j + 10.0, 2.0])
        })
        .collect();
    let present: Vec<u32> = (0..60).filter(|k| k % 3 == 1).collect();
    let sets: Vec<Vec<u32>> = present
        .iter()
        .map(|&k| {
            (0..500u32)
                .filter(|o| (o / 5).abs_diff(k * 8) < 60 || o % 37 == 0)
                .collect()
        })
        .collect();
    let mut header = Header::new(0x5eed, "erosion", vec![], 500, 60);
    header.shard = Some(Shard { index: 1, count: 3 });
    let bytes = sightline_pvs::format::encode(&header, &cells, &present, &sets).unwrap();
    let mut rows = vec![None; cells.len()];
    for (&k, s) in present.iter().zip(sets) {
        rows[k as usize] = Some(s);
    }
    Written { bytes, rows }
}

/// Points to locate in a file: every cell's centre, corners and face centres, and
/// random points over (and a little beyond) the cells' extent.
pub fn probe_points(boxes: &[[f64; 6]], random: usize) -> Vec<[f64; 3]> {
    let mut pts = Vec::new();
    for b in boxes {
        let c = [
            0.5 * (b[0] + b[3]),
            0.5 * (b[1] + b[4]),
            0.5 * (b[2] + b[5]),
        ];
        pts.push(c);
        pts.push([b[0], b[1], b[2]]);
        pts.push([b[3], b[4], b[5]]);
        pts.push([b[0], c[1], c[2]]);
        pts.push([c[0], b[4], c[2]]);
    }
    let lo: [f64; 3] = std::array::from_fn(|k| boxes.iter().map(|b| b[k]).fold(f64::MAX, f64::min));
    let hi: [f64; 3] =
        std::array::from_fn(|k| boxes.iter().map(|b| b[k + 3]).fold(f64::MIN, f64::max));
    let mut r = rng(11);
    for _ in 0..random {
        pts.push(std::array::from_fn(|k| {
            let span = hi[k] - lo[k];
            lo[k] - 0.05 * span + 1.1 * span * r()
        }));
    }
    pts.push([f64::NAN, 0.0, 0.0]);
    pts.push([f64::INFINITY, 0.0, 0.0]);
    pts
}
