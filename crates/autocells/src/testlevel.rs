//! Small generated levels for tests and examples, built as game levels are: free space
//! on a lattice, its boundary faces facing into the free space, grouped by material
//! (floor, ceiling, walls: each spans the level), plus closed props.

use sightline_geom::DVec3;
use sightline_scene::{Mesh, Object, Scene};

/// Faces between free and non-free lattice cells of side `unit`, facing the free
/// cell; `free(i, j, k)` for `i, j, k` in `0..dims`; the lattice's corner at `origin`.
pub fn lattice_level(
    unit: f64,
    dims: [i32; 3],
    origin: DVec3,
    free: impl Fn(i32, i32, i32) -> bool,
    props: &[(&str, DVec3, DVec3)],
) -> Scene {
    let inside = |i: i32, j: i32, k: i32| {
        i >= 0 && j >= 0 && k >= 0 && i < dims[0] && j < dims[1] && k < dims[2] && free(i, j, k)
    };
    // floor, ceiling, walls
    let mut meshes = [Mesh::default(), Mesh::default(), Mesh::default()];
    for k in 0..dims[2] {
        for j in 0..dims[1] {
            for i in 0..dims[0] {
                if !inside(i, j, k) {
                    continue;
                }
                for axis in 0..3 {
                    for dir in [-1i32, 1] {
                        let mut n = [i, j, k];
                        n[axis] += dir;
                        if inside(n[0], n[1], n[2]) {
                            continue;
                        }
                        // The face of cell (i, j, k) on side `dir` of `axis`; normal -dir.
                        let mut lo = [i as f64, j as f64, k as f64];
                        if dir > 0 {
                            lo[axis] += 1.0;
                        }
                        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
                        let corner = |da: f64, db: f64| {
                            let mut p = lo;
                            p[a] += da;
                            p[b] += db;
                            origin + DVec3::from_array(p) * unit
                        };
                        let q = [
                            corner(0.0, 0.0),
                            corner(1.0, 0.0),
                            corner(1.0, 1.0),
                            corner(0.0, 1.0),
                        ];
                        // `q` is counter-clockwise seen from +axis (e_a × e_b = e_axis);
                        // the face must look into the free cell, towards -dir.
                        let q = if dir < 0 { q } else { [q[0], q[3], q[2], q[1]] };
                        let m = match (axis, dir) {
                            (2, -1) => 0,
                            (2, 1) => 1,
                            _ => 2,
                        };
                        push_quad(&mut meshes[m], q);
                    }
                }
            }
        }
    }
    let mut objects: Vec<Object> = ["floor", "ceiling", "walls"]
        .into_iter()
        .zip(meshes)
        .filter(|(_, m)| !m.triangles.is_empty())
        .map(|(name, m)| Object::mesh(Some(name.into()), m, vec![], vec![]))
        .collect();
    for (name, lo, hi) in props {
        objects.push(Object::mesh(
            Some((*name).into()),
            closed_box(*lo + origin, *hi + origin),
            vec![],
            vec![],
        ));
    }
    Scene::from_objects(objects)
}

fn push_quad(m: &mut Mesh, q: [DVec3; 4]) {
    let b = m.vertices.len() as u32;
    m.vertices.extend(q);
    m.triangles.push([b, b + 1, b + 2]);
    m.triangles.push([b, b + 2, b + 3]);
}

/// A closed box with outward faces.
pub fn closed_box(lo: DVec3, hi: DVec3) -> Mesh {
    let mut m = Mesh::default();
    for axis in 0..3 {
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        for side in [0, 1] {
            let corner = |ua: usize, ub: usize| {
                let mut p = lo;
                p[axis] = if side == 1 { hi[axis] } else { lo[axis] };
                p[a] = if ua == 1 { hi[a] } else { lo[a] };
                p[b] = if ub == 1 { hi[b] } else { lo[b] };
                p
            };
            let q = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
            let q = if side == 1 {
                q
            } else {
                [q[0], q[3], q[2], q[1]]
            };
            push_quad(&mut m, q);
        }
    }
    m
}

