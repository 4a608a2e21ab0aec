//! Volumetric visibility from box viewcells over the level's voxels — Schaufler, Dorsey,
//! Décoret & Sillion, "Conservative volumetric visibility with occluder fusion"
//! (SIGGRAPH 2000; the visibility course, §7.1): the opaque voxels and the closed voxel
//! faces are the occluders, and a target is hidden from a viewcell when every segment
//! from the cell to it crosses opaque space.
//!
//! Guarantee: a voxel box is reported hidden from a viewcell only if every segment from
//! a point of the cell to a point of the box crosses, on one axis-aligned plane strictly
//! separating them, only faces that no sight line passes (closed faces, faces of solid
//! or sealed voxels), so a cluster all of whose voxels are hidden is seen by no line.
//!
//! The test. Let the cell `V` and the target `W` be boxes separated along axis `k`
//! (`V` below the grid plane `m`, `W` above it, or the mirror). The segments from `V`
//! to `W` fill the convex hull of `V ∪ W`, and they cross the plane `m` inside the
//! rectangle bounding the crossings of segments between extreme points: on each other
//! axis the crossing is `v + (w − v) t` with `t = (m − v_k)/(w_k − v_k)` in
//! `[t_min, t_max]` (both ends at corners of the boxes), linear in `v`, `w` and `t`,
//! hence extreme at the boxes' extreme coordinates and at `t_min` or `t_max`. When every
//! voxel face of the plane meeting that rectangle (its closed boundary included) is
//! opaque, every segment crosses an occluder: `W` is hidden. Faces are counted by a
//! summed-area table per plane, so the test of one plane costs four lookups; a target
//! is tested on every plane between it and the cell until one covers it.
//!
//! Fusion: every opaque face of a plane takes part at once, so coplanar occluders fuse
//! (a wall cut by a door into three rectangles hides all that lies behind its parts);
//! a paper-thin wall on the lattice occludes through its closed faces; the open sky
//! costs nothing, since empty space is never an occluder and never needs a cell.

use crate::cells::VoxelBox;
use crate::voxels::{Voxels, SEALED, SOLID};
use rayon::prelude::*;
use sightline_geom::DVec3;
use std::collections::HashMap;

/// The opaque faces of every grid plane, with their summed-area tables.
pub struct Occluders {
    dims: [usize; 3],
    origin: DVec3,
    size: f64,
    /// Planar patches of any orientation (off the lattice or oblique).
    patches: Patches,
    /// `sat[k][m]`: prefix counts of opaque faces on plane `m` normal to axis `k`,
    /// `(na + 1) × (nc + 1)` entries, `a = (k+1) % 3` fastest, `c = (k+2) % 3`.
    sat: [Vec<u32>; 3],
    /// `opaque[k][m]`: one byte per face (the cheap first look).
    opaque: [Vec<u8>; 3],
}

const EPS: f64 = 1e-9;

fn other(k: usize) -> (usize, usize) {
    ((k + 1) % 3, (k + 2) % 3)
}

impl Occluders {
    /// Opaque faces: a face between voxels `p` and `p + e_k` is opaque when it is
    /// closed (it lies in a polygon of the surface) or when either voxel is solid or
    /// sealed (no sight line enters them: [`crate::voxels`]). Faces on the grid's outer
    /// planes border the solid border layer.
    pub fn new(v: &Voxels, tris: &[[DVec3; 3]]) -> Occluders {
        let dims = v.grid.dims;
        let g = &v.grid;
        let blocked = |i: usize| {
            let s = v.state[i];
            s == SOLID || s == SEALED
        };
        let mut sat: [Vec<u32>; 3] = Default::default();
        let mut opaque: [Vec<u8>; 3] = Default::default();
        for k in 0..3 {
            let (a, c) = other(k);
            let (na, nc) = (dims[a], dims[c]);
            let planes = dims[k] + 1;
            let face = |m: usize, i: usize, j: usize| -> bool {
                let mut p = [0usize; 3];
                p[a] = i;
                p[c] = j;
                let mut below = false;
                if m > 0 {
                    p[k] = m - 1;
                    let b = g.index(p[0], p[1], p[2]);
                    below = blocked(b) || v.face_closed(b, k);
                }
                let mut above = m >= dims[k];
                if m < dims[k] {
                    p[k] = m;
                    above = blocked(g.index(p[0], p[1], p[2]));
                }
                below || above || m == 0
            };
            let mut op = vec![0u8; planes * na * nc];
            op.par_chunks_mut(na * nc)
                .enumerate()
                .for_each(|(m, plane)| {
                    for j in 0..nc {
                        for i in 0..na {
                            plane[j * na + i] = face(m, i, j) as u8;
                        }
                    }
                });
            let w = na + 1;
            let mut s = vec![0u32; planes * w * (nc + 1)];
            s.par_chunks_mut(w * (nc + 1))
                .zip(op.par_chunks(na * nc))
                .for_each(|(t, plane)| {
                    for j in 0..nc {
                        let mut row = 0u32;
                        for i in 0..na {
                            row += plane[j * na + i] as u32;
                            t[(j + 1) * w + i + 1] = t[j * w + i + 1] + row;
                        }
                    }
                });
            sat[k] = s;
            opaque[k] = op;
        }
        Occluders {
            dims,
            origin: g.origin,
            size: g.size,
            patches: Patches::new(tris, g.size, g.origin, dims),
            sat,
            opaque,
        }
    }

