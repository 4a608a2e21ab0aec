//! `sightline clusters LEVEL.obj`: the listing's triangle indices are the file's faces
//! (after triangulation) and rebuild the importer's clusters; the GLB has one node per
//! cluster, named by its id, holding exactly its triangles; the ids are the `.pvs`'s.

mod common;

use common::sightline;
use sightline_geom::DVec3;
use std::fmt::Write as _;
use std::path::Path;

/// An OBJ with quads, a pentagon, triangles and several groups (one name used twice,
/// an unnamed start): a 10 × 10 floor of unit quads in group `floor`, walls of quads,
/// a roof with a pentagon, then `floor` again with one more quad.
fn quads_level(dir: &Path) -> String {
    let mut s = String::from("# test level\nvt 0 0\n");
    let mut n = 0;
    let mut v = |s: &mut String, x: f64, y: f64, z: f64| {
        writeln!(s, "v {x} {y} {z}").unwrap();
        n += 1;
        n
    };
    // y-up: the floor is the plane y = 0.
    let mut grid = vec![vec![0; 11]; 11];
    for (i, row) in grid.iter_mut().enumerate() {
        for (j, g) in row.iter_mut().enumerate() {
            *g = v(&mut s, i as f64, 0.0, j as f64);
        }
    }
    let top: Vec<usize> = [(0.0, 0.0), (10.0, 0.0), (10.0, 10.0), (0.0, 10.0)]
        .iter()
        .map(|&(x, z)| v(&mut s, x, 3.0, z))
        .collect();
    let apex = v(&mut s, 5.0, 4.0, 5.0);
    s.push_str("f 1 2 13\n");
    s.push_str("g floor\n");
    for i in 0..10 {
        for j in 0..10 {
            let (a, b, c, d) = (
                grid[i][j],
                grid[i + 1][j],
                grid[i + 1][j + 1],
                grid[i][j + 1],
            );
            writeln!(s, "f {a} {d} {c} {b}").unwrap();
        }
    }
    s.push_str("g walls\n");
    let corners = [grid[0][0], grid[10][0], grid[10][10], grid[0][10]];
    for k in 0..4 {
        let (a, b) = (corners[k], corners[(k + 1) % 4]);
        let (c, d) = (top[(k + 1) % 4], top[k]);
        writeln!(s, "f {a}/1 {b}/1 {c}/1 {d}/1").unwrap();
    }
    s.push_str("g roof\n");
    writeln!(s, "f {} {} {apex} {} {}", top[0], top[1], top[2], top[3]).unwrap();
    writeln!(s, "f {} {} {}", top[0], top[2], top[3]).unwrap();
    s.push_str("g floor\n");
    writeln!(s, "f {} {} {} {}", top[0], top[3], top[2], top[1]).unwrap();
    let path = dir.join("quads.obj");
    std::fs::write(&path, s).unwrap();
    path.to_string_lossy().into_owned()
}

/// The file's triangles by an independent reading of the OBJ: faces in file order, each
/// polygon fanned from its first vertex, y-up turned to z-up as the importer does.
fn file_triangles(obj: &str) -> Vec<[DVec3; 3]> {
    let text = std::fs::read_to_string(obj).unwrap();
    let mut vs = Vec::new();
    let mut out = Vec::new();
    for line in text.lines() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let p: Vec<f64> = w.map(|x| x.parse().unwrap()).collect();
                vs.push(DVec3::new(p[0], -p[2], p[1]));
            }
            Some("f") => {
                let ids: Vec<usize> = w
                    .map(|x| x.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
                    .collect();
                for k in 2..ids.len() {
                    out.push([vs[ids[0]], vs[ids[k - 1]], vs[ids[k]]]);
                }
            }
            _ => {}
        }
    }
    out
}

fn listing(args: &[&str]) -> serde_json::Value {
    let (code, out, err) = sightline(args);
    assert_eq!(code, 0, "{err}");
    serde_json::from_str(&out).unwrap()
}

fn indices(c: &serde_json::Value) -> Vec<usize> {
    c["triangles"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t.as_u64().unwrap() as usize)
        .collect()
}

/// A triangle as bits, for multiset comparison.
fn key(t: &[DVec3; 3]) -> [u64; 9] {
    let mut k = [0; 9];
    for (i, p) in t.iter().enumerate() {
        for a in 0..3 {
            k[3 * i + a] = p[a].to_bits();
        }
    }
    k
}

fn sorted_keys(t: &[[DVec3; 3]]) -> Vec<[u64; 9]> {
    let mut k: Vec<_> = t.iter().map(key).collect();
    k.sort_unstable();
    k
}

