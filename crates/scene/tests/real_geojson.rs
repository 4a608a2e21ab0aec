//! The vendored real scenes load with the right counts, bounds and no errors.

use sightline_scene::import::{load, ImportOptions};
use sightline_scene::ObjectKind;
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(name)
}

#[test]
fn lyon_loads_2570_blocks() {
    let s = load(&data("lyon1_bdtopo.geojson"), &ImportOptions::default()).unwrap();
    assert_eq!(s.len(), 2570);
    assert!(s.objects.iter().all(|o| o.kind() == ObjectKind::Blocks));
    // Local frame: -939.14..939.4 x -555.43..554.79, heights 0.7..50.7 m.
    let b = s.bounds;
    assert!((b.min.x + 939.14).abs() < 1e-9 && (b.max.x - 939.4).abs() < 1e-9);
    assert!((b.min.y + 555.43).abs() < 1e-9 && (b.max.y - 554.79).abs() < 1e-9);
    assert_eq!(b.min.z, 0.0);
    assert!((b.max.z - 50.7).abs() < 1e-9);
    assert_eq!(s.objects[0].name.as_deref(), Some("0"));
    // Every exterior is clockwise in the file: reoriented, counted, nothing else serious.
    let counts = s.warning_counts();
    assert!(
        counts
            .iter()
            .all(|(k, _)| k == "wrong-orientation" || k == "duplicate-points"),
        "{counts:?}"
    );
}

#[test]
fn denhaag_loads_1918_blocks() {
    let s = load(
        &data("denhaag_tile01_lod2.geojson"),
        &ImportOptions::default(),
    )
    .unwrap();
    assert_eq!(s.len(), 1918);
    assert!(s.objects.iter().all(|o| o.kind() == ObjectKind::Blocks));
    let b = s.bounds;
    assert!((b.min.x + 339.2).abs() < 1e-9 && (b.max.x - 338.65).abs() < 1e-9);
    assert!((b.min.y + 307.74).abs() < 1e-9 && (b.max.y - 307.86).abs() < 1e-9);
    assert!((b.max.z - 25.07).abs() < 1e-9);
}
