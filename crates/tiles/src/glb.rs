//! GLB content of one tile, written directly (glTF 2.0 binary container, spec §4.4).
//!
//! One mesh with one triangle primitive holding every object of the tile:
//!
//! * `POSITION` (`f32` × 3), relative to the tile's centre, which the single node's
//!   `translation` restores — absolute projected coordinates would lose millimetres in
//!   `f32`;
//! * `_FEATURE_ID_0` (`f32`, exact below 2²⁴): per vertex, the object's *feature id* in the tile (its row in the
//!   property table), bound by `EXT_mesh_features` (`featureIds[0].attribute = 0`);
//! * `EXT_structural_metadata`: class `object` with `object_id` (`UINT32`, the sightline
//!   object id) and `name` (`STRING`, empty when the object has none), one property
//!   table row per feature.
//!
//! glTF is y-up: a scene point (x, y, z) is written (x, z, −y). 3D Tiles clients turn
//! glTF content back to z-up by +90° about x (3D Tiles 1.1 §"glTF transforms"), so
//! the tileset's frame is the scene's local frame again.
//!
//! Vertices are shared within an object (merged by their `f32` bits), never between
//! objects, so every vertex has one feature id. The triangles are the scene model's own
//! ([`sightline_scene::Object::triangles`]).

use serde_json::{json, Value};
use sightline_geom::DVec3;
use sightline_scene::Scene;
use std::collections::HashMap;

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;

/// The binary chunk under construction: buffer views aligned to 8 bytes, as
/// `EXT_structural_metadata` requires of its views (and more than any accessor needs).
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
}

impl Bin {
    fn view(&mut self, data: &[u8], target: Option<u32>) -> usize {
        while !self.bytes.len().is_multiple_of(8) {
            self.bytes.push(0);
        }
        let mut v = json!({
            "buffer": 0,
            "byteOffset": self.bytes.len(),
            "byteLength": data.len(),
        });
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bytes.extend_from_slice(data);
        self.views.push(v);
        self.views.len() - 1
    }
}

