//! Hand-checked facts for `dual-ray` and `dual-ray-exact` on tiny fixture scenes
//! (ericw-tools style): each test names what a person standing in the cell sees.

use sightline_geom::{DVec2, DVec3, Polygon, ViewCell};
use sightline_methods::dual_ray::{DualRay, Planarity};
use sightline_methods::{create, MethodOptions, VisibilityMethod};
use sightline_scene::{Object, Prism, Scene};
use std::sync::Arc;

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Polygon {
    Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1))
}

fn cell(s: &str) -> ViewCell {
    s.parse().expect("valid cell")
}

/// Both methods, at a few resolutions; returns the PVS of each, checking that every
/// discretized PVS contains the exact one.
fn pvs_all(scene: Scene, c: &str) -> Vec<Vec<u32>> {
    let scene = Arc::new(scene);
    let c = cell(c);
    let exact = create("dual-ray-exact", scene.clone(), &MethodOptions::default())
        .expect("method")
        .pvs(&c)
        .expect("pvs");
    let mut out = vec![exact.clone()];
    for r in [16, 64, 128, 256] {
        let opts = MethodOptions {
            resolution_px: Some(r),
            ..Default::default()
        };
        let p = create("dual-ray", scene.clone(), &opts)
            .expect("method")
            .pvs(&c)
            .expect("pvs");
        for id in &exact {
            assert!(
                p.contains(id),
                "resolution {r}: exact has {id}, discrete {p:?}"
            );
        }
        out.push(p);
    }
    out
}

const CELL: &str = "0,0,1.5,10,10,2";

#[test]
fn wall_hides_low_building_but_not_tower_behind_it() {
    let scene = Scene::from_objects(vec![
        Object::rect_block(20.0, -50.0, 22.0, 60.0, 10.0), // 0: wall
        Object::rect_block(40.0, 0.0, 50.0, 10.0, 6.0),    // 1: low house behind
        Object::rect_block(40.0, 20.0, 50.0, 30.0, 60.0),  // 2: tower behind
        Object::rect_block(-40.0, 0.0, -30.0, 10.0, 6.0),  // 3: house on the open side
    ]);
    for p in pvs_all(scene, CELL) {
        assert_eq!(p, vec![0, 2, 3]);
    }
}

#[test]
fn touching_row_houses_act_as_one_wall() {
    // Party walls y = const run exactly along rays of the x shaft: unfused, each would
    // leave a crack in the ray space.
    let mut objs = Vec::new();
    let heights = [10.0, 12.0, 10.0, 14.0, 10.0, 10.0];
    for (k, h) in heights.iter().enumerate() {
        let y0 = -20.0 + 10.0 * k as f64;
        objs.push(Object::rect_block(20.0, y0, 30.0, y0 + 10.0, *h));
    }
    objs.push(Object::rect_block(50.0, 0.0, 60.0, 10.0, 5.0)); // 6: low house behind the row
    objs.push(Object::rect_block(50.0, 120.0, 60.0, 140.0, 5.0)); // 7: seen past the end of the row
    for p in pvs_all(Scene::from_objects(objs), CELL) {
        assert_eq!(p, vec![0, 1, 2, 3, 4, 5, 7]);
    }
}

#[test]
fn slanted_party_walls_fuse_too() {
    // Parallelogram houses whose party walls follow the direction (10, 1); the one
    // from (20, 1) is a ray of the x shaft (it crosses both faces inside the hull).
    let mut objs = Vec::new();
    for k in 0..8 {
        let y0 = -20.0 + 7.0 * k as f64;
        let f = Polygon::new(
            vec![
                DVec2::new(20.0, y0),
                DVec2::new(30.0, y0 + 1.0),
                DVec2::new(30.0, y0 + 8.0),
                DVec2::new(20.0, y0 + 7.0),
            ],
            vec![],
        );
        objs.push(Object::block(None, f, 0.0, 10.0));
    }
    objs.push(Object::rect_block(50.0, 0.0, 60.0, 10.0, 5.0)); // 8
    for p in pvs_all(Scene::from_objects(objs), CELL) {
        assert_eq!(p, vec![0, 1, 2, 3, 4, 5, 6, 7]);
    }
}

