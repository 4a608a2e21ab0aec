//! Spatial index over the objects of a scene: a 2D R-tree (rstar, bulk-loaded by
//! sort-tile-recursive packing) over each object's horizontal bounding rectangle, with
//! its z-range kept beside it.
//!
//! Queries the methods need:
//! * [`SceneIndex::query_rect`] / [`SceneIndex::query_box`] — objects whose bounding
//!   box meets a rectangle / a 3D box (closed tests: touching counts);
//! * [`SceneIndex::query_convex`] and [`SceneIndex::query_wedge`] — objects whose
//!   rectangle meets a convex polygon, e.g. the footprint of a view frustum or of the
//!   shaft between a cell and an occludee, or a wedge of directions from a point;
//! * [`SceneIndex::by_distance`] — front-to-back order from a point (distance to each
//!   rectangle), for occluder selection and early termination.
//!
//! Every query is conservative: it may return an object whose rectangle meets the
//! region while its geometry does not, never the other way round.
//!
//! ```
//! use sightline_scene::{generate, index::SceneIndex};
//! use sightline_geom::{Aabb2, DVec2};
//! let scene = generate::city(1, 100);
//! let index = SceneIndex::new(&scene);
//! let near = index.query_rect(&Aabb2::new(DVec2::new(0.0, 0.0), DVec2::new(50.0, 50.0)));
//! assert!(near.windows(2).all(|w| w[0] < w[1]));
//! ```

use crate::Scene;
use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, SelectionFunction, AABB};
use sightline_geom::{Aabb2, Aabb3, DVec2};

type Entry = GeomWithData<Rectangle<[f64; 2]>, u32>;

/// A 2D R-tree over object bounding rectangles; ids are object ids (or whatever ids
/// [`SceneIndex::from_boxes`] was given).
pub struct SceneIndex {
    tree: RTree<Entry>,
    /// Bounding box per id (EMPTY for ids not in the tree).
    boxes: Vec<Aabb3>,
}

impl SceneIndex {
    /// Index every object of `scene` by its bounding box (objects with an empty box are left out).
    pub fn new(scene: &Scene) -> Self {
        Self::from_boxes(scene.objects.iter().map(|o| o.bounds).enumerate())
    }

    /// Index arbitrary boxes by id, e.g. the inner bounds of the occluders only.
    pub fn from_boxes(boxes: impl IntoIterator<Item = (usize, Aabb3)>) -> Self {
        let mut all: Vec<Aabb3> = Vec::new();
        let mut entries = Vec::new();
        for (id, b) in boxes {
            if all.len() <= id {
                all.resize(id + 1, Aabb3::EMPTY);
            }
            all[id] = b;
            if !b.is_empty() && b.min.is_finite() && b.max.is_finite() {
                let r = Rectangle::from_corners([b.min.x, b.min.y], [b.max.x, b.max.y]);
                entries.push(GeomWithData::new(r, id as u32));
            }
        }
        SceneIndex {
            tree: RTree::bulk_load(entries),
            boxes: all,
        }
    }

    /// Number of indexed boxes.
    pub fn len(&self) -> usize {
        self.tree.size()
    }

    pub fn is_empty(&self) -> bool {
        self.tree.size() == 0
    }

    /// The stored box of `id`.
    pub fn bounds(&self, id: u32) -> Aabb3 {
        self.boxes.get(id as usize).copied().unwrap_or(Aabb3::EMPTY)
    }

    /// Ids whose rectangle meets `r` (closed), sorted ascending.
    pub fn query_rect(&self, r: &Aabb2) -> Vec<u32> {
        let env = AABB::from_corners([r.min.x, r.min.y], [r.max.x, r.max.y]);
        let mut ids: Vec<u32> = self
            .tree
            .locate_in_envelope_intersecting(env)
            .map(|e| e.data)
            .collect();
        ids.sort_unstable();
        ids
    }

    /// Ids whose box meets the 3D box `b` (closed), sorted ascending.
    pub fn query_box(&self, b: &Aabb3) -> Vec<u32> {
        let mut ids = self.query_rect(&b.xy());
        ids.retain(|&id| {
            let o = self.boxes[id as usize];
            o.min.z <= b.max.z && b.min.z <= o.max.z
        });
        ids
    }

