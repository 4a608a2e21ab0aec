//! Writers: a scene as a GeoJSON FeatureCollection (blocks and flat objects), as a
//! Wavefront OBJ (any object, as triangles), or as a binary glTF with one node per
//! object ([`glb`]).
//!
//! The GeoJSON is what the importer reads back: one feature per object, a
//! `Polygon` (or `MultiPolygon` for several parts), properties `name`, `height` (= top),
//! `min_height` (= base, only when > 0) and `"kind": "street"` for flat objects.
//! Coordinates are projected metres (marked by a top-level `local_frame` member), written with Rust's shortest round-trip float
//! formatting, so shared vertices (party walls) stay bit-identical after a round trip.
//!
//! ```
//! use sightline_scene::{export, Object, Scene};
//! use sightline_geom::{DVec2, Polygon};
//! let s = Scene::from_objects(vec![Object::block(Some("a".into()),
//!     Polygon::rect(DVec2::ZERO, DVec2::splat(10.0)), 0.0, 12.5)]);
//! let mut out = Vec::new();
//! export::write_geojson(&s, &mut out).unwrap();
//! let v: serde_json::Value = serde_json::from_slice(&out).unwrap();
//! assert_eq!(v["features"][0]["properties"]["height"], 12.5);
//! ```

pub mod glb;

use crate::{Geometry, Scene};
use sightline_geom::{DVec2, Polygon};
use std::io::Write;

/// Why a scene cannot be written in the requested format.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("object {index}: {message}")]
    Object { index: usize, message: String },
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// The writer itself failed (a document that cannot be serialized).
    #[error("{0}")]
    Format(String),
}

fn num(v: f64, index: usize) -> Result<String, ExportError> {
    if v.is_finite() {
        Ok(format!("{v}"))
    } else {
        Err(ExportError::Object {
            index,
            message: "non-finite coordinate".into(),
        })
    }
}

fn write_ring(w: &mut impl Write, ring: &[DVec2], index: usize) -> Result<(), ExportError> {
    w.write_all(b"[")?;
    // GeoJSON rings are closed: repeat the first vertex.
    for (k, p) in ring.iter().chain(ring.first()).enumerate() {
        if k > 0 {
            w.write_all(b",")?;
        }
        write!(w, "[{},{}]", num(p.x, index)?, num(p.y, index)?)?;
    }
    w.write_all(b"]")?;
    Ok(())
}

fn write_polygon(w: &mut impl Write, p: &Polygon, index: usize) -> Result<(), ExportError> {
    w.write_all(b"[")?;
    for (k, r) in p.rings().enumerate() {
        if k > 0 {
            w.write_all(b",")?;
        }
        write_ring(w, r, index)?;
    }
    w.write_all(b"]")?;
    Ok(())
}

/// Write blocks and flat objects as a GeoJSON FeatureCollection. Meshes, and blocks
/// whose parts have different heights (one feature carries one height), are errors.
pub fn write_geojson(scene: &Scene, w: &mut impl Write) -> Result<(), ExportError> {
    // `local_frame` (a foreign member) tells the importer these are projected metres,
    // even when a small scene's coordinates would fit in the lon/lat ranges.
    w.write_all(
        b"{\"type\":\"FeatureCollection\",\"local_frame\":{\"units\":\"m\"},\"features\":[\n",
    )?;
    for (index, o) in scene.objects.iter().enumerate() {
        let (polys, props): (Vec<&Polygon>, String) = match &o.geometry {
            Geometry::Blocks(prisms) => {
                let Some(first) = prisms.first() else {
                    return Err(ExportError::Object {
                        index,
                        message: "block without parts".into(),
                    });
                };
                if prisms
                    .iter()
                    .any(|p| p.base != first.base || p.top != first.top)
                {
                    return Err(ExportError::Object {
                        index,
                        message: "parts of different heights cannot share one GeoJSON feature"
                            .into(),
                    });
                }
                let mut props = format!("\"height\":{}", num(first.top, index)?);
                if first.base > 0.0 {
                    props.push_str(&format!(",\"min_height\":{}", num(first.base, index)?));
                }
                (prisms.iter().map(|p| &p.footprint).collect(), props)
            }
            Geometry::Flat(polys) => (polys.iter().collect(), "\"kind\":\"street\"".into()),
            Geometry::Mesh(_) => {
                return Err(ExportError::Object {
                    index,
                    message: "a mesh cannot be written as GeoJSON (write OBJ instead)".into(),
                })
            }
        };
        if polys.is_empty() {
            return Err(ExportError::Object {
                index,
                message: "object without polygons".into(),
            });
        }
        if index > 0 {
            w.write_all(b",\n")?;
        }
        w.write_all(b"{\"type\":\"Feature\",\"properties\":{")?;
        if let Some(name) = &o.name {
            let name = serde_json::to_string(name).map_err(std::io::Error::other)?;
            write!(w, "\"name\":{name},")?;
        }
        w.write_all(props.as_bytes())?;
        if let [p] = polys.as_slice() {
            w.write_all(b"},\"geometry\":{\"type\":\"Polygon\",\"coordinates\":")?;
            write_polygon(w, p, index)?;
        } else {
            w.write_all(b"},\"geometry\":{\"type\":\"MultiPolygon\",\"coordinates\":[")?;
            for (k, p) in polys.iter().enumerate() {
                if k > 0 {
                    w.write_all(b",")?;
                }
                write_polygon(w, p, index)?;
            }
            w.write_all(b"]")?;
        }
        w.write_all(b"}}")?;
    }
    w.write_all(b"\n]}\n")?;
    Ok(())
}

/// Write every object as an OBJ object (`o name`) of triangles; meshes keep their own
/// vertices and triangles, blocks and flat objects are triangulated
/// ([`Object::triangles`](crate::Object::triangles)). Positions are written **y-up**,
/// (x, y, z) ↦ (x, z, −y), the convention the OBJ importer reads, so that a written
/// scene loads back upright.
pub fn write_obj(scene: &Scene, w: &mut impl Write) -> Result<(), ExportError> {
    writeln!(w, "# sightline scene: {} objects", scene.objects.len())?;
    let mut next = 1usize; // OBJ indices are 1-based and global
    for (index, o) in scene.objects.iter().enumerate() {
        let name = o
            .name
            .as_deref()
            .map(|n| n.replace(char::is_whitespace, "_"))
            .unwrap_or_else(|| format!("object-{index}"));
        writeln!(w, "o {name}")?;
        let (vertices, triangles) = match &o.geometry {
            Geometry::Mesh(m) => (m.vertices.clone(), m.triangles.clone()),
            _ => {
                let tris = o.triangles();
                let v = tris.iter().flatten().copied().collect();
                let t = (0..tris.len() as u32)
                    .map(|k| [3 * k, 3 * k + 1, 3 * k + 2])
                    .collect();
                (v, t)
            }
        };
        for v in &vertices {
            writeln!(
                w,
                "v {} {} {}",
                num(v.x, index)?,
                num(v.z, index)?,
                num(-v.y, index)?
            )?;
        }
        for t in &triangles {
            if t.iter().any(|&i| i as usize >= vertices.len()) {
                return Err(ExportError::Object {
                    index,
                    message: "triangle index out of range".into(),
                });
            }
            writeln!(
                w,
                "f {} {} {}",
                next + t[0] as usize,
                next + t[1] as usize,
                next + t[2] as usize
            )?;
        }
        next += vertices.len();
    }
    Ok(())
}
