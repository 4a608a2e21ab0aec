//! Facts about the generated scenes: determinism, counts, party walls, bounds, writers.

use sightline_geom::{boolean, DVec2, Polygon};
use sightline_scene::generate::{self, ForestParams};
use sightline_scene::{export, Geometry, ObjectKind, Scene};
use std::collections::HashMap;

fn blocks(s: &Scene) -> Vec<(usize, &Polygon, f64, f64)> {
    s.objects
        .iter()
        .enumerate()
        .filter_map(|(i, o)| match &o.geometry {
            Geometry::Blocks(p) => Some((i, &p[0].footprint, p[0].base, p[0].top)),
            _ => None,
        })
        .collect()
}

type PointKey = (u64, u64);

fn key(p: DVec2) -> PointKey {
    (p.x.to_bits(), p.y.to_bits())
}

/// Number of footprint edges shared exactly (same two vertices) by two different objects.
fn shared_edges(s: &Scene) -> usize {
    let mut owners: HashMap<(PointKey, PointKey), Vec<usize>> = HashMap::new();
    for (i, fp, _, _) in blocks(s) {
        for (a, b) in fp.edges() {
            let (ka, kb) = (key(a), key(b));
            owners.entry((ka.min(kb), ka.max(kb))).or_default().push(i);
        }
    }
    owners
        .values()
        .filter(|o| o.len() == 2 && o[0] != o[1])
        .count()
}

#[test]
fn city_is_deterministic_and_seed_dependent() {
    let a = generate::city(1, 500);
    let b = generate::city(1, 500);
    assert_eq!(a.fingerprint(), b.fingerprint());
    assert_eq!(a, b);
    assert_ne!(a.fingerprint(), generate::city(2, 500).fingerprint());
}

#[test]
fn city_has_exactly_the_requested_buildings_and_realistic_heights() {
    for n in [1, 37, 500] {
        let s = generate::city(5, n);
        let b = blocks(&s);
        assert_eq!(b.len(), n, "size {n}");
        assert!(b
            .iter()
            .all(|(_, _, base, top)| *base == 0.0 && *top >= 4.0 && *top <= 80.0));
    }
    let s = generate::city(1, 500);
    let tops: Vec<f64> = blocks(&s).iter().map(|b| b.3).collect();
    let houses = tops.iter().filter(|h| (10.0..=25.0).contains(*h)).count();
    let towers = tops.iter().filter(|h| **h >= 40.0).count();
    assert!(houses > 400, "{houses} houses of 10-25 m");
    assert!((3..=40).contains(&towers), "{towers} towers");
    // Streets and squares are flat objects after the buildings.
    let flats = s
        .objects
        .iter()
        .filter(|o| o.kind() == ObjectKind::Flat)
        .count();
    assert!(flats >= 10, "{flats} flat objects");
    assert!(s.objects[..500]
        .iter()
        .all(|o| o.kind() == ObjectKind::Blocks));
    // Names are unique.
    let mut names: Vec<_> = s.objects.iter().map(|o| o.name.clone()).collect();
    names.sort();
    names.dedup();
    assert_eq!(names.len(), s.objects.len());
}

#[test]
fn city_buildings_touch_along_party_walls_without_overlapping() {
    let s = generate::city(1, 500);
    let shared = shared_edges(&s);
    assert!(shared >= 400, "only {shared} party walls");
    // Touching, never overlapping: the union's area is the sum of the footprints'.
    let fps: Vec<Polygon> = blocks(&s).iter().map(|b| b.1.clone()).collect();
    let sum: f64 = fps.iter().map(Polygon::area).sum();
    let union: f64 = boolean::union(&fps).iter().map(Polygon::area).sum();
    assert!((sum - union).abs() < 1e-4 * sum, "sum {sum} union {union}");
    // Touching buildings fuse: far fewer union pieces than buildings.
    assert!(boolean::union(&fps).len() < 150);
}

