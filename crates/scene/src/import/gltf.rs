//! glTF 2.0 / GLB importer (the `gltf` crate, buffers only — images are never
//! decoded): **one mesh object per node with a mesh**, named by the node, in the node
//! order of a depth-first walk of the default scene (else the first scene, else every
//! root node). Node transforms are composed down the hierarchy and applied.
//!
//! glTF is y-up (spec §3.4); sightline is z-up: positions are turned by
//! (x, y, z) ↦ (x, −z, y), a rotation of +90° about x, after the node transforms.
//! Triangle strips and fans are unrolled; points and lines are skipped (warning
//! `unsupported-primitive`). Bounds come from [`super::mesh_bounds`].

use super::obj::{mesh_object, y_up_to_z_up};
use super::validate::Diagnostics;
use super::{ImportError, ImportOptions};
use crate::{Mesh, Scene};
use glam::DMat4;
use gltf::mesh::Mode;
use sightline_geom::DVec3;
use std::path::Path;

fn err(m: impl std::fmt::Display) -> ImportError {
    ImportError::Format(format!("invalid glTF: {m}"))
}

/// Whether the accessor `acc` holds elements of `size` bytes laid out as the gltf
/// crate reads them: it asserts that (in debug builds) and misreads otherwise, so a
/// corrupted file is refused before it reads. Sparse accessors' views must not be
/// strided (glTF §3.6.2.3).
pub(crate) fn accessor_fits(acc: &gltf::Accessor, size: usize) -> bool {
    let stride_ok =
        |v: Option<gltf::buffer::View>| v.is_none_or(|v| v.stride().is_none_or(|s| s >= size));
    size > 0
        && acc.size() == size
        && stride_ok(acc.view())
        && acc.sparse().is_none_or(|s| {
            s.values().view().stride().is_none() && s.indices().view().stride().is_none()
        })
}

/// Whether a primitive's POSITION (three `f32`) and index (one unsigned integer)
/// accessors, when present, have the shapes the readers expect ([`accessor_fits`]).
pub(crate) fn primitive_fits(prim: &gltf::Primitive) -> bool {
    use gltf::accessor::DataType;
    let pos = prim
        .get(&gltf::Semantic::Positions)
        .is_none_or(|a| a.data_type() == DataType::F32 && accessor_fits(&a, 12));
    let idx = prim.indices().is_none_or(|a| {
        matches!(a.data_type(), DataType::U8 | DataType::U16 | DataType::U32)
            && accessor_fits(&a, a.data_type().size())
    });
    pos && idx
}

/// The glTF document of a .gltf or .glb and its JSON (the gltf crate does not expose
/// extensions it does not know). Accessor indices of mesh primitives are checked
/// first: the gltf crate's validation indexes the accessors with them unchecked and
/// panics on one out of range.
pub(crate) fn read(bytes: &[u8]) -> Result<(gltf::Gltf, serde_json::Value), String> {
    let json = if bytes.starts_with(b"glTF") {
        glb_json(bytes)?
    } else {
        serde_json::from_slice(bytes).map_err(|e| e.to_string())?
    };
    check_accessor_indices(&json)?;
    let gltf = gltf::Gltf::from_slice(bytes).map_err(|e| e.to_string())?;
    Ok((gltf, json))
}

/// The JSON chunk of a GLB.
fn glb_json(glb: &[u8]) -> Result<serde_json::Value, String> {
    let len = glb
        .get(12..16)
        .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
        .ok_or("GLB shorter than its header")?;
    let chunk = glb
        .get(20..20usize.saturating_add(len))
        .ok_or("GLB JSON chunk truncated")?;
    serde_json::from_slice(chunk).map_err(|e| format!("GLB JSON chunk: {e}"))
}

