//! The occluder model of every method: the prisms of the objects' *inner* bounds
//! (contained in their solids, so whatever they hide is hidden), selected here once, and
//! a uniform bucket grid over boxes.
//!
//! * [`inner_prisms`]: the inner prisms that can occlude at all (a finite top above its
//!   base and the ground, a finite footprint with an exterior ring), with their
//!   object's id.
//! * [`ground_prisms`]: those standing on the ground, `base <= GROUND_M`. The ground is
//!   opaque, so such a prism and the ground under it are one solid: Observation 1 of
//!   Koltun et al. 2001 (an occluder contains the vertical wall under its top), the
//!   seed's 2.5D horizon, erosion's height field and ext-proj's level sets extruded from
//!   the ground rely on it. The threshold is exactly the ground: with any tolerance, the
//!   gap under a slightly raised prism would count as solid and hide the sight lines
//!   through it.
//! * [`collect_occluders`]: the ground prisms as [`Occluder`]s in a local frame
//!   ([`local_origin`]), for `dual-ray` (which fuses them into slabs) and the seed.
//!   Erosion rasterizes [`ground_prisms`] into its height field; ext-proj fuses them by
//!   height levels and cuts convex pieces, in scene coordinates.
//!
//! Raised prisms (arcades, overhangs) are left out by the 2.5D methods, which is
//! conservative: an occluder left out can only make more visible. Ext-proj, whose
//! occluders are any convex solids, uses them as they are.

use crate::{Prism, Scene};
use sightline_geom::{DVec2, Polygon};

/// A prism whose base is at most this high stands on the ground.
pub const GROUND_M: f64 = 0.0;

/// One ground-based occluder prism, in local scene coordinates.
#[derive(Clone, Debug)]
pub struct Occluder {
    /// Rings (exterior and holes), open.
    pub rings: Vec<Vec<DVec2>>,
    pub height: f64,
    pub min: DVec2,
    pub max: DVec2,
    /// The object whose inner bound this prism is.
    pub object: u32,
}

/// The bucket of `v` on an axis of `n` buckets of `1 / inv_m` metres from `origin`,
/// clamped to the grid. `as` saturates: below the origin (and NaN) is bucket 0, as
/// floor-then-clamp. A product, not a quotient (the division was a third of the cost of
/// the walks over the hidden boxes): monotone in `v` all the same, so a box is met by
/// every walk over a range it overlaps as long as both use this function; near a bucket
/// border the two may differ by an ulp, which only decides in which of two neighbouring
/// buckets a point lying on the border is looked up.
#[inline]
pub fn bucket_of(v: f64, origin: f64, inv_m: f64, n: usize) -> usize {
    (((v - origin) * inv_m) as usize).min(n - 1)
}

/// Marks of the ids met by the current walk of a [`BucketGrid`] (an id listed in several
/// buckets is handled once): [`Stamps::next`] starts a walk by taking a new generation,
/// so the marks are cleared only when the ids outgrow them or the generation wraps.
#[derive(Clone, Debug, Default)]
pub struct Stamps {
    pub marks: Vec<u32>,
    gen: u32,
}

impl Stamps {
    /// A new walk over ids `0..len`: its generation.
    pub fn next(&mut self, len: usize) -> u32 {
        // Grown (geometrically: the hidden boxes grow during a traversal) with marks 0,
        // older than any generation handed out after it.
        if self.marks.len() < len {
            let n = len.max(2 * self.marks.len());
            self.marks.resize(n, 0);
        }
        self.gen = self.gen.wrapping_add(1);
        if self.gen == 0 {
            self.marks.fill(0);
            self.gen = 1;
        }
        self.gen
    }
}

/// A uniform grid of the ids of boxes (slabs, prisms) over the scene, in local
/// coordinates: each id is in every bucket its box meets.
#[derive(Clone, Debug)]
pub struct BucketGrid {
    pub origin: DVec2,
    pub cell_m: f64,
    /// `1 / cell_m`.
    pub inv_m: f64,
    pub nx: usize,
    pub ny: usize,
    /// CSR: bucket `i` holds `ids[start[i]..start[i + 1]]`.
    pub start: Vec<u32>,
    pub ids: Vec<u32>,
}

impl BucketGrid {
    /// The grid of `boxes` (`(min, max)`, id = index), with buckets of
    /// `cell_m(extent, count)` metres.
    pub fn from_boxes(boxes: &[(DVec2, DVec2)], cell_m: impl FnOnce(DVec2, usize) -> f64) -> Self {
        let mut min = DVec2::splat(f64::INFINITY);
        let mut max = DVec2::splat(f64::NEG_INFINITY);
        for (a, b) in boxes {
            min = min.min(*a);
            max = max.max(*b);
        }
        if boxes.is_empty() {
            min = DVec2::ZERO;
            max = DVec2::ONE;
        }
        let ext = (max - min).max(DVec2::splat(1.0));
        let cell_m = cell_m(ext, boxes.len());
        let nx = ((ext.x / cell_m).ceil() as usize).max(1);
        let ny = ((ext.y / cell_m).ceil() as usize).max(1);
        let mut grid = BucketGrid {
            origin: min,
            cell_m,
            inv_m: 1.0 / cell_m,
            nx,
            ny,
            start: vec![0; nx * ny + 1],
            ids: Vec::new(),
        };
        let range = |g: &BucketGrid, (a, b): &(DVec2, DVec2)| {
            (g.col(a.x), g.col(b.x), g.row(a.y), g.row(b.y))
        };
        for bx in boxes {
            let (c0, c1, r0, r1) = range(&grid, bx);
            for r in r0..=r1 {
                for c in c0..=c1 {
                    grid.start[r * nx + c + 1] += 1;
                }
            }
        }
        for i in 0..nx * ny {
            grid.start[i + 1] += grid.start[i];
        }
        let mut fill = grid.start.clone();
        grid.ids = vec![0; grid.start[nx * ny] as usize];
        for (id, bx) in boxes.iter().enumerate() {
            let (c0, c1, r0, r1) = range(&grid, bx);
            for r in r0..=r1 {
                for c in c0..=c1 {
                    let b = r * nx + c;
                    grid.ids[fill[b] as usize] = id as u32;
                    fill[b] += 1;
                }
            }
        }
        grid
    }

