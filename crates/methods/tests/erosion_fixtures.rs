//! Hand-checked facts about the erosion methods on fixture scenes, and
//! `missed = 0` against an exact sampled oracle on each of them.

mod erosion_support;

use erosion_support::*;
use sightline_methods::{create, MethodOptions};
use sightline_scene::{Object, Scene};
use std::sync::Arc;

fn pvs(scene: &Arc<Scene>, method: &str, cell: &sightline_geom::ViewCell) -> Vec<u32> {
    create(method, scene.clone(), &MethodOptions::default())
        .expect("method")
        .pvs(cell)
        .expect("pvs")
}

/// Every method contains the sampled visible set on `cell`.
fn assert_conservative(scene: &Arc<Scene>, cell: &sightline_geom::ViewCell) {
    let vs = sampled_visible(scene, cell, 5);
    for m in METHODS {
        let p = pvs(scene, m, cell);
        assert!(
            missed(&p, &vs).is_empty(),
            "{m} misses {:?} on {cell} (pvs {p:?}, vs {vs:?})",
            missed(&p, &vs)
        );
    }
}

fn wall_scene() -> Arc<Scene> {
    // 0: wall at x 20..21; 1: low block behind; 2: tower behind; 3: street behind.
    Arc::new(Scene::from_objects(vec![
        Object::rect_block(20.0, -40.0, 21.0, 40.0, 10.0),
        Object::rect_block(40.0, -5.0, 50.0, 5.0, 8.0),
        Object::rect_block(60.0, -5.0, 70.0, 5.0, 80.0),
        street(75.0, -3.0, 120.0, 3.0),
    ]))
}

#[test]
fn wall_hides_low_building_but_not_tower_behind() {
    let scene = wall_scene();
    let c = cell(0.0, -5.0, 10.0, 5.0);
    for m in METHODS {
        let p = pvs(&scene, m, &c);
        assert!(p.contains(&0), "{m}: the wall is visible");
        assert!(p.contains(&2), "{m}: the tower is visible over the wall");
        if matches!(m, "erosion-cell" | "shrink-sphere" | "erosion-rays") {
            // Fig. 2: eroded by the whole 10 m cell, the 1 m wall vanishes.
            assert!(p.contains(&1), "{m}: the wall vanished: {p:?}");
        } else {
            // Eroded by the supporting segment (the cell's side), it does not.
            assert!(!p.contains(&1), "{m}: the low block is hidden: {p:?}");
            assert!(!p.contains(&3), "{m}: the street is hidden: {p:?}");
        }
    }
    assert_conservative(&scene, &c);
}

#[test]
fn tower_seen_from_the_back_of_the_cell_over_a_low_wall() {
    // The literal §3.3 (segment at the cell's height) would hide the tower: from the
    // near side the 3 m wall hides it, from the back of the cell it does not.
    let scene = Arc::new(Scene::from_objects(vec![
        Object::rect_block(10.5, -100.0, 11.0, 100.0, 3.0),
        Object::rect_block(50.0, 4.0, 60.0, 6.0, 30.0),
    ]));
    let c = cell(-15.0, 0.0, 10.0, 10.0);
    let vs = sampled_visible(&scene, &c, 6);
    assert!(vs.contains(&1), "oracle sees the tower");
    assert_conservative(&scene, &c);
}

#[test]
fn courtyard_is_hidden_from_outside() {
    // A closed block of four touching 12 m deep wings around a courtyard: the yard (a
    // street object) is hidden from a cell in the street outside, the block visible.
    let ring = |x0: f64, y0: f64, x1: f64, y1: f64| Object::rect_block(x0, y0, x1, y1, 15.0);
    let scene = Arc::new(Scene::from_objects(vec![
        ring(20.0, -10.0, 68.0, 2.0),
        ring(20.0, 28.0, 68.0, 40.0),
        ring(20.0, 2.0, 32.0, 28.0),
        ring(56.0, 2.0, 68.0, 28.0),
        street(32.0, 2.0, 56.0, 28.0),
    ]));
    let c = cell(0.0, 10.0, 10.0, 20.0);
    for m in METHODS {
        let p = pvs(&scene, m, &c);
        assert!(p.contains(&2), "{m}: the facing wing is visible");
        if m != "shrink-sphere" {
            assert!(!p.contains(&4), "{m}: the courtyard is hidden: {p:?}");
        }
    }
    assert_conservative(&scene, &c);
}

