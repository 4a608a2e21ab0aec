//! The plugin in a headless app (no GPU, no window: `MinimalPlugins`, transforms, assets
//! and `bevy_camera`'s visibility propagation): a camera walks through a small generated
//! city whose `.pvs` is loaded by the asset loader, and at every step the entities hidden
//! are exactly the objects outside the PVS of the camera's cell, as `sightline query`
//! (the `sightline-pvs` reader) answers it; children of a hidden node are hidden too.

use bevy::asset::{AssetPlugin, LoadState};
use bevy::camera::visibility::{InheritedVisibility, Visibility, VisibilityPlugin};
use bevy::mesh::skinning::SkinnedMeshInverseBindposes;
use bevy::mesh::Mesh;
use bevy::prelude::*;
use bevy::transform::TransformPlugin;
use bevy_sightline::{
    ActivePvs, Axes, PvsAsset, PvsCamera, PvsIds, PvsKey, PvsView, SightlinePlugin,
};
use sightline_core::Cell;
use sightline_geom::{DVec3, ViewCell};
use sightline_pvs::format::{encode_cells, EncodeOptions};
use sightline_pvs::{Header, PvsFile};
use std::path::Path;
use std::sync::Arc;

fn city_pvs(path: &Path) {
    let scene = Arc::new(sightline_scene::generate::city(5, 50));
    let cells = sightline_scene::cells::grid_cells(&scene, 25.0, 1.5, 2.0).unwrap();
    let method = sightline_methods::create(
        "dual-ray",
        scene.clone(),
        &sightline_methods::MethodOptions::default(),
    )
    .unwrap();
    let opts = sightline_pvs::BuildOptions::default();
    sightline_pvs::build(&scene, &*method, &cells, path, &opts, &|_, _| {}).unwrap();
}

fn app(assets: &Path) -> App {
    let mut app = App::new();
    app.add_plugins((
        MinimalPlugins,
        TransformPlugin,
        AssetPlugin {
            file_path: assets.display().to_string(),
            watch_for_changes_override: Some(false),
            use_asset_processor_override: Some(false),
            ..default()
        },
        VisibilityPlugin,
        SightlinePlugin::default(),
    ))
    // VisibilityPlugin computes mesh bounds: it needs the mesh assets, never used here.
    .init_asset::<Mesh>()
    .init_asset::<SkinnedMeshInverseBindposes>();
    app
}

