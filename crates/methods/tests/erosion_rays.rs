//! `erosion-rays` (the X-sampling ray test of §7.1, Theorem 2): hand-checked facts on
//! fixture scenes, `missed = 0` against the sampled ground truth (`sampled`,
//! `sightline_core::check`) on random generated cities, and a side-by-side with
//! `erosion` and `erosion-cell` on the same cells.

mod erosion_support;

use erosion_support::*;
use proptest::prelude::*;
use sightline_core::check::{check_cell_prepared, TruthOptions, TruthScene};
use sightline_geom::ViewCell;
use sightline_methods::{create, MethodOptions, VisibilityMethod};
use sightline_scene::cells::grid_cells;
use sightline_scene::generate::city;
use sightline_scene::{Object, Scene};
use std::sync::Arc;

fn rays(scene: &Arc<Scene>) -> Box<dyn VisibilityMethod> {
    create("erosion-rays", scene.clone(), &MethodOptions::default()).expect("method")
}

/// The cheap ground truth used by the property test (a lower bound of the VS).
fn truth_opts() -> TruthOptions {
    TruthOptions {
        samples: 16,
        resolution_px: 128,
        targeted_rays_per_object: 8,
        seed: 3,
    }
}

/// 0: a 20 m deep, 15 m high block; behind it 1: a low house, 2: a tower, 3: a street,
/// 4: a 17 m house right behind the block (hidden: from an eye at 2 m, a sight line
/// over the block's front edge at x = 20 is at least 28.6 m high at x = 41).
fn thick_block_scene() -> Arc<Scene> {
    Arc::new(Scene::from_objects(vec![
        Object::rect_block(20.0, -40.0, 40.0, 40.0, 15.0),
        Object::rect_block(50.0, -5.0, 60.0, 5.0, 8.0),
        Object::rect_block(60.0, -5.0, 70.0, 5.0, 80.0),
        street(75.0, -3.0, 120.0, 3.0),
        Object::rect_block(41.0, 10.0, 61.0, 14.0, 17.0),
    ]))
}

#[test]
fn thick_block_hides_what_is_low_behind_it() {
    let scene = thick_block_scene();
    let c = cell(0.0, -5.0, 10.0, 5.0);
    let p = rays(&scene).pvs(&c).expect("pvs");
    assert!(p.contains(&0), "the block is visible: {p:?}");
    assert!(p.contains(&2), "the tower is visible over the block: {p:?}");
    assert!(!p.contains(&1), "the low house is hidden: {p:?}");
    assert!(!p.contains(&3), "the street is hidden: {p:?}");
    assert!(!p.contains(&4), "the house right behind is hidden: {p:?}");
    let vs = sampled_visible(&scene, &c, 5);
    assert!(missed(&p, &vs).is_empty(), "misses {:?}", missed(&p, &vs));
}

#[test]
fn a_terrace_thinner_than_a_third_level_quarter_hides_with_the_fourth() {
    // A row of 3 m deep, 20 m high terraced houses beside a 25 m cell: eroded by the
    // 3.1 m quarters of the third level it is empty, by the 1.6 m quarters of the
    // fourth (RAYS_MAX_DEPTH) it keeps a core that hides the low house behind it.
    let scene = Arc::new(Scene::from_objects(vec![
        Object::rect_block(30.0, -60.0, 33.0, 85.0, 20.0),
        Object::rect_block(40.0, 5.0, 50.0, 20.0, 5.0),
    ]));
    let c = cell(0.0, 0.0, 25.0, 25.0);
    let p = rays(&scene).pvs(&c).expect("pvs");
    assert_eq!(p, vec![0], "the house behind the terrace is hidden");
    let vs = sampled_visible(&scene, &c, 5);
    assert!(missed(&p, &vs).is_empty(), "misses {:?}", missed(&p, &vs));
}

