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
