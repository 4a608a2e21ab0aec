//! A scene as a binary glTF 2.0 (GLB): **one node and one mesh per object**, in object
//! order, each the object's triangles in [`Object::triangles`] order (triangle `k` of
//! a node is indices `3k .. 3k + 3` of its primitive), with flat normals, under one
//! scene. Names and `extras` of the nodes are the caller's (`sightline clusters` names
//! them by cluster id, the id a `.pvs` lists).
//!
//! glTF is y-up (spec §3.4): a scene point (x, y, z) is written (x, z, −y), the inverse
//! of the importers' turn, so an OBJ or glTF level comes back in its own frame and
//! [`crate::import`] reads the file back to the same triangles. Positions are `f32`,
//! as they were in the input (OBJ and glTF store `f32`); nodes have no transform.
//! Vertices are shared within a node when position and normal are equal; an object
//! without triangles gets a node without a mesh (glTF forbids empty accessors).
//!
//! The document is built with `gltf-json` (re-exported by the `gltf` crate) and the
//! container with `gltf::binary::Glb`.
//!
//! ```
//! use sightline_scene::{export::glb::{scene_glb, GlbNode}, Mesh, Object, Scene};
//! use sightline_geom::DVec3;
//! let tri = Mesh { vertices: vec![DVec3::ZERO, DVec3::X, DVec3::Y], triangles: vec![[0, 1, 2]] };
//! let s = Scene::from_objects(vec![Object::mesh(None, tri, vec![], vec![])]);
//! let glb = scene_glb(&s, |i| GlbNode { name: i.to_string(), extras: None }, None).unwrap();
//! let doc = gltf::Gltf::from_slice(&glb).unwrap();
//! assert_eq!(doc.nodes().next().unwrap().name(), Some("0"));
//! ```

use super::ExportError;
use crate::{Object, Scene};
use gltf::json::{self as gj, validation::Checked::Valid, validation::USize64};
use sightline_geom::DVec3;
use std::collections::{BTreeMap, HashMap};

/// The name and `extras` (any JSON value) of one object's node.
pub struct GlbNode {
    pub name: String,
    pub extras: Option<serde_json::Value>,
}

/// Scene (x, y, z) → glTF (x, z, −y).
fn z_up_to_y_up(p: DVec3) -> [f32; 3] {
    [p.x as f32, p.z as f32, -p.y as f32]
}