#[test]
fn thin_wall_vanishes_in_the_erosion_by_the_cell() {
    // Theorem 1's price, as for `erosion-cell`: a 1 m wall eroded by a 10 m cell (and
    // by its 1.25 m deepest quarters) is empty, so what is behind it stays visible.
    let scene = Arc::new(Scene::from_objects(vec![
        Object::rect_block(20.0, -40.0, 21.0, 40.0, 10.0),
        Object::rect_block(40.0, -5.0, 50.0, 5.0, 8.0),
    ]));
    let c = cell(0.0, -5.0, 10.0, 5.0);
    let p = rays(&scene).pvs(&c).expect("pvs");
    assert_eq!(p, vec![0, 1]);
}

#[test]
fn cells_against_and_inside_facades() {
    // Cells touching, overlapping and straddling the block: the samples of the block
    // itself fall near the eye, and what is behind a facade the cell overlaps is seen.
    let scene = thick_block_scene();
    for c in [
        cell(10.0, -5.0, 20.0, 5.0),
        cell(15.0, -5.0, 25.0, 5.0),
        cell(15.0, 35.0, 25.0, 45.0),
        cell(35.0, 2.0, 45.0, 12.0),
    ] {
        let p = rays(&scene).pvs(&c).expect("pvs");
        let vs = sampled_visible(&scene, &c, 5);
        assert!(
            missed(&p, &vs).is_empty(),
            "{c}: misses {:?} (pvs {p:?})",
            missed(&p, &vs)
        );
    }
}

/// A cell of a generated city: one of its 25 m grid cells with free space, picked by `k`.
fn city_case(seed: u64, k: usize) -> (Arc<Scene>, ViewCell) {
    let scene = Arc::new(city(seed, 40));
    let cells = grid_cells(&scene, 25.0, 1.5, 2.0).expect("cells");
    let c = cells[k % cells.len()];
    (scene, c)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 12, ..ProptestConfig::default() })]

    /// missed = 0 against the sampled ground truth on random generated cities, at the
    /// default number of azimuth bins and at a coarse 64 (conservative at any).
    #[test]
    fn rays_miss_nothing_on_generated_cities(seed in 0..1_000u64, k in 0..10_000usize) {
        let (scene, c) = city_case(seed, k);
        let ts = TruthScene::new(&scene);
        let coarse = MethodOptions { resolution_px: Some(64), ..MethodOptions::default() };
        for opts in [MethodOptions::default(), coarse] {
            let m = create("erosion-rays", scene.clone(), &opts).expect("method");
            let r = check_cell_prepared(&ts, m.as_ref(), &c, &truth_opts()).expect("check");
            prop_assert!(r.missed.is_empty(), "seed {seed} cell {c} {opts:?}: missed {:?}", r.missed);
        }
    }
}

#[test]
fn rays_beside_erosion_on_the_same_cells() {
    // Each contains the ground truth on every cell, and each culls something on these
    // cells of a city of closed blocks.
    let scene = Arc::new(city(5, 120));
    let ts = TruthScene::new(&scene);
    let cells = grid_cells(&scene, 25.0, 1.5, 2.0).expect("cells");
    let step = (cells.len() / 5).max(1);
    let methods: Vec<Box<dyn VisibilityMethod>> = ["erosion-rays", "erosion", "erosion-cell"]
        .iter()
        .map(|m| create(m, scene.clone(), &MethodOptions::default()).expect("method"))
        .collect();
    let mut hidden = vec![0usize; methods.len()];
    for c in cells.iter().skip(step / 2).step_by(step).take(5) {
        for (k, m) in methods.iter().enumerate() {
            let r = check_cell_prepared(&ts, m.as_ref(), c, &truth_opts()).expect("check");
            assert!(
                r.missed.is_empty(),
                "{} {c}: missed {:?}",
                m.name(),
                r.missed
            );
            assert!(
                r.pvs_len >= r.vs_len,
                "{} {c}: PVS smaller than VS",
                m.name()
            );
            hidden[k] += scene.objects.len() - r.pvs_len;
        }
    }
    for (k, m) in methods.iter().enumerate() {
        assert!(
            hidden[k] > 0,
            "{} hides nothing on 5 street cells",
            m.name()
        );
    }
}
