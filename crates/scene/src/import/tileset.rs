//! OGC 3D Tiles importer (`tileset.json`, 1.0 and 1.1): every tile's GLB or b3dm
//! content becomes mesh objects, **one object per feature** — the `EXT_mesh_features`
//! feature id (`_FEATURE_ID_n`) of 3D Tiles 1.1, or the b3dm `_BATCHID` of 1.0 — named
//! from the `EXT_structural_metadata` property table or the b3dm batch table (`name`,
//! else `id`) when present. A primitive without feature ids is one object per node.
//! External tilesets (content that is a `.json` tileset) are followed.
//!
//! Frames (3D Tiles 1.1 "Coordinate reference system" and "glTF transforms"): a point
//! of a glTF node is mapped by the node's transforms, turned from glTF's y-up to z-up
//! ((x, y, z) ↦ (x, −z, y)), offset by a b3dm `RTC_CENTER`, then by the tile transforms
//! from the tile up to the root. The root tile's own transform places the local frame
//! on the Earth (ECEF): it is left out (warning `root-transform-dropped`) so the scene
//! stays in local metres, z up.
//!
//! Safety: every URI is resolved inside the folder of the top `tileset.json`; absolute
//! URIs, other schemes and paths escaping the folder (`../`, symbolic links) are
//! refused, as are cycles of external tilesets. Every problem is one error naming the
//! tileset file and the tile (`root.children[2]`).

use super::obj::{mesh_object, y_up_to_z_up};
use super::validate::Diagnostics;
use super::ImportError;
use crate::{Mesh, Object, Scene};
use glam::{DMat4, DVec3};
use serde_json::Value;
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};

/// Deepest tile nesting and external-tileset nesting followed.
const MAX_TILE_DEPTH: usize = 64;
const MAX_EXTERNAL_DEPTH: usize = 16;
/// Most tiles visited in all (a guard against tilesets made to exhaust memory).
const MAX_TILES: usize = 1 << 20;

/// Load the tileset at `path` (its folder bounds every URI).
pub fn load(path: &Path) -> Result<Scene, ImportError> {
    let bytes = super::read(path)?;
    let root: Value = serde_json::from_slice(&bytes)
        .map_err(|e| ImportError::Format(format!("{}: invalid JSON: {e}", path.display())))?;
    from_value(&root, path)
}

/// Whether a parsed JSON document is a 3D Tiles tileset (it has `asset` and `root`).
pub fn is_tileset(v: &Value) -> bool {
    v.get("asset").is_some_and(Value::is_object) && v.get("root").is_some_and(Value::is_object)
}

/// Import the parsed tileset `root` read from `path`.
pub fn from_value(root: &Value, path: &Path) -> Result<Scene, ImportError> {
    let canonical = path.canonicalize().map_err(|source| ImportError::Io {
        path: path.display().to_string(),
        source,
    })?;
    let folder = canonical
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("/"));
    let mut ctx = Importer {
        folder,
        chain: vec![canonical.clone()],
        diag: Diagnostics::default(),
        objects: Vec::new(),
        tiles: 0,
    };
    ctx.tileset(&canonical, root, DMat4::IDENTITY, true)?;
    if ctx.objects.is_empty() {
        return Err(ImportError::Format(format!(
            "{}: no tile has triangle content",
            path.display()
        )));
    }
    let mut scene = Scene::from_objects(ctx.objects);
    scene.warnings = ctx.diag.warnings;
    Ok(scene)
}

/// The objects of one tile content (GLB or b3dm) in the tileset frame of an untransformed
/// tile: the content parsers alone, for fuzzing and tests.
pub fn parse_content(bytes: &[u8]) -> Result<Scene, ImportError> {
    let mut ctx = Importer {
        folder: PathBuf::new(),
        chain: vec![],
        diag: Diagnostics::default(),
        objects: Vec::new(),
        tiles: 0,
    };
    let r = if bytes.starts_with(b"glTF") {
        ctx.glb(bytes, DMat4::IDENTITY, None, &Names::None, "content")
    } else if bytes.starts_with(b"b3dm") {
        ctx.b3dm(bytes, DMat4::IDENTITY, "content")
    } else {
        Err("not GLB or b3dm".into())
    };
    r.map_err(|m| ImportError::Format(format!("content: {m}")))?;
    let mut scene = Scene::from_objects(ctx.objects);
    scene.warnings = ctx.diag.warnings;
    Ok(scene)
}