/// Updates until `handle` has loaded or failed.
fn load(app: &mut App, handle: &Handle<PvsAsset>) -> LoadState {
    for _ in 0..2000 {
        app.update();
        let state = app.world().resource::<AssetServer>().load_state(handle);
        if state.is_loaded() || state.is_failed() {
            return state;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    panic!("the .pvs did not load");
}

/// One object of the city as a glTF scene would spawn it: a node with a mesh child.
struct Node {
    id: u32,
    node: Entity,
    child: Entity,
}

#[test]
fn hidden_entities_are_exactly_those_outside_the_pvs_along_a_walk() {
    let dir = std::env::temp_dir().join(format!("bevy-sightline-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pvs_path = dir.join("city.pvs");
    city_pvs(&pvs_path);
    let file = PvsFile::open(&pvs_path).unwrap();
    let objects = file.header().object_count;
    assert!(objects > 10, "{objects} objects");

    let mut app = app(&dir);
    // Nodes named as the cluster export names them ("12", "cluster 12"), and objects
    // keyed by id; one name that matches nothing stays shown.
    let nodes: Vec<Node> = (0..objects)
        .map(|id| {
            let world = app.world_mut();
            let child = world
                .spawn((Transform::default(), Visibility::default()))
                .id();
            let mut node = world.spawn((Transform::default(), Visibility::default()));
            match id % 3 {
                0 => node.insert(Name::new(id.to_string())),
                1 => node.insert(Name::new(format!("cluster {id}"))),
                _ => node.insert((Name::new("not a cluster"), PvsKey::Id(id))),
            };
            node.add_child(child);
            Node {
                id,
                node: node.id(),
                child,
            }
        })
        .collect();
    let stray = app.world_mut().spawn(Name::new("lamp post")).id();
    let camera = app
        .world_mut()
        .spawn((Transform::default(), PvsCamera))
        .id();

    let handle: Handle<PvsAsset> = app.world().resource::<AssetServer>().load("city.pvs");
    assert!(load(&mut app, &handle).is_loaded());
    app.insert_resource(ActivePvs(handle.clone()));
    let runtime = app
        .world()
        .resource::<Assets<PvsAsset>>()
        .get(&handle)
        .unwrap()
        .pvs()
        .clone();

    // The walk: through the middle of every cell in file order, three steps between two
    // cells (crossing cell boundaries and empty ground), then out of the city.
    let centres: Vec<DVec3> = file.cells().iter().map(|c| (c.min + c.max) * 0.5).collect();
    let mut path = Vec::new();
    for pair in centres.windows(2) {
        for k in 0..3 {
            let p = pair[0].lerp(pair[1], k as f64 / 3.0);
            path.push(DVec3::new(p.x, p.y, 1.7));
        }
    }
    path.push(DVec3::new(1e6, 0.0, 1.7));

    let (mut culled_steps, mut outside_steps) = (0, 0);
    let mut around = Vec::new();
    for (step, p) in path.iter().enumerate() {
        app.world_mut()
            .entity_mut(camera)
            .insert(Transform::from_translation(Axes::YUp.to_bevy(p.to_array())));
        app.update();

        let cell = file.locate(*p);
        let expected: Option<Vec<u32>> = cell.map(|c| file.pvs(c).unwrap());
        let view = app.world().resource::<PvsView>();
        assert_eq!(view.cell(), cell.map(|c| c as u32), "step {step} at {p}");
        assert_eq!(view.error(), None);
        match &expected {
            Some(row) => {
                assert!(view.culling());
                assert_eq!(view.visible(), &row[..], "step {step}");
                runtime.neighbours_into(cell.unwrap() as u32, &mut around);
                assert_eq!(view.neighbours(), &around[..], "step {step}");
                culled_steps += usize::from(row.len() < objects as usize);
            }
            None => {
                assert!(!view.culling());
                outside_steps += 1;
            }
        }
        let world = app.world();
        for n in &nodes {
            let shown = expected
                .as_ref()
                .is_none_or(|row| row.binary_search(&n.id).is_ok());
            let want = if shown {
                Visibility::Inherited
            } else {
                Visibility::Hidden
            };
            assert_eq!(
                world.get::<Visibility>(n.node),
                Some(&want),
                "step {step}, object {}",
                n.id
            );
            assert_eq!(
                world.get::<PvsIds>(n.node).map(PvsIds::ids),
                Some(&[n.id][..])
            );
            let child = world.get::<InheritedVisibility>(n.child).unwrap();
            assert_eq!(child.get(), shown, "step {step}, child of object {}", n.id);
        }
        assert!(world.get::<PvsIds>(stray).is_none());
        assert_eq!(
            world.get::<Visibility>(stray),
            None,
            "an unmatched name is left alone"
        );
    }
    assert!(
        culled_steps > path.len() / 2,
        "{culled_steps} of {} steps hid something",
        path.len()
    );
    assert!(outside_steps >= 1, "the walk ends outside the city");

    // Without an active file every entity is shown again.
    app.world_mut().remove_resource::<ActivePvs>();
    app.update();
    for n in &nodes {
        assert_eq!(
            app.world().get::<Visibility>(n.node),
            Some(&Visibility::Inherited)
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_truncated_pvs_fails_to_load() {
    let dir = std::env::temp_dir().join(format!("bevy-sightline-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pvs_path = dir.join("city.pvs");
    city_pvs(&pvs_path);
    let bytes = std::fs::read(&pvs_path).unwrap();
    std::fs::write(dir.join("truncated.pvs"), &bytes[..bytes.len() / 2]).unwrap();
    std::fs::write(dir.join("empty.pvs"), b"").unwrap();
    let mut app = app(&dir);
    for name in ["truncated.pvs", "empty.pvs", "missing.pvs"] {
        let handle: Handle<PvsAsset> = app.world().resource::<AssetServer>().load(name);
        assert!(load(&mut app, &handle).is_failed(), "{name}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A mesh level's file: 4 box cells in a row, 12 clusters of 4 source objects (OBJ
/// groups) named in the file; each source is hidden from every other cell.
fn level_pvs() -> (Vec<u8>, Vec<u32>, Vec<&'static str>) {
    let names = vec!["crate", "door", "pillar", "stairs \"up\""];
    let sources: Vec<u32> = (0..12).map(|c| c / 3).collect();
    let cells: Vec<Cell> = (0..4)
        .map(|k| {
            let x = k as f64 * 4.0;
            Cell::Box(ViewCell::from_array([x, 0.0, 0.0, x + 4.0, 4.0, 3.0]).unwrap())
        })
        .collect();
    let sets: Vec<roaring::RoaringBitmap> = (0..4u32)
        .map(|k| {
            (0..12u32)
                .filter(|&c| (sources[c as usize] + k).is_multiple_of(2) || (k == 1 && c == 1))
                .collect()
        })
        .collect();
    let json_names: Vec<String> = names
        .iter()
        .map(|n| format!("\"{}\"", n.replace('"', "\\\"")))
        .collect();
    let header = Header::new(
        0x5eed,
        "volumetric",
        vec![
            (
                "sources".into(),
                sources
                    .iter()
                    .map(u32::to_string)
                    .collect::<Vec<_>>()
                    .join(","),
            ),
            ("source_names".into(), format!("[{}]", json_names.join(","))),
        ],
        12,
        cells.len(),
    );
    let present: Vec<u32> = (0..4).collect();
    let bytes = encode_cells(&header, &cells, &present, &sets, &EncodeOptions::default()).unwrap();
    (bytes, sources, names)
}

#[test]
fn source_names_map_nodes_to_all_their_clusters() {
    let dir = std::env::temp_dir().join(format!("bevy-sightline-level-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (bytes, sources, names) = level_pvs();
    std::fs::write(dir.join("level.pvs"), &bytes).unwrap();
    let file = PvsFile::open(dir.join("level.pvs")).unwrap();
    let mut app = app(&dir);
    // glTF nodes named as the level's OBJ groups; one group keyed explicitly, and a
    // cluster node beside them.
    let by_name: Vec<Entity> = names
        .iter()
        .map(|n| app.world_mut().spawn(Name::new(*n)).id())
        .collect();
    let keyed = app.world_mut().spawn(PvsKey::Source("door".into())).id();
    let cluster = app
        .world_mut()
        .spawn(PvsKey::NodeName("cluster_7".into()))
        .id();
    app.world_mut().spawn((Transform::default(), PvsCamera));
    let handle: Handle<PvsAsset> = app.world().resource::<AssetServer>().load("level.pvs");
    assert!(load(&mut app, &handle).is_loaded());
    app.insert_resource(ActivePvs(handle));

    for x in [2.0, 6.0, 10.0, 14.0, 40.0] {
        let p = DVec3::new(x, 2.0, 1.5);
        let mut camera = app
            .world_mut()
            .query_filtered::<&mut Transform, With<PvsCamera>>();
        *camera.single_mut(app.world_mut()).unwrap() =
            Transform::from_translation(Axes::YUp.to_bevy(p.to_array()));
        app.update();
        let row = file.locate(p).map(|c| file.pvs(c).unwrap());
        let shown = |clusters: &[u32]| {
            row.as_ref()
                .is_none_or(|r| clusters.iter().any(|c| r.binary_search(c).is_ok()))
        };
        let world = app.world();
        for (s, &e) in by_name.iter().enumerate() {
            let clusters: Vec<u32> = (0..12)
                .filter(|&c| sources[c as usize] == s as u32)
                .collect();
            assert_eq!(world.get::<PvsIds>(e).map(PvsIds::ids), Some(&clusters[..]));
            let want = if shown(&clusters) {
                Visibility::Inherited
            } else {
                Visibility::Hidden
            };
            assert_eq!(
                world.get::<Visibility>(e),
                Some(&want),
                "{} at x {x}",
                names[s]
            );
        }
        assert_eq!(
            world.get::<Visibility>(keyed),
            world.get::<Visibility>(by_name[1])
        );
        let want = if shown(&[7]) {
            Visibility::Inherited
        } else {
            Visibility::Hidden
        };
        assert_eq!(
            world.get::<Visibility>(cluster),
            Some(&want),
            "cluster 7 at x {x}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