#[test]
fn the_listing_indexes_the_files_triangles_and_rebuilds_the_clusters() {
    let dir = tempfile::tempdir().unwrap();
    let obj = quads_level(dir.path());
    // Smallest hole 0.25: clusters on a grid of 16 × 0.25 = 4 units, so the floor splits.
    let v = listing(&["clusters", &obj, "--smallest-hole", "0.25", "--json"]);
    let file = file_triangles(&obj);
    let scene =
        sightline_scene::import::load(Path::new(&obj), &Default::default()).expect("imports");
    let imported: Vec<[DVec3; 3]> = scene.objects.iter().flat_map(|o| o.triangles()).collect();
    // 1 + 200 + 8 + 3 + 1 + 2 triangles; the importer's order is the file's.
    assert_eq!(file.len(), 215);
    assert_eq!(imported, file);
    assert_eq!(v["triangles"], 215);
    let names: Vec<&str> = v["sources"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap_or("-"))
        .collect();
    assert_eq!(names, ["-", "floor", "walls", "roof", "floor"]);
    assert_eq!(v["sources"][4]["first_triangle"], 213);

    // The same clusters as the importer's level clustered as `build` clusters it.
    let h = v["smallest_hole"].as_f64().unwrap();
    assert_eq!((h, v["cluster_size"].as_f64().unwrap()), (0.25, 4.0));
    let clustered = sightline_scene::clusters::cluster_scene(
        &scene,
        4.0,
        sightline_autocells::MAX_CLUSTER_TRIANGLES,
    );
    let clusters = v["clusters"].as_array().unwrap();
    assert_eq!(clusters.len(), clustered.scene.objects.len());
    assert!(clusters.len() >= 9, "the floor spans several cluster cubes");
    let mut seen = vec![0; file.len()];
    for (c, entry) in clusters.iter().enumerate() {
        assert_eq!(entry["id"], c);
        assert_eq!(entry["source"], clustered.source[c]);
        let idx = indices(entry);
        assert!(idx.windows(2).all(|w| w[0] < w[1]), "ascending");
        let from_file: Vec<[DVec3; 3]> = idx.iter().map(|&i| file[i]).collect();
        assert_eq!(
            sorted_keys(&from_file),
            sorted_keys(&clustered.scene.objects[c].triangles()),
            "cluster {c}"
        );
        // Every triangle lies in its cluster's box, in the source object's range.
        let b: Vec<f64> = serde_json::from_value(entry["bounds"].clone()).unwrap();
        let src = &v["sources"][entry["source"].as_u64().unwrap() as usize];
        let (first, n) = (
            src["first_triangle"].as_u64().unwrap() as usize,
            src["triangles"].as_u64().unwrap() as usize,
        );
        for &i in &idx {
            seen[i] += 1;
            assert!((first..first + n).contains(&i));
            for p in file[i] {
                assert!(
                    (0..3).all(|a| b[a] <= p[a] && p[a] <= b[a + 3]),
                    "{p} in {b:?}"
                );
            }
        }
    }
    assert!(seen.iter().all(|&s| s == 1), "each triangle in one cluster");

    // -o L.json writes the same listing.
    let out = dir.path().join("l.json");
    let (code, _, err) = sightline(&[
        "clusters",
        &obj,
        "--smallest-hole",
        "0.25",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let written: serde_json::Value = serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap();
    assert_eq!(written, v);
}

#[test]
fn the_glb_has_one_node_per_cluster_named_by_its_id() {
    let dir = tempfile::tempdir().unwrap();
    let obj = quads_level(dir.path());
    let glb = dir.path().join("level.glb");
    let glb_s = glb.to_string_lossy().into_owned();
    let (code, _, err) = sightline(&["clusters", &obj, "--smallest-hole", "0.25", "-o", &glb_s]);
    assert_eq!(code, 0, "{err}");
    let v = listing(&["clusters", &obj, "--smallest-hole", "0.25", "--json"]);
    let clusters = v["clusters"].as_array().unwrap();
    let file = file_triangles(&obj);

    let (doc, buffers, _) = gltf::import(&glb).expect("a valid glTF");
    let scene = doc.default_scene().expect("a default scene");
    assert_eq!(doc.scenes().count(), 1);
    let nodes: Vec<gltf::Node> = scene.nodes().collect();
    assert_eq!(nodes.len(), clusters.len());
    let mut total = 0;
    for (node, c) in nodes.iter().zip(clusters) {
        assert_eq!(node.name(), Some(c["id"].to_string().as_str()));
        let extras: serde_json::Value =
            serde_json::from_str(node.extras().as_ref().unwrap().get()).unwrap();
        assert_eq!(
            (&extras["cluster"], &extras["source"]),
            (&c["id"], &c["source"])
        );
        let mesh = node.mesh().expect("a mesh");
        let mut tris = Vec::new();
        for prim in mesh.primitives() {
            assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles);
            let r = prim.reader(|b| Some(&buffers[b.index()].0[..]));
            let pos: Vec<[f32; 3]> = r.read_positions().unwrap().collect();
            let normals: Vec<[f32; 3]> = r.read_normals().unwrap().collect();
            assert!(normals
                .iter()
                .all(|n| ((n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt() - 1.0).abs() < 1e-5));
            let idx: Vec<u32> = r.read_indices().unwrap().into_u32().collect();
            for t in idx.chunks_exact(3) {
                // glTF y-up (x, y, z) is sightline's (x, −z, y).
                let p = |i: u32| {
                    let p = pos[i as usize];
                    DVec3::new(p[0] as f64, -p[2] as f64, p[1] as f64)
                };
                tris.push([p(t[0]), p(t[1]), p(t[2])]);
            }
        }
        // Node triangle k is the listing's triangle k: the file's, in its order.
        let expected: Vec<[DVec3; 3]> = indices(c).iter().map(|&i| file[i]).collect();
        assert_eq!(tris, expected, "node {:?}", node.name());
        total += tris.len();
    }
    assert_eq!(total, file.len());
    let asset: serde_json::Value =
        serde_json::from_str(doc.as_json().asset.extras.as_ref().unwrap().get()).unwrap();
    assert_eq!(asset["sightline"]["fingerprint"], v["fingerprint"]);
}

/// The listing's ids are those of `build`'s `.pvs`: `--pvs` checks the fingerprint,
/// and `--smallest-hole` with the build's value gives the same listing.
#[test]
fn cluster_ids_are_the_pvs_ids() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("rooms.obj");
    let mut f = std::fs::File::create(&obj).unwrap();
    sightline_scene::export::write_obj(
        &sightline_autocells::testlevel::two_rooms_and_a_door(0.0),
        &mut f,
    )
    .unwrap();
    let obj = obj.to_string_lossy().into_owned();
    let pvs = dir.path().join("rooms.pvs").to_string_lossy().into_owned();
    let (code, _, err) = sightline(&[
        "build",
        &obj,
        "--method",
        "portals-fast",
        "--smallest-hole",
        "0.45",
        "-o",
        &pvs,
    ]);
    assert_eq!(code, 0, "{err}");
    let by_file = listing(&["clusters", &obj, "--pvs", &pvs, "--json"]);
    let by_hole = listing(&["clusters", &obj, "--smallest-hole", "0.45", "--json"]);
    assert_eq!(by_file["clusters"], by_hole["clusters"]);
    assert_eq!(by_file["fingerprint"], by_hole["fingerprint"]);
    let (code, out, err) = sightline(&["query", &pvs, "--at=-3,-2,1.5", "--json"]);
    assert_eq!(code, 0, "{err}");
    let q: serde_json::Value = serde_json::from_str(&out).unwrap();
    let n = by_file["clusters"].as_array().unwrap().len() as u64;
    for id in q["visible"].as_array().unwrap() {
        assert!(id.as_u64().unwrap() < n);
    }
    // Sources of the visible clusters, by the listing, are query's.
    let mut sources: Vec<u64> = q["visible"]
        .as_array()
        .unwrap()
        .iter()
        .map(|id| {
            by_file["clusters"][id.as_u64().unwrap() as usize]["source"]
                .as_u64()
                .unwrap()
        })
        .collect();
    sources.sort_unstable();
    sources.dedup();
    let expected: Vec<u64> = q["visible_sources"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_u64().unwrap())
        .collect();
    assert_eq!(sources, expected);

    // Another level's .pvs: an error, and nothing written.
    let other = quads_level(dir.path());
    let glb = dir.path().join("other.glb");
    let (code, _, err) = sightline(&[
        "clusters",
        &other,
        "--pvs",
        &pvs,
        "-o",
        glb.to_str().unwrap(),
    ]);
    assert_ne!(code, 0);
    assert!(
        err.starts_with("error:") && err.contains("fingerprints differ"),
        "{err}"
    );
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(!glb.exists());
}

#[test]
fn bad_input_is_one_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.glb");
    let out_s = out.to_string_lossy().into_owned();
    let broken = dir.path().join("broken.obj");
    std::fs::write(&broken, "v 0 0 0\nv 1 0 0\nf 1 2 7\n").unwrap();
    let geojson = dir.path().join("city.geojson");
    std::fs::write(&geojson, r#"{"type":"FeatureCollection","features":[]}"#).unwrap();
    let obj = quads_level(dir.path());
    let cases: Vec<(Vec<String>, &str)> = vec![
        (vec![broken.to_string_lossy().into()], "broken.obj"),
        (vec![geojson.to_string_lossy().into()], "mesh levels"),
        (
            vec![dir.path().join("none.obj").to_string_lossy().into()],
            "none.obj",
        ),
        (
            vec![obj.clone(), "--smallest-hole=-1".into()],
            "--smallest-hole",
        ),
        (
            vec![obj.clone(), "--smallest-hole=1000".into()],
            "larger than the level",
        ),
    ];
    for (args, says) in cases {
        let mut a = vec!["clusters".to_string()];
        a.extend(args);
        a.extend(["-o".to_string(), out_s.clone()]);
        let a: Vec<&str> = a.iter().map(String::as_str).collect();
        let (code, _, err) = sightline(&a);
        assert_ne!(code, 0, "{a:?}");
        assert!(
            err.starts_with("error:") && err.contains(says),
            "{a:?}: {err}"
        );
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(!out.exists(), "{a:?}");
    }
    let (code, _, err) = sightline(&["clusters", &obj, "-o", "level.txt"]);
    assert_ne!(code, 0);
    assert!(err.contains(".json") && err.contains(".glb"), "{err}");
}
