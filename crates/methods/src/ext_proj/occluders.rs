//! Occluders of the extended projections and their selection (Durand et al. 2000,
//! §3.3 and §6.1 "Occluder selection").
//!
//! * Occluders are the objects' *inner* 2.5D prisms, those of the methods' one occluder
//!   model (`sightline_scene::occluders`, in scene coordinates). Touching buildings are fused
//!   first: the ground prisms (base exactly on the ground: a gap under a raised prism
//!   must stay open) form a height field whose level sets `{H ≥ h}` are unioned and
//!   extruded from the ground to `h`; each union is split into convex pieces
//!   (Hertel–Mehlhorn on a triangulation), so a whole street block becomes a few large
//!   convex occluders instead of many small ones, and slices (§3.3) of neighbouring
//!   pieces meet exactly. Raised prisms are cut into convex pieces alone.
//! * Union results live on a 1 mm grid: every *boundary* edge of a piece is moved
//!   inward by [`INWARD_M`]; shared (internal) edges stay put.
//! * Selection: an occluder matters where its solid angle, seen from the cell, exceeds
//!   a threshold; the region where it may be relevant (a disc of radius
//!   `√(area / threshold)`) is precomputed and stored in a spatial tree (the paper's
//!   kd-tree; here an R-tree), which each cell queries with its own box.
//! * Mesh triangles (leaves) are kept apart: only the occlusion sweep uses them (§5).
//! * Each piece and triangle knows the objects it may be made of ([`Piece::sources`]),
//!   so the adaptive recursion can drop the occluders hidden from the parent cell
//!   (§6.1: "we also use the PVS of the parent cell to cull hidden occluders").

use super::projection::{clip_halfplane, polygon_area, ConvexOccluder};
use rstar::{primitives::GeomWithData, primitives::Rectangle, RTree, AABB};
use sightline_geom::{boolean, Aabb3, DVec2, Polygon};
use sightline_scene::occluders::{inner_prisms, stands_on_ground};
use sightline_scene::{Geometry, Scene};
use std::collections::HashMap;

/// Inward move of boundary edges of fused footprints (two grid steps of the booleans).
pub(crate) const INWARD_M: f64 = 2.0 * boolean::GRID_M;

/// At most this many height levels are fused (levels are chosen among the distinct
/// heights; each building counts at the highest level not above its top).
const MAX_LEVELS: usize = 8;

/// One convex occluder with its bounds and the approximate area it presents.
#[derive(Clone, Debug)]
pub struct Piece {
    pub occluder: ConvexOccluder,
    pub bounds: Aabb3,
    /// A rough largest cross-section (m²), for the solid-angle heuristic.
    pub area: f64,
    /// The cross-section (m²) that decides the piece's relevance region: that of the
    /// whole fused footprint it was cut from. The convex decomposition cuts a street
    /// front into pieces, some of them thin slivers whose own solid angle is tiny;
    /// leaving them out opens gaps in the fused front that hide nothing behind it.
    pub relevance: f64,
    /// The objects the piece may be made of (sorted ids, a superset): every object
    /// whose prism, cut at the piece's level, can contribute to its fused footprint,
    /// or the mesh object of a triangle. A piece none of whose sources is in a
    /// parent cell's PVS is hidden from it, and from every sub-cell (§6.1).
    pub sources: Vec<u32>,
}

impl Piece {
    /// Whether some object of the piece is among `candidates` (sorted ids).
    pub fn made_of_any(&self, candidates: &[u32]) -> bool {
        self.sources
            .iter()
            .any(|s| candidates.binary_search(s).is_ok())
    }
}

type Entry = GeomWithData<Rectangle<[f64; 2]>, u32>;

/// Occluders of a scene, prepared once.
pub struct OccluderSet {
    pub pieces: Vec<Piece>,
    tree: RTree<Entry>,
    /// Mesh triangles (leaves, trunks, detailed walls) for the sweep.
    pub triangles: Vec<Piece>,
    tri_tree: RTree<Entry>,
    /// Solid-angle threshold (sr) of the relevance regions.
    pub solid_angle: f64,
}

