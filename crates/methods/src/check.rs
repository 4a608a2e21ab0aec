//! Ground-truth visible sets and the checking of methods against them (SPEC §3).
//!
//! The **visible set (VS)** of a cell is estimated by dense sampling (survey §7.6,
//! "aggressive" visibility): stratified viewpoints in the cell's free space each render
//! the full sphere of directions (six cube faces) into object-id buffers with the
//! standard coverage rule, and the ids seen are united. *Targeted* rays then look for
//! every object still unseen: segments from the viewpoints (and from fresh random points
//! of the cell's free space) to random points of the object's front faces (their area,
//! their highest edge: a roof line seen over other roofs, and their boundary), tested
//! exactly against every other object (a ray caster of its own, independent of the
//! rasterizer), so that objects seen only through gaps or as slivers narrower than a
//! pixel are found too. Every id reported comes with a [`Witness`]: the viewpoint and
//! the direction of a sample that saw it.
//!
//! The VS is a *lower bound* of the true visible set: an object in the VS is visible,
//! so a conservative PVS must contain it (NOTES §6). Grazing sight lines do not count
//! (SPEC §3): a targeted ray is accepted only if it stays farther than [`GRAZE_M`] from
//! every other object, and the rasterizer's closed, watertight standard rule leaves no
//! crack along shared edges (a party wall seen edge-on shows no pixel of what lies
//! behind it).
//!
//! Viewpoints lie in the cell shrunk by [`INSET_M`] (a cell touching a facade then sees
//! the facade at a positive distance); points inside or within [`INSET_M`]/2 of a block
//! are not viewpoints (SPEC §2), nor points at or below the ground.
//!
//! ```
//! use sightline_methods::check::{ground_truth, TruthOptions};
//! use sightline_scene::{Scene, Object};
//! use sightline_geom::{Polygon, DVec2, ViewCell};
//! // A 10 m high wall at y = 10..11 hides a 5 m block behind it, not a 40 m tower.
//! let rect = |x0, y0, x1, y1| Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1));
//! let scene = Scene::from_objects(vec![
//!     Object::block(Some("wall".into()), rect(-50.0, 10.0, 50.0, 11.0), 0.0, 10.0),
//!     Object::block(Some("low".into()), rect(-5.0, 20.0, 5.0, 30.0), 0.0, 5.0),
//!     Object::block(Some("tower".into()), rect(10.0, 20.0, 20.0, 30.0), 0.0, 40.0),
//! ]);
//! let cell: ViewCell = "-2,0,1.5,2,4,2".parse().unwrap();
//! let opts = TruthOptions { samples: 16, resolution_px: 128, ..TruthOptions::default() };
//! let truth = ground_truth(&scene, &cell, &opts);
//! assert_eq!(truth.visible, vec![0, 2]);
//! ```

use crate::{MethodError, VisibilityMethod};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sightline_geom::{DVec2, DVec3, Polygon, ViewCell};
use sightline_raster::{prism_faces, Coverage, Face, Framebuffer, View, NO_ID};
use sightline_scene::{Geometry, Scene};
use std::time::Instant;

/// Viewpoints are taken in the cell shrunk by this much (metres).
pub const INSET_M: f64 = 1e-3;
/// A targeted ray passing closer than this to another object does not count (metres).
pub const GRAZE_M: f64 = 1e-6;
/// Near plane of the cube-face renderings (metres; below INSET_M / 2).
const NEAR_M: f64 = 1e-4;

/// Parameters of the ground truth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TruthOptions {
    /// Number of viewpoints (corners, edges, faces, interior; stratified).
    pub samples: u32,
    /// Cube-face resolution (pixels per side).
    pub resolution_px: u32,
    /// Targeted rays per object not seen by the renderings (spread over the viewpoints).
    pub targeted_rays_per_object: u32,
    /// Seed of the jitter (results are deterministic for a seed).
    pub seed: u64,
}

impl Default for TruthOptions {
    fn default() -> Self {
        TruthOptions {
            samples: 128,
            resolution_px: 1024,
            targeted_rays_per_object: 256,
            seed: 1,
        }
    }
}

/// The sample that saw an object: from `viewpoint`, looking along `direction` (unit).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Witness {
    pub id: u32,
    pub viewpoint: [f64; 3],
    pub direction: [f64; 3],
}

/// A ground-truth visible set.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    pub cell: ViewCell,
    /// Ids seen, sorted ascending.
    pub visible: Vec<u32>,
    /// One witness per id of `visible`, in the same order.
    pub witnesses: Vec<Witness>,
    /// Viewpoints actually used (outside blocks).
    pub samples_used: u32,
    /// How many of `visible` only the targeted rays found.
    pub found_by_rays: u32,
    pub seconds: f64,
}

/// A ray-casting occluder: an exact prism or a mesh triangle, of object `id`.
#[derive(Clone, Debug)]
enum Occluder {
    Prism {
        footprint: Polygon,
        base: f64,
        top: f64,
    },
    Triangle([DVec3; 3]),
}