/// Rooms A (west), B (east) through a door in the wall at x = 0; B opens north into a
/// corridor that turns west above A into room D, which A cannot see. Lattice of 0.5 m,
/// ceilings at 3 m; `offset` moves the whole level (coordinates far from the origin).
/// Objects: floor, ceiling, walls (material slots spanning the level), then props
/// `crate-a` (in A), `crate-b` (in B), `crate-d` (at D's west end).
pub fn two_rooms_and_a_door(offset: f64) -> Scene {
    let origin = DVec3::new(-6.0, -3.0, 0.0) + DVec3::splat(offset);
    // Lattice indices: x = -6 + 0.5 i, y = -3 + 0.5 j, z = 0.5 k.
    let free = |i: i32, j: i32, k: i32| {
        let x = -6.0 + 0.5 * i as f64 + 0.25;
        let y = -3.0 + 0.5 * j as f64 + 0.25;
        let z = 0.5 * k as f64 + 0.25;
        if z > 3.0 {
            return false;
        }
        let room_a = x < -0.5 && y < 3.0;
        let room_b = x > 0.5 && y < 3.0;
        let door1 = x.abs() < 0.5 && y.abs() < 0.5 && z < 2.0;
        let door2 = (4.0..5.0).contains(&x) && (3.0..3.5).contains(&y) && z < 2.0;
        let corridor = (4.0..5.0).contains(&x) && (3.5..6.0).contains(&y);
        let room_d = (5.0..6.0).contains(&y) && x < 5.0;
        room_a || room_b || door1 || door2 || corridor || room_d
    };
    let o = DVec3::new(-6.0, -3.0, 0.0);
    let prop = |lo: [f64; 3], hi: [f64; 3]| (DVec3::from_array(lo) - o, DVec3::from_array(hi) - o);
    let (a0, a1) = prop([-4.0, -1.0, 0.0], [-3.5, -0.5, 0.5]);
    let (b0, b1) = prop([3.0, 0.0, 0.0], [3.5, 0.5, 0.5]);
    let (d0, d1) = prop([-5.0, 5.25, 0.0], [-4.5, 5.75, 0.5]);
    lattice_level(
        0.5,
        [24, 18, 7],
        origin,
        free,
        &[
            ("crate-a", a0, a1),
            ("crate-b", b0, b1),
            ("crate-d", d0, d1),
        ],
    )
}

/// One room with a thin closed wall (0.1 thick, outward faces) across its middle,
/// leaving a gap at the top: the wall is thinner than twice the smallest hole and
/// must not occlude; a crate on each side.
pub fn thin_wall() -> Scene {
    let origin = DVec3::new(-4.0, -2.0, 0.0);
    let mut scene = lattice_level(
        0.5,
        [16, 8, 6],
        origin,
        |_, _, _| true,
        &[
            (
                "crate-w",
                DVec3::new(0.5, 1.5, 0.0),
                DVec3::new(1.0, 2.0, 0.5),
            ),
            (
                "crate-e",
                DVec3::new(7.0, 1.5, 0.0),
                DVec3::new(7.5, 2.0, 0.5),
            ),
        ],
    );
    scene.objects.push(Object::mesh(
        Some("thin-wall".into()),
        closed_box(DVec3::new(-0.05, -2.0, 0.0), DVec3::new(0.05, 2.0, 2.5)),
        vec![],
        vec![],
    ));
    Scene::from_objects(scene.objects)
}

/// One room (16 × 8 × 6 voxels of 0.5) split in two by a wall of zero thickness: one
/// quad at x = `wall_x` (two triangles), floor to ceiling, wall to wall; a crate on
/// each side. On the lattice (`wall_x` a multiple of 0.5) the wall closes the voxel
/// faces it lies in; off it, it closes nothing. (Crates are placed from the room's
/// corner, as in [`lattice_level`]: crate-w at x = −3, crate-e at x = 2.5.)
pub fn paper_wall(wall_x: f64) -> Scene {
    let mut scene = lattice_level(
        0.5,
        [16, 8, 6],
        DVec3::new(-4.0, -2.0, 0.0),
        |_, _, _| true,
        &[
            (
                "crate-w",
                DVec3::new(1.0, 3.0, 0.0),
                DVec3::new(1.5, 3.5, 0.5),
            ),
            (
                "crate-e",
                DVec3::new(6.5, 3.0, 0.0),
                DVec3::new(7.0, 3.5, 0.5),
            ),
        ],
    );
    let mut wall = Mesh::default();
    push_quad(
        &mut wall,
        [
            DVec3::new(wall_x, -2.0, 0.0),
            DVec3::new(wall_x, 2.0, 0.0),
            DVec3::new(wall_x, 2.0, 3.0),
            DVec3::new(wall_x, -2.0, 3.0),
        ],
    );
    scene.objects.push(Object::mesh(
        Some("paper-wall".into()),
        wall,
        vec![],
        vec![],
    ));
    Scene::from_objects(scene.objects)
}
