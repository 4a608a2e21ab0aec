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
//! open a gap of the cell's width. Prisms are grouped into *clusters* (connected
//! components of overlapping bounding boxes): the erosion of a union of far-apart
//! sets by a connected element is the union of their erosions, so clusters are
//! eroded independently (and lazily).

use super::erode::{erode, Element, GRID_MARGIN_M};
use rstar::{RTree, RTreeObject, AABB};
use sightline_geom::{boolean, Aabb2, DVec2, Polygon};
use sightline_scene::Scene;
use std::sync::OnceLock;

/// Occluder heights are rounded down to this step.
pub const HEIGHT_STEP_M: f64 = 0.25;

/// One level set of a cluster: the union of its footprints with height ≥ `h`.
#[derive(Clone, Debug)]
pub struct Level {
    pub h: f64,
    pub polys: Vec<Polygon>,
}

/// A group of touching or nearby occluder prisms, fused.
#[derive(Debug)]
pub struct Cluster {
    pub bbox: Aabb2,
    /// Highest level.
    pub h_max: f64,
    /// Level sets, highest first (nested: a higher level lies inside the lower ones).
    pub levels: Vec<Level>,
}

/// The fused occluder height field of a scene.
#[derive(Debug)]
pub struct HeightField {
    pub clusters: Vec<Cluster>,
}

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

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

impl HeightField {
    /// Fuse the inner bounds of every object of `scene`.
    pub fn build(scene: &Scene) -> Self {
        // Ground-standing inner prisms, heights rounded down.
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
        // Clusters: connected components of bounding boxes grown by 1 cm.
        let items: Vec<Item> = prisms
            .iter()
            .enumerate()
            .map(|(idx, p)| Item {
                idx,
                bbox: p.2.expand(0.01),
            })
            .collect();
        let mut parent: Vec<usize> = (0..prisms.len()).collect();
        let tree = RTree::bulk_load(
            items
                .iter()
                .map(|i| Item {
                    idx: i.idx,
                    bbox: i.bbox,
                })
                .collect(),
        );
        for it in &items {
            for other in tree.locate_in_envelope_intersecting(it.envelope()) {
                let (a, b) = (find(&mut parent, it.idx), find(&mut parent, other.idx));
                if a != b {
                    parent[a.max(b)] = a.min(b);
                }
            }
        }
        let mut groups: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for i in 0..prisms.len() {
            let r = find(&mut parent, i);
            groups.entry(r).or_default().push(i);
        }
        let clusters = groups
            .into_values()
            .map(|members| {
                let mut heights: Vec<f64> = members.iter().map(|&i| prisms[i].1).collect();
                heights.sort_by(|a, b| b.total_cmp(a));
                heights.dedup();
                let bbox = members
                    .iter()
                    .fold(Aabb2::EMPTY, |b, &i| b.union(prisms[i].2));
                let levels: Vec<Level> = heights
                    .iter()
                    .map(|&h| {
                        let polys: Vec<Polygon> = members
                            .iter()
                            .filter(|&&i| prisms[i].1 >= h)
                            .map(|&i| prisms[i].0.clone())
                            .collect();
                        Level {
                            h,
                            polys: boolean::union(&polys),
                        }
                    })
                    .filter(|l| !l.polys.is_empty())
                    .collect();
                Cluster {
                    bbox,
                    h_max: levels.first().map_or(0.0, |l| l.h),
                    levels,
                }
            })
            .filter(|c| !c.levels.is_empty())
            .collect();
        HeightField { clusters }
    }

    /// Whether some occluder footprint meets the interior of the rectangle `rect`
    /// (conservatively: may answer `true` for a footprint that only comes close).
    pub fn meets_rect(&self, rect: Aabb2) -> bool {
        self.clusters.iter().any(|c| {
            c.bbox.intersects(&rect)
                && c.levels.last().is_some_and(|l| {
                    l.polys
                        .iter()
                        .any(|p| p.bbox().intersects(&rect) && ring_meets_rect(&p.exterior, rect))
                })
        })
    }
}

/// Whether a ring's interior meets the rectangle (area of the clipped ring > 0).
fn ring_meets_rect(ring: &[DVec2], rect: Aabb2) -> bool {
    let clipped = super::shrink::clip_ring(ring, rect.min, rect.max);
    sightline_geom::polygon::ring_signed_area(&clipped).abs() > 1e-9
}

/// The erosion of every cluster by one element, computed lazily per cluster and shared
/// by every cell of the same shape (§5.1).
#[derive(Debug)]
pub struct ErodedField {
    pub element: Element,
    pub half: DVec2,
    levels: Vec<OnceLock<Vec<Level>>>,
}

impl ErodedField {
    pub fn new(field: &HeightField, element: Element, half: DVec2) -> Self {
        ErodedField {
            element,
            half,
            levels: (0..field.clusters.len()).map(|_| OnceLock::new()).collect(),
        }
    }

    /// The eroded levels of cluster `i` (highest first; empty levels dropped).
    pub fn cluster(&self, field: &HeightField, i: usize) -> &[Level] {
        self.levels[i].get_or_init(|| {
            let x = self.element.vertices(self.half);
            field.clusters[i]
                .levels
                .iter()
                .map(|l| Level {
                    h: l.h,
                    polys: erode(&l.polys, &x, GRID_MARGIN_M),
                })
                .filter(|l| !l.polys.is_empty())
                .collect()
        })
    }
}
