//! `sightline frames` end to end through the binary: a path file, a generated walk on a
//! real city, two-level culling inside a `.pvs`, and bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn sightline(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_sightline"))
        .args(args)
        .output()
        .expect("run sightline")
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn lyon() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/lyon1_bdtopo.geojson")
}

fn json(o: &Output) -> serde_json::Value {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).expect("JSON output")
}

#[test]
fn a_path_file_gives_one_answer_per_frame_with_medians() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("path.json");
    // Fixture: the wall 0..3 m high hides the low block behind it; the frame looking
    // away sees neither.
    let scene = dir.path().join("s.geojson");
    std::fs::write(
        &scene,
        r#"{"type":"FeatureCollection","features":[
        {"type":"Feature","properties":{"height":3},"geometry":{"type":"Polygon","coordinates":[[[-20,10],[20,10],[20,11],[-20,11],[-20,10]]]}},
        {"type":"Feature","properties":{"height":3},"geometry":{"type":"Polygon","coordinates":[[[-2,20],[2,20],[2,24],[-2,24],[-2,20]]]}},
        {"type":"Feature","properties":{"height":60},"geometry":{"type":"Polygon","coordinates":[[[-2,30],[2,30],[2,34],[-2,34],[-2,30]]]}}]}"#,
    )
    .unwrap();
    std::fs::write(
        &p,
        r#"[{"eye":[0,0,1.7],"dir":[0,1,0],"fov_deg":60},{"eye":[0,0,1.7],"dir":[0,-1,0]}]"#,
    )
    .unwrap();
    for m in ["hzb", "hom", "cplp"] {
        let v = json(&sightline(&[
            "frames",
            path(&scene),
            "--path",
            path(&p),
            "--method",
            m,
            "--size",
            "320x180",
            "--json",
        ]));
        assert_eq!(v["method"], m);
        assert_eq!(v["conservative"], true);
        let frames = v["frames"].as_array().unwrap();
        assert_eq!(frames.len(), 2);
        assert_eq!(frames[0]["visible"], serde_json::json!([0, 2]), "{m}");
        assert_eq!(frames[1]["visible"], serde_json::json!([]), "{m}");
        assert!(frames[0]["culled_pct"].as_f64().unwrap() > 33.0);
        assert!(frames[0]["ms"].as_f64().is_some());
        assert!(v["median_ms"].as_f64().is_some() && v["median_culled_pct"].as_f64().is_some());
    }
    let v = json(&sightline(&[
        "frames",
        path(&scene),
        "--path",
        path(&p),
        "--method",
        "hom-approx",
        "--json",
    ]));
    assert_eq!(v["conservative"], false);
}

