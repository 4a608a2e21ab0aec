//! `sightline generate` end to end through the binary.

use std::path::Path;
use std::process::{Command, Output};

fn sightline(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sightline"))
        .args(args)
        .output()
        .expect("run sightline")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn generate_city_writes_geojson_deterministically() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.geojson"), dir.path().join("b.geojson"));
    for f in [&a, &b] {
        let o = sightline(&[
            "generate",
            "city",
            "--seed",
            "3",
            "--size",
            "40",
            "-o",
            path(f),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let bytes = std::fs::read(&a).unwrap();
    assert_eq!(bytes, std::fs::read(&b).unwrap(), "same seed, same bytes");
    let v: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
    let features = v["features"].as_array().unwrap();
    let buildings = features
        .iter()
        .filter(|f| f["properties"].get("height").is_some())
        .count();
    assert_eq!(buildings, 40);
    assert!(features.iter().any(|f| f["properties"]["kind"] == "street"));
}

#[test]
fn generate_forest_writes_obj_and_refuses_geojson() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("forest.obj");
    let o = sightline(&[
        "generate",
        "forest",
        "--size",
        "5",
        "--leaves",
        "20",
        "-o",
        path(&obj),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&obj).unwrap();
    assert_eq!(text.lines().filter(|l| l.starts_with("o ")).count(), 5);
    assert_eq!(
        text.lines().filter(|l| l.starts_with("f ")).count(),
        5 * (12 + 40)
    );

    let gj = dir.path().join("forest.geojson");
    let o = sightline(&["generate", "forest", "-o", path(&gj)]);
    assert!(!o.status.success());
    let err = stderr(&o);
    assert!(err.starts_with("error:") && err.contains(".obj"), "{err}");
    assert_eq!(err.lines().count(), 1);
    assert!(!gj.exists(), "no file on error");
}

#[test]
fn generate_rejects_bad_sizes_and_formats() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.geojson");
    for args in [
        vec!["generate", "city", "--size", "0", "-o", path(&out)],
        vec![
            "generate",
            "metropolis",
            "--size",
            "99999999999",
            "-o",
            path(&out),
        ],
        vec![
            "generate", "forest", "--size", "1000", "--leaves", "100000", "-o", "f.obj",
        ],
        vec!["generate", "city", "-o", "city.txt"],
        vec!["generate", "city", "--leaves", "3", "-o", path(&out)],
    ] {
        let o = sightline(&args);
        assert!(!o.status.success(), "{args:?} should fail");
        assert!(stderr(&o).starts_with("error:"), "{args:?}: {}", stderr(&o));
    }
    assert!(!out.exists());
}

#[test]
fn generate_metropolis_small() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.geojson");
    let o = sightline(&["generate", "metropolis", "--size", "500", "-o", path(&out)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(v["features"].as_array().unwrap().len(), 500);
    assert!(String::from_utf8_lossy(&o.stdout).contains("500 objects"));
}

#[test]
fn cells_on_a_generated_city() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("city.geojson");
    let o = sightline(&["generate", "city", "--size", "60", "-o", path(&scene)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cells = dir.path().join("cells.json");
    let o = sightline(&[
        "cells",
        path(&scene),
        "--size",
        "40",
        "--z",
        "1.5:2",
        "-o",
        path(&cells),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: Vec<[f64; 6]> = serde_json::from_slice(&std::fs::read(&cells).unwrap()).unwrap();
    assert!(!v.is_empty());
    assert!(v
        .iter()
        .all(|c| c[3] - c[0] == 40.0 && c[2] == 1.5 && c[5] == 2.0));
    assert!(String::from_utf8_lossy(&o.stdout).contains(&format!("{} cells", v.len())));

    // Clipped to a small square around the first cell: only cells meeting it stay.
    let clip = dir.path().join("clip.geojson");
    let [x0, y0, _, x1, y1, _] = v[0];
    let (cx, cy) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
    let poly = serde_json::json!({"type": "Polygon", "coordinates": [[
        [cx - 1.0, cy - 1.0], [cx + 1.0, cy - 1.0], [cx + 1.0, cy + 1.0], [cx - 1.0, cy + 1.0], [cx - 1.0, cy - 1.0]
    ]]});
    std::fs::write(&clip, poly.to_string()).unwrap();
    let clipped = dir.path().join("clipped.json");
    let o = sightline(&[
        "cells",
        path(&scene),
        "--size",
        "40",
        "--clip",
        path(&clip),
        "-o",
        path(&clipped),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let w: Vec<[f64; 6]> = serde_json::from_slice(&std::fs::read(&clipped).unwrap()).unwrap();
    assert!(w.len() == 1 || w.is_empty(), "{w:?}");
}

#[test]
fn cells_rejects_bad_arguments_with_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("city.geojson");
    let o = sightline(&["generate", "city", "--size", "20", "-o", path(&scene)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = dir.path().join("cells.json");
    let bad_clip = dir.path().join("clip.geojson");
    std::fs::write(
        &bad_clip,
        "{\"type\": \"Polygon\", \"coordinates\": [[[0, 0], [1, 1]]]}",
    )
    .unwrap();
    for args in [
        vec!["cells", path(&scene), "--z", "2:1", "-o", path(&out)],
        vec!["cells", path(&scene), "--z", "-1:2", "-o", path(&out)],
        vec!["cells", path(&scene), "--z", "abc", "-o", path(&out)],
        vec!["cells", path(&scene), "--z", "1:nan", "-o", path(&out)],
        vec!["cells", path(&scene), "--size", "-3", "-o", path(&out)],
        vec!["cells", path(&scene), "--size", "0", "-o", path(&out)],
        vec!["cells", path(&scene), "--size", "0.0001", "-o", path(&out)],
        vec![
            "cells",
            path(&scene),
            "--clip",
            path(&bad_clip),
            "-o",
            path(&out),
        ],
        vec!["cells", "missing.geojson", "-o", path(&out)],
    ] {
        let o = sightline(&args);
        assert!(!o.status.success(), "{args:?} should fail");
        let err = stderr(&o);
        assert!(
            err.starts_with("error:") && err.lines().count() == 1,
            "{args:?}: {err}"
        );
    }
    assert!(!out.exists(), "no output file on error");
}

#[test]
fn help_lists_every_method_with_its_summary() {
    for args in [
        &["--help"][..],
        &["pvs", "--help"][..],
        &["build", "--help"][..],
    ] {
        let o = sightline(args);
        assert!(o.status.success(), "{args:?}");
        let help = String::from_utf8_lossy(&o.stdout);
        for m in sightline_methods::Method::ALL {
            assert!(
                help.lines()
                    .any(|l| l.trim_start().starts_with(m.name()) && l.contains(m.summary())),
                "{args:?}: {} missing from\n{help}",
                m.name()
            );
        }
    }
}

#[test]
fn demo_runs_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("demo");
    let o = sightline(&["demo", "-o", path(&out), "--quiet"]);
    assert!(o.status.success(), "{}", stderr(&o));
    for f in [
        "city.geojson",
        "cells.json",
        "summary.md",
        "summary.json",
        "city.pvs",
        "map.png",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let png = std::fs::read(out.join("map.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("sightline serve"), "{stdout}");
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("summary.json")).unwrap()).unwrap();
    let methods = v["methods"].as_array().unwrap();
    let all = methods.iter().find(|m| m["method"] == "all").unwrap();
    assert_eq!(
        v["objects"].as_u64().unwrap() as usize,
        all["pvs_median"].as_u64().unwrap() as usize
    );
    let city_methods = sightline_methods::Method::ALL
        .iter()
        .filter(|m| m.works_on(sightline_core::SceneKind::City))
        .count();
    assert_eq!(methods.len(), city_methods);
    // Measured against the ground truth, not claimed: no conservative method misses.
    for m in methods {
        assert!(m["status"].as_str().unwrap().starts_with("ok"), "{m}");
        if m["conservative"] == true {
            assert_eq!(m["missed"], 0, "{m}");
            assert!(m["over_median"].as_f64().unwrap() >= 1.0, "{m}");
        }
    }
    // The `.pvs` is readable and holds the grid.
    let cells: Vec<serde_json::Value> =
        serde_json::from_slice(&std::fs::read(out.join("cells.json")).unwrap()).unwrap();
    let f = sightline_pvs::PvsFile::open(out.join("city.pvs")).unwrap();
    assert_eq!(f.cells().len(), cells.len());
}

#[test]
fn check_runs_the_sweep_from_the_cli() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("dense.obj");
    let o = sightline(&[
        "generate",
        "forest",
        "--dense",
        "--size",
        "9",
        "--leaves",
        "100",
        "-o",
        path(&obj),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cells = dir.path().join("cells.json");
    std::fs::write(&cells, "[[1.75,1.75,1.5,2.25,2.25,2.0]]").unwrap();
    let o = sightline(&[
        "check",
        path(&obj),
        "--method",
        "ext-proj",
        "--sweep",
        "--planes",
        "3",
        "--resolution",
        "64",
        "--cells",
        path(&cells),
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["params"]["sweep"], "true");
    assert_eq!(v["params"]["planes"], "3");
    assert_eq!(v["params"]["resolution"], "64");
    assert_eq!(v["missed"], 0);
    // The sweep flags are refused where they mean nothing.
    for args in [
        vec![
            "check",
            path(&obj),
            "--method",
            "erosion",
            "--sweep",
            "--cells",
            path(&cells),
        ],
        vec![
            "check",
            path(&obj),
            "--method",
            "ext-proj",
            "--planes",
            "3",
            "--cells",
            path(&cells),
        ],
        vec!["generate", "city", "--dense", "-o", path(&obj)],
    ] {
        let o = sightline(&args);
        assert!(!o.status.success(), "{args:?} should fail");
        assert!(stderr(&o).starts_with("error:"), "{args:?}: {}", stderr(&o));
    }
}

#[test]
fn set_gives_knobs_by_key_and_refuses_bad_ones() {
    let dir = tempfile::tempdir().unwrap();
    let city = dir.path().join("city.geojson");
    let o = sightline(&[
        "generate",
        "city",
        "--seed",
        "2",
        "--size",
        "60",
        "-o",
        path(&city),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cell = "--cell=0,0,1.5,20,20,2";
    let ids = |extra: &[&str]| -> Vec<u64> {
        let mut args = vec!["pvs", path(&city), cell, "--method", "dual-ray", "--json"];
        args.extend_from_slice(extra);
        let o = sightline(&args);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        v["visible"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap())
            .collect()
    };
    let base = ids(&[]);
    let vo = ids(&[
        "--set",
        "virtual_occluders=true",
        "--set",
        "seed_rays=false",
    ]);
    // Virtual occluders can only remove hidden objects.
    assert!(vo.iter().all(|i| base.contains(i)));
    for bad in ["nope=1", "hidden_boxes=maybe", "novalue"] {
        let o = sightline(&[
            "pvs",
            path(&city),
            cell,
            "--method",
            "dual-ray",
            "--set",
            bad,
        ]);
        assert!(!o.status.success(), "{bad}");
        let e = stderr(&o);
        assert_eq!(e.trim().lines().count(), 1, "{bad}: {e}");
        assert!(e.starts_with("error:"), "{bad}: {e}");
    }
}
