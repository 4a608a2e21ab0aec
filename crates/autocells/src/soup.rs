//! A Quake level read as a triangle soup: its world faces as a plain mesh scene with no
//! tree, so that the automatic cells of this crate can be compared face by face with
//! the BSP path ([`sightline_portals`]) and with the level's own `vis` (issue #39).
//!
//! One object per world face, in face order, triangulated as a fan and wound
//! counter-clockwise seen from the face's front (the face's plane normal, flipped for
//! back-sided faces): the orientation [`crate::voxels`] reads as front. Sky faces are
//! kept: sky is opaque, as in the BSP path. Liquid surfaces (`*` textures) are left
//! out: the BSP path treats liquids as see-through (their leaves are open), so the soup
//! has no triangle there, and a face PVS compared with the soup's ignores them. Faces
//! with fewer than three vertices are left out too (no triangle).
//!
//! The soup is not clustered: each object is one face, so the clusters the PVS lists
//! are the faces, and [`Soup::faces`] maps them back to face ids exactly.
//!
//! [`judge`] compares the automatic cells' face PVS at random viewpoints with the faces
//! of the leaves `vis` says the viewpoint's leaf sees, with the BSP path's face PVS of
//! that leaf, and with a ray oracle through the BSP tree (Quake's hull trace, shared with
//! neither path): a clear segment from the viewpoint's cell to a face the PVS drops is a
//! miss. The tree is the level's exact geometry (solid and sky leaves opaque), so the
//! oracle judges the soup pipeline against the level itself, not against its voxels.

use crate::AutoCells;
use rayon::prelude::*;
use sightline_geom::DVec3;
use sightline_portals::oracle::{sample_leaf, segment_clear, Rng};
use sightline_portals::{Mode, Portals};
use sightline_scene::import::bsp::{is_liquid, BspLevel};
use sightline_scene::{Mesh, Object, Scene};
use std::io::Write;

/// A level's world faces as a triangle soup.
pub struct Soup {
    /// One mesh object per kept face (no inner bound: thin faces never occlude through
    /// a 2.5D bound; this crate's voxels do the occluding).
    pub scene: Scene,
    /// World face id of each object of `scene`, ascending.
    pub faces: Vec<u32>,
    /// Liquid faces left out.
    pub liquid_faces: usize,
}

/// The soup of `level`'s world faces (see the module doc).
pub fn bsp_soup(level: &BspLevel) -> Soup {
    let mut objects = Vec::new();
    let mut faces = Vec::new();
    let mut liquid_faces = 0;
    for (id, f) in level.faces.iter().enumerate() {
        if is_liquid(&f.texture) {
            liquid_faces += 1;
            continue;
        }
        if f.polygon.len() < 3 {
            continue;
        }
        let plane = level.planes[f.plane as usize];
        let mut normal = DVec3::from(plane.normal);
        if f.back {
            normal = -normal;
        }
        let vertices: Vec<DVec3> = f.polygon.iter().map(|p| DVec3::from(*p)).collect();
        // The polygon's own winding (Newell's normal) against the face's front.
        let mut newell = DVec3::ZERO;
        for (k, a) in vertices.iter().enumerate() {
            newell += a.cross(vertices[(k + 1) % vertices.len()]);
        }
        let ccw = newell.dot(normal) >= 0.0;
        let triangles = (1..vertices.len() as u32 - 1)
            .map(|k| if ccw { [0, k, k + 1] } else { [0, k + 1, k] })
            .collect();
        let mesh = Mesh {
            vertices,
            triangles,
        };
        let name = Some(format!("face_{id}"));
        objects.push(Object::mesh(name, mesh, Vec::new(), Vec::new()));
        faces.push(id as u32);
    }
    Soup {
        scene: Scene::from_objects(objects),
        faces,
        liquid_faces,
    }
}

impl Soup {
    /// The face ids of soup objects `objects` (as a PVS lists them), ascending.
    pub fn face_ids(&self, objects: &[u32]) -> Vec<u32> {
        objects
            .iter()
            .filter_map(|&o| self.faces.get(o as usize).copied())
            .collect()
    }

