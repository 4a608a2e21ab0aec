//! Import of 3D Tiles: b3dm content with `_BATCHID` and a batch table, external
//! tilesets, and bad tilesets that must give one clear error naming the tile.

use serde_json::{json, Value};
use sightline_scene::{generate, import};
use sightline_tiles::export::{self, TILESET_FILE};
use sightline_tiles::glb::tile_glb;
use sightline_tiles::layout::Layout;
use std::path::Path;

fn load(path: &Path) -> Result<sightline_scene::Scene, String> {
    import::load(path, &Default::default()).map_err(|e| e.to_string())
}

/// A small exported tileset in `dir/ts`.
fn tileset(dir: &Path) -> std::path::PathBuf {
    let scene = generate::city(4, 12);
    let layout = Layout::build(&scene, 4).unwrap();
    let out = dir.join("ts");
    export::write(&scene, &layout, &out, &[]).unwrap();
    out
}

fn write_json(path: &Path, v: &Value) {
    std::fs::write(path, serde_json::to_vec(v).unwrap()).unwrap();
}

fn one_tile(uri: &str) -> Value {
    json!({
        "asset": { "version": "1.1" },
        "geometricError": 10.0,
        "root": {
            "boundingVolume": { "box": [0, 0, 0, 100, 0, 0, 0, 100, 0, 0, 0, 50] },
            "geometricError": 0.0,
            "content": { "uri": uri }
        }
    })
}

/// The GLB's JSON chunk, edited, back in a GLB.
fn edit_glb(glb: &[u8], f: impl FnOnce(&mut Value)) -> Vec<u8> {
    let n = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let mut json: Value = serde_json::from_slice(&glb[20..20 + n]).unwrap();
    f(&mut json);
    let mut j = serde_json::to_vec(&json).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let bin = &glb[20 + n..];
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + 8 + j.len() + bin.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&j);
    out.extend_from_slice(bin);
    out
}

fn b3dm(glb: &[u8], feature_table: &Value, batch_table: &Value) -> Vec<u8> {
    let pad = |v: &Value| {
        let mut b = serde_json::to_vec(v).unwrap();
        while !b.len().is_multiple_of(8) {
            b.push(b' ');
        }
        b
    };
    let (ft, bt) = (pad(feature_table), pad(batch_table));
    let len = 28 + ft.len() + bt.len() + glb.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"b3dm");
    for w in [1, len, ft.len(), 0, bt.len(), 0] {
        out.extend_from_slice(&(w as u32).to_le_bytes());
    }
    out.extend_from_slice(&ft);
    out.extend_from_slice(&bt);
    out.extend_from_slice(glb);
    out
}

#[test]
fn b3dm_batches_become_named_objects_offset_by_rtc_center() {
    let dir = tempfile::tempdir().unwrap();
    let scene = generate::city(6, 8);
    let ids: Vec<u32> = (0..scene.len() as u32).collect();
    let glb = tile_glb(&scene, &ids, scene.bounds.center());
    // 3D Tiles 1.0 style: `_BATCHID` and no EXT_mesh_features.
    let glb = edit_glb(&glb, |j| {
        let p = &mut j["meshes"][0]["primitives"][0];
        let a = p["attributes"]["_FEATURE_ID_0"].take();
        p["attributes"]
            .as_object_mut()
            .unwrap()
            .remove("_FEATURE_ID_0");
        p["attributes"]["_BATCHID"] = a;
        p.as_object_mut().unwrap().remove("extensions");
        j.as_object_mut().unwrap().remove("extensions");
        j["extensionsUsed"] = json!([]);
    });
    let names: Vec<String> = ids.iter().map(|i| format!("house-{i}")).collect();
    let rtc = [1000.0, 2000.0, 5.0];
    let bytes = b3dm(
        &glb,
        &json!({ "BATCH_LENGTH": ids.len(), "RTC_CENTER": rtc }),
        &json!({ "name": names }),
    );
    std::fs::write(dir.path().join("a.b3dm"), bytes).unwrap();
    let ts = dir.path().join(TILESET_FILE);
    write_json(&ts, &one_tile("a.b3dm"));
    let back = load(&ts).unwrap();
    assert_eq!(back.len(), scene.len());
    let expect_min = scene.bounds.min + sightline_geom::DVec3::from_array(rtc);
    assert!(
        (back.bounds.min - expect_min).abs().max_element() < 1e-2,
        "{:?}",
        back.bounds
    );
    let mut got: Vec<String> = back
        .objects
        .iter()
        .map(|o| o.name.clone().unwrap())
        .collect();
    got.sort();
    let mut want = names.clone();
    want.sort();
    assert_eq!(got, want);
}

