//! Fused 2.5D occluders, decomposed into slabs along each axis.
//!
//! The planar problems of §4 (Koltun et al. 2001) cut the occluders by the ceiling plane
//! `T` of a shaft. Touching buildings must act as one occluder there: a
//! party wall whose line is a ray of the shaft would otherwise leave a crack in the dual
//! ray space. We therefore prepare, once per scene and per axis, a *vertical
//! decomposition* of the fused height field of every cluster of touching buildings:
//!
//! * a **cluster** is a connected component of ground-based occluder prisms whose
//!   bounding rectangles touch or overlap;
//! * a cluster is cut into **slabs** by the lines `x = const` through all its vertices
//!   and edge crossings (here `x` is the *along* coordinate of the axis, `y` the across
//!   one);
//! * inside a slab the edges do not cross, so the cross-section is a stack of
//!   trapezoids ([`Trap`]) of constant height `h`, bottom to top, each flagged when it
//!   touches the one below (no gap between them: they belong to the same fused
//!   occluder).
//!
//! Pieces of one cluster therefore only ever meet along `x = const` lines or inside a
//! stack, and a stack is fused at query time (by the planar problems of `plane`). Lines
//! `x = const` are never rays of a shaft along `x`, so no crack can appear there.
//!
//! The prisms are the shared ground-based ones of [`sightline_scene::occluders`] (Observation 1 of
//! the paper needs occluders that contain the vertical wall under their top).

use sightline_geom::{orient2d, Aabb3, DVec2, Orientation};
use sightline_scene::occluders::{BucketGrid, Occluder};

/// Two edges of a stack closer than this (at both slab ends) are the same wall: a party
/// wall between touching buildings. One nanometre: float noise, not a gap anyone sees.
pub(crate) const TOUCH_EPS_M: f64 = 1e-9;

/// The two axes a shaft can run along.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Axis {
    X,
    Y,
}

impl Axis {
    /// Scene `(x, y)` to `(along, across)`.
    #[inline]
    pub(crate) fn to_local(self, p: DVec2) -> DVec2 {
        match self {
            Axis::X => p,
            Axis::Y => DVec2::new(p.y, p.x),
        }
    }
}

/// A rectangle `[x0, x1] × [y0, y1]` in local (along, across) coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Rect {
    pub x0: f64,
    pub x1: f64,
    pub y0: f64,
    pub y1: f64,
}

impl Default for Rect {
    fn default() -> Self {
        Rect {
            x0: 0.0,
            x1: 0.0,
            y0: 0.0,
            y1: 0.0,
        }
    }
}

/// The rectangle of a box in `axis`-local coordinates, translated by `-origin`.
pub(crate) fn local_rect(b: &Aabb3, axis: Axis) -> Rect {
    let (p, q) = (
        axis.to_local(b.min.truncate()),
        axis.to_local(b.max.truncate()),
    );
    Rect {
        x0: p.x,
        x1: q.x,
        y0: p.y,
        y1: q.y,
    }
}

/// A trapezoid of a slab: between the lines `bot` and `top` (y at the slab's `x0` and
/// `x1`), of constant height `h`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Trap {
    pub bot: [f64; 2],
    pub top: [f64; 2],
    pub h: f64,
    /// No gap between this trapezoid and the previous one of the stack.
    pub touches_prev: bool,
}

/// A slab of a cluster: `x0 < x1`, trapezoids `traps[first..first + len]` bottom to top.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Slab {
    pub x0: f64,
    pub x1: f64,
    pub y_min: f64,
    pub y_max: f64,
    pub h_max: f64,
    pub first: u32,
    pub len: u32,
}

/// The vertical decomposition of every cluster along one axis.
#[derive(Clone, Debug)]
pub(crate) struct Decomposition {
    pub slabs: Vec<Slab>,
    pub traps: Vec<Trap>,
    pub grid: BucketGrid,
    /// Tallest slab (`h_max`) per bucket of `grid`.
    pub bucket_top: Vec<f64>,
}

