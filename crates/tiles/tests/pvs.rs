//! The tile-level PVS: exactly the tiles (and features) of the cell's object PVS, and
//! conservative against the ground truth when the object PVS is.

use proptest::prelude::*;
use sightline_geom::{DVec3, ViewCell};
use sightline_pvs::format::{encode, Header};
use sightline_pvs::PvsFile;
use sightline_scene::{generate, Object, Scene};
use sightline_tiles::layout::Layout;
use sightline_tiles::pvs::Sidecar;
use std::collections::BTreeSet;

fn cell(x: f64, y: f64) -> ViewCell {
    ViewCell::new(DVec3::new(x, y, 1.5), DVec3::new(x + 10.0, y + 10.0, 2.0)).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    /// Every tile holding an object of a cell's PVS is listed with that object's feature,
    /// and no other tile or feature is.
    #[test]
    fn tiles_are_the_image_of_the_object_pvs(
        boxes in prop::collection::vec((-300.0..300.0f64, -300.0..300.0f64, 2.0..30.0f64), 1..80),
        max in 1usize..10,
        picks in prop::collection::vec(prop::collection::btree_set(0usize..80, 0..40), 1..6),
    ) {
        let scene = Scene::from_objects(boxes.iter().map(|&(x, y, s)| Object::rect_block(x, y, x + s, y + s, s)).collect());
        let layout = Layout::build(&scene, max).unwrap();
        let cells: Vec<(usize, ViewCell, Vec<u32>)> = picks.iter().enumerate().map(|(k, p)| {
            let ids: Vec<u32> = p.iter().filter(|&&i| i < scene.len()).map(|&i| i as u32).collect();
            (k, cell(k as f64 * 10.0, 0.0), ids)
        }).collect();
        let sc = Sidecar::build(&layout, scene.fingerprint(), "test", cells.clone()).unwrap();
        let back = Sidecar::from_slice(&serde_json::to_vec(&sc).unwrap()).unwrap();
        // serde_json's float parsing may differ in the last bit: compare the structure.
        prop_assert_eq!(&back.cells, &sc.cells);
        prop_assert!(back.tiles.iter().zip(&sc.tiles).all(|(a, b)| a.uri == b.uri && a.objects == b.objects));
        for ((_, _, ids), c) in cells.iter().zip(&sc.cells) {
            let listed: BTreeSet<(u32, u32)> = c.tiles.iter().zip(&c.features)
                .flat_map(|(&t, fs)| fs.iter().map(move |&f| (t, f)))
                .collect();
            let objects: BTreeSet<u32> = listed.iter().map(|&(t, f)| sc.tiles[t as usize].objects[f as usize]).collect();
            prop_assert_eq!(objects, ids.iter().copied().collect::<BTreeSet<u32>>());
            prop_assert!(c.tiles.windows(2).all(|w| w[0] < w[1]));
            prop_assert!(c.features.iter().all(|f| !f.is_empty()));
        }
    }
}

#[test]
fn sidecar_from_a_pvs_file_holds_every_tile_the_truth_sees() {
    let scene = std::sync::Arc::new(generate::city(1, 40));
    let layout = Layout::build(&scene, 4).unwrap();
    let cells = sightline_core::check::street_cells(
        &scene,
        10.0,
        (1.5, 2.0),
        2,
        sightline_core::check::Clearance::Box,
    );
    let method = sightline_methods::create("dual-ray", scene.clone(), &Default::default()).unwrap();
    let sets: Vec<Vec<u32>> = cells.iter().map(|c| method.pvs(c).unwrap()).collect();
    let header = Header::new(
        scene.fingerprint(),
        "dual-ray",
        vec![],
        scene.len(),
        cells.len(),
    );
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    let file = PvsFile::from_bytes(encode(&header, &cells, &present, &sets).unwrap()).unwrap();
    let sc = sightline_tiles::sidecar_from_pvs(&scene, &layout, &file).unwrap();
    assert_eq!(sc.cells.len(), cells.len());
    for (c, cellbox) in sc.cells.iter().zip(&cells) {
        let truth = sightline_core::check::ground_truth(&scene, cellbox, &Default::default());
        for id in truth.visible {
            let p = layout.placement[id as usize];
            let uri = layout.tiles[p.tile as usize].content_uri().unwrap();
            let k = c
                .tiles
                .iter()
                .position(|&t| sc.tiles[t as usize].uri == uri);
            let k = k.unwrap_or_else(|| {
                panic!(
                    "cell {}: tile {uri} of visible object {id} missing",
                    c.index
                )
            });
            assert!(
                c.features[k].contains(&p.feature),
                "object {id}'s feature listed"
            );
        }
        assert_eq!(sc.locate(cellbox.center()).map(|c| c.index), Some(c.index));
    }
    // A .pvs of another scene is refused.
    let other = generate::city(2, 40);
    let e = sightline_tiles::sidecar_from_pvs(&other, &layout, &file).unwrap_err();
    assert!(e.to_string().contains("another scene"), "{e}");
}

#[test]
fn malformed_sidecars_are_refused() {
    let scene = generate::city(1, 10);
    let layout = Layout::build(&scene, 4).unwrap();
    let sc = Sidecar::build(&layout, 1, "x", vec![(0, cell(0.0, 0.0), vec![0, 1])]).unwrap();
    let mut v = serde_json::to_value(&sc).unwrap();
    v["cells"][0]["tiles"][0] = 999.into();
    assert!(Sidecar::from_slice(&serde_json::to_vec(&v).unwrap()).is_err());
    let mut v = serde_json::to_value(&sc).unwrap();
    v["cells"][0]["features"][0][0] = 999.into();
    assert!(Sidecar::from_slice(&serde_json::to_vec(&v).unwrap()).is_err());
    let mut v = serde_json::to_value(&sc).unwrap();
    v["version"] = 7.into();
    let e = Sidecar::from_slice(&serde_json::to_vec(&v).unwrap()).unwrap_err();
    assert!(e.to_string().contains("version 7"), "{e}");
    assert!(Sidecar::from_slice(b"{").is_err());
    let e = Sidecar::build(&layout, 1, "x", vec![(0, cell(0.0, 0.0), vec![999])]).unwrap_err();
    assert!(e.to_string().contains("another scene"), "{e}");
}