#[test]
fn one_metre_slit_shows_a_far_building() {
    let scene = Scene::from_objects(vec![
        Object::rect_block(20.0, -100.0, 22.0, 4.5, 20.0), // 0
        Object::rect_block(20.0, 5.5, 22.0, 100.0, 20.0),  // 1
        Object::rect_block(200.0, 0.0, 210.0, 10.0, 5.0),  // 2: seen through the slit
        Object::rect_block(200.0, 200.0, 210.0, 210.0, 5.0), // 3: not in line with the slit
    ]);
    for p in pvs_all(scene, CELL) {
        assert_eq!(p, vec![0, 1, 2]);
    }
}

#[test]
fn closed_wall_hides_the_far_building() {
    // The same without the slit: the two walls touch.
    let scene = Scene::from_objects(vec![
        Object::rect_block(20.0, -100.0, 22.0, 5.0, 20.0),
        Object::rect_block(20.0, 5.0, 22.0, 100.0, 20.0),
        Object::rect_block(200.0, 0.0, 210.0, 10.0, 5.0),
    ]);
    for p in pvs_all(scene, CELL) {
        assert_eq!(p, vec![0, 1]);
    }
}

#[test]
fn courtyard_hides_a_kiosk_but_not_a_tower() {
    let ring = Polygon::new(
        rect(20.0, -30.0, 80.0, 40.0).exterior,
        vec![rect(30.0, -20.0, 70.0, 30.0).exterior],
    );
    let scene = Scene::from_objects(vec![
        Object::block(None, ring, 0.0, 15.0),              // 0
        Object::rect_block(45.0, -5.0, 55.0, 5.0, 3.0),    // 1: kiosk in the courtyard
        Object::rect_block(60.0, 20.0, 65.0, 25.0, 100.0), // 2: tower in the courtyard
        Object::rect_block(100.0, 0.0, 110.0, 10.0, 5.0),  // 3: house beyond the block
    ]);
    for p in pvs_all(scene, CELL) {
        assert_eq!(p, vec![0, 2]);
    }
}

#[test]
fn cell_touching_a_facade() {
    let scene = Scene::from_objects(vec![
        Object::rect_block(10.0, -20.0, 30.0, 30.0, 10.0), // 0: the cell's x1 face lies on its facade
        Object::rect_block(40.0, 0.0, 50.0, 10.0, 5.0),    // 1: behind it
        Object::rect_block(-30.0, 0.0, -20.0, 10.0, 5.0),  // 2: in the open
    ]);
    for p in pvs_all(scene, CELL) {
        assert_eq!(p, vec![0, 2]);
    }
}

#[test]
fn cell_cutting_through_a_building_sees_from_its_free_part() {
    let scene = Scene::from_objects(vec![
        Object::rect_block(5.0, -20.0, 30.0, 30.0, 10.0), // 0: overlaps the cell (free part x < 5)
        Object::rect_block(40.0, 0.0, 50.0, 10.0, 5.0),   // 1: behind it
        Object::rect_block(-30.0, 0.0, -20.0, 10.0, 5.0), // 2: in the open
    ]);
    for p in pvs_all(scene, CELL) {
        assert_eq!(p, vec![0, 2]);
    }
}

#[test]
fn diagonal_boxes_are_hidden_along_either_axis() {
    // Separated from the cell along both x and y; only the x shaft crosses the wall.
    let scene = Scene::from_objects(vec![
        Object::rect_block(15.0, -100.0, 17.0, 100.0, 12.0), // 0: wall
        Object::rect_block(30.0, 12.0, 40.0, 20.0, 4.0),     // 1: larger gap in x (x shaft first)
        Object::rect_block(20.0, 40.0, 25.0, 50.0, 4.0),     // 2: larger gap in y (x shaft second)
    ]);
    for p in pvs_all(scene, CELL) {
        assert_eq!(p, vec![0]);
    }
}

