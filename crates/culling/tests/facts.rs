//! Hand-checked facts, every method.

use glam::DVec3;
use sightline_culling::{method, CullScene, Frustum, CULLER_NAMES};
use sightline_scene::{Object, Scene};
use std::sync::Arc;

fn scene() -> Scene {
    Scene::from_objects(vec![
        // 0: a 3 m wall 10 m ahead, 10 m wide.
        Object::rect_block(-5.0, 10.0, 5.0, 11.0, 3.0),
        // 1: a low block behind it: hidden.
        Object::rect_block(-2.0, 20.0, 2.0, 24.0, 3.0),
        // 2: a tower behind it: its top shows above the wall.
        Object::rect_block(-2.0, 30.0, 2.0, 34.0, 60.0),
        // 3: a block behind the eye: outside the frustum.
        Object::rect_block(-2.0, -20.0, 2.0, -16.0, 10.0),
        // 4: a low block partly behind the wall's end: the sight line to (12, 20) passes
        // the wall's plane at x = 6, beyond its end.
        Object::rect_block(8.0, 20.0, 12.0, 24.0, 3.0),
    ])
}

#[test]
fn wall_hides_the_low_block_not_the_tower_nor_what_is_past_its_end() {
    let cs = Arc::new(CullScene::new(&scene()));
    let f = Frustum::new(DVec3::new(0.0, 0.0, 1.7), DVec3::Y, 60.0, 640, 360).unwrap();
    for name in CULLER_NAMES {
        let c = method(name, cs.clone()).unwrap();
        let fr = c.cull(&f, None);
        assert_eq!(fr.visible, vec![0, 2, 4], "{name}");
        assert_eq!(fr.frustum_culled, 1, "{name}");
        assert_eq!(fr.occlusion_culled, 1, "{name}");
        assert!((fr.culled_pct() - 40.0).abs() < 1e-9);
    }
}

#[test]
fn a_box_reaching_in_front_of_the_near_plane_is_visible() {
    // The eye stands right at the face of a block: its box crosses the near plane.
    let s = Scene::from_objects(vec![
        Object::rect_block(-20.0, 5.0, 20.0, 6.0, 10.0),
        Object::rect_block(-1.0, 0.01, 1.0, 2.0, 1.0),
    ]);
    let cs = Arc::new(CullScene::new(&s));
    let f = Frustum::new(DVec3::new(0.0, 0.0, 1.7), DVec3::Y, 60.0, 320, 180).unwrap();
    for name in ["hzb", "hom", "cplp"] {
        let fr = method(name, cs.clone()).unwrap().cull(&f, None);
        assert!(fr.visible.contains(&1), "{name}");
    }
}
