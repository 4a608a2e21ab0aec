//! Occluder reprojection and the occlusion sweep (Durand et al. 2000, §5, App. B).
//!
//! The cell is swept by parallel planes leaving it. On each plane the *occlusion map*
//! (black = in the umbra of the occluders in front of the plane) is
//! * the previous plane's map **re-projected**: the black pixels of a plane behind the
//!   occluders lie in their umbra and form one planar equivalent occluder (App. B,
//!   Property 3); its umbra on the next plane is the convolution of the map by the
//!   inverse image of the cell, keeping only fully black pixels (§5.1). The paper
//!   convolves with the inverse image of the *equivalent planar cell* `E` (the
//!   rectangle on the cell's far-face plane crossed by every ray from the cell to the
//!   next plane's rectangle, Fig. 11c; [`equivalent_cell`]) so that one kernel serves
//!   the whole plane. We evaluate per pixel (a summed-area table answers "all black?"
//!   for a rectangle in O(1)) with the cell's own near and far faces, which `E`
//!   contains: pixel `Q` is black iff the bounding rectangle of the cell's view from
//!   `Q` on the old plane touches only black pixels ([`reproject`]). For a deep cell
//!   near the planes `E` is several times the cell, and so was the erosion per plane;
//! * plus the ground: plane points below z = 0 are in its umbra (no sight line meets the ground below z = 0,
//!   [`ground_black`]);
//! * plus the Projections of the occluders lying between the two planes, including
//!   every mesh triangle (the leaves: each alone hides almost nothing, but their
//!   Projections fuse in the union-aware coverage and then in the re-projected map);
//! * plus the slices of the prisms cut by the plane (§3.3).
//!
//! Planes are spaced by `ΔD = D(K−1)P/(CN)` (§5.2: `D` distance from the cell's far
//! face, `C` the cell's cross-section — the size of the kernel's source, as above —
//! `P` the plane's size, `N` the resolution, `K = 5` the kernel in pixels) from
//! `sweep_start_m` beyond the cell (or just behind the nearest occluder); the sweep
//! stops after the requested number of planes (denser near the cell, where occlusion
//! varies fastest). When the requested planes would stop short of `sweep_reach_m`
//! the kernel `K` is enlarged until they reach it ([`plane_positions`]): leaves fuse
//! only on planes near them, and with `K = 5` a few planes all crowd near the first.
//! Leaves outside a direction's extended frustum are left to the other directions.
//! Occludees behind a plane are hidden when their Projection (supporting lines,
//! §3.1) covers only black pixels: black pixels have depth ≤ 0 by construction.
//! Occludees between the cell and a plane use the improved Projection of §4 against
//! the plane's *depth* map: a black pixel keeps the depth of what blackened it — an
//! occluder's Projection its farthest depth, a re-projected pixel the previous
//! plane's (the equivalent occluder is planar, Property 1 holds behind it), a slice
//! or the ground 0 (no use for an occludee in front of the plane) — and the occludee
//! must lie behind all of them.

use super::depth_map::{
    depth_down, depth_up, pixel_range, CoverageBuilder, DepthMap, OcclusionMap,
};
use super::planes::{Direction, LocalBox, Plane};
use super::projection::{extended_projection, split_at, FACE_CLEARANCE_M};
use super::{occludee::occludee_projection, projection_touches_nothing, ExtProj};
use sightline_geom::{Aabb3, DVec2, DVec3, ViewCell};

/// How far beyond the cell the sweep reaches at most (m).
pub(crate) const MAX_REACH_M: f64 = 400.0;

/// One plane of the sweep with its occlusion map.
pub struct SweepPlane {
    pub plane: Plane,
    pub cell: LocalBox,
    pub umbra: OcclusionMap,
    /// Per black pixel, the extended depth of what makes it black (+∞ elsewhere),
    /// with its max pyramid, for the improved Projection of occludees in front.
    pub depth: DepthMap,
}

/// The sweep planes of all six directions of one cell.
pub struct Sweep {
    pub planes: Vec<SweepPlane>,
}

struct LocalOccluder {
    vertices: Vec<DVec3>,
    near: f64,
    far: f64,
    /// Extent in u and v.
    ext: DVec2,
    /// Index of a prism piece (sliced), or None for a triangle.
    piece: Option<u32>,
}

impl Sweep {
    pub(crate) fn empty() -> Self {
        Sweep { planes: vec![] }
    }

