//! Quake levels on the command line: `pvs LEVEL.bsp --at X,Y,Z --method portals`
//! and `info LEVEL.bsp`.

mod common;

use common::sightline;
use std::path::PathBuf;

fn dm1() -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/quake/dm1.bsp")
        .to_string_lossy()
        .into_owned()
}

/// A point in open space: the centre of the first open leaf whose box centre lies in it.
fn open_point() -> [f64; 3] {
    let level = sightline_scene::import::bsp::load_bsp(std::path::Path::new(&dm1())).unwrap();
    (1..=level.visleafs)
        .find_map(|l| {
            let leaf = &level.leaves[l as usize];
            let c = [0, 1, 2].map(|k| 0.5 * (leaf.mins[k] + leaf.maxs[k]));
            (level.is_view_leaf(l) && level.point_leaf(c) == l).then_some(c)
        })
        .unwrap()
}

#[test]
fn pvs_at_a_point_of_dm1() {
    let p = open_point();
    let at = format!("{},{},{}", p[0], p[1], p[2]);
    let mut answers = Vec::new();
    for method in ["portals", "portals-fast"] {
        let (code, out, err) =
            sightline(&["pvs", &dm1(), "--at", &at, "--method", method, "--json"]);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value = serde_json::from_str(&out).unwrap();
        let leaf = v["leaf"].as_u64().unwrap();
        let leaves: Vec<u64> = v["visible_leaves"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap())
            .collect();
        let faces: Vec<u64> = v["visible"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_u64().unwrap())
            .collect();
        assert!(leaves.contains(&leaf));
        assert!(!faces.is_empty() && faces.windows(2).all(|w| w[0] < w[1]));
        assert!(faces.iter().all(|&f| f < 2174));
        answers.push((leaves, faces));
    }
    // portals-fast contains portals.
    let (full, fast) = (&answers[0], &answers[1]);
    assert!(full.0.iter().all(|l| fast.0.contains(l)));
    assert!(full.1.iter().all(|f| fast.1.contains(f)));
}

