//! `dual-ray` and `dual-ray-exact` against the sampled ground truth
//! (`sightline_core::check`): missed = 0 on a generated city and on street cells of
//! the real scenes.

use sightline_core::check::{check_cell_prepared, TruthOptions, TruthScene};
use sightline_methods::{create, MethodOptions};
use sightline_scene::cells::grid_cells;
use sightline_scene::generate::city;
use sightline_scene::Scene;
use std::sync::Arc;

fn truth_opts() -> TruthOptions {
    TruthOptions {
        samples: 16,
        resolution_px: 128,
        targeted_rays_per_object: 8,
        seed: 7,
    }
}

fn no_miss(scene: Arc<Scene>, cells: &[sightline_geom::ViewCell]) {
    let ts = TruthScene::new(&scene);
    let methods = [
        create("dual-ray-exact", scene.clone(), &MethodOptions::default()).expect("method"),
        create(
            "dual-ray",
            scene.clone(),
            &MethodOptions {
                resolution_px: Some(16),
                ..Default::default()
            },
        )
        .expect("method"),
        create("dual-ray", scene.clone(), &MethodOptions::default()).expect("method"),
    ];
    for c in cells {
        for m in &methods {
            let r = check_cell_prepared(&ts, m.as_ref(), c, &truth_opts()).expect("check");
            assert!(
                r.missed.is_empty(),
                "{} {c}: missed {:?}",
                m.name(),
                r.missed
            );
        }
    }
}

#[test]
fn generated_city_misses_nothing() {
    let scene = Arc::new(city(3, 150));
    let cells = grid_cells(&scene, 40.0, 1.5, 2.0).expect("cells");
    let step = (cells.len() / 6).max(1);
    let pick: Vec<_> = cells.iter().step_by(step).take(6).copied().collect();
    no_miss(scene, &pick);
}

#[test]
fn lyon_street_cells_miss_nothing() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/lyon1_bdtopo.geojson");
    let scene = Arc::new(
        sightline_scene::import::load(&path, &Default::default()).expect("vendored scene loads"),
    );
    let cells = grid_cells(&scene, 50.0, 1.5, 2.0).expect("cells");
    let step = (cells.len() / 3).max(1);
    let pick: Vec<_> = cells
        .iter()
        .skip(step / 2)
        .step_by(step)
        .take(3)
        .copied()
        .collect();
    no_miss(scene, &pick);
}

/// Street crossings of a generated metropolis, where boxes proven hidden occlude the
/// later tests: nothing the ground truth sees is missed, the hidden boxes are used, and
/// the PVS with them is contained in the one without.
#[test]
fn metropolis_hidden_occluders_miss_nothing() {
    use sightline_methods::dual_ray::{crossing_cells, DualRay, Planarity};
    let scene = Arc::new(sightline_scene::generate::metropolis(3, 3000));
    let cells = crossing_cells(&scene, 100.0, 3);
    assert!(!cells.is_empty());
    let planarity = Planarity::Discrete { resolution_px: 128 };
    let on = DualRay::new("dual-ray", scene.clone(), planarity);
    let off = DualRay::new("dual-ray", scene.clone(), planarity).with_hidden_occluders(false);
    let ts = TruthScene::new(&scene);
    let mut used = 0;
    for c in &cells {
        let (with, st) = on.pvs_with_stats(c);
        let (without, st_off) = off.pvs_with_stats(c);
        used += st.hidden_pieces;
        assert_eq!(st_off.hidden_pieces, 0);
        for id in &with {
            assert!(
                without.binary_search(id).is_ok(),
                "{c}: {id} only with hidden boxes"
            );
        }
        let truth = ts.ground_truth(c, &truth_opts());
        for id in &truth.visible {
            assert!(with.binary_search(id).is_ok(), "{c}: misses {id}");
        }
    }
    assert!(used > 0, "no hidden box was used");
}