struct Importer {
    /// Canonical folder of the top tileset: no URI may leave it.
    folder: PathBuf,
    /// Canonical paths of the tilesets being read (the external-tileset chain).
    chain: Vec<PathBuf>,
    diag: Diagnostics,
    objects: Vec<Object>,
    tiles: usize,
}

/// Where an error happened: the tileset file (relative to the top folder) and the tile.
struct At<'a> {
    file: &'a str,
    tile: &'a str,
}

impl At<'_> {
    fn err(&self, m: impl std::fmt::Display) -> ImportError {
        ImportError::Format(format!("tileset {}: tile {}: {m}", self.file, self.tile))
    }
}

impl Importer {
    fn rel(&self, p: &Path) -> String {
        p.strip_prefix(&self.folder)
            .unwrap_or(p)
            .display()
            .to_string()
    }

    fn tileset(
        &mut self,
        file: &Path,
        v: &Value,
        transform: DMat4,
        top: bool,
    ) -> Result<(), ImportError> {
        let name = self.rel(file);
        let at = At {
            file: &name,
            tile: "-",
        };
        let version = v
            .get("asset")
            .and_then(|a| a.get("version"))
            .and_then(Value::as_str);
        if version.is_none() {
            return Err(at.err("missing asset.version"));
        }
        let Some(root) = v.get("root").filter(|r| r.is_object()) else {
            return Err(at.err("missing root tile"));
        };
        self.tile(file, &name, root, "root".into(), transform, 0, top)
    }

    #[allow(clippy::too_many_arguments)]
    fn tile(
        &mut self,
        file: &Path,
        file_name: &str,
        t: &Value,
        path: String,
        parent: DMat4,
        depth: usize,
        top_root: bool,
    ) -> Result<(), ImportError> {
        let at = At {
            file: file_name,
            tile: &path,
        };
        self.tiles += 1;
        if self.tiles > MAX_TILES {
            return Err(at.err(format!("more than {MAX_TILES} tiles")));
        }
        if depth > MAX_TILE_DEPTH {
            return Err(at.err(format!("tiles nested deeper than {MAX_TILE_DEPTH}")));
        }
        check_bounding_volume(t.get("boundingVolume")).map_err(|m| at.err(m))?;
        match t.get("geometricError").and_then(Value::as_f64) {
            Some(e) if e.is_finite() && e >= 0.0 => {}
            Some(e) => return Err(at.err(format!("geometricError {e} is negative"))),
            None => return Err(at.err("missing geometricError")),
        }
        let local = match t.get("transform") {
            None => DMat4::IDENTITY,
            Some(m) => matrix(m).ok_or_else(|| at.err("transform is not 16 finite numbers"))?,
        };
        let world = if top_root && local != DMat4::IDENTITY {
            self.diag.warn(
                "root-transform-dropped",
                None,
                "the root tile's transform (its place on the Earth) is left out: the scene is in the tileset's local frame",
            );
            parent
        } else {
            parent * local
        };
        let mut contents: Vec<&Value> = Vec::new();
        if let Some(c) = t.get("content") {
            contents.push(c);
        }
        if let Some(cs) = t.get("contents") {
            let Some(cs) = cs.as_array() else {
                return Err(at.err("contents is not an array"));
            };
            contents.extend(cs);
        }
        for c in contents {
            let Some(uri) = c
                .get("uri")
                .or_else(|| c.get("url"))
                .and_then(Value::as_str)
            else {
                return Err(at.err("content without a uri"));
            };
            if let Some(bv) = c.get("boundingVolume") {
                check_bounding_volume(Some(bv)).map_err(|m| at.err(format!("content: {m}")))?;
            }
            self.content(file, &at, uri, world)?;
        }
        if let Some(children) = t.get("children") {
            let Some(children) = children.as_array() else {
                return Err(at.err("children is not an array"));
            };
            for (k, c) in children.iter().enumerate() {
                if !c.is_object() {
                    return Err(at.err(format!("children[{k}] is not a tile")));
                }
                self.tile(
                    file,
                    file_name,
                    c,
                    format!("{path}.children[{k}]"),
                    world,
                    depth + 1,
                    false,
                )?;
            }
        }
        Ok(())
    }

