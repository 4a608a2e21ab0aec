//! Conservative voxelization: surface voxels (touched by a triangle), components of
//! untouched voxels, and which components are solid.
//!
//! * A voxel is **surface** when a triangle meets the closed voxel grown by a hair
//!   (`TOUCH_EPS` of the voxel size): a line may pass beside the triangle inside it,
//!   so surface voxels are open.
//! * The grid's **border layer** lies just outside the scene's bounding box; no
//!   segment between two points of the (convex) box enters it, so it is solid, and it
//!   is closed before anything else.
//! * Untouched voxels inside the border are flood-filled into components through
//!   shared faces.
//! * A component is **solid** when rays cast from its boundary voxels (those next to a
//!   surface voxel; 14 directions, 6 axes and 8 diagonals) first hit the *back* of a
//!   triangle: at least one back hit and at most `backface_tolerance` of the hits on
//!   a front. From inside closed geometry a ray can only meet the back of the
//!   surface that encloses it, so an enclosed region is solid, and a region that sees
//!   the front of the geometry is air. Rays that leave the grid do not vote.
//! * A component next to the border layer is an **outside** region. It too becomes
//!   solid when it only sees back faces: the outside of a sealed indoor level, the
//!   void qbsp fills, or the inside of walls whose tops meet the bounding box unclosed.
//!   When such a region sees the back of the geometry and yet stays air (it also sees
//!   fronts: the level's inside), the level **leaks**: reported with a voxel path from
//!   a voxel that saw a front face to the border, as qbsp does.

use rayon::prelude::*;
use sightline_geom::DVec3;
use std::collections::VecDeque;

/// Grow voxels by this fraction of their size in the touch test (errs towards surface).
pub const TOUCH_EPS: f64 = 1e-4;

/// Voxel states.
pub const AIR: u8 = 0;
pub const SURFACE: u8 = 1;
pub const SOLID: u8 = 2;
/// Open (air or surface) yet out of sight: no chain of open voxels through open faces
/// joins it to a viewpoint (an air voxel that meets a front).
pub const SEALED: u8 = 3;

/// A regular grid of cubes.
#[derive(Clone, Debug)]
pub struct Grid {
    pub origin: DVec3,
    pub size: f64,
    pub dims: [usize; 3],
}

impl Grid {
    pub fn len(&self) -> usize {
        self.dims[0] * self.dims[1] * self.dims[2]
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    #[inline]
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        x + self.dims[0] * (y + self.dims[1] * z)
    }
    #[inline]
    pub fn coords(&self, i: usize) -> [usize; 3] {
        let x = i % self.dims[0];
        let r = i / self.dims[0];
        [x, r % self.dims[1], r / self.dims[1]]
    }
    pub fn voxel_min(&self, c: [usize; 3]) -> DVec3 {
        self.origin + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * self.size
    }
    pub fn center(&self, c: [usize; 3]) -> DVec3 {
        self.voxel_min(c) + DVec3::splat(self.size * 0.5)
    }
    /// The voxel holding `p`, if inside the grid.
    pub fn locate(&self, p: DVec3) -> Option<[usize; 3]> {
        let q = (p - self.origin) / self.size;
        let mut c = [0; 3];
        for k in 0..3 {
            if !(q[k] >= 0.0 && q[k] < self.dims[k] as f64) {
                return None;
            }
            c[k] = q[k] as usize;
        }
        Some(c)
    }
    fn on_border(&self, c: [usize; 3]) -> bool {
        (0..3).any(|k| c[k] == 0 || c[k] + 1 == self.dims[k])
    }
    /// Face neighbours of voxel `i`.
    pub fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let c = self.coords(i);
        (0..6).filter_map(move |f| {
            let k = f / 2;
            let mut d = c;
            if f % 2 == 0 {
                d[k] = d[k].checked_sub(1)?;
            } else {
                d[k] += 1;
                if d[k] >= self.dims[k] {
                    return None;
                }
            }
            Some(self.index(d[0], d[1], d[2]))
        })
    }
}

/// What the voxelizer found, for reports.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct VoxelStats {
    pub voxels: usize,
    pub surface: usize,
    pub air: usize,
    pub solid: usize,
    pub components: usize,
    pub solid_components: usize,
    /// Triangles skipped: zero area or not finite.
    pub degenerate_triangles: usize,
    /// Voxel faces inside an axis-aligned polygon of the surface (closed to sight).
    pub closed_faces: usize,
    /// Open voxels out of sight ([`SEALED`]): behind closed faces and solid voxels.
    pub sealed: usize,
}

