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
