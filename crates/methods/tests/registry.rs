//! The registry end to end: every registered method is built by `create` from its
//! name, knobs given by key reach the method and the `.pvs` header (only the switches
//! that change the PVS, and only when not at their defaults), bad knobs are errors.

use sightline_core::Family;
use sightline_geom::{DVec2, Polygon};
use sightline_methods::{create, Method, MethodError, MethodOptions};
use sightline_scene::{Object, Scene};
use std::sync::Arc;

fn scene() -> Arc<Scene> {
    let objects = (0..4)
        .map(|i| {
            let x = 20.0 * i as f64;
            let p = Polygon::rect(DVec2::new(x, 0.0), DVec2::new(x + 10.0, 10.0));
            Object::block(None, p, 0.0, 10.0 + i as f64)
        })
        .collect();
    Arc::new(Scene::from_objects(objects))
}

fn with(set: &[(&str, &str)]) -> MethodOptions {
    MethodOptions {
        set: set
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        ..MethodOptions::default()
    }
}

#[test]
fn every_registered_method_is_built_by_name() {
    let s = scene();
    for m in Method::ALL {
        if m.family() == Family::Portals || m.family() == Family::Volumetric {
            // Built from a level (sightline-portals, sightline-autocells), above this
            // crate: a clear error naming where.
            let e = create(m.name(), s.clone(), &MethodOptions::default()).err();
            assert!(e.is_some_and(|e| e.to_string().contains("levels")));
            continue;
        }
        let built = create(m.name(), s.clone(), &MethodOptions::default()).unwrap();
        assert_eq!(built.name(), m.name());
        assert_eq!(built.is_conservative(), m.is_conservative());
    }
}

#[test]
fn dual_ray_switches_reach_the_header_only_off_default() {
    let s = scene();
    let d = create("dual-ray", s.clone(), &MethodOptions::default()).unwrap();
    assert_eq!(d.params(), vec![("resolution".into(), "128".into())]);
    let d = create(
        "dual-ray",
        s.clone(),
        &with(&[
            ("virtual_occluders", "true"),
            ("hidden_boxes", "false"),
            ("seed_rays", "false"),
        ]),
    )
    .unwrap();
    let p = d.params();
    assert!(p.contains(&("virtual_occluders".into(), "true".into())));
    assert!(p.contains(&("hidden_boxes".into(), "false".into())));
    assert!(!p.iter().any(|(k, _)| k == "seed_rays"));
}

#[test]
fn unknown_or_bad_knobs_are_errors() {
    let s = scene();
    for (m, set) in [
        ("erosion", ("sweep", "true")),
        ("dual-ray", ("hidden_boxes", "maybe")),
        ("shrink-sphere", ("hidden_boxes", "true")),
        ("dual-ray", ("resolution", "0")),
    ] {
        match create(m, s.clone(), &with(&[set])) {
            Err(MethodError::BadOption { .. }) => {}
            other => panic!("{m} {set:?}: {:?}", other.map(|x| x.name())),
        }
    }
}
