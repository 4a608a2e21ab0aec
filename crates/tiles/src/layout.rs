//! The tile tree: an explicit quadtree over the scene's ground plane.
//!
//! The scene's xy bounds are covered by one square, split in four recursively until a
//! square holds at most `max_features_per_tile` objects. An object belongs to exactly one
//! tile: the leaf whose square holds the centre of its bounding box. Only leaves have
//! content, so a tile's bounding box is the union of its objects' boxes (leaf) or of its
//! children's boxes (inner tile): every box encloses its content and its subtree, as
//! 3D Tiles requires of bounding volumes.
//!
//! The scene has no levels of detail: an inner tile without content stands for all
//! the geometry below it, so its geometric error is the diagonal of its box (what is
//! missing if nothing below is drawn), and a leaf's is 0.

use sightline_geom::{Aabb3, DVec2, DVec3};
use sightline_scene::Scene;

/// Deepest level of the quadtree: below it, objects with (nearly) the same centre stay
/// together in one leaf instead of splitting forever.
pub const MAX_LEVEL: u32 = 20;

/// Smallest half-extent of a bounding box (metres): flat objects have zero height, and
/// a box with a zero axis is degenerate for 3D Tiles clients.
pub const MIN_HALF_EXTENT_M: f64 = 0.005;

/// One tile of the tree.
#[derive(Clone, Debug, PartialEq)]
pub struct Tile {
    /// Quadtree address: level (0 = root) and column/row of the square at that level.
    pub level: u32,
    pub x: u32,
    pub y: u32,
    /// Bounds of everything below (never empty, at least [`MIN_HALF_EXTENT_M`] thick).
    pub bounds: Aabb3,
    /// Indices of the children in [`Layout::tiles`].
    pub children: Vec<usize>,
    /// Object ids of the content, in feature-id order (empty for inner tiles).
    pub objects: Vec<u32>,
    pub geometric_error: f64,
}

impl Tile {
    /// The content URI, relative to `tileset.json` (content tiles only).
    pub fn content_uri(&self) -> Option<String> {
        (!self.objects.is_empty())
            .then(|| format!("tiles/{}-{}-{}.glb", self.level, self.x, self.y))
    }
}

/// Where an object went: its tile and its feature id there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Placement {
    pub tile: u32,
    pub feature: u32,
}

/// The whole tree: `tiles[0]` is the root; a parent precedes its children.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    pub tiles: Vec<Tile>,
    /// Per object id, its tile and feature id.
    pub placement: Vec<Placement>,
}

impl Layout {
    /// Split `scene` into tiles of at most `max_features_per_tile` objects (more only
    /// at [`MAX_LEVEL`]). `None` for an empty scene or a limit of 0.
    pub fn build(scene: &Scene, max_features_per_tile: usize) -> Option<Layout> {
        if scene.is_empty() || max_features_per_tile == 0 {
            return None;
        }
        let b = scene.bounds.xy();
        let side = (b.max - b.min).max_element().max(1e-3);
        let centres: Vec<DVec2> = scene
            .objects
            .iter()
            .map(|o| o.bounds.center().truncate())
            .collect();
        let mut layout = Layout {
            tiles: vec![],
            placement: vec![
                Placement {
                    tile: 0,
                    feature: 0
                };
                scene.len()
            ],
        };
        let all: Vec<u32> = (0..scene.len() as u32).collect();
        let square = Square {
            min: b.min,
            side,
            level: 0,
            x: 0,
            y: 0,
        };
        layout.split(scene, &centres, square, all, max_features_per_tile);
        Some(layout)
    }

    /// Add the tile of `square` holding `ids` and its subtree; returns its index.
    fn split(
        &mut self,
        scene: &Scene,
        centres: &[DVec2],
        sq: Square,
        ids: Vec<u32>,
        max: usize,
    ) -> usize {
        let index = self.tiles.len();
        self.tiles.push(Tile {
            level: sq.level,
            x: sq.x,
            y: sq.y,
            bounds: Aabb3::EMPTY,
            children: vec![],
            objects: vec![],
            geometric_error: 0.0,
        });
        let bounds = if ids.len() <= max || sq.level >= MAX_LEVEL {
            for (feature, &id) in ids.iter().enumerate() {
                self.placement[id as usize] = Placement {
                    tile: index as u32,
                    feature: feature as u32,
                };
            }
            let b = ids.iter().fold(Aabb3::EMPTY, |b, &id| {
                b.union(scene.objects[id as usize].bounds)
            });
            self.tiles[index].objects = ids;
            b
        } else {
            let half = sq.side / 2.0;
            let mid = sq.min + DVec2::splat(half);
            let mut quadrants: [Vec<u32>; 4] = Default::default();
            for id in ids {
                let c = centres[id as usize];
                let q = usize::from(c.x >= mid.x) + 2 * usize::from(c.y >= mid.y);
                quadrants[q].push(id);
            }
            let mut b = Aabb3::EMPTY;
            for (q, ids) in quadrants.into_iter().enumerate() {
                if ids.is_empty() {
                    continue;
                }
                let (qx, qy) = ((q % 2) as u32, (q / 2) as u32);
                let child = Square {
                    min: sq.min + DVec2::new(qx as f64 * half, qy as f64 * half),
                    side: half,
                    level: sq.level + 1,
                    x: 2 * sq.x + qx,
                    y: 2 * sq.y + qy,
                };
                let c = self.split(scene, centres, child, ids, max);
                b = b.union(self.tiles[c].bounds);
                self.tiles[index].children.push(c);
            }
            b
        };
        let bounds = thicken(bounds);
        let t = &mut self.tiles[index];
        t.bounds = bounds;
        t.geometric_error = if t.children.is_empty() {
            0.0
        } else {
            bounds.size().length()
        };
        index
    }

    /// Indices of the tiles with content.
    pub fn content_tiles(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.tiles.len()).filter(|&t| !self.tiles[t].objects.is_empty())
    }
}

#[derive(Clone, Copy)]
struct Square {
    min: DVec2,
    side: f64,
    level: u32,
    x: u32,
    y: u32,
}

/// Grow each half-extent to at least [`MIN_HALF_EXTENT_M`] (a box still contains what it
/// contained).
fn thicken(b: Aabb3) -> Aabb3 {
    let c = b.center();
    let h = (b.size() / 2.0).max(DVec3::splat(MIN_HALF_EXTENT_M));
    Aabb3::new(b.min.min(c - h), b.max.max(c + h))
}
