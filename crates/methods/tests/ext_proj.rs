//! `ext-proj` on hand-checked fixture scenes (ericw-tools style): every fact is named,
//! and every PVS must contain the sampled visible set (conservativeness).

mod ext_proj_common;

use ext_proj_common::{missed, sampled_visible};
use sightline_geom::{DVec2, Polygon, ViewCell};
use sightline_methods::ext_proj::{ExtProj, Params};
use sightline_methods::{create, MethodOptions, VisibilityMethod};
use sightline_scene::{Object, Scene};
use std::sync::Arc;

fn cell(s: &str) -> ViewCell {
    s.parse().expect("fixture cell")
}

fn pvs(scene: &Arc<Scene>, c: &ViewCell, params: Params) -> Vec<u32> {
    ExtProj::new(scene.clone(), params).pvs(c).expect("pvs")
}

fn assert_conservative(scene: &Arc<Scene>, c: &ViewCell, p: &[u32]) {
    let vs = sampled_visible(scene, c, 3, 4);
    let m = missed(&vs, p);
    assert!(
        m.is_empty(),
        "missed {m:?} (pvs {p:?}, sampled {vs:?}) from {c}"
    );
}

/// Wall 40 m wide and 10 m high at x = 20..21; a low building hides behind it, a
/// 60 m tower rises behind it.
fn wall_scene() -> Arc<Scene> {
    Arc::new(Scene::from_objects(vec![
        Object::rect_block(20.0, -20.0, 21.0, 20.0, 10.0), // 0 wall
        Object::rect_block(30.0, -5.0, 40.0, 5.0, 6.0),    // 1 low building behind
        Object::rect_block(45.0, -5.0, 55.0, 5.0, 60.0),   // 2 tower behind
        Object::rect_block(-30.0, -5.0, -20.0, 5.0, 6.0),  // 3 in the open, behind the cell
    ]))
}

#[test]
fn wall_hides_the_low_building_but_not_the_tower() {
    let scene = wall_scene();
    let c = cell("0,-2,1.5,4,2,2");
    let p = pvs(&scene, &c, Params::default());
    assert!(p.contains(&0), "the wall is visible");
    assert!(
        !p.contains(&1),
        "the low building behind the wall is hidden: {p:?}"
    );
    assert!(p.contains(&2), "the tower behind the wall is visible");
    assert!(p.contains(&3), "the building in the open is visible");
    assert_conservative(&scene, &c, &p);
}

#[test]
fn method_is_created_by_name_and_records_its_parameters() {
    let scene = wall_scene();
    let m = create("ext-proj", scene.clone(), &MethodOptions::default()).expect("create");
    assert_eq!(m.name(), "ext-proj");
    assert!(m.is_conservative());
    assert!(m
        .params()
        .iter()
        .any(|(k, v)| k == "resolution" && v == "512"));
    let c = cell("0,-2,1.5,4,2,2");
    assert_eq!(m.pvs(&c).expect("pvs"), pvs(&scene, &c, Params::default()));
}

/// A row of touching buildings fuses into one wall: what stands behind the
/// row is hidden, although no single building of the row hides it.
#[test]
fn touching_buildings_fuse_into_one_occluder() {
    let mut objs: Vec<Object> = (0..8)
        .map(|i| {
            let y = -20.0 + 5.0 * i as f64;
            Object::rect_block(20.0, y, 28.0, y + 5.0, 12.0 + (i % 3) as f64)
        })
        .collect();
    objs.push(Object::rect_block(35.0, -4.0, 45.0, 4.0, 8.0)); // 8 behind the row
    let scene = Arc::new(Scene::from_objects(objs));
    let c = cell("0,-3,1.5,6,3,2");
    let p = pvs(&scene, &c, Params::default());
    assert!(!p.contains(&8), "hidden behind the fused row: {p:?}");
    assert_conservative(&scene, &c, &p);
}

