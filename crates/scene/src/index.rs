//! Spatial index over the objects of a scene: a 2D R-tree (rstar, bulk-loaded by
//! sort-tile-recursive packing) over each object's horizontal bounding rectangle.
//!
//! [`SceneIndex::query_rect`] returns the objects whose rectangle meets a rectangle
//! (closed test: touching counts); the viewcell grid's free-space test
//! ([`crate::cells::FreeSpace`]) is built on it. The query is conservative: it may
//! return an object whose rectangle meets the region while its geometry does not,
//! never the other way round. The visibility methods index their occluders
//! themselves (uniform bucket grids walked along shafts and rays, kd-trees of
//! occludees), which an R-tree of object boxes does not serve.
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
use rstar::{RTree, AABB};
use sightline_geom::{Aabb2, Aabb3};

type Entry = GeomWithData<Rectangle<[f64; 2]>, u32>;

/// A 2D R-tree over object bounding rectangles; ids are object ids (or whatever ids
/// [`SceneIndex::from_boxes`] was given).
pub struct SceneIndex {
    tree: RTree<Entry>,
}

impl SceneIndex {
    /// Index every object of `scene` by its bounding box (objects with an empty box are left out).
    pub fn new(scene: &Scene) -> Self {
        Self::from_boxes(scene.objects.iter().map(|o| o.bounds).enumerate())
    }

    /// Index arbitrary boxes by id, e.g. the inner bounds of the occluders only.
    pub fn from_boxes(boxes: impl IntoIterator<Item = (usize, Aabb3)>) -> Self {
        let mut entries = Vec::new();
        for (id, b) in boxes {
            if !b.is_empty() && b.min.is_finite() && b.max.is_finite() {
                let r = Rectangle::from_corners([b.min.x, b.min.y], [b.max.x, b.max.y]);
                entries.push(GeomWithData::new(r, id as u32));
            }
        }
        SceneIndex {
            tree: RTree::bulk_load(entries),
        }
    }

    /// Number of indexed boxes.
    pub fn len(&self) -> usize {
        self.tree.size()
    }

    pub fn is_empty(&self) -> bool {
        self.tree.size() == 0
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Object, Scene};
    use sightline_geom::{DVec2, Polygon};

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
    fn rect_queries_match_brute_force() {
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
    }
}