    /// Per bucket, the largest `value` of its ids (−∞ for an empty bucket).
    pub fn max_per_bucket(&self, value: impl Fn(u32) -> f64) -> Vec<f64> {
        self.start
            .windows(2)
            .map(|w| {
                self.ids[w[0] as usize..w[1] as usize]
                    .iter()
                    .map(|&i| value(i))
                    .fold(f64::NEG_INFINITY, f64::max)
            })
            .collect()
    }

    #[inline]
    pub fn col(&self, x: f64) -> usize {
        bucket_of(x, self.origin.x, self.inv_m, self.nx)
    }
    #[inline]
    pub fn row(&self, y: f64) -> usize {
        bucket_of(y, self.origin.y, self.inv_m, self.ny)
    }
    #[inline]
    pub fn bucket(&self, c: usize, r: usize) -> &[u32] {
        let i = r * self.nx + c;
        &self.ids[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

/// The inner prisms of `scene` that can occlude, with their object's id, in object
/// order.
pub fn inner_prisms(scene: &Scene) -> impl Iterator<Item = (u32, &Prism)> {
    scene.objects.iter().enumerate().flat_map(|(id, o)| {
        o.inner
            .iter()
            .filter(|p| is_solid(p))
            .map(move |p| (id as u32, p))
    })
}

/// The inner prisms of `scene` standing on the ground, with their object's id.
pub fn ground_prisms(scene: &Scene) -> impl Iterator<Item = (u32, &Prism)> {
    inner_prisms(scene).filter(|(_, p)| stands_on_ground(p))
}

/// Whether the prism stands on the ground (`base <= GROUND_M`).
pub fn stands_on_ground(p: &Prism) -> bool {
    p.base <= GROUND_M
}

/// A finite top above the base and the ground, and a finite footprint with an exterior
/// ring.
fn is_solid(p: &Prism) -> bool {
    p.top > p.base
        && p.top.is_finite()
        && p.top > GROUND_M
        && p.footprint.exterior.len() >= 3
        && p.footprint.rings().flatten().all(|v| v.is_finite())
}

/// The ground prisms ([`ground_prisms`]) as occluders, translated by `-origin`.
pub fn collect_occluders(scene: &Scene, origin: DVec2) -> Vec<Occluder> {
    ground_prisms(scene)
        .map(|(object, p)| {
            let rings = local_rings(&p.footprint, origin);
            let mut min = DVec2::splat(f64::INFINITY);
            let mut max = DVec2::splat(f64::NEG_INFINITY);
            for v in rings.iter().flatten() {
                min = min.min(*v);
                max = max.max(*v);
            }
            Occluder {
                rings,
                height: p.top,
                min,
                max,
                object,
            }
        })
        .collect()
}

/// The origin of the methods' local frame for `scene` (coordinates minus it keep their
/// precision when the scene's own coordinates are large): the centre of its bounds,
/// rounded to the metre.
pub fn local_origin(scene: &Scene) -> DVec2 {
    if scene.bounds.is_empty() {
        DVec2::ZERO
    } else {
        scene.bounds.center().truncate().round()
    }
}

/// The rings (exterior and holes, at least 3 vertices) of `footprint` translated by
/// `-origin`.
pub fn local_rings(footprint: &Polygon, origin: DVec2) -> Vec<Vec<DVec2>> {
    footprint
        .rings()
        .filter(|r| r.len() >= 3)
        .map(|r| r.iter().map(|v| *v - origin).collect())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Object;

    /// A prism a micrometre above the ground is raised (the gap under it stays open);
    /// flat and inverted prisms occlude nothing.
    #[test]
    fn only_prisms_exactly_on_the_ground_stand_on_it() {
        let rect = Polygon::rect(DVec2::new(0.0, 0.0), DVec2::new(10.0, 10.0));
        let prism = |base: f64, top: f64| Prism::new(rect.clone(), base, top);
        let scene = Scene::from_objects(vec![
            Object::blocks(None, vec![prism(0.0, 10.0)]),
            Object::blocks(None, vec![prism(1e-6, 10.0)]),
            Object::blocks(None, vec![prism(3.0, 10.0), prism(0.0, 0.0)]),
            Object::blocks(None, vec![prism(5.0, 2.0), prism(0.0, f64::INFINITY)]),
        ]);
        let ids = |it: &mut dyn Iterator<Item = (u32, &Prism)>| -> Vec<(u32, f64)> {
            it.map(|(id, p)| (id, p.base)).collect()
        };
        assert_eq!(
            ids(&mut inner_prisms(&scene)),
            vec![(0, 0.0), (1, 1e-6), (2, 3.0)]
        );
        assert_eq!(ids(&mut ground_prisms(&scene)), vec![(0, 0.0)]);
        let occ = collect_occluders(&scene, DVec2::new(5.0, 5.0));
        assert_eq!(occ.len(), 1);
        assert_eq!((occ[0].object, occ[0].height), (0, 10.0));
        assert_eq!(
            (occ[0].min, occ[0].max),
            (DVec2::splat(-5.0), DVec2::splat(5.0))
        );
    }
}