#[derive(Clone, Debug)]
struct Item {
    id: u32,
    lo: DVec3,
    hi: DVec3,
    occ: Occluder,
}

/// A face to render: a planar convex polygon, its outward normal if the object is a
/// closed solid (back faces are culled), and its object id.
#[derive(Clone, Debug)]
struct RFace {
    id: u32,
    verts: Vec<DVec3>,
    normal: Option<DVec3>,
    area: f64,
}

/// A scene prepared for ground truth: faces to render, occluders to cast rays against
/// (in a uniform 2D grid), and per-object surface samplers. Build once, query many cells.
pub struct TruthScene {
    objects: usize,
    faces: Vec<RFace>,
    /// Faces of each object (indices into `faces`).
    object_faces: Vec<Vec<u32>>,
    items: Vec<Item>,
    grid: Grid,
    blocks: Vec<u32>,
}

/// Uniform grid over the xy plane holding item indices.
struct Grid {
    origin: DVec2,
    cell: f64,
    nx: usize,
    ny: usize,
    cells: Vec<Vec<u32>>,
}

impl Grid {
    fn new(items: &[Item]) -> Grid {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for it in items {
            lo = lo.min(it.lo.truncate());
            hi = hi.max(it.hi.truncate());
        }
        if items.is_empty() {
            lo = DVec2::ZERO;
            hi = DVec2::ONE;
        }
        let size = (hi - lo).max(DVec2::splat(1.0));
        let cell = ((size.x * size.y) / (items.len().max(1) as f64))
            .sqrt()
            .max(1.0)
            * 1.5;
        let nx = ((size.x / cell).ceil() as usize).clamp(1, 4096);
        let ny = ((size.y / cell).ceil() as usize).clamp(1, 4096);
        let cell = (size.x / nx as f64).max(size.y / ny as f64);
        let mut g = Grid {
            origin: lo,
            cell,
            nx,
            ny,
            cells: vec![Vec::new(); nx * ny],
        };
        for (k, it) in items.iter().enumerate() {
            let (x0, y0) = g.index(it.lo.truncate());
            let (x1, y1) = g.index(it.hi.truncate());
            for y in y0..=y1 {
                for x in x0..=x1 {
                    g.cells[y * nx + x].push(k as u32);
                }
            }
        }
        g
    }

    fn index(&self, p: DVec2) -> (usize, usize) {
        let q = (p - self.origin) / self.cell;
        (
            (q.x.floor().max(0.0) as usize).min(self.nx - 1),
            (q.y.floor().max(0.0) as usize).min(self.ny - 1),
        )
    }

    /// Visit the grid cells the 2D segment `a → b` passes through (Amanatides–Woo), in
    /// order, until `f` returns true. Returns whether it did.
    fn walk(&self, a: DVec2, b: DVec2, mut f: impl FnMut(&[u32]) -> bool) -> bool {
        let (mut x, mut y) = self.index(a);
        let (xe, ye) = self.index(b);
        let d = b - a;
        let step_x: i64 = if d.x > 0.0 { 1 } else { -1 };
        let step_y: i64 = if d.y > 0.0 { 1 } else { -1 };
        let next_bound =
            |i: usize, s: i64, o: f64| o + (i as f64 + if s > 0 { 1.0 } else { 0.0 }) * self.cell;
        let mut t_max_x = if d.x != 0.0 {
            (next_bound(x, step_x, self.origin.x) - a.x) / d.x
        } else {
            f64::INFINITY
        };
        let mut t_max_y = if d.y != 0.0 {
            (next_bound(y, step_y, self.origin.y) - a.y) / d.y
        } else {
            f64::INFINITY
        };
        let t_dx = if d.x != 0.0 {
            self.cell / d.x.abs()
        } else {
            f64::INFINITY
        };
        let t_dy = if d.y != 0.0 {
            self.cell / d.y.abs()
        } else {
            f64::INFINITY
        };
        let limit = self.nx + self.ny + 4;
        for _ in 0..limit {
            if f(&self.cells[y * self.nx + x]) {
                return true;
            }
            if x == xe && y == ye {
                return false;
            }
            if t_max_x < t_max_y {
                let nx = x as i64 + step_x;
                if nx < 0 || nx >= self.nx as i64 || t_max_x > 1.0 {
                    break;
                }
                x = nx as usize;
                t_max_x += t_dx;
            } else {
                let ny = y as i64 + step_y;
                if ny < 0 || ny >= self.ny as i64 || t_max_y > 1.0 {
                    break;
                }
                y = ny as usize;
                t_max_y += t_dy;
            }
        }
        // Fell off the walk (rounding at a cell corner): visit the end cell too.
        f(&self.cells[ye * self.nx + xe])
    }
}

fn polygon_area3(v: &[DVec3]) -> (DVec3, f64) {
    let mut n = DVec3::ZERO;
    for k in 1..v.len().saturating_sub(1) {
        n += (v[k] - v[0]).cross(v[k + 1] - v[0]);
    }
    let len = n.length();
    (if len > 0.0 { n / len } else { DVec3::Z }, 0.5 * len)
}