    /// Write the soup as Wavefront OBJ: one `o face_N` per face (N the world face id),
    /// vertices not shared between faces.
    pub fn write_obj<W: Write>(&self, mut w: W) -> std::io::Result<()> {
        writeln!(
            w,
            "# Quake level as a triangle soup: one object per world face"
        )?;
        let mut base = 1usize;
        for (o, face) in self.scene.objects.iter().zip(&self.faces) {
            let sightline_scene::Geometry::Mesh(m) = &o.geometry else {
                continue;
            };
            writeln!(w, "o face_{face}")?;
            for v in &m.vertices {
                writeln!(w, "v {} {} {}", v.x, v.y, v.z)?;
            }
            for t in &m.triangles {
                let [a, b, c] = t.map(|i| base + i as usize);
                writeln!(w, "f {a} {b} {c}")?;
            }
            base += m.vertices.len();
        }
        Ok(())
    }
}

/// The thickness of the solid behind each kept face of the soup (Quake units), by the
/// tree: from the face's centroid, steps of `step` straight back until a point lies in
/// an open leaf; `None` when none is within `max`, or the face's polygon is degenerate.
/// A wall of thickness `t` holds a voxel of side `h` wholly inside it whatever the
/// grid's offset only when `t > 2 h`: the smallest hole to ask for is under half the
/// thinnest walls that must occlude.
pub fn wall_thickness(level: &BspLevel, soup: &Soup, step: f64, max: f64) -> Vec<Option<f64>> {
    soup.faces
        .iter()
        .map(|&f| {
            let face = &level.faces[f as usize];
            let plane = level.planes[face.plane as usize];
            let sign = if face.back { -1.0 } else { 1.0 };
            let n = DVec3::from(plane.normal) * sign;
            let k = face.polygon.len() as f64;
            if k < 3.0 {
                return None;
            }
            let c = face
                .polygon
                .iter()
                .fold(DVec3::ZERO, |a, p| a + DVec3::from(*p))
                / k;
            let steps = (max / step).ceil() as usize;
            (1..=steps).map(|i| i as f64 * step).find(|&d| {
                let q = c - n * d;
                level.is_view_leaf(level.point_leaf(q.to_array()))
            })
        })
        .collect()
}

/// How a soup's PVS is judged against the BSP ([`judge`]).
#[derive(Clone, Debug)]
pub struct JudgeOptions {
    /// Viewpoints: random points of random open BSP leaves that lie in an automatic cell.
    pub viewpoints: usize,
    /// Points of each viewpoint's cell (in open BSP leaves) that the oracle's segments
    /// start from, the viewpoint included.
    pub cell_points: usize,
    /// Segments to each face our PVS drops.
    pub segments: usize,
    /// Segments to each face of vis's leaves our PVS drops.
    pub segments_vis: usize,
    /// The BSP path's bound to compare with.
    pub bsp_mode: Mode,
    pub seed: u64,
}

impl Default for JudgeOptions {
    fn default() -> Self {
        JudgeOptions {
            viewpoints: 60,
            cell_points: 32,
            segments: 16,
            segments_vis: 256,
            bsp_mode: Mode::Fast,
            seed: 1,
        }
    }
}

/// One viewpoint's face sets (sizes over the soup's faces).
#[derive(Clone, Debug, serde::Serialize)]
pub struct SoupViewpoint {
    pub point: [f64; 3],
    pub leaf: u32,
    pub cell: u32,
    /// Faces of the clusters our cell sees.
    pub ours: usize,
    /// Faces of the leaves vis says the leaf sees (marksurfaces).
    pub vis: usize,
    /// The BSP path's face PVS of the leaf.
    pub bsp: usize,
    /// Faces of vis's set that ours lacks.
    pub vis_not_ours: usize,
    /// Points of the cell the oracle started from.
    pub cell_points: usize,
}

/// A clear segment from a cell's free space to a face its PVS drops.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SoupMiss {
    pub cell: u32,
    pub face: u32,
    pub from: [f64; 3],
    pub to: [f64; 3],
    /// The face is in vis's set for the viewpoint's leaf.
    pub in_vis: bool,
}

/// The comparison of a soup's automatic-cell PVS with vis and the BSP path.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct SoupJudgement {
    /// Faces of the soup (the universe of every set below).
    pub faces: usize,
    pub viewpoints: Vec<SoupViewpoint>,
    /// Points of open BSP leaves drawn as viewpoints that lie in no automatic cell (a
    /// solid voxel or outside the grid): solid voxels must lie inside walls, so any
    /// such point is a bug of the voxelization.
    pub viewpoints_in_solid: usize,
    pub segments: usize,
    /// (viewpoint, face) pairs with a clear segment; the first 64 kept in `misses`.
    pub missed: usize,
    pub misses: Vec<SoupMiss>,
    /// How many viewpoints drop each soup face.
    pub culled_by: Vec<u32>,
}