#[test]
fn a_walk_through_lyon_culls_most_of_the_city() {
    let v = json(&sightline(&[
        "frames",
        path(&lyon()),
        "--walk",
        "5",
        "--size",
        "640x360",
        "--json",
    ]));
    let frames = v["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 5);
    assert!(
        v["median_culled_pct"].as_f64().unwrap() > 50.0,
        "{}",
        v["median_culled_pct"]
    );
    for f in frames {
        let ids: Vec<u64> = f["visible"]
            .as_array()
            .unwrap()
            .iter()
            .map(|i| i.as_u64().unwrap())
            .collect();
        assert!(ids.windows(2).all(|w| w[0] < w[1]), "sorted ascending");
    }
}

#[test]
fn two_level_culling_stays_inside_the_cell_pvs() {
    let dir = tempfile::tempdir().unwrap();
    let (scene, cells, pvs) = (
        dir.path().join("c.geojson"),
        dir.path().join("cells.json"),
        dir.path().join("c.pvs"),
    );
    assert!(
        sightline(&["generate", "city", "--size", "80", "-o", path(&scene)])
            .status
            .success()
    );
    assert!(
        sightline(&["cells", path(&scene), "--size", "100", "-o", path(&cells)])
            .status
            .success()
    );
    let b = sightline(&[
        "--quiet",
        "build",
        path(&scene),
        "--cells",
        path(&cells),
        "--method",
        "erosion",
        "-o",
        path(&pvs),
    ]);
    assert!(b.status.success(), "{}", String::from_utf8_lossy(&b.stderr));
    let v = json(&sightline(&[
        "frames",
        path(&scene),
        "--walk",
        "6",
        "--pvs",
        path(&pvs),
        "--size",
        "320x180",
        "--json",
    ]));
    assert!(v["median_second_level_removed_pct"].as_f64().is_some());
    for f in v["frames"].as_array().unwrap() {
        if f["cell"].is_null() {
            continue;
        }
        let cell: Vec<f64> = f["cell"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| c.as_f64().unwrap())
            .collect();
        let q = json(&sightline(&[
            "query",
            path(&pvs),
            "--at",
            &format!(
                "{},{},{}",
                (cell[0] + cell[3]) / 2.0,
                (cell[1] + cell[4]) / 2.0,
                (cell[2] + cell[5]) / 2.0
            ),
            "--json",
        ]));
        let in_pvs = q["visible"].as_array().unwrap();
        for id in f["visible"].as_array().unwrap() {
            assert!(in_pvs.contains(id), "{id} not in the cell's PVS");
        }
    }
}

#[test]
fn bad_input_is_a_one_line_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("p.json");
    let lyon = lyon();
    for (content, args, what) in [
        (r#"[{"eye":[0,0,1.7],"dir":[0,0,0]}]"#, vec![], "direction"),
        (
            r#"[{"eye":[0,0,1.7],"dir":[0,1,0],"fov_deg":0}]"#,
            vec![],
            "field of view",
        ),
        (r#"{"eye":[0,0,1.7]}"#, vec![], "JSON list"),
        (
            r#"[{"eye":[0,0,1.7],"dir":[0,1,0]}]"#,
            vec!["--size", "0x10"],
            "buffer",
        ),
        (
            r#"[{"eye":[0,0,1.7],"dir":[0,1,0]}]"#,
            vec!["--size", "big"],
            "WIDTHxHEIGHT",
        ),
        (
            r#"[{"eye":[0,0,1.7],"dir":[0,1,0]}]"#,
            vec!["--method", "zbuf"],
            "unknown culling method",
        ),
    ] {
        std::fs::write(&p, content).unwrap();
        let mut a = vec!["frames", path(&lyon), "--path", path(&p)];
        a.extend(args);
        let o = sightline(&a);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{content}");
        assert!(err.starts_with("error:") && err.contains(what), "{err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    let o = sightline(&["frames", path(&lyon), "--walk", "0"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("--walk"));
}

#[test]
fn a_bsp_level_walk_uses_its_faces_as_occluders() {
    let bsp = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/quake/dm1.bsp");
    let o = sightline(&[
        "frames",
        path(&bsp),
        "--walk",
        "6",
        "--eye-height",
        "46",
        "--size",
        "320x180",
        "--json",
    ]);
    let v = json(&o);
    assert_eq!(v["occluders"], "surfaces");
    assert!(v["surface_occluders"].as_u64().unwrap() > 1000, "{v}");
    assert_eq!(v["frames"].as_array().unwrap().len(), 6);
    let occluded: u64 = v["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["occlusion_culled"].as_u64().unwrap())
        .sum();
    assert!(occluded > 0, "{v}");
    // Prisms only: a BSP level has none, nothing is occlusion-culled.
    let o = sightline(&[
        "frames",
        path(&bsp),
        "--walk",
        "2",
        "--eye-height",
        "46",
        "--size",
        "320x180",
        "--occluders",
        "prisms",
        "--json",
    ]);
    let v = json(&o);
    assert_eq!(v["occluders"], "prisms");
    for f in v["frames"].as_array().unwrap() {
        assert_eq!(f["occlusion_culled"], 0, "{f}");
    }
    let o = sightline(&["frames", path(&bsp), "--walk", "2", "--eye-height", "-1"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--eye-height"));
}