impl TruthScene {
    /// Prepare `scene`.
    pub fn new(scene: &Scene) -> TruthScene {
        let mut faces = Vec::new();
        let mut object_faces = vec![Vec::new(); scene.objects.len()];
        let mut items = Vec::new();
        let mut blocks = Vec::new();
        for (id, o) in scene.objects.iter().enumerate() {
            let id = id as u32;
            let mut push = |verts: Vec<DVec3>, solid: bool, faces: &mut Vec<RFace>| {
                let (n, area) = polygon_area3(&verts);
                if area <= 0.0 {
                    return;
                }
                object_faces[id as usize].push(faces.len() as u32);
                faces.push(RFace {
                    id,
                    verts,
                    normal: solid.then_some(n),
                    area,
                });
            };
            match &o.geometry {
                Geometry::Blocks(prisms) => {
                    for p in prisms {
                        if !(p.top > p.base) {
                            continue;
                        }
                        // Walls are quads oriented by the ring's winding; make each face
                        // outward whatever the input winding was (normals drive culling).
                        let fp = p.footprint.clone().normalized();
                        for f in prism_faces(&fp, p.base, p.top) {
                            push(f, true, &mut faces);
                        }
                        let bb = p.aabb();
                        blocks.push(items.len() as u32);
                        items.push(Item {
                            id,
                            lo: bb.min,
                            hi: bb.max,
                            occ: Occluder::Prism {
                                footprint: fp,
                                base: p.base,
                                top: p.top,
                            },
                        });
                    }
                }
                Geometry::Flat(polys) => {
                    for t in polys.iter().flat_map(|p| p.triangulate_at(0.0)) {
                        push(t.to_vec(), false, &mut faces);
                    }
                }
                Geometry::Mesh(m) => {
                    for t in &m.triangles {
                        let tri = m.triangle(t);
                        push(tri.to_vec(), false, &mut faces);
                        let lo = tri[0].min(tri[1]).min(tri[2]);
                        let hi = tri[0].max(tri[1]).max(tri[2]);
                        items.push(Item {
                            id,
                            lo,
                            hi,
                            occ: Occluder::Triangle(tri),
                        });
                    }
                }
            }
        }
        let grid = Grid::new(&items);
        TruthScene {
            objects: scene.objects.len(),
            faces,
            object_faces,
            items,
            grid,
            blocks,
        }
    }

    /// Whether `p` is inside a block or closer than `margin` to one.
    fn in_block(&self, p: DVec3, margin: f64) -> bool {
        let mut hit = false;
        self.grid.walk(p.truncate(), p.truncate(), |cell| {
            for &k in cell {
                let it = &self.items[k as usize];
                if let Occluder::Prism {
                    footprint,
                    base,
                    top,
                } = &it.occ
                {
                    if p.z < base - margin || p.z > top + margin {
                        continue;
                    }
                    let q = p.truncate();
                    if footprint.contains(q) || dist_to_boundary(footprint, q) <= margin {
                        hit = true;
                        return true;
                    }
                }
            }
            false
        });
        let _ = &self.blocks;
        hit
    }

    /// Stratified viewpoints of `cell` in its free space.
    pub fn viewpoints(&self, cell: &ViewCell, opts: &TruthOptions) -> Vec<DVec3> {
        let (lo, hi) = inset_box(cell);
        let mut rng = SplitMix(opts.seed ^ cell_hash(cell));
        let pts = stratified(lo, hi, opts.samples.max(1) as usize, &mut rng);
        pts.into_iter()
            .filter(|p| p.z > INSET_M / 2.0 && !self.in_block(*p, INSET_M / 2.0))
            .collect()
    }

