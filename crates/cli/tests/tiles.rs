//! `sightline tiles`: a tileset with its tile-PVS sidecar from a generated city and its
//! `.pvs`; bad arguments give one `error:` line and write nothing.

mod common;

use common::sightline;
use std::path::Path;

fn ok(args: &[&str]) -> String {
    let (code, out, err) = sightline(args);
    assert_eq!(code, 0, "{args:?}: {err}");
    out
}

fn one_error(args: &[&str], want: &str) {
    let (code, _, err) = sightline(args);
    assert_eq!(code, 1, "{args:?}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{args:?}: {err}");
    assert!(
        lines[0].starts_with("error: ") && lines[0].contains(want),
        "{args:?}: {err}"
    );
}

#[test]
fn tiles_writes_a_tileset_and_its_tile_pvs() {
    let d = tempfile::tempdir().unwrap();
    let p = |n: &str| d.path().join(n).display().to_string();
    ok(&["generate", "city", "--size", "40", "-o", &p("city.geojson")]);
    ok(&[
        "cells",
        &p("city.geojson"),
        "--size",
        "50",
        "-o",
        &p("cells.json"),
    ]);
    ok(&[
        "build",
        &p("city.geojson"),
        "--cells",
        &p("cells.json"),
        "--method",
        "dual-ray",
        "-o",
        &p("city.pvs"),
    ]);
    let out = ok(&[
        "tiles",
        &p("city.geojson"),
        "--pvs",
        &p("city.pvs"),
        "--max-features-per-tile",
        "5",
        "-o",
        &p("ts"),
        "--json",
    ]);
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["objects"], v["features"]);
    assert!(v["content_tiles"].as_u64().unwrap() >= 8);
    assert!(v["pvs_cells"].as_u64().unwrap() > 0);
    assert!(Path::new(&p("ts/sightline-pvs.json")).is_file());
    // The tileset loads as a scene with the same number of objects.
    let info = ok(&["info", &p("ts/tileset.json"), "--json"]);
    let i: serde_json::Value = serde_json::from_str(&info).unwrap();
    assert_eq!(i["objects"], v["objects"]);

    one_error(
        &[
            "tiles",
            &p("city.geojson"),
            "--max-features-per-tile",
            "0",
            "-o",
            &p("t0"),
        ],
        "at least 1",
    );
    one_error(
        &["tiles", &p("none.geojson"), "-o", &p("t1")],
        "cannot load",
    );
    ok(&[
        "generate",
        "city",
        "--size",
        "12",
        "--seed",
        "9",
        "-o",
        &p("other.geojson"),
    ]);
    one_error(
        &[
            "tiles",
            &p("other.geojson"),
            "--pvs",
            &p("city.pvs"),
            "-o",
            &p("t2"),
        ],
        "another scene",
    );
    std::fs::create_dir(d.path().join("mine")).unwrap();
    std::fs::write(d.path().join("mine/keep.txt"), "x").unwrap();
    one_error(
        &["tiles", &p("city.geojson"), "-o", &p("mine")],
        "not a tileset folder",
    );
    for t in ["t0", "t1", "t2"] {
        assert!(!d.path().join(t).exists(), "{t} written on error");
    }
}
