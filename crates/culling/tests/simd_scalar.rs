//! Property: the SIMD rasterizer path gives the scalar path's buffer bit for bit (masks
//! and both depth layers of every tile), at the best instruction set of this CPU and at
//! the target's baseline. Identical buffers answer every query identically, so the SIMD
//! path never claims more occlusion than the scalar one.

use fearless_simd::Level;
use glam::DVec3;
use proptest::prelude::*;
use sightline_culling::hzb::draw_occluders;
use sightline_culling::masked::{MaskedBuffer, RasterPath};
use sightline_culling::{CullScene, Frustum};
use sightline_raster::ScreenVertex;
use sightline_scene::{Object, Scene};

/// A convex polygon: `n` vertices at increasing angles around `(cx, cy)` with radii in
/// `[r/2, r]`, `w` affine over the screen (a planar face). `snap` rounds the vertices to
/// half pixels: edges on pixel borders and horizontal/vertical edges are the ties that
/// decide coverage.
fn polygon(
    (cx, cy, r): (f64, f64, f64),
    angles: &[(f64, f64)],
    (w0, gx, gy): (f64, f64, f64),
    snap: bool,
) -> Vec<ScreenVertex> {
    let mut a: Vec<(f64, f64)> = angles.to_vec();
    a.sort_by(|p, q| p.0.total_cmp(&q.0));
    a.iter()
        .map(|&(t, k)| {
            let (mut x, mut y) = (cx + r * k * t.cos(), cy + r * k * t.sin());
            if snap {
                x = (x * 2.0).round() / 2.0;
                y = (y * 2.0).round() / 2.0;
            }
            ScreenVertex {
                x,
                y,
                w: w0 + gx * (x - cx) + gy * (y - cy),
            }
        })
        .collect()
}

type PolyParams = ((f64, f64, f64), Vec<(f64, f64)>, (f64, f64, f64), bool);

fn poly_params() -> impl Strategy<Value = PolyParams> {
    (
        (-40.0..240.0f64, -30.0..130.0f64, 0.2..150.0f64),
        prop::collection::vec((0.0..std::f64::consts::TAU, 0.5..1.0f64), 3..7),
        (0.01..2.0f64, -0.004..0.004f64, -0.004..0.004f64),
        any::<bool>(),
    )
}

fn same_after_each(w: u32, h: u32, polys: &[PolyParams]) -> Result<(), TestCaseError> {
    let mut scalar = MaskedBuffer::with_path(w, h, RasterPath::Scalar);
    let mut best = MaskedBuffer::with_path(w, h, RasterPath::Simd);
    let mut base = MaskedBuffer::with_simd_level(w, h, Level::baseline());
    for (k, (c, angles, plane, snap)) in polys.iter().enumerate() {
        let p = polygon(*c, angles, *plane, *snap);
        scalar.draw_polygon(&p);
        best.draw_polygon(&p);
        base.draw_polygon(&p);
        prop_assert!(
            scalar.same_tiles(&best),
            "best SIMD level differs after polygon {k}: {p:?}"
        );
        prop_assert!(
            scalar.same_tiles(&base),
            "baseline SIMD differs after polygon {k}: {p:?}"
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]
    #[test]
    fn simd_and_scalar_buffers_are_identical(
        polys in prop::collection::vec(poly_params(), 1..24),
        w in 1u32..230, h in 1u32..110,
    ) {
        same_after_each(w, h, &polys)?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 24, ..ProptestConfig::default() })]
    /// The same on whole frames of random box cities, drawn by `hzb`'s occluder pass.
    #[test]
    fn simd_and_scalar_frames_are_identical(
        boxes in prop::collection::vec((-60.0..60.0f64, -60.0..60.0f64, 1.0..25.0f64, 1.0..25.0f64, 1.0..40.0f64), 1..30),
        ex in -70.0..70.0f64, ey in -70.0..70.0f64, ez in 0.5..30.0f64,
        az in 0.0..std::f64::consts::TAU, pitch in -0.6..0.6f64, fov in 20.0..120.0f64,
    ) {
        let scene = Scene::from_objects(
            boxes.iter().map(|&(x, y, w, d, h)| Object::rect_block(x, y, x + w, y + d, h)).collect(),
        );
        let dir = DVec3::new(az.cos() * pitch.cos(), az.sin() * pitch.cos(), pitch.sin());
        let f = Frustum::new(DVec3::new(ex, ey, ez), dir, fov, 237, 131).unwrap();
        let cs = CullScene::new(&scene);
        let (a, ta) = draw_occluders(&cs, &f, None, false, RasterPath::Scalar);
        let (b, tb) = draw_occluders(&cs, &f, None, false, RasterPath::Simd);
        prop_assert_eq!(ta, tb);
        prop_assert!(a.same_tiles(&b));
    }
}
