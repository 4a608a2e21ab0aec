//! Fixture scenes with hand-checked facts (in the manner of ericw-tools' test maps):
//! the ground truth must find exactly the expected visible sets.

use sightline_core::check::{ground_truth, TruthOptions, TruthScene};
use sightline_geom::{DVec2, DVec3, Polygon, ViewCell};
use sightline_scene::{Object, Scene};

fn rect(x0: f64, y0: f64, x1: f64, y1: f64) -> Polygon {
    Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1))
}

fn block(name: &str, p: Polygon, top: f64) -> Object {
    Object::block(Some(name.to_string()), p, 0.0, top)
}

fn cell(s: &str) -> ViewCell {
    s.parse().expect("fixture cell")
}

/// Names of the visible objects, sorted, for readable assertions.
fn visible_names(scene: &Scene, c: &ViewCell) -> Vec<String> {
    let t = ground_truth(scene, c, &TruthOptions::default());
    assert!(t.samples_used > 0, "no viewpoint in {c}");
    assert_eq!(t.witnesses.len(), t.visible.len());
    let mut v: Vec<String> = t
        .visible
        .iter()
        .map(|&i| scene.objects[i as usize].name.clone().unwrap_or_default())
        .collect();
    v.sort();
    v
}

/// A 10 m wall in front of the cell hides a 5 m block behind it, not a 40 m tower.
#[test]
fn wall_hides_low_block_but_not_tower() {
    let scene = Scene::from_objects(vec![
        block("wall", rect(-50.0, 10.0, 50.0, 11.0), 10.0),
        block("low", rect(-5.0, 20.0, 5.0, 30.0), 5.0),
        block("tower", rect(10.0, 20.0, 20.0, 30.0), 40.0),
    ]);
    assert_eq!(
        visible_names(&scene, &cell("-2,0,1.5,2,4,2")),
        ["tower", "wall"]
    );
}

/// From inside a courtyard (15 m ring, 20 m court) only the ring itself and a 200 m
/// tower beyond it are visible; a 10 m building outside is hidden.
#[test]
fn courtyard_sees_only_its_walls_and_a_tall_tower() {
    let mut ring = rect(0.0, 0.0, 40.0, 40.0);
    ring.holes.push(rect(10.0, 10.0, 30.0, 30.0).exterior);
    let scene = Scene::from_objects(vec![
        block("ring", ring, 15.0),
        block("outside", rect(60.0, 10.0, 70.0, 30.0), 10.0),
        block("tower", rect(60.0, 60.0, 70.0, 70.0), 200.0),
        Object::flat(Some("court".into()), vec![rect(12.0, 12.0, 28.0, 28.0)]),
        Object::flat(Some("street".into()), vec![rect(45.0, 0.0, 55.0, 40.0)]),
    ]);
    assert_eq!(
        visible_names(&scene, &cell("15,15,1.5,25,25,2")),
        ["court", "ring", "tower"]
    );
}

/// Two buildings touching along a party wall: nothing behind is seen through the
/// joint, even from a viewpoint exactly in the plane of the party wall.
#[test]
fn party_wall_lets_nothing_through() {
    let scene = Scene::from_objects(vec![
        block("west", rect(-40.0, 10.0, 10.0, 20.0), 10.0),
        block("east", rect(10.0, 10.0, 60.0, 20.0), 10.0),
        block("behind", rect(8.0, 30.0, 12.0, 40.0), 5.0),
    ]);
    assert_eq!(
        visible_names(&scene, &cell("9,0,1.5,11,4,2")),
        ["east", "west"]
    );
    let ts = TruthScene::new(&scene);
    for res in [64, 256, 1024] {
        let seen = ts.visible_from(DVec3::new(10.0, 5.0, 1.75), res);
        assert_eq!(seen, vec![0, 1], "through the joint at {res} px");
    }
    // A sight line running inside the party wall's plane is grazing: it does not count.
    assert!(ts.segment_blocked(DVec3::new(10.0, 5.0, 1.75), DVec3::new(10.0, 35.0, 1.75), 2));
    // A line beside the block does not meet it.
    assert!(!ts.segment_blocked(DVec3::new(70.0, 5.0, 1.75), DVec3::new(70.0, 35.0, 1.75), 2));
}