#[test]
fn external_tilesets_and_tile_transforms_are_followed() {
    let dir = tempfile::tempdir().unwrap();
    let ts = tileset(dir.path());
    let n = load(&ts.join(TILESET_FILE)).unwrap().len();
    // A parent tileset with a child tile translated 100 m east that points at `ts`.
    let parent = json!({
        "asset": { "version": "1.1" },
        "geometricError": 1000.0,
        "root": {
            "boundingVolume": { "box": [0, 0, 0, 1000, 0, 0, 0, 1000, 0, 0, 0, 100] },
            "geometricError": 1000.0,
            "children": [{
                "boundingVolume": { "box": [0, 0, 0, 1000, 0, 0, 0, 1000, 0, 0, 0, 100] },
                "geometricError": 500.0,
                "transform": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 100, 0, 0, 1],
                "content": { "uri": "ts/tileset.json" }
            }]
        }
    });
    write_json(&dir.path().join("top.json"), &parent);
    let direct = load(&ts.join(TILESET_FILE)).unwrap();
    let via = load(&dir.path().join("top.json")).unwrap();
    assert_eq!(via.len(), n);
    assert!((via.bounds.min.x - direct.bounds.min.x - 100.0).abs() < 1e-6);
}

/// Every bad tileset gives one line naming the tile and the problem.
#[test]
fn bad_tilesets_give_one_clear_error_naming_the_tile() {
    let dir = tempfile::tempdir().unwrap();
    let ts = tileset(dir.path());
    let glb_uri = "tiles/".to_string()
        + &std::fs::read_dir(ts.join("tiles"))
            .unwrap()
            .next()
            .unwrap()
            .unwrap()
            .file_name()
            .to_string_lossy();
    std::fs::write(ts.join("broken.glb"), b"glTF\x02\0\0\0garbage").unwrap();
    std::fs::write(ts.join("junk.bin"), b"\x00\x01\x02\x03").unwrap();
    let cases: Vec<(&str, Value, &str)> = vec![
        ("missing", one_tile("tiles/none.glb"), "missing"),
        ("broken", one_tile("broken.glb"), "broken GLB"),
        ("junk", one_tile("junk.bin"), "not GLB"),
        (
            "escape",
            one_tile("../../etc/passwd"),
            "escapes the tileset folder",
        ),
        ("absolute", one_tile("/etc/passwd"), "absolute"),
        (
            "scheme",
            one_tile("https://example.org/a.glb"),
            "absolute URIs",
        ),
        ("encoded", one_tile("%2e%2e/%2e%2e/etc/passwd"), "escapes"),
        (
            "no-volume",
            {
                let mut v = one_tile(&glb_uri);
                v["root"].as_object_mut().unwrap().remove("boundingVolume");
                v
            },
            "missing boundingVolume",
        ),
        (
            "short-box",
            {
                let mut v = one_tile(&glb_uri);
                v["root"]["boundingVolume"]["box"] = json!([0, 0, 0, 1]);
                v
            },
            "not 12 finite numbers",
        ),
        (
            "bad-region",
            {
                let mut v = one_tile(&glb_uri);
                v["root"]["boundingVolume"] = json!({ "region": [0, 1, 1, 0, 0, 10] });
                v
            },
            "region",
        ),
        (
            "no-error",
            {
                let mut v = one_tile(&glb_uri);
                v["root"].as_object_mut().unwrap().remove("geometricError");
                v
            },
            "missing geometricError",
        ),
        (
            "bad-transform",
            {
                let mut v = one_tile(&glb_uri);
                v["root"]["transform"] = json!([1, 0, 0]);
                v
            },
            "transform",
        ),
        ("self-cycle", one_tile("self-cycle.json"), "cycle"),
    ];
    for (name, v, want) in cases {
        let path = ts.join(format!("{name}.json"));
        write_json(&path, &v);
        let e = load(&path).expect_err(name);
        assert!(e.contains(want), "{name}: {e}");
        assert!(e.contains("tile root"), "{name} names the tile: {e}");
        assert!(!e.contains('\n'), "{name}: one line: {e}");
    }
    // A two-step cycle, and a child tile named by its path.
    write_json(&ts.join("a.json"), &one_tile("b.json"));
    write_json(&ts.join("b.json"), &one_tile("a.json"));
    let e = load(&ts.join("a.json")).unwrap_err();
    assert!(e.contains("cycle") && e.contains("b.json"), "{e}");
    let mut nested = one_tile(&glb_uri);
    nested["root"]["children"] = json!([one_tile("tiles/gone.glb")["root"].clone()]);
    write_json(&ts.join("nested.json"), &nested);
    let e = load(&ts.join("nested.json")).unwrap_err();
    assert!(
        e.contains("root.children[0]") && e.contains("gone.glb"),
        "{e}"
    );
}

