//! The voxelizer's promises on random triangle soups and closed boxes: every voxel a
//! triangle touches is surface, and no solid voxel is touched by any triangle.

use proptest::prelude::*;
use sightline_autocells::testlevel::closed_box;
use sightline_autocells::voxels::{touched, tri_box_overlap, voxelize, Grid, SOLID, SURFACE};
use sightline_geom::DVec3;

/// Triangles stay inside the grid's inner part: its border layer is solid by rule 3
/// (outside the scene's bounding box).
fn grid() -> Grid {
    Grid {
        origin: DVec3::splat(-1.25),
        size: 0.5,
        dims: [25, 25, 25],
    }
}

fn point() -> impl Strategy<Value = DVec3> {
    (-0.5..10.5f64, -0.5..10.5f64, -0.5..10.5f64).prop_map(|(x, y, z)| DVec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn surface_covers_triangles_and_solid_is_untouched(
        tris in prop::collection::vec((point(), point(), point()), 1..12),
        boxes in prop::collection::vec(((0.0..6.0f64, 0.0..6.0f64, 0.0..6.0f64), 0.6..4.0f64), 0..4),
    ) {
        let mut soup: Vec<[DVec3; 3]> = tris.iter().map(|&(a, b, c)| [a, b, c]).collect();
        for ((x, y, z), s) in &boxes {
            let lo = DVec3::new(*x, *y, *z);
            let m = closed_box(lo, lo + DVec3::splat(*s));
            soup.extend(m.triangles.iter().map(|t| m.triangle(t)));
        }
        let v = voxelize(grid(), &soup, 0.05);
        let mut buf = Vec::new();
        for t in &soup {
            touched(&v.grid, t, &mut buf);
            for &i in &buf {
                prop_assert_eq!(v.state[i], SURFACE);
            }
        }
        for (i, &s) in v.state.iter().enumerate() {
            if s == SOLID {
                let c = v.grid.center(v.grid.coords(i));
                for t in &soup {
                    prop_assert!(!tri_box_overlap(c, v.grid.size * 0.5, t));
                }
            }
        }
    }
}

#[test]
fn closed_box_interior_is_solid() {
    let m = closed_box(DVec3::splat(2.0), DVec3::splat(6.0));
    let soup: Vec<[DVec3; 3]> = m.triangles.iter().map(|t| m.triangle(t)).collect();
    let v = voxelize(grid(), &soup, 0.05);
    let c = v.grid.locate(DVec3::splat(4.1)).expect("in the grid");
    assert_eq!(v.state[v.grid.index(c[0], c[1], c[2])], SOLID);
    let o = v.grid.locate(DVec3::splat(0.0)).expect("in the grid");
    assert_ne!(v.state[v.grid.index(o[0], o[1], o[2])], SOLID);
    assert!(v.leak.is_none());
}

/// A room (faces towards its inside) with its +x wall missing, in the open: the
/// outside sees the walls' backs and reaches the room's inside, which sees fronts. The
/// leak is reported from inside the room to the void next to the grid's border.
#[test]
fn open_room_leaks_from_inside_to_the_void() {
    let m = closed_box(DVec3::splat(2.0), DVec3::splat(6.0));
    let soup: Vec<[DVec3; 3]> = m
        .triangles
        .iter()
        .map(|t| m.triangle(t))
        .filter(|t| t.iter().any(|p| p.x < 5.99))
        .map(|[a, b, c]| [a, c, b])
        .collect();
    let v = voxelize(grid(), &soup, 0.05);
    let leak = v.leak.expect("the open room leaks");
    let inside = DVec3::from_array(leak.inside);
    let void = DVec3::from_array(leak.border);
    assert!(inside.cmpgt(DVec3::splat(2.0)).all() && inside.cmplt(DVec3::splat(6.0)).all());
    assert!(!(void.cmpgt(DVec3::splat(1.5)).all() && void.cmplt(DVec3::splat(6.5)).all()));
    assert_eq!(leak.path.first(), Some(&leak.inside));
    assert_eq!(leak.path.last(), Some(&leak.border));
    for w in leak.path.windows(2) {
        let d = DVec3::from_array(w[1]) - DVec3::from_array(w[0]);
        assert!((d.length() - v.grid.size).abs() < 1e-9, "face neighbours");
    }
}

/// A random point of a closed face's inside is inside some triangle of the soup (so a
/// line through the face crosses that triangle): quads on lattice planes, split into
/// two triangles along either diagonal, with random triangles beside them.
mod closed_faces {
    use super::*;
    use sightline_autocells::faces::closed_faces;

    fn in_triangle(t: &[DVec3; 3], p: DVec3) -> bool {
        let n = (t[1] - t[0]).cross(t[2] - t[0]);
        if n.dot(p - t[0]).abs() > 1e-9 * n.length() {
            return false;
        }
        (0..3).all(|i| {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            (b - a).cross(p - a).dot(n) >= -1e-9 * n.length_squared()
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn a_closed_face_lies_inside_a_triangle(
            quads in prop::collection::vec((0usize..3, 2usize..20, 2usize..20, 2usize..20, 1usize..6, 1usize..6, any::<bool>()), 1..6),
            tris in prop::collection::vec((point(), point(), point()), 0..4),
            (u, w) in (0.0..1.0f64, 0.0..1.0f64),
        ) {
            let g = grid();
            let mut soup: Vec<[DVec3; 3]> = tris.iter().map(|&(a, b, c)| [a, b, c]).collect();
            for &(k, m, i, j, di, dj, diag) in &quads {
                let (a, c) = ((k + 1) % 3, (k + 2) % 3);
                let at = |x: usize, y: usize| {
                    let mut p = [0usize; 3];
                    p[k] = m;
                    p[a] = x;
                    p[c] = y;
                    g.voxel_min(p)
                };
                let q = [at(i, j), at(i + di, j), at(i + di, j + dj), at(i, j + dj)];
                if diag {
                    soup.push([q[0], q[1], q[2]]);
                    soup.push([q[0], q[2], q[3]]);
                } else {
                    soup.push([q[0], q[1], q[3]]);
                    soup.push([q[1], q[2], q[3]]);
                }
            }
            let closed = closed_faces(&g, &soup);
            let mut quad_faces = 0;
            for (v, &bits) in closed.iter().enumerate() {
                for k in 0..3 {
                    if bits & (1 << k) == 0 {
                        continue;
                    }
                    let (a, c) = ((k + 1) % 3, (k + 2) % 3);
                    let mut p = g.voxel_min(g.coords(v));
                    p[k] += g.size;
                    p[a] += u * g.size;
                    p[c] += w * g.size;
                    prop_assert!(soup.iter().any(|t| in_triangle(t, p)), "face {v}/{k} at {p:?}");
                }
                quad_faces += bits.count_ones() as usize;
            }
            // Every face of every quad closes (quads split either way are found).
            let largest = quads.iter().map(|&(_, _, _, _, di, dj, _)| di * dj).max().unwrap_or(0);
            prop_assert!(quad_faces >= largest);
        }
    }
}