impl OccluderSet {
    pub(crate) fn build(scene: &Scene, solid_angle: f64) -> Self {
        let mut pieces = Vec::new();
        // Ground prisms, by height, for the fusion; raised ones as they are.
        let mut ground: Vec<(&Polygon, f64)> = Vec::new();
        let mut ground_ids: Vec<u32> = Vec::new();
        for (id, p) in inner_prisms(scene) {
            if stands_on_ground(p) {
                ground.push((&p.footprint, p.top));
                ground_ids.push(id);
            } else {
                let whole = cross_section(&p.footprint, p.top - p.base);
                for (poly, _) in convex_pieces(&p.footprint) {
                    push_prism(&mut pieces, poly, p.base, p.top, whole, vec![id]);
                }
            }
        }
        // Ground prisms by footprint box, to find the sources of the fused pieces: a
        // fused piece lies in the union of the footprints of the prisms with
        // `top ≥ level`, so each prism that contributes meets the piece's box.
        let ground_tree: RTree<GeomWithData<Rectangle<[f64; 2]>, usize>> = RTree::bulk_load(
            ground
                .iter()
                .enumerate()
                .map(|(k, (f, _))| {
                    let b = f.bbox();
                    GeomWithData::new(Rectangle::from_corners(b.min.into(), b.max.into()), k)
                })
                .collect(),
        );
        for (level, polys) in fused_levels(&ground) {
            for poly in polys {
                let whole = cross_section(&poly, level);
                for (piece, _) in convex_pieces(&poly) {
                    let b = sightline_geom::Aabb2::from_points(&piece);
                    let env = AABB::from_corners(b.min.into(), b.max.into());
                    let mut sources: Vec<u32> = ground_tree
                        .locate_in_envelope_intersecting(env)
                        .filter(|e| ground[e.data].1 >= level)
                        .map(|e| ground_ids[e.data])
                        .collect();
                    sources.sort_unstable();
                    sources.dedup();
                    push_prism(&mut pieces, piece, 0.0, level, whole, sources);
                }
            }
        }
        let tree = relevance_tree(&pieces, solid_angle);
        let mut triangles = Vec::new();
        for (id, o) in scene.objects.iter().enumerate() {
            if let Geometry::Mesh(m) = &o.geometry {
                for t in &m.triangles {
                    let tri = m.triangle(t);
                    let e1 = tri[1] - tri[0];
                    let e2 = tri[2] - tri[0];
                    let area = 0.5 * e1.cross(e2).length();
                    if !(area > 0.0) {
                        continue;
                    }
                    triangles.push(Piece {
                        occluder: ConvexOccluder::Planar(tri.to_vec()),
                        bounds: Aabb3::from_points(&tri),
                        area,
                        relevance: area,
                        sources: vec![id as u32],
                    });
                }
            }
        }
        let tri_tree = bounds_tree(&triangles);
        OccluderSet {
            pieces,
            tree,
            triangles,
            tri_tree,
            solid_angle,
        }
    }

    /// Pieces whose relevance region meets the cell's footprint (§6.1).
    pub fn relevant(&self, cell: &Aabb3) -> Vec<u32> {
        self.relevant_among(cell, None)
    }

    /// [`OccluderSet::relevant`], keeping only the pieces made of some object of
    /// `candidates` (sorted ids; `None` = all): the others are hidden from the cell
    /// whose PVS `candidates` is (§6.1).
    pub fn relevant_among(&self, cell: &Aabb3, candidates: Option<&[u32]>) -> Vec<u32> {
        in_envelope(&self.tree, &self.pieces, cell, candidates)
    }

    /// Mesh triangles whose footprint meets the box `area` (the sweep's reach) and
    /// whose object is among `candidates` (sorted ids; `None` = all).
    pub(crate) fn triangles_in(&self, area: &Aabb3, candidates: Option<&[u32]>) -> Vec<u32> {
        in_envelope(&self.tri_tree, &self.triangles, area, candidates)
    }
}

/// The entries of `tree` meeting the footprint of `area`, made of some object of
/// `candidates` (all when `None`), sorted.
fn in_envelope(
    tree: &RTree<Entry>,
    pieces: &[Piece],
    area: &Aabb3,
    candidates: Option<&[u32]>,
) -> Vec<u32> {
    let env = AABB::from_corners([area.min.x, area.min.y], [area.max.x, area.max.y]);
    let mut v: Vec<u32> = tree
        .locate_in_envelope_intersecting(env)
        .map(|e| e.data)
        .filter(|&i| candidates.is_none_or(|c| pieces[i as usize].made_of_any(c)))
        .collect();
    v.sort_unstable();
    v
}

