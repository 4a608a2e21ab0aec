//! What a culler works on: the occluders (faces of the objects' *inner* prisms, which
//! lie inside the solids, so whatever they hide is hidden) and the occludees (the
//! objects' *outer* bounding boxes), prepared once per scene.

use glam::DVec3;
use sightline_raster::prism_faces;
use sightline_scene::{occluders::inner_prisms, Geometry, Mesh, Scene};

/// One planar convex face of an occluder prism, outward normal; its vertices are
/// `CullScene::verts[first_vert .. first_vert + vert_count]`.
#[derive(Clone, Debug)]
pub struct OccluderFace {
    pub first_vert: u32,
    pub vert_count: u32,
    pub normal: DVec3,
    /// `normal · verts[0]`: the face is front-facing from `eye` when `normal · eye` is
    /// greater (tested without reaching into `verts`).
    pub offset: f64,
    /// Triangles it stands for (a wall quad is 2), for throughput figures.
    pub tris: u32,
}

/// An occluder: one inner prism of an object, as its faces
/// `CullScene::faces[first_face .. first_face + face_count]`.
#[derive(Clone, Debug)]
pub struct OccluderPrism {
    pub object: u32,
    pub lo: DVec3,
    pub hi: DVec3,
    pub first_face: u32,
    pub face_count: u32,
}

/// A scene prepared for from-point culling.
#[derive(Clone, Debug)]
pub struct CullScene {
    /// Closed prisms (front faces drawn) and, with [`CullScene::with_surfaces`], opaque
    /// surfaces (one polygon each, both orientations).
    pub occluders: Vec<OccluderPrism>,
    /// How many of `occluders` are mesh surfaces.
    pub surface_occluders: usize,
    /// The occluders' faces, prism after prism, and their vertices, face after face: one
    /// pass over a frame's occluders reads memory in order.
    pub faces: Vec<OccluderFace>,
    pub verts: Vec<DVec3>,
    /// Outer bounding box of each object (`lo`, `hi`), by id.
    pub boxes: Vec<(DVec3, DVec3)>,
}

impl CullScene {
    /// Occluders from the inner prisms of `scene` (every one with a top above its base,
    /// raised ones included: they are drawn as the closed solids they are), occludees
    /// from the objects' bounds.
    pub fn new(scene: &Scene) -> CullScene {
        let mut cs = CullScene {
            occluders: Vec::new(),
            surface_occluders: 0,
            faces: Vec::new(),
            verts: Vec::new(),
            boxes: Vec::new(),
        };
        for (id, p) in inner_prisms(scene) {
            let fp = p.footprint.clone().normalized();
            let bb = p.aabb();
            cs.push_occluder(id, bb.min, bb.max, prism_faces(&fp, p.base, p.top));
        }
        let boxes = scene
            .objects
            .iter()
            .map(|o| (o.bounds.min, o.bounds.max))
            .collect();
        cs.boxes = boxes;
        cs
    }

    /// Add an occluder of `object` with box `[lo, hi]` made of the planar convex
    /// `polygons` (degenerate ones left out).
    fn push_occluder(&mut self, object: u32, lo: DVec3, hi: DVec3, polygons: Vec<Vec<DVec3>>) {
        let first_face = self.faces.len() as u32;
        for verts in polygons {
            let normal = newell(&verts);
            if !(normal.length() > 0.0) || verts.len() < 3 {
                continue;
            }
            self.faces.push(OccluderFace {
                first_vert: self.verts.len() as u32,
                vert_count: verts.len() as u32,
                normal,
                offset: normal.dot(verts[0]),
                tris: verts.len() as u32 - 2,
            });
            self.verts.extend_from_slice(&verts);
        }
        self.occluders.push(OccluderPrism {
            object,
            lo,
            hi,
            first_face,
            face_count: self.faces.len() as u32 - first_face,
        });
    }

    /// The faces of occluder `o` facing the eye, with their vertices (the back faces of
    /// a closed prism lie behind its front faces in every direction, so they hide
    /// nothing more).
    pub fn front_faces(
        &self,
        o: &OccluderPrism,
        eye: DVec3,
    ) -> impl Iterator<Item = (&OccluderFace, &[DVec3])> {
        let faces = &self.faces[o.first_face as usize..(o.first_face + o.face_count) as usize];
        faces
            .iter()
            .filter(move |f| eye.dot(f.normal) > f.offset)
            .map(|f| {
                let v = &self.verts[f.first_vert as usize..(f.first_vert + f.vert_count) as usize];
                (f, v)
            })
    }