    /// The ground-truth visible set of `cell`.
    pub fn ground_truth(&self, cell: &ViewCell, opts: &TruthOptions) -> Truth {
        let t0 = Instant::now();
        let vps = self.viewpoints(cell, opts);
        let res = opts.resolution_px.max(8);
        // Rendering: union of ids over viewpoints × faces, first witness kept.
        let seen: Vec<(Option<Witness>, bool)> = vps
            .par_iter()
            // One framebuffer per rayon job, reused over its viewpoints (no 8 MB
            // allocation and page faults per viewpoint).
            .map_init(
                || Framebuffer::new(res, res),
                |fb, &eye| {
                    // Per object: its witness, and whether it is a strong one.
                    let mut seen: Vec<(Option<Witness>, bool)> = vec![(None, false); self.objects];
                    let bins = self.bin_faces(eye);
                    for (face, bin) in Face::ALL.into_iter().zip(&bins) {
                        let view = View::cube_face(eye, face, res, NEAR_M);
                        fb.clear();
                        self.render(&view, bin, fb);
                        let ids = &fb.ids;
                        let w = res as usize;
                        for (k, &id) in ids.iter().enumerate() {
                            if id == NO_ID || seen[id as usize].1 {
                                continue;
                            }
                            // The witness pixel: preferably one whose four neighbours
                            // show the same object (a strong witness: its ray meets the
                            // object well inside its silhouette, not at a grazing
                            // edge); else the first one.
                            let (i, j) = (k % w, k / w);
                            let interior = i > 0
                                && i + 1 < w
                                && j > 0
                                && j + 1 < w
                                && ids[k - 1] == id
                                && ids[k + 1] == id
                                && ids[k - w] == id
                                && ids[k + w] == id;
                            if interior || seen[id as usize].0.is_none() {
                                let d = view.direction(i as f64 + 0.5, j as f64 + 0.5);
                                seen[id as usize] = (
                                    Some(Witness {
                                        id,
                                        viewpoint: eye.to_array(),
                                        direction: d.to_array(),
                                    }),
                                    interior,
                                );
                            }
                        }
                    }
                    seen
                },
            )
            .reduce(
                || vec![(None, false); self.objects],
                |mut a, b| {
                    for (x, y) in a.iter_mut().zip(b) {
                        if x.0.is_none() || (!x.1 && y.1) {
                            *x = y;
                        }
                    }
                    a
                },
            );
        let seen: Vec<Option<Witness>> = seen.into_iter().map(|(w, _)| w).collect();
        // Targeted rays for the objects still unseen.
        let rendered = seen.iter().filter(|s| s.is_some()).count();
        let mut seen = seen;
        if !vps.is_empty() && opts.targeted_rays_per_object > 0 {
            let found: Vec<(usize, Witness)> = (0..self.objects)
                .into_par_iter()
                .filter(|&id| seen[id].is_none())
                .filter_map(|id| self.targeted(id as u32, &vps, opts, cell).map(|w| (id, w)))
                .collect();
            for (id, w) in found {
                seen[id] = Some(w);
            }
        }
        let witnesses: Vec<Witness> = seen.into_iter().flatten().collect();
        let visible: Vec<u32> = witnesses.iter().map(|w| w.id).collect();
        Truth {
            cell: *cell,
            found_by_rays: (visible.len() - rendered) as u32,
            visible,
            witnesses,
            samples_used: vps.len() as u32,
            seconds: t0.elapsed().as_secs_f64(),
        }
    }

    /// The faces each cube face around `eye` may show, in [`Face::ALL`] order: back faces
    /// of solids culled, and faces whose vertices all lie outside one plane of a cube
    /// face's frustum (the near plane or a side) left out of that face's list. One pass
    /// over the scene per viewpoint instead of one per cube face.
    fn bin_faces(&self, eye: DVec3) -> [Vec<u32>; 6] {
        let mut bins: [Vec<u32>; 6] = Default::default();
        // Per cube face: (forward axis, sign, the two other axes). A cube face's camera
        // coordinates are ±components of `v - eye`, so these tests are the ones of
        // `View::to_camera` exactly.
        let frames: [(usize, f64, usize, usize); 6] = Face::ALL.map(|f| {
            let (fw, _) = f.axes();
            let a = (0..3).find(|&k| fw[k] != 0.0).unwrap_or(0);
            (a, fw[a], (a + 1) % 3, (a + 2) % 3)
        });
        for (k, f) in self.faces.iter().enumerate() {
            if let Some(n) = f.normal {
                if n.dot(eye - f.verts[0]) <= 0.0 {
                    continue;
                }
            }
            // Bit 5 c + p: every vertex lies outside plane p of cube face c.
            let mut out = u32::MAX;
            for v in &f.verts {
                let d = *v - eye;
                let mut m = 0u32;
                for (c, &(a, s, b, e)) in frames.iter().enumerate() {
                    let z = s * d[a];
                    let bits = (z < NEAR_M) as u32
                        | ((d[b] > z) as u32) << 1
                        | ((d[b] < -z) as u32) << 2
                        | ((d[e] > z) as u32) << 3
                        | ((d[e] < -z) as u32) << 4;
                    m |= bits << (5 * c);
                }
                out &= m;
            }
            for (c, bin) in bins.iter_mut().enumerate() {
                if (out >> (5 * c)) & 0x1f == 0 {
                    bin.push(k as u32);
                }
            }
        }
        bins
    }

    /// Draw the faces of `list` into `fb` with the standard rule.
    fn render(&self, view: &View, list: &[u32], fb: &mut Framebuffer) {
        for &k in list {
            let f = &self.faces[k as usize];
            fb.draw_polygon(view, &f.verts, f.id, Coverage::Standard);
        }
    }

