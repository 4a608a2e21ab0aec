//! The ground-truth visible set of a cell: stratified viewpoints render the full sphere
//! of directions into object-id buffers, then targeted exact rays look for every object
//! still unseen (see the module doc of [`super`]).

use super::rays::{dist_to_boundary, segment_meets, Grid, Item, Occluder};
use super::samples::{
    cell_hash, nudge_inward, polygon_area3, random_edge_point, random_point, random_top_edge_point,
    stratified,
};
use crate::Cell;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sightline_geom::{DVec3, ViewCell};
use sightline_raster::{prism_faces, Coverage, Face, Framebuffer, View, NO_ID};
use sightline_scene::{Geometry, Scene};
use sightline_stats::Rng;
use std::time::Instant;

/// Viewpoints are taken in the cell shrunk by this much (metres).
pub const INSET_M: f64 = 1e-3;
/// Near plane of the cube-face renderings (metres; below INSET_M / 2).
pub(super) const NEAR_M: f64 = 1e-4;

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

/// A face to render: a planar convex polygon, its outward normal if the object is a
/// closed solid (back faces are culled), and its object id.
#[derive(Clone, Debug)]
pub(super) struct RFace {
    pub(super) id: u32,
    pub(super) verts: Vec<DVec3>,
    pub(super) normal: Option<DVec3>,
    pub(super) area: f64,
}

/// A scene prepared for ground truth: faces to render, occluders to cast rays against
/// (in a uniform 2D grid), and per-object surface samplers. Build once, query many cells.
pub struct TruthScene {
    pub(super) objects: usize,
    pub(super) faces: Vec<RFace>,
    /// Faces of each object (indices into `faces`).
    pub(super) object_faces: Vec<Vec<u32>>,
    pub(super) items: Vec<Item>,
    pub(super) grid: Grid,
    pub(super) blocks: Vec<u32>,
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
    pub(super) fn in_block(&self, p: DVec3, margin: f64) -> bool {
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
        self.viewpoints_in(&Cell::Box(*cell), opts)
    }

    /// Stratified viewpoints of a viewcell of any kind in its free space: those of its
    /// bounding box (shrunk by [`INSET_M`]) that lie in the cell.
    pub fn viewpoints_in(&self, cell: &Cell, opts: &TruthOptions) -> Vec<DVec3> {
        let bounds = cell.bounds();
        let (lo, hi) = inset_box(&bounds);
        let mut rng = Rng::new(opts.seed ^ cell_hash(&bounds));
        let pts = stratified(lo, hi, opts.samples.max(1) as usize, &mut rng);
        pts.into_iter()
            .filter(|p| {
                p.z > INSET_M / 2.0 && cell.contains(*p) && !self.in_block(*p, INSET_M / 2.0)
            })
            .collect()
    }

    /// The ground-truth visible set of `cell`.
    pub fn ground_truth(&self, cell: &ViewCell, opts: &TruthOptions) -> Truth {
        self.ground_truth_in(&Cell::Box(*cell), opts)
    }

    /// The ground-truth visible set of a viewcell of any kind (`Truth::cell` is its
    /// bounding box).
    pub fn ground_truth_in(&self, region: &Cell, opts: &TruthOptions) -> Truth {
        let t0 = Instant::now();
        let cell = &region.bounds();
        let vps = self.viewpoints_in(region, opts);
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
                .filter_map(|id| {
                    self.targeted(id as u32, &vps, opts, region)
                        .map(|w| (id, w))
                })
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
    pub(super) fn bin_faces(&self, eye: DVec3) -> [Vec<u32>; 6] {
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
        region: &Cell,
    ) -> Option<Witness> {
        let cell = &region.bounds();
        let faces = &self.object_faces[id as usize];
        if faces.is_empty() {
            return None;
        }
        let mut rng =
            Rng::new(opts.seed ^ cell_hash(cell) ^ (id as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15));
        let (lo, hi) = inset_box(cell);
        for r in 0..opts.targeted_rays_per_object as usize {
            // Odd rays start at the rendered viewpoints, even ones at fresh uniform points
            // of the cell's free space (what is seen only from a small part of the cell
            // is found without more renderings; the rays do not depend on `samples`).
            let fresh = lo + (hi - lo) * DVec3::new(rng.f64(), rng.f64(), rng.f64());
            let vp = if r % 2 == 0
                && fresh.z > INSET_M / 2.0
                && region.contains(fresh)
                && !self.in_block(fresh, INSET_M / 2.0)
            {
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
            let mut pick = rng.f64() * total;
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
}

/// The box viewpoints are taken from: the cell shrunk by [`INSET_M`] (per axis, when
/// it is wider than twice that).
pub(super) fn inset_box(cell: &ViewCell) -> (DVec3, DVec3) {
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

/// The ground-truth visible set of `cell` in `scene` (prepares the scene each call; use
/// [`TruthScene`] to check many cells).
pub fn ground_truth(scene: &Scene, cell: &ViewCell, opts: &TruthOptions) -> Truth {
    TruthScene::new(scene).ground_truth(cell, opts)
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

impl TruthScene {
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