/// The rough largest cross-section (m²) of a prism of `height` over `footprint`.
fn cross_section(footprint: &Polygon, height: f64) -> f64 {
    (footprint.bbox().size().length() * height).max(footprint.area())
}

fn push_prism(
    pieces: &mut Vec<Piece>,
    footprint: Vec<DVec2>,
    base: f64,
    top: f64,
    whole: f64,
    sources: Vec<u32>,
) {
    let area = polygon_area(&footprint);
    if footprint.len() < 3 || !(area > 0.0) {
        return;
    }
    let b = sightline_geom::Aabb2::from_points(&footprint);
    let diag = b.size().length();
    let own = (diag * (top - base)).max(area);
    pieces.push(Piece {
        bounds: Aabb3::new(b.min.extend(base), b.max.extend(top)),
        area: own,
        relevance: own.max(whole),
        sources,
        occluder: ConvexOccluder::Prism {
            footprint,
            base,
            top,
        },
    });
}

fn relevance_tree(pieces: &[Piece], solid_angle: f64) -> RTree<Entry> {
    let entries = pieces
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let r = (p.relevance / solid_angle.max(1e-9)).sqrt();
            GeomWithData::new(
                Rectangle::from_corners(
                    [p.bounds.min.x - r, p.bounds.min.y - r],
                    [p.bounds.max.x + r, p.bounds.max.y + r],
                ),
                i as u32,
            )
        })
        .collect();
    RTree::bulk_load(entries)
}

fn bounds_tree(pieces: &[Piece]) -> RTree<Entry> {
    let entries = pieces
        .iter()
        .enumerate()
        .map(|(i, p)| {
            GeomWithData::new(
                Rectangle::from_corners(
                    [p.bounds.min.x, p.bounds.min.y],
                    [p.bounds.max.x, p.bounds.max.y],
                ),
                i as u32,
            )
        })
        .collect();
    RTree::bulk_load(entries)
}

/// Level sets of the height field of ground-standing prisms: for each
/// chosen level `h`, the union of the footprints of prisms with `top ≥ h`. A level
/// is kept only where it differs from the next higher one (components identical to
/// a taller component are dominated by it).
pub(crate) fn fused_levels(ground: &[(&Polygon, f64)]) -> Vec<(f64, Vec<Polygon>)> {
    if ground.is_empty() {
        return vec![];
    }
    let mut heights: Vec<f64> = ground.iter().map(|g| g.1).collect();
    heights.sort_by(f64::total_cmp);
    // Distinct heights on a 0.5 m floor grid (rounding down keeps occluders inside).
    let mut levels: Vec<f64> = heights.iter().map(|h| (h * 2.0).floor() / 2.0).collect();
    levels.dedup();
    levels.retain(|h| *h > 0.0);
    if levels.is_empty() {
        levels.push(heights[0]);
    }
    if levels.len() > MAX_LEVELS {
        let step = levels.len() as f64 / MAX_LEVELS as f64;
        let mut picked: Vec<f64> = (0..MAX_LEVELS)
            .map(|i| levels[(i as f64 * step) as usize])
            .collect();
        picked.dedup();
        levels = picked;
    }
    let mut out: Vec<(f64, Vec<Polygon>)> = Vec::new();
    let mut higher: Vec<(f64, sightline_geom::Aabb2)> = Vec::new();
    for &h in levels.iter().rev() {
        let polys: Vec<Polygon> = ground
            .iter()
            .filter(|g| g.1 >= h)
            .map(|g| g.0.clone())
            .collect();
        let u = boolean::union(&polys);
        let signature: Vec<(f64, sightline_geom::Aabb2)> =
            u.iter().map(|p| (p.area(), p.bbox())).collect();
        let kept: Vec<Polygon> = u
            .into_iter()
            .filter(|p| {
                let (a, b) = (p.area(), p.bbox());
                !higher.iter().any(|(ha, hb)| {
                    (ha - a).abs() <= 1e-6 * a.max(1.0)
                        && (hb.min - b.min).abs().max_element() < 1e-9
                        && (hb.max - b.max).abs().max_element() < 1e-9
                })
            })
            .collect();
        higher = signature;
        if !kept.is_empty() {
            out.push((h, kept));
        }
    }
    out.reverse();
    out
}

/// A directed edge between two vertices identified by their exact bits.
type EdgeKey = ((u64, u64), (u64, u64));