#[cfg(unix)]
#[test]
fn a_symbolic_link_out_of_the_folder_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let ts = tileset(dir.path());
    let outside = dir.path().join("secret.glb");
    std::fs::copy(
        std::fs::read_dir(ts.join("tiles"))
            .unwrap()
            .next()
            .unwrap()
            .unwrap()
            .path(),
        &outside,
    )
    .unwrap();
    std::os::unix::fs::symlink(&outside, ts.join("link.glb")).unwrap();
    write_json(&ts.join("link.json"), &one_tile("link.glb"));
    let e = load(&ts.join("link.json")).unwrap_err();
    assert!(e.contains("link leads out"), "{e}");
}

mod mutations {
    use super::*;
    use proptest::prelude::*;

    fn seeds() -> Vec<Vec<u8>> {
        let scene = generate::city(6, 6);
        let ids: Vec<u32> = (0..scene.len() as u32).collect();
        let glb = tile_glb(&scene, &ids, scene.bounds.center());
        let b = b3dm(
            &glb,
            &json!({ "BATCH_LENGTH": 0, "RTC_CENTER": [1, 2, 3] }),
            &json!({ "name": ["a"] }),
        );
        vec![glb, b]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// Corrupted GLB and b3dm content gives an error or a scene, never a panic.
        #[test]
        fn corrupted_content_never_panics(
            which in 0usize..2,
            flips in prop::collection::vec((any::<prop::sample::Index>(), any::<u8>()), 0..8),
            cut in any::<prop::sample::Index>(),
            truncate in any::<bool>(),
        ) {
            let mut bytes = seeds().swap_remove(which);
            for (at, v) in flips {
                let i = at.index(bytes.len());
                bytes[i] = v;
            }
            if truncate {
                bytes.truncate(cut.index(bytes.len()));
            }
            let _ = import::tileset::parse_content(&bytes);
        }
    }

    /// Every byte of the GLB seed set to `'0'` in turn (the shape of a case the mutation
    /// test found: a digit of the JSON changed, an accessor's component type or count
    /// no longer matching what the readers expect): an error or a scene, never a panic.
    #[test]
    fn every_byte_set_to_a_digit_never_panics() {
        let seed = seeds().swap_remove(0);
        for i in 0..seed.len() {
            let mut bytes = seed.clone();
            bytes[i] = b'0';
            let _ = import::tileset::parse_content(&bytes);
        }
    }

    #[test]
    fn the_seeds_parse() {
        for s in seeds() {
            let scene = import::tileset::parse_content(&s).unwrap();
            assert_eq!(scene.len(), generate::city(6, 6).len());
        }
    }
}

#[test]
fn accessors_beyond_their_buffer_are_errors() {
    let scene = generate::city(6, 6);
    let ids: Vec<u32> = (0..scene.len() as u32).collect();
    let glb = tile_glb(&scene, &ids, scene.bounds.center());
    for (acc, field, value) in [
        (0, "count", json!(10_000_000)),
        (1, "count", json!(10_000_000)),
        (2, "count", json!(10_000_000)),
        (0, "byteOffset", json!(1_000_000)),
        (2, "byteOffset", json!(4)),
    ] {
        let bad = edit_glb(&glb, |j| j["accessors"][acc][field] = value.clone());
        let r = import::tileset::parse_content(&bad);
        eprintln!(
            "{acc} {field}: {:?}",
            r.as_ref().map(|s| s.len()).map_err(|e| e.to_string())
        );
    }
    for (view, len) in [(0, 4), (1, 4), (2, 4)] {
        let bad = edit_glb(&glb, |j| j["bufferViews"][view]["byteLength"] = json!(len));
        let r = import::tileset::parse_content(&bad);
        eprintln!(
            "view {view}: {:?}",
            r.as_ref().map(|s| s.len()).map_err(|e| e.to_string())
        );
    }
}
