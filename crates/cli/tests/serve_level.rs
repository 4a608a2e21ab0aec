//! `serve LEVEL.bsp`: the level's PVS built in memory with portals-fast and served on
//! its leaves; the viewer is told it walks a level.

mod common;

use common::sightline;
use std::io::{BufRead, BufReader, Read, Write};
use std::net::TcpStream;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};

fn dm1() -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/quake/dm1.bsp")
        .to_string_lossy()
        .into_owned()
}

/// A server process, killed when dropped.
struct Serve(Child);

impl Drop for Serve {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// Start `sightline serve ARGS --addr 127.0.0.1:0`; the address it listens on (from the
/// line it prints).
fn serve(args: &[&str]) -> (Serve, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_sightline"))
        .args(args)
        .args(["--addr", "127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let guard = Serve(child);
    let mut lines = BufReader::new(stdout).lines();
    let line = lines.next().expect("a line").unwrap();
    let addr = line
        .split("on http://")
        .nth(1)
        .unwrap_or_else(|| panic!("no address in {line:?}"))
        .trim_end_matches('/')
        .to_string();
    (guard, line.replace(&addr, "ADDR") + "|" + &addr)
}

fn get(addr: &str, path: &str) -> (u16, serde_json::Value) {
    let mut s = TcpStream::connect(addr).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut buf = vec![];
    s.read_to_end(&mut buf).unwrap();
    let text = String::from_utf8_lossy(&buf).into_owned();
    let (head, body) = text.split_once("\r\n\r\n").unwrap();
    let status = head.split_whitespace().nth(1).unwrap().parse().unwrap();
    (status, serde_json::from_str(body).unwrap())
}

#[test]
fn serve_dm1_answers_the_scene_and_a_cells_pvs() {
    let (_server, out) = serve(&["serve", &dm1()]);
    let (line, addr) = out.split_once('|').unwrap();
    assert!(
        line.contains("method portals-fast (memory, conservative)"),
        "{line}"
    );
    let (code, scene) = get(addr, "/api/scene");
    assert_eq!(code, 200);
    assert_eq!(scene["kind"], "level");
    assert_eq!(scene["layout"], "cells");
    assert_eq!(scene["eye_height"], 46.0);
    assert_eq!(scene["method"], "portals-fast");
    assert_eq!(scene["source"], "memory");
    let cells = scene["cells"].as_u64().unwrap();
    assert!(cells > 100, "{cells} cells");
    // The start: dm1's info_player_start (324, 1156, 24), at the eye (+22).
    assert_eq!(scene["start"], serde_json::json!([324.0, 1156.0, 46.0]));

    let (code, pvs) = get(addr, "/api/pvs?at=324,1156,46");
    assert_eq!(code, 200, "{pvs}");
    assert_eq!(pvs["method"], "portals-fast");
    let visible: Vec<u64> = serde_json::from_value(pvs["visible"].clone()).unwrap();
    assert!(!visible.is_empty());
    // The same set as `pvs --at` with the same method.
    let (code, json, err) = sightline(&[
        "pvs",
        &dm1(),
        "--at",
        "324,1156,46",
        "--method",
        "portals-fast",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    let want: Vec<u64> = serde_json::from_value(v["visible"].clone()).unwrap();
    assert_eq!(visible, want);

    let (code, e) = get(addr, "/api/pvs?at=100000,0,0");
    assert_eq!(code, 400);
    assert!(e["error"].as_str().unwrap().contains("no cell"), "{e}");
}

#[test]
fn serve_on_a_level_refuses_bad_input_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let city = dir.path().join("c.geojson");
    let city = city.to_str().unwrap();
    let (code, _, err) = sightline(&["generate", "city", "--size", "40", "-o", city]);
    assert_eq!(code, 0, "{err}");
    let pvs = dir.path().join("c.pvs");
    let cells = dir.path().join("c.json");
    let (code, _, err) = sightline(&[
        "cells",
        city,
        "--size",
        "100",
        "-o",
        cells.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, _, err) = sightline(&[
        "build",
        city,
        "--cells",
        cells.to_str().unwrap(),
        "--method",
        "all",
        "-o",
        pvs.to_str().unwrap(),
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let dm1 = dm1();
    let cases: [&[&str]; 3] = [
        // A .pvs of another scene.
        &["serve", &dm1, "--pvs", pvs.to_str().unwrap()],
        &["serve", &dm1, "--eye-height", "-1"],
        &["serve", &dm1, "--method", "portals-nope"],
    ];
    for args in cases {
        let mut all = args.to_vec();
        all.extend(["--addr", "127.0.0.1:0"]);
        let (code, _, err) = sightline(&all);
        let lines: Vec<&str> = err.lines().collect();
        assert!(
            code != 0 && lines.len() == 1 && lines[0].starts_with("error: "),
            "{args:?}: exit {code}, stderr {err:?}"
        );
    }
}

#[test]
fn serve_a_mesh_level_in_memory_and_from_its_pvs() {
    use sightline_autocells::testlevel::two_rooms_and_a_door;
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("rooms.obj");
    let mut f = std::fs::File::create(&obj).unwrap();
    sightline_scene::export::write_obj(&two_rooms_and_a_door(0.0), &mut f).unwrap();
    let obj = obj.to_string_lossy().into_owned();
    let pvs = dir.path().join("rooms.pvs").to_string_lossy().into_owned();
    let walk = dir.path().join("walk.pvs").to_string_lossy().into_owned();
    for (method, out) in [("portals-fast", &pvs), ("volumetric", &walk)] {
        let (code, _, err) = sightline(&[
            "build",
            &obj,
            "--method",
            method,
            "--smallest-hole",
            "0.45",
            "-o",
            out,
            "--quiet",
        ]);
        assert_eq!(code, 0, "{err}");
    }
    let clusters = sightline_pvs::PvsFile::open(&pvs)
        .unwrap()
        .header()
        .object_count;
    // No --method: a mesh level is served on its walkable viewcells, as `build` makes
    // them; --method portals-fast and a --pvs file as asked.
    for (args, method, file) in [
        (
            vec!["serve", &obj, "--smallest-hole", "0.45"],
            "volumetric",
            &walk,
        ),
        (vec!["serve", &obj, "--pvs", &walk], "volumetric", &walk),
        (
            vec![
                "serve",
                &obj,
                "--smallest-hole",
                "0.45",
                "--method",
                "portals-fast",
            ],
            "portals-fast",
            &pvs,
        ),
        (vec!["serve", &obj, "--pvs", &pvs], "portals-fast", &pvs),
    ] {
        let (code, q, err) = sightline(&["query", file, "--at=-3,-2,1.5", "--json"]);
        assert_eq!(code, 0, "{err}");
        let q: serde_json::Value = serde_json::from_str(&q).unwrap();
        let (_server, out) = serve(&args);
        let (line, addr) = out.split_once('|').unwrap();
        assert!(line.contains(&format!("method {method}")), "{line}");
        let (code, scene) = get(addr, "/api/scene");
        assert_eq!(code, 200);
        assert_eq!(scene["kind"], "level");
        assert_eq!(scene["layout"], "cells");
        // The clusters are the objects served.
        assert_eq!(scene["objects"], clusters, "{args:?}");
        // Smallest hole 0.45: the eye at 1.7 (above 2.5 × 0.45; the volumetric default
        // is 1.7 as well).
        assert_eq!(scene["eye_height"], 1.7);
        let start = scene["start"].as_array().expect("a start point").clone();
        if method == "volumetric" {
            // The walk starts on a floor, the eye in a walkable viewcell.
            let at = format!(
                "--at={},{},{}",
                start[0].as_f64().unwrap(),
                start[1].as_f64().unwrap(),
                start[2].as_f64().unwrap()
            );
            let (code, s, err) = sightline(&["query", file, &at, "--json"]);
            assert_eq!(code, 0, "{err}");
            let s: serde_json::Value = serde_json::from_str(&s).unwrap();
            assert_eq!(s["free_space"], false, "{s}");
        }
        let (code, v) = get(addr, "/api/pvs?at=-3,-2,1.5");
        assert_eq!(code, 200, "{v}");
        assert_eq!(v["visible"], q["visible"], "{args:?}");
        assert_eq!(v["cell_id"], q["index"], "{args:?}");
    }
}