    /// Whether an occludee box is hidden on some sweep plane: behind the plane with
    /// its Projection (supporting lines) on black pixels, or — with `improved` —
    /// between the cell and the plane with its improved Projection (§4) on black
    /// pixels whose depth is below its own.
    pub fn hides(&self, b: &Aabb3, improved: bool) -> bool {
        self.planes.iter().any(|sp| {
            let occ = sp.plane.dir.box_to_local(b.min, b.max);
            let in_front = occ.max.x <= sp.plane.x;
            if !(occ.min.x > sp.plane.x || (improved && in_front)) {
                return false;
            }
            let Some((rect, depth)) = occludee_projection(&sp.cell, &occ, sp.plane.x, improved)
            else {
                return false;
            };
            let (lo, hi) = (sp.plane.to_px(rect.min), sp.plane.to_px(rect.max));
            let Some(r) = pixel_range(lo, hi, sp.umbra.n) else {
                return false;
            };
            if occ.min.x > sp.plane.x {
                sp.umbra.all_black(r)
            } else {
                sp.depth
                    .all_below(r[0], r[1], r[2], r[3], depth_down(depth))
            }
        })
    }

    /// Whether the Projection of the box meets no black pixel on any sweep plane
    /// (§6.1 "fully visible"; see [`super::PlaneMap::touches_nothing`]).
    pub(crate) fn touches_nothing(&self, b: &Aabb3, improved: bool) -> bool {
        self.planes.iter().all(|sp| {
            projection_touches_nothing(&sp.plane, &sp.cell, sp.umbra.n, b, improved, |r| {
                sp.umbra.any_black(r)
            })
        })
    }

    /// Run the sweep in the six directions of `cell`, with the occluders (prisms and
    /// leaves) made of some object of `candidates` (sorted ids; `None` = all: the
    /// others are hidden from a parent cell, §6.1).
    pub fn run(ext: &ExtProj, cell: &ViewCell, candidates: Option<&[u32]>) -> Sweep {
        let ids = ext.occluders.relevant_among(&cell.aabb(), candidates);
        let reach = cell.aabb();
        let reach = Aabb3::new(
            reach.min - DVec3::splat(MAX_REACH_M),
            reach.max + DVec3::splat(MAX_REACH_M),
        );
        let tri_ids = ext.occluders.triangles_in(&reach, candidates);
        let mut planes = Vec::new();
        for dir in Direction::ALL {
            planes.extend(sweep_direction(ext, cell, dir, &ids, &tri_ids));
        }
        Sweep { planes }
    }
}

/// Depths (local `w`) of at most `k` sweep planes from `x0`, spaced as in §5.2 with
/// kernel `kernel` (pixels), not beyond `x1`.
pub(crate) fn spaced_positions(
    ext: &ExtProj,
    lc: &LocalBox,
    x0: f64,
    x1: f64,
    k: usize,
    kernel: usize,
) -> Vec<f64> {
    if k == 0 || !(x1 > x0) {
        return vec![];
    }
    let n = ext.params.resolution_px as f64;
    let kk = kernel.max(2) as f64;
    // The kernel of [`reproject`] is the inverse image of the cell's own faces: its
    // size on the plane is about C·ΔD/D with C the cell's cross-section.
    let c = (lc.max.y - lc.min.y).max(lc.max.z - lc.min.z).max(1e-3);
    let step = |x: f64| -> f64 {
        let plane = Plane::new(Direction::PosX, lc, x, 1, ext.params.extension);
        let p = plane.rect.size().max_element();
        let d = x - lc.max.x;
        d * (kk - 1.0) * p / (c * n)
    };
    // The paper's spacing from the first plane on; the sweep stops after k planes
    // (occludees beyond the last plane are tested against its map).
    let mut v = vec![x0];
    while v.len() < k {
        let x = v[v.len() - 1];
        let next = x + step(x).max(1e-3);
        if next > x1 {
            break;
        }
        v.push(next);
    }
    v
}

/// Largest kernel (pixels) [`plane_positions`] grows to.
pub(crate) const MAX_KERNEL_PX: usize = 64;

