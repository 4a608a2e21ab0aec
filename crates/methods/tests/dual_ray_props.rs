//! Property tests of `dual-ray` / `dual-ray-exact` on random box cities, against an
//! independent brute-force visibility (segments from sample points of the cell's free
//! space to sample points on each object, tested against the open boxes of the others).
//!
//! * every object the brute force sees is in both PVS (conservative);
//! * `dual-ray` at every resolution contains `dual-ray-exact`;
//! * the virtual occluders only drop hidden objects (PVS with them ⊆ without, ⊇ seen);
//! * so do the boxes proven hidden, used as occluders by the later tests.

use proptest::prelude::*;
use sightline_geom::{DVec2, DVec3, Polygon, ViewCell};
use sightline_methods::dual_ray::{DualRay, Planarity};
use sightline_methods::{create, MethodOptions};
use sightline_scene::{Object, Scene};
use std::ops::Range;
use std::sync::Arc;

#[derive(Clone, Debug)]
struct Bx {
    min: DVec3,
    max: DVec3,
}

/// Whether the segment `p → q` meets the open box.
fn hits_open_box(p: DVec3, q: DVec3, b: &Bx) -> bool {
    let d = q - p;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        if d[k] == 0.0 {
            if p[k] <= b.min[k] || p[k] >= b.max[k] {
                return false;
            }
        } else {
            let a = (b.min[k] - p[k]) / d[k];
            let c = (b.max[k] - p[k]) / d[k];
            let (lo, hi) = if a < c { (a, c) } else { (c, a) };
            t0 = t0.max(lo);
            t1 = t1.min(hi);
        }
    }
    t1 - t0 > 1e-9
}

fn inside_open(p: DVec3, b: &Bx) -> bool {
    (0..3).all(|k| p[k] > b.min[k] && p[k] < b.max[k])
}

/// Sample points on the 5 visible faces of a box (jittered to avoid grazing planes).
fn face_points(b: &Bx, k: usize) -> Vec<DVec3> {
    let mut out = Vec::new();
    let f = |i: usize| (i as f64 + 0.5 + 0.0137 * (i as f64 + 1.0)) / (k as f64 + 0.2);
    for i in 0..k {
        for j in 0..k {
            let (s, t) = (f(i), f(j));
            let x = b.min.x + s * (b.max.x - b.min.x);
            let y = b.min.y + t * (b.max.y - b.min.y);
            let z = b.min.z + t * (b.max.z - b.min.z);
            let y2 = b.min.y + s * (b.max.y - b.min.y);
            out.push(DVec3::new(x, y, b.max.z));
            out.push(DVec3::new(x, b.min.y, z));
            out.push(DVec3::new(x, b.max.y, z));
            out.push(DVec3::new(b.min.x, y2, z));
            out.push(DVec3::new(b.max.x, y2, z));
        }
    }
    out
}

fn brute_visible(boxes: &[Bx], cell: &ViewCell) -> Vec<u32> {
    let mut eyes = Vec::new();
    let n = 6;
    for i in 0..=n {
        for j in 0..=n {
            for k in 0..2 {
                let s = (i as f64 + 0.031) / (n as f64 + 0.07);
                let t = (j as f64 + 0.047) / (n as f64 + 0.09);
                let p = DVec3::new(
                    cell.min.x + s * (cell.max.x - cell.min.x),
                    cell.min.y + t * (cell.max.y - cell.min.y),
                    cell.min.z + (k as f64 * 0.9 + 0.05) * (cell.max.z - cell.min.z),
                );
                if !boxes.iter().any(|b| inside_open(p, b)) {
                    eyes.push(p);
                }
            }
        }
    }
    let mut vis = Vec::new();
    for (id, b) in boxes.iter().enumerate() {
        let targets = face_points(b, 4);
        let seen = targets.iter().any(|q| {
            eyes.iter().any(|p| {
                boxes
                    .iter()
                    .enumerate()
                    .all(|(o, ob)| o == id || !hits_open_box(*p, *q, ob))
            })
        });
        if seen {
            vis.push(id as u32);
        }
    }
    vis
}

