//! No false culls on real cities: random street-level frames of the project's Lyon and
//! Den Haag extracts, every conservative culler against the item-buffer truth.

use glam::DVec3;
use sightline_culling::truth::FrameTruth;
use sightline_culling::walk::street_walk;
use sightline_culling::{method, CullScene, Frustum};
use sightline_scene::Scene;
use std::path::PathBuf;
use std::sync::Arc;

fn load(name: &str) -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../data")
        .join(name);
    sightline_scene::import::load(&path, &Default::default()).expect("vendored scene loads")
}

fn no_false_culls(name: &str, frames: usize, seed: u64) {
    let scene = load(name);
    let cs = Arc::new(CullScene::new(&scene));
    let truth = FrameTruth::new(&scene);
    let cullers: Vec<_> = ["hzb", "hom", "cplp"]
        .iter()
        .map(|m| method(m, cs.clone()).unwrap())
        .collect();
    let mut culled = vec![0usize; cullers.len()];
    let mut seen = 0usize;
    for pf in street_walk(&scene, frames, seed, 60.0) {
        let f = Frustum::new(
            DVec3::from_array(pf.eye),
            DVec3::from_array(pf.dir),
            pf.fov_deg,
            480,
            270,
        )
        .unwrap();
        let vs = truth.visible(&f);
        seen += vs.len();
        for (k, c) in cullers.iter().enumerate() {
            let fr = c.cull(&f, None);
            let missed: Vec<u32> = vs
                .iter()
                .copied()
                .filter(|i| fr.visible.binary_search(i).is_err())
                .collect();
            assert!(
                missed.is_empty(),
                "{name}: {} culled visible objects {missed:?} from {pf:?}",
                c.name()
            );
            culled[k] += fr.occlusion_culled;
        }
    }
    // The masked-buffer cullers must cull something in a city (hom's coarse map and
    // depth slices cull little in Lyon: see docs/culling.md).
    for (k, c) in cullers.iter().enumerate() {
        if c.name() != "hom" {
            assert!(culled[k] > 0, "{name}: {} culled nothing", c.name());
        }
    }
    assert!(seen > 0);
}

#[test]
fn lyon_street_frames_have_no_false_culls() {
    no_false_culls("lyon1_bdtopo.geojson", 24, 7);
}

#[test]
fn den_haag_street_frames_have_no_false_culls() {
    no_false_culls("denhaag_tile01_lod2.geojson", 24, 11);
}

#[test]
fn two_level_culling_stays_inside_the_candidates() {
    let scene = load("lyon1_bdtopo.geojson");
    let cs = Arc::new(CullScene::new(&scene));
    let pf = street_walk(&scene, 1, 3, 60.0)[0];
    let f = Frustum::new(
        DVec3::from_array(pf.eye),
        DVec3::from_array(pf.dir),
        60.0,
        320,
        180,
    )
    .unwrap();
    let hzb = method("hzb", cs).unwrap();
    let all = hzb.cull(&f, None);
    let cand: Vec<u32> = all.visible.iter().copied().step_by(2).collect();
    let two = hzb.cull(&f, Some(&cand));
    assert!(two.visible.iter().all(|i| cand.binary_search(i).is_ok()));
    assert_eq!(two.candidates, cand.len());
}