/// A 1 m slit between two walls: the building seen through it must stay visible.
#[test]
fn one_metre_slit_keeps_what_is_behind_visible() {
    let scene = Arc::new(Scene::from_objects(vec![
        Object::rect_block(20.0, -20.0, 21.0, -0.5, 10.0), // 0
        Object::rect_block(20.0, 0.5, 21.0, 20.0, 10.0),   // 1
        Object::rect_block(40.0, -1.0, 42.0, 1.0, 5.0),    // 2 seen through the slit
        Object::rect_block(40.0, 10.0, 45.0, 15.0, 5.0),   // 3 hidden off-axis
    ]));
    let c = cell("0,-1,1.5,2,1,2");
    let p = pvs(&scene, &c, Params::default());
    assert!(p.contains(&2), "visible through the slit: {p:?}");
    assert!(
        !p.contains(&3),
        "off-axis building behind the wall is hidden: {p:?}"
    );
    assert_conservative(&scene, &c, &p);
}

/// A courtyard building: from inside the courtyard only the courtyard walls are seen.
#[test]
fn courtyard_hides_the_outside() {
    let mut ring = Polygon::rect(DVec2::new(-30.0, -30.0), DVec2::new(30.0, 30.0));
    ring.holes
        .push(Polygon::rect(DVec2::new(-10.0, -10.0), DVec2::new(10.0, 10.0)).exterior);
    let scene = Arc::new(Scene::from_objects(vec![
        Object::block(None, ring, 0.0, 15.0), // 0 the courtyard building
        Object::rect_block(40.0, -5.0, 50.0, 5.0, 10.0), // 1 outside, lower
        Object::rect_block(-5.0, 40.0, 5.0, 50.0, 60.0), // 2 outside, a tall tower
    ]));
    let c = cell("-3,-3,1.5,3,3,2");
    let p = pvs(&scene, &c, Params::default());
    assert!(p.contains(&0));
    assert!(
        !p.contains(&1),
        "outside building hidden by the courtyard: {p:?}"
    );
    assert!(p.contains(&2), "the tower rises above the courtyard");
    assert_conservative(&scene, &c, &p);
}

/// A cell that touches and one that overlaps a facade: the building itself and what
/// is visible along the street stay in the PVS.
#[test]
fn cells_touching_and_overlapping_a_facade() {
    let scene = Arc::new(Scene::from_objects(vec![
        Object::rect_block(0.0, 10.0, 50.0, 20.0, 12.0), // 0 facade along the street at y = 10
        Object::rect_block(0.0, -20.0, 50.0, -5.0, 12.0), // 1 other side of the street
        Object::rect_block(60.0, 0.0, 70.0, 8.0, 6.0),   // 2 down the street, in view
        Object::rect_block(10.0, 25.0, 20.0, 35.0, 8.0), // 3 behind the facade
    ]));
    for s in ["10,0,1.5,20,10,2", "10,2,1.5,20,12,2"] {
        let c = cell(s);
        let p = pvs(&scene, &c, Params::default());
        assert!(
            p.contains(&0) && p.contains(&1) && p.contains(&2),
            "{s}: {p:?}"
        );
        assert_conservative(&scene, &c, &p);
    }
    let p = pvs(&scene, &cell("10,0,1.5,20,10,2"), Params::default());
    assert!(!p.contains(&3), "behind the facade, from the street: {p:?}");
}

/// The improved projection (§4) never loses objects and never enlarges the PVS.
#[test]
fn improved_projection_is_no_larger() {
    let scene = wall_scene();
    for s in ["0,-2,1.5,4,2,2", "-10,-10,1.5,10,10,2"] {
        let c = cell(s);
        let plain = pvs(
            &scene,
            &c,
            Params {
                improved: false,
                ..Params::default()
            },
        );
        let imp = pvs(&scene, &c, Params::default());
        assert!(imp.iter().all(|i| plain.contains(i)), "{imp:?} ⊄ {plain:?}");
        assert_conservative(&scene, &c, &imp);
    }
}

