//! The volumetric test and the walkable viewcells: 0 misses against the item-buffer
//! truth sampled in every viewcell's free space on the small levels (far from the
//! origin too, on and off the lattice), hand-checked culling, every floor point in a
//! viewcell, and a property test of the planar patches against exact segment casts.

use proptest::prelude::*;
use sightline_autocells::viewcells::Walker;
use sightline_autocells::volumetric::Patches;
use sightline_autocells::{testlevel, AutoCells, Options};
use sightline_core::check::{TruthOptions, TruthScene};
use sightline_geom::DVec3;
use sightline_scene::Scene;

fn build(scene: &Scene, h: f64) -> AutoCells {
    AutoCells::build(
        scene,
        &Options {
            smallest_hole: Some(h),
            full: false,
            ..Options::default()
        },
    )
    .expect("builds")
}

fn id(scene: &Scene, name: &str) -> u32 {
    scene
        .objects
        .iter()
        .position(|o| o.name.as_deref() == Some(name))
        .expect("named object") as u32
}

/// Every viewcell's PVS holds what the truth sees from its free voxels; returns the
/// viewcells (world boxes) and their PVS.
fn judged(scene: &Scene, auto: &AutoCells, eye: f64) -> Vec<(sightline_geom::ViewCell, Vec<u32>)> {
    let cells = auto.viewcells(&Walker {
        eye_height: eye,
        width: 8,
    });
    assert!(!cells.is_empty(), "a level with floors has viewcells");
    let vol = auto.volumetric();
    let truth = TruthScene::new(scene);
    let topts = TruthOptions {
        samples: 8,
        resolution_px: 64,
        targeted_rays_per_object: 16,
        seed: 5,
    };
    let mut out = Vec::new();
    for (i, b) in cells.iter().enumerate() {
        let pvs = auto.viewcell_pvs(&vol, b);
        if let Some(region) = auto.free_region_of(b, i as u32) {
            let t = truth.ground_truth_in(&region, &topts);
            let missed: Vec<u32> = t
                .visible
                .iter()
                .copied()
                .filter(|o| pvs.binary_search(o).is_err())
                .collect();
            assert!(missed.is_empty(), "viewcell {b:?} missed {missed:?}");
        }
        out.push((sightline_autocells::cells::world_box(&auto.voxels, b), pvs));
    }
    out
}

#[test]
fn two_rooms_viewcells_see_no_further_than_the_truth_allows() {
    for offset in [0.0, 1.0e5] {
        for h in [0.5, 0.45] {
            let scene = testlevel::two_rooms_and_a_door(offset);
            let auto = build(&scene, h);
            let cells = judged(&scene, &auto, 1.7);
            let o = DVec3::splat(offset);
            let crate_d = id(&scene, "crate-d");
            // A viewer standing in room A, away from the door, never sees crate-d
            // around two corners (on the lattice: walls are closed faces).
            if h == 0.5 {
                let eye = DVec3::new(-4.5, -2.0, 1.7) + o;
                let (_, pvs) = cells
                    .iter()
                    .find(|(c, _)| c.contains(eye))
                    .expect("the eye of a viewer in room A is in a viewcell");
                assert!(!pvs.contains(&crate_d), "h {h} offset {offset}: {pvs:?}");
                assert!(pvs.contains(&id(&scene, "crate-a")));
            }
            // Every floor point of the rooms, the eye 1.7 above it, is in a viewcell.
            for i in 0..40 {
                for j in 0..20 {
                    let p = DVec3::new(-5.9 + 0.3 * i as f64, -2.9 + 0.29 * j as f64, 1.7);
                    if p.x.abs() < 0.6 || p.y > 2.9 {
                        continue;
                    }
                    assert!(
                        cells.iter().any(|(c, _)| c.contains(p + o)),
                        "h {h}: no viewcell holds the eye at {p:?}"
                    );
                }
            }
        }
    }
}

#[test]
fn thin_and_paper_walls() {
    let scene = testlevel::thin_wall();
    let auto = build(&scene, 0.25);
    judged(&scene, &auto, 1.2);
    for x in [0.0, 0.1] {
        let scene = testlevel::paper_wall(x);
        let auto = build(&scene, 0.25);
        judged(&scene, &auto, 1.2);
    }
}

