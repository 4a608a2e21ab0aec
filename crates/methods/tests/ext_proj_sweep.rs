//! The occlusion sweep (§5) on a small forest of leaf triangles: conservative, never
//! larger than the plain PVS, and the leaves fuse on its occlusion maps.

mod ext_proj_common;

use ext_proj_common::sampled_visible_among;
use sightline_geom::{Aabb3, DVec2, DVec3, Polygon, ViewCell};
use sightline_methods::ext_proj::{ExtProj, Params};
use sightline_methods::VisibilityMethod;
use sightline_scene::{Mesh, Object, Prism, Scene};
use sightline_stats::Rng;
use std::sync::Arc;

/// A tree: a trunk prism (its inner bound) and `leaves` small triangles in a crown.
fn tree(c: DVec2, leaves: usize, rng: &mut Rng) -> Object {
    let mut m = Mesh::default();
    let trunk = Polygon::rect(c - DVec2::splat(0.2), c + DVec2::splat(0.2));
    let trunk_prism = Prism::new(trunk.clone().normalized(), 0.0, 3.0);
    for t in trunk_prism.triangles() {
        let base = m.vertices.len() as u32;
        m.vertices.extend(t);
        m.triangles.push([base, base + 1, base + 2]);
    }
    for _ in 0..leaves {
        let p = DVec3::new(
            c.x + (rng.f64() - 0.5) * 4.0,
            c.y + (rng.f64() - 0.5) * 4.0,
            1.0 + rng.f64() * 5.0,
        );
        let a = DVec3::new(rng.f64() - 0.5, rng.f64() - 0.5, rng.f64() - 0.5) * 3.5;
        let b = DVec3::new(rng.f64() - 0.5, rng.f64() - 0.5, rng.f64() - 0.5) * 3.5;
        let base = m.vertices.len() as u32;
        m.vertices.extend([p, p + a, p + b]);
        m.triangles.push([base, base + 1, base + 2]);
    }
    let outer = Prism::new(
        Polygon::rect(c - DVec2::splat(2.9), c + DVec2::splat(2.9)).normalized(),
        0.0,
        7.0,
    );
    Object::mesh(None, m, vec![trunk_prism], vec![outer])
}

/// The PVS of `c` by ext-proj with `params`.
fn pvs(scene: &Arc<Scene>, params: Params, c: &ViewCell) -> Vec<u32> {
    ExtProj::new(scene.clone(), params).pvs(c).expect("pvs")
}

fn forest(rows: usize, cols: usize, leaves: usize) -> Scene {
    let mut rng = Rng::new(0x9e37_79b9_7f4a_7c15);
    let mut objs = Vec::new();
    for i in 0..rows {
        for j in 0..cols {
            let c = DVec2::new(8.0 + 4.5 * i as f64, -12.0 + 4.5 * j as f64);
            objs.push(tree(c, leaves, &mut rng));
        }
    }
    Scene::from_objects(objs)
}

#[test]
fn sweep_is_conservative_and_never_adds_objects() {
    let scene = Arc::new(forest(5, 7, 300));
    let c: ViewCell = "0,-1,1.5,2,1,2".parse().expect("cell");
    let plain = pvs(
        &scene,
        Params {
            resolution_px: 256,
            ..Params::default()
        },
        &c,
    );
    let swept = pvs(
        &scene,
        Params {
            sweep: true,
            sweep_planes: 15,
            resolution_px: 256,
            kernel_px: 9,
            ..Params::default()
        },
        &c,
    );
    assert!(
        swept.iter().all(|i| plain.contains(i)),
        "sweep adds nothing"
    );
    let culled: Vec<u32> = (0..scene.objects.len() as u32)
        .filter(|i| swept.binary_search(i).is_err())
        .collect();
    let missed = sampled_visible_among(&scene, &c, 3, 3, &culled);
    assert!(missed.is_empty(), "missed {missed:?}");
}

/// A 15-plane sweep of a small forest (5 × 7 trees of 300 leaves) and a 2 m cell
/// inside it.
fn small_forest_sweep() -> (ExtProj, ViewCell) {
    let e = ExtProj::new(
        Arc::new(forest(5, 7, 300)),
        Params {
            sweep: true,
            sweep_planes: 15,
            resolution_px: 256,
            kernel_px: 9,
            ..Params::default()
        },
    );
    (e, "0,-1,1.5,2,1,2".parse().expect("cell"))
}

/// Leaves alone fill the sweep's occlusion maps: thousands of fully black pixels
/// appear where no prism occludes (only the thin trunks are prisms).
#[test]
fn leaves_fill_the_occlusion_maps() {
    let (e, c) = small_forest_sweep();
    let sw = sightline_methods::ext_proj::Sweep::run(&e, &c, None);
    let best = sw.planes.iter().map(|p| p.umbra.count()).max().unwrap_or(0);
    assert!(best > 5000, "{best}");
}