/// The GLB of a tile holding `objects` (in feature-id order), positions relative to
/// `centre`.
pub fn tile_glb(scene: &Scene, objects: &[u32], centre: DVec3) -> Vec<u8> {
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut feature_ids: Vec<u32> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    for (feature, &id) in objects.iter().enumerate() {
        let mut index_of: HashMap<[u32; 3], u32> = HashMap::new();
        for tri in scene.objects[id as usize].triangles() {
            for v in tri {
                let r = v - centre;
                // y-up: (x, y, z) ↦ (x, z, −y).
                let p = [r.x as f32, r.z as f32, -r.y as f32];
                let i = *index_of.entry(p.map(f32::to_bits)).or_insert_with(|| {
                    positions.push(p);
                    feature_ids.push(feature as u32);
                    (positions.len() - 1) as u32
                });
                indices.push(i);
            }
        }
    }
    let (mut lo, mut hi) = ([f32::MAX; 3], [f32::MIN; 3]);
    for p in &positions {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    if positions.is_empty() {
        (lo, hi) = ([0.0; 3], [0.0; 3]);
    }

    // glTF forbids empty buffer views, accessors and buffers (`byteLength` and `count`
    // are at least 1): objects without triangles (an empty flat object, a mesh whose
    // faces were all degenerate) give a tile without a mesh, and a tile without objects
    // one without metadata either.
    let has_mesh = !indices.is_empty();
    let has_table = !objects.is_empty();
    let mut bin = Bin::default();
    let mut mesh_views = None;
    if has_mesh {
        let pos_view = bin.view(&le_f32(positions.iter().flatten()), Some(ARRAY_BUFFER));
        // Vertex attributes must be 4-byte aligned per element: a u16 id would need
        // padding to 4 bytes anyway, and f32 holds every id below 2^24 exactly.
        let fids: Vec<f32> = feature_ids.iter().map(|&f| f as f32).collect();
        let fid_view = bin.view(&le_f32(fids.iter()), Some(ARRAY_BUFFER));
        let idx_view = bin.view(&le_u32(indices.iter()), Some(ELEMENT_ARRAY_BUFFER));
        mesh_views = Some((pos_view, fid_view, idx_view));
    }
    let object_view = has_table.then(|| bin.view(&le_u32(objects.iter()), None));
    let mut names = Vec::new();
    let mut offsets = vec![0u32];
    for &id in objects {
        if let Some(n) = &scene.objects[id as usize].name {
            names.extend_from_slice(n.as_bytes());
        }
        offsets.push(names.len() as u32);
    }
    // A buffer view cannot be empty: a tile of unnamed objects has no `name` column.
    let name_column = (!names.is_empty()).then(|| {
        let values = bin.view(&names, None);
        let offsets = bin.view(&le_u32(offsets.iter()), None);
        json!({ "values": values, "stringOffsets": offsets, "stringOffsetType": "UINT32" })
    });
    while !bin.bytes.len().is_multiple_of(4) {
        bin.bytes.push(0);
    }

    let fid_type = FLOAT;
    let (pos_view, fid_view, idx_view) = mesh_views.unwrap_or_default();
    let mut doc = json!({
        "asset": { "version": "2.0", "generator": "sightline" },
        "extensionsUsed": ["EXT_mesh_features", "EXT_structural_metadata"],
        "extensions": {
            "EXT_structural_metadata": {
                "schema": {
                    "id": "sightline",
                    "classes": {
                        "object": {
                            "description": "One sightline object (building, ground polygon or mesh).",
                            "properties": {
                                "object_id": { "type": "SCALAR", "componentType": "UINT32", "required": true },
                                "name": { "type": "STRING" }
                            }
                        }
                    }
                },
                "propertyTables": [{
                    "class": "object",
                    "count": objects.len(),
                    "properties": {
                        "object_id": { "values": object_view }
                    }
                }]
            }
        },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0, "translation": [centre.x, centre.z, -centre.y] }],
        "meshes": [{
            "primitives": [{
                "attributes": { "POSITION": 0, "_FEATURE_ID_0": 1 },
                "indices": 2,
                "material": 0,
                "mode": 4,
                "extensions": {
                    "EXT_mesh_features": {
                        "featureIds": [{ "featureCount": objects.len(), "attribute": 0, "propertyTable": 0 }]
                    }
                }
            }]
        }],
        "materials": [{
            "pbrMetallicRoughness": { "baseColorFactor": [0.82, 0.8, 0.76, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.9 }
        }],
        "accessors": [
            { "bufferView": pos_view, "componentType": FLOAT, "count": positions.len(), "type": "VEC3", "min": lo, "max": hi },
            { "bufferView": fid_view, "componentType": fid_type, "count": feature_ids.len(), "type": "SCALAR" },
            { "bufferView": idx_view, "componentType": UNSIGNED_INT, "count": indices.len(), "type": "SCALAR" }
        ],
        "bufferViews": bin.views,
        "buffers": [{ "byteLength": bin.bytes.len() }]
    });
    if let Some(c) = name_column {
        doc["extensions"]["EXT_structural_metadata"]["propertyTables"][0]["properties"]["name"] = c;
    }
    if let Value::Object(d) = &mut doc {
        if !has_mesh {
            d.remove("meshes");
            d.remove("accessors");
            d.remove("materials");
            doc_remove_mesh_use(d);
        }
        if !has_table {
            // No objects, so no mesh either: nothing uses an extension.
            d.remove("extensions");
            d.remove("extensionsUsed");
        }
        if bin.bytes.is_empty() {
            d.remove("bufferViews");
            d.remove("buffers");
        }
    }
    // serde_json cannot fail on a Value built from numbers and strings.
    let mut json_bytes = serde_json::to_vec(&doc).unwrap_or_default();
    while !json_bytes.len().is_multiple_of(4) {
        json_bytes.push(b' ');
    }
    container(&json_bytes, &bin.bytes)
}

/// A document without a mesh: its node keeps only the translation, and
/// `EXT_mesh_features` (which only a primitive can use) is not listed as used.
fn doc_remove_mesh_use(d: &mut serde_json::Map<String, Value>) {
    if let Some(Value::Object(node)) = d.get_mut("nodes").and_then(|n| n.get_mut(0)) {
        node.remove("mesh");
    }
    if let Some(Value::Array(used)) = d.get_mut("extensionsUsed") {
        used.retain(|e| e != "EXT_mesh_features");
    }
}

/// The GLB container: 12-byte header, the JSON chunk, the BIN chunk (left out when
/// empty: glTF allows no empty buffer).
fn container(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let bin_chunk = if bin.is_empty() { 0 } else { 8 + bin.len() };
    let total = 12 + 8 + json.len() + bin_chunk;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(&CHUNK_JSON.to_le_bytes());
    out.extend_from_slice(json);
    if !bin.is_empty() {
        out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        out.extend_from_slice(&CHUNK_BIN.to_le_bytes());
        out.extend_from_slice(bin);
    }
    out
}

fn le_f32<'a>(v: impl Iterator<Item = &'a f32>) -> Vec<u8> {
    v.flat_map(|f| f.to_le_bytes()).collect()
}

fn le_u32<'a>(v: impl Iterator<Item = &'a u32>) -> Vec<u8> {
    v.flat_map(|f| f.to_le_bytes()).collect()
}