    fn content(
        &mut self,
        file: &Path,
        at: &At,
        uri: &str,
        world: DMat4,
    ) -> Result<(), ImportError> {
        let base = file.parent().unwrap_or(&self.folder).to_path_buf();
        let path = resolve(&self.folder, &base, uri)
            .map_err(|m| at.err(format!("content '{uri}': {m}")))?;
        let bytes = std::fs::read(&path)
            .map_err(|e| at.err(format!("content '{uri}': cannot read: {e}")))?;
        let cerr = |m: String| at.err(format!("content '{uri}': {m}"));
        if bytes.starts_with(b"glTF") {
            self.glb(&bytes, world, None, &Names::None, uri)
                .map_err(cerr)
        } else if bytes.starts_with(b"b3dm") {
            self.b3dm(&bytes, world, uri).map_err(cerr)
        } else if bytes.first().is_some_and(|b| *b == b'{') {
            let v: Value =
                serde_json::from_slice(&bytes).map_err(|e| cerr(format!("invalid JSON: {e}")))?;
            if !is_tileset(&v) {
                return Err(cerr(
                    "JSON content that is not a tileset (glTF JSON content is not supported: use GLB)".into(),
                ));
            }
            if self.chain.contains(&path) {
                return Err(cerr("external tilesets form a cycle".into()));
            }
            if self.chain.len() > MAX_EXTERNAL_DEPTH {
                return Err(cerr(format!(
                    "external tilesets nested deeper than {MAX_EXTERNAL_DEPTH}"
                )));
            }
            self.chain.push(path.clone());
            let r = self.tileset(&path, &v, world, false);
            self.chain.pop();
            r
        } else if [b"pnts", b"i3dm", b"cmpt"]
            .iter()
            .any(|m| bytes.starts_with(&m[..]))
        {
            self.diag.warn(
                "unsupported-content",
                None,
                format!(
                    "tile {}: content '{uri}' ({}) holds no triangle features, skipped",
                    at.tile,
                    String::from_utf8_lossy(&bytes[..4])
                ),
            );
            Ok(())
        } else {
            Err(cerr("not GLB, b3dm or a tileset".into()))
        }
    }

