//! Bad frames get clear errors, never a panic.

use glam::DVec3;
use sightline_culling::{method, CullScene, Frustum};
use sightline_scene::{Object, Scene};
use std::sync::Arc;

#[test]
fn bad_frusta_are_errors() {
    let e = DVec3::new(0.0, 0.0, 1.7);
    for (eye, dir, fov, w, h, what) in [
        (
            DVec3::new(f64::NAN, 0.0, 1.0),
            DVec3::Y,
            60.0,
            64,
            64,
            "eye",
        ),
        (
            DVec3::new(f64::INFINITY, 0.0, 1.0),
            DVec3::Y,
            60.0,
            64,
            64,
            "eye",
        ),
        (e, DVec3::ZERO, 60.0, 64, 64, "direction"),
        (e, DVec3::new(0.0, f64::NAN, 0.0), 60.0, 64, 64, "direction"),
        (e, DVec3::Y, 0.0, 64, 64, "field of view"),
        (e, DVec3::Y, 180.0, 64, 64, "field of view"),
        (e, DVec3::Y, f64::NAN, 64, 64, "field of view"),
        (e, DVec3::Y, 60.0, 0, 64, "buffer"),
        (e, DVec3::Y, 60.0, 64, 0, "buffer"),
        (e, DVec3::Y, 60.0, 100_000, 64, "buffer"),
    ] {
        let err = Frustum::new(eye, dir, fov, w, h).unwrap_err().to_string();
        assert!(err.contains(what), "{err}");
    }
}

#[test]
fn unknown_method_is_an_error_naming_the_known_ones() {
    let cs = Arc::new(CullScene::new(&Scene::from_objects(vec![])));
    let err = method("zbuffer", cs).err().unwrap().to_string();
    assert!(err.contains("zbuffer") && err.contains("hzb"), "{err}");
}

#[test]
fn odd_but_valid_frames_do_not_panic() {
    let scene = Scene::from_objects(vec![Object::rect_block(-5.0, 5.0, 5.0, 6.0, 10.0)]);
    let cs = Arc::new(CullScene::new(&scene));
    for name in ["hzb", "hom", "hom-approx", "cplp"] {
        let c = method(name, cs.clone()).unwrap();
        for (eye, dir, fov, w, h) in [
            (DVec3::new(0.0, 0.0, 1.7), DVec3::Z, 60.0, 1, 1),
            (DVec3::new(0.0, 0.0, 1.7), DVec3::NEG_Z, 179.0, 7, 3),
            (DVec3::new(0.0, 5.5, 5.0), DVec3::Y, 60.0, 33, 9),
            (DVec3::new(1e7, -1e7, 1.7), DVec3::X, 1e-3, 64, 64),
        ] {
            let f = Frustum::new(eye, dir, fov, w, h).unwrap();
            let fr = c.cull(&f, None);
            assert_eq!(fr.candidates, 1);
        }
        // Candidates out of range are ignored.
        let f = Frustum::new(DVec3::new(0.0, 0.0, 1.7), DVec3::Y, 60.0, 64, 64).unwrap();
        let fr = c.cull(&f, Some(&[0, 99]));
        assert_eq!(fr.visible, vec![0]);
        assert_eq!(fr.candidates, 1);
    }
}
