//! CityJSON importer: versions 0.8 (the Den Haag tile), 1.0, 1.1 and 2.0, as a `.json`
//! / `.city.json` file or the `.json` inside a `.zip` (macOS `__MACOSX` entries ignored).
//!
//! * **One object per city object with geometry** of type `Building` or `BuildingPart`:
//!   a Building made of parts (children with geometry, no geometry of its own) yields
//!   one object per part; a Building with geometry of its own yields that object too.
//!   Other types (the `TINRelief` terrain, roads, vegetation, …) are skipped with a
//!   counted `skipped-object` warning per type. The object's name is its CityObjects key.
//! * Objects are in **key order** (CityObjects is a JSON object, whose member order
//!   carries no meaning), so ids are deterministic.
//! * Per object, the geometry of the **highest LoD** is used. LoD < 2 (LoD1 solids or
//!   surfaces) → blocks: footprint = union of the projected faces, from its lowest to its
//!   highest vertex. LoD ≥ 2 → a triangle mesh (faces triangulated by ear clipping in
//!   their dominant plane) with the conservative inner and outer 2.5D bounds of
//!   [`super::mesh_bounds`].
//! * Vertices are `vertices × transform.scale + transform.translate`; x, y are kept in
//!   the file's CRS (projected metres).
//! * **Ground**: sightline's ground is the plane z = 0, while real tiles stand on terrain that
//!   varies (2.5–16 m in Den Haag). Each building is set on the ground plane: every z of a
//!   Building and of all its parts is lowered by the lowest z of that building (over the
//!   Building and its parts). Parts keep their heights relative to each other (a tower
//!   part on a podium part stays on it); the terrain is replaced by the plane.

use super::mesh_bounds;
use super::validate::Diagnostics;
use super::{ImportError, ImportOptions};
use crate::{Mesh, Object, Prism, Scene};
use serde_json::{Map, Value};
use sightline_geom::{boolean, DVec3, Polygon};
use std::collections::BTreeMap;

fn fmt_err(m: impl Into<String>) -> ImportError {
    ImportError::Format(m.into())
}

/// Read the CityJSON document inside a zip archive.
pub fn parse_zip(bytes: &[u8], opts: &ImportOptions) -> Result<Scene, ImportError> {
    let mut zip = zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| fmt_err(format!("corrupt zip archive: {e}")))?;
    let mut found = None;
    for i in 0..zip.len() {
        let entry = zip
            .by_index(i)
            .map_err(|e| fmt_err(format!("corrupt zip archive: {e}")))?;
        let name = entry.name().to_string();
        let base = name.rsplit('/').next().unwrap_or("");
        if entry.is_dir()
            || name.starts_with("__MACOSX/")
            || base.starts_with("._")
            || !name.to_ascii_lowercase().ends_with(".json")
        {
            continue;
        }
        found = Some(i);
        break;
    }
    let i = found.ok_or_else(|| fmt_err("zip archive contains no .json file"))?;
    let mut entry = zip
        .by_index(i)
        .map_err(|e| fmt_err(format!("corrupt zip archive: {e}")))?;
    const MAX_BYTES: u64 = 4 << 30;
    if entry.size() > MAX_BYTES {
        return Err(fmt_err(format!(
            "{}: {} bytes uncompressed is too large",
            entry.name(),
            entry.size()
        )));
    }
    let mut buf = Vec::with_capacity(entry.size() as usize);
    std::io::Read::read_to_end(&mut entry, &mut buf)
        .map_err(|e| fmt_err(format!("corrupt zip archive ({}): {e}", entry.name())))?;
    let root: Value = serde_json::from_slice(&buf)
        .map_err(|e| fmt_err(format!("{}: invalid JSON: {e}", entry.name())))?;
    from_value(&root, opts)
}

/// Version string of the document ("0.8", "1.1", "2.0", …).
fn version(root: &Value) -> String {
    match root.get("version") {
        Some(Value::String(s)) => s.clone(),
        Some(Value::Number(n)) => n.to_string(),
        _ => "?".into(),
    }
}