/// Connected components of occluders whose bounding rectangles touch (closed overlap).
pub(crate) fn clusters(occ: &[Occluder]) -> Vec<Vec<u32>> {
    let n = occ.len();
    let mut parent: Vec<u32> = (0..n as u32).collect();
    fn find(p: &mut [u32], mut i: u32) -> u32 {
        while p[i as usize] != i {
            p[i as usize] = p[p[i as usize] as usize];
            i = p[i as usize];
        }
        i
    }
    let mut order: Vec<u32> = (0..n as u32).collect();
    order.sort_by(|a, b| occ[*a as usize].min.x.total_cmp(&occ[*b as usize].min.x));
    let mut active: Vec<u32> = Vec::new();
    for &i in &order {
        let oi = &occ[i as usize];
        active.retain(|&j| occ[j as usize].max.x >= oi.min.x);
        for &j in &active {
            let oj = &occ[j as usize];
            if oj.min.y <= oi.max.y && oi.min.y <= oj.max.y {
                let (a, b) = (find(&mut parent, i), find(&mut parent, j));
                if a != b {
                    parent[a as usize] = b;
                }
            }
        }
        active.push(i);
    }
    let mut groups: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    for i in 0..n as u32 {
        let r = find(&mut parent, i);
        groups.entry(r).or_default().push(i);
    }
    groups.into_values().collect()
}

/// An edge with `a.x < b.x` (canonical direction, so the same wall seen from two
/// buildings interpolates to bit-identical values).
#[derive(Clone, Copy, Debug)]
struct Edge {
    a: DVec2,
    b: DVec2,
    owner: u32,
}

impl Edge {
    #[inline]
    fn y_at(&self, x: f64) -> f64 {
        if x <= self.a.x {
            self.a.y
        } else if x >= self.b.x {
            self.b.y
        } else {
            self.a.y + (x - self.a.x) * (self.b.y - self.a.y) / (self.b.x - self.a.x)
        }
    }
}

/// Decompose every cluster along `axis`.
pub(crate) fn decompose(occ: &[Occluder], clusters: &[Vec<u32>], axis: Axis) -> Decomposition {
    let mut slabs = Vec::new();
    let mut traps = Vec::new();
    for cl in clusters {
        decompose_cluster(occ, cl, axis, &mut slabs, &mut traps);
    }
    let grid = build_grid(&slabs);
    let bucket_top = grid.max_per_bucket(|i| slabs[i as usize].h_max);
    Decomposition {
        slabs,
        traps,
        grid,
        bucket_top,
    }
}

