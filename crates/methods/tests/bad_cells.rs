//! Every method on the cells a user can get wrong: empty scenes, flat and tiny cells,
//! cells far outside the scene, under the ground, inside a building, above everything
//! or covering the whole city. None may panic; each answers a sorted PVS of ids of the
//! scene or a clear error, and the PVS of a conservative method keeps what the ground
//! truth sees.

use sightline_core::check::{TruthOptions, TruthScene};
use sightline_geom::{DVec2, DVec3, Polygon, ViewCell};
use sightline_methods::dual_ray::{DualRay, Planarity};
use sightline_methods::{create, Method, MethodOptions, VisibilityMethod};
use sightline_scene::generate::city;
use sightline_scene::{Object, Scene};
use std::sync::Arc;

fn cell(a: [f64; 6]) -> ViewCell {
    ViewCell::from_array(a).expect("a valid cell")
}

/// Every method, and `dual-ray` with its virtual occluders on.
fn methods(scene: &Arc<Scene>) -> Vec<(String, Box<dyn VisibilityMethod>)> {
    let mut out: Vec<(String, Box<dyn VisibilityMethod>)> = Method::ALL
        .into_iter()
        // The level families are built from levels (`sightline-portals`, `-autocells`).
        .filter(|m| m.works_on(sightline_core::SceneKind::City))
        .map(|m| {
            let made = create(m, scene.clone(), &MethodOptions::default());
            (m.name().to_string(), made.expect("method"))
        })
        .collect();
    let vo = DualRay::new(
        "dual-ray",
        scene.clone(),
        Planarity::Discrete { resolution_px: 128 },
    )
    .with_virtual_occluders(true);
    out.push(("dual-ray+vo".to_string(), Box::new(vo)));
    out
}

/// The cells of the test in `scene` (bounds `b`): each may be odd, none is invalid.
fn odd_cells(scene: &Scene) -> Vec<(&'static str, ViewCell)> {
    let b = scene.bounds;
    let (lo, hi) = (b.min, b.max);
    let inside = scene
        .objects
        .iter()
        .find_map(|o| o.inner.first().map(|p| p.footprint.bbox()))
        .map(|r| {
            let m = r.center();
            cell([m.x - 0.5, m.y - 0.5, 1.0, m.x + 0.5, m.y + 0.5, 1.5])
        });
    let mut cells = vec![
        (
            "flat",
            cell([lo.x - 5.0, lo.y - 5.0, 1.5, lo.x - 1.0, lo.y - 1.0, 1.5]),
        ),
        (
            "tiny",
            cell([
                lo.x - 2.0,
                lo.y - 2.0,
                1.5,
                lo.x - 2.0 + 1e-6,
                lo.y - 2.0 + 1e-6,
                1.5 + 1e-6,
            ]),
        ),
        (
            "far outside",
            cell([
                hi.x + 5e4,
                hi.y + 5e4,
                0.0,
                hi.x + 5e4 + 50.0,
                hi.y + 5e4 + 50.0,
                2.0,
            ]),
        ),
        (
            "under the ground",
            cell([
                lo.x - 30.0,
                lo.y - 30.0,
                -20.0,
                lo.x - 10.0,
                lo.y - 10.0,
                -10.0,
            ]),
        ),
        (
            "above everything",
            cell([
                lo.x,
                lo.y,
                hi.z + 100.0,
                lo.x + 40.0,
                lo.y + 40.0,
                hi.z + 120.0,
            ]),
        ),
        (
            "the whole city",
            cell([lo.x - 1.0, lo.y - 1.0, 0.0, hi.x + 1.0, hi.y + 1.0, 2.0]),
        ),
    ];
    if let Some(c) = inside {
        cells.push(("inside a building", c));
    }
    cells
}

#[test]
fn empty_scene_gives_empty_pvs_for_every_method() {
    let scene = Arc::new(Scene::from_objects(vec![]));
    for (name, m) in methods(&scene) {
        for c in [
            cell([0.0, 0.0, 1.5, 10.0, 10.0, 2.0]),
            cell([-1e5, 3e5, 0.0, -1e5 + 1.0, 3e5 + 1.0, 0.0]),
        ] {
            match m.pvs(&c) {
                Ok(p) => assert!(p.is_empty(), "{name} {c}: {p:?}"),
                Err(e) => assert!(!e.to_string().is_empty(), "{name} {c}"),
            }
        }
    }
}

#[test]
fn odd_cells_answer_without_panicking_and_stay_conservative() {
    let mut scene = city(11, 60);
    // A lone tower far from the blocks: seen from above everything and from far away.
    scene = Scene::from_objects(
        scene
            .objects
            .into_iter()
            .chain([Object::block(
                None,
                Polygon::rect(DVec2::new(-400.0, -400.0), DVec2::new(-390.0, -390.0)),
                0.0,
                80.0,
            )])
            .collect(),
    );
    let scene = Arc::new(scene);
    let n = scene.objects.len() as u32;
    let cells = odd_cells(&scene);
    let oracle = TruthScene::new(&scene);
    let opts = TruthOptions {
        samples: 24,
        resolution_px: 128,
        targeted_rays_per_object: 16,
        seed: 7,
    };
    let all = methods(&scene);
    for (what, c) in &cells {
        let truth = oracle.ground_truth(c, &opts).visible;
        for (name, m) in &all {
            let pvs = match m.pvs(c) {
                Ok(p) => p,
                Err(e) => {
                    // An error is allowed, but it must say something.
                    assert!(!e.to_string().is_empty(), "{name} on {what}");
                    continue;
                }
            };
            assert!(
                pvs.windows(2).all(|w| w[0] < w[1]),
                "{name} on {what}: not sorted"
            );
            assert!(
                pvs.iter().all(|&i| i < n),
                "{name} on {what}: id out of range"
            );
            if name != "sampled" {
                let missed: Vec<u32> = truth
                    .iter()
                    .copied()
                    .filter(|i| pvs.binary_search(i).is_err())
                    .collect();
                assert!(
                    missed.is_empty(),
                    "{name} on {what} ({c}) missed {missed:?}"
                );
            }
        }
    }
}

#[test]
fn raw_degenerate_cells_do_not_panic() {
    // `ViewCell`'s fields are public: a caller can build cells `from_array` refuses.
    let scene = Arc::new(city(5, 30));
    let p = scene.bounds.center();
    let raw = [
        ViewCell { min: p, max: p },
        ViewCell {
            min: p + DVec3::new(5.0, 5.0, 0.0),
            max: p,
        },
    ];
    for (name, m) in methods(&scene) {
        for c in &raw {
            if let Ok(pvs) = m.pvs(c) {
                assert!(
                    pvs.iter().all(|&i| (i as usize) < scene.objects.len()),
                    "{name}"
                );
            }
        }
    }
}