/// Fig. 7(a) of the paper: a small building just behind a wall slightly wider than
/// it, a projection plane far behind both. The standard Projection of the building
/// (separating lines) overflows the wall's Projection on that plane; the improved
/// one (supporting lines, §4) lies inside it, and the building is hidden indeed.
#[test]
fn improved_projection_hides_an_occludee_in_front_of_the_plane() {
    use sightline_methods::ext_proj::PlaneMap;
    use sightline_methods::ext_proj::{Direction, Plane};
    let scene = Arc::new(Scene::from_objects(vec![
        Object::rect_block(20.0, -3.0, 21.0, 3.0, 6.0), // 0 wall
        Object::rect_block(21.5, -1.0, 22.5, 1.0, 3.0), // 1 just behind it
    ]));
    let c = cell("0,-2,1.5,4,2,2");
    let ext = ExtProj::new(scene.clone(), Params::default());
    let dir = Direction::PosX;
    let lc = dir.box_to_local(c.min, c.max);
    let pieces = ext.local_pieces(&c, dir, &ext.occluders.relevant(&c.aabb()));
    let plane = Plane::new(dir, &lc, 40.0, 256, 1.5);
    let map = ext.depth_map(&plane, &lc, &pieces);
    let m = PlaneMap {
        plane,
        cell: lc,
        map,
    };
    let b = scene.objects[1].bounds;
    assert!(
        !m.hides(&b, false),
        "the standard Projection overflows the wall's"
    );
    assert!(m.hides(&b, true), "the improved Projection lies inside it");
    assert!(m.hides_points(&b.corners(), true) && !m.hides_points(&b.corners(), false));
    let p = pvs(&scene, &c, Params::default());
    assert_eq!(p, vec![0]);
    assert_conservative(&scene, &c, &p);
}

/// Adaptive preprocess (§6.1): a 60 m cell in front of a long high wall is split into
/// halves, which cull only the parent's PVS and drop the occluders hidden from the
/// parent — here a second wall behind the first, whose pieces are made only of a
/// hidden object. The union of the halves' PVSs is conservative and no larger than the
/// parent's.
#[test]
fn adaptive_halves_cull_the_parents_pvs_without_its_hidden_occluders() {
    let scene = Arc::new(Scene::from_objects(vec![
        Object::rect_block(-200.0, 20.0, 260.0, 22.0, 20.0), // 0 front wall
        Object::rect_block(10.0, 40.0, 50.0, 42.0, 15.0),    // 1 second wall, hidden
        Object::rect_block(20.0, 60.0, 40.0, 70.0, 10.0),    // 2 behind both
        Object::rect_block(20.0, -40.0, 40.0, -30.0, 10.0),  // 3 in the open
    ]));
    let c = cell("0,0,1.5,60,10,2");
    let flat = Params {
        adaptive_budget: None,
        ..Params::default()
    };
    let ext = ExtProj::new(scene.clone(), flat);
    let parent = ext.pvs_among(&c, &[0, 1, 2, 3]);
    assert_eq!(parent, vec![0, 3], "both walls' shadows hide 1 and 2");
    // The second wall's pieces are made of object 1 only: the halves drop them.
    let all = ext.occluders.relevant(&c.aabb());
    let kept = ext.occluders.relevant_among(&c.aabb(), Some(&parent));
    assert!(kept.len() < all.len(), "{} of {}", kept.len(), all.len());
    assert!(kept
        .iter()
        .all(|&i| ext.occluders.pieces[i as usize].made_of_any(&parent)));
    let adaptive = pvs(
        &scene,
        &c,
        Params {
            adaptive_budget: Some(0),
            adaptive_min_m: 25.0,
            ..Params::default()
        },
    );
    assert!(adaptive.iter().all(|i| parent.contains(i)), "{adaptive:?}");
    assert!(adaptive.contains(&0) && adaptive.contains(&3));
    assert_conservative(&scene, &c, &adaptive);
}