/// Parents of a city object: `parents` (1.x, 2.0) or `parent` (0.8).
fn parents(o: &Value) -> Vec<&str> {
    if let Some(ps) = o.get("parents").and_then(Value::as_array) {
        return ps.iter().filter_map(Value::as_str).collect();
    }
    o.get("parent")
        .and_then(Value::as_str)
        .into_iter()
        .collect()
}

fn lod_of(g: &Value) -> f64 {
    match g.get("lod") {
        Some(Value::Number(n)) => n.as_f64().unwrap_or(0.0),
        Some(Value::String(s)) => s.trim().parse().unwrap_or(0.0),
        _ => 0.0,
    }
}

/// The faces of a geometry: each a list of rings of vertex indices.
fn faces(g: &Value, key: &str) -> Result<Vec<Vec<Vec<usize>>>, ImportError> {
    let ty = g.get("type").and_then(Value::as_str).unwrap_or("");
    let depth = match ty {
        "MultiSurface" | "CompositeSurface" => 0,
        "Solid" => 1,
        "MultiSolid" | "CompositeSolid" => 2,
        other => {
            return Err(fmt_err(format!(
                "city object '{key}': unsupported geometry type '{other}'"
            )))
        }
    };
    let b = g
        .get("boundaries")
        .ok_or_else(|| fmt_err(format!("city object '{key}': geometry without boundaries")))?;
    let bad = || fmt_err(format!("city object '{key}': malformed {ty} boundaries"));
    // Flatten `depth` levels of nesting down to a list of surfaces.
    let mut surfaces: Vec<&Value> = vec![b];
    for _ in 0..depth + 1 {
        surfaces = surfaces
            .into_iter()
            .map(|v| v.as_array().ok_or_else(bad))
            .collect::<Result<Vec<_>, _>>()?
            .into_iter()
            .flatten()
            .collect();
    }
    surfaces
        .into_iter()
        .map(|s| {
            s.as_array()
                .ok_or_else(bad)?
                .iter()
                .map(|ring| {
                    ring.as_array()
                        .ok_or_else(bad)?
                        .iter()
                        .map(|i| i.as_u64().map(|i| i as usize).ok_or_else(bad))
                        .collect()
                })
                .collect()
        })
        .collect()
}

/// Triangulate a planar 3D face (rings of points) in its dominant plane.
fn triangulate_face(rings: &[Vec<DVec3>]) -> Vec<[usize; 3]> {
    let ext = &rings[0];
    // Newell normal of the exterior.
    let mut n = DVec3::ZERO;
    for i in 0..ext.len() {
        let (a, b) = (ext[i], ext[(i + 1) % ext.len()]);
        n += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let an = n.abs();
    let proj = |p: &DVec3| -> [f64; 2] {
        if an.z >= an.x && an.z >= an.y {
            [p.x, p.y]
        } else if an.x >= an.y {
            [p.y, p.z]
        } else {
            [p.z, p.x]
        }
    };
    let mut data = Vec::new();
    let mut holes = Vec::new();
    for (k, r) in rings.iter().enumerate() {
        if k > 0 {
            holes.push(data.len() as u32);
        }
        data.extend(r.iter().map(proj));
    }
    let mut out: Vec<u32> = Vec::new();
    earcut::Earcut::new().earcut(data.iter().copied(), &holes, &mut out);
    out.chunks_exact(3)
        .map(|t| [t[0] as usize, t[1] as usize, t[2] as usize])
        .collect()
}

struct Doc<'a> {
    vertices: &'a [Value],
    scale: DVec3,
    translate: DVec3,
}

impl Doc<'_> {
    fn vertex(&self, i: usize, key: &str) -> Result<DVec3, ImportError> {
        let v = self.vertices.get(i).ok_or_else(|| {
            fmt_err(format!(
                "city object '{key}': vertex index {i} out of range ({} vertices)",
                self.vertices.len()
            ))
        })?;
        let c = v
            .as_array()
            .filter(|a| a.len() >= 3)
            .ok_or_else(|| fmt_err(format!("vertex {i} is not [x, y, z]")))?;
        let mut p = [0.0; 3];
        for k in 0..3 {
            p[k] = c[k]
                .as_f64()
                .ok_or_else(|| fmt_err(format!("vertex {i}: {} is not a number", c[k])))?;
        }
        let p = DVec3::from(p) * self.scale + self.translate;
        if !p.is_finite() || p.abs().max_element() > super::validate::MAX_COORD_M {
            return Err(fmt_err(format!("vertex {i}: coordinates {p} out of range")));
        }
        Ok(p)
    }
}