    /// A b3dm: 28-byte header, feature table (JSON + binary), batch table (JSON +
    /// binary), GLB.
    fn b3dm(&mut self, bytes: &[u8], world: DMat4, uri: &str) -> Result<(), String> {
        let word = |k: usize| {
            bytes
                .get(4 * k..4 * k + 4)
                .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
        };
        let (Some(len), Some(ftj), Some(ftb), Some(btj), Some(btb)) =
            (word(2), word(3), word(4), word(5), word(6))
        else {
            return Err("b3dm header shorter than 28 bytes".into());
        };
        let glb_start = 28usize
            .checked_add(ftj)
            .and_then(|s| s.checked_add(ftb))
            .and_then(|s| s.checked_add(btj))
            .and_then(|s| s.checked_add(btb))
            .filter(|&s| s <= len && len <= bytes.len())
            .ok_or("b3dm table lengths exceed the file (truncated, or a legacy header)")?;
        let json_at = |start: usize, n: usize| -> Result<Value, String> {
            if n == 0 {
                return Ok(Value::Null);
            }
            let s = std::str::from_utf8(&bytes[start..start + n])
                .map_err(|_| "b3dm table JSON is not UTF-8".to_string())?;
            serde_json::from_str(s.trim_end_matches([' ', '\0']))
                .map_err(|e| format!("b3dm table JSON: {e}"))
        };
        let ft = json_at(28, ftj)?;
        let bt = json_at(28 + ftj + ftb, btj)?;
        let rtc = match ft.get("RTC_CENTER") {
            None => None,
            Some(Value::Array(a)) if a.len() == 3 => {
                let v: Option<Vec<f64>> = a.iter().map(Value::as_f64).collect();
                let v = v.filter(|v| v.iter().all(|c| c.is_finite()));
                Some(
                    v.map(|v| DVec3::new(v[0], v[1], v[2]))
                        .ok_or("bad RTC_CENTER")?,
                )
            }
            Some(Value::Object(o)) => {
                let off = o
                    .get("byteOffset")
                    .and_then(Value::as_u64)
                    .ok_or("bad RTC_CENTER")? as usize;
                let bin = &bytes[28 + ftj..28 + ftj + ftb];
                let f = |k: usize| {
                    bin.get(off + 4 * k..off + 4 * k + 4)
                        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64)
                };
                match (f(0), f(1), f(2)) {
                    (Some(x), Some(y), Some(z)) => Some(DVec3::new(x, y, z)),
                    _ => return Err("RTC_CENTER outside the feature table".into()),
                }
            }
            Some(_) => return Err("bad RTC_CENTER".into()),
        };
        let names = ["name", "id"]
            .iter()
            .find_map(|k| bt.get(*k).and_then(Value::as_array))
            .map(|a| {
                Names::Batch(
                    a.iter()
                        .map(|v| match v {
                            Value::String(s) => Some(s.clone()),
                            Value::Number(n) => Some(n.to_string()),
                            _ => None,
                        })
                        .collect(),
                )
            })
            .unwrap_or(Names::None);
        self.glb(&bytes[glb_start..len], world, rtc, &names, uri)
    }

    /// The objects of one GLB: by feature id when the primitives have them.
    fn glb(
        &mut self,
        glb: &[u8],
        world: DMat4,
        rtc: Option<DVec3>,
        batch_names: &Names,
        uri: &str,
    ) -> Result<(), String> {
        let (gltf::Gltf { document, blob }, json) =
            super::gltf::read(glb).map_err(|e| format!("broken GLB: {e}"))?;
        let bin = blob.clone();
        let buffers = gltf::import_buffers(&document, None, blob)
            .map_err(|e| format!("broken GLB buffers: {e}"))?;
        let metadata_names = Names::from_metadata(&json, bin.as_deref());
        // Objects of this content by feature key (property table, feature id) or by node.
        let mut by_key: HashMap<(i64, i64), usize> = HashMap::new();
        let mut meshes: Vec<(Option<String>, Mesh)> = Vec::new();
        let roots: Vec<gltf::Node> = match document
            .default_scene()
            .or_else(|| document.scenes().next())
        {
            Some(s) => s.nodes().collect(),
            None => document.nodes().collect(),
        };
        let to_tileset = DMat4::from_translation(rtc.unwrap_or(DVec3::ZERO));
        let mut stack: Vec<(gltf::Node, DMat4, usize)> = roots
            .into_iter()
            .rev()
            .map(|n| (n, DMat4::IDENTITY, 0))
            .collect();
        while let Some((node, parent, depth)) = stack.pop() {
            if depth > 64 {
                return Err("node hierarchy deeper than 64 (cycle?)".into());
            }
            let local =
                DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
            let node_world = parent * local;
            for child in node.children().collect::<Vec<_>>().into_iter().rev() {
                stack.push((child, node_world, depth + 1));
            }
            let Some(gmesh) = node.mesh() else { continue };
            for prim in gmesh.primitives() {
                if prim.mode() != gltf::mesh::Mode::Triangles {
                    self.diag.warn(
                        "unsupported-primitive",
                        None,
                        format!("{uri}: {:?} primitive skipped", prim.mode()),
                    );
                    continue;
                }
                if !super::gltf::primitive_fits(&prim) {
                    return Err(format!(
                        "mesh {}: POSITION or indices accessor of the wrong type or layout",
                        gmesh.index()
                    ));
                }
                let get = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
                let reader = prim.reader(get);
                // POSITION is required (glTF §3.7.2.1): unreadable means out of its buffer.
                let Some(pos) = reader.read_positions() else {
                    return Err(format!(
                        "mesh {}: POSITION accessor cannot be read",
                        gmesh.index()
                    ));
                };
                let points: Vec<DVec3> = pos
                    .map(|p| {
                        let g = node_world.transform_point3(DVec3::new(
                            p[0] as f64,
                            p[1] as f64,
                            p[2] as f64,
                        ));
                        world.transform_point3(to_tileset.transform_point3(y_up_to_z_up(g)))
                    })
                    .collect();
                let n = points.len() as u32;
                let idx: Vec<u32> = match (reader.read_indices(), prim.indices()) {
                    (Some(i), _) => i.into_u32().collect(),
                    (None, None) => (0..n).collect(),
                    (None, Some(_)) => {
                        return Err(format!(
                            "mesh {}: indices accessor cannot be read",
                            gmesh.index()
                        ))
                    }
                };
                if !idx.len().is_multiple_of(3) {
                    return Err(format!(
                        "mesh {}: {} indices, not a multiple of 3",
                        gmesh.index(),
                        idx.len()
                    ));
                }
                if let Some(bad) = idx.iter().find(|&&i| i >= n) {
                    return Err(format!(
                        "index {bad} out of range ({n} vertices) in mesh {}",
                        gmesh.index()
                    ));
                }
                let (ids, table) = feature_ids(&json, gmesh.index(), &prim, &buffers)?;
                for t in idx.chunks_exact(3) {
                    let key = match &ids {
                        Some(f) => (table, f[t[0] as usize]),
                        None => (-1, -1 - node.index() as i64),
                    };
                    let o = *by_key.entry(key).or_insert_with(|| {
                        let name = match (&ids, key) {
                            (Some(_), (tb, f)) => {
                                metadata_names.get(tb, f).or_else(|| batch_names.get(-1, f))
                            }
                            (None, _) => node.name().map(str::to_string),
                        };
                        meshes.push((name, Mesh::default()));
                        meshes.len() - 1
                    });
                    let m = &mut meshes[o].1;
                    let base = m.vertices.len() as u32;
                    m.vertices.extend(t.iter().map(|&i| points[i as usize]));
                    m.triangles.push([base, base + 1, base + 2]);
                }
            }
        }
        for (name, mesh) in meshes {
            let index = self.objects.len();
            let mesh = weld(mesh);
            if let Some(o) =
                mesh_object(name, mesh, index, &mut self.diag).map_err(|e| e.to_string())?
            {
                self.objects.push(o);
            }
        }
        Ok(())
    }
}

