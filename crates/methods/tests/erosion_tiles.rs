//! The lazy tiled erosion (`erosion::tiles`) gives the PVS of the whole-raster erosion:
//! on random cities (proptest) for every erosion method, and on street cells of the
//! vendored real scenes (Lyon 1er BD TOPO, Den Haag tile 01) around each cell.

mod erosion_support;

use erosion_support::*;
use proptest::prelude::*;
use sightline_core::check::{near_middle, street_cells, Clearance};
use sightline_geom::{Aabb2, DVec2, ViewCell};
use sightline_methods::erosion::{ErosionMethod, Variant};
use sightline_methods::{MethodOptions, VisibilityMethod};
use sightline_scene::import::{load, ImportOptions};
use sightline_scene::{Object, Scene};
use std::path::PathBuf;
use std::sync::Arc;

const VARIANTS: [(&str, Variant); 5] = [
    ("erosion", Variant::Full),
    ("erosion-segment", Variant::Segment),
    ("erosion-cell", Variant::Cell),
    ("shrink-sphere", Variant::Sphere),
    ("erosion-rays", Variant::Rays),
];

/// The PVS of `cell` with the tiled and with the whole-raster erosion (seed rays off,
/// so that every object goes through the erosion test).
fn both(
    scene: &Arc<Scene>,
    name: &'static str,
    variant: Variant,
    cell: &ViewCell,
) -> (Vec<u32>, Vec<u32>) {
    let method = |tiled: bool| {
        ErosionMethod::new(name, variant, scene.clone(), &MethodOptions::default())
            .expect("method")
            .with_seed(false)
            .with_tiles(tiled)
    };
    let tiled = method(true).pvs(cell).expect("pvs");
    let whole = method(false).pvs(cell).expect("pvs");
    (tiled, whole)
}

/// Boxes `(x0, y0, x1, y1, h)` and a cell `(x, y, size)`.
type CityCase = (Vec<(f64, f64, f64, f64, f64)>, (f64, f64, f64));

/// Random blocks of touching houses over 300 m (several tiles), with courtyards.
fn city() -> impl Strategy<Value = CityCase> {
    let houses = prop::collection::vec(
        (
            0..7usize,
            0..7usize,
            0..4usize,
            3..45i32,
            prop::bool::weighted(0.8),
        ),
        20..70,
    );
    let cellpos = (
        0..6usize,
        0..100i32,
        prop::sample::select(vec![4.0, 10.0, 25.0]),
    );
    (houses, cellpos).prop_map(|(hs, (street, along, size))| {
        // Blocks 32 m wide with 4 houses of 8 m on each of two sides, streets 12 m.
        let mut out = Vec::new();
        for (i, j, k, h, keep) in hs {
            if !keep {
                continue;
            }
            let (x0, y0) = (44.0 * i as f64, 44.0 * j as f64);
            for (dy, depth) in [(0.0, 10.0), (22.0, 10.0)] {
                let rect = (
                    x0 + 8.0 * k as f64,
                    y0 + dy,
                    x0 + 8.0 * (k + 1) as f64,
                    y0 + dy + depth,
                    h as f64,
                );
                if !out
                    .iter()
                    .any(|o: &(f64, f64, f64, f64, f64)| o.0 == rect.0 && o.1 == rect.1)
                {
                    out.push(rect);
                }
            }
        }
        let c = 32.0 + 44.0 * street as f64 + 6.0 - size / 2.0;
        (out, (c, along as f64 * 3.0, size))
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 5, ..ProptestConfig::default() })]

    #[test]
    fn tiled_equals_whole_on_random_cities((houses, (x, y, size)) in city()) {
        let objs: Vec<Object> = houses.iter().map(|&(x0, y0, x1, y1, h)| Object::rect_block(x0, y0, x1, y1, h)).collect();
        let scene = Arc::new(Scene::from_objects(objs));
        let c = cell(x, y, x + size, y + size);
        // The segments, the cell and the rays (the octagon's tiles: the unit tests).
        for (name, variant) in [VARIANTS[0], VARIANTS[2], VARIANTS[4]] {
            let (tiled, whole) = both(&scene, name, variant, &c);
            prop_assert_eq!(tiled, whole, "{} on {}", name, c);
        }
    }
}

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(name)
}

/// Two street cells of `size` whose centre column is free, and the scene cut to the
/// objects within `r` of each (a few tiles around the cell).
fn real_cells(file: &str, size: f64, r: f64) -> Vec<(Arc<Scene>, ViewCell)> {
    let scene = load(&data(file), &ImportOptions::default()).expect("load scene");
    let street = street_cells(&scene, size, (1.5, 2.0), usize::MAX, Clearance::Centre);
    near_middle(&scene, &street, 2, 50)
        .into_iter()
        .map(|cell| {
            let p = cell.center().truncate();
            let near = Aabb2::new(p - DVec2::splat(r), p + DVec2::splat(r));
            let objs = scene
                .objects
                .iter()
                .filter(|o| o.bounds.xy().intersects(&near))
                .cloned()
                .collect();
            (Arc::new(Scene::from_objects(objs)), cell)
        })
        .collect()
}

fn check_real(file: &str) {
    for (size, variants) in [(25.0, &VARIANTS[..1]), (10.0, &VARIANTS[..3])] {
        for (scene, cell) in real_cells(file, size, 120.0) {
            for &(name, variant) in variants {
                let (tiled, whole) = both(&scene, name, variant, &cell);
                assert_eq!(tiled, whole, "{name} on {file} cell {cell}");
            }
        }
    }
}

#[test]
fn tiled_equals_whole_on_lyon_cells() {
    check_real("lyon1_bdtopo.geojson");
}

#[test]
fn tiled_equals_whole_on_denhaag_cells() {
    check_real("denhaag_tile01_lod2.geojson");
}
