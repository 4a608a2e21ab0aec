//! One scene of each kind opened and asked, end to end: a generated city (GeoJSON), a
//! mesh level (the two rooms of `sightline-autocells`, as OBJ) and dm1 (`data/quake`).

use sightline_core::{Method, MethodOptions, SceneKind};
use sightline_geom::ViewCell;
use sightline_world::{Evidence, OpenOptions, World};
use std::path::{Path, PathBuf};

fn dm1() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/quake/dm1.bsp")
}

fn rooms(dir: &Path) -> PathBuf {
    let path = dir.join("rooms.obj");
    let mut f = std::fs::File::create(&path).unwrap();
    let level = sightline_autocells::testlevel::two_rooms_and_a_door(0.0);
    sightline_scene::export::write_obj(&level, &mut f).unwrap();
    path
}

fn cell(v: [f64; 6]) -> ViewCell {
    serde_json::from_value(serde_json::json!(v)).unwrap()
}

#[test]
fn a_city_answers_boxes_with_its_methods_and_refuses_points() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("city.geojson");
    let scene = sightline_scene::generate::city(1, 12);
    let mut f = std::fs::File::create(&path).unwrap();
    sightline_scene::export::write_geojson(&scene, &mut f).unwrap();
    let world = World::open(&path, &OpenOptions::default()).unwrap();
    assert_eq!(world.kind(), SceneKind::City);
    assert_eq!(world.default_method(), Method::Erosion);
    assert!(world.resolve(Some("portals")).is_err());
    let b = world.scene().bounds;
    let c = cell([b.min.x, b.min.y, 1.5, b.max.x, b.max.y, 2.0]);
    let all = world
        .pvs_of(Method::All, &c, &MethodOptions::default())
        .unwrap();
    assert_eq!(all.visible.len(), world.scene().objects.len());
    assert_eq!(all.unit(), "objects");
    let dual = world
        .pvs_of(Method::DualRay, &c, &MethodOptions::default())
        .unwrap();
    assert!(dual.visible.iter().all(|id| all.visible.contains(id)));
    let e = world.pvs_at(Method::DualRay, [0.0, 0.0, 1.7]).unwrap_err();
    assert!(e.to_string().contains("--at answers"), "{e}");
    // The one harness: `all` misses nothing.
    let m = world
        .method(Method::All, &MethodOptions::default())
        .unwrap();
    let j = world.judge_boxes(m.as_ref(), &[c], &|| {}).unwrap();
    assert_eq!((j.judged, j.missed, j.unit), (1, 0, "object"));
    assert!(matches!(j.evidence, Evidence::Boxes(_)));
    j.verdict().unwrap();
    assert!(world.encode(Method::Erosion).is_err());
}

#[test]
fn a_mesh_level_answers_at_a_point_for_a_box_and_as_a_file() {
    let dir = tempfile::tempdir().unwrap();
    let opts = OpenOptions {
        smallest_hole: Some(0.45),
        ..OpenOptions::default()
    };
    let world = World::open(&rooms(dir.path()), &opts).unwrap();
    assert_eq!(world.kind(), SceneKind::Mesh);
    assert_eq!(world.default_method(), Method::Volumetric);
    // Room A (as the CLI's mesh test): its crate is seen, room D's is not.
    let at = world.pvs_at(Method::Portals, [-3.0, -2.0, 1.5]).unwrap();
    let sources = at.visible_sources.clone().unwrap();
    assert!(sources.contains(&3) && !sources.contains(&5), "{sources:?}");
    assert_eq!(at.unit(), "clusters");
    // A box around the point answers at least the point's cell.
    let b = world
        .pvs_of(
            Method::Portals,
            &cell([-3.1, -2.1, 1.4, -2.9, -1.9, 1.6]),
            &MethodOptions::default(),
        )
        .unwrap();
    assert!(at.visible.iter().all(|c| b.visible.contains(c)));
    // In a wall: an error, not a panic.
    assert!(world.pvs_at(Method::Portals, [0.0, -2.0, 1.5]).is_err());
    // The file: walkable viewcells first, then the automatic cells.
    let enc = world.encode(Method::Volumetric).unwrap();
    let facts = enc.mesh.as_ref().unwrap();
    assert!(facts.viewcells > 0);
    assert_eq!(enc.cells, facts.viewcells + facts.auto_cells);
    let file = sightline_pvs::PvsFile::from_bytes(enc.bytes).unwrap();
    assert_eq!(file.cells().len(), enc.cells);
    assert_eq!(
        world.clustered_for(&file).unwrap().scene.fingerprint(),
        file.header().fingerprint
    );
    // Judged by the one harness.
    let (j, level) = world.judge(Method::PortalsFast, 3).unwrap();
    assert_eq!(j.missed, 0);
    assert!(j.judged > 0 && level.is_some());
    j.verdict().unwrap();
}

#[test]
fn a_bsp_level_answers_by_leaf_and_builds_every_leaf() {
    let world = World::open(&dm1(), &OpenOptions::default()).unwrap();
    assert_eq!(world.kind(), SceneKind::Bsp);
    assert_eq!(world.default_method(), Method::Portals);
    assert!(world.resolve(Some("volumetric")).is_err());
    let info = world.bsp_info().unwrap().unwrap();
    assert_eq!(info.visleafs, 434);
    assert!(world.player_start().is_some());
    let at = world
        .pvs_at(Method::PortalsFast, [200.0, 1000.0, 50.0])
        .unwrap();
    let leaf = at.leaf.unwrap();
    assert!(at.visible_leaves.as_ref().unwrap().contains(&leaf));
    assert_eq!(at.unit(), "faces");
    assert!(world
        .pvs_at(Method::PortalsFast, [1e5, 1e5, 1e5])
        .unwrap_err()
        .to_string()
        .contains("not in open space"));
    let enc = world.encode(Method::PortalsFast).unwrap();
    assert_eq!(enc.cells, info.open_leaves);
    let file = sightline_pvs::PvsFile::from_bytes(enc.bytes).unwrap();
    let i = file
        .locate(sightline_geom::DVec3::new(200.0, 1000.0, 50.0))
        .unwrap();
    assert_eq!(file.pvs(i).unwrap(), at.visible);
}