/// Square eye-height cells of side `sides` m, their low corner at `(x + 0.3, y + 0.6)` for
/// whole `x`, `y` in `0..extent` (off the buildings' grid).
fn square_cell(extent: i32, sides: Range<i32>) -> impl Strategy<Value = ViewCell> {
    (0..extent, 0..extent, sides).prop_map(|(x, y, s)| {
        ViewCell::from_array([
            x as f64 + 0.3,
            y as f64 + 0.6,
            1.5,
            x as f64 + 0.3 + s as f64,
            y as f64 + 0.6 + s as f64,
            2.0,
        ])
        .expect("valid cell")
    })
}

fn city() -> impl Strategy<Value = (Vec<Bx>, ViewCell)> {
    // Buildings on a 5 m grid, so many of them touch (party walls) or overlap.
    let building =
        (0i32..24, 0i32..24, 1i32..5, 1i32..5, 2u32..30).prop_map(|(x, y, w, d, h)| Bx {
            min: DVec3::new(x as f64 * 5.0, y as f64 * 5.0, 0.0),
            max: DVec3::new((x + w) as f64 * 5.0, (y + d) as f64 * 5.0, h as f64),
        });
    (
        prop::collection::vec(building, 4..16),
        square_cell(100, 2..25),
    )
}

/// A wider city of long walls and blocks (up to 400 m) and larger cells, cut into
/// strips whose virtual occluders' planes have occluders in front and occludees behind.
fn wide_city() -> impl Strategy<Value = (Vec<Bx>, ViewCell)> {
    let building = (
        0i32..40,
        0i32..40,
        1i32..12,
        1i32..4,
        2u32..30,
        any::<bool>(),
    )
        .prop_map(|(x, y, w, d, h, across)| {
            let (w, d) = if across { (d, w) } else { (w, d) };
            Bx {
                min: DVec3::new(x as f64 * 10.0, y as f64 * 10.0, 0.0),
                max: DVec3::new((x + w) as f64 * 10.0, (y + d) as f64 * 10.0, h as f64),
            }
        });
    (
        prop::collection::vec(building, 8..18),
        square_cell(300, 5..60),
    )
}

