//! Wavefront OBJ importer (tobj): **one mesh object per OBJ object/group** (`o`/`g`),
//! named by it; faces are triangulated; materials are ignored.
//!
//! OBJ has no up axis; like Blender's and Maya's default export it is read as **y-up**
//! and turned to sightline's z-up by (x, y, z) ↦ (x, −z, y) (a rotation, so handedness
//! and face orientation are kept). Inner and outer 2.5D bounds come from
//! [`super::mesh_bounds`].

use super::validate::Diagnostics;
use super::{mesh_bounds, ImportError, ImportOptions};
use crate::{Mesh, Object, Scene};
use sightline_geom::DVec3;

/// y-up → z-up.
pub fn y_up_to_z_up(p: DVec3) -> DVec3 {
    DVec3::new(p.x, -p.z, p.y)
}

/// Build a mesh object with derived bounds; `None` (and a warning) when empty.
pub fn mesh_object(
    name: Option<String>,
    mesh: Mesh,
    index: usize,
    diag: &mut Diagnostics,
) -> Result<Option<Object>, ImportError> {
    if let Some(p) = mesh
        .vertices
        .iter()
        .find(|p| !p.is_finite() || p.abs().max_element() > super::validate::MAX_COORD_M)
    {
        return Err(ImportError::Feature {
            index,
            message: format!("vertex {p} is not finite or out of range"),
        });
    }
    if let Some(t) = mesh
        .triangles
        .iter()
        .find(|t| t.iter().any(|&i| i as usize >= mesh.vertices.len()))
    {
        return Err(ImportError::Feature {
            index,
            message: format!(
                "triangle {t:?} refers to a missing vertex ({} vertices)",
                mesh.vertices.len()
            ),
        });
    }
    if mesh.triangles.is_empty() {
        diag.warn(
            "empty-mesh",
            Some(index),
            format!(
                "{}: no triangles, skipped",
                name.as_deref().unwrap_or("mesh")
            ),
        );
        return Ok(None);
    }
    let inner = mesh_bounds::inner_bound(&mesh);
    let outer = mesh_bounds::outer_bound(&mesh);
    Ok(Some(Object::mesh(name, mesh, inner, outer)))
}

/// Parse OBJ text.
pub fn parse(bytes: &[u8], import: &ImportOptions) -> Result<Scene, ImportError> {
    // Other tobj feature sets add fields: keep the struct update.
    #[allow(clippy::needless_update)]
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let mut reader = std::io::BufReader::new(bytes);
    let (models, _) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Ok((Vec::new(), Default::default())))
            .map_err(|e| ImportError::Format(format!("invalid OBJ: {e}")))?;
    let mut diag = Diagnostics::new(import.strict);
    let mut objects = Vec::new();
    for (index, m) in models.into_iter().enumerate() {
        let vertices: Vec<DVec3> = m
            .mesh
            .positions
            .chunks_exact(3)
            .map(|p| y_up_to_z_up(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)))
            .collect();
        let triangles = m
            .mesh
            .indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let name = (!m.name.is_empty() && m.name != "unnamed_object").then(|| m.name.clone());
        let mesh = Mesh {
            vertices,
            triangles,
        };
        match mesh_object(name, mesh, index, &mut diag) {
            Ok(Some(o)) => objects.push(o),
            Ok(None) => {}
            Err(e) => diag.skip(e)?,
        }
    }
    if objects.is_empty() {
        return Err(diag.nothing_left("empty scene: the OBJ file has no faces"));
    }
    let mut scene = Scene::from_objects(objects);
    scene.warnings = diag.warnings;
    Ok(scene)
}