#[test]
fn bsp_errors_and_info() {
    // A point inside a wall, a portal method on a city scene, --at without a level.
    let (code, _, err) = sightline(&["pvs", &dm1(), "--at", "1e5,1e5,1e5", "--method", "portals"]);
    assert_eq!(code, 1);
    assert!(
        err.starts_with("error: ") && err.contains("not in open space"),
        "{err}"
    );
    let (code, out, err) = sightline(&["info", &dm1(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["objects"], 2174);
    assert_eq!(v["bsp"]["visleafs"], 434);
    assert!(v["bsp"]["portals"].as_u64().unwrap() > 1000);
}

#[test]
fn build_and_query_a_level_by_its_leaves() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("dm1.pvs");
    let out_s = out.to_string_lossy().into_owned();
    let (code, _, err) = sightline(&[
        "build",
        &dm1(),
        "--method",
        "portals-fast",
        "-o",
        &out_s,
        "--quiet",
    ]);
    assert_eq!(code, 0, "{err}");
    let level = sightline_scene::import::bsp::load_bsp(std::path::Path::new(&dm1())).unwrap();
    let file = sightline_pvs::PvsFile::open(&out).unwrap();
    assert_eq!(file.header().method, "portals-fast");
    let open = (1..=level.visleafs)
        .filter(|&l| level.is_view_leaf(l))
        .count();
    assert_eq!(file.cells().len(), open);
    // Point location by the leaves' shapes agrees with the tree's on random points of
    // the level (points within a hair of a node plane may belong to either side).
    let (lo, hi) = (level.bounds.min, level.bounds.max);
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64
    };
    let (mut inside, mut checked) = (0, 0);
    for _ in 0..4000 {
        let p = [
            lo.x + next() * (hi.x - lo.x),
            lo.y + next() * (hi.y - lo.y),
            lo.z + next() * (hi.z - lo.z),
        ];
        let near_plane = level
            .nodes
            .iter()
            .any(|n| level.planes[n.plane as usize].distance(p).abs() < 1e-3);
        if near_plane {
            continue;
        }
        checked += 1;
        let leaf = level.point_leaf(p);
        let found = file.locate(sightline_geom::DVec3::from_array(p));
        if level.is_view_leaf(leaf) {
            inside += 1;
            let i = found.unwrap_or_else(|| panic!("{p:?} in leaf {leaf}: no cell"));
            assert_eq!(file.cell(i).and_then(|c| c.id()), Some(leaf), "{p:?}");
        } else {
            assert_eq!(found, None, "{p:?} in closed leaf {leaf}");
        }
    }
    assert!(checked > 3000 && inside > 100, "{checked} {inside}");
    // `query --at` answers the leaf with the same faces as `pvs --at`.
    let p = open_point();
    let at = format!("{},{},{}", p[0], p[1], p[2]);
    let (code, q, err) = sightline(&["query", &out_s, "--at", &at, "--json"]);
    assert_eq!(code, 0, "{err}");
    let (code, v, err) = sightline(&[
        "pvs",
        &dm1(),
        "--at",
        &at,
        "--method",
        "portals-fast",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let q: serde_json::Value = serde_json::from_str(&q).unwrap();
    let v: serde_json::Value = serde_json::from_str(&v).unwrap();
    assert_eq!(q["leaf"], v["leaf"]);
    assert_eq!(q["visible"], v["visible"]);
    assert_eq!(q["visible_leaves"], v["visible_leaves"]);
    assert!(q["visible_leaves"]
        .as_array()
        .is_some_and(|l| !l.is_empty()));
    // On random open points the file answers what `pvs --at` computes (the same
    // library calls, in process): the leaf, its faces and its visible leaves.
    assert!(file.has_visible_leaves());
    let direct = sightline_portals::PortalMethod::new(
        sightline_portals::Portals::build(&level).unwrap(),
        sightline_portals::Mode::Fast,
    );
    let mut compared = 0;
    while compared < 300 {
        let p = [
            lo.x + next() * (hi.x - lo.x),
            lo.y + next() * (hi.y - lo.y),
            lo.z + next() * (hi.z - lo.z),
        ];
        let leaf = level.point_leaf(p);
        let near_plane = level
            .nodes
            .iter()
            .any(|n| level.planes[n.plane as usize].distance(p).abs() < 1e-3);
        if !level.is_view_leaf(leaf) || near_plane {
            continue;
        }
        compared += 1;
        let i = file.locate(sightline_geom::DVec3::from_array(p)).unwrap();
        assert_eq!(file.cell(i).and_then(|c| c.id()), Some(leaf), "{p:?}");
        let want = direct.leaf_pvs(leaf);
        assert_eq!(file.pvs(i).unwrap(), want.faces, "{p:?} leaf {leaf}");
        assert_eq!(
            file.visible_leaves(i),
            Some(want.leaves.as_slice()),
            "{p:?}"
        );
    }
    // A cells file, shards or resume make no sense for a level: one-line errors.
    let (code, _, err) = sightline(&[
        "build",
        &dm1(),
        "--method",
        "portals",
        "--cells",
        "x.json",
        "-o",
        &out_s,
    ]);
    assert_ne!(code, 0);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

#[test]
fn check_a_level_against_its_own_vis_and_the_oracle() {
    let (code, out, err) = sightline(&[
        "check",
        &dm1(),
        "--method",
        "portals-fast",
        "--reference",
        "vis",
        "--cells",
        "12",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["visleafs"], 434);
    assert_eq!(v["sources"], 12);
    assert_eq!(v["missed_pairs"], 0);
    assert_eq!(v["reference_only_clear"], 0);
    // The flood bound holds vis's rows (vis is conservative too, and tighter).
    assert!(v["leaves_ours"].as_u64().unwrap() >= v["leaves_reference"].as_u64().unwrap());
    assert!(v["faces_ours"].as_u64().unwrap() > 0);
    // --reference belongs to a level with a portal method.
    let (code, _, err) = sightline(&["check", &dm1(), "--method", "erosion", "--reference", "vis"]);
    assert_ne!(code, 0);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}

#[test]
fn map_of_a_level_shows_visible_and_culled_floors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("map.png");
    let out_s = out.to_string_lossy().into_owned();
    let p = open_point();
    let at = format!("{},{},{}", p[0], p[1], p[2]);
    let (code, stdout, err) = sightline(&[
        "map",
        &dm1(),
        "--at",
        &at,
        "--method",
        "portals-fast",
        "-o",
        &out_s,
    ]);
    assert_eq!(code, 0, "{err}");
    assert!(
        stdout.contains("faces") && stdout.contains("leaves"),
        "{stdout}"
    );
    let img = image::open(&out).unwrap().to_rgb8();
    // Above the legend (130 px): floors in the PVS (blue) and culled floors (grey).
    let count = |c: [u8; 3]| {
        img.enumerate_pixels()
            .filter(|(_, y, px)| *y + 130 < img.height() && px.0 == c)
            .count()
    };
    let (seen, culled) = (count([40, 90, 200]), count([215, 215, 215]));
    assert!(seen > 1000 && culled > 1000, "{seen} {culled}");
    // A point in a wall, a city method, no --at: one-line errors.
    for args in [
        vec!["map", &dm1(), "--at", "1e5,1e5,1e5", "-o", &out_s],
        vec![
            "map",
            &dm1(),
            "--at",
            &at,
            "--method",
            "erosion",
            "-o",
            &out_s,
        ],
        vec!["map", &dm1(), "--cell", "0,0,0,1,1,1", "-o", &out_s],
    ] {
        let (code, _, err) = sightline(&args);
        assert_ne!(code, 0, "{args:?}");
        assert!(err.starts_with("error: "), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}

#[test]
fn bench_levels_that_do_not_exist_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("report").to_string_lossy().into_owned();
    let empty = dir.path().to_string_lossy().into_owned();
    for levels in ["/nonexistent/level.bsp", empty.as_str()] {
        let (code, _, err) = sightline(&["bench", "--indoor-only", "--levels", levels, "-o", &out]);
        assert_ne!(code, 0);
        assert!(err.starts_with("error: "), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
}