/// Merge bit-identical vertices (triangles were copied out vertex by vertex).
fn weld(m: Mesh) -> Mesh {
    let mut index_of: HashMap<[u64; 3], u32> = HashMap::new();
    let mut out = Mesh::default();
    let remap: Vec<u32> = m
        .vertices
        .iter()
        .map(|v| {
            *index_of
                .entry([v.x.to_bits(), v.y.to_bits(), v.z.to_bits()])
                .or_insert_with(|| {
                    out.vertices.push(*v);
                    (out.vertices.len() - 1) as u32
                })
        })
        .collect();
    out.triangles = m
        .triangles
        .iter()
        .map(|t| t.map(|i| remap[i as usize]))
        .collect();
    out
}

/// The per-vertex feature ids of a primitive and the property table they index (−1 for
/// none): `EXT_mesh_features` first, else a b3dm `_BATCHID`.
fn feature_ids(
    json: &Value,
    mesh: usize,
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
) -> Result<(Option<Vec<i64>>, i64), String> {
    let ext = json
        .pointer(&format!(
            "/meshes/{}/primitives/{}/extensions/EXT_mesh_features/featureIds",
            mesh,
            prim.index()
        ))
        .and_then(Value::as_array);
    let mut semantic = None;
    let mut table = -1;
    if let Some(f) = ext.and_then(|a| a.iter().find(|f| f.get("attribute").is_some())) {
        let n = f.get("attribute").and_then(Value::as_u64).unwrap_or(0);
        semantic = Some(format!("FEATURE_ID_{n}"));
        table = f.get("propertyTable").and_then(Value::as_i64).unwrap_or(-1);
    }
    let semantic = semantic.unwrap_or_else(|| "BATCHID".to_string());
    let Some(acc) = prim.get(&gltf::Semantic::Extras(semantic.clone())) else {
        return Ok((None, -1));
    };
    let get = |b: gltf::Buffer| buffers.get(b.index()).map(|d| &d.0[..]);
    use gltf::accessor::{DataType, Iter};
    if !super::gltf::accessor_fits(&acc, acc.data_type().size()) {
        return Err(format!("_{semantic} accessor of the wrong layout"));
    }
    let ids: Option<Vec<i64>> = match acc.data_type() {
        DataType::U8 => Iter::<u8>::new(acc, get).map(|i| i.map(i64::from).collect()),
        DataType::U16 => Iter::<u16>::new(acc, get).map(|i| i.map(i64::from).collect()),
        DataType::U32 => Iter::<u32>::new(acc, get).map(|i| i.map(i64::from).collect()),
        DataType::F32 => Iter::<f32>::new(acc, get).map(|i| i.map(|f| f as i64).collect()),
        other => return Err(format!("_{semantic} of type {other:?}")),
    };
    let ids = ids.ok_or_else(|| format!("_{semantic} accessor cannot be read"))?;
    let vertices = prim
        .get(&gltf::Semantic::Positions)
        .map_or(0, |a| a.count());
    if ids.len() < vertices {
        return Err(format!(
            "_{semantic} has {} values for {vertices} vertices",
            ids.len()
        ));
    }
    Ok((Some(ids), table))
}

