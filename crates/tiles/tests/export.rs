//! Export: the layout's invariants, the GLB's feature ids and metadata, the atomic
//! folder write, and the export → import round trip.

use proptest::prelude::*;
use sightline_geom::{Aabb3, DVec3};
use sightline_scene::{generate, import, Object, Scene};
use sightline_tiles::export::{self, TILESET_FILE};
use sightline_tiles::glb::tile_glb;
use sightline_tiles::layout::Layout;

fn encloses(outer: &Aabb3, inner: &Aabb3) -> bool {
    let e = 1e-9;
    (0..3).all(|k| outer.min[k] <= inner.min[k] + e && inner.max[k] <= outer.max[k] + e)
}

fn check_layout(scene: &Scene, layout: &Layout, max: usize) {
    let mut seen = vec![0usize; scene.len()];
    for (t, tile) in layout.tiles.iter().enumerate() {
        for (f, &id) in tile.objects.iter().enumerate() {
            seen[id as usize] += 1;
            let p = layout.placement[id as usize];
            assert_eq!((p.tile as usize, p.feature as usize), (t, f));
            assert!(encloses(&tile.bounds, &scene.objects[id as usize].bounds));
        }
        assert!(tile.objects.len() <= max || tile.level == sightline_tiles::layout::MAX_LEVEL);
        assert!(
            tile.objects.is_empty() || tile.children.is_empty(),
            "content only at leaves"
        );
        for &c in &tile.children {
            assert!(c > t, "a parent precedes its children");
            let child = &layout.tiles[c];
            assert!(encloses(&tile.bounds, &child.bounds));
            assert!(child.geometric_error <= tile.geometric_error);
            assert_eq!(child.level, tile.level + 1);
        }
    }
    assert!(
        seen.iter().all(|&n| n == 1),
        "every object in exactly one tile"
    );
}