    /// [`CullScene::new`] plus the surfaces of the mesh objects as occluders: each
    /// triangle — or each convex planar polygon a mesh is a fan of, as a BSP level's
    /// faces are — occludes what lies entirely behind it, drawn from whichever side the
    /// eye is on. Conservative where the surfaces are opaque: a Quake level's world
    /// faces bound its solid and sky, which `docs/culling.md` treats as opaque (a face named `*…`, a
    /// liquid surface, is see-through and left out); a mesh scene's triangles are opaque
    /// to the renderer and to the item-buffer truth. It is *not* the 2.5D inner bound
    /// of the from-region methods (`docs/culling.md`), under which an open mesh hides nothing.
    pub fn with_surfaces(scene: &Scene) -> CullScene {
        let mut cs = CullScene::new(scene);
        for (id, o) in scene.objects.iter().enumerate() {
            let Geometry::Mesh(mesh) = &o.geometry else {
                continue;
            };
            if o.name
                .as_deref()
                .is_some_and(sightline_scene::import::bsp::is_liquid)
            {
                continue;
            }
            for verts in surface_polygons(mesh) {
                let normal = newell(&verts);
                if !(normal.length() > 1e-12) {
                    continue;
                }
                let (mut lo, mut hi) = (verts[0], verts[0]);
                for v in &verts {
                    lo = lo.min(*v);
                    hi = hi.max(*v);
                }
                let back: Vec<DVec3> = verts.iter().rev().copied().collect();
                cs.push_occluder(id as u32, lo, hi, vec![verts, back]);
                cs.surface_occluders += 1;
            }
        }
        cs
    }

    /// Number of objects (occludees).
    pub fn objects(&self) -> usize {
        self.boxes.len()
    }
}

/// Newell's normal of a planar polygon (its length is twice the area).
fn newell(v: &[DVec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for k in 0..v.len() {
        let (a, b) = (v[k], v[(k + 1) % v.len()]);
        n += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    n
}

/// The mesh as convex planar polygons: the whole vertex ring when the triangles are the
/// fan `[0, k, k + 1]` over it and the ring is planar and convex (a BSP face), else one
/// polygon per triangle.
fn surface_polygons(mesh: &Mesh) -> Vec<Vec<DVec3>> {
    let v = &mesh.vertices;
    let fan = v.len() >= 3
        && mesh.triangles.len() == v.len() - 2
        && mesh
            .triangles
            .iter()
            .enumerate()
            .all(|(k, t)| *t == [0, k as u32 + 1, k as u32 + 2]);
    if fan && is_planar_convex(v) {
        return vec![v.clone()];
    }
    mesh.triangles
        .iter()
        .filter(|t| t.iter().all(|&i| (i as usize) < v.len()))
        .map(|t| t.iter().map(|&i| v[i as usize]).collect())
        .collect()
}

/// Whether the ring `v` is planar (within 1e-6 of its size) and strictly convex.
fn is_planar_convex(v: &[DVec3]) -> bool {
    let n = newell(v);
    let len = n.length();
    if !(len > 0.0) {
        return false;
    }
    let n = n / len;
    let d = n.dot(v[0]);
    let size = v.iter().map(|p| (*p - v[0]).length()).fold(0.0, f64::max);
    if v.iter()
        .any(|p| (n.dot(*p) - d).abs() > 1e-6 * size.max(1.0))
    {
        return false;
    }
    (0..v.len()).all(|k| {
        let (a, b, c) = (v[k], v[(k + 1) % v.len()], v[(k + 2) % v.len()]);
        (b - a).cross(c - b).dot(n) >= 0.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fan(v: Vec<DVec3>) -> Mesh {
        let triangles = (1..v.len() as u32 - 1).map(|k| [0, k, k + 1]).collect();
        Mesh {
            vertices: v,
            triangles,
        }
    }

    #[test]
    fn a_planar_convex_fan_is_one_polygon_else_its_triangles() {
        let quad = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(4.0, 0.0, 0.0),
            DVec3::new(4.0, 0.0, 3.0),
            DVec3::new(0.0, 0.0, 3.0),
        ];
        assert_eq!(surface_polygons(&fan(quad.clone())).len(), 1);
        // A dent makes it non-convex; a lifted corner non-planar: triangles then.
        let mut dent = quad.clone();
        dent.insert(2, DVec3::new(2.0, 0.0, 1.0));
        assert_eq!(surface_polygons(&fan(dent)).len(), 3);
        let mut bent = quad;
        bent[2].y = 0.5;
        assert_eq!(surface_polygons(&fan(bent)).len(), 2);
    }
}