#[test]
fn flat_streets_and_raised_prisms() {
    let scene = Scene::from_objects(vec![
        Object::rect_block(20.0, -50.0, 22.0, 60.0, 10.0), // 0: wall
        Object::flat(None, vec![rect(40.0, 0.0, 60.0, 10.0)]), // 1: street behind the wall
        Object::flat(None, vec![rect(-5.0, -5.0, 15.0, 15.0)]), // 2: street under the cell
        // 3: an arcade (raised prism, never occludes) in front of 4
        Object::blocks(
            None,
            vec![Prism::new(rect(-22.0, -50.0, -20.0, 60.0), 3.0, 10.0)],
        ),
        Object::rect_block(-40.0, 0.0, -30.0, 10.0, 2.5), // 4: seen under the arcade
    ]);
    for p in pvs_all(scene, CELL) {
        assert_eq!(p, vec![0, 2, 3, 4]);
    }
}

#[test]
fn neighbourhood_is_nine_cells_around() {
    let scene = Arc::new(Scene::from_objects(vec![
        Object::rect_block(20.0, -50.0, 22.0, 60.0, 10.0),
        Object::rect_block(40.0, 0.0, 50.0, 10.0, 6.0),
    ]));
    let m = DualRay::new(
        "dual-ray",
        scene.clone(),
        Planarity::Discrete { resolution_px: 128 },
    );
    let c = cell(CELL);
    let nine = m.pvs_with_neighbours(&c);
    assert_eq!(nine[4].0, c);
    assert_eq!(nine[0].0, cell("-10,-10,1.5,0,0,2"));
    assert_eq!(nine[8].0, cell("10,10,1.5,20,20,2"));
    for (cc, p) in &nine {
        assert_eq!(p, &m.pvs(cc).expect("pvs"));
    }
    // The cell at x in [10, 20] is right in front of the wall: still hidden behind.
    assert_eq!(nine[5].1, vec![0]);
}

#[test]
fn empty_scene_and_bad_resolution() {
    let scene = Arc::new(Scene::from_objects(vec![]));
    let m = create("dual-ray", scene.clone(), &MethodOptions::default()).expect("method");
    assert_eq!(m.pvs(&cell(CELL)).expect("pvs"), Vec::<u32>::new());
    let opts = MethodOptions {
        resolution_px: Some(0),
        ..Default::default()
    };
    assert!(create("dual-ray", scene, &opts).is_err());
}

#[test]
fn virtual_occluder_behind_a_long_wall_hides_the_far_houses() {
    // A wall 10 m high, 1 km long, 10 m in front of the cell: the plane 150 m beyond the
    // cell is hidden up to 26 m, so the low houses far behind need no test of their own;
    // the tower above the virtual occluder's height is still tested (and seen).
    let mut objects = vec![Object::block(
        None,
        rect(20.0, -500.0, 22.0, 500.0),
        0.0,
        10.0,
    )];
    for k in 0..6 {
        let y = -150.0 + 60.0 * k as f64;
        objects.push(Object::block(
            None,
            rect(400.0, y, 410.0, y + 10.0),
            0.0,
            6.0,
        ));
    }
    objects.push(Object::block(
        None,
        rect(400.0, 0.0, 410.0, 10.0),
        0.0,
        450.0,
    ));
    let scene = Arc::new(Scene::from_objects(objects));
    let c = cell("0,0,1.5,10,10,2");
    for planarity in [Planarity::Exact, Planarity::Discrete { resolution_px: 128 }] {
        let m = DualRay::new("dual-ray", scene.clone(), planarity).with_virtual_occluders(true);
        let (pvs, st) = m.pvs_with_stats(&c);
        assert_eq!(pvs, vec![0, 7], "{planarity:?}");
        assert!(st.vo_rects > 0 && st.vo_hidden > 0, "{planarity:?}: {st:?}");
        let plain = DualRay::new("dual-ray", scene.clone(), planarity)
            .pvs_with_stats(&c)
            .0;
        assert_eq!(plain, pvs, "{planarity:?}");
        // Degenerate cells and cells far outside the scene: answers, never a panic.
        let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
        let odd = [
            (v(5.0, 5.0, 1.5), v(5.0, 5.0, 1.5)),
            (v(1e6, 1e6, 0.0), v(1e6 + 10.0, 1e6 + 10.0, 2.0)),
            (v(-9e15, 0.0, 0.0), v(9e15, 1.0, 2.0)),
        ];
        for (min, max) in odd {
            let (p, _) = m.pvs_with_stats(&ViewCell { min, max });
            assert!(p.contains(&7), "{min} {max}: {p:?}");
        }
    }
}