fn random_scene(boxes: &[(f64, f64, f64, f64, f64)]) -> Scene {
    Scene::from_objects(
        boxes
            .iter()
            .map(|&(x, y, w, d, h)| Object::rect_block(x, y, x + w, y + d, h))
            .collect(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn layout_places_every_object_once_in_enclosing_boxes(
        boxes in prop::collection::vec((-500.0..500.0f64, -500.0..500.0f64, 1.0..40.0f64, 1.0..40.0f64, 1.0..80.0f64), 1..120),
        max in 1usize..12,
    ) {
        let scene = random_scene(&boxes);
        let layout = Layout::build(&scene, max).unwrap();
        check_layout(&scene, &layout, max);
    }
}

#[test]
fn identical_centres_stop_at_the_deepest_level() {
    let scene = random_scene(&[(0.0, 0.0, 10.0, 10.0, 5.0); 5]);
    let layout = Layout::build(&scene, 2).unwrap();
    check_layout(&scene, &layout, 2);
    assert!(Layout::build(&Scene::from_objects(vec![]), 4).is_none());
}

#[test]
fn glb_carries_feature_ids_and_object_ids() {
    let scene = generate::city(3, 30);
    let layout = Layout::build(&scene, 8).unwrap();
    let t = layout.content_tiles().next().unwrap();
    let tile = &layout.tiles[t];
    let glb = tile_glb(&scene, &tile.objects, tile.bounds.center());
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice(&glb).unwrap();
    let buffers = gltf::import_buffers(&document, None, blob).unwrap();
    let prim = document
        .meshes()
        .next()
        .unwrap()
        .primitives()
        .next()
        .unwrap();
    let acc = prim
        .get(&gltf::Semantic::Extras("FEATURE_ID_0".into()))
        .unwrap();
    let ids: Vec<f32> = gltf::accessor::Iter::<f32>::new(acc, |b| Some(&buffers[b.index()].0[..]))
        .unwrap()
        .collect();
    let n = tile.objects.len();
    assert!(ids
        .iter()
        .all(|&f| f >= 0.0 && (f as usize) < n && f.fract() == 0.0));
    let distinct: std::collections::BTreeSet<u32> = ids.iter().map(|&f| f as u32).collect();
    assert_eq!(distinct.len(), n, "every feature has vertices");
    // The metadata: one property table row per feature, object ids in feature order.
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let table = &json["extensions"]["EXT_structural_metadata"]["propertyTables"][0];
    assert_eq!(table["count"], n);
    let f = &json["meshes"][0]["primitives"][0]["extensions"]["EXT_mesh_features"]["featureIds"][0];
    assert_eq!(f["featureCount"], n);
    let view =
        &json["bufferViews"][table["properties"]["object_id"]["values"].as_u64().unwrap() as usize];
    let off = view["byteOffset"].as_u64().unwrap() as usize;
    let bin = &buffers[0].0;
    let object_ids: Vec<u32> = (0..n)
        .map(|k| u32::from_le_bytes(bin[off + 4 * k..off + 4 * k + 4].try_into().unwrap()))
        .collect();
    assert_eq!(object_ids, tile.objects);
    assert_eq!(json["asset"]["version"], "2.0");
}

/// The glTF minimums a GLB must meet: no empty buffer view, accessor or buffer, and
/// every buffer view inside its buffer.
fn assert_valid_glb(glb: &[u8]) -> serde_json::Value {
    assert_eq!(&glb[0..4], b"glTF");
    assert_eq!(
        u32::from_le_bytes(glb[8..12].try_into().unwrap()) as usize,
        glb.len()
    );
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice(glb).unwrap();
    gltf::import_buffers(&document, None, blob).unwrap();
    let json_len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let json: serde_json::Value = serde_json::from_slice(&glb[20..20 + json_len]).unwrap();
    let empty = vec![];
    let field = |k: &str| json[k].as_array().unwrap_or(&empty).clone();
    for v in field("bufferViews") {
        assert!(
            v["byteLength"].as_u64().unwrap() >= 1,
            "empty buffer view {v}"
        );
    }
    for a in field("accessors") {
        assert!(a["count"].as_u64().unwrap() >= 1, "empty accessor {a}");
    }
    for b in field("buffers") {
        assert!(b["byteLength"].as_u64().unwrap() >= 1, "empty buffer {b}");
    }
    json
}

#[test]
fn objects_without_triangles_give_a_valid_glb() {
    // An empty flat object has no triangle: alone, its tile has no mesh but keeps its row.
    let scene = Scene::from_objects(vec![
        Object::flat(Some("nothing".into()), vec![]),
        Object::rect_block(0.0, 0.0, 10.0, 10.0, 5.0),
    ]);
    assert!(scene.objects[0].triangles().is_empty());
    let json = assert_valid_glb(&tile_glb(&scene, &[0], DVec3::ZERO));
    assert!(json.get("meshes").is_none());
    assert_eq!(
        json["extensions"]["EXT_structural_metadata"]["propertyTables"][0]["count"],
        1
    );
    assert_eq!(
        json["extensionsUsed"],
        serde_json::json!(["EXT_structural_metadata"])
    );
    // Beside an object with triangles: one mesh, both rows.
    let json = assert_valid_glb(&tile_glb(&scene, &[0, 1], DVec3::ZERO));
    assert_eq!(json["meshes"].as_array().unwrap().len(), 1);
    // No objects at all: no buffer, no BIN chunk.
    let json = assert_valid_glb(&tile_glb(&scene, &[], DVec3::ZERO));
    assert!(json.get("buffers").is_none());
}

#[test]
fn export_then_import_keeps_objects_bounds_and_names() {
    let dir = tempfile::tempdir().unwrap();
    let mut scene = generate::city(5, 40);
    for (i, o) in scene.objects.iter_mut().enumerate() {
        o.name = Some(format!("b{i}"));
    }
    let layout = Layout::build(&scene, 6).unwrap();
    let out = dir.path().join("ts");
    let stats = export::write(&scene, &layout, &out, &[]).unwrap();
    assert_eq!(stats.features, scene.len());
    let back = import::load(&out.join(TILESET_FILE), &Default::default()).unwrap();
    assert_eq!(back.len(), scene.len());
    let close = |a: DVec3, b: DVec3| (a - b).abs().max_element() < 1e-3;
    assert!(close(back.bounds.min, scene.bounds.min) && close(back.bounds.max, scene.bounds.max));
    // Objects come back in tile order; match them by name.
    for o in &back.objects {
        let name = o.name.as_deref().unwrap();
        let id: usize = name[1..].parse().unwrap();
        let orig = &scene.objects[id];
        assert!(
            close(o.bounds.min, orig.bounds.min) && close(o.bounds.max, orig.bounds.max),
            "{name}"
        );
        assert_eq!(o.triangle_count(), orig.triangle_count(), "{name}");
    }
}

#[test]
fn export_replaces_a_tileset_but_not_other_folders() {
    let dir = tempfile::tempdir().unwrap();
    let scene = generate::city(2, 10);
    let layout = Layout::build(&scene, 4).unwrap();
    let out = dir.path().join("ts");
    export::write(&scene, &layout, &out, &[]).unwrap();
    export::write(&scene, &layout, &out, &[("extra.json", b"{}".to_vec())]).unwrap();
    assert!(out.join("extra.json").is_file() && out.join(TILESET_FILE).is_file());
    let other = dir.path().join("home");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "keep").unwrap();
    let e = export::write(&scene, &layout, &other, &[]).unwrap_err();
    assert!(e.to_string().contains("not a tileset folder"), "{e}");
    assert_eq!(
        std::fs::read_to_string(other.join("notes.txt")).unwrap(),
        "keep"
    );
    // Nothing temporary is left behind.
    let names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
}