#[test]
fn metropolis_small_is_sane() {
    let n = 3000;
    let s = generate::metropolis(3, n);
    assert_eq!(s.objects.len(), n);
    assert_eq!(s.fingerprint(), generate::metropolis(3, n).fingerprint());
    let tris: usize = s.objects.iter().map(|o| o.triangle_count()).sum();
    // ≥ 2 M triangles at 150,000 buildings needs ≥ 13.4 per building.
    assert!(tris as f64 / n as f64 >= 13.4, "{tris} triangles");
    let mut h: Vec<f64> = blocks(&s).iter().map(|b| b.3).collect();
    h.sort_by(f64::total_cmp);
    let median = h[n / 2];
    assert!((8.0..=40.0).contains(&median), "median height {median}");
    assert!(h[n - 1] >= 60.0, "no high-rise: max {}", h[n - 1]);
    assert!(h[0] >= 4.0 && h[n - 1] <= 450.0);
    assert!(shared_edges(&s) > n / 4);
    // Lots never overlap.
    let fps: Vec<Polygon> = blocks(&s).iter().map(|b| b.1.clone()).collect();
    let sum: f64 = fps.iter().map(Polygon::area).sum();
    let union: f64 = boolean::union(&fps).iter().map(Polygon::area).sum();
    assert!((sum - union).abs() < 1e-4 * sum, "sum {sum} union {union}");
}

#[test]
fn forest_trees_are_meshes_inside_their_outer_bounds() {
    let p = ForestParams {
        trees: 12,
        leaves_per_tree: 50,
        ..ForestParams::default()
    };
    let s = generate::forest_with(9, &p);
    assert_eq!(s.objects.len(), 12);
    assert_eq!(s.fingerprint(), generate::forest_with(9, &p).fingerprint());
    for o in &s.objects {
        let Geometry::Mesh(m) = &o.geometry else {
            panic!("tree is not a mesh")
        };
        assert_eq!(m.triangles.len(), 12 + 2 * 50);
        assert_eq!(o.inner.len(), 1, "inner bound = trunk prism");
        let trunk = &o.inner[0];
        // The trunk box's vertices are the inner prism's corners.
        assert!(m.vertices[..8]
            .iter()
            .all(|v| trunk.footprint.bbox().contains(v.truncate()) && v.z <= trunk.top));
        // Every vertex lies in some outer prism.
        for v in &m.vertices {
            assert!(o.outer.iter().any(|p| {
                p.footprint.bbox().contains(v.truncate()) && v.z >= p.base && v.z <= p.top
            }));
        }
        assert!(o.bounds.min.z >= 0.0);
    }
    assert_eq!(generate::forest(1, 3).objects[0].triangle_count(), 12 + 400);
}

#[test]
fn geojson_writer_writes_what_the_spec_reads() {
    let s = generate::city(4, 30);
    let mut out = Vec::new();
    export::write_geojson(&s, &mut out).unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["type"], "FeatureCollection");
    let features = v["features"].as_array().unwrap();
    assert_eq!(features.len(), s.objects.len());
    for (f, o) in features.iter().zip(&s.objects) {
        assert_eq!(f["properties"]["name"].as_str(), o.name.as_deref());
        let g = &f["geometry"];
        let polys: Vec<&serde_json::Value> = match g["type"].as_str().unwrap() {
            "Polygon" => vec![&g["coordinates"]],
            "MultiPolygon" => g["coordinates"].as_array().unwrap().iter().collect(),
            t => panic!("unexpected geometry {t}"),
        };
        for p in polys {
            for ring in p.as_array().unwrap() {
                let r = ring.as_array().unwrap();
                assert!(r.len() >= 4);
                assert_eq!(r[0], r[r.len() - 1], "ring not closed");
            }
        }
        match &o.geometry {
            Geometry::Blocks(p) => {
                assert_eq!(f["properties"]["height"].as_f64(), Some(p[0].top));
                assert!(f["properties"].get("min_height").is_none());
                assert!(f["properties"].get("kind").is_none());
            }
            Geometry::Flat(_) => assert_eq!(f["properties"]["kind"], "street"),
            Geometry::Mesh(_) => unreachable!(),
        }
    }
    // Coordinates survive the round trip bit for bit.
    let Geometry::Blocks(p) = &s.objects[0].geometry else {
        unreachable!()
    };
    let x = features[0]["geometry"]["coordinates"][0][0][0]
        .as_f64()
        .unwrap();
    assert_eq!(x.to_bits(), p[0].footprint.exterior[0].x.to_bits());
    // A raised block writes min_height; a mesh is refused.
    let raised = Scene::from_objects(vec![sightline_scene::Object::block(
        None,
        Polygon::rect(DVec2::ZERO, DVec2::ONE),
        3.0,
        9.0,
    )]);
    let mut out = Vec::new();
    export::write_geojson(&raised, &mut out).unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(v["features"][0]["properties"]["min_height"], 3.0);
    let err = export::write_geojson(&generate::forest(1, 1), &mut Vec::new()).unwrap_err();
    assert!(err.to_string().contains("mesh"), "{err}");
}