/// A one-metre slit between two 20 m walls shows a far building straight behind it,
/// not one far to the side.
#[test]
fn slit_shows_far_building() {
    let scene = Scene::from_objects(vec![
        block("wall-w", rect(-60.0, 10.0, 0.0, 11.0), 20.0),
        block("wall-e", rect(1.0, 10.0, 60.0, 11.0), 20.0),
        block("far", rect(-10.0, 100.0, 11.0, 110.0), 10.0),
        block("side", rect(45.0, 100.0, 55.0, 110.0), 10.0),
    ]);
    assert_eq!(
        visible_names(&scene, &cell("-1,0,1.5,2,4,2")),
        ["far", "wall-e", "wall-w"]
    );
}

/// A cell touching a facade (and one cutting into the building): the building itself
/// and its side neighbour are visible, the block behind it is not.
#[test]
fn cell_touching_and_cutting_a_facade() {
    let scene = Scene::from_objects(vec![
        block("front", rect(-10.0, 4.0, 10.0, 14.0), 10.0),
        block("behind", rect(-3.0, 20.0, 3.0, 30.0), 5.0),
        block("side", rect(20.0, 0.0, 30.0, 10.0), 10.0),
    ]);
    assert_eq!(
        visible_names(&scene, &cell("-2,0,1.5,2,4,2")),
        ["front", "side"]
    );
    assert_eq!(
        visible_names(&scene, &cell("-2,0,1.5,2,6,2")),
        ["front", "side"]
    );
    // A cell entirely inside the building has no viewpoint.
    let t = ground_truth(&scene, &cell("-2,6,1.5,2,8,2"), &TruthOptions::default());
    assert_eq!(t.samples_used, 0);
    assert!(t.visible.is_empty());
}

/// A slit far narrower than a pixel (1 cm, seen at 16 px per cube face) is still
/// found, by the targeted rays.
#[test]
fn targeted_rays_find_a_hair_thin_slit() {
    let scene = Scene::from_objects(vec![
        block("wall-w", rect(-60.0, 10.0, 0.0, 10.2), 20.0),
        block("wall-e", rect(0.01, 10.0, 60.0, 10.2), 20.0),
        block("far", rect(-1.0, 30.0, 1.0, 32.0), 10.0),
    ]);
    let opts = TruthOptions {
        samples: 32,
        resolution_px: 16,
        targeted_rays_per_object: 4096,
        seed: 7,
    };
    let t = ground_truth(&scene, &cell("-1,0,1.5,1,4,2"), &opts);
    assert_eq!(t.visible, vec![0, 1, 2]);
    assert!(t.found_by_rays >= 1);
}

/// Witnesses are genuine: the witness ray reaches the object unobstructed.
#[test]
fn witnesses_point_at_their_object() {
    let scene = Scene::from_objects(vec![
        block("wall", rect(-50.0, 10.0, 50.0, 11.0), 10.0),
        block("tower", rect(10.0, 20.0, 20.0, 30.0), 40.0),
    ]);
    let t = ground_truth(&scene, &cell("-2,0,1.5,2,4,2"), &TruthOptions::default());
    for w in &t.witnesses {
        let o = &scene.objects[w.id as usize];
        let (vp, d) = (DVec3::from(w.viewpoint), DVec3::from(w.direction));
        assert!((d.length() - 1.0).abs() < 1e-9);
        // March along the ray: it must enter the object's box.
        let hit = (0..20000).any(|k| o.bounds.contains(vp + d * (k as f64 * 0.01)));
        assert!(hit, "witness of {} misses it", w.id);
    }
}