fn key(p: DVec2) -> (u64, u64) {
    (p.x.to_bits(), p.y.to_bits())
}

/// Convex decomposition of a polygon (with holes) by Hertel–Mehlhorn: triangulate,
/// then remove internal diagonals while the merged piece stays convex. Boundary edges
/// (those of the input polygon) are moved inward by [`INWARD_M`]. Returns each piece
/// (counter-clockwise) with, per edge, whether it lies on the input's boundary.
pub(crate) fn convex_pieces(poly: &Polygon) -> Vec<(Vec<DVec2>, Vec<bool>)> {
    let poly = poly.clone().normalized();
    let boundary: std::collections::HashSet<EdgeKey> =
        poly.edges().map(|(a, b)| (key(a), key(b))).collect();
    let mut parts: Vec<Option<Vec<DVec2>>> = poly
        .triangulate()
        .into_iter()
        .filter(|t| (t[1] - t[0]).perp_dot(t[2] - t[0]) > 0.0)
        .map(|t| Some(t.to_vec()))
        .collect();
    // Directed edge → owning part.
    let mut owner: HashMap<EdgeKey, usize> = HashMap::new();
    for (i, p) in parts.iter().enumerate() {
        if let Some(p) = p {
            for k in 0..p.len() {
                owner.insert((key(p[k]), key(p[(k + 1) % p.len()])), i);
            }
        }
    }
    // Internal diagonals, each once, in a deterministic order.
    let mut diagonals: Vec<EdgeKey> = owner
        .keys()
        .filter(|(a, b)| !boundary.contains(&(*a, *b)) && a < b)
        .copied()
        .collect();
    diagonals.sort_unstable();
    for (a, b) in diagonals {
        let (Some(&pi), Some(&qi)) = (owner.get(&(a, b)), owner.get(&(b, a))) else {
            continue;
        };
        if pi == qi {
            continue;
        }
        let (Some(p), Some(q)) = (parts[pi].as_ref(), parts[qi].as_ref()) else {
            continue;
        };
        let Some(merged) = merge_across(p, q, a, b) else {
            continue;
        };
        if !is_convex(&merged) {
            continue;
        }
        owner.remove(&(a, b));
        owner.remove(&(b, a));
        for k in 0..merged.len() {
            owner.insert((key(merged[k]), key(merged[(k + 1) % merged.len()])), pi);
        }
        parts[pi] = Some(merged);
        parts[qi] = None;
    }
    parts
        .into_iter()
        .flatten()
        .filter_map(|p| {
            let flags: Vec<bool> = (0..p.len())
                .map(|k| boundary.contains(&(key(p[k]), key(p[(k + 1) % p.len()]))))
                .collect();
            let shrunk = shrink_boundary(&p, &flags, INWARD_M);
            (shrunk.len() >= 3 && polygon_area(&shrunk) > 0.0).then_some((shrunk, flags))
        })
        .collect()
}

/// Merge `p` (having edge a→b) and `q` (having edge b→a) into one ring.
fn merge_across(p: &[DVec2], q: &[DVec2], a: (u64, u64), b: (u64, u64)) -> Option<Vec<DVec2>> {
    let ip = (0..p.len()).find(|&k| key(p[k]) == a && key(p[(k + 1) % p.len()]) == b)?;
    let iq = (0..q.len()).find(|&k| key(q[k]) == b && key(q[(k + 1) % q.len()]) == a)?;
    let mut out = Vec::with_capacity(p.len() + q.len() - 2);
    // p from b around to a (inclusive), then q after a up to before b.
    for k in 0..p.len() {
        out.push(p[(ip + 1 + k) % p.len()]);
    }
    for k in 2..q.len() {
        out.push(q[(iq + k) % q.len()]);
    }
    Some(out)
}

fn is_convex(p: &[DVec2]) -> bool {
    let n = p.len();
    (0..n).all(|i| {
        let (a, b, c) = (p[i], p[(i + 1) % n], p[(i + 2) % n]);
        !matches!(
            sightline_geom::orient2d(a, b, c),
            sightline_geom::Orientation::Right
        )
    })
}