/// Feature names: from `EXT_structural_metadata` (per table) or a b3dm batch table.
enum Names {
    None,
    Batch(Vec<Option<String>>),
    Tables(HashMap<i64, Vec<Option<String>>>),
}

impl Names {
    fn get(&self, table: i64, feature: i64) -> Option<String> {
        let f = usize::try_from(feature).ok()?;
        match self {
            Names::None => None,
            Names::Batch(v) => v.get(f).cloned().flatten(),
            Names::Tables(t) => t.get(&table)?.get(f).cloned().flatten(),
        }
        .filter(|s| !s.is_empty())
    }

    /// The `name` (else `id`) STRING column of each property table.
    fn from_metadata(json: &Value, bin: Option<&[u8]>) -> Names {
        let (Some(tables), Some(bin)) = (
            json.pointer("/extensions/EXT_structural_metadata/propertyTables")
                .and_then(Value::as_array),
            bin,
        ) else {
            return Names::None;
        };
        let view = |i: &Value| -> Option<&[u8]> {
            let v = json.pointer(&format!("/bufferViews/{}", i.as_u64()?))?;
            if v.get("buffer").and_then(Value::as_u64) != Some(0) {
                return None;
            }
            let off = v.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
            let len = v.get("byteLength").and_then(Value::as_u64)? as usize;
            bin.get(off..off.checked_add(len)?)
        };
        let mut out = HashMap::new();
        for (k, t) in tables.iter().enumerate() {
            let count = t.get("count").and_then(Value::as_u64).unwrap_or(0) as usize;
            let Some(col) = ["name", "id"]
                .iter()
                .find_map(|p| t.pointer(&format!("/properties/{p}")))
            else {
                continue;
            };
            let (Some(values), Some(offsets)) = (
                col.get("values").and_then(view),
                col.get("stringOffsets").and_then(view),
            ) else {
                continue;
            };
            let width = match col.get("stringOffsetType").and_then(Value::as_str) {
                Some("UINT8") => 1,
                Some("UINT16") => 2,
                Some("UINT64") => 8,
                _ => 4,
            };
            let offset = |i: usize| -> Option<usize> {
                let b = offsets.get(i * width..(i + 1) * width)?;
                let mut w = [0u8; 8];
                w[..width].copy_from_slice(b);
                usize::try_from(u64::from_le_bytes(w)).ok()
            };
            let names = (0..count)
                .map(|i| {
                    let (a, b) = (offset(i)?, offset(i + 1)?);
                    values
                        .get(a..b)
                        .map(|s| String::from_utf8_lossy(s).into_owned())
                })
                .collect();
            out.insert(k as i64, names);
        }
        Names::Tables(out)
    }
}

