//! `dual-ray` / `dual-ray-exact` on street cells of the vendored real scenes (Lyon 1er
//! BD TOPO, Den Haag tile 01): the discretized PVS contains the exact one, every cell
//! keeps the objects around it, and the methods cull something.

use sightline_core::check::{near_middle, street_cells, Clearance};
use sightline_methods::dual_ray::{DualRay, Planarity};
use sightline_scene::import::{load, ImportOptions};
use std::path::PathBuf;
use std::sync::Arc;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(name)
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
    let street = street_cells(&scene, 20.0, (1.5, 2.0), usize::MAX, Clearance::Centre);
    for c in near_middle(&scene, &street, cells, 50) {
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