/// Depths of the `k` sweep planes of a direction: the §5.2 spacing with the kernel
/// `K = kernel_px`, or — when those `k` planes would stop short of
/// `sweep_reach_m` beyond the cell (and of `x1`) — with the smallest larger `K`
/// whose planes reach it. The spacing grows as the square of the distance, so with
/// `K = 5` a few planes all crowd within a metre or two of the first one (five
/// planes from 2 m span 2–3.5 m for a 0.5 m cell at 512 px), where the leaves in
/// front have barely begun to fuse, and wider cells (smaller steps) fare worse.
pub(crate) fn plane_positions(
    ext: &ExtProj,
    lc: &LocalBox,
    x0: f64,
    x1: f64,
    k: usize,
) -> Vec<f64> {
    let target = x1.min(lc.max.x + ext.params.sweep_reach_m);
    let mut kernel = ext.params.kernel_px.max(2);
    loop {
        let v = spaced_positions(ext, lc, x0, x1, k, kernel);
        let reached = v.last().is_none_or(|&l| l >= target) || v.len() < k;
        if reached || kernel >= MAX_KERNEL_PX {
            return v;
        }
        kernel += 1;
    }
}

/// The equivalent planar cell of §5.1 on the cell's far-face plane `w = cw1`: every
/// ray from the cell to the plane's rectangle crosses it. The tests check the
/// re-projection kernel against it.
#[cfg(test)]
fn equivalent_cell(lc: &LocalBox, plane: &Plane) -> sightline_geom::Aabb2 {
    let t = (lc.max.x - lc.min.x) / (plane.x - lc.min.x);
    let (r0, r1) = (plane.rect.min, plane.rect.max);
    let c0 = DVec2::new(lc.min.y, lc.min.z);
    let c1 = DVec2::new(lc.max.y, lc.max.z);
    sightline_geom::Aabb2::new(
        c0.min(c0 * (1.0 - t) + r0 * t),
        c1.max(c1 * (1.0 - t) + r1 * t),
    )
}

/// Re-project the occlusion map of `from` onto `to` (§5.1): pixel `Q` of `to` is black
/// iff every point of `from` through which a sight line from the cell reaches `Q` is
/// black (then each such line is blocked before `from`, black points being in the
/// umbra). Those points are the view of the cell from `Q` on `from`, inside the
/// bounding rectangle of the views of the cell's corners. For a corner `e` the view
/// of `e` through `Q` is `t·Q + (1−t)·e` with `t = (x₁ − e_w)/(x₂ − e_w)`, affine in
/// `Q`, so over the pixel and the corners it spans the rectangles `t·pixel + (1−t)·face`
/// for the near and the far face — the inverse image of the cell, conservatively
/// rasterized (over-estimated to whole pixels), as the convolution kernel of §5.1.
/// It is the paper's kernel with the cell itself in place of its planar equivalent
/// `E` ([`equivalent_cell`]), which contains it: the paper needs one kernel for the
/// whole plane (a convolution on graphics hardware); evaluated per pixel (a summed-
/// area table answers "all black?" for a rectangle in O(1)) the cell's own faces give
/// a kernel several times smaller for a deep cell near the plane, and still every
/// sight line from the cell to the pixel passes through it.
pub(crate) fn reproject(lc: &LocalBox, from: &Plane, map: &OcclusionMap, to: &Plane) -> Vec<bool> {
    let n = to.n;
    let mut out = vec![false; n * n];
    if map.count() == 0 {
        return out;
    }
    let (face0, face1) = (
        DVec2::new(lc.min.y, lc.min.z),
        DVec2::new(lc.max.y, lc.max.z),
    );
    let t_of = |ew: f64| (from.x - ew) / (to.x - ew);
    let ts = [t_of(lc.min.x), t_of(lc.max.x)];
    let ps = to.pixel_size();
    for j in 0..n {
        for i in 0..n {
            let q0 = to.rect.min + DVec2::new(i as f64, j as f64) * ps;
            let q1 = q0 + ps;
            let mut lo = DVec2::splat(f64::INFINITY);
            let mut hi = DVec2::splat(f64::NEG_INFINITY);
            for &t in &ts {
                lo = lo.min(q0 * t + face0 * (1.0 - t));
                hi = hi.max(q1 * t + face1 * (1.0 - t));
            }
            let (plo, phi) = (from.to_px(lo), from.to_px(hi));
            if let Some(r) = pixel_range(plo, phi, map.n) {
                out[j * n + i] = map.all_black(r);
            }
        }
    }
    out
}

