//! Property: on random box cities, from random free eyes, no culler culls an object the
//! item buffer sees.

use glam::DVec3;
use proptest::prelude::*;
use sightline_culling::truth::FrameTruth;
use sightline_culling::walk::is_free;
use sightline_culling::{method, CullScene, Frustum};
use sightline_scene::{Object, Scene};
use std::sync::Arc;

fn scene_of(boxes: &[(f64, f64, f64, f64, f64)]) -> Scene {
    Scene::from_objects(
        boxes
            .iter()
            .map(|&(x, y, w, d, h)| Object::rect_block(x, y, x + w, y + d, h))
            .collect(),
    )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
    #[test]
    fn no_false_culls_on_random_boxes(
        boxes in prop::collection::vec((-60.0..60.0f64, -60.0..60.0f64, 1.0..25.0f64, 1.0..25.0f64, 1.0..40.0f64), 1..40),
        ex in -70.0..70.0f64, ey in -70.0..70.0f64, ez in 0.5..30.0f64,
        az in 0.0..std::f64::consts::TAU, pitch in -0.6..0.6f64, fov in 20.0..120.0f64,
    ) {
        let scene = scene_of(&boxes);
        let eye = DVec3::new(ex, ey, ez);
        prop_assume!(is_free(&scene, eye, 0.2));
        let dir = DVec3::new(az.cos() * pitch.cos(), az.sin() * pitch.cos(), pitch.sin());
        let f = Frustum::new(eye, dir, fov, 160, 96).unwrap();
        let vs = FrameTruth::new(&scene).visible(&f);
        let cs = Arc::new(CullScene::new(&scene));
        for name in ["hzb", "hom", "cplp"] {
            let fr = method(name, cs.clone()).unwrap().cull(&f, None);
            for id in &vs {
                prop_assert!(fr.visible.binary_search(id).is_ok(), "{} culled visible {}", name, id);
            }
        }
    }
}