#[test]
fn touching_buildings_fuse() {
    // A row of touching 6 m wide, 12 m deep houses: eroded one by one by a 10 m cell
    // they all vanish; fused they form a 30 m block that still hides the one behind.
    let mut objs: Vec<_> = (0..5)
        .map(|i| {
            Object::rect_block(
                20.0,
                -15.0 + 6.0 * i as f64,
                32.0,
                -9.0 + 6.0 * i as f64,
                12.0,
            )
        })
        .collect();
    objs.push(Object::rect_block(40.0, -3.0, 48.0, 3.0, 10.0));
    let scene = Arc::new(Scene::from_objects(objs));
    let c = cell(0.0, -5.0, 10.0, 5.0);
    for m in ["erosion", "erosion-segment", "erosion-cell"] {
        let p = pvs(&scene, m, &c);
        assert!(
            !p.contains(&5),
            "{m}: the block behind the fused row is hidden: {p:?}"
        );
    }
    assert_conservative(&scene, &c);
}

#[test]
fn one_metre_slit_lets_the_street_through() {
    let scene = Arc::new(Scene::from_objects(vec![
        Object::rect_block(20.0, -40.0, 30.0, -0.5, 20.0),
        Object::rect_block(20.0, 0.5, 30.0, 40.0, 20.0),
        street(30.0, -2.0, 200.0, 2.0),
        Object::rect_block(100.0, -1.0, 104.0, 1.0, 6.0),
    ]));
    let c = cell(0.0, -5.0, 10.0, 5.0);
    let vs = sampled_visible(&scene, &c, 5);
    assert!(
        vs.contains(&2) && vs.contains(&3),
        "oracle sees through the slit: {vs:?}"
    );
    assert_conservative(&scene, &c);
}

#[test]
fn cells_touching_and_overlapping_facades() {
    let scene = wall_scene();
    // Touching the wall's facade, overlapping the wall, straddling its end.
    for c in [
        cell(10.0, -5.0, 20.0, 5.0),
        cell(15.0, -5.0, 25.0, 5.0),
        cell(15.0, 35.0, 25.0, 45.0),
        cell(19.0, -50.0, 29.0, -38.0),
    ] {
        assert_conservative(&scene, &c);
    }
    // From a cell overlapping the wall, what lies behind it is visible.
    let p = pvs(&scene, "erosion", &cell(15.0, -5.0, 25.0, 5.0));
    assert!(p.contains(&1) && p.contains(&2), "{p:?}");
}

#[test]
fn objects_straddling_cell_borders() {
    // Long blocks crossing the cell's x and y ranges: split into side and corner pieces.
    let scene = Arc::new(Scene::from_objects(vec![
        Object::rect_block(12.0, -30.0, 16.0, 40.0, 10.0),
        Object::rect_block(-30.0, 12.0, 40.0, 15.0, 10.0),
        Object::rect_block(30.0, -5.0, 34.0, 30.0, 25.0),
        street(-50.0, 3.0, 50.0, 7.0),
        Object::rect_block(-20.0, -20.0, -12.0, -12.0, 9.0),
    ]));
    for c in [cell(0.0, 0.0, 10.0, 10.0), cell(2.0, 2.0, 8.0, 8.0)] {
        assert_conservative(&scene, &c);
    }
}

#[test]
fn fig9_ordering_on_fixtures() {
    let scene = wall_scene();
    let c = cell(0.0, -5.0, 10.0, 5.0);
    let n: Vec<usize> = [
        "shrink-sphere",
        "erosion-cell",
        "erosion-segment",
        "erosion",
    ]
    .iter()
    .map(|m| pvs(&scene, m, &c).len())
    .collect();
    assert!(n[0] >= n[1] && n[1] >= n[2] && n[2] >= n[3], "{n:?}");
}
