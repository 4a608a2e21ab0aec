//! `query FILE.pvs --can-see A,B --seen-by X,Y,Z --secondary CELL` answers from the
//! sets `query --at` prints: on a city file two cells may see each other when their sets
//! share an object.

mod common;

use common::sightline;
use serde_json::Value;
use std::collections::BTreeSet;

fn ids(v: &Value) -> BTreeSet<u64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect()
}

#[test]
fn gameplay_queries_agree_with_the_sets() {
    let dir = tempfile::tempdir().unwrap();
    let p = |f: &str| dir.path().join(f).to_string_lossy().into_owned();
    let run = |args: &[&str]| {
        let (code, out, err) = sightline(args);
        assert_eq!(code, 0, "{args:?}: {err}");
        out
    };
    run(&["generate", "city", "--size", "40", "-o", &p("c.geojson")]);
    run(&[
        "cells",
        &p("c.geojson"),
        "--size",
        "25",
        "-o",
        &p("cells.json"),
    ]);
    run(&[
        "--quiet",
        "build",
        &p("c.geojson"),
        "--cells",
        &p("cells.json"),
        "--method",
        "erosion",
        "-o",
        &p("c.pvs"),
    ]);
    let cells: Vec<[f64; 6]> =
        serde_json::from_str(&std::fs::read_to_string(p("cells.json")).unwrap()).unwrap();
    let centre = |c: &[f64; 6]| format!("{},{},{}", (c[0] + c[3]) / 2.0, (c[1] + c[4]) / 2.0, 1.75);
    let set = |i: usize| -> BTreeSet<u64> {
        let v: Value = serde_json::from_str(&run(&[
            "query",
            &p("c.pvs"),
            "--at",
            &centre(&cells[i]),
            "--json",
        ]))
        .unwrap();
        assert_eq!(v["index"], i);
        ids(&v["visible"])
    };
    let sets: Vec<BTreeSet<u64>> = (0..cells.len()).map(set).collect();
    let n = cells.len().min(12);
    for a in 0..n {
        let b = (a * 7 + 3) % cells.len();
        let v: Value = serde_json::from_str(&run(&[
            "query",
            &p("c.pvs"),
            "--can-see",
            &format!("{a},{b}"),
            "--seen-by",
            &centre(&cells[a]),
            "--secondary",
            &a.to_string(),
            "--json",
        ]))
        .unwrap();
        assert_eq!(v["relation"], "shared-objects");
        let shares = |x: usize, y: usize| x == y || !sets[x].is_disjoint(&sets[y]);
        assert_eq!(v["can_see"]["visible"], shares(a, b), "{a} sees {b}");
        assert_eq!(v["seen_by"]["cell"], a);
        let seeing: BTreeSet<u64> = (0..cells.len())
            .filter(|&c| shares(a, c))
            .map(|c| c as u64)
            .collect();
        assert_eq!(ids(&v["seen_by"]["cells"]), seeing);
        let union: BTreeSet<u64> = seeing
            .iter()
            .flat_map(|&c| sets[c as usize].clone())
            .collect();
        assert_eq!(ids(&v["secondary"]["visible"]), union);
    }
    let (code, _, err) = sightline(&["query", &p("c.pvs"), "--can-see", "0,99999"]);
    assert_eq!(code, 1);
    assert!(
        err.starts_with("error: ") && err.contains("no cell 99999"),
        "{err}"
    );
    let (code, _, err) = sightline(&["query", &p("c.pvs"), "--can-see", "0"]);
    assert_ne!(code, 0);
    assert!(err.contains("expected A,B"), "{err}");
}