/// Every accessor a mesh primitive names (attributes, indices, morph targets) exists.
fn check_accessor_indices(json: &serde_json::Value) -> Result<(), String> {
    let count = json
        .get("accessors")
        .and_then(|a| a.as_array())
        .map_or(0, Vec::len);
    let meshes = json.get("meshes").and_then(|m| m.as_array());
    for (m, mesh) in meshes.into_iter().flatten().enumerate() {
        let prims = mesh.get("primitives").and_then(|p| p.as_array());
        for (k, prim) in prims.into_iter().flatten().enumerate() {
            let targets = prim.get("targets").and_then(|t| t.as_array());
            let maps = prim
                .get("attributes")
                .into_iter()
                .chain(targets.into_iter().flatten());
            let named = maps
                .filter_map(|a| a.as_object())
                .flat_map(|a| a.values())
                .chain(prim.get("indices"));
            for v in named {
                if v.as_u64().is_none_or(|i| i >= count as u64) {
                    return Err(format!(
                        "mesh {m} primitive {k}: accessor {v} does not exist ({count} accessors)"
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Parse a .gltf (JSON; external buffers relative to `base`) or .glb.
pub fn parse(
    bytes: &[u8],
    base: Option<&Path>,
    import: &ImportOptions,
) -> Result<Scene, ImportError> {
    let (gltf::Gltf { document, blob }, _) = read(bytes).map_err(err)?;
    let buffers = gltf::import_buffers(&document, base, blob).map_err(err)?;
    let mut diag = Diagnostics::new(import.strict);
    let mut objects = Vec::new();
    let roots: Vec<gltf::Node> = match document
        .default_scene()
        .or_else(|| document.scenes().next())
    {
        Some(s) => s.nodes().collect(),
        None => document.nodes().collect(),
    };
    // Depth-first with accumulated transforms; depth bounded against cyclic input.
    let mut stack: Vec<(gltf::Node, DMat4, usize)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY, 0))
        .collect();
    let mut index = 0usize;
    while let Some((node, parent, depth)) = stack.pop() {
        if depth > 64 {
            return Err(err("node hierarchy deeper than 64 (cycle?)"));
        }
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        for child in node.children().collect::<Vec<_>>().into_iter().rev() {
            stack.push((child, world, depth + 1));
        }
        let Some(gmesh) = node.mesh() else { continue };
        let mut mesh = Mesh::default();
        let mut rejected = false;
        for prim in gmesh.primitives() {
            if !primitive_fits(&prim) {
                continue;
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(pos) = reader.read_positions() else {
                continue;
            };
            let off = mesh.vertices.len() as u32;
            let start = mesh.vertices.len();
            mesh.vertices.extend(pos.map(|p| {
                y_up_to_z_up(world.transform_point3(DVec3::new(
                    p[0] as f64,
                    p[1] as f64,
                    p[2] as f64,
                )))
            }));
            let n = (mesh.vertices.len() - start) as u32;
            let idx: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..n).collect(),
            };
            if let Some(bad) = idx.iter().find(|&&i| i >= n) {
                diag.skip(ImportError::Feature {
                    index,
                    message: format!(
                        "index {bad} out of range ({n} vertices) in node {:?}",
                        node.name()
                    ),
                })?;
                rejected = true;
                break;
            }
            let tris: Vec<[u32; 3]> = match prim.mode() {
                Mode::Triangles => idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
                Mode::TriangleStrip => (2..idx.len())
                    .map(|k| {
                        if k % 2 == 0 {
                            [idx[k - 2], idx[k - 1], idx[k]]
                        } else {
                            [idx[k - 1], idx[k - 2], idx[k]]
                        }
                    })
                    .collect(),
                Mode::TriangleFan => (2..idx.len())
                    .map(|k| [idx[0], idx[k - 1], idx[k]])
                    .collect(),
                other => {
                    diag.warn(
                        "unsupported-primitive",
                        Some(index),
                        format!("{other:?} primitive skipped"),
                    );
                    continue;
                }
            };
            mesh.triangles
                .extend(tris.iter().map(|t| t.map(|i| i + off)));
        }
        if !rejected {
            match mesh_object(node.name().map(str::to_string), mesh, index, &mut diag) {
                Ok(Some(o)) => objects.push(o),
                Ok(None) => {}
                Err(e) => diag.skip(e)?,
            }
        }
        index += 1;
    }
    if objects.is_empty() {
        return Err(diag.nothing_left("invalid glTF: empty scene: no node with a triangle mesh"));
    }
    let mut scene = Scene::from_objects(objects);
    scene.warnings = diag.warnings;
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_primitive_naming_a_missing_accessor_is_an_error_not_a_panic() {
        let doc = br#"{"asset":{"version":"2.0"},"accessors":[],
            "meshes":[{"primitives":[{"attributes":{"POSITION":3}}]}]}"#;
        let e = parse(doc, None, &ImportOptions::default()).expect_err("broken");
        let msg = e.to_string();
        assert!(msg.contains("accessor 3 does not exist"), "{msg}");
        assert!(!msg.contains('\n'), "{msg}");
    }
}
