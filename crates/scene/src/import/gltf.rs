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

/// Parse a .gltf (JSON; external buffers relative to `base`) or .glb.
pub fn parse(
    bytes: &[u8],
    base: Option<&Path>,
    import: &ImportOptions,
) -> Result<Scene, ImportError> {
    let gltf::Gltf { document, blob } = gltf::Gltf::from_slice(bytes).map_err(err)?;
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