/// A level that leaks: the outside sees the back of the geometry yet reaches a voxel
/// that sees a front face.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Leak {
    /// Centre of the inside voxel (it saw a front face).
    pub inside: [f64; 3],
    /// Centre of the void voxel the path ends at: next to the grid's border layer
    /// (just outside the scene's bounding box) and meeting no front face along the
    /// axes (any voxel next to the border layer when no such voxel is reachable).
    pub border: [f64; 3],
    /// Voxel centres from `inside` to `border`, face neighbours, all untouched.
    pub path: Vec<[f64; 3]>,
}

/// The voxelized level.
pub struct Voxels {
    pub grid: Grid,
    /// `AIR`, `SURFACE` or `SOLID` per voxel.
    pub state: Vec<u8>,
    /// Triangles touching each surface voxel: `tri_of[start[v]..start[v + 1]]`
    /// (compressed rows over every voxel).
    pub start: Vec<u32>,
    pub tri_of: Vec<u32>,
    pub stats: VoxelStats,
    pub leak: Option<Leak>,
    /// Air voxels that meet the front of a triangle along some axis: the viewpoints of
    /// the level (voxels in the void around it, which meet only backs or nothing, are
    /// not).
    pub sees_front: Vec<bool>,
    /// Bit `k`: the face towards the `+k` neighbour is closed ([`crate::faces`]).
    pub closed: Vec<u8>,
}

impl Voxels {
    pub fn triangles_in(&self, v: usize) -> &[u32] {
        &self.tri_of[self.start[v] as usize..self.start[v + 1] as usize]
    }
    /// Whether the face between voxel `v` and its `+k` neighbour is closed.
    pub fn face_closed(&self, v: usize, k: usize) -> bool {
        self.closed[v] & (1 << k) != 0
    }
    pub fn is_open(&self, v: usize) -> bool {
        self.state[v] == AIR || self.state[v] == SURFACE
    }
}

/// Triangle–box overlap by the separating axis theorem (Akenine-Möller 2001), box
/// given by centre and half size.
pub fn tri_box_overlap(center: DVec3, half: f64, tri: &[DVec3; 3]) -> bool {
    let v = tri.map(|p| p - center);
    let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
    // 9 cross axes.
    for ei in &e {
        for k in 0..3 {
            let mut axis = DVec3::ZERO;
            axis[k] = 1.0;
            let a = axis.cross(*ei);
            if a.length_squared() == 0.0 {
                continue;
            }
            let p = v.map(|q| q.dot(a));
            let r = half * (a.x.abs() + a.y.abs() + a.z.abs());
            let mn = p[0].min(p[1]).min(p[2]);
            let mx = p[0].max(p[1]).max(p[2]);
            if mn > r || mx < -r {
                return false;
            }
        }
    }
    // Box faces.
    let (mn, mx) = (v[0].min(v[1]).min(v[2]), v[0].max(v[1]).max(v[2]));
    if mn.max_element() > half || mx.min_element() < -half {
        return false;
    }
    // Triangle plane.
    let n = e[0].cross(e[1]);
    let d = n.dot(v[0]);
    let r = half * (n.x.abs() + n.y.abs() + n.z.abs());
    d.abs() <= r
}

/// Whether a triangle is usable: finite and of positive area.
pub fn is_proper(t: &[DVec3; 3]) -> bool {
    t.iter().all(|p| p.is_finite()) && (t[1] - t[0]).cross(t[2] - t[0]).length_squared() > 0.0
}