fn decompose_cluster(
    occ: &[Occluder],
    cluster: &[u32],
    axis: Axis,
    slabs: &mut Vec<Slab>,
    traps: &mut Vec<Trap>,
) {
    let mut edges: Vec<Edge> = Vec::new();
    let mut xs: Vec<f64> = Vec::new();
    for (k, &oi) in cluster.iter().enumerate() {
        for ring in &occ[oi as usize].rings {
            let n = ring.len();
            for i in 0..n {
                let p = axis.to_local(ring[i]);
                let q = axis.to_local(ring[(i + 1) % n]);
                xs.push(p.x);
                if p.x == q.x {
                    continue; // parallel to the slab lines: never crosses a slab's interior
                }
                let (a, b) = if p.x < q.x { (p, q) } else { (q, p) };
                edges.push(Edge {
                    a,
                    b,
                    owner: k as u32,
                });
            }
        }
    }
    // Proper crossings between edges (overlapping building parts, bad data): the slab
    // lines through them keep the edges of each slab in a fixed vertical order.
    let mut by_x: Vec<u32> = (0..edges.len() as u32).collect();
    by_x.sort_by(|i, j| edges[*i as usize].a.x.total_cmp(&edges[*j as usize].a.x));
    for (k, &i) in by_x.iter().enumerate() {
        let e = edges[i as usize];
        for &j in &by_x[k + 1..] {
            let f = edges[j as usize];
            if f.a.x >= e.b.x {
                break;
            }
            if e.a.y.max(e.b.y) < f.a.y.min(f.b.y) || f.a.y.max(f.b.y) < e.a.y.min(e.b.y) {
                continue;
            }
            if let Some(x) = proper_crossing_x(&e, &f) {
                xs.push(x);
            }
        }
    }
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    let owners = cluster.len();
    let heights: Vec<f64> = cluster.iter().map(|&i| occ[i as usize].height).collect();
    let mut inside = vec![false; owners];
    let mut inside_list: Vec<u32> = Vec::new();
    let mut active: Vec<(f64, f64, f64, u32)> = Vec::new(); // (y mid, y0, y1, owner)
    for w in xs.windows(2) {
        let (x0, x1) = (w[0], w[1]);
        if x1 <= x0 {
            continue;
        }
        active.clear();
        let xm = 0.5 * (x0 + x1);
        for e in &edges {
            if e.a.x <= x0 && e.b.x >= x1 {
                active.push((e.y_at(xm), e.y_at(x0), e.y_at(x1), e.owner));
            }
        }
        if active.len() < 2 {
            continue;
        }
        active.sort_by(|p, q| p.0.total_cmp(&q.0));
        inside_list.clear();
        for f in inside.iter_mut() {
            *f = false;
        }
        let first = traps.len() as u32;
        let mut chain_open = false; // the last emitted trap can still touch the next
        let mut h_max: f64 = 0.0;
        for k in 0..active.len() - 1 {
            let owner = active[k].3 as usize;
            inside[owner] = !inside[owner];
            if inside[owner] {
                inside_list.push(owner as u32);
            } else {
                inside_list.retain(|&o| o as usize != owner);
            }
            let (lo, hi) = (active[k], active[k + 1]);
            let bot = [lo.1, lo.2];
            let mut top = [hi.1, hi.2];
            // Rounding at a crossing may invert the order at one slab end by an ulp.
            top[0] = top[0].max(bot[0]);
            top[1] = top[1].max(bot[1]);
            let zero_width = top[0] - bot[0] <= TOUCH_EPS_M && top[1] - bot[1] <= TOUCH_EPS_M;
            let h = inside_list
                .iter()
                .map(|&o| heights[o as usize])
                .fold(0.0, f64::max);
            if h <= 0.0 {
                if !zero_width {
                    chain_open = false;
                }
                continue;
            }
            if zero_width {
                continue; // a wall between two fused parts, or a sliver: keeps the chain
            }
            // Merge with the previous trap when it touches and has the same height.
            if chain_open {
                let last = traps.last_mut().expect("chain_open implies a trap");
                if last.h == h {
                    last.top = top;
                    continue;
                }
            }
            traps.push(Trap {
                bot,
                top,
                h,
                touches_prev: chain_open,
            });
            h_max = h_max.max(h);
            chain_open = true;
        }
        let len = traps.len() as u32 - first;
        if len == 0 {
            continue;
        }
        let ts = &traps[first as usize..];
        let y_min = ts
            .iter()
            .map(|t| t.bot[0].min(t.bot[1]))
            .fold(f64::INFINITY, f64::min);
        let y_max = ts
            .iter()
            .map(|t| t.top[0].max(t.top[1]))
            .fold(f64::NEG_INFINITY, f64::max);
        slabs.push(Slab {
            x0,
            x1,
            y_min,
            y_max,
            h_max,
            first,
            len,
        });
    }
}