#[test]
fn obj_writer_writes_one_object_per_tree() {
    let s = generate::forest_with(
        2,
        &ForestParams {
            trees: 3,
            leaves_per_tree: 10,
            ..ForestParams::default()
        },
    );
    let mut out = Vec::new();
    export::write_obj(&s, &mut out).unwrap();
    let text = String::from_utf8(out).unwrap();
    assert_eq!(text.lines().filter(|l| l.starts_with("o ")).count(), 3);
    assert_eq!(
        text.lines().filter(|l| l.starts_with("v ")).count(),
        3 * (8 + 40)
    );
    assert_eq!(
        text.lines().filter(|l| l.starts_with("f ")).count(),
        3 * (12 + 20)
    );
    let max_index: usize = text
        .lines()
        .filter(|l| l.starts_with("f "))
        .flat_map(|l| l[2..].split(' ').map(|i| i.parse::<usize>().unwrap()))
        .max()
        .unwrap();
    assert_eq!(max_index, 3 * 48);
}

/// A forest written as OBJ loads back upright (the importer reads OBJ as y-up).
#[test]
fn obj_round_trips_through_the_importer() {
    use sightline_scene::import::obj;
    let s = generate::forest_with(
        3,
        &ForestParams {
            trees: 4,
            leaves_per_tree: 20,
            ..ForestParams::default()
        },
    );
    let mut out = Vec::new();
    export::write_obj(&s, &mut out).unwrap();
    let back = obj::parse(&out, &Default::default()).unwrap();
    assert_eq!(back.objects.len(), s.objects.len());
    for (a, b) in s.objects.iter().zip(&back.objects) {
        assert!(
            (a.bounds.min - b.bounds.min).abs().max_element() < 1e-3
                && (a.bounds.max - b.bounds.max).abs().max_element() < 1e-3,
            "{:?} came back as {:?}",
            a.bounds,
            b.bounds
        );
    }
}

#[test]
fn geojson_round_trips_through_the_importer() {
    use sightline_scene::import::{geojson, ImportOptions};
    // A tiny city fits in the lon/lat ranges: the local frame marker keeps it metric.
    for s in [
        generate::city(1, 3),
        generate::city(2, 120),
        generate::metropolis(1, 200),
    ] {
        let mut out = Vec::new();
        export::write_geojson(&s, &mut out).unwrap();
        let back = geojson::parse(&out, &ImportOptions::default()).unwrap();
        assert_eq!(back.objects.len(), s.objects.len());
        assert_eq!(
            back.fingerprint(),
            s.fingerprint(),
            "geometry changed in the round trip"
        );
        assert_eq!(shared_edges(&back), shared_edges(&s));
        let names = |s: &Scene| s.objects.iter().map(|o| o.name.clone()).collect::<Vec<_>>();
        assert_eq!(names(&back), names(&s));
    }
}