/// The voxels a triangle touches (conservatively): grid coordinates.
pub fn touched(grid: &Grid, t: &[DVec3; 3], out: &mut Vec<usize>) {
    out.clear();
    let eps = grid.size * TOUCH_EPS;
    let lo = t[0].min(t[1]).min(t[2]) - DVec3::splat(eps);
    let hi = t[0].max(t[1]).max(t[2]) + DVec3::splat(eps);
    let mut r0 = [0usize; 3];
    let mut r1 = [0usize; 3];
    for k in 0..3 {
        let a = ((lo[k] - grid.origin[k]) / grid.size).floor();
        let b = ((hi[k] - grid.origin[k]) / grid.size).floor();
        let top = grid.dims[k] as f64 - 1.0;
        r0[k] = a.clamp(0.0, top) as usize;
        r1[k] = b.clamp(0.0, top) as usize;
    }
    let half = grid.size * 0.5 + eps;
    for z in r0[2]..=r1[2] {
        for y in r0[1]..=r1[1] {
            for x in r0[0]..=r1[0] {
                if tri_box_overlap(grid.center([x, y, z]), half, t) {
                    out.push(grid.index(x, y, z));
                }
            }
        }
    }
}

/// Voxelize `tris` on `grid` and classify (module doc). `backface_tolerance` is the
/// share of front hits a component may have and still be solid.
pub fn voxelize(grid: Grid, tris: &[[DVec3; 3]], backface_tolerance: f64) -> Voxels {
    voxelize_with(grid, tris, backface_tolerance, false)
}