/// Move the flagged edges of a convex counter-clockwise polygon inward by `d`.
fn shrink_boundary(p: &[DVec2], flags: &[bool], d: f64) -> Vec<DVec2> {
    let mut out = p.to_vec();
    for k in 0..p.len() {
        if !flags[k] {
            continue;
        }
        let (a, b) = (p[k], p[(k + 1) % p.len()]);
        let e = b - a;
        let len = e.length();
        if !(len > 0.0) {
            continue;
        }
        let n = DVec2::new(-e.y, e.x) / len;
        out = clip_halfplane(&out, n, n.dot(a) + d);
        if out.len() < 3 {
            return vec![];
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use sightline_geom::DVec3;
    use sightline_scene::Object;

    #[test]
    fn l_shape_decomposes_into_two_convex_pieces() {
        let l = Polygon::new(
            vec![
                DVec2::new(0.0, 0.0),
                DVec2::new(8.0, 0.0),
                DVec2::new(8.0, 4.0),
                DVec2::new(4.0, 4.0),
                DVec2::new(4.0, 8.0),
                DVec2::new(0.0, 8.0),
            ],
            vec![],
        );
        let pieces = convex_pieces(&l);
        assert!(pieces.len() <= 3, "{}", pieces.len());
        let area: f64 = pieces.iter().map(|p| polygon_area(&p.0)).sum();
        assert!(area < 48.0 && area > 47.9, "{area}");
        for (p, _) in &pieces {
            assert!(is_convex(p));
        }
    }

    /// A street front fused from a long bar and a thin wing: the wing's own piece has a
    /// small cross-section, but it is relevant wherever the front is (a gap would open
    /// in the fused front otherwise).
    #[test]
    fn pieces_are_relevant_where_their_whole_front_is() {
        let bar = Object::rect_block(0.0, 0.0, 200.0, 10.0, 20.0);
        let wing = Object::rect_block(100.0, 10.0, 101.0, 12.0, 20.0);
        let scene = Scene::from_objects(vec![bar, wing]);
        let set = OccluderSet::build(&scene, 0.002);
        assert!(set.pieces.len() >= 2, "{}", set.pieces.len());
        let small = set
            .pieces
            .iter()
            .map(|p| p.area)
            .fold(f64::INFINITY, f64::min);
        let r_small = (small / 0.002).sqrt();
        // A cell beyond the small piece's own radius, within the front's.
        let y = 12.0 + r_small + 50.0;
        let cell = Aabb3::new(DVec3::new(90.0, y, 1.5), DVec3::new(110.0, y + 20.0, 2.0));
        let rel = set.relevant(&cell);
        assert_eq!(rel.len(), set.pieces.len(), "{rel:?} radius {r_small}");
        assert!(set.pieces.iter().all(|p| p.relevance >= p.area));
    }

    #[test]
    fn touching_buildings_fuse_per_level() {
        let a = Object::block(
            None,
            Polygon::rect(DVec2::new(0.0, 0.0), DVec2::new(10.0, 10.0)),
            0.0,
            20.0,
        );
        let b = Object::block(
            None,
            Polygon::rect(DVec2::new(10.0, 0.0), DVec2::new(20.0, 10.0)),
            0.0,
            10.0,
        );
        let scene = Scene::from_objects(vec![a, b]);
        let set = OccluderSet::build(&scene, 0.01);
        // Level 10: one 20x10 rectangle; level 20: the tall one alone.
        let wide = set
            .pieces
            .iter()
            .any(|p| p.bounds.max.z == 10.0 && p.bounds.size().x > 19.9 && p.bounds.size().y > 9.9);
        assert!(
            wide,
            "{:?}",
            set.pieces.iter().map(|p| p.bounds).collect::<Vec<_>>()
        );
        assert!(set.pieces.iter().any(|p| p.bounds.max.z == 20.0));
        assert_eq!(set.relevant(&scene.bounds).len(), set.pieces.len());
        // The pieces at level 10 are made of both buildings, those at 20 of the tall
        // one only: with the tall one hidden (not a candidate) only level 10 is left.
        for p in &set.pieces {
            let want: &[u32] = if p.bounds.max.z == 10.0 {
                &[0, 1]
            } else {
                &[0]
            };
            assert_eq!(p.sources, want, "{:?}", p.bounds);
        }
        let without_tall = set.relevant_among(&scene.bounds, Some(&[1]));
        assert!(!without_tall.is_empty());
        assert!(without_tall
            .iter()
            .all(|&i| set.pieces[i as usize].bounds.max.z == 10.0));
        assert!(set.relevant_among(&scene.bounds, Some(&[])).is_empty());
    }
}
