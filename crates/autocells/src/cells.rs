//! Cells and portals from free space.
//!
//! Rule: the open voxels (air and surface) are merged greedily into maximal
//! axis-aligned boxes — scanning voxels in x, then y, then z order, each unassigned
//! open voxel starts a box grown along x, then y, then z while the whole new row or
//! slab is open and unassigned (and, when walls bound cells, crosses no closed face),
//! up to `max_box` voxels per side. Every box is a
//! convex cell. Two boxes that share part of a face share one portal: the rectangle
//! of the overlap, covering it whole, less its closed faces ([`crate::faces`]: faces
//! inside a polygon of the surface, which no sight line crosses); no box holds a
//! closed face inside. Sight crosses from box to box only through open voxels and open
//! faces, that is through these rectangles, so no opening is ever smaller than its
//! portals.

use crate::voxels::Voxels;
use sightline_geom::{DVec3, ViewCell};
use sightline_portals::winding::{Plane, Winding};

/// A box of voxels: `[lo, hi)` in grid coordinates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VoxelBox {
    pub lo: [usize; 3],
    pub hi: [usize; 3],
}

/// A portal between boxes `cells[0]` and `cells[1]`; its plane's normal points into
/// `cells[1]`.
#[derive(Clone, Debug)]
pub struct Portal {
    pub winding: Winding,
    pub plane: Plane,
    pub cells: [u32; 2],
}

/// Greedy boxes over the open voxels; returns the boxes and each voxel's box
/// (`u32::MAX` for solid voxels).
pub fn greedy_boxes(v: &Voxels, max_box: usize, walls_bound: bool) -> (Vec<VoxelBox>, Vec<u32>) {
    let g = &v.grid;
    let [nx, ny, nz] = g.dims;
    let max_box = max_box.max(1);
    let mut owner = vec![u32::MAX; g.len()];
    let mut boxes = Vec::new();
    let free = |owner: &[u32], i: usize| v.is_open(i) && owner[i] == u32::MAX;
    // With `walls_bound`, a box holds no closed face between two of its voxels.
    let closed =
        |x: usize, y: usize, z: usize, k: usize| walls_bound && v.face_closed(g.index(x, y, z), k);
    for z in 0..nz {
        for y in 0..ny {
            for x in 0..nx {
                if !free(&owner, g.index(x, y, z)) {
                    continue;
                }
                let mut x1 = x + 1;
                while x1 < nx
                    && x1 - x < max_box
                    && free(&owner, g.index(x1, y, z))
                    && !closed(x1 - 1, y, z, 0)
                {
                    x1 += 1;
                }
                let mut y1 = y + 1;
                while y1 < ny
                    && y1 - y < max_box
                    && (x..x1).all(|xx| {
                        free(&owner, g.index(xx, y1, z))
                            && !closed(xx, y1 - 1, z, 1)
                            && (xx + 1 == x1 || !closed(xx, y1, z, 0))
                    })
                {
                    y1 += 1;
                }
                let mut z1 = z + 1;
                while z1 < nz
                    && z1 - z < max_box
                    && (y..y1).all(|yy| {
                        (x..x1).all(|xx| {
                            free(&owner, g.index(xx, yy, z1))
                                && !closed(xx, yy, z1 - 1, 2)
                                && (xx + 1 == x1 || !closed(xx, yy, z1, 0))
                                && (yy + 1 == y1 || !closed(xx, yy, z1, 1))
                        })
                    })
                {
                    z1 += 1;
                }
                let id = boxes.len() as u32;
                for zz in z..z1 {
                    for yy in y..y1 {
                        for xx in x..x1 {
                            owner[g.index(xx, yy, zz)] = id;
                        }
                    }
                }
                boxes.push(VoxelBox {
                    lo: [x, y, z],
                    hi: [x1, y1, z1],
                });
            }
        }
    }
    (boxes, owner)
}

/// The world box of a voxel box.
pub fn world_box(v: &Voxels, b: &VoxelBox) -> ViewCell {
    ViewCell {
        min: v.grid.voxel_min(b.lo),
        max: v.grid.voxel_min(b.hi),
    }
}