    /// Ids whose rectangle meets the convex polygon `poly` (any orientation, closed
    /// test), sorted ascending. A polygon of fewer than 3 points selects nothing.
    pub fn query_convex(&self, poly: &[DVec2]) -> Vec<u32> {
        if poly.len() < 3 {
            return Vec::new();
        }
        let sel = ConvexSelection::new(poly);
        let mut ids: Vec<u32> = self
            .tree
            .locate_with_selection_function(sel)
            .map(|e| e.data)
            .collect();
        ids.sort_unstable();
        ids
    }

    /// Ids whose rectangle meets the wedge of directions from `apex` turning
    /// counter-clockwise from `dir_from` to `dir_to` (at most a half-turn), up to
    /// `max_dist` from the apex. The wedge is covered by a convex polygon whose outer
    /// edges are tangent to the circle of radius `max_dist`, so nothing is lost.
    pub fn query_wedge(
        &self,
        apex: DVec2,
        dir_from: DVec2,
        dir_to: DVec2,
        max_dist: f64,
    ) -> Vec<u32> {
        let a0 = dir_from.y.atan2(dir_from.x);
        let mut sweep = dir_to.y.atan2(dir_to.x) - a0;
        if sweep < 0.0 {
            sweep += std::f64::consts::TAU;
        }
        let sweep = sweep.min(std::f64::consts::PI);
        let steps = ((sweep / std::f64::consts::FRAC_PI_4).ceil() as usize).max(1);
        let step = sweep / steps as f64;
        let r = max_dist / (0.5 * step).cos();
        let mut poly = vec![apex];
        // Segment ends at radius r: each chord touches the circle of radius max_dist.
        poly.push(apex + DVec2::from_angle(a0) * max_dist);
        for k in 0..steps {
            poly.push(apex + DVec2::from_angle(a0 + (k as f64 + 0.5) * step) * r);
        }
        poly.push(apex + DVec2::from_angle(a0 + sweep) * max_dist);
        self.query_convex(&poly)
    }

    /// All ids ordered by the distance from `p` to their rectangle (0 inside),
    /// nearest first, with that distance.
    pub fn by_distance(&self, p: DVec2) -> impl Iterator<Item = (u32, f64)> + '_ {
        self.tree
            .nearest_neighbor_iter_with_distance_2([p.x, p.y])
            .map(|(e, d2)| (e.data, d2.sqrt()))
    }
}

/// Separating-axis selection of rectangles meeting a convex polygon.
struct ConvexSelection {
    poly: Vec<DVec2>,
    bbox: Aabb2,
    /// Edge normals (not normalized) with the polygon's extent along each.
    axes: Vec<(DVec2, f64, f64)>,
}

impl ConvexSelection {
    fn new(poly: &[DVec2]) -> Self {
        let n = poly.len();
        let axes = (0..n)
            .map(|k| {
                let e = poly[(k + 1) % n] - poly[k];
                let axis = e.perp();
                let (lo, hi) = extent(poly.iter().copied(), axis);
                (axis, lo, hi)
            })
            .collect();
        ConvexSelection {
            poly: poly.to_vec(),
            bbox: Aabb2::from_points(poly),
            axes,
        }
    }

    fn meets(&self, min: [f64; 2], max: [f64; 2]) -> bool {
        let r = Aabb2::new(DVec2::from(min), DVec2::from(max));
        if !r.intersects(&self.bbox) {
            return false;
        }
        let corners = [
            r.min,
            DVec2::new(r.max.x, r.min.y),
            r.max,
            DVec2::new(r.min.x, r.max.y),
        ];
        self.axes.iter().all(|&(axis, lo, hi)| {
            let (a, b) = extent(corners.iter().copied(), axis);
            a <= hi && lo <= b
        }) && !self.poly.is_empty()
    }
}

fn extent(points: impl Iterator<Item = DVec2>, axis: DVec2) -> (f64, f64) {
    points.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
        let d = p.dot(axis);
        (lo.min(d), hi.max(d))
    })
}

impl SelectionFunction<Entry> for ConvexSelection {
    fn should_unpack_parent(&self, envelope: &AABB<[f64; 2]>) -> bool {
        self.meets(envelope.lower(), envelope.upper())
    }

