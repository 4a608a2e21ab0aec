//! Indoor frames on a real Quake level (`data/quake/dm1.bsp`, in the repository): its
//! world faces are the objects and, through [`CullScene::with_surfaces`], the
//! occluders. From eyes above its floors, no culler hides a face the item buffer sees,
//! and the faces do occlude (walls hide the rooms behind them).

use glam::DVec3;
use sightline_culling::truth::FrameTruth;
use sightline_culling::walk::floor_frames;
use sightline_culling::{method, CullScene, Frustum};
use std::path::Path;
use std::sync::Arc;

#[test]
fn dm1_frames_have_no_false_culls() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/quake/dm1.bsp");
    let scene = sightline_scene::import::load(&path, &Default::default()).unwrap();
    let cs = Arc::new(CullScene::with_surfaces(&scene));
    assert!(cs.surface_occluders > 1000, "{}", cs.surface_occluders);
    let truth = FrameTruth::new(&scene);
    let frames = floor_frames(&scene, 24, 7, 46.0, 75.0);
    assert_eq!(frames.len(), 24);
    let cullers: Vec<_> = ["hzb", "hom", "cplp"]
        .iter()
        .map(|n| method(n, cs.clone()).unwrap())
        .collect();
    let mut occluded = 0;
    for pf in &frames {
        let f = Frustum::new(
            DVec3::from_array(pf.eye),
            DVec3::from_array(pf.dir),
            pf.fov_deg,
            256,
            144,
        )
        .unwrap();
        let vs = truth.visible(&f);
        for c in &cullers {
            let fr = c.cull(&f, None);
            for id in &vs {
                assert!(
                    fr.visible.binary_search(id).is_ok(),
                    "{} culled face {id}, seen from {:?} looking {:?}",
                    c.name(),
                    pf.eye,
                    pf.dir
                );
            }
            if c.name() == "hzb" {
                occluded += fr.occlusion_culled;
            }
        }
    }
    assert!(occluded > 0, "the level's faces hid nothing");
}
