//! Viewcells where a viewer can be: boxes over the walkable floors of a level, from the
//! floor to above eye height, a few metres wide, never across a wall.
//!
//! Guarantee: every eye point of a viewer standing on a walkable floor (an upward
//! surface with head room for the eye) lies in a viewcell.
//!
//! * A **floor voxel** is a surface voxel holding a triangle facing up (normal within
//!   about 45° of +z, either winding: exports disagree on it) whose voxel above is
//!   open, holds no such triangle, and is free air or surface up to eye height (no
//!   solid or sealed voxel, no closed face across the column): the top of a floor
//!   surface with room for the eye above it.
//! * A viewer standing on that floor has its feet in the floor voxel and its eye at
//!   most `eye_height` above the floor voxel's top: the column from the floor voxel up
//!   to `ceil(eye_height / h)` voxels above its top holds it, and those voxels must be
//!   open (the eye's room).
//! * Columns whose floor voxels lie in the same band of two voxels (steps, slopes) are
//!   merged greedily into rectangles of at
//!   most `width` voxels a side holding no closed face between two of its voxels: a
//!   viewcell never straddles a wall on the lattice, and its box is open (every column
//!   of it has the eye's room).

use crate::cells::VoxelBox;
use crate::voxels::{Voxels, AIR, SURFACE};
use sightline_geom::DVec3;
use std::collections::BTreeMap;

/// How far the eye may lie above the floor, and how wide a viewcell may be.
#[derive(Clone, Copy, Debug)]
pub struct Walker {
    /// Eye height above the floor (scene units).
    pub eye_height: f64,
    /// Largest viewcell side, in voxels.
    pub width: usize,
}

/// Whether triangle `t` faces up or down within about 45° of the vertical.
fn horizontal(t: &[DVec3; 3]) -> bool {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let len = n.length();
    len > 0.0 && len.is_finite() && n.z.abs() >= 0.7 * len
}

/// The walkable viewcells of a voxelized level (module doc): boxes in voxel
/// coordinates, ordered by standing level, then y, then x.
pub fn walkable(v: &Voxels, tris: &[[DVec3; 3]], walker: &Walker) -> Vec<VoxelBox> {
    let g = &v.grid;
    let [nx, ny, nz] = g.dims;
    let eye = ((walker.eye_height.max(0.0) / g.size).ceil() as usize).max(1);
    let is_floor = |i: usize| is_floor(v, tris, i);
    let open = |i: usize| v.state[i] == AIR || v.state[i] == SURFACE;
    // Standing levels: z of the floor voxel → columns (x, y).
    let mut levels: BTreeMap<usize, Vec<(usize, usize)>> = BTreeMap::new();
    for z in 0..nz.saturating_sub(eye) {
        for y in 0..ny {
            for x in 0..nx {
                let f = g.index(x, y, z);
                if !is_floor(f) || is_floor(g.index(x, y, z + 1)) {
                    continue;
                }
                let room = (1..=eye).all(|d| {
                    let i = g.index(x, y, z + d);
                    open(i) && !v.face_closed(g.index(x, y, z + d - 1), 2)
                });
                if room {
                    levels.entry(z).or_default().push((x, y));
                }
            }
        }
    }
    let width = walker.width.max(1);
    let mut out = Vec::new();
    // Standing levels two voxels apart share viewcells (steps and slopes): the box of
    // band `b` spans the floor voxels 2b and 2b + 1 and the eye's room above both.
    let mut bands: BTreeMap<usize, Vec<(usize, usize)>> = BTreeMap::new();
    for (z, cols) in levels {
        bands.entry(z / 2).or_default().extend(cols);
    }
    for (band, cols) in bands {
        let (z0, z1) = (2 * band, (2 * band + 2 + eye).min(nz));
        let mut flag = vec![false; nx * ny];
        for &(x, y) in &cols {
            flag[y * nx + x] = true;
        }
        // A flagged column [z0, z1) is open with no closed face across it (`room`).
        let no_wall =
            |x: usize, y: usize, k: usize| (z0..z1).all(|zz| !v.face_closed(g.index(x, y, zz), k));
        for y in 0..ny {
            for x in 0..nx {
                if !flag[y * nx + x] {
                    continue;
                }
                let mut x1 = x + 1;
                while x1 < nx && x1 - x < width && flag[y * nx + x1] && no_wall(x1 - 1, y, 0) {
                    x1 += 1;
                }
                let mut y1 = y + 1;
                while y1 < ny
                    && y1 - y < width
                    && (x..x1).all(|xx| {
                        flag[y1 * nx + xx]
                            && no_wall(xx, y1 - 1, 1)
                            && (xx + 1 == x1 || no_wall(xx, y1, 0))
                    })
                {
                    y1 += 1;
                }
                for yy in y..y1 {
                    for xx in x..x1 {
                        flag[yy * nx + xx] = false;
                    }
                }
                out.push(VoxelBox {
                    lo: [x, y, z0],
                    hi: [x1, y1, z1],
                });
            }
        }
    }
    out
}