fn sweep_direction(
    ext: &ExtProj,
    cell: &ViewCell,
    dir: Direction,
    ids: &[u32],
    tri_ids: &[u32],
) -> Vec<SweepPlane> {
    let lc = dir.box_to_local(cell.min, cell.max);
    let w_min = lc.max.x + FACE_CLEARANCE_M;
    let mut occ: Vec<LocalOccluder> = Vec::new();
    let mut push = |vertices: Vec<DVec3>, piece: Option<u32>| {
        if vertices.len() < 3 {
            return;
        }
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for p in &vertices {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        if lo.x - lc.max.x > MAX_REACH_M {
            return;
        }
        occ.push(LocalOccluder {
            vertices,
            near: lo.x,
            far: hi.x,
            ext: DVec2::new(hi.y - lo.y, hi.z - lo.z),
            piece,
        });
    };
    for p in ext.local_pieces(cell, dir, ids) {
        push(p.vertices, Some(p.index));
    }
    for &t in tri_ids {
        let tri = &ext.occluders.triangles[t as usize];
        let lb = dir.box_to_local(tri.bounds.min, tri.bounds.max);
        // Leaves outside the direction's extended frustum project outside its planes
        // (leaving an occluder out is always conservative).
        if lb.max.x <= w_min || !super::in_frustum(&lc, &lb, ext.params.extension) {
            continue;
        }
        push(tri.occluder.local_vertices(dir, w_min), None);
    }
    if occ.is_empty() {
        return vec![];
    }
    let mut fars: Vec<f64> = occ.iter().map(|o| o.far).collect();
    fars.sort_by(f64::total_cmp);
    let x0 = (fars[0] + 1e-3).max(lc.max.x + ext.params.sweep_start_m.max(FACE_CLEARANCE_M));
    let x1 = fars[fars.len() - 1] + 1e-3;
    let xs = plane_positions(ext, &lc, x0, x1.max(x0 + 1.0), ext.params.sweep_planes);
    let n = ext.params.resolution_px;
    let cell_size = DVec2::new(lc.max.y - lc.min.y, lc.max.z - lc.min.z);
    let mut out: Vec<SweepPlane> = Vec::with_capacity(xs.len());
    for &x in &xs {
        let plane = Plane::new(dir, &lc, x, n, ext.params.extension);
        let mut b = CoverageBuilder::new(n);
        for o in &occ {
            // Every occluder in front of the plane is projected unless its Projection
            // is provably void (most leaves far in front of it).
            if o.far <= x && !void_projection(o, &lc, cell_size, x) {
                if let Some((poly, d)) = extended_projection(&o.vertices, &lc, x) {
                    let px: Vec<DVec2> = poly.iter().map(|q| plane.to_px(*q)).collect();
                    b.add_convex(&px, depth_up(d).min(0.0));
                }
            } else if o.near < x && x < o.far {
                // An occluder crossing the plane: its part in front (a subset, on one
                // side of the plane, see `projection::plane_safe_projections`) lies against the
                // plane, where Projections are largest — the leaves that fuse best on
                // this plane. Every sight line to its Projection is blocked at w ≤ x.
                let (front, _) = split_at(&o.vertices, x);
                if let Some((poly, _)) = extended_projection(&front, &lc, x) {
                    let px: Vec<DVec2> = poly.iter().map(|q| plane.to_px(*q)).collect();
                    b.add_convex(&px, 0.0);
                }
            }
            if let Some(pi) = o.piece {
                if o.near < x && x < o.far {
                    if let Some(s) = ext.occluders.pieces[pi as usize].occluder.slice(dir, x) {
                        let px: Vec<DVec2> = s.iter().map(|q| plane.to_px(*q)).collect();
                        b.add_convex(&px, 0.0);
                    }
                }
            }
        }
        let drawn = b.finish();
        let (mut black, prev_depth) = match out.last() {
            Some(prev) => (
                reproject(&lc, &prev.plane, &prev.umbra, &plane),
                depth_up(prev.plane.x - x),
            ),
            None => (vec![false; n * n], 0.0),
        };
        let mut depth: Vec<f32> = black
            .iter()
            .map(|&b| if b { prev_depth } else { f32::INFINITY })
            .collect();
        for j in 0..n {
            for i in 0..n {
                let d = drawn.at(i, j);
                if d.is_finite() {
                    black[j * n + i] = true;
                    depth[j * n + i] = depth[j * n + i].min(d);
                }
            }
        }
        let mut ground = vec![false; n * n];
        ground_black(&plane, &mut ground);
        for (k, g) in ground.iter().enumerate() {
            if *g {
                black[k] = true;
                depth[k] = depth[k].min(0.0);
            }
        }
        out.push(SweepPlane {
            plane,
            cell: lc,
            umbra: OcclusionMap::new(n, black),
            depth: DepthMap::new(n, depth),
        });
    }
    out.retain(|p| p.umbra.count() > 0);
    out
}

/// The ground is opaque (no sight line meets the ground below z = 0) and the
/// cell lies above it, so every sight line from the cell to a plane point below the
/// ground meets the ground first: such pixels are in the umbra. For the horizontal
/// directions these are the rows whose whole extent lies below z = 0 (`v` is z); for
/// `-z`, a plane at or below the ground is entirely black.
pub(crate) fn ground_black(plane: &Plane, black: &mut [bool]) {
    let n = plane.n;
    match plane.dir {
        Direction::PosZ => {}
        Direction::NegZ => {
            // Local w = −z: the plane is at z = −x.
            if -plane.x <= 0.0 {
                black.iter_mut().for_each(|b| *b = true);
            }
        }
        _ => {
            for j in 0..n {
                if plane.from_px(DVec2::new(0.0, (j + 1) as f64)).y <= 0.0 {
                    black[j * n..(j + 1) * n].iter_mut().for_each(|b| *b = true);
                } else {
                    break;
                }
            }
        }
    }
}

/// A cheap proof that an occluder's Projection on `w = x` is void: its views from two
/// cell corners are shifted by more than its projected width, so they do not overlap
/// (skipping an occluder is always conservative). A Projection thinner than a pixel is
/// not skipped: the union-aware coverage fuses it with its neighbours.
fn void_projection(o: &LocalOccluder, lc: &LocalBox, cell: DVec2, x: f64) -> bool {
    let near = (o.near - lc.max.x).max(1e-9);
    let scale = (x - lc.min.x) / near; // largest magnification of a view
    let width = o.ext * scale;
    let shift = cell * ((x - o.far) / (o.far - lc.min.x)).max(0.0);
    width.x <= shift.x || width.y <= shift.y
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Five planes of the K = 5 spacing from 2 m crowd within 2–3.5 m of a 0.5 m
    /// cell; the kernel grows until they reach `sweep_reach_m`. Fifteen planes
    /// already reach it with K = 5 and are left as they are.
    #[test]
    fn few_planes_reach_as_far_as_asked() {
        use sightline_scene::{Object, Scene};
        let scene = std::sync::Arc::new(Scene::from_objects(vec![Object::rect_block(
            10.0, 10.0, 12.0, 12.0, 5.0,
        )]));
        let params = super::super::Params {
            sweep: true,
            resolution_px: 512,
            ..super::super::Params::default()
        };
        let ext = ExtProj::new(scene, params);
        let lc = Direction::PosX.box_to_local(DVec3::ZERO, DVec3::new(0.5, 0.5, 0.5));
        let (x0, x1) = (lc.max.x + 2.0, lc.max.x + 300.0);
        let paper = spaced_positions(&ext, &lc, x0, x1, 5, 5);
        assert_eq!(paper.len(), 5);
        assert!(paper[4] - lc.max.x < 4.0, "{paper:?}");
        let ours = plane_positions(&ext, &lc, x0, x1, 5);
        assert_eq!(ours.len(), 5);
        assert!(ours[4] - lc.max.x >= ext.params.sweep_reach_m, "{ours:?}");
        assert!(ours.windows(2).all(|w| w[1] > w[0]));
        let fifteen = plane_positions(&ext, &lc, x0, x1, 15);
        assert_eq!(fifteen, spaced_positions(&ext, &lc, x0, x1, 15, 5));
        // Planes never go beyond the last occluder.
        let short = plane_positions(&ext, &lc, x0, x0 + 5.0, 5);
        assert!(short.iter().all(|&x| x <= x0 + 5.0) && !short.is_empty());
    }

    #[test]
    fn equivalent_cell_contains_the_face_and_grows() {
        let lc = Direction::PosX.box_to_local(DVec3::ZERO, DVec3::new(10.0, 10.0, 2.0));
        let plane = Plane::new(Direction::PosX, &lc, 30.0, 64, 1.5);
        let e = equivalent_cell(&lc, &plane);
        assert!(e.min.x <= 0.0 && e.max.x >= 10.0 && e.min.y <= 0.0 && e.max.y >= 2.0);
        assert!(e.size().x > 10.0);
    }

    /// Rows wholly below the ground are black on horizontal planes, the row crossing
    /// z = 0 is not; a -z plane below the ground is all black, a +z plane untouched.
    #[test]
    fn the_ground_is_in_the_umbra() {
        let cell = (DVec3::new(0.0, 0.0, 1.5), DVec3::new(2.0, 2.0, 2.0));
        let n = 64;
        let lc = Direction::PosX.box_to_local(cell.0, cell.1);
        let plane = Plane::new(Direction::PosX, &lc, 10.0, n, 1.5);
        let mut black = vec![false; n * n];
        ground_black(&plane, &mut black);
        for j in 0..n {
            let top = plane.from_px(DVec2::new(0.0, (j + 1) as f64)).y;
            assert_eq!(black[j * n], top <= 0.0, "row {j} top {top}");
            assert!(black[j * n..(j + 1) * n].iter().all(|b| *b == black[j * n]));
        }
        assert!(black.iter().any(|b| *b) && !black.iter().all(|b| *b));
        for (dir, all) in [(Direction::NegZ, true), (Direction::PosZ, false)] {
            let lc = dir.box_to_local(cell.0, cell.1);
            let plane = Plane::new(dir, &lc, lc.max.x + 3.0, n, 1.5);
            let mut black = vec![false; n * n];
            ground_black(&plane, &mut black);
            assert!(black.iter().all(|b| *b == all), "{dir:?}");
        }
    }

    /// The kernel is the inverse image of the cell itself: for a deep cell it erodes a
    /// black square less than the kernel of the (larger) equivalent planar cell would.
    #[test]
    fn reprojection_kernel_is_the_cells_own() {
        let lc = Direction::PosX.box_to_local(DVec3::ZERO, DVec3::new(6.0, 1.0, 1.0));
        let from = Plane::new(Direction::PosX, &lc, 10.0, 128, 1.5);
        let to = Plane::new(Direction::PosX, &lc, 10.5, 128, 1.5);
        let n = 128;
        let mut black = vec![false; n * n];
        for j in 32..96 {
            for i in 32..96 {
                black[j * n + i] = true;
            }
        }
        let m = OcclusionMap::new(n, black);
        let ours = reproject(&lc, &from, &m, &to)
            .iter()
            .filter(|b| **b)
            .count();
        // The same rule with the equivalent cell's rectangle as the source.
        let e = equivalent_cell(&lc, &to);
        let a = (from.x - lc.max.x) / (to.x - lc.max.x);
        let ps = to.pixel_size();
        let mut theirs = 0;
        for j in 0..n {
            for i in 0..n {
                let q0 = to.rect.min + DVec2::new(i as f64, j as f64) * ps;
                let (lo, hi) = (
                    q0 * a + e.min * (1.0 - a),
                    (q0 + ps) * a + e.max * (1.0 - a),
                );
                if let Some(r) = pixel_range(from.to_px(lo), from.to_px(hi), n) {
                    theirs += m.all_black(r) as usize;
                }
            }
        }
        assert!(
            ours > theirs,
            "cell kernel {ours} vs equivalent-cell kernel {theirs}"
        );
        assert!(ours < 64 * 64);
    }

    /// A fully black map stays black inside when re-projected, and its border erodes.
    #[test]
    fn reprojection_erodes_by_the_kernel() {
        let lc = Direction::PosX.box_to_local(DVec3::ZERO, DVec3::new(2.0, 2.0, 2.0));
        let from = Plane::new(Direction::PosX, &lc, 10.0, 32, 1.0);
        let to = Plane::new(Direction::PosX, &lc, 12.0, 32, 1.0);
        let n = 32;
        let mut black = vec![false; n * n];
        for j in 4..28 {
            for i in 4..28 {
                black[j * n + i] = true;
            }
        }
        let m = OcclusionMap::new(n, black);
        let r = reproject(&lc, &from, &m, &to);
        let count = r.iter().filter(|b| **b).count();
        assert!(count > 0 && count < 24 * 24, "{count}");
        // The centre stays black.
        assert!(r[16 * n + 16]);
        // Nothing black outside the image of the black square.
        assert!(!r[0]);
    }
}
