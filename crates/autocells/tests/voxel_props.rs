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
