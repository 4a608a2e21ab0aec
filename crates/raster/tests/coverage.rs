//! Property tests of the three coverage rules against exact pixel–polygon areas:
//! inner ⊆ exact coverage ⊆ outer, standard in between, conservative depths, the inner
//! rule of a union, and the pyramid's rectangle query against brute force.

use proptest::prelude::*;
use sightline_raster::{Coverage, Framebuffer, ScreenVertex, NO_ID};

const W: u32 = 16;
const H: u32 = 16;

/// Clip a polygon (x, y, w) to the pixel square (Sutherland–Hodgman).
fn clip_to_pixel(poly: &[ScreenVertex], i: u32, j: u32) -> Vec<ScreenVertex> {
    let (x0, y0, x1, y1) = (i as f64, j as f64, i as f64 + 1.0, j as f64 + 1.0);
    let planes: [(f64, f64, f64); 4] = [
        (1.0, 0.0, -x0),
        (-1.0, 0.0, x1),
        (0.0, 1.0, -y0),
        (0.0, -1.0, y1),
    ];
    let mut cur = poly.to_vec();
    for (a, b, c) in planes {
        let f = |v: &ScreenVertex| a * v.x + b * v.y + c;
        let mut out = Vec::new();
        for k in 0..cur.len() {
            let p = cur[k];
            let q = cur[(k + 1) % cur.len()];
            let (fp, fq) = (f(&p), f(&q));
            if fp >= 0.0 {
                out.push(p);
            }
            if (fp >= 0.0) != (fq >= 0.0) {
                let t = fp / (fp - fq);
                out.push(ScreenVertex {
                    x: p.x + (q.x - p.x) * t,
                    y: p.y + (q.y - p.y) * t,
                    w: p.w + (q.w - p.w) * t,
                });
            }
        }
        cur = out;
        if cur.is_empty() {
            break;
        }
    }
    cur
}

fn area(poly: &[ScreenVertex]) -> f64 {
    let n = poly.len();
    if n < 3 {
        return 0.0;
    }
    let mut s = 0.0;
    for k in 0..n {
        let (p, q) = (poly[k], poly[(k + 1) % n]);
        s += p.x * q.y - q.x * p.y;
    }
    0.5 * s.abs()
}

fn point_inside_margin(poly: &[ScreenVertex], x: f64, y: f64) -> f64 {
    // Signed distance-like margin: min over edges of the (normalized) edge function,
    // positive inside for either orientation.
    let n = poly.len();
    let orient = {
        let mut s = 0.0;
        for k in 0..n {
            let (p, q) = (poly[k], poly[(k + 1) % n]);
            s += p.x * q.y - q.x * p.y;
        }
        s.signum()
    };
    let mut m = f64::INFINITY;
    for k in 0..n {
        let (p, q) = (poly[k], poly[(k + 1) % n]);
        let len = ((q.x - p.x).powi(2) + (q.y - p.y).powi(2))
            .sqrt()
            .max(1e-300);
        let e = ((q.x - p.x) * (y - p.y) - (q.y - p.y) * (x - p.x)) / len * orient;
        m = m.min(e);
    }
    m
}

fn draw(poly: &[ScreenVertex], c: Coverage) -> Framebuffer {
    let mut fb = Framebuffer::new(W, H);
    fb.draw_screen_polygon(poly, 1, c);
    fb
}

fn vertex() -> impl Strategy<Value = ScreenVertex> {
    (-3.0f64..19.0, -3.0f64..19.0, 0.05f64..1.0).prop_map(|(x, y, w)| ScreenVertex { x, y, w })
}

/// Snap some coordinates to the pixel grid to exercise exact-boundary cases.
fn vertex_snapped() -> impl Strategy<Value = ScreenVertex> {
    (
        -3i32..19,
        -3i32..19,
        0.05f64..1.0,
        any::<bool>(),
        0.0f64..1.0,
    )
        .prop_map(|(x, y, w, snap, f)| {
            let off = if snap { 0.0 } else { f };
            ScreenVertex {
                x: x as f64 + off,
                y: y as f64,
                w,
            }
        })
}

/// Exact depth range of the polygon within the pixel (w is affine: extremes at the
/// vertices of the clipped polygon).
fn depth_range(clipped: &[ScreenVertex]) -> (f64, f64) {
    let zs = clipped.iter().map(|v| 1.0 / v.w);
    zs.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), z| {
        (a.min(z), b.max(z))
    })
}