fn scene_of(boxes: &[Bx]) -> Arc<Scene> {
    Arc::new(Scene::from_objects(
        boxes
            .iter()
            .map(|b| {
                Object::block(
                    None,
                    Polygon::rect(DVec2::new(b.min.x, b.min.y), DVec2::new(b.max.x, b.max.y)),
                    0.0,
                    b.max.z,
                )
            })
            .collect(),
    ))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn conservative_and_nested((boxes, cell) in city()) {
        let scene = scene_of(&boxes);
        let exact = create("dual-ray-exact", scene.clone(), &MethodOptions::default())
            .unwrap()
            .pvs(&cell)
            .unwrap();
        let vis = brute_visible(&boxes, &cell);
        for id in &vis {
            prop_assert!(exact.contains(id), "exact misses {} (visible {:?}, pvs {:?})", id, vis, exact);
        }
        for r in [16u32, 32, 128] {
            let opts = MethodOptions { resolution_px: Some(r), ..Default::default() };
            let p = create("dual-ray", scene.clone(), &opts).unwrap().pvs(&cell).unwrap();
            for id in &exact {
                prop_assert!(p.contains(id), "res {}: exact has {}, discrete {:?}", r, id, p);
            }
        }
    }

    /// The seed rays spare tests but change no PVS, and everything they report is in
    /// the exact PVS (they follow real clear rays).
    #[test]
    fn seed_rays_change_no_pvs((mut boxes, cell) in city()) {
        // Low walls and sheds under the eye too (descending rays).
        for b in &mut boxes {
            if b.max.z < 8.0 {
                b.max.z *= 0.25;
            }
        }
        let scene = scene_of(&boxes);
        for planarity in [Planarity::Exact, Planarity::Discrete { resolution_px: 32 }] {
            let on = DualRay::new("dual-ray", scene.clone(), planarity);
            let seeded = on.seed_objects(&cell);
            let with = on.pvs_with_stats(&cell).0;
            let without = DualRay::new("dual-ray", scene.clone(), planarity)
                .with_seed(false)
                .pvs_with_stats(&cell)
                .0;
            prop_assert_eq!(&with, &without);
            for id in &seeded {
                prop_assert!(without.contains(id), "seed reports {} not in {:?}", id, without);
            }
        }
    }

    /// The cell's strips and virtual occluders drop only hidden objects: with them the
    /// PVS is contained in the one without, still holds everything the brute force
    /// sees, and `dual-ray` with them contains `dual-ray-exact` with them.
    #[test]
    fn virtual_occluders_only_drop_hidden((boxes, cell) in wide_city()) {
        let scene = scene_of(&boxes);
        let vis = brute_visible(&boxes, &cell);
        let exact = DualRay::new("dual-ray-exact", scene.clone(), Planarity::Exact)
            .with_virtual_occluders(true)
            .pvs_with_stats(&cell)
            .0;
        for planarity in [Planarity::Exact, Planarity::Discrete { resolution_px: 32 }] {
            let with = DualRay::new("dual-ray", scene.clone(), planarity)
                .with_virtual_occluders(true)
                .pvs_with_stats(&cell)
                .0;
            let without = DualRay::new("dual-ray", scene.clone(), planarity).pvs_with_stats(&cell).0;
            for id in &with {
                prop_assert!(without.contains(id), "{:?}: {} only with VOs", planarity, id);
            }
            for id in vis.iter().chain(&exact) {
                prop_assert!(with.contains(id), "{:?}: misses {} ({:?})", planarity, id, with);
            }
        }
    }

    /// Boxes proven hidden occlude the later tests: with them the PVS is contained in
    /// the one without, still holds everything the brute force sees, and `dual-ray`
    /// contains `dual-ray-exact` (both with them).
    #[test]
    fn hidden_occluders_only_drop_hidden((boxes, cell) in dense_city()) {
        let scene = scene_of(&boxes);
        let vis = brute_visible(&boxes, &cell);
        let exact = DualRay::new("dual-ray-exact", scene.clone(), Planarity::Exact)
            .pvs_with_stats(&cell)
            .0;
        for planarity in [Planarity::Exact, Planarity::Discrete { resolution_px: 32 }] {
            let with = DualRay::new("dual-ray", scene.clone(), planarity).pvs_with_stats(&cell).0;
            let without = DualRay::new("dual-ray", scene.clone(), planarity)
                .with_hidden_occluders(false)
                .pvs_with_stats(&cell)
                .0;
            for id in &with {
                prop_assert!(without.contains(id), "{:?}: {} only with hidden boxes", planarity, id);
            }
            for id in vis.iter().chain(&exact) {
                prop_assert!(with.contains(id), "{:?}: misses {} ({:?})", planarity, id, with);
            }
        }
    }
}

/// Rows of 10 m deep blocks along 12 m streets, some blocks missing, heights 3–40 m:
/// the blocks behind the first row are hidden kd-nodes, and hide what stands behind
/// them.
fn dense_city() -> impl Strategy<Value = (Vec<Bx>, ViewCell)> {
    let block =
        (0i32..12, 0i32..12, 0i32..3, 3u32..40, any::<bool>()).prop_map(|(i, j, k, h, wide)| {
            // Parts of a 10 m deep block, touching or overlapping their neighbours.
            let (x0, y0) = (i as f64 * 22.0 + k as f64 * 4.0, j as f64 * 22.0);
            let w = if wide { 10.0 } else { 6.0 };
            Bx {
                min: DVec3::new(x0, y0, 0.0),
                max: DVec3::new(x0 + w, y0 + 10.0, h as f64),
            }
        });
    (
        prop::collection::vec(block, 20..48),
        square_cell(260, 2..20),
    )
}
