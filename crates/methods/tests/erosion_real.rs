//! `missed = 0` for the four erosion methods on a handful of street cells of the
//! vendored real scenes (Lyon 1er BD TOPO, Den Haag tile 01), on the real buildings
//! within 50 m of each cell (to keep the dev-profile runtime modest; whole-scene
//! checks are run in release by `sightline check`), against the exact sampled oracle.

mod erosion_support;

use erosion_support::*;
use sightline_core::check::{near_middle, street_cells, Clearance};
use sightline_geom::{Aabb2, ViewCell};
use sightline_methods::erosion::{ErosionMethod, Variant};
use sightline_methods::{create, MethodOptions, VisibilityMethod};
use sightline_scene::import::{load, ImportOptions};
use sightline_scene::Scene;
use std::path::PathBuf;
use std::sync::Arc;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(name)
}

/// The scene restricted to objects whose footprint lies within `r` of the cell:
/// occlusion by the rest is ignored, so the oracle's VS of the sub-scene is a
/// superset of the true VS restricted to it — a stricter check.
fn near(scene: &Scene, cell: &ViewCell, r: f64) -> (Scene, Vec<u32>) {
    let rect = Aabb2::new(cell.min.truncate(), cell.max.truncate()).expand(r);
    let ids: Vec<u32> = (0..scene.objects.len() as u32)
        .filter(|&i| scene.objects[i as usize].bounds.xy().intersects(&rect))
        .collect();
    let objs = ids
        .iter()
        .map(|&i| scene.objects[i as usize].clone())
        .collect();
    (Scene::from_objects(objs), ids)
}

fn check_scene(file: &str) {
    let scene = Arc::new(load(&data(file), &ImportOptions::default()).expect("load scene"));
    let street = street_cells(&scene, 20.0, (1.5, 2.0), usize::MAX, Clearance::Centre);
    for cell in near_middle(&scene, &street, 3, 50) {
        let (sub, ids) = near(&scene, &cell, 50.0);
        let sub = Arc::new(sub);
        let vs = sampled_visible(&sub, &cell, 3);
        for m in METHODS {
            let method = create(m, sub.clone(), &MethodOptions::default()).expect("method");
            let p = method.pvs(&cell).expect("pvs");
            let miss: Vec<u32> = missed(&p, &vs).iter().map(|&i| ids[i as usize]).collect();
            assert!(miss.is_empty(), "{m} misses {miss:?} on {file} cell {cell}");
        }
        // The seed rays change no PVS (crate::seed).
        let with = create("erosion", sub.clone(), &MethodOptions::default())
            .and_then(|m| m.pvs(&cell))
            .expect("pvs");
        let without = ErosionMethod::new(
            "erosion",
            Variant::Full,
            sub.clone(),
            &MethodOptions::default(),
        )
        .expect("method")
        .with_seed(false)
        .pvs(&cell)
        .expect("pvs");
        assert_eq!(with, without, "seed changes the PVS on {file} cell {cell}");
    }
}

#[test]
fn lyon_street_cells() {
    check_scene("lyon1_bdtopo.geojson");
}

#[test]
fn denhaag_street_cells() {
    check_scene("denhaag_tile01_lod2.geojson");
}
