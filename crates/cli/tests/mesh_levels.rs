//! Mesh levels on the command line: automatic cells (`cells LEVEL.obj`), `pvs LEVEL.obj
//! --at X,Y,Z --method portals`, `build LEVEL.obj --method portals` and `query`.

mod common;

use common::sightline;
use sightline_autocells::testlevel::two_rooms_and_a_door;

fn level(dir: &std::path::Path) -> String {
    let path = dir.join("rooms.obj");
    let mut f = std::fs::File::create(&path).unwrap();
    sightline_scene::export::write_obj(&two_rooms_and_a_door(0.0), &mut f).unwrap();
    path.to_string_lossy().into_owned()
}

fn ids(v: &serde_json::Value) -> Vec<u64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_u64().unwrap())
        .collect()
}

#[test]
fn pvs_build_query_cells_on_a_mesh_level() {
    let dir = tempfile::tempdir().unwrap();
    let obj = level(dir.path());
    // Objects in info's order: floor, ceiling, walls, crate-a, crate-b, crate-d.
    let (code, out, err) = sightline(&[
        "pvs",
        &obj,
        "--at=-3,-2,1.5",
        "--method",
        "portals",
        "--smallest-hole",
        "0.45",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    let sources = ids(&v["visible_sources"]);
    assert!(
        sources.contains(&4),
        "crate-b through the door: {sources:?}"
    );
    assert!(
        !sources.contains(&5),
        "crate-d around two corners: {sources:?}"
    );
    assert!(!ids(&v["visible"]).is_empty());

    let pvs = dir.path().join("rooms.pvs");
    let pvs_s = pvs.to_string_lossy().into_owned();
    let (code, _, err) = sightline(&[
        "build",
        &obj,
        "--method",
        "portals",
        "--smallest-hole",
        "0.45",
        "-o",
        &pvs_s,
    ]);
    assert_eq!(code, 0, "{err}");
    let (code, out, err) = sightline(&["query", &pvs_s, "--at=-3,-2,1.5", "--json"]);
    assert_eq!(code, 0, "{err}");
    let q: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(ids(&q["visible"]), ids(&v["visible"]));
    assert_eq!(ids(&q["visible_sources"]), sources);

    let cells = dir.path().join("cells.json");
    let cells_s = cells.to_string_lossy().into_owned();
    let (code, _, err) = sightline(&["cells", &obj, "--smallest-hole", "0.45", "-o", &cells_s]);
    assert_eq!(code, 0, "{err}");
    let boxes: Vec<[f64; 6]> =
        serde_json::from_str(&std::fs::read_to_string(&cells).unwrap()).unwrap();
    assert!(boxes.len() > 1);

    // Errors, not panics.
    let (code, _, err) = sightline(&[
        "pvs",
        &obj,
        "--at=0,-2,1.5",
        "--method",
        "portals",
        "--smallest-hole",
        "0.45",
    ]);
    assert_ne!(code, 0);
    assert!(err.starts_with("error:"), "{err}");
    let (code, _, err) = sightline(&[
        "pvs",
        &obj,
        "--at=-3,-2,1.5",
        "--method",
        "portals",
        "--smallest-hole",
        "1000",
    ]);
    assert_ne!(code, 0);
    assert!(err.contains("larger than the level"), "{err}");
}

#[test]
fn check_judges_the_automatic_cells_by_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let obj = level(dir.path());
    let (code, out, err) = sightline(&[
        "check",
        &obj,
        "--method",
        "portals",
        "--smallest-hole",
        "0.45",
        "--cells",
        "3",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["missed"], 0);
    assert!(v["judged"].as_u64().unwrap() >= 1, "{v}");
    assert!(v["culled_median"].as_f64().unwrap() > 0.0, "{v}");
    let (code, _, err) = sightline(&["check", &obj, "--method", "portals", "--reference", "vis"]);
    assert_ne!(code, 0);
    assert!(err.starts_with("error:"), "{err}");
}

#[test]
fn build_defaults_to_walkable_viewcells_on_a_mesh_level() {
    let dir = tempfile::tempdir().unwrap();
    let obj = level(dir.path());
    let pvs = dir.path().join("walk.pvs");
    let pvs_s = pvs.to_string_lossy().into_owned();
    // No --method: volumetric on the walkable viewcells.
    let (code, _, err) = sightline(&["build", &obj, "--smallest-hole", "0.5", "-o", &pvs_s]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("walkable viewcells"), "{err}");
    // A viewer's eye in room A: a walkable viewcell; crate-d, around two corners, hidden.
    let (code, out, err) = sightline(&["query", &pvs_s, "--at=-4.5,-2,1.7", "--json"]);
    assert_eq!(code, 0, "{err}");
    let q: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(q["method"], "volumetric");
    assert_eq!(q["free_space"], false, "{q}");
    let sources = ids(&q["visible_sources"]);
    assert!(sources.contains(&3) && !sources.contains(&5), "{sources:?}");
    // Under the ceiling, above any eye: a free-space cell, flagged, still an answer.
    let (code, out, err) = sightline(&["query", &pvs_s, "--at=-4.5,-2,2.9", "--json"]);
    assert_eq!(code, 0, "{err}");
    let f: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(f["free_space"], true, "{f}");
    assert!(ids(&f["visible"]).len() >= ids(&q["visible"]).len());
    let (code, out, _) = sightline(&["query", &pvs_s, "--at=-4.5,-2,2.9"]);
    assert_eq!(code, 0);
    assert!(out.contains("free space"), "{out}");
    // check judges walkable viewcells by default on a mesh level.
    let (code, out, err) = sightline(&[
        "check",
        &obj,
        "--smallest-hole",
        "0.5",
        "--cells",
        "3",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    let c: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(c["method"], "volumetric");
    assert_eq!(c["missed"], 0);
    assert!(c["judged"].as_u64().unwrap() >= 1, "{c}");
    assert!(c["culled_median"].as_f64().unwrap() > 0.0, "{c}");
    // A bad eye height is one error line.
    let (code, _, err) = sightline(&["build", &obj, "--eye-height", "-1", "-o", &pvs_s]);
    assert_ne!(code, 0);
    assert!(err.starts_with("error:"), "{err}");
}

#[test]
fn spawn_points_and_view_volumes_set_the_viewcells() {
    let dir = tempfile::tempdir().unwrap();
    let obj = level(dir.path());
    // The count `build` reports: "wrote L.pvs: N walkable viewcells and …".
    let viewcells = |err: &str| -> u64 {
        let at = err
            .find(" walkable viewcells")
            .expect("the build's summary");
        err[..at]
            .rsplit(' ')
            .next()
            .and_then(|n| n.parse().ok())
            .expect("a count")
    };
    // `build` of the test level into `out` with `extra` flags.
    let build = |out: &str, extra: &[&str]| {
        let mut a = vec!["build", obj.as_str(), "--smallest-hole", "0.5", "-o", out];
        a.extend_from_slice(extra);
        sightline(&a)
    };
    let all = dir.path().join("all.pvs").to_string_lossy().into_owned();
    let (code, _, err) = build(&all, &[]);
    assert_eq!(code, 0, "{err}");
    let all_cells = viewcells(&err);
    // Every room of the test level is reached from room A: the same viewcells.
    let spawned = dir.path().join("spawn.pvs").to_string_lossy().into_owned();
    let (code, _, err) = build(&spawned, &["--spawn=-4.5,-2,0.1"]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(viewcells(&err), all_cells);
    let (code, out, _) = sightline(&["query", &spawned, "--at=-4.5,-2,1.7", "--json"]);
    assert_eq!(code, 0);
    let q: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(q["free_space"], false, "{q}");
    // View volumes: one box in room A is the one viewcell.
    let boxes = dir.path().join("volumes.json");
    std::fs::write(
        &boxes,
        r#"[{"min": [-5, -2.5, 0.2], "max": [-3, -1, 1.8]}]"#,
    )
    .unwrap();
    let vv = dir.path().join("vv.pvs").to_string_lossy().into_owned();
    let boxes_s = boxes.to_string_lossy().into_owned();
    let (code, _, err) = build(&vv, &["--view-volumes", &boxes_s]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(viewcells(&err), 1);
    let (code, out, _) = sightline(&["query", &vv, "--at=-4,-2,1", "--json"]);
    assert_eq!(code, 0);
    let q: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(q["free_space"], false, "{q}");
    // The same volume as a named object of a mesh file (an editor's occlusion area),
    // beside one the name pattern leaves out: the same file, byte for byte.
    let volume = |name: &str, x0: f64, x1: f64| {
        sightline_scene::Object::block(
            Some(name.into()),
            sightline_geom::Polygon::rect(
                sightline_geom::DVec2::new(x0, -2.5),
                sightline_geom::DVec2::new(x1, -1.0),
            ),
            0.2,
            1.8,
        )
    };
    let volumes = sightline_scene::Scene::from_objects(vec![
        volume("ViewVolume_A", -5.0, -3.0),
        volume("Lamp", 2.0, 3.0),
    ]);
    let volumes_obj = dir.path().join("volumes.obj");
    sightline_scene::export::write_obj(&volumes, &mut std::fs::File::create(&volumes_obj).unwrap())
        .unwrap();
    let volumes_s = volumes_obj.to_string_lossy().into_owned();
    let named = dir.path().join("named.pvs").to_string_lossy().into_owned();
    let (code, _, err) = build(
        &named,
        &[
            "--view-volumes",
            &volumes_s,
            "--view-volume-names",
            "ViewVol*_?",
        ],
    );
    assert_eq!(code, 0, "{err}");
    assert_eq!(viewcells(&err), 1);
    assert_eq!(std::fs::read(&named).unwrap(), std::fs::read(&vv).unwrap());
    let (code, _, err) = build(&named, &["--view-volumes", &volumes_s]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(
        viewcells(&err),
        2,
        "every object of the file without a pattern"
    );
    // Bad input: one error line, no file.
    std::fs::write(&boxes, r#"[{"min": [1, 1, 1]}]"#).unwrap();
    let bad = dir.path().join("bad.pvs");
    let bad_s = bad.to_string_lossy().into_owned();
    for args in [
        vec!["--view-volumes", boxes_s.as_str()],
        vec!["--spawn=-4.5,-2,-50"],
        vec!["--spawn=-4.5,-2,0.1", "--view-volumes", boxes_s.as_str()],
        vec![
            "--view-volumes",
            volumes_s.as_str(),
            "--view-volume-names",
            "Door*",
        ],
        vec!["--view-volume-names", "ViewVolume*"],
        vec![
            "--view-volumes",
            boxes_s.as_str(),
            "--view-volume-names",
            "*",
        ],
    ] {
        let (code, _, err) = build(&bad_s, &args);
        assert_ne!(code, 0, "{args:?}");
        assert!(
            err.starts_with("error:") && err.trim().lines().count() == 1,
            "{err}"
        );
        assert!(!bad.exists());
    }
}