    /// Whether every face of plane `m` (normal to `k`) in `[i0, i1) × [j0, j1)` is opaque.
    #[inline]
    fn covered(&self, k: usize, m: usize, i0: usize, i1: usize, j0: usize, j1: usize) -> bool {
        let (a, c) = other(k);
        let (na, nc) = (self.dims[a], self.dims[c]);
        // The cheap look first: the faces at two corners.
        let op = &self.opaque[k][m * na * nc..(m + 1) * na * nc];
        if op[j0 * na + i0] == 0 || op[(j1 - 1) * na + i1 - 1] == 0 {
            return false;
        }
        let w = na + 1;
        let t = &self.sat[k][m * w * (nc + 1)..(m + 1) * w * (nc + 1)];
        let sum = t[j1 * w + i1] + t[j0 * w + i0] - t[j0 * w + i1] - t[j1 * w + i0];
        sum as usize == (i1 - i0) * (j1 - j0)
    }

    /// Whether every segment from box `v` to box `w` (voxel coordinates) crosses
    /// opaque faces on one plane between them (module doc).
    pub fn hidden(&self, v: &VoxelBox, w: &VoxelBox) -> bool {
        self.hidden_by_voxels(v, w) || {
            let world = |b: &VoxelBox| {
                let f = |x: [usize; 3]| DVec3::new(x[0] as f64, x[1] as f64, x[2] as f64);
                [
                    self.origin + f(b.lo) * self.size,
                    self.origin + f(b.hi) * self.size,
                ]
            };
            self.patches.hidden(world(v), world(w))
        }
    }