fn check_polygon(poly: &[ScreenVertex]) -> Result<(), TestCaseError> {
    let inner = draw(poly, Coverage::Inner);
    let standard = draw(poly, Coverage::Standard);
    let outer = draw(poly, Coverage::Outer);
    for j in 0..H {
        for i in 0..W {
            let clipped = clip_to_pixel(poly, i, j);
            let a = area(&clipped);
            let is_in = inner.id_at(i, j) != NO_ID;
            let is_std = standard.id_at(i, j) != NO_ID;
            let is_out = outer.id_at(i, j) != NO_ID;
            if is_in {
                prop_assert!(a >= 1.0 - 1e-7, "inner pixel ({i},{j}) only {a} covered");
                let (_, zmax) = depth_range(&clipped);
                prop_assert!(
                    inner.depth_at(i, j) as f64 >= zmax * (1.0 - 1e-9),
                    "inner depth {} < farthest {zmax}",
                    inner.depth_at(i, j)
                );
                prop_assert!(is_std, "inner pixel ({i},{j}) not standard");
            }
            if a > 1e-9 {
                prop_assert!(is_out, "pixel ({i},{j}) covered {a} but not outer");
                let (zmin, _) = depth_range(&clipped);
                prop_assert!(
                    outer.depth_at(i, j) as f64 <= zmin * (1.0 + 1e-9),
                    "outer depth {} > nearest {zmin}",
                    outer.depth_at(i, j)
                );
            }
            if is_std {
                prop_assert!(is_out, "standard pixel ({i},{j}) not outer");
            }
            let m = point_inside_margin(poly, i as f64 + 0.5, j as f64 + 0.5);
            if m > 1e-7 {
                prop_assert!(is_std, "centre of ({i},{j}) inside by {m} but not standard");
            }
            if m < -1e-7 {
                prop_assert!(!is_std, "centre of ({i},{j}) outside by {m} but standard");
            }
        }
    }
    Ok(())
}

fn non_degenerate(t: &[ScreenVertex]) -> bool {
    area(t) > 1e-3
}