/// The x of a proper crossing of two edges (interiors cross), decided robustly.
fn proper_crossing_x(e: &Edge, f: &Edge) -> Option<f64> {
    let side = |o: Orientation| match o {
        Orientation::Left => 1,
        Orientation::Right => -1,
        Orientation::Collinear => 0,
    };
    let d1 = side(orient2d(e.a, e.b, f.a));
    let d2 = side(orient2d(e.a, e.b, f.b));
    let d3 = side(orient2d(f.a, f.b, e.a));
    let d4 = side(orient2d(f.a, f.b, e.b));
    if d1 * d2 >= 0 || d3 * d4 >= 0 {
        return None;
    }
    let r = e.b - e.a;
    let s = f.b - f.a;
    let den = r.perp_dot(s);
    if den == 0.0 {
        return None;
    }
    let t = (f.a - e.a).perp_dot(s) / den;
    Some((e.a.x + t * r.x).clamp(e.a.x.max(f.a.x), e.b.x.min(f.b.x)))
}

fn build_grid(slabs: &[Slab]) -> BucketGrid {
    let boxes: Vec<(DVec2, DVec2)> = slabs
        .iter()
        .map(|s| (DVec2::new(s.x0, s.y_min), DVec2::new(s.x1, s.y_max)))
        .collect();
    // About 16 m buckets, at most 2048 per side.
    BucketGrid::from_boxes(&boxes, |ext, _| (ext.x.max(ext.y) / 2048.0).max(16.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect_occ(x0: f64, y0: f64, x1: f64, y1: f64, h: f64) -> Occluder {
        Occluder {
            rings: vec![vec![
                DVec2::new(x0, y0),
                DVec2::new(x1, y0),
                DVec2::new(x1, y1),
                DVec2::new(x0, y1),
            ]],
            height: h,
            min: DVec2::new(x0, y0),
            max: DVec2::new(x1, y1),
            object: 0,
        }
    }

    #[test]
    fn touching_buildings_fuse_into_one_stack() {
        // Two row houses sharing the party wall y = 10.
        let occ = vec![
            rect_occ(0.0, 0.0, 10.0, 10.0, 8.0),
            rect_occ(0.0, 10.0, 10.0, 20.0, 8.0),
        ];
        let cl = clusters(&occ);
        assert_eq!(cl.len(), 1);
        let d = decompose(&occ, &cl, Axis::X);
        assert_eq!(d.slabs.len(), 1);
        // Same height: merged into a single trapezoid spanning both.
        assert_eq!(d.slabs[0].len, 1);
        let t = d.traps[0];
        assert_eq!((t.bot, t.top, t.h), ([0.0, 0.0], [20.0, 20.0], 8.0));
    }

    #[test]
    fn different_heights_stay_separate_but_touch() {
        let occ = vec![
            rect_occ(0.0, 0.0, 10.0, 10.0, 8.0),
            rect_occ(0.0, 10.0, 10.0, 20.0, 20.0),
        ];
        let cl = clusters(&occ);
        let d = decompose(&occ, &cl, Axis::X);
        assert_eq!(d.slabs[0].len, 2);
        assert!(!d.traps[0].touches_prev);
        assert!(d.traps[1].touches_prev);
        assert_eq!(d.traps[1].h, 20.0);
    }

    #[test]
    fn gap_breaks_the_chain_and_overlap_takes_the_max() {
        let occ = vec![
            rect_occ(0.0, 0.0, 10.0, 10.0, 8.0),
            rect_occ(0.0, 11.0, 10.0, 20.0, 8.0),
            rect_occ(2.0, 5.0, 8.0, 15.0, 30.0), // tower overlapping both
        ];
        let cl = clusters(&occ);
        assert_eq!(cl.len(), 1);
        let d = decompose(&occ, &cl, Axis::Y);
        // Along y the slabs are y in [0,5],[5,10],[10,11],[11,15],[15,20].
        assert_eq!(d.slabs.len(), 5);
        let s = d.slabs[2]; // y in [10, 11]: only the tower, across x in [2, 8]
        assert_eq!(s.len, 1);
        let t = d.traps[s.first as usize];
        assert_eq!((t.bot[0], t.top[0], t.h), (2.0, 8.0, 30.0));
    }
}