    /// The test on the grid planes alone (opaque voxels and closed faces).
    pub fn hidden_by_voxels(&self, v: &VoxelBox, w: &VoxelBox) -> bool {
        for k in 0..3 {
            if v.hi[k] < w.lo[k] {
                for m in v.hi[k]..=w.lo[k] {
                    if self.plane_covers(k, m, v, w, false) {
                        return true;
                    }
                }
            } else if w.hi[k] < v.lo[k] {
                for m in (w.hi[k]..=v.lo[k]).rev() {
                    if self.plane_covers(k, m, v, w, true) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// The crossing rectangle of the segments from `v` to `w` on plane `m` of axis `k`
    /// lies in opaque faces (`mirror`: `w` lies below the plane, `v` above).
    #[inline]
    fn plane_covers(&self, k: usize, m: usize, v: &VoxelBox, w: &VoxelBox, mirror: bool) -> bool {
        let f = |x: usize| x as f64;
        let mf = f(m);
        let (t_min, t_max) = if mirror {
            (
                (f(v.lo[k]) - mf) / (f(v.lo[k]) - f(w.lo[k])),
                (f(v.hi[k]) - mf) / (f(v.hi[k]) - f(w.hi[k])),
            )
        } else {
            (
                (mf - f(v.hi[k])) / (f(w.hi[k]) - f(v.hi[k])),
                (mf - f(v.lo[k])) / (f(w.lo[k]) - f(v.lo[k])),
            )
        };
        let (a, c) = other(k);
        let mut range = [[0usize; 2]; 2];
        for (slot, &d) in [a, c].iter().enumerate() {
            let lo_at = |t: f64| f(v.lo[d]) + (f(w.lo[d]) - f(v.lo[d])) * t;
            let hi_at = |t: f64| f(v.hi[d]) + (f(w.hi[d]) - f(v.hi[d])) * t;
            let lo = lo_at(t_min).min(lo_at(t_max)) - EPS;
            let hi = hi_at(t_min).max(hi_at(t_max)) + EPS;
            // Faces meeting the closed rectangle: a line through the edge between an
            // opaque face and an open one passes.
            if lo.is_nan() || lo < 0.0 || hi >= self.dims[d] as f64 {
                return false;
            }
            range[slot] = [lo.floor() as usize, hi.floor() as usize + 1];
        }
        self.covered(k, m, range[0][0], range[0][1], range[1][0], range[1][1])
    }
}

/// The voxels each cluster touches, grouped in blocks for the hierarchical test.
pub struct ClusterVoxels {
    /// Per cluster: the bounding box of its voxels, and its blocks
    /// `blocks[start[c]..start[c + 1]]`.
    pub bounds: Vec<Option<VoxelBox>>,
    start: Vec<u32>,
    /// Per block: its box (bounds of the cluster's voxels in it) and its voxels
    /// `voxels[vstart[b]..vstart[b + 1]]`.
    blocks: Vec<VoxelBox>,
    vstart: Vec<u32>,
    voxels: Vec<[u32; 3]>,
}

/// Side of the blocks of [`ClusterVoxels`], in voxels.
pub const BLOCK: usize = 4;

impl ClusterVoxels {
    /// From the surface voxels' triangle lists and each triangle's cluster.
    pub fn new(v: &Voxels, tri_object: &[u32], clusters: usize) -> ClusterVoxels {
        let g = &v.grid;
        let mut per: Vec<Vec<[u32; 3]>> = vec![Vec::new(); clusters];
        for i in 0..g.len() {
            let tris = v.triangles_in(i);
            if tris.is_empty() {
                continue;
            }
            let c = g.coords(i).map(|x| x as u32);
            let mut last = u32::MAX;
            for &t in tris {
                let o = tri_object[t as usize];
                if o != last {
                    let l = &mut per[o as usize];
                    if l.last() != Some(&c) {
                        l.push(c);
                    }
                    last = o;
                }
            }
        }
        let mut out = ClusterVoxels {
            bounds: Vec::with_capacity(clusters),
            start: vec![0],
            blocks: Vec::new(),
            vstart: vec![0],
            voxels: Vec::new(),
        };
        for mut l in per {
            l.sort_unstable_by_key(|c| {
                let b = c.map(|x| x as usize / BLOCK);
                (b[2], b[1], b[0], c[2], c[1], c[0])
            });
            l.dedup();
            out.bounds.push(bounds_of(&l));
            let mut s = 0;
            while s < l.len() {
                let key = l[s].map(|x| x as usize / BLOCK);
                let mut e = s + 1;
                while e < l.len() && l[e].map(|x| x as usize / BLOCK) == key {
                    e += 1;
                }
                if let Some(b) = bounds_of(&l[s..e]) {
                    out.blocks.push(b);
                }
                out.voxels.extend_from_slice(&l[s..e]);
                out.vstart.push(out.voxels.len() as u32);
                s = e;
            }
            out.start.push(out.blocks.len() as u32);
        }
        out
    }

    /// Whether cluster `c` is hidden from the viewcell `cell`: its bounding box, else
    /// each of its blocks, else each voxel of a block, hidden.
    pub fn hidden(&self, occ: &Occluders, cell: &VoxelBox, c: usize) -> bool {
        let Some(b) = self.bounds[c] else {
            return true;
        };
        if occ.hidden(cell, &b) {
            return true;
        }
        for blk in self.start[c] as usize..self.start[c + 1] as usize {
            if occ.hidden(cell, &self.blocks[blk]) {
                continue;
            }
            for p in &self.voxels[self.vstart[blk] as usize..self.vstart[blk + 1] as usize] {
                let lo = p.map(|x| x as usize);
                let one = VoxelBox {
                    lo,
                    hi: lo.map(|x| x + 1),
                };
                if !occ.hidden(cell, &one) {
                    return false;
                }
            }
        }
        true
    }
}

fn bounds_of(l: &[[u32; 3]]) -> Option<VoxelBox> {
    let first = l.first()?;
    let mut lo = first.map(|x| x as usize);
    let mut hi = lo.map(|x| x + 1);
    for p in l {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k] as usize);
            hi[k] = hi[k].max(p[k] as usize + 1);
        }
    }
    Some(VoxelBox { lo, hi })
}

/// Planar patches: the triangles of the level grouped by the plane they lie in
/// (exactly, to 10⁻⁶ voxel), each plane rasterized into cells of half a voxel that lie
/// wholly inside the union of its triangles ([`crate::faces`]' exact cover), with a
/// summed-area table. A target is hidden by a plane that strictly separates it from
/// the cell when the crossings of the 64 segments between their corners (whose hull
/// is the crossing of every segment) fall in covered cells only: coplanar triangles
/// fuse, oblique walls and walls off the lattice occlude.
pub struct Patches {
    planes: Vec<Patch>,
    /// Buckets of `bucket` world units over the level: the patches meeting each.
    origin: DVec3,
    bucket: f64,
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<u32>,
}

struct Patch {
    n: DVec3,
    d: f64,
    u: DVec3,
    v: DVec3,
    /// Raster origin (plane coordinates), cell side, cells.
    o: [f64; 2],
    cell: f64,
    nu: usize,
    nv: usize,
    sat: Vec<u32>,
    /// Largest distance of a member triangle's vertex from the plane.
    slack: f64,
}

/// Patches smaller than this many squared voxels are not worth a plane.
const MIN_PATCH_AREA: f64 = 2.0;

impl Patches {
    /// The patches of `tris` over a grid of `dims` voxels of side `h` from `origin`.
    pub fn new(tris: &[[DVec3; 3]], h: f64, origin: DVec3, dims: [usize; 3]) -> Patches {
        // Group by the rounded plane, then keep the triangles lying in the plane of
        // the group's largest triangle.
        let mut groups: HashMap<[i64; 4], Vec<usize>> = HashMap::new();
        for (i, t) in tris.iter().enumerate() {
            let n = (t[1] - t[0]).cross(t[2] - t[0]);
            let len = n.length();
            if !(len > 0.0 && len.is_finite()) {
                continue;
            }
            let mut n = n / len;
            let m = (0..3)
                .max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
                .unwrap_or(2);
            if n[m] < 0.0 {
                n = -n;
            }
            let d = n.dot(t[0]);
            let key = [
                (n.x * 1e4).round() as i64,
                (n.y * 1e4).round() as i64,
                (n.z * 1e4).round() as i64,
                (d / h * 1e3).round() as i64,
            ];
            groups.entry(key).or_default().push(i);
        }
        let mut keys: Vec<[i64; 4]> = groups.keys().copied().collect();
        keys.sort_unstable();
        let lists: Vec<Vec<usize>> = keys.iter().filter_map(|k| groups.remove(k)).collect();
        let planes: Vec<Patch> = lists
            .par_iter()
            .filter_map(|l| Patch::new(tris, l, h))
            .collect();
        // Buckets.
        let bucket = 16.0 * h;
        let bdims = dims.map(|d| d.div_ceil(16).max(1));
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); bdims[0] * bdims[1] * bdims[2]];
        for (pi, p) in planes.iter().enumerate() {
            let (lo, hi) = p.bounds();
            let b0 = ((lo - origin) / bucket).floor();
            let b1 = ((hi - origin) / bucket).floor();
            let clamp = |x: f64, k: usize| (x.max(0.0) as usize).min(bdims[k] - 1);
            for z in clamp(b0.z, 2)..=clamp(b1.z, 2) {
                for y in clamp(b0.y, 1)..=clamp(b1.y, 1) {
                    for x in clamp(b0.x, 0)..=clamp(b1.x, 0) {
                        lists[x + bdims[0] * (y + bdims[1] * z)].push(pi as u32);
                    }
                }
            }
        }
        let mut start = vec![0u32];
        let mut items = Vec::new();
        for l in lists {
            items.extend(l);
            start.push(items.len() as u32);
        }
        Patches {
            planes,
            origin,
            bucket,
            dims: bdims,
            start,
            items,
        }
    }

    /// Whether a patch hides world box `w` from world box `v` (both `[min, max]`).
    pub fn hidden(&self, v: [DVec3; 2], w: [DVec3; 2]) -> bool {
        // Every segment crosses the blocking patch, the one between the centres too:
        // the patch meets a bucket along it.
        let a = (v[0] + v[1]) * 0.5;
        let b = (w[0] + w[1]) * 0.5;
        let len = (b - a).length();
        let steps = ((len / (0.25 * self.bucket)).ceil() as usize).max(1);
        let mut cands: Vec<u32> = Vec::new();
        let mut last = usize::MAX;
        for s in 0..=steps {
            let p = a + (b - a) * (s as f64 / steps as f64);
            let q = ((p - self.origin) / self.bucket).floor();
            if q.x < 0.0 || q.y < 0.0 || q.z < 0.0 {
                continue;
            }
            let c = [q.x as usize, q.y as usize, q.z as usize];
            if (0..3).any(|k| c[k] >= self.dims[k]) {
                continue;
            }
            let bi = c[0] + self.dims[0] * (c[1] + self.dims[1] * c[2]);
            if bi != last {
                last = bi;
                cands.extend_from_slice(
                    &self.items[self.start[bi] as usize..self.start[bi + 1] as usize],
                );
            }
        }
        cands.sort_unstable();
        cands.dedup();
        cands
            .iter()
            .any(|&pi| self.planes[pi as usize].hides(v, w, a, b))
    }
}