    /// Rays from the viewpoints to random points of object `id`; the first clear one.
    fn targeted(
        &self,
        id: u32,
        vps: &[DVec3],
        opts: &TruthOptions,
        cell: &ViewCell,
    ) -> Option<Witness> {
        let faces = &self.object_faces[id as usize];
        if faces.is_empty() {
            return None;
        }
        let mut rng =
            SplitMix(opts.seed ^ cell_hash(cell) ^ (id as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let (lo, hi) = inset_box(cell);
        for r in 0..opts.targeted_rays_per_object as usize {
            // Odd rays start at the rendered viewpoints, even ones at fresh uniform points
            // of the cell's free space (what is seen only from a small part of the cell
            // is found without more renderings; the rays do not depend on `samples`).
            let fresh = lo + (hi - lo) * DVec3::new(rng.next(), rng.next(), rng.next());
            let vp =
                if r % 2 == 0 && fresh.z > INSET_M / 2.0 && !self.in_block(fresh, INSET_M / 2.0) {
                    fresh
                } else {
                    vps[(r + id as usize) % vps.len()]
                };
            // An area-weighted face among those facing the viewpoint.
            let front = |f: &RFace| f.normal.is_none_or(|n| n.dot(vp - f.verts[0]) > 0.0);
            let total: f64 = faces
                .iter()
                .map(|&f| &self.faces[f as usize])
                .filter(|f| front(f))
                .map(|f| f.area)
                .sum();
            if !(total > 0.0) {
                continue;
            }
            let mut pick = rng.next() * total;
            let mut face = &self.faces[faces[0] as usize];
            for &f in faces {
                let cand = &self.faces[f as usize];
                if !front(cand) {
                    continue;
                }
                face = cand;
                pick -= face.area;
                if pick <= 0.0 {
                    break;
                }
            }
            // What is seen of a far object over the roofs or through a gap is mostly a
            // sliver along an edge, which area sampling rarely hits: a third of the rays
            // aim at the face's highest edge (a roof line seen from the street), a third
            // at any point of its boundary (corners, gaps), a third at its area.
            let target = match r % 3 {
                0 => random_point(&face.verts, &mut rng),
                1 => nudge_inward(random_top_edge_point(&face.verts, &mut rng), &face.verts),
                _ => nudge_inward(random_edge_point(&face.verts, &mut rng), &face.verts),
            };
            if target.z < 0.0 {
                continue;
            }
            if !self.segment_blocked(vp, target, id) {
                let d = (target - vp).normalize_or_zero();
                return Some(Witness {
                    id,
                    viewpoint: vp.to_array(),
                    direction: d.to_array(),
                });
            }
        }
        None
    }

    /// Whether the segment `a → b` meets (or passes within GRAZE_M of) an object other
    /// than `target`.
    pub fn segment_blocked(&self, a: DVec3, b: DVec3, target: u32) -> bool {
        let mut tested: Vec<u32> = Vec::new();
        self.grid.walk(a.truncate(), b.truncate(), |cell| {
            for &k in cell {
                let it = &self.items[k as usize];
                if it.id == target || tested.contains(&k) {
                    continue;
                }
                tested.push(k);
                if segment_meets(a, b, it) {
                    return true;
                }
            }
            false
        })
    }
}

/// The box viewpoints are taken from: the cell shrunk by [`INSET_M`] (per axis, when
/// it is wider than twice that).
fn inset_box(cell: &ViewCell) -> (DVec3, DVec3) {
    let mut lo = cell.min;
    let mut hi = cell.max;
    for a in 0..3 {
        if hi[a] - lo[a] > 2.0 * INSET_M {
            lo[a] += INSET_M;
            hi[a] -= INSET_M;
        }
    }
    (lo, hi)
}

/// Distance from `p` to the boundary of `poly`.
fn dist_to_boundary(poly: &Polygon, p: DVec2) -> f64 {
    poly.edges()
        .map(|(a, b)| point_segment_dist(p, a, b))
        .fold(f64::INFINITY, f64::min)
}

fn point_segment_dist(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let l2 = ab.length_squared();
    let t = if l2 > 0.0 {
        ((p - a).dot(ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * t - p).length()
}

fn segments_dist(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> f64 {
    let o = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let (d1, d2, d3, d4) = (o(c, d, a), o(c, d, b), o(a, b, c), o(a, b, d));
    if ((d1 > 0.0) != (d2 > 0.0) || d1 == 0.0 || d2 == 0.0)
        && ((d3 > 0.0) != (d4 > 0.0) || d3 == 0.0 || d4 == 0.0)
        && d1.signum() * d2.signum() <= 0.0
        && d3.signum() * d4.signum() <= 0.0
    {
        return 0.0;
    }
    point_segment_dist(a, c, d)
        .min(point_segment_dist(b, c, d))
        .min(point_segment_dist(c, a, b))
        .min(point_segment_dist(d, a, b))
}

/// Segment `a → b` against an occluder expanded by GRAZE_M.
fn segment_meets(a: DVec3, b: DVec3, it: &Item) -> bool {
    let g = GRAZE_M;
    // Slab test against the item's box.
    let d = b - a;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..3 {
        let (lo, hi) = (it.lo[k] - g, it.hi[k] + g);
        if d[k].abs() < 1e-300 {
            if a[k] < lo || a[k] > hi {
                return false;
            }
        } else {
            let (mut u, mut v) = ((lo - a[k]) / d[k], (hi - a[k]) / d[k]);
            if u > v {
                std::mem::swap(&mut u, &mut v);
            }
            t0 = t0.max(u);
            t1 = t1.min(v);
            if t0 > t1 {
                return false;
            }
        }
    }
    match &it.occ {
        Occluder::Prism { footprint, .. } => {
            // Within the z-slab already (the box's z-range is [base, top]).
            let p = (a + d * t0).truncate();
            let q = (a + d * t1).truncate();
            if footprint.contains(p) || footprint.contains(q) {
                return true;
            }
            footprint
                .edges()
                .any(|(e0, e1)| segments_dist(p, q, e0, e1) <= g)
        }
        Occluder::Triangle(tri) => segment_triangle(a, b, tri, g),
    }
}

/// Möller–Trumbore segment/triangle test with barycentric slack `eps` (metres, roughly).
fn segment_triangle(a: DVec3, b: DVec3, t: &[DVec3; 3], eps: f64) -> bool {
    let d = b - a;
    let e1 = t[1] - t[0];
    let e2 = t[2] - t[0];
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-18 {
        return false;
    }
    let inv = 1.0 / det;
    let s = a - t[0];
    let u = s.dot(p) * inv;
    let q = s.cross(e1);
    let v = d.dot(q) * inv;
    let tt = e2.dot(q) * inv;
    let slack = eps / e1.length().max(e2.length()).max(1e-12);
    u >= -slack && v >= -slack && u + v <= 1.0 + slack && (0.0..=1.0).contains(&tt)
}

/// `p` (on the boundary of the planar polygon `v`) moved 1 mm (at most a thousandth of
/// its distance) towards the centroid, into the face: the witness ray then meets the
/// face inside, not at its edge.
fn nudge_inward(p: DVec3, v: &[DVec3]) -> DVec3 {
    let c = v.iter().copied().sum::<DVec3>() / v.len().max(1) as f64;
    let d = c - p;
    let len = d.length();
    if len > 0.0 {
        p + d * (1e-3f64.min(1e-3 * len) / len)
    } else {
        p
    }
}

/// A uniform point on the highest edge of the polygon `v` (largest mean height of its
/// ends; the top edge of a wall).
fn random_top_edge_point(v: &[DVec3], rng: &mut SplitMix) -> DVec3 {
    let n = v.len();
    let k = (0..n)
        .max_by(|&a, &b| {
            let za = v[a].z + v[(a + 1) % n].z;
            let zb = v[b].z + v[(b + 1) % n].z;
            za.total_cmp(&zb)
        })
        .unwrap_or(0);
    let (a, b) = (v[k], v[(k + 1) % n]);
    a + (b - a) * rng.next()
}

/// A uniform point on the boundary of the polygon `v` (length-weighted edge).
fn random_edge_point(v: &[DVec3], rng: &mut SplitMix) -> DVec3 {
    let n = v.len();
    let total: f64 = (0..n).map(|k| (v[(k + 1) % n] - v[k]).length()).sum();
    let mut pick = rng.next() * total;
    let t = rng.next();
    for k in 0..n {
        let (a, b) = (v[k], v[(k + 1) % n]);
        let len = (b - a).length();
        if pick <= len || k + 1 == n {
            return a + (b - a) * t;
        }
        pick -= len;
    }
    v[0]
}

fn random_point(v: &[DVec3], rng: &mut SplitMix) -> DVec3 {
    // Fan triangles, area-weighted.
    let areas: Vec<f64> = (1..v.len() - 1)
        .map(|k| 0.5 * (v[k] - v[0]).cross(v[k + 1] - v[0]).length())
        .collect();
    let total: f64 = areas.iter().sum();
    let mut pick = rng.next() * total;
    let mut k = 0;
    while k + 1 < areas.len() && pick > areas[k] {
        pick -= areas[k];
        k += 1;
    }
    let (mut r1, mut r2) = (rng.next(), rng.next());
    if r1 + r2 > 1.0 {
        r1 = 1.0 - r1;
        r2 = 1.0 - r2;
    }
    v[0] + (v[k + 1] - v[0]) * r1 + (v[k + 2] - v[0]) * r2
}

/// SplitMix64 (deterministic, dependency-free).
struct SplitMix(u64);
impl SplitMix {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    fn next(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn cell_hash(cell: &ViewCell) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for v in cell.to_array() {
        h = (h ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// Stratified viewpoints in the box `[lo, hi]`: its 8 corners, points along its 12
/// edges, jittered points on its 6 faces and jittered strata of its interior, about `n`
/// in all (duplicates of degenerate boxes removed).
fn stratified(lo: DVec3, hi: DVec3, n: usize, rng: &mut SplitMix) -> Vec<DVec3> {
    let at = |u: DVec3| lo + (hi - lo) * u;
    let mut pts: Vec<DVec3> = Vec::with_capacity(n + 8);
    for c in 0..8 {
        pts.push(at(DVec3::new(
            (c & 1) as f64,
            ((c >> 1) & 1) as f64,
            ((c >> 2) & 1) as f64,
        )));
    }
    let rest = n.saturating_sub(8);
    let per_edge = (rest / 4) / 12;
    let per_face = (rest / 4) / 6;
    let interior = rest.saturating_sub(12 * per_edge + 6 * per_face);
    // Edges: along axis `a`, the other two coordinates at 0/1.
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for corner in 0..4 {
            for k in 0..per_edge {
                let mut u = DVec3::ZERO;
                u[a] = (k as f64 + 0.5 + (rng.next() - 0.5) * 0.5) / per_edge as f64;
                u[b] = (corner & 1) as f64;
                u[c] = ((corner >> 1) & 1) as f64;
                pts.push(at(u));
            }
        }
    }
    // Faces: normal axis `a` at 0/1, jittered strata over the other two.
    let side = (per_face as f64).sqrt().ceil() as usize;
    for a in 0..3 {
        let (b, c) = ((a + 1) % 3, (a + 2) % 3);
        for s in 0..2 {
            for k in 0..per_face {
                let (i, j) = (k % side.max(1), k / side.max(1));
                let mut u = DVec3::ZERO;
                u[a] = s as f64;
                u[b] = (i as f64 + rng.next()) / side.max(1) as f64;
                u[c] = ((j % side.max(1)) as f64 + rng.next()) / side.max(1) as f64;
                pts.push(at(u));
            }
        }
    }
    // Interior: jittered strata of a grid with about `interior` cells.
    let side = (interior as f64).cbrt().ceil() as usize;
    for k in 0..interior {
        let s = side.max(1);
        let (i, j, l) = (k % s, (k / s) % s, (k / (s * s)) % s);
        pts.push(at(DVec3::new(
            (i as f64 + rng.next()) / s as f64,
            (j as f64 + rng.next()) / s as f64,
            (l as f64 + rng.next()) / s as f64,
        )));
    }
    let mut out: Vec<DVec3> = Vec::with_capacity(pts.len());
    for p in pts {
        if !out.contains(&p) {
            out.push(p);
        }
    }
    out
}

/// The ground-truth visible set of `cell` in `scene` (prepares the scene each call; use
/// [`TruthScene`] to check many cells).
pub fn ground_truth(scene: &Scene, cell: &ViewCell, opts: &TruthOptions) -> Truth {
    TruthScene::new(scene).ground_truth(cell, opts)
}

/// An object of the VS that the PVS lacks, with the sample that saw it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Missed {
    pub id: u32,
    pub viewpoint: [f64; 3],
    pub direction: [f64; 3],
}

/// A method's PVS of one cell against the ground truth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellCheck {
    pub cell: ViewCell,
    pub pvs_len: usize,
    pub vs_len: usize,
    pub missed: Vec<Missed>,
    /// |PVS| / |VS| (1 when both are empty; |PVS| when only the VS is).
    pub over: f64,
    /// 1 − |PVS| / objects.
    pub hidden_fraction: f64,
    pub pvs_seconds: f64,
    pub truth_seconds: f64,
}

/// Compare a PVS with a truth.
pub fn compare(objects: usize, pvs: &[u32], truth: &Truth, pvs_seconds: f64) -> CellCheck {
    let missed: Vec<Missed> = truth
        .witnesses
        .iter()
        .filter(|w| pvs.binary_search(&w.id).is_err())
        .map(|w| Missed {
            id: w.id,
            viewpoint: w.viewpoint,
            direction: w.direction,
        })
        .collect();
    let vs_len = truth.visible.len();
    let over = if vs_len == 0 {
        pvs.len().max(1) as f64
    } else {
        pvs.len() as f64 / vs_len as f64
    };
    CellCheck {
        cell: truth.cell,
        pvs_len: pvs.len(),
        vs_len,
        missed,
        over,
        hidden_fraction: if objects == 0 {
            0.0
        } else {
            1.0 - pvs.len() as f64 / objects as f64
        },
        pvs_seconds,
        truth_seconds: truth.seconds,
    }
}

/// Check `method` on one cell.
pub fn check_cell(
    scene: &Scene,
    method: &dyn VisibilityMethod,
    cell: &ViewCell,
    opts: &TruthOptions,
) -> Result<CellCheck, MethodError> {
    check_cell_prepared(&TruthScene::new(scene), method, cell, opts)
}

/// Check `method` on one cell of a prepared scene.
pub fn check_cell_prepared(
    truth_scene: &TruthScene,
    method: &dyn VisibilityMethod,
    cell: &ViewCell,
    opts: &TruthOptions,
) -> Result<CellCheck, MethodError> {
    let t0 = Instant::now();
    let mut pvs = method.pvs(cell)?;
    let pvs_seconds = t0.elapsed().as_secs_f64();
    pvs.sort_unstable();
    pvs.dedup();
    let truth = truth_scene.ground_truth(cell, opts);
    Ok(compare(truth_scene.objects, &pvs, &truth, pvs_seconds))
}

/// Aggregate of [`CellCheck`]s (SPEC §5 check JSON).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckReport {
    pub method: String,
    pub cells: usize,
    /// Total missed ids over all cells (must be 0 for a conservative method).
    pub missed: usize,
    pub over_median: f64,
    pub over_p90: f64,
    pub over_max: f64,
    /// Mean hidden fraction.
    pub hidden_fraction: f64,
    /// Median PVS time per cell (ms).
    pub pvs_ms_median: f64,
    /// Median ground-truth time per cell (ms).
    pub truth_ms_median: f64,
    pub per_cell: Vec<CellCheck>,
}

fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return 0.0;
    }
    let k = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[k.min(sorted.len() - 1)]
}

/// Aggregate per-cell checks.
pub fn aggregate(method: &str, per_cell: Vec<CellCheck>) -> CheckReport {
    let mut overs: Vec<f64> = per_cell.iter().map(|c| c.over).collect();
    overs.sort_by(f64::total_cmp);
    let mut pvs_ms: Vec<f64> = per_cell.iter().map(|c| c.pvs_seconds * 1e3).collect();
    pvs_ms.sort_by(f64::total_cmp);
    let mut truth_ms: Vec<f64> = per_cell.iter().map(|c| c.truth_seconds * 1e3).collect();
    truth_ms.sort_by(f64::total_cmp);
    let n = per_cell.len();
    CheckReport {
        method: method.to_string(),
        cells: n,
        missed: per_cell.iter().map(|c| c.missed.len()).sum(),
        over_median: quantile(&overs, 0.5),
        over_p90: quantile(&overs, 0.9),
        over_max: overs.last().copied().unwrap_or(0.0),
        hidden_fraction: if n == 0 {
            0.0
        } else {
            per_cell.iter().map(|c| c.hidden_fraction).sum::<f64>() / n as f64
        },
        pvs_ms_median: quantile(&pvs_ms, 0.5),
        truth_ms_median: quantile(&truth_ms, 0.5),
        per_cell,
    }
}

/// Check `method` on many cells in parallel; `progress` is called once per finished cell.
pub fn check_cells(
    scene: &Scene,
    method: &dyn VisibilityMethod,
    cells: &[ViewCell],
    opts: &TruthOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<CheckReport, MethodError> {
    let ts = TruthScene::new(scene);
    let per_cell = cells
        .par_iter()
        .map(|c| {
            let r = check_cell_prepared(&ts, method, c, opts);
            progress();
            r
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(aggregate(method.name(), per_cell))
}

impl TruthScene {
    /// Ids seen from one point (six cube faces, standard rule, no targeted rays).
    pub fn visible_from(&self, eye: DVec3, resolution_px: u32) -> Vec<u32> {
        let mut fb = Framebuffer::new(resolution_px, resolution_px);
        let mut ids: Vec<u32> = Vec::new();
        let bins = self.bin_faces(eye);
        for (face, bin) in Face::ALL.into_iter().zip(&bins) {
            let view = View::cube_face(eye, face, resolution_px, NEAR_M);
            fb.clear();
            self.render(&view, bin, &mut fb);
            ids.extend(fb.ids_seen());
        }
        ids.sort_unstable();
        ids.dedup();
        ids
    }

    /// Whether `p` lies in free space (not inside a block, above the ground).
    pub fn is_free(&self, p: DVec3) -> bool {
        p.z > 0.0 && !self.in_block(p, 0.0)
    }
}

/// Up to `k` square street cells of side `size_m` at heights `z = (z0, z1)` whose whole
/// box is free of blocks (tested on a 5 × 5 grid at both heights), spread evenly over
/// the scene in a deterministic order.
pub fn street_cells(scene: &Scene, size_m: f64, z: (f64, f64), k: usize) -> Vec<ViewCell> {
    if scene.objects.is_empty() || k == 0 || !(size_m > 0.0) {
        return Vec::new();
    }
    let ts = TruthScene::new(scene);
    let b = scene.bounds.xy();
    let nx = ((b.size().x / size_m).floor() as usize).min(10_000);
    let ny = ((b.size().y / size_m).floor() as usize).min(10_000);
    let mut free = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            let lo = b.min + DVec2::new(i as f64, j as f64) * size_m;
            let ok = (0..5).all(|u| {
                (0..5).all(|v| {
                    let p = lo + DVec2::new(u as f64, v as f64) * (size_m / 4.0);
                    ts.is_free(p.extend(z.0)) && ts.is_free(p.extend(z.1))
                })
            });
            if ok {
                if let Ok(c) =
                    ViewCell::from_array([lo.x, lo.y, z.0, lo.x + size_m, lo.y + size_m, z.1])
                {
                    free.push(c);
                }
            }
        }
    }
    if free.len() <= k {
        return free;
    }
    (0..k)
        .map(|i| free[i * free.len() / k + free.len() / (2 * k)])
        .collect()
}
