//! The occluder model shared by `dual-ray`, the seed and the erosion family: the
//! ground-based prisms of every object's inner bound, in a local frame centred on the
//! scene, and a uniform bucket grid over boxes.
//!
//! Only prisms standing on the ground (`base <= GROUND_EPS_M`) occlude: Observation 1 of
//! Koltun et al. 2001 needs occluders that contain the vertical wall under their top, and
//! the seed's 2.5D horizon relies on the same. Raised prisms (arcades, overhangs) are
//! ignored, which is conservative: an occluder left out can only make more visible.

use sightline_geom::{DVec2, Polygon};
use sightline_scene::Scene;

/// A prism whose base is at most this high counts as standing on the ground.
pub(crate) const GROUND_EPS_M: f64 = 1e-6;

/// One ground-based occluder prism, in local scene coordinates.
#[derive(Clone, Debug)]
pub(crate) struct Occluder {
    /// Rings (exterior and holes), open.
    pub rings: Vec<Vec<DVec2>>,
    pub height: f64,
    pub min: DVec2,
    pub max: DVec2,
    /// The object whose inner bound this prism is.
    pub object: u32,
}

/// A uniform grid of the ids of boxes (slabs, prisms) over the scene, in local
/// coordinates: each id is in every bucket its box meets.
#[derive(Clone, Debug)]
pub(crate) struct BucketGrid {
    pub origin: DVec2,
    pub cell_m: f64,
    pub nx: usize,
    pub ny: usize,
    /// CSR: bucket `i` holds `ids[start[i]..start[i + 1]]`.
    pub start: Vec<u32>,
    pub ids: Vec<u32>,
}

impl BucketGrid {
    /// The grid of `boxes` (`(min, max)`, id = index), with buckets of
    /// `cell_m(extent, count)` metres.
    pub(crate) fn from_boxes(
        boxes: &[(DVec2, DVec2)],
        cell_m: impl FnOnce(DVec2, usize) -> f64,
    ) -> Self {
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
    pub(crate) fn max_per_bucket(&self, value: impl Fn(u32) -> f64) -> Vec<f64> {
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
    pub(crate) fn col(&self, x: f64) -> usize {
        (((x - self.origin.x) / self.cell_m).floor().max(0.0) as usize).min(self.nx - 1)
    }
    #[inline]
    pub(crate) fn row(&self, y: f64) -> usize {
        (((y - self.origin.y) / self.cell_m).floor().max(0.0) as usize).min(self.ny - 1)
    }
    #[inline]
    pub(crate) fn bucket(&self, c: usize, r: usize) -> &[u32] {
        let i = r * self.nx + c;
        &self.ids[self.start[i] as usize..self.start[i + 1] as usize]
    }
}

/// Collect the ground-based occluder prisms of every object's inner bound, translated by
/// `-origin`.
pub(crate) fn collect_occluders(scene: &Scene, origin: DVec2) -> Vec<Occluder> {
    let mut out = Vec::new();
    for (id, o) in scene.objects.iter().enumerate() {
        for p in &o.inner {
            if p.base > GROUND_EPS_M || p.top <= GROUND_EPS_M || !p.top.is_finite() {
                continue;
            }
            let rings = local_rings(&p.footprint, origin);
            if rings.is_empty() || rings.iter().flatten().any(|v| !v.is_finite()) {
                continue;
            }
            let mut min = DVec2::splat(f64::INFINITY);
            let mut max = DVec2::splat(f64::NEG_INFINITY);
            for v in rings.iter().flatten() {
                min = min.min(*v);
                max = max.max(*v);
            }
            out.push(Occluder {
                rings,
                height: p.top,
                min,
                max,
                object: id as u32,
            });
        }
    }
    out
}

/// The origin of the methods' local frame for `scene` (coordinates minus it keep their
/// precision when the scene's own coordinates are large): the centre of its bounds,
/// rounded to the metre.
pub(crate) fn local_origin(scene: &Scene) -> DVec2 {
    if scene.bounds.is_empty() {
        DVec2::ZERO
    } else {
        scene.bounds.center().truncate().round()
    }
}

/// The rings (exterior and holes, at least 3 vertices) of `footprint` translated by
/// `-origin`.
pub(crate) fn local_rings(footprint: &Polygon, origin: DVec2) -> Vec<Vec<DVec2>> {
    footprint
        .rings()
        .filter(|r| r.len() >= 3)
        .map(|r| r.iter().map(|v| *v - origin).collect())
        .collect()
}