/// Convex hull (monotone chain) of points, counter-clockwise.
fn hull(mut pts: Vec<ScreenVertex>) -> Vec<ScreenVertex> {
    pts.sort_by(|a, b| (a.x, a.y).partial_cmp(&(b.x, b.y)).unwrap());
    let cross = |o: &ScreenVertex, a: &ScreenVertex, b: &ScreenVertex| {
        (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
    };
    let mut lower: Vec<ScreenVertex> = Vec::new();
    for p in &pts {
        while lower.len() >= 2 && cross(&lower[lower.len() - 2], &lower[lower.len() - 1], p) <= 0.0
        {
            lower.pop();
        }
        lower.push(*p);
    }
    let mut upper: Vec<ScreenVertex> = Vec::new();
    for p in pts.iter().rev() {
        while upper.len() >= 2 && cross(&upper[upper.len() - 2], &upper[upper.len() - 1], p) <= 0.0
        {
            upper.pop();
        }
        upper.push(*p);
    }
    lower.pop();
    upper.pop();
    lower.extend(upper);
    lower
}

/// Give a hull's vertices w values from one plane, so the polygon is planar.
fn planar(mut poly: Vec<ScreenVertex>, a: f64, b: f64, c: f64) -> Vec<ScreenVertex> {
    for v in &mut poly {
        v.w = (a * v.x + b * v.y + c).max(0.01);
    }
    poly
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    #[test]
    fn triangle_rules_bracket_exact_coverage(t in prop::array::uniform3(vertex())) {
        prop_assume!(non_degenerate(&t));
        check_polygon(&t)?;
    }

    #[test]
    fn grid_aligned_triangles(t in prop::array::uniform3(vertex_snapped())) {
        prop_assume!(non_degenerate(&t));
        check_polygon(&t)?;
    }

    #[test]
    fn convex_polygons(pts in prop::collection::vec(vertex(), 3..9), a in -0.02f64..0.02, b in -0.02f64..0.02) {
        let h = planar(hull(pts), a, b, 1.0);
        prop_assume!(h.len() >= 3 && non_degenerate(&h));
        check_polygon(&h)?;
    }

    /// The inner rule of a union of interior-disjoint pieces (a convex polygon cut into
    /// a fan) covers only fully covered pixels, and at least what the pieces cover
    /// separately.
    #[test]
    fn union_inner_is_conservative_and_fuses(pts in prop::collection::vec(vertex(), 3..9), a in -0.02f64..0.02, b in -0.02f64..0.02) {
        let h = planar(hull(pts), a, b, 1.0);
        prop_assume!(h.len() >= 4 && non_degenerate(&h));
        let fan: Vec<Vec<ScreenVertex>> = (1..h.len() - 1).map(|k| vec![h[0], h[k], h[k + 1]]).collect();
        let refs: Vec<&[ScreenVertex]> = fan.iter().map(|f| f.as_slice()).collect();
        let mut union = Framebuffer::new(W, H);
        union.draw_screen_union(&refs, 1);
        let mut separate = Framebuffer::new(W, H);
        for f in &fan {
            separate.draw_screen_polygon(f, 1, Coverage::Inner);
        }
        for j in 0..H {
            for i in 0..W {
                let clipped = clip_to_pixel(&h, i, j);
                if union.id_at(i, j) != NO_ID {
                    prop_assert!(area(&clipped) >= 1.0 - 1e-7);
                    let (_, zmax) = depth_range(&clipped);
                    prop_assert!(union.depth_at(i, j) as f64 >= zmax * (1.0 - 1e-9));
                }
                if separate.id_at(i, j) != NO_ID {
                    prop_assert!(union.id_at(i, j) != NO_ID, "union lost ({i},{j})");
                }
            }
        }
    }

    /// The pyramid's rectangle query agrees with brute force.
    #[test]
    fn pyramid_rect_query(depths in prop::collection::vec(0.0f32..10.0, (W * H) as usize),
                          x0 in 0u32..W, y0 in 0u32..H, dx in 0u32..W, dy in 0u32..H, z in 0.0f32..12.0) {
        let mut fb = Framebuffer::new(W, H);
        fb.depth.copy_from_slice(&depths);
        let pyr = fb.pyramid();
        let (x1, y1) = ((x0 + dx).min(W - 1), (y0 + dy).min(H - 1));
        let brute = (y0..=y1).all(|j| (x0..=x1).all(|i| fb.depth_at(i, j) < z));
        prop_assert_eq!(pyr.rect_occluded(x0, y0, x1, y1, z), brute);
    }
}

/// Two quads sharing a vertical edge fuse exactly: their union covers what the whole
/// rectangle covers, while drawing them separately leaves a crack.
#[test]
fn union_of_quads_sharing_an_edge_has_no_crack() {
    let q = |x0: f64, x1: f64| {
        vec![
            ScreenVertex {
                x: x0,
                y: 2.3,
                w: 0.5,
            },
            ScreenVertex {
                x: x1,
                y: 2.3,
                w: 0.5,
            },
            ScreenVertex {
                x: x1,
                y: 12.6,
                w: 0.5,
            },
            ScreenVertex {
                x: x0,
                y: 12.6,
                w: 0.5,
            },
        ]
    };
    let (a, b, whole) = (q(1.2, 7.5), q(7.5, 13.9), q(1.2, 13.9));
    let mut union = Framebuffer::new(W, H);
    union.draw_screen_union(&[&a, &b], 1);
    let mut single = Framebuffer::new(W, H);
    single.draw_screen_polygon(&whole, 1, Coverage::Inner);
    let mut separate = Framebuffer::new(W, H);
    separate.draw_screen_polygon(&a, 1, Coverage::Inner);
    separate.draw_screen_polygon(&b, 1, Coverage::Inner);
    assert_eq!(union.ids, single.ids);
    let count = |fb: &Framebuffer| fb.ids.iter().filter(|&&i| i != NO_ID).count();
    assert_eq!(count(&single), 11 * 9);
    assert!(count(&separate) < count(&single));
}

/// Stacked pieces (a horizontal shared edge inside a pixel row) fuse too.
#[test]
fn union_of_stacked_quads_has_no_crack() {
    let q = |y0: f64, y1: f64| {
        vec![
            ScreenVertex {
                x: 2.0,
                y: y0,
                w: 0.5,
            },
            ScreenVertex {
                x: 10.0,
                y: y0,
                w: 0.5,
            },
            ScreenVertex {
                x: 10.0,
                y: y1,
                w: 0.5,
            },
            ScreenVertex {
                x: 2.0,
                y: y1,
                w: 0.5,
            },
        ]
    };
    let mut union = Framebuffer::new(W, H);
    union.draw_screen_union(&[&q(1.0, 5.5), &q(5.5, 9.0)], 1);
    let covered: Vec<bool> = (0..H).map(|j| union.id_at(5, j) != NO_ID).collect();
    assert_eq!(covered.iter().filter(|&&c| c).count(), 8);
    assert!(covered[5]);
}