/// The viewcells a walker reaches from the voxels `starts`, generously. The walker
/// moves through *walk space*: open voxels at most `reach` voxels above a floor voxel
/// (the module's floors), in any of six directions — so it climbs stairs, slopes and
/// any wall at most `reach` voxels high, and passes doors too low for the eye's
/// room; it steps off a ledge into open space beside it and falls straight down
/// through open voxels until it meets walk space again. No collision model (a gap a
/// body cannot pass counts as passable), so a point where a walker can stand stays in
/// a kept viewcell; teleporters and lifts need a start of their own. Returns the
/// indices of the viewcells holding a reached voxel, ascending.
pub fn reachable(
    v: &Voxels,
    tris: &[[DVec3; 3]],
    cells: &[VoxelBox],
    starts: &[[usize; 3]],
    reach: usize,
) -> Vec<usize> {
    let g = &v.grid;
    let [nx, ny, nz] = g.dims;
    let open = |i: usize| v.state[i] == AIR || v.state[i] == SURFACE;
    // Height above the nearest floor voxel below, through open voxels.
    let mut walk = vec![false; g.len()];
    for y in 0..ny {
        for x in 0..nx {
            let mut above: Option<usize> = None;
            for z in 0..nz {
                let i = g.index(x, y, z);
                if is_floor(v, tris, i) {
                    above = Some(0);
                } else if open(i) {
                    above = above.map(|d| d + 1);
                } else {
                    above = None;
                }
                walk[i] = open(i) && above.is_some_and(|d| d <= reach);
            }
        }
    }
    const WALK: u8 = 1;
    const FALL: u8 = 2;
    let mut state = vec![0u8; g.len()];
    let mut todo: Vec<usize> = Vec::new();
    for s in starts {
        if (0..3).all(|k| s[k] < g.dims[k]) {
            let i = g.index(s[0], s[1], s[2]);
            if open(i) && state[i] == 0 {
                state[i] = if walk[i] { WALK } else { FALL };
                todo.push(i);
            }
        }
    }
    while let Some(i) = todo.pop() {
        let [x, y, z] = g.coords(i);
        let mut go = |j: usize, falling: bool, state: &mut Vec<u8>| {
            if state[j] == 0 && open(j) && (walk[j] || falling) {
                state[j] = if walk[j] { WALK } else { FALL };
                todo.push(j);
            }
        };
        if z > 0 {
            go(g.index(x, y, z - 1), true, &mut state);
        }
        if state[i] == WALK {
            if z + 1 < nz {
                go(g.index(x, y, z + 1), false, &mut state);
            }
            // Sideways: into walk space, or off a ledge into open space to fall.
            for (dx, dy) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                let (xx, yy) = (x as i64 + dx, y as i64 + dy);
                if xx >= 0 && yy >= 0 && (xx as usize) < nx && (yy as usize) < ny {
                    go(g.index(xx as usize, yy as usize, z), true, &mut state);
                }
            }
        }
    }
    (0..cells.len())
        .filter(|&c| {
            let b = &cells[c];
            (b.lo[2]..b.hi[2]).any(|z| {
                (b.lo[1]..b.hi[1]).any(|y| (b.lo[0]..b.hi[0]).any(|x| state[g.index(x, y, z)] != 0))
            })
        })
        .collect()
}

/// A floor voxel: a surface voxel holding a triangle within about 45° of horizontal.
fn is_floor(v: &Voxels, tris: &[[DVec3; 3]], i: usize) -> bool {
    v.state[i] == SURFACE
        && v.triangles_in(i)
            .iter()
            .any(|&t| horizontal(&tris[t as usize]))
}