/// The portals between boxes: for each box, the boxes beyond its +x, +y and +z faces
/// and the overlap rectangles.
pub fn portals(v: &Voxels, boxes: &[VoxelBox], owner: &[u32]) -> Vec<Portal> {
    let g = &v.grid;
    let mut out = Vec::new();
    let mut seen = Vec::new();
    for (id, b) in boxes.iter().enumerate() {
        for k in 0..3 {
            let at = b.hi[k];
            if at >= g.dims[k] {
                continue;
            }
            let (a, c) = ((k + 1) % 3, (k + 2) % 3);
            seen.clear();
            for i in b.lo[a]..b.hi[a] {
                for j in b.lo[c]..b.hi[c] {
                    let mut p = [0; 3];
                    p[k] = at;
                    p[a] = i;
                    p[c] = j;
                    let o = owner[g.index(p[0], p[1], p[2])];
                    if o != u32::MAX && !seen.contains(&o) {
                        seen.push(o);
                    }
                }
            }
            for &o in &seen {
                let n = &boxes[o as usize];
                let (ra0, ra1) = (b.lo[a].max(n.lo[a]), b.hi[a].min(n.hi[a]));
                let (rc0, rc1) = (b.lo[c].max(n.lo[c]), b.hi[c].min(n.hi[c]));
                // The face between voxel (at - 1) and (at) along k, at (i, j).
                let open = |i: usize, j: usize| {
                    let mut p = [0; 3];
                    p[k] = at - 1;
                    p[a] = i;
                    p[c] = j;
                    !v.face_closed(g.index(p[0], p[1], p[2]), k)
                };
                for [a0, a1, c0, c1] in open_rectangles(ra0, ra1, rc0, rc1, open) {
                    let corner = |i: usize, j: usize| {
                        let mut p = [0; 3];
                        p[k] = at;
                        p[a] = i;
                        p[c] = j;
                        g.voxel_min(p)
                    };
                    // Clockwise seen from the normal's tip, as qbsp's windings.
                    let winding = Winding::new(vec![
                        corner(a0, c1),
                        corner(a1, c1),
                        corner(a1, c0),
                        corner(a0, c0),
                    ]);
                    let mut normal = DVec3::ZERO;
                    normal[k] = 1.0;
                    let plane = Plane::new(normal, g.voxel_min([at; 3])[k]);
                    out.push(Portal {
                        winding,
                        plane,
                        cells: [id as u32, o],
                    });
                }
            }
        }
    }
    out
}

/// The open faces of the rectangle `[a0, a1) × [c0, c1)` as rectangles `[a0, a1, c0,
/// c1]` that cover them exactly (greedy: rows along `a`, then grown along `c`).
fn open_rectangles(
    a0: usize,
    a1: usize,
    c0: usize,
    c1: usize,
    open: impl Fn(usize, usize) -> bool,
) -> Vec<[usize; 4]> {
    let (w, h) = (a1 - a0, c1 - c0);
    let cells: Vec<bool> = (0..w * h).map(|q| open(a0 + q % w, c0 + q / w)).collect();
    if cells.iter().all(|&x| x) {
        return vec![[a0, a1, c0, c1]];
    }
    let mut used = vec![false; w * h];
    let mut out = Vec::new();
    for j in 0..h {
        for i in 0..w {
            if !cells[j * w + i] || used[j * w + i] {
                continue;
            }
            let mut i1 = i + 1;
            while i1 < w && cells[j * w + i1] && !used[j * w + i1] {
                i1 += 1;
            }
            let mut j1 = j + 1;
            while j1 < h && (i..i1).all(|x| cells[j1 * w + x] && !used[j1 * w + x]) {
                j1 += 1;
            }
            for y in j..j1 {
                for x in i..i1 {
                    used[y * w + x] = true;
                }
            }
            out.push([a0 + i, a0 + i1, c0 + j, c0 + j1]);
        }
    }
    out
}

/// Group boxes into coarser cells for the solver: boxes whose lower corners lie in the
/// same block of `block` voxels a side and that are connected through portals inside
/// it form one cell (a union of boxes, not convex: the flow then assumes a line can
/// cross it from any portal to any other in front, which only adds visibility). Boxes
/// on two sides of a wall stay apart unless open space joins them within the block.
/// Returns each box's group and the number of groups.
pub fn group_boxes(boxes: &[VoxelBox], portals: &[Portal], block: usize) -> (Vec<u32>, usize) {
    let block = block.max(1);
    let key = |b: &VoxelBox| b.lo.map(|x| x / block);
    let mut parent: Vec<u32> = (0..boxes.len() as u32).collect();
    fn find(parent: &mut [u32], mut x: u32) -> u32 {
        while parent[x as usize] != x {
            parent[x as usize] = parent[parent[x as usize] as usize];
            x = parent[x as usize];
        }
        x
    }
    for p in portals {
        let [a, b] = p.cells;
        if key(&boxes[a as usize]) == key(&boxes[b as usize]) {
            let (ra, rb) = (find(&mut parent, a), find(&mut parent, b));
            if ra != rb {
                parent[ra.max(rb) as usize] = ra.min(rb);
            }
        }
    }
    let mut id = vec![u32::MAX; boxes.len()];
    let mut group = vec![0u32; boxes.len()];
    let mut n = 0u32;
    for b in 0..boxes.len() as u32 {
        let r = find(&mut parent, b) as usize;
        if id[r] == u32::MAX {
            id[r] = n;
            n += 1;
        }
        group[b as usize] = id[r];
    }
    (group, n as usize)
}
