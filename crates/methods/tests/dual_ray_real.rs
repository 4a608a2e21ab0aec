//! `dual-ray` / `dual-ray-exact` on street cells of the vendored real scenes (Lyon 1er
//! BD TOPO, Den Haag tile 01): the discretized PVS contains the exact one, every cell
//! keeps the objects around it, and the methods cull something.

use sightline_geom::{DVec2, ViewCell};
use sightline_methods::dual_ray::{DualRay, Planarity};
use sightline_scene::import::{load, ImportOptions};
use sightline_scene::Scene;
use std::path::PathBuf;
use std::sync::Arc;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(name)
}

/// A few cells of `size` whose centre is not inside any footprint, spread over the scene.
pub fn street_cells(scene: &Scene, size: f64, n: usize) -> Vec<ViewCell> {
    let b = scene.bounds;
    let mut out = Vec::new();
    let mut k: u64 = 12345;
    let mut tries = 0;
    while out.len() < n && tries < 10_000 {
        tries += 1;
        k = k
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let fx = ((k >> 11) as f64) / ((1u64 << 53) as f64);
        k = k
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let fy = ((k >> 11) as f64) / ((1u64 << 53) as f64);
        let c = DVec2::new(
            b.min.x + (0.2 + 0.6 * fx) * (b.max.x - b.min.x),
            b.min.y + (0.2 + 0.6 * fy) * (b.max.y - b.min.y),
        );
        let inside = scene.objects.iter().any(|o| {
            o.inner
                .iter()
                .any(|p| p.footprint.bbox().contains(c) && p.footprint.contains(c))
        });
        if inside {
            continue;
        }
        let h = size / 2.0;
        if let Ok(cell) = ViewCell::from_array([c.x - h, c.y - h, 1.5, c.x + h, c.y + h, 2.0]) {
            out.push(cell);
        }
    }
    out
}

fn check_scene(name: &str, cells: usize) {
    let scene =
        Arc::new(load(&data(name), &ImportOptions::default()).expect("vendored scene loads"));
    let exact = DualRay::new("dual-ray-exact", scene.clone(), Planarity::Exact);
    let coarse = DualRay::new(
        "dual-ray",
        scene.clone(),
        Planarity::Discrete { resolution_px: 16 },
    );
    let fine = DualRay::new(
        "dual-ray",
        scene.clone(),
        Planarity::Discrete { resolution_px: 128 },
    );
    let unseeded = DualRay::new(
        "dual-ray",
        scene.clone(),
        Planarity::Discrete { resolution_px: 128 },
    )
    .with_seed(false);
    let (mut culled, mut seeded) = (0usize, 0usize);
    for c in street_cells(&scene, 20.0, cells) {
        let e = exact.pvs_with_stats(&c).0;
        // The seed rays report only exact-PVS objects and change no PVS.
        let seed = fine.seed_objects(&c);
        for id in &seed {
            assert!(
                e.binary_search(id).is_ok(),
                "{name} {c}: seed {id} not exact"
            );
        }
        seeded += seed.len();
        let p16 = coarse.pvs_with_stats(&c).0;
        let p128 = fine.pvs_with_stats(&c).0;
        for id in &e {
            assert!(p128.binary_search(id).is_ok(), "{name} {c}: 128 lacks {id}");
            assert!(p16.binary_search(id).is_ok(), "{name} {c}: 16 lacks {id}");
        }
        for id in &p128 {
            assert!(
                p16.binary_search(id).is_ok(),
                "{name} {c}: 16 lacks {id} of 128"
            );
        }
        // Objects whose outer boxes overlap the cell are always kept.
        for (i, o) in scene.objects.iter().enumerate() {
            let overlaps = o.outer.iter().any(|p| {
                let b = p.aabb().xy();
                b.min.x < c.max.x && c.min.x < b.max.x && b.min.y < c.max.y && c.min.y < b.max.y
            });
            if overlaps {
                assert!(
                    e.binary_search(&(i as u32)).is_ok(),
                    "{name} {c}: overlapping {i}"
                );
            }
        }
        assert_eq!(
            p128,
            unseeded.pvs_with_stats(&c).0,
            "{name} {c}: seed changed the PVS"
        );
        culled += scene.objects.len() - p128.len();
    }
    assert!(culled > 0, "{name}: nothing culled");
    assert!(seeded > 0, "{name}: the seed rays met nothing");
}

#[test]
fn lyon_street_cells() {
    check_scene("lyon1_bdtopo.geojson", 4);
}

#[test]
fn denhaag_street_cells() {
    check_scene("denhaag_tile01_lod2.geojson", 4);
}