    fn should_unpack_leaf(&self, leaf: &Entry) -> bool {
        let e = leaf.geom();
        self.meets(e.lower(), e.upper())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Object, Scene};
    use sightline_geom::Polygon;

    fn grid_scene() -> Scene {
        // 10 × 10 unit squares of height 1..10 at (2i, 2j).
        let objects = (0..100)
            .map(|k| {
                let (i, j) = ((k % 10) as f64, (k / 10) as f64);
                let lo = DVec2::new(2.0 * i, 2.0 * j);
                Object::block(
                    None,
                    Polygon::rect(lo, lo + DVec2::ONE),
                    0.0,
                    1.0 + (k % 10) as f64,
                )
            })
            .collect();
        Scene::from_objects(objects)
    }

    fn brute_rect(s: &Scene, r: &Aabb2) -> Vec<u32> {
        (0..s.objects.len() as u32)
            .filter(|&i| s.objects[i as usize].bounds.xy().intersects(r))
            .collect()
    }

    #[test]
    fn rect_and_box_queries_match_brute_force() {
        let s = grid_scene();
        let idx = SceneIndex::new(&s);
        assert_eq!(idx.len(), 100);
        for r in [
            Aabb2::new(DVec2::new(0.5, 0.5), DVec2::new(4.5, 2.5)),
            Aabb2::new(DVec2::new(1.0, 1.0), DVec2::new(2.0, 2.0)), // touches 4 squares' corners
            Aabb2::new(DVec2::new(-5.0, -5.0), DVec2::new(-1.0, -1.0)),
            Aabb2::new(DVec2::new(1.2, 1.2), DVec2::new(1.8, 1.8)), // in a street
        ] {
            assert_eq!(idx.query_rect(&r), brute_rect(&s, &r), "{r:?}");
        }
        let tall = idx.query_box(&Aabb3::new(
            DVec2::ZERO.extend(5.5),
            DVec2::splat(3.0).extend(20.0),
        ));
        // Squares (0,0),(1,0),(0,1),(1,1) have heights 1,2,1,2: none reaches 5.5.
        assert!(tall.is_empty());
        let low = idx.query_box(&Aabb3::new(
            DVec2::ZERO.extend(1.5),
            DVec2::splat(3.0).extend(2.0),
        ));
        assert_eq!(low, vec![1, 11]);
    }

    #[test]
    fn convex_and_wedge_queries() {
        let s = grid_scene();
        let idx = SceneIndex::new(&s);
        // A thin diagonal triangle along y = x meets only the diagonal squares (and
        // their corner-touching neighbours are excluded by the separating axes).
        let tri = [
            DVec2::new(0.5, 0.4),
            DVec2::new(18.6, 18.5),
            DVec2::new(18.4, 18.6),
        ];
        let ids = idx.query_convex(&tri);
        assert_eq!(ids, (0..10).map(|k| 11 * k).collect::<Vec<u32>>());
        // Wedge from the origin corner towards +x, 10° wide, 7 m: first-row squares 0..=3.
        let d = 5f64.to_radians();
        let w = idx.query_wedge(
            DVec2::new(-0.5, 0.5),
            DVec2::from_angle(-d),
            DVec2::from_angle(d),
            7.0,
        );
        assert_eq!(w, vec![0, 1, 2, 3]);
        // A half-turn wedge looking up from below the grid sees the first rows.
        let h = idx.query_wedge(DVec2::new(9.5, -1.0), DVec2::X, -DVec2::X, 2.5);
        assert!(h.contains(&4) && h.contains(&5), "{h:?}");
        assert!(h.iter().all(|&i| i < 10), "{h:?}");
    }

    #[test]
    fn by_distance_is_front_to_back() {
        let s = grid_scene();
        let idx = SceneIndex::new(&s);
        let order: Vec<(u32, f64)> = idx.by_distance(DVec2::new(0.5, 0.5)).collect();
        assert_eq!(order.len(), 100);
        assert_eq!(order[0], (0, 0.0));
        assert!(order.windows(2).all(|w| w[0].1 <= w[1].1));
        assert_eq!(order[99].0, 99);
    }
}