/// [`voxelize`], with rule 2 (`axis_rule`: voxels behind the geometry along every axis
/// that meets any are solid) when asked. Rule 2 is not conservative: on pandora it
/// closed open space next to the level's shell that the truth sees through.
pub fn voxelize_with(
    grid: Grid,
    tris: &[[DVec3; 3]],
    backface_tolerance: f64,
    axis_rule: bool,
) -> Voxels {
    let n = grid.len();
    let mut stats = VoxelStats {
        voxels: n,
        ..VoxelStats::default()
    };
    // Surface voxels and their triangles (pairs sorted by voxel → compressed rows).
    let mut pairs: Vec<(u32, u32)> = tris
        .par_iter()
        .enumerate()
        .fold(
            || (Vec::new(), Vec::new()),
            |(mut acc, mut buf): (Vec<(u32, u32)>, Vec<usize>), (i, t)| {
                if is_proper(t) {
                    touched(&grid, t, &mut buf);
                    acc.extend(buf.iter().map(|&v| (v as u32, i as u32)));
                }
                (acc, buf)
            },
        )
        .map(|(acc, _)| acc)
        .reduce(Vec::new, |mut a, mut b| {
            a.append(&mut b);
            a
        });
    stats.degenerate_triangles = tris.iter().filter(|t| !is_proper(t)).count();
    let closed = crate::faces::closed_faces(&grid, tris);
    stats.closed_faces = closed.iter().map(|b| b.count_ones() as usize).sum();
    pairs.par_sort_unstable();
    let mut start = vec![0u32; n + 1];
    for &(v, _) in &pairs {
        start[v as usize + 1] += 1;
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let tri_of: Vec<u32> = pairs.iter().map(|&(_, t)| t).collect();
    drop(pairs);
    // The grid's border layer lies outside the scene's bounding box (touching it at
    // most), which is convex: a segment between a viewpoint and a triangle, both
    // inside it, never enters the layer. Closing it is exact. It is closed before the
    // flood: through it, the room air under a level's open sky and the inside of its
    // walls (open at the top where the sky faces are missing) would be one component.
    let mut state: Vec<u8> = (0..n)
        .map(|v| {
            if grid.on_border(grid.coords(v)) {
                SOLID
            } else if start[v + 1] > start[v] {
                SURFACE
            } else {
                AIR
            }
        })
        .collect();

    // Components of untouched voxels.
    let mut label = vec![u32::MAX; n];
    let mut comps: Vec<Vec<u32>> = Vec::new(); // boundary voxels of each component
    let mut outside: Vec<bool> = Vec::new(); // the component meets the border layer
    let mut queue = VecDeque::new();
    for seed in 0..n {
        if state[seed] != AIR || label[seed] != u32::MAX {
            continue;
        }
        let c = comps.len() as u32;
        let mut boundary = Vec::new();
        let mut at_border = false;
        label[seed] = c;
        queue.push_back(seed);
        while let Some(v) = queue.pop_front() {
            let mut next_to_surface = false;
            for w in grid.neighbours(v) {
                if state[w] == SURFACE {
                    next_to_surface = true;
                } else if state[w] == SOLID {
                    at_border = true;
                } else if label[w] == u32::MAX {
                    label[w] = c;
                    queue.push_back(w);
                }
            }
            if next_to_surface {
                boundary.push(v as u32);
            }
        }
        comps.push(boundary);
        outside.push(at_border);
    }
    stats.components = comps.len();

    // Votes: rays from up to 64 boundary voxels of each component.
    let voxels_ref = (&grid, &start, &tri_of, tris);
    let votes: Vec<(usize, usize, Option<u32>)> = comps
        .par_iter()
        .map(|boundary| {
            let stride = (boundary.len() / 64).max(1);
            let (mut front, mut back, mut front_voxel) = (0, 0, None);
            for &v in boundary.iter().step_by(stride) {
                // Off-centre and tilted by odd amounts: rays through an edge or a
                // vertex of the level's lattice would vote by a tie.
                let o = voxels_ref.0.center(voxels_ref.0.coords(v as usize))
                    + DVec3::new(0.0131, 0.0079, 0.0043) * voxels_ref.0.size;
                for d in DIRECTIONS {
                    let d = DVec3::from_array(d).normalize() + DVec3::new(0.0113, 0.0067, 0.0029);
                    match first_hit(voxels_ref, o, d.normalize()) {
                        Some(true) => {
                            front += 1;
                            // The deepest such voxel (farthest from the grid's
                            // border) starts the leak path: the level's inside.
                            let depth = |v: u32| {
                                let c = voxels_ref.0.coords(v as usize);
                                (0..3)
                                    .map(|k| c[k].min(voxels_ref.0.dims[k] - 1 - c[k]))
                                    .min()
                                    .unwrap_or(0)
                            };
                            if front_voxel.is_none_or(|f| depth(v) > depth(f)) {
                                front_voxel = Some(v);
                            }
                        }
                        Some(false) => back += 1,
                        None => {}
                    }
                }
            }
            (front, back, front_voxel)
        })
        .collect();
    let axis = axis_votes(&grid, &state, &start, &tri_of, tris);
    let sees_front: Vec<bool> = axis.iter().map(|&x| x & AXIS_FRONT != 0).collect();
    let solid_comp: Vec<bool> = votes
        .iter()
        .map(|&(f, b, _)| b > 0 && (f as f64) <= backface_tolerance * (f + b) as f64)
        .collect();
    stats.solid_components = solid_comp.iter().filter(|&&s| s).count();
    let mut leak = None;
    let mut worst_leak = 0;
    for (c, &(front, back, front_voxel)) in votes.iter().enumerate() {
        let hits = front + back;
        if !solid_comp[c] && outside[c] && back * 4 >= hits && back > worst_leak {
            // An outside region sees the back of the geometry (≥ 25 %) yet some
            // fronts: the one with the most back hits is reported.
            if let Some(v) = front_voxel {
                worst_leak = back;
                leak = Some(leak_path(&grid, &label, &sees_front, v as usize));
            }
        }
    }
    // Apply: mark solid voxels, whole components, then single voxels that see only
    // backs along the six axes.
    for v in 0..n {
        let behind = if sees_front[v] || !axis_rule {
            0
        } else {
            axis[v]
        };
        if state[v] == AIR && label[v] != u32::MAX && (solid_comp[label[v] as usize] || behind >= 2)
        {
            state[v] = SOLID;
        }
    }
    seal_out_of_sight(&grid, &mut state, &sees_front, &closed);
    for &s in &state {
        match s {
            SURFACE => stats.surface += 1,
            SOLID => stats.solid += 1,
            SEALED => stats.sealed += 1,
            _ => stats.air += 1,
        }
    }
    Voxels {
        grid,
        state,
        start,
        tri_of,
        stats,
        leak,
        sees_front,
        closed,
    }
}

/// Mark [`SEALED`] the open voxels no viewpoint reaches: a sight line runs through a
/// chain of face-adjacent open voxels, from a viewpoint (an air voxel meeting a front
/// along an axis) across open faces only — through a closed face it would cross a
/// polygon of the surface, and through an edge or corner between two closed faces it
/// would touch one (grazing: nothing is seen by it). Behind the closed faces of a wall
/// on the lattice lies a layer of surface voxels that no line reaches.
fn seal_out_of_sight(grid: &Grid, state: &mut [u8], sees_front: &[bool], closed: &[u8]) {
    let n = grid.len();
    let mut reached = vec![false; n];
    let mut queue: VecDeque<usize> = (0..n)
        .filter(|&v| state[v] == AIR && sees_front[v])
        .collect();
    if queue.is_empty() {
        return;
    }
    for &v in &queue {
        reached[v] = true;
    }
    let strides = [1, grid.dims[0], grid.dims[0] * grid.dims[1]];
    while let Some(v) = queue.pop_front() {
        let c = grid.coords(v);
        for k in 0..3 {
            // +k across v's face, -k across the neighbour's.
            if c[k] + 1 < grid.dims[k] && closed[v] & (1 << k) == 0 {
                let w = v + strides[k];
                if !reached[w] && (state[w] == AIR || state[w] == SURFACE) {
                    reached[w] = true;
                    queue.push_back(w);
                }
            }
            if c[k] > 0 {
                let w = v - strides[k];
                if closed[w] & (1 << k) == 0
                    && !reached[w]
                    && (state[w] == AIR || state[w] == SURFACE)
                {
                    reached[w] = true;
                    queue.push_back(w);
                }
            }
        }
    }
    for v in 0..n {
        if !reached[v] && (state[v] == AIR || state[v] == SURFACE) {
            state[v] = SEALED;
        }
    }
}

const DIRECTIONS: [[f64; 3]; 14] = [
    [1.0, 0.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0],
    [1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, 1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [-1.0, -1.0, -1.0],
];

/// First triangle hit by the ray `o + t d` (t > 0) through the grid: `Some(true)` for
/// its front (`d · n < 0`), `Some(false)` for its back, `None` when it leaves the grid
/// or only grazes (triangles edge-on to the ray do not vote).
fn first_hit(
    (grid, start, tri_of, tris): (&Grid, &Vec<u32>, &Vec<u32>, &[[DVec3; 3]]),
    o: DVec3,
    d: DVec3,
) -> Option<bool> {
    let mut c = grid.locate(o)?.map(|x| x as i64);
    let step = d.to_array().map(|x| if x > 0.0 { 1i64 } else { -1 });
    let mut t_max = [0.0; 3];
    let mut t_delta = [0.0; 3];
    for k in 0..3 {
        if d[k] == 0.0 {
            t_max[k] = f64::INFINITY;
            t_delta[k] = f64::INFINITY;
        } else {
            let edge = grid.origin[k] + (c[k] + i64::from(step[k] > 0)) as f64 * grid.size;
            t_max[k] = (edge - o[k]) / d[k];
            t_delta[k] = grid.size / d[k].abs();
        }
    }
    loop {
        let v = grid.index(c[0] as usize, c[1] as usize, c[2] as usize);
        let t_exit = t_max[0].min(t_max[1]).min(t_max[2]);
        let mut best: Option<(f64, bool)> = None;
        for &ti in &tri_of[start[v] as usize..start[v + 1] as usize] {
            let t = &tris[ti as usize];
            if let Some((th, front)) = ray_triangle(o, d, t) {
                if th <= t_exit + 1e-9 * grid.size && best.is_none_or(|(b, _)| th < b) {
                    best = Some((th, front));
                }
            }
        }
        if let Some((_, front)) = best {
            return Some(front);
        }
        let k = if t_max[0] <= t_max[1] && t_max[0] <= t_max[2] {
            0
        } else if t_max[1] <= t_max[2] {
            1
        } else {
            2
        };
        c[k] += step[k];
        if c[k] < 0 || c[k] >= grid.dims[k] as i64 {
            return None;
        }
        t_max[k] += t_delta[k];
    }
}

/// Möller–Trumbore: `(t, front)` of a proper hit with t > 0.
fn ray_triangle(o: DVec3, d: DVec3, t: &[DVec3; 3]) -> Option<(f64, bool)> {
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    let scale = e1.length() * e2.length();
    if det.abs() <= 1e-12 * scale {
        return None;
    }
    let inv = 1.0 / det;
    let s = o - t[0];
    let u = s.dot(p) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let q = s.cross(e1);
    let w = d.dot(q) * inv;
    if w < 0.0 || u + w > 1.0 {
        return None;
    }
    let th = e2.dot(q) * inv;
    (th > 0.0).then_some((th, det > 0.0))
}

/// A shortest path of untouched voxels (within the component of `inside`) from
/// `inside` to the void: a voxel next to the grid's border layer that meets no front
/// face along the axes, or failing that any voxel next to the border layer.
fn leak_path(grid: &Grid, label: &[u32], sees_front: &[bool], inside: usize) -> Leak {
    let c = label[inside];
    let mut prev = vec![u32::MAX; grid.len()];
    let mut queue = VecDeque::from([inside]);
    prev[inside] = inside as u32;
    let mut end = None;
    let mut fallback = None;
    while let Some(v) = queue.pop_front() {
        if grid.neighbours(v).any(|w| grid.on_border(grid.coords(w))) {
            fallback.get_or_insert(v);
            if !sees_front[v] {
                end = Some(v);
                break;
            }
        }
        for w in grid.neighbours(v) {
            if label[w] == c && prev[w] == u32::MAX {
                prev[w] = v as u32;
                queue.push_back(w);
            }
        }
    }
    let end = end.or(fallback).unwrap_or(inside);
    let mut path = vec![end];
    while *path.last().unwrap_or(&inside) != inside {
        let p = prev[*path.last().unwrap_or(&inside)] as usize;
        path.push(p);
    }
    path.reverse();
    let at = |v: usize| grid.center(grid.coords(v)).to_array();
    Leak {
        inside: at(inside),
        border: at(end),
        path: path.into_iter().map(at).collect(),
    }
}

/// Per untouched voxel, the number of axis directions (of six) whose first oriented
/// surface voxel holds only triangles facing away (the voxel is behind them), and
/// [`AXIS_FRONT`] when some direction meets a front. Rule 2 makes solid a voxel of an open region (a wall whose top is
/// the level's open sky) that sees the back of the geometry along every axis that
/// meets any. A surface voxel whose triangles are all edge-on to the axis is passed
/// through; one holding both orientations counts as a front.
fn axis_votes(
    grid: &Grid,
    state: &[u8],
    start: &[u32],
    tri_of: &[u32],
    tris: &[[DVec3; 3]],
) -> Vec<u8> {
    const FRONT: u8 = AXIS_FRONT;
    let n = grid.len();
    // Bits 2k / 2k+1: a triangle with normal component k positive / negative.
    let orient: Vec<u8> = (0..n)
        .into_par_iter()
        .map(|v| {
            if start[v + 1] == start[v] {
                return 0;
            }
            let mut bits = 0u8;
            for &t in &tri_of[start[v] as usize..start[v + 1] as usize] {
                let t = &tris[t as usize];
                let nrm = (t[1] - t[0]).cross(t[2] - t[0]);
                let len = nrm.length();
                for k in 0..3 {
                    if nrm[k] > 0.05 * len {
                        bits |= 1 << (2 * k);
                    } else if nrm[k] < -0.05 * len {
                        bits |= 1 << (2 * k + 1);
                    }
                }
            }
            bits
        })
        .collect();
    let mut votes = vec![0u8; n];
    for k in 0..3 {
        let (a, b) = ((k + 1) % 3, (k + 2) % 3);
        let stride = [1, grid.dims[0], grid.dims[0] * grid.dims[1]][k];
        for j in 0..grid.dims[b] {
            for i in 0..grid.dims[a] {
                let mut c = [0; 3];
                c[a] = i;
                c[b] = j;
                let first = grid.index(c[0], c[1], c[2]);
                for forward in [true, false] {
                    // `last`: what a ray from the current voxel towards decreasing
                    // (forward pass) or increasing k meets first: 0 nothing, 1 back, 2 front.
                    let mut last = 0u8;
                    for step in 0..grid.dims[k] {
                        let s = if forward {
                            step
                        } else {
                            grid.dims[k] - 1 - step
                        };
                        let v = first + s * stride;
                        if start[v + 1] > start[v] {
                            let pos = orient[v] & (1 << (2 * k)) != 0;
                            let neg = orient[v] & (1 << (2 * k + 1)) != 0;
                            // Ray towards -k (forward pass) meets a front when n_k > 0.
                            let (towards, away) = if forward { (pos, neg) } else { (neg, pos) };
                            if towards {
                                last = 2;
                            } else if away {
                                last = 1;
                            }
                        } else if state[v] == AIR {
                            match last {
                                2 => votes[v] |= FRONT,
                                1 => votes[v] += 1,
                                _ => {}
                            }
                        }
                    }
                }
            }
        }
    }
    votes
}

/// Flag of [`axis_votes`]: some axis direction meets a front.
const AXIS_FRONT: u8 = 0x80;
