//! What a culler works on: the occluders (faces of the objects' *inner* prisms, which
//! lie inside the solids, so whatever they hide is hidden) and the occludees (the
//! objects' *outer* bounding boxes), prepared once per scene.

use glam::DVec3;
use sightline_raster::prism_faces;
use sightline_scene::{occluders::inner_prisms, Scene};

/// One planar convex face of an occluder prism, outward normal.
#[derive(Clone, Debug)]
pub struct OccluderFace {
    pub verts: Vec<DVec3>,
    pub normal: DVec3,
    /// Triangles it stands for (a wall quad is 2), for throughput figures.
    pub tris: u32,
}

/// An occluder: one inner prism of an object, as its faces.
#[derive(Clone, Debug)]
pub struct OccluderPrism {
    pub object: u32,
    pub lo: DVec3,
    pub hi: DVec3,
    pub faces: Vec<OccluderFace>,
}

impl OccluderPrism {
    /// Faces facing the eye (the back faces of a closed prism lie behind its front
    /// faces in every direction, so they hide nothing more).
    pub fn front_faces(&self, eye: DVec3) -> impl Iterator<Item = &OccluderFace> {
        self.faces
            .iter()
            .filter(move |f| (eye - f.verts[0]).dot(f.normal) > 0.0)
    }
}

/// A scene prepared for from-point culling.
#[derive(Clone, Debug)]
pub struct CullScene {
    pub occluders: Vec<OccluderPrism>,
    /// Outer bounding box of each object (`lo`, `hi`), by id.
    pub boxes: Vec<(DVec3, DVec3)>,
}

impl CullScene {
    /// Occluders from the inner prisms of `scene` (every one with a top above its base,
    /// raised ones included: they are drawn as the closed solids they are), occludees
    /// from the objects' bounds.
    pub fn new(scene: &Scene) -> CullScene {
        let mut occluders = Vec::new();
        for (id, p) in inner_prisms(scene) {
            let fp = p.footprint.clone().normalized();
            let mut faces = Vec::new();
            for verts in prism_faces(&fp, p.base, p.top) {
                let normal = newell(&verts);
                if normal.length() == 0.0 {
                    continue;
                }
                let tris = verts.len() as u32 - 2;
                faces.push(OccluderFace {
                    verts,
                    normal,
                    tris,
                });
            }
            let bb = p.aabb();
            occluders.push(OccluderPrism {
                object: id,
                lo: bb.min,
                hi: bb.max,
                faces,
            });
        }
        let boxes = scene
            .objects
            .iter()
            .map(|o| (o.bounds.min, o.bounds.max))
            .collect();
        CullScene { occluders, boxes }
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
