//! OSM PBF importer on a fixture made with osmium-tool from hand-written XML
//! (`tests/fixtures/buildings.osm` → `buildings.osm.pbf`, committed).

use sightline_scene::import::{load, ImportOptions};
use sightline_scene::{Geometry, ObjectKind};
use std::path::PathBuf;

#[test]
fn buildings_heights_and_multipolygon() {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/buildings.osm.pbf");
    let s = load(&p, &ImportOptions::default()).unwrap();
    let names: Vec<_> = s.objects.iter().map(|o| o.name.clone().unwrap()).collect();
    // Ways 1, 2, 3, 5 (the highway and building=no are not buildings), then relation 10.
    assert_eq!(names, ["way/1", "way/2", "way/3", "way/5", "relation/10"]);
    assert!(s.objects.iter().all(|o| o.kind() == ObjectKind::Blocks));
    let top = |i: usize| s.objects[i].bounds.max.z;
    assert!((top(0) - 12.0).abs() < 1e-9); // "12 m"
    assert!((top(1) - 6.0).abs() < 1e-9); // 2 levels
    assert!((top(2) - 9.0).abs() < 1e-9); // default
    assert!((top(3) - 12.192).abs() < 1e-9); // "40 ft"
    assert!((s.objects[3].bounds.min.z - 3.0).abs() < 1e-9); // min_height
    assert!((top(4) - 20.0).abs() < 1e-9);
    let counts = s.warning_counts();
    assert!(
        counts.contains(&("height-from-levels".to_string(), 1)),
        "{counts:?}"
    );
    assert!(
        counts.contains(&("height-default".to_string(), 1)),
        "{counts:?}"
    );
    // Way 1 is a 20 m square (projected: within 5 cm), the multipolygon 40² − 10².
    let area = |i: usize| match &s.objects[i].geometry {
        Geometry::Blocks(ps) => ps.iter().map(|p| p.footprint.area()).sum::<f64>(),
        _ => 0.0,
    };
    assert!((area(0) - 400.0).abs() < 2.0, "{}", area(0));
    assert!((area(4) - 1500.0).abs() < 8.0, "{}", area(4));
    match &s.objects[4].geometry {
        Geometry::Blocks(ps) => assert_eq!(ps[0].footprint.holes.len(), 1),
        _ => unreachable!(),
    }
}

/// One bad building never aborts a city: each is skipped with a counted warning naming
/// it (the way), the others load; `strict` restores the abort on the first one.
#[test]
fn broken_parts_are_skipped_and_named() {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/broken_parts.osm.pbf");
    let s = load(&p, &ImportOptions::default()).unwrap();
    let names: Vec<_> = s.objects.iter().map(|o| o.name.clone().unwrap()).collect();
    assert_eq!(names, ["way/101", "way/105"]);
    let skipped: Vec<&str> = s
        .warnings
        .iter()
        .filter(|w| w.kind == "skipped-feature")
        .map(|w| w.message.as_str())
        .collect();
    assert_eq!(skipped.len(), 3, "{skipped:?}");
    for (way, why) in [
        ("way/102", "min_height 30 is not below height 9"),
        ("way/103", "node 99 is missing"),
        ("way/104", "not a number"),
    ] {
        assert!(
            skipped.iter().any(|m| m.contains(way) && m.contains(why)),
            "{way}: {why} not in {skipped:?}"
        );
    }
    let strict = ImportOptions {
        strict: true,
        ..ImportOptions::default()
    };
    let e = load(&p, &strict).unwrap_err().to_string();
    assert!(e.contains("way/103"), "{e}");
}