impl SoupJudgement {
    pub fn sum_ours(&self) -> usize {
        self.viewpoints.iter().map(|v| v.ours).sum()
    }
    pub fn sum_vis(&self) -> usize {
        self.viewpoints.iter().map(|v| v.vis).sum()
    }
    pub fn sum_bsp(&self) -> usize {
        self.viewpoints.iter().map(|v| v.bsp).sum()
    }
    /// Median share of the soup's faces culled per viewpoint by `size` (ours, vis…).
    pub fn median_culled(&self, size: impl Fn(&SoupViewpoint) -> usize) -> f64 {
        let mut c: Vec<f64> = self
            .viewpoints
            .iter()
            .map(|v| 1.0 - size(v) as f64 / self.faces.max(1) as f64)
            .collect();
        c.sort_by(f64::total_cmp);
        c.get(c.len() / 2).copied().unwrap_or(0.0)
    }
}

/// Judge the PVS of `auto` (built on `soup`) at random viewpoints of `level`: its faces
/// against the faces of the leaves vis sees and against the BSP path's face PVS
/// (`portals`, `opts.bsp_mode`), and against the ray oracle through the BSP tree, which
/// shares no code with either path: from points of the viewpoint's cell that lie in open
/// leaves (points inside walls are not viewpoints), segments to random points just in
/// front of every face the PVS drops; a clear segment is a miss.
pub fn judge(
    level: &BspLevel,
    soup: &Soup,
    auto: &AutoCells,
    portals: &Portals,
    opts: &JudgeOptions,
) -> SoupJudgement {
    let mut soup_index = vec![u32::MAX; level.faces.len()];
    for (o, &f) in soup.faces.iter().enumerate() {
        soup_index[f as usize] = o as u32;
    }
    let view: Vec<u32> = (1..=level.visleafs)
        .filter(|&l| level.is_view_leaf(l))
        .collect();
    let mut j = SoupJudgement {
        faces: soup.faces.len(),
        culled_by: vec![0; soup.faces.len()],
        ..SoupJudgement::default()
    };
    if view.is_empty() {
        return j;
    }
    // Viewpoints, drawn in order from one generator (deterministic).
    let mut rng = Rng::new(opts.seed);
    let mut picks = Vec::new();
    for _ in 0..opts.viewpoints * 16 {
        if picks.len() == opts.viewpoints {
            break;
        }
        let leaf = view[(rng.next_u64() % view.len() as u64) as usize];
        let Some(&p) = sample_leaf(level, leaf, 1, &mut rng).first() else {
            continue;
        };
        match auto.locate(p) {
            Some(c) => picks.push((p, leaf, c)),
            None => j.viewpoints_in_solid += 1,
        }
    }
    let triangles: Vec<Vec<[DVec3; 3]>> =
        soup.scene.objects.iter().map(|o| o.triangles()).collect();
    let fronts: Vec<DVec3> = triangles
        .iter()
        .map(|t| {
            t.iter()
                .map(|t| (t[1] - t[0]).cross(t[2] - t[0]))
                .sum::<DVec3>()
                .normalize_or_zero()
        })
        .collect();
    let results: Vec<(SoupViewpoint, Vec<u32>, usize, Vec<SoupMiss>)> = picks
        .par_iter()
        .enumerate()
        .map(|(i, &(p, leaf, cell))| {
            let mut rng = Rng::new(opts.seed ^ (0x5eed_0000 + i as u64));
            let ours = soup.face_ids(&auto.pvs(cell as usize));
            let mut vis: Vec<u32> = level
                .reference_row(leaf)
                .iter()
                .flat_map(|&l| level.leaves[l as usize].faces.iter().copied())
                .filter(|&f| soup_index[f as usize] != u32::MAX)
                .collect();
            vis.sort_unstable();
            vis.dedup();
            let bsp = portals
                .solve(leaf, opts.bsp_mode)
                .faces
                .into_iter()
                .filter(|&f| soup_index[f as usize] != u32::MAX)
                .count();
            // Points of the cell in open leaves: the viewpoint, then random ones.
            let b = auto.cell_box(cell as usize);
            let mut from = vec![p];
            for _ in 0..opts.cell_points * 32 {
                if from.len() >= opts.cell_points.max(1) {
                    break;
                }
                let q: [f64; 3] =
                    std::array::from_fn(|k| b.min[k] + rng.unit() * (b.max[k] - b.min[k]));
                if level.is_view_leaf(level.point_leaf(q)) && auto.locate(q) == Some(cell) {
                    from.push(q);
                }
            }
            let mut in_ours = vec![false; soup.faces.len()];
            for &f in &ours {
                in_ours[soup_index[f as usize] as usize] = true;
            }
            let mut dropped = Vec::new();
            let mut segments = 0;
            let mut misses = Vec::new();
            for (o, &face) in soup.faces.iter().enumerate() {
                if in_ours[o] {
                    continue;
                }
                dropped.push(o as u32);
                let in_vis = vis.binary_search(&face).is_ok();
                let n = if in_vis {
                    opts.segments_vis
                } else {
                    opts.segments
                };
                for _ in 0..n {
                    let eye = from[(rng.next_u64() % from.len() as u64) as usize];
                    let Some(target) = point_in_front(&triangles[o], fronts[o], &mut rng) else {
                        break;
                    };
                    if (DVec3::from(eye) - target).dot(fronts[o]) <= 0.0 {
                        continue;
                    }
                    segments += 1;
                    if segment_clear(level, eye, target.to_array()) {
                        misses.push(SoupMiss {
                            cell,
                            face,
                            from: eye,
                            to: target.to_array(),
                            in_vis,
                        });
                        break;
                    }
                }
            }
            let v = SoupViewpoint {
                point: p,
                leaf,
                cell,
                ours: ours.len(),
                vis: vis.len(),
                bsp,
                vis_not_ours: vis
                    .iter()
                    .filter(|f| ours.binary_search(f).is_err())
                    .count(),
                cell_points: from.len(),
            };
            (v, dropped, segments, misses)
        })
        .collect();
    for (v, dropped, segments, misses) in results {
        for o in dropped {
            j.culled_by[o as usize] += 1;
        }
        j.segments += segments;
        j.missed += misses.len();
        let room = 64usize.saturating_sub(j.misses.len());
        j.misses.extend(misses.into_iter().take(room));
        j.viewpoints.push(v);
    }
    j
}