fn hits(a: DVec3, b: DVec3, t: &[DVec3; 3]) -> bool {
    // Segment a → b against the closed triangle (Möller–Trumbore, no culling).
    let d = b - a;
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 {
        return false;
    }
    let s = a - t[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t_hit = e2.dot(q) / det;
    u >= -1e-9 && v >= -1e-9 && u + v <= 1.0 + 1e-9 && (-1e-9..=1.0 + 1e-9).contains(&t_hit)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]
    /// A wall of any orientation (a quad of two triangles, a hole cut in it by a
    /// missing triangle pair or not): whenever the patches say it hides box `w` from
    /// box `v`, every sampled segment between them crosses one of its triangles.
    #[test]
    fn patches_hide_only_what_every_segment_crosses(
        yaw in -1.5f64..1.5, tilt in -0.6f64..0.6, half in 0.5f64..4.0,
        vx in -6.0f64..-0.2, vy in -3.0f64..3.0, vz in -3.0f64..3.0, vs in 0.05f64..2.0,
        wx in 0.2f64..6.0, wy in -3.0f64..3.0, wz in -3.0f64..3.0, ws in 0.05f64..2.0,
        hole in proptest::bool::ANY, seed in 0u64..1000,
    ) {
        let n = DVec3::new(yaw.cos() * tilt.cos(), yaw.sin() * tilt.cos(), tilt.sin());
        let u = DVec3::Z.cross(n).normalize();
        let v = n.cross(u);
        let q = |a: f64, b: f64| u * a + v * b;
        // A wall of 2 × 2 quads; `hole` leaves one quad out.
        let mut tris = Vec::new();
        for (i, j) in [(0, 0), (0, 1), (1, 0), (1, 1)] {
            if hole && (i, j) == (1, 1) {
                continue;
            }
            let (a0, b0) = (-half + i as f64 * half, -half + j as f64 * half);
            let (a1, b1) = (a0 + half, b0 + half);
            tris.push([q(a0, b0), q(a1, b0), q(a1, b1)]);
            tris.push([q(a0, b0), q(a1, b1), q(a0, b1)]);
        }
        let h = 0.25;
        let patches = Patches::new(&tris, h, DVec3::splat(-16.0), [128, 128, 128]);
        let vb = [DVec3::new(vx, vy, vz), DVec3::new(vx, vy, vz) + DVec3::splat(vs)];
        let wb = [DVec3::new(wx, wy, wz), DVec3::new(wx, wy, wz) + DVec3::splat(ws)];
        if patches.hidden(vb, wb) {
            let mut r = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let mut rnd = || {
                r = r.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                (r >> 11) as f64 / (1u64 << 53) as f64
            };
            for _ in 0..64 {
                let a = vb[0] + (vb[1] - vb[0]) * DVec3::new(rnd(), rnd(), rnd());
                let b = wb[0] + (wb[1] - wb[0]) * DVec3::new(rnd(), rnd(), rnd());
                prop_assert!(tris.iter().any(|t| hits(a, b, t)), "segment {a:?} → {b:?} passes");
            }
            // The corners too (the extreme segments).
            for i in 0..8 {
                for j in 0..8 {
                    let c = |b: [DVec3; 2], k: usize| DVec3::new(
                        if k & 1 == 0 { b[0].x } else { b[1].x },
                        if k & 2 == 0 { b[0].y } else { b[1].y },
                        if k & 4 == 0 { b[0].z } else { b[1].z });
                    prop_assert!(tris.iter().any(|t| hits(c(vb, i), c(wb, j), t)));
                }
            }
        }
    }
}

/// Two rooms on the lattice, joined by a door or not; the eye 1.7 above the floor.
fn rooms(door: bool) -> Scene {
    testlevel::lattice_level(
        0.5,
        [24, 10, 7],
        DVec3::new(-6.0, -3.0, 0.0),
        move |i, _j, k| {
            let x = -6.0 + 0.5 * i as f64 + 0.25;
            let z = 0.5 * k as f64 + 0.25;
            z < 3.0 && (x.abs() > 0.5 || (door && z < 2.0))
        },
        &[],
    )
}

#[test]
fn spawn_points_keep_every_reachable_floor_and_drop_sealed_rooms() {
    use sightline_autocells::viewcells::reachable;
    for door in [true, false] {
        let scene = rooms(door);
        let auto = build(&scene, 0.5);
        let cells = auto.viewcells(&Walker {
            eye_height: 1.7,
            width: 4,
        });
        let g = &auto.voxels.grid;
        let vox = |p: DVec3| ((p - g.origin) / g.size).to_array();
        let spawn = vox(DVec3::new(-4.0, -1.0, 0.1)).map(|x| x as usize);
        let kept = reachable(&auto.voxels, &auto.tris, &cells, &[spawn], 5);
        let world: Vec<_> = kept
            .iter()
            .map(|&c| sightline_autocells::cells::world_box(&auto.voxels, &cells[c]))
            .collect();
        for i in 0..40 {
            for j in 0..8 {
                let p = DVec3::new(-5.9 + 0.3 * i as f64, -2.9 + 0.29 * j as f64, 1.7);
                if p.x.abs() < 0.6 {
                    continue;
                }
                let in_kept = world.iter().any(|c| c.contains(p));
                if door || p.x < 0.0 {
                    assert!(
                        in_kept,
                        "door {door}: the eye at {p:?} is in no kept viewcell"
                    );
                } else {
                    assert!(!in_kept, "the sealed room's floor at {p:?} was kept");
                }
            }
        }
        assert_eq!(
            kept.len() == cells.len(),
            door,
            "{} of {}",
            kept.len(),
            cells.len()
        );
    }
}
