//! Boxes proven hidden from the cell, used as occluders by the tests that come after them:
//! the *virtual occluders* of Koltun, Chrysanthou & Cohen-Or (*Virtual occluders: an
//! efficient intermediate PVS representation*, EGWR 2000, §3), obtained for free from the
//! traversal itself.
//!
//! **Why a hidden box occludes.** A box-to-box test (§3–§5 of Koltun et al. 2001) that
//! answers "hidden" for a box `H` proves that every segment from a point of the cell to a
//! point of `H` meets a real occluder; it decides from `H`'s footprint and top only, so
//! the proof holds for the whole column `H' = footprint(H) × (−∞, top(H)]`. A later
//! segment from the cell to any farther box that passes through `H'` is therefore blocked
//! before it reaches `H'`. So `H'` is a 2.5D occluder standing on the ground like the
//! buildings (Observation 1 holds for it), and its cut by a ceiling `T` is the rectangle
//! of its footprint where `T < top(H)`: a convex piece of the planar problem. Adding such
//! pieces can only hide more, and only what is hidden: the PVS keeps its guarantee. A
//! hidden kd-node is much larger than the buildings in it (streets, courtyards and the air
//! between roofs included), so a few of them stand for the thousands of slabs a long shaft
//! crosses.
//!
//! **Front to back.** The traversal visits the nearer child of a node first, so what it
//! proves hidden occludes the farther one (the accumulated occlusion of §3's
//! hierarchical traversal).
//!
//! **Slabs under a hidden box.** A slab whose every part in a bucket lies under the top of
//! a hidden box covering the bucket adds nothing the box's piece does not block: the
//! gathers skip such buckets ([`Cover`]). A slab reaching out of the bucket is still met
//! in its other buckets; only pieces are dropped, so skipping never hides anything more.
//!
//! The set depends on the cell and on the order of the tests, which is fixed; the exact
//! planar method proves hidden every box the discretized one does (or an ancestor of it),
//! so the region its set covers contains the discretized one's at every step, and
//! `dual-ray` keeps containing `dual-ray-exact` (property-tested).

use super::occluders::{local_rect, Axis, Decomposition, Rect};
use sightline_geom::{Aabb3, DVec2};
use sightline_scene::occluders::{bucket_of, BucketGrid};

/// Fine buckets of the occluder grid per cover cell, along each side.
pub(crate) const COVER_FACTOR: usize = 4;

/// No hidden box covers the cell.
const NONE: u32 = u32::MAX;

/// A grid over one decomposition's buckets, [`COVER_FACTOR`] buckets a side: per cell,
/// the tallest hidden box whose footprint contains the whole cell (its top and index).
pub(crate) struct Cover {
    origin: DVec2,
    cell_m: f64,
    /// `1 / cell_m`.
    inv_m: f64,
    nx: usize,
    ny: usize,
    top: Vec<f64>,
    owner: Vec<u32>,
}

impl Cover {
    fn new(g: &BucketGrid) -> Self {
        let nx = g.nx.div_ceil(COVER_FACTOR);
        let ny = g.ny.div_ceil(COVER_FACTOR);
        Cover {
            origin: g.origin,
            cell_m: g.cell_m * COVER_FACTOR as f64,
            inv_m: 1.0 / (g.cell_m * COVER_FACTOR as f64),
            nx,
            ny,
            top: vec![f64::NEG_INFINITY; nx * ny],
            owner: vec![NONE; nx * ny],
        }
    }

    /// Record box `id` (footprint `r` in the decomposition's frame, top `top`) in every
    /// cell its footprint contains.
    fn insert(&mut self, r: &Rect, top: f64, id: u32) {
        let span = |a: f64, b: f64, o: f64, n: usize| {
            let lo = ((a - o) / self.cell_m).ceil().max(0.0);
            let hi = ((b - o) / self.cell_m).floor().min(n as f64);
            (lo as usize, hi.max(lo) as usize)
        };
        let (c0, c1) = span(r.x0, r.x1, self.origin.x, self.nx);
        let (r0, r1) = span(r.y0, r.y1, self.origin.y, self.ny);
        for row in r0..r1 {
            for c in c0..c1 {
                let i = row * self.nx + c;
                if top > self.top[i] {
                    self.top[i] = top;
                    self.owner[i] = id;
                }
            }
        }
    }

    /// The top of the hidden box covering the occluder grid's bucket `(c, r)` (−∞: none).
    #[inline]
    pub(crate) fn top_of_bucket(&self, c: usize, r: usize) -> f64 {
        self.top[(r / COVER_FACTOR) * self.nx + c / COVER_FACTOR]
    }

    #[inline]
    fn col(&self, x: f64) -> usize {
        bucket_of(x, self.origin.x, self.inv_m, self.nx)
    }

    #[inline]
    fn row(&self, y: f64) -> usize {
        bucket_of(y, self.origin.y, self.inv_m, self.ny)
    }

    /// Visit the boxes covering the cells over `[x0, x1]` whose rows meet `rows(cx0,
    /// cx1)` and whose box rises above `floor(cx0, cx1)` there (ids may repeat).
    pub(crate) fn visit(
        &self,
        (x0, x1): (f64, f64),
        rows: impl Fn(f64, f64) -> (f64, f64),
        floor: impl Fn(f64, f64) -> f64,
        mut visit: impl FnMut(u32),
    ) {
        if !(x0 <= x1) {
            return;
        }
        for c in self.col(x0)..=self.col(x1) {
            let cx0 = (self.origin.x + c as f64 * self.cell_m).max(x0);
            let cx1 = (self.origin.x + (c + 1) as f64 * self.cell_m).min(x1);
            let (ylo, yhi) = rows(cx0, cx1);
            let f = floor(cx0, cx1);
            for r in self.row(ylo)..=self.row(yhi) {
                let i = r * self.nx + c;
                if self.owner[i] != NONE && self.top[i] > f {
                    visit(self.owner[i]);
                }
            }
        }
    }
}

/// The boxes proven hidden from one cell so far, with a [`Cover`] per axis.
pub(crate) struct HiddenSet {
    pub boxes: Vec<Aabb3>,
    x: Cover,
    y: Cover,
}

impl HiddenSet {
    pub(crate) fn new(dx: &Decomposition, dy: &Decomposition) -> Self {
        HiddenSet {
            boxes: Vec::new(),
            x: Cover::new(&dx.grid),
            y: Cover::new(&dy.grid),
        }
    }

    /// Record `b`, proven hidden from the cell.
    pub(crate) fn insert(&mut self, b: &Aabb3) {
        if b.is_empty() || !(b.min.is_finite() && b.max.is_finite()) {
            return;
        }
        let id = self.boxes.len() as u32;
        self.boxes.push(*b);
        self.x.insert(&local_rect(b, Axis::X), b.max.z, id);
        self.y.insert(&local_rect(b, Axis::Y), b.max.z, id);
    }

    pub(crate) fn cover(&self, axis: Axis) -> &Cover {
        match axis {
            Axis::X => &self.x,
            Axis::Y => &self.y,
        }
    }
}