/// Import a parsed CityJSON document.
pub fn from_value(root: &Value, opts: &ImportOptions) -> Result<Scene, ImportError> {
    if root.get("type").and_then(Value::as_str) != Some("CityJSON") {
        return Err(fmt_err(
            "not a CityJSON document (\"type\" is not \"CityJSON\")",
        ));
    }
    let ver = version(root);
    let vertices = root
        .get("vertices")
        .and_then(Value::as_array)
        .ok_or_else(|| fmt_err(format!("CityJSON {ver}: no \"vertices\" array")))?;
    let (scale, translate) = match root.get("transform") {
        None | Some(Value::Null) => (DVec3::ONE, DVec3::ZERO),
        Some(t) => {
            let v3 = |k: &str| -> Result<DVec3, ImportError> {
                let a = t
                    .get(k)
                    .and_then(Value::as_array)
                    .filter(|a| a.len() == 3)
                    .ok_or_else(|| fmt_err(format!("transform.{k} is not 3 numbers")))?;
                let mut p = [0.0; 3];
                for i in 0..3 {
                    p[i] = a[i]
                        .as_f64()
                        .ok_or_else(|| fmt_err(format!("transform.{k} is not 3 numbers")))?;
                }
                Ok(DVec3::from(p))
            };
            (v3("scale")?, v3("translate")?)
        }
    };
    let doc = Doc {
        vertices,
        scale,
        translate,
    };
    let objs: &Map<String, Value> = root
        .get("CityObjects")
        .and_then(Value::as_object)
        .ok_or_else(|| fmt_err(format!("CityJSON {ver}: no \"CityObjects\" object")))?;
    let mut diag = Diagnostics::new(opts.strict);

    // Pick the geometry of the highest LoD of every Building/BuildingPart.
    let mut chosen: BTreeMap<&str, (&Value, f64)> = BTreeMap::new();
    let mut skipped: BTreeMap<&str, usize> = BTreeMap::new();
    for (key, o) in objs {
        let ty = o.get("type").and_then(Value::as_str).unwrap_or("?");
        let geoms = o.get("geometry").and_then(Value::as_array);
        let Some(geoms) = geoms.filter(|g| !g.is_empty()) else {
            continue;
        };
        if ty != "Building" && ty != "BuildingPart" {
            *skipped.entry(ty).or_default() += 1;
            continue;
        }
        let best = geoms
            .iter()
            .filter(|g| g.get("type").and_then(Value::as_str) != Some("GeometryInstance"))
            .max_by(|a, b| lod_of(a).total_cmp(&lod_of(b)));
        match best {
            Some(g) => {
                chosen.insert(key.as_str(), (g, lod_of(g)));
            }
            None => *skipped.entry("GeometryInstance").or_default() += 1,
        }
    }
    for (ty, n) in &skipped {
        diag.warn(
            "skipped-object",
            None,
            format!("{n} city object(s) of type {ty} skipped (not a building)"),
        );
    }

    // Resolve faces to points once; find each building's lowest z.
    let mut faces_of: BTreeMap<&str, Vec<Vec<Vec<DVec3>>>> = BTreeMap::new();
    let mut root_of: BTreeMap<&str, &str> = BTreeMap::new();
    let mut ground: BTreeMap<&str, f64> = BTreeMap::new();
    for (index, (&key, (g, _))) in chosen.iter().enumerate() {
        let resolve = || -> Result<Vec<Vec<Vec<DVec3>>>, ImportError> {
            let fs = faces(g, key)?;
            let mut pts = Vec::with_capacity(fs.len());
            for f in fs {
                let mut rings = Vec::with_capacity(f.len());
                for r in f {
                    let ring: Vec<DVec3> = r
                        .iter()
                        .map(|&i| doc.vertex(i, key))
                        .collect::<Result<_, _>>()?;
                    rings.push(ring);
                }
                pts.push(rings);
            }
            Ok(pts)
        };
        // A broken city object is one unusable feature, not a broken file.
        let pts = match resolve() {
            Ok(pts) => pts,
            Err(e) => {
                diag.skip(ImportError::Feature {
                    index,
                    message: e.to_string(),
                })?;
                continue;
            }
        };
        // Walk up to the root Building (bounded: cycles in bad input stop).
        let mut r = key;
        for _ in 0..16 {
            match objs.get(r).map(parents).and_then(|p| p.first().copied()) {
                Some(p) if objs.contains_key(p) => r = p,
                _ => break,
            }
        }
        let zmin = pts
            .iter()
            .flatten()
            .flatten()
            .fold(f64::INFINITY, |a, p| a.min(p.z));
        let e = ground.entry(r).or_insert(f64::INFINITY);
        *e = e.min(zmin);
        root_of.insert(key, r);
        faces_of.insert(key, pts);
    }

    let mut objects = Vec::with_capacity(chosen.len());
    for (index, (&key, &(_, lod))) in chosen.iter().enumerate() {
        if !faces_of.contains_key(key) {
            continue;
        }
        let g0 = ground.get(root_of[key]).copied().unwrap_or(0.0);
        let mut mesh = Mesh::default();
        let mut degenerate = 0usize;
        for rings in &faces_of[key] {
            let rings: Vec<Vec<DVec3>> = rings
                .iter()
                .map(|r| {
                    let mut r: Vec<DVec3> =
                        r.iter().map(|p| DVec3::new(p.x, p.y, p.z - g0)).collect();
                    r.dedup();
                    if r.len() > 1 && r.first() == r.last() {
                        r.pop();
                    }
                    r
                })
                .filter(|r| r.len() >= 3)
                .collect();
            if rings.is_empty() {
                degenerate += 1;
                continue;
            }
            let tris = triangulate_face(&rings);
            if tris.is_empty() {
                degenerate += 1;
                continue;
            }
            let off = mesh.vertices.len() as u32;
            mesh.vertices.extend(rings.iter().flatten());
            mesh.triangles
                .extend(tris.iter().map(|t| t.map(|i| off + i as u32)));
        }
        if degenerate > 0 {
            diag.warn(
                "degenerate-face",
                Some(index),
                format!("'{key}': {degenerate} degenerate face(s) skipped"),
            );
        }
        if mesh.triangles.is_empty() {
            diag.skip(ImportError::Feature {
                index,
                message: format!("city object '{key}': no usable face"),
            })?;
            continue;
        }
        let name = Some(key.to_string());
        if lod < 2.0 {
            let b = sightline_geom::Aabb3::from_points(&mesh.vertices);
            let tris: Vec<Polygon> = mesh
                .triangles
                .iter()
                .map(|t| {
                    Polygon::new(
                        mesh.triangle(t).iter().map(|v| v.truncate()).collect(),
                        vec![],
                    )
                    .normalized()
                })
                .filter(|p| p.area() > 1e-9)
                .collect();
            let footprint = boolean::union(&tris);
            let (base, top) = (b.min.z.max(0.0), b.max.z);
            if footprint.is_empty() || top <= base {
                diag.skip(ImportError::Feature {
                    index,
                    message: format!("city object '{key}': LoD{lod} geometry has no volume"),
                })?;
                continue;
            }
            objects.push(Object::blocks(
                name,
                footprint
                    .into_iter()
                    .map(|f| Prism::new(f, base, top))
                    .collect(),
            ));
        } else {
            let inner = mesh_bounds::inner_bound(&mesh);
            let outer = mesh_bounds::outer_bound(&mesh);
            if inner.is_empty() {
                diag.warn(
                    "no-inner-bound",
                    Some(index),
                    format!("'{key}': mesh not closed or too thin: it will not occlude"),
                );
            }
            objects.push(Object::mesh(name, mesh, inner, outer));
        }
    }
    if objects.is_empty() {
        return Err(diag.nothing_left(format!(
            "empty scene: no Building or BuildingPart with geometry among {} city object(s)",
            objs.len()
        )));
    }
    let mut scene = Scene::from_objects(objects);
    scene.warnings = diag.warnings;
    Ok(scene)
}