fn corners(b: [DVec3; 2]) -> [DVec3; 8] {
    std::array::from_fn(|i| {
        DVec3::new(
            if i & 1 == 0 { b[0].x } else { b[1].x },
            if i & 2 == 0 { b[0].y } else { b[1].y },
            if i & 4 == 0 { b[0].z } else { b[1].z },
        )
    })
}

impl Patch {
    fn new(tris: &[[DVec3; 3]], list: &[usize], h: f64) -> Option<Patch> {
        let area = |t: &[DVec3; 3]| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
        let big = *list
            .iter()
            .max_by(|&&a, &&b| area(&tris[a]).total_cmp(&area(&tris[b])))?;
        let t = &tris[big];
        let mut n = (t[1] - t[0]).cross(t[2] - t[0]).normalize();
        let m = (0..3)
            .max_by(|&a, &b| n[a].abs().total_cmp(&n[b].abs()))
            .unwrap_or(2);
        if n[m] < 0.0 {
            n = -n;
        }
        let d = n.dot(t[0]);
        let tol = 1e-6 * h;
        let members: Vec<&[DVec3; 3]> = list
            .iter()
            .map(|&i| &tris[i])
            .filter(|t| t.iter().all(|p| (n.dot(*p) - d).abs() <= tol))
            .collect();
        let slack = members
            .iter()
            .flat_map(|t| t.iter().map(|p| (n.dot(*p) - d).abs()))
            .fold(0.0, f64::max);
        let total: f64 = members.iter().map(|t| area(t)).sum();
        if total < MIN_PATCH_AREA * h * h {
            return None;
        }
        let u = if n.x.abs() < 0.9 {
            DVec3::X.cross(n).normalize()
        } else {
            DVec3::Y.cross(n).normalize()
        };
        let v = n.cross(u);
        let cell = 0.5 * h;
        let flat: Vec<[[f64; 2]; 3]> = members
            .iter()
            .map(|t| t.map(|p| [p.dot(u) / cell, p.dot(v) / cell]))
            .collect();
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for t in &flat {
            for p in t {
                for k in 0..2 {
                    lo[k] = lo[k].min(p[k]);
                    hi[k] = hi[k].max(p[k]);
                }
            }
        }
        let o = [lo[0].floor(), lo[1].floor()];
        let nu = (hi[0] - o[0]).ceil() as usize;
        let nv = (hi[1] - o[1]).ceil() as usize;
        if nu == 0 || nv == 0 || nu * nv > 1 << 24 {
            return None;
        }
        let mut by_cell: HashMap<(usize, usize), Vec<usize>> = HashMap::new();
        let local: Vec<[[f64; 2]; 3]> = flat
            .iter()
            .map(|t| t.map(|p| [p[0] - o[0], p[1] - o[1]]))
            .collect();
        for (ti, t) in local.iter().enumerate() {
            let (mut a, mut b) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in t {
                for k in 0..2 {
                    a[k] = a[k].min(p[k]);
                    b[k] = b[k].max(p[k]);
                }
            }
            let i0 = a[0].floor().max(0.0) as usize;
            let j0 = a[1].floor().max(0.0) as usize;
            let i1 = (b[0].ceil() as usize).min(nu);
            let j1 = (b[1].ceil() as usize).min(nv);
            for j in j0..j1 {
                for i in i0..i1 {
                    by_cell.entry((i, j)).or_default().push(ti);
                }
            }
        }
        let mut full = vec![0u8; nu * nv];
        for ((i, j), ts) in by_cell {
            let (x, y) = (i as f64, j as f64);
            let square = vec![[x, y], [x + 1.0, y], [x + 1.0, y + 1.0], [x, y + 1.0]];
            if crate::faces::covered(square, ts.iter().map(|&t| &local[t])) {
                full[j * nu + i] = 1;
            }
        }
        if !full.iter().any(|&f| f != 0) {
            return None;
        }
        let w = nu + 1;
        let mut sat = vec![0u32; w * (nv + 1)];
        for j in 0..nv {
            let mut row = 0u32;
            for i in 0..nu {
                row += full[j * nu + i] as u32;
                sat[(j + 1) * w + i + 1] = sat[j * w + i + 1] + row;
            }
        }
        Some(Patch {
            n,
            d,
            u,
            v,
            o,
            cell,
            nu,
            nv,
            sat,
            slack,
        })
    }

