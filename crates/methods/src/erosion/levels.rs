//! The occluders of a scene as one fused height field (NOTES §1).
//!
//! Occluders are the *inner* bounds of the objects (§4.2). Their union with the
//! ground half-space is a height field `G(x, y)` (columns `(−∞, G]`); only prisms
//! standing on the ground are used (an overhang is not a height-field column, and
//! dropping an occluder is always conservative). Heights are rounded *down* to
//! [`HEIGHT_STEP_M`] (inner bound, fewer distinct levels).
//!
//! Horizontal erosion of a height field is a min-filter, computed exactly by level
//! sets: for each distinct height `h`, the footprint union `{G ≥ h}` is eroded and
//! extruded to `h`. Touching buildings are fused first, so a party wall does not
//! open a gap of the cell's width. The plane is cut into square tiles: erosion is
//! local (a point of `P ⊖ X` only depends on `P` within the element's reach), so
//! each tile's level sets are clipped to the tile grown by that reach, eroded, and
//! clipped back — exact inside the tile, computed lazily, and a unit of culling.

use super::erode::{erode, Element, GRID_MARGIN_M};
use rstar::{RTree, RTreeObject, AABB};
use sightline_geom::{boolean, Aabb2, DVec2, Polygon};
use sightline_scene::Scene;
use std::sync::OnceLock;

/// Occluder heights are rounded down to this step (inner bound, fewer levels).
pub const HEIGHT_STEP_M: f64 = 1.0;
/// Side of the square tiles the eroded height field is computed and culled by.
pub const TILE_M: f64 = 100.0;
/// Eroded tiles overlap their neighbours by this much, so that a wall crossing a tile
/// border is still covered by one piece in most map bins (a seam costs tightness,
/// never correctness).
pub const OVERLAP_M: f64 = 4.0;

/// One level set: the union of footprints with height ≥ `h`.
#[derive(Clone, Debug)]
pub struct Level {
    pub h: f64,
    pub polys: Vec<Polygon>,
}

/// A square tile of the plane holding some occluders.
#[derive(Debug)]
pub struct Tile {
    pub rect: Aabb2,
}

/// The fused occluder height field of a scene: ground-standing inner prisms, indexed.
#[derive(Debug)]
pub struct HeightField {
    prisms: Vec<(Polygon, f64, Aabb2)>,
    tree: RTree<Item>,
    bounds: Aabb2,
}

#[derive(Debug)]
struct Item {
    idx: usize,
    bbox: Aabb2,
}

impl RTreeObject for Item {
    type Envelope = AABB<[f64; 2]>;
    fn envelope(&self) -> Self::Envelope {
        AABB::from_corners(
            [self.bbox.min.x, self.bbox.min.y],
            [self.bbox.max.x, self.bbox.max.y],
        )
    }
}

fn envelope(r: Aabb2) -> AABB<[f64; 2]> {
    AABB::from_corners([r.min.x, r.min.y], [r.max.x, r.max.y])
}

impl HeightField {
    /// Index the inner bounds of every object of `scene`.
    pub fn build(scene: &Scene) -> Self {
        let mut prisms: Vec<(Polygon, f64, Aabb2)> = Vec::new();
        for o in &scene.objects {
            for p in &o.inner {
                if p.base > 1e-6 || !p.top.is_finite() {
                    continue;
                }
                let h = (p.top / HEIGHT_STEP_M).floor() * HEIGHT_STEP_M;
                if h <= 0.0 || p.footprint.exterior.len() < 3 || p.footprint.area() <= 0.0 {
                    continue;
                }
                let bb = p.footprint.bbox();
                if !(bb.min.is_finite() && bb.max.is_finite()) {
                    continue;
                }
                prisms.push((p.footprint.clone(), h, bb));
            }
        }
        let tree = RTree::bulk_load(
            prisms
                .iter()
                .enumerate()
                .map(|(idx, p)| Item { idx, bbox: p.2 })
                .collect(),
        );
        let bounds = prisms.iter().fold(Aabb2::EMPTY, |b, p| b.union(p.2));
        HeightField {
            prisms,
            tree,
            bounds,
        }
    }