/// A random point of the triangles (area-weighted), `FRONT_OFFSET` in front of them.
fn point_in_front(tris: &[[DVec3; 3]], front: DVec3, rng: &mut Rng) -> Option<DVec3> {
    let areas: Vec<f64> = tris
        .iter()
        .map(|t| (t[1] - t[0]).cross(t[2] - t[0]).length())
        .collect();
    let total: f64 = areas.iter().sum();
    if total <= 0.0 {
        return None;
    }
    let mut x = rng.unit() * total;
    let mut k = tris.len() - 1;
    for (i, a) in areas.iter().enumerate() {
        if x < *a {
            k = i;
            break;
        }
        x -= a;
    }
    let (mut a, mut b) = (rng.unit(), rng.unit());
    if a + b > 1.0 {
        (a, b) = (1.0 - a, 1.0 - b);
    }
    let t = &tris[k];
    Some(t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b + front * FRONT_OFFSET)
}

/// How far in front of a face the oracle's segments end (Quake units): off the face's
/// plane, which the tree puts on the solid side, and still in the open leaf before it.
pub const FRONT_OFFSET: f64 = 0.05;

#[cfg(test)]
mod tests {
    use super::*;
    use sightline_portals::testlevel::two_rooms;

    #[test]
    fn faces_become_front_facing_objects() {
        let level = two_rooms(2.0);
        let soup = bsp_soup(&level);
        assert_eq!(
            soup.faces,
            (0..level.faces.len() as u32).collect::<Vec<_>>()
        );
        for (o, &f) in soup.scene.objects.iter().zip(&soup.faces) {
            let face = &level.faces[f as usize];
            let plane = level.planes[face.plane as usize];
            let sign = if face.back { -1.0 } else { 1.0 };
            let n = DVec3::from(plane.normal) * sign;
            for t in o.triangles() {
                assert!((t[1] - t[0]).cross(t[2] - t[0]).dot(n) > 0.0);
            }
        }
        let mut obj = Vec::new();
        soup.write_obj(&mut obj).unwrap();
        let text = String::from_utf8(obj).unwrap();
        assert_eq!(text.matches("\no face_").count(), soup.faces.len());
    }
}