    /// World bounds of the raster.
    fn bounds(&self) -> (DVec3, DVec3) {
        let mut lo = DVec3::splat(f64::INFINITY);
        let mut hi = DVec3::splat(f64::NEG_INFINITY);
        for (a, b) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
            let p = self.n * self.d
                + self.u * ((self.o[0] + a * self.nu as f64) * self.cell)
                + self.v * ((self.o[1] + b * self.nv as f64) * self.cell);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        (lo, hi)
    }

    /// Whether the plane strictly separates `v` from `w` and every segment between
    /// them crosses it in covered cells.
    fn hides(&self, v: [DVec3; 2], w: [DVec3; 2], vc: DVec3, wc: DVec3) -> bool {
        // The cheap look first: the plane separates the centres and the segment
        // between them crosses a covered cell.
        let (a, b) = (self.n.dot(vc) - self.d, self.n.dot(wc) - self.d);
        if a * b >= 0.0 {
            return false;
        }
        let x = vc + (wc - vc) * (a / (a - b));
        let (cu, cv0) = (
            x.dot(self.u) / self.cell - self.o[0],
            x.dot(self.v) / self.cell - self.o[1],
        );
        if cu.is_nan()
            || cv0.is_nan()
            || cu < 0.0
            || cv0 < 0.0
            || cu >= self.nu as f64
            || cv0 >= self.nv as f64
        {
            return false;
        }
        {
            let (i, j) = (cu as usize, cv0 as usize);
            let w = self.nu + 1;
            let t = &self.sat;
            if t[(j + 1) * w + i + 1] + t[j * w + i] - t[j * w + i + 1] - t[(j + 1) * w + i] == 0 {
                return false;
            }
        }
        let cv = corners(v);
        let cw = corners(w);
        let sv = cv.map(|p| self.n.dot(p) - self.d);
        let sw = cw.map(|p| self.n.dot(p) - self.d);
        let margin = 1e-7 * self.cell;
        let (vmin, vmax) = min_max(&sv);
        let (wmin, wmax) = min_max(&sw);
        if !((vmax < -margin && wmin > margin) || (vmin > margin && wmax < -margin)) {
            return false;
        }
        let mut lo = [f64::INFINITY; 2];
        let mut hi = [f64::NEG_INFINITY; 2];
        for (i, p) in cv.iter().enumerate() {
            for (j, q) in cw.iter().enumerate() {
                let t = sv[i] / (sv[i] - sw[j]);
                let x = *p + (*q - *p) * t;
                let c = [
                    x.dot(self.u) / self.cell - self.o[0],
                    x.dot(self.v) / self.cell - self.o[1],
                ];
                for k in 0..2 {
                    lo[k] = lo[k].min(c[k]);
                    hi[k] = hi[k].max(c[k]);
                }
            }
        }
        // A segment crosses a member triangle's own plane within `slack / sin θ` of
        // where it crosses this one, θ its angle with the plane: at least the boxes'
        // distances to the plane over their span.
        let gap = if vmax < 0.0 { wmin - vmax } else { vmin - wmax };
        let span = (v[1].max(w[1]) - v[0].min(w[0])).length().max(gap);
        let eps = 1e-6 + self.slack * span / gap / self.cell;
        if lo.iter().any(|x| x.is_nan() || x - eps < 0.0)
            || hi[0] + eps >= self.nu as f64
            || hi[1] + eps >= self.nv as f64
        {
            return false;
        }
        let i0 = (lo[0] - eps).floor() as usize;
        let j0 = (lo[1] - eps).floor() as usize;
        let i1 = (hi[0] + eps).floor() as usize + 1;
        let j1 = (hi[1] + eps).floor() as usize + 1;
        let w = self.nu + 1;
        let t = &self.sat;
        let sum = t[j1 * w + i1] + t[j0 * w + i0] - t[j0 * w + i1] - t[j1 * w + i0];
        sum as usize == (i1 - i0) * (j1 - j0)
    }
}

fn min_max(s: &[f64; 8]) -> (f64, f64) {
    s.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        })
}