    /// Prisms whose bounding box meets `r`.
    fn near(&self, r: Aabb2) -> impl Iterator<Item = usize> + '_ {
        self.tree
            .locate_in_envelope_intersecting(envelope(r))
            .map(|it| it.idx)
    }

    /// Whether some occluder footprint meets the interior of the rectangle `rect`
    /// (conservatively: may answer `true` for a footprint that only comes close).
    pub fn meets_rect(&self, rect: Aabb2) -> bool {
        self.near(rect)
            .any(|i| ring_meets_rect(&self.prisms[i].0.exterior, rect))
    }
}

/// Whether a ring's interior meets the rectangle (area of the clipped ring > 0).
fn ring_meets_rect(ring: &[DVec2], rect: Aabb2) -> bool {
    let clipped = super::shrink::clip_ring(ring, rect.min, rect.max);
    sightline_geom::polygon::ring_signed_area(&clipped).abs() > 1e-9
}

/// The erosion of the height field by one element, per tile, computed lazily and
/// shared by every cell of the same shape (§5.1).
#[derive(Debug)]
pub struct ErodedField {
    pub element: Element,
    pub half: DVec2,
    reach: f64,
    pub tiles: Vec<Tile>,
    h_max: Vec<OnceLock<f64>>,
    levels: Vec<OnceLock<Vec<Level>>>,
}

impl ErodedField {
    pub fn new(field: &HeightField, element: Element, half: DVec2) -> Self {
        let reach = element
            .vertices(half)
            .iter()
            .map(|v| v.length())
            .fold(0.0, f64::max);
        // Eroded pieces may lie up to `reach` away from the occluders (an element not
        // containing the origin translates them): tile the grown bounds.
        let mut tiles = Vec::new();
        if !field.bounds.is_empty() {
            let area = field.bounds.expand(reach + 1.0);
            let n = (area.size() / TILE_M).ceil().max(DVec2::ONE);
            for i in 0..n.x as usize {
                for j in 0..n.y as usize {
                    let min = area.min + DVec2::new(i as f64, j as f64) * TILE_M;
                    let rect = Aabb2::new(min, min + DVec2::splat(TILE_M));
                    let window = rect.expand(OVERLAP_M + reach + 1.0);
                    if field.near(window).next().is_some() {
                        tiles.push(Tile { rect });
                    }
                }
            }
        }
        let n = tiles.len();
        ErodedField {
            element,
            half,
            reach,
            tiles,
            h_max: (0..n).map(|_| OnceLock::new()).collect(),
            levels: (0..n).map(|_| OnceLock::new()).collect(),
        }
    }

    /// The region the eroded pieces of tile `i` lie in.
    pub fn piece_rect(&self, i: usize) -> Aabb2 {
        self.tiles[i].rect.expand(OVERLAP_M)
    }

    /// An upper bound of the eroded heights in tile `i`.
    pub fn h_max(&self, field: &HeightField, i: usize) -> f64 {
        *self.h_max[i].get_or_init(|| {
            let r = self.piece_rect(i).expand(self.reach + 1.0);
            field.near(r).map(|k| field.prisms[k].1).fold(0.0, f64::max)
        })
    }

    /// The eroded levels of tile `i`, highest first (empty levels dropped): the
    /// level sets of the occluders near the tile, clipped to the tile grown by the
    /// element's reach (the erosion is exact inside the piece rectangle), eroded,
    /// clipped to the piece rectangle.
    pub fn tile(&self, field: &HeightField, i: usize) -> &[Level] {
        self.levels[i].get_or_init(|| {
            let x = self.element.vertices(self.half);
            let keep = self.piece_rect(i);
            let window = keep.expand(self.reach + 1.0);
            let members: Vec<usize> = field.near(window).collect();
            let mut heights: Vec<f64> = members.iter().map(|&k| field.prisms[k].1).collect();
            heights.sort_by(|a, b| b.total_cmp(a));
            heights.dedup();
            let window_poly = [Polygon::rect(window.min, window.max)];
            let keep_poly = [Polygon::rect(keep.min, keep.max)];
            heights
                .iter()
                .filter_map(|&h| {
                    let polys: Vec<Polygon> = members
                        .iter()
                        .filter(|&&k| field.prisms[k].1 >= h)
                        .map(|&k| field.prisms[k].0.clone())
                        .collect();
                    let level = boolean::intersection(&polys, &window_poly);
                    let eroded = erode(&level, &x, GRID_MARGIN_M);
                    if eroded.is_empty() {
                        return None;
                    }
                    let polys = boolean::intersection(&eroded, &keep_poly);
                    (!polys.is_empty()).then_some(Level { h, polys })
                })
                .collect()
        })
    }
}