/// 16 finite numbers, column-major (glTF and 3D Tiles order).
fn matrix(v: &Value) -> Option<DMat4> {
    let a = v.as_array().filter(|a| a.len() == 16)?;
    let mut m = [0.0; 16];
    for (o, x) in m.iter_mut().zip(a) {
        *o = x.as_f64().filter(|f| f.is_finite())?;
    }
    Some(DMat4::from_cols_array(&m))
}

/// A bounding volume: `box` (12 numbers, not all half-axes zero), `region` (6: west ≤
/// π … south ≤ north, minimum height ≤ maximum) or `sphere` (4, radius ≥ 0).
fn check_bounding_volume(bv: Option<&Value>) -> Result<(), String> {
    let Some(bv) = bv.filter(|b| b.is_object()) else {
        return Err("missing boundingVolume".into());
    };
    let nums = |k: &str, n: usize| -> Option<Result<Vec<f64>, String>> {
        let v = bv.get(k)?;
        let parsed = v
            .as_array()
            .filter(|a| a.len() == n)
            .and_then(|a| {
                a.iter()
                    .map(|x| x.as_f64().filter(|f| f.is_finite()))
                    .collect::<Option<Vec<f64>>>()
            })
            .ok_or(format!("boundingVolume.{k} is not {n} finite numbers"));
        Some(parsed)
    };
    if let Some(b) = nums("box", 12) {
        let b = b?;
        if b[3..].iter().all(|&c| c == 0.0) {
            return Err("boundingVolume.box has zero half-axes".into());
        }
        return Ok(());
    }
    if let Some(r) = nums("region", 6) {
        let r = r?;
        let pi = std::f64::consts::PI;
        if r[..4].iter().any(|c| c.abs() > pi + 1e-9) || r[1] > r[3] || r[4] > r[5] {
            return Err(format!(
                "boundingVolume.region {r:?} is not [west, south, east, north] in radians with minimum ≤ maximum height"
            ));
        }
        return Ok(());
    }
    if let Some(s) = nums("sphere", 4) {
        let s = s?;
        if s[3] < 0.0 {
            return Err("boundingVolume.sphere has a negative radius".into());
        }
        return Ok(());
    }
    Err("boundingVolume has no box, region or sphere".into())
}

/// The file a content URI names, inside `folder`: relative URIs only, resolved from
/// `base` (the referring tileset's folder), never above `folder`, through no symbolic
/// link leading out of it.
fn resolve(folder: &Path, base: &Path, uri: &str) -> Result<PathBuf, String> {
    let uri = uri.split(['?', '#']).next().unwrap_or("");
    if uri.is_empty() {
        return Err("empty URI".into());
    }
    if uri.contains("://") || uri.starts_with("data:") || uri.contains(':') {
        return Err(
            "absolute URIs and other schemes are not allowed: only paths relative to the tileset"
                .into(),
        );
    }
    let decoded = percent_decode(uri).ok_or("bad percent-encoding")?;
    if decoded.starts_with('/') || decoded.starts_with('\\') || decoded.contains('\0') {
        return Err("absolute paths are not allowed".into());
    }
    let mut out = base
        .strip_prefix(folder)
        .map_err(|_| "outside the tileset folder")?
        .to_path_buf();
    for c in Path::new(&decoded.replace('\\', "/")).components() {
        match c {
            Component::Normal(p) => out.push(p),
            Component::CurDir => {}
            Component::ParentDir => {
                if !out.pop() {
                    return Err("the path escapes the tileset folder".into());
                }
            }
            Component::RootDir | Component::Prefix(_) => {
                return Err("absolute paths are not allowed".into())
            }
        }
    }
    let full = folder.join(out);
    let canonical = full.canonicalize().map_err(|e| format!("missing ({e})"))?;
    if !canonical.starts_with(folder) {
        return Err("a link leads out of the tileset folder".into());
    }
    Ok(canonical)
}

fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let h = std::str::from_utf8(b.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(h, 16).ok()?);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}