/// The generated dense forest (`ForestParams::dense`, few trees): from a small cell
/// inside it the sweep's PVS is a subset of the plain PVS (by construction: the sweep
/// only adds a hiding test on the same planes, and the default subdivision does not
/// depend on the PVS), misses nothing the ground truth sees, and culls trees that plain
/// extended projections cannot (leaves are not occluders there: only the thin trunks).
#[test]
fn sweep_culls_the_dense_generated_forest_without_missing() {
    use sightline_core::check::{ground_truth, TruthOptions};
    use sightline_scene::generate::{forest_with, ForestParams};
    let scene = Arc::new(forest_with(1, &ForestParams::dense(100)));
    // A 0.5 m cell between four trees near a corner of the 10 × 10 grid (4 m spacing),
    // looking across the forest.
    let c: ViewCell = "5.75,5.75,1.5,6.25,6.25,2".parse().expect("cell");
    let params = Params {
        resolution_px: 512,
        ..Params::default()
    };
    let plain = pvs(&scene, params.clone(), &c);
    let swept = pvs(
        &scene,
        Params {
            sweep: true,
            sweep_planes: 15,
            ..params
        },
        &c,
    );
    assert!(swept.iter().all(|i| plain.binary_search(i).is_ok()));
    let truth = ground_truth(
        &scene,
        &c,
        &TruthOptions {
            samples: 16,
            resolution_px: 256,
            ..TruthOptions::default()
        },
    );
    let missed: Vec<u32> = truth
        .visible
        .iter()
        .copied()
        .filter(|i| swept.binary_search(i).is_err())
        .collect();
    assert!(missed.is_empty(), "missed {missed:?}");
    assert!(
        swept.len() < plain.len(),
        "sweep {} vs plain {} of {} (truth {})",
        swept.len(),
        plain.len(),
        scene.objects.len(),
        truth.visible.len()
    );
}

/// On the sweep's planes, the improved Projection (§4, against the planes' depth
/// maps) hides every probe box the standard test hides (1 m cubes on a grid over the
/// forest). It rarely hides more there: a re-projected pixel carries the previous
/// plane's depth, so only boxes between two consecutive planes can use it.
#[test]
fn improved_projection_on_sweep_planes() {
    let (e, c) = small_forest_sweep();
    let sw = sightline_methods::ext_proj::Sweep::run(&e, &c, None);
    let mut hidden = 0;
    for i in 0..40 {
        for j in 0..30 {
            for k in 0..4 {
                let lo = DVec3::new(6.0 + i as f64, -15.0 + j as f64, 2.0 * k as f64);
                let b = Aabb3::new(lo, lo + DVec3::ONE);
                let (std, imp) = (sw.hides(&b, false), sw.hides(&b, true));
                assert!(!std || imp, "{b:?}");
                hidden += std as usize;
            }
        }
    }
    assert!(hidden > 0, "the sweep hides some probes");
}

/// A leaf crossing a sweep plane projects its part in front of the plane (§5.2: the
/// occluders in front of the plane): a slanted 10 m board whose top leans over the
/// first plane (x = 3) blackens pixels there, where before it was left to later planes.
#[test]
fn leaves_crossing_a_plane_project_their_front_part() {
    let mesh_of = |tris: &[[DVec3; 3]]| {
        let mut m = Mesh::default();
        for t in tris {
            let base = m.vertices.len() as u32;
            m.vertices.extend(t);
            m.triangles.push([base, base + 1, base + 2]);
        }
        Object::mesh(None, m, vec![], vec![])
    };
    let v = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    // A small leaf just beyond 2.5 m sets the first plane at x = 3 (start 2 m).
    let leaf = mesh_of(&[[v(2.5, 0.4, 1.7), v(2.6, 0.6, 1.7), v(2.55, 0.5, 1.8)]]);
    // The board runs from x = 4 on the ground to x = 2.8 at z = 4: its part z ≥ 3.33
    // lies in front of x = 3.
    let board = mesh_of(&[
        [v(4.0, -5.0, 0.0), v(4.0, 5.0, 0.0), v(2.8, 5.0, 4.0)],
        [v(4.0, -5.0, 0.0), v(2.8, 5.0, 4.0), v(2.8, -5.0, 4.0)],
    ]);
    let c: ViewCell = "0,0,1.5,1,1,2".parse().expect("cell");
    let black_above_ground = |objects: Vec<Object>| {
        let e = ExtProj::new(
            Arc::new(Scene::from_objects(objects)),
            Params {
                sweep: true,
                sweep_planes: 1,
                resolution_px: 256,
                adaptive_budget: None,
                ..Params::default()
            },
        );
        let sw = sightline_methods::ext_proj::Sweep::run(&e, &c, None);
        let plane = sw
            .planes
            .iter()
            .find(|p| p.plane.dir == sightline_methods::ext_proj::Direction::PosX)
            .expect("a +x plane");
        assert!((plane.plane.x - 3.0).abs() < 0.01, "{}", plane.plane.x);
        let n = plane.umbra.n;
        (0..n * n)
            .filter(|&k| {
                let p = plane
                    .plane
                    .from_px(DVec2::new((k % n) as f64, (k / n) as f64));
                plane.umbra.black[k] && p.y > 0.0
            })
            .count()
    };
    let alone = black_above_ground(vec![leaf.clone()]);
    let with_board = black_above_ground(vec![leaf, board]);
    assert!(with_board > alone + 1000, "{alone} → {with_board}");
}