/// The flat unit normal of a triangle in glTF's frame; a degenerate triangle (zero
/// area) gets +y, since a normal must be a unit vector.
fn flat_normal(t: &[[f32; 3]; 3]) -> [f32; 3] {
    let d = |a: [f32; 3], b: [f32; 3]| [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let (u, v) = (d(t[0], t[1]), d(t[0], t[2]));
    let n = [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ];
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 && len.is_finite() {
        n.map(|c| c / len)
    } else {
        [0.0, 1.0, 0.0]
    }
}

fn raw(v: &serde_json::Value) -> Result<gj::Extras, ExportError> {
    serde_json::value::to_raw_value(v)
        .map(Some)
        .map_err(|e| ExportError::Format(format!("extras: {e}")))
}

/// The growing binary chunk and the document's views and accessors.
struct Builder {
    root: gj::Root,
    bin: Vec<u8>,
}

impl Builder {
    fn view(&mut self, bytes: &[u8], target: gj::buffer::Target) -> gj::Index<gj::buffer::View> {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.root.push(gj::buffer::View {
            buffer: gj::Index::new(0),
            byte_length: USize64::from(bytes.len()),
            byte_offset: Some(USize64::from(offset)),
            byte_stride: None,
            name: None,
            target: Some(Valid(target)),
            extensions: None,
            extras: None,
        })
    }

    fn accessor(
        &mut self,
        view: gj::Index<gj::buffer::View>,
        count: usize,
        component: gj::accessor::ComponentType,
        type_: gj::accessor::Type,
        bounds: Option<([f32; 3], [f32; 3])>,
    ) -> gj::Index<gj::Accessor> {
        self.root.push(gj::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: USize64::from(count),
            component_type: Valid(gj::accessor::GenericComponentType(component)),
            extensions: None,
            extras: None,
            type_: Valid(type_),
            min: bounds.map(|b| serde_json::json!(b.0)),
            max: bounds.map(|b| serde_json::json!(b.1)),
            name: None,
            normalized: false,
            sparse: None,
        })
    }

    /// The mesh of one object's triangles, `None` when it has none.
    fn mesh(&mut self, o: &Object, name: &str) -> Option<gj::Index<gj::Mesh>> {
        let mut positions: Vec<[f32; 3]> = Vec::new();
        let mut normals: Vec<[f32; 3]> = Vec::new();
        let mut indices: Vec<u32> = Vec::new();
        let mut index_of: HashMap<[u32; 6], u32> = HashMap::new();
        for t in o.triangles() {
            let t = t.map(z_up_to_y_up);
            let n = flat_normal(&t);
            for p in t {
                let key = [p[0], p[1], p[2], n[0], n[1], n[2]].map(f32::to_bits);
                let i = *index_of.entry(key).or_insert_with(|| {
                    positions.push(p);
                    normals.push(n);
                    (positions.len() - 1) as u32
                });
                indices.push(i);
            }
        }
        if indices.is_empty() {
            return None;
        }
        let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
        for p in &positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        use gj::accessor::{ComponentType, Type};
        use gj::buffer::Target;
        let le = |v: &[[f32; 3]]| -> Vec<u8> {
            v.iter().flatten().flat_map(|f| f.to_le_bytes()).collect()
        };
        let pv = self.view(&le(&positions), Target::ArrayBuffer);
        let pa = self.accessor(
            pv,
            positions.len(),
            ComponentType::F32,
            Type::Vec3,
            Some((lo, hi)),
        );
        let nv = self.view(&le(&normals), Target::ArrayBuffer);
        let na = self.accessor(nv, normals.len(), ComponentType::F32, Type::Vec3, None);
        let idx: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let iv = self.view(&idx, Target::ElementArrayBuffer);
        let ia = self.accessor(iv, indices.len(), ComponentType::U32, Type::Scalar, None);
        let mut attributes = BTreeMap::new();
        attributes.insert(Valid(gj::mesh::Semantic::Positions), pa);
        attributes.insert(Valid(gj::mesh::Semantic::Normals), na);
        Some(self.root.push(gj::Mesh {
            extensions: None,
            extras: None,
            name: Some(name.to_string()),
            primitives: vec![gj::mesh::Primitive {
                attributes,
                extensions: None,
                extras: None,
                indices: Some(ia),
                material: None,
                mode: Valid(gj::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        }))
    }
}

/// The GLB of `scene` (module doc): node `i` is object `i`, named and tagged by
/// `node(i)`; `asset_extras` goes into the asset's `extras`.
pub fn scene_glb(
    scene: &Scene,
    node: impl Fn(usize) -> GlbNode,
    asset_extras: Option<serde_json::Value>,
) -> Result<Vec<u8>, ExportError> {
    let mut b = Builder {
        root: gj::Root::default(),
        bin: Vec::new(),
    };
    b.root.asset = gj::Asset {
        generator: Some(format!("sightline {}", env!("CARGO_PKG_VERSION"))),
        extras: asset_extras.as_ref().map(raw).transpose()?.flatten(),
        ..Default::default()
    };
    let mut nodes = Vec::with_capacity(scene.objects.len());
    for (i, o) in scene.objects.iter().enumerate() {
        let GlbNode { name, extras } = node(i);
        let mesh = b.mesh(o, &name);
        nodes.push(b.root.push(gj::Node {
            mesh,
            name: Some(name),
            extras: extras.as_ref().map(raw).transpose()?.flatten(),
            ..Default::default()
        }));
    }
    let scene_index = b.root.push(gj::Scene {
        extensions: None,
        extras: None,
        name: None,
        nodes,
    });
    b.root.scene = Some(scene_index);
    if !b.bin.is_empty() {
        b.root.push(gj::Buffer {
            byte_length: USize64::from(b.bin.len()),
            name: None,
            uri: None,
            extensions: None,
            extras: None,
        });
    }
    let json = b
        .root
        .to_vec()
        .map_err(|e| ExportError::Format(format!("glTF JSON: {e}")))?;
    let bin = (!b.bin.is_empty()).then_some(std::borrow::Cow::Borrowed(&b.bin[..]));
    let glb = gltf::binary::Glb {
        header: gltf::binary::Header {
            magic: *b"glTF",
            version: 2,
            // `to_vec` writes the true length.
            length: 0,
        },
        json: std::borrow::Cow::Owned(json),
        bin,
    };
    glb.to_vec()
        .map_err(|e| ExportError::Format(format!("GLB: {e}")))
}
