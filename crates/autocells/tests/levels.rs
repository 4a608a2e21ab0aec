//! Hand-checked facts on small generated levels, and 0 misses against the item-buffer
//! ground truth sampled from every cell's free space.

use sightline_autocells::{testlevel, AutoCells, Options};
use sightline_core::check::{TruthOptions, TruthScene};
use sightline_scene::Scene;

fn opts(h: f64) -> Options {
    Options {
        smallest_hole: Some(h),
        ..Options::default()
    }
}

fn id(scene: &Scene, name: &str) -> u32 {
    scene
        .objects
        .iter()
        .position(|o| o.name.as_deref() == Some(name))
        .expect("named object") as u32
}

/// Every cell: the truth from its free voxels is inside its PVS.
fn no_misses(scene: &Scene, auto: &AutoCells) {
    let truth = TruthScene::new(scene);
    let topts = TruthOptions {
        samples: 8,
        resolution_px: 64,
        targeted_rays_per_object: 16,
        seed: 3,
    };
    let mut judged = 0;
    for c in 0..auto.len() {
        let Some(region) = auto.free_region(c) else {
            continue;
        };
        let t = truth.ground_truth_in(&region, &topts);
        let pvs = auto.pvs(c);
        let missed: Vec<u32> = t
            .visible
            .iter()
            .copied()
            .filter(|o| pvs.binary_search(o).is_err())
            .collect();
        assert!(
            missed.is_empty(),
            "cell {c} {:?} missed {missed:?}",
            auto.cell_box(c)
        );
        judged += 1;
    }
    assert!(judged > 0);
}

#[test]
fn two_rooms_and_a_door() {
    for offset in [0.0, 1.0e5] {
        let scene = testlevel::two_rooms_and_a_door(offset);
        let auto = AutoCells::build(&scene, &opts(0.45)).expect("builds");
        let r = &auto.report;
        assert!(r.voxels.solid > 0, "{r:?}");
        assert!(r.leak.is_none(), "{:?}", r.leak);
        let at = |x: f64, y: f64| [x + offset, y + offset, 1.5 + offset];
        let from_a = auto.pvs_at(at(-3.0, -2.0)).expect("A is free");
        let crate_b = id(&scene, "crate-b");
        let crate_d = id(&scene, "crate-d");
        assert!(from_a.contains(&crate_b), "B is seen through the door");
        assert!(!from_a.contains(&crate_d), "D is around two corners");
        let from_d = auto.pvs_at(at(-5.0, 5.5)).expect("D is free");
        assert!(!from_d.contains(&id(&scene, "crate-a")));
        assert!(auto.pvs_at(at(0.0, -2.0)).is_err(), "inside the wall");
        no_misses(&scene, &auto);
    }
}

#[test]
fn thin_wall_does_not_occlude() {
    let scene = testlevel::thin_wall();
    let auto = AutoCells::build(&scene, &opts(0.45)).expect("builds");
    let from_w = auto.pvs_at([-2.0, 0.0, 1.0]).expect("free");
    assert!(from_w.contains(&id(&scene, "crate-e")));
    no_misses(&scene, &auto);
}

#[test]
fn bad_input_is_an_error_or_a_counted_warning() {
    use sightline_autocells::AutoError;
    use sightline_geom::DVec3;
    use sightline_scene::{Mesh, Object};
    let empty = Scene::from_objects(vec![]);
    assert!(matches!(
        AutoCells::build(&empty, &opts(0.5)),
        Err(AutoError::NoTriangles)
    ));
    let level = testlevel::two_rooms_and_a_door(0.0);
    assert!(matches!(
        AutoCells::build(&level, &opts(100.0)),
        Err(AutoError::HoleTooLarge { .. })
    ));
    for h in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(matches!(
            AutoCells::build(&level, &opts(h)),
            Err(AutoError::BadHole(_))
        ));
    }
    // Degenerate and huge triangles, an open mesh: counted, no panic.
    let mut objects = level.objects.clone();
    let m = Mesh {
        vertices: vec![
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 1.0, 1.0),
            DVec3::new(2.0, 2.0, 1.0),
            DVec3::new(-1e4, -1e4, 1.7),
            DVec3::new(1e4, -1e4, 2.3),
        ],
        triangles: vec![[0, 1, 2], [0, 0, 0], [3, 4, 1]],
    };
    objects.push(Object::mesh(Some("junk".into()), m, vec![], vec![]));
    let small = Options {
        max_voxels: 1 << 16,
        ..opts(0.45)
    };
    let auto = AutoCells::build(&Scene::from_objects(objects), &small).expect("builds");
    assert_eq!(auto.report.voxels.degenerate_triangles, 2);
    assert!(
        auto.report.smallest_hole > 0.45,
        "raised to fit the voxel budget"
    );
}

#[test]
fn a_wall_of_zero_thickness_on_the_lattice_occludes() {
    let scene = testlevel::paper_wall(0.0);
    let walls = Options {
        walls_bound_cells: true,
        ..opts(0.5)
    };
    let auto = AutoCells::build(&scene, &walls).expect("builds");
    assert!(
        auto.voxels.stats.closed_faces >= 8 * 6,
        "{:?}",
        auto.voxels.stats
    );
    let from_w = auto.pvs_at([-2.0, 0.0, 1.0]).expect("free");
    assert!(from_w.contains(&id(&scene, "crate-w")));
    assert!(from_w.contains(&id(&scene, "paper-wall")));
    assert!(!from_w.contains(&id(&scene, "crate-e")), "{from_w:?}");
    no_misses(&scene, &auto);
    // Off the lattice the wall closes no face: conservative, nothing culled across it.
    let scene = testlevel::paper_wall(0.2);
    let auto = AutoCells::build(&scene, &walls).expect("builds");
    let from_w = auto.pvs_at([-2.0, 0.0, 1.0]).expect("free");
    assert!(from_w.contains(&id(&scene, "crate-e")));
    no_misses(&scene, &auto);
}
