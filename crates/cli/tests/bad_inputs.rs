//! The bad-input corpus (`tests/bad/`): every malformed file gives exit code 1
//! and exactly one `error:` line naming the problem (`err-*`), or loads with a counted
//! warning of the expected kind (`warn-*`); never a panic, never an output file.

mod common;

use common::sightline;
use std::path::PathBuf;
use std::process::Command;

fn corpus() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/bad")
}

fn cases() -> Vec<(String, String)> {
    let text = std::fs::read_to_string(corpus().join("expected.txt")).unwrap();
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let (f, e) = l.split_once('\t').unwrap();
            (f.to_string(), e.to_string())
        })
        .collect()
}

#[test]
fn corpus_is_large_enough_and_listed() {
    let cases = cases();
    assert!(cases.len() >= 25, "{} cases", cases.len());
    for entry in std::fs::read_dir(corpus()).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        if name != "expected.txt" {
            assert!(
                cases.iter().any(|(f, _)| *f == name),
                "{name} not in expected.txt"
            );
        }
    }
}

#[test]
fn every_bad_input_fails_cleanly_or_warns() {
    let dir = tempfile::tempdir().unwrap();
    let mut failures = Vec::new();
    for (file, expect) in cases() {
        let path = corpus().join(&file);
        let path = path.to_str().unwrap();
        if file.starts_with("err-") {
            let (code, _, err) = sightline(&["info", path]);
            let lines: Vec<&str> = err.lines().collect();
            let ok = code == 1
                && !err.contains("panicked")
                && lines.len() == 1
                && lines[0].starts_with("error: ")
                && lines[0].contains(&expect);
            if !ok {
                failures.push(format!(
                    "{file}: exit {code}, stderr {err:?}, expected {expect:?}"
                ));
            }
            // A command that writes a file leaves nothing behind.
            let out = dir.path().join(format!("{file}.cells.json"));
            let (code, _, err) = sightline(&["cells", path, "-o", out.to_str().unwrap()]);
            if code != 1 || err.contains("panicked") || out.exists() {
                failures.push(format!(
                    "{file}: cells exit {code}, output left: {}",
                    out.exists()
                ));
            }
        } else {
            let (code, stdout, err) = sightline(&["info", path, "--json"]);
            let ok = code == 0
                && !err.contains("panicked")
                && serde_json::from_str::<serde_json::Value>(&stdout)
                    .ok()
                    .and_then(|v| v["warning_counts"][expect.as_str()].as_u64())
                    .is_some_and(|n| n > 0);
            if !ok {
                failures.push(format!("{file}: exit {code}, stdout {stdout}, stderr {err:?}, expected warning {expect}"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn info_reports_real_scenes() {
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data");
    for (file, n) in [
        ("lyon1_bdtopo.geojson", 2570),
        ("denhaag_tile01_lod2.geojson", 1918),
    ] {
        let (code, stdout, err) = sightline(&["info", data.join(file).to_str().unwrap(), "--json"]);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        assert_eq!(v["objects"], n);
        assert_eq!(v["blocks"], n);
        assert_eq!(v["bounds"].as_array().unwrap().len(), 6);
        let (code, text, _) = sightline(&["info", data.join(file).to_str().unwrap()]);
        assert_eq!(code, 0);
        assert!(text.contains(&format!("objects:   {n}")), "{text}");
    }
}

#[test]
fn serve_refuses_a_pvs_of_another_scene_or_a_broken_one() {
    let dir = tempfile::tempdir().unwrap();
    let p = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    for (seed, name) in [("1", "a.geojson"), ("2", "b.geojson")] {
        let (code, _, err) = sightline(&[
            "generate",
            "city",
            "--seed",
            seed,
            "--size",
            "40",
            "-o",
            &p(name),
        ]);
        assert_eq!(code, 0, "{err}");
    }
    let (code, _, err) = sightline(&[
        "cells",
        &p("a.geojson"),
        "--size",
        "100",
        "-o",
        &p("c.json"),
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = sightline(&[
        "build",
        &p("a.geojson"),
        "--cells",
        &p("c.json"),
        "--method",
        "dual-ray",
        "-o",
        &p("a.pvs"),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let bytes = std::fs::read(p("a.pvs")).unwrap();
    std::fs::write(p("cut.pvs"), &bytes[..bytes.len() / 2]).unwrap();
    for (scene, pvs) in [("b.geojson", "a.pvs"), ("a.geojson", "cut.pvs")] {
        let (code, _, err) = sightline(&["serve", &p(scene), &p(pvs), "--addr", "127.0.0.1:0"]);
        let lines: Vec<&str> = err.lines().collect();
        assert!(
            code == 1 && lines.len() == 1 && lines[0].starts_with("error: "),
            "{scene} {pvs}: exit {code}, stderr {err:?}"
        );
    }
}

#[test]
fn a_closed_stdout_ends_quietly() {
    // `sightline info --json | head -0`: the reader is gone before the first line.
    let lyon = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/lyon1_bdtopo.geojson");
    let mut child = Command::new(env!("CARGO_BIN_EXE_sightline"))
        .args(["info", lyon.to_str().unwrap(), "--json"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(out.status.code(), Some(0), "{err}");
}

/// Inputs with a few broken features load the rest (counted `skipped-feature` warnings);
/// `--strict` makes the first broken feature the one error line.
#[test]
fn strict_aborts_where_the_default_skips() {
    for (file, expect) in cases() {
        if !(file.starts_with("warn-") && expect == "skipped-feature") {
            continue;
        }
        let path = corpus().join(&file);
        let (code, _, err) = sightline(&["info", path.to_str().unwrap(), "--strict"]);
        let lines: Vec<&str> = err.lines().collect();
        assert!(
            code == 1
                && lines.len() == 1
                && lines[0].starts_with("error: ")
                && lines[0].contains("feature "),
            "{file}: exit {code}, stderr {err:?}"
        );
    }
}
