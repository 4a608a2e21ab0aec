//! Quake BSP (version 29) importer: the compiled level's tree (planes, nodes, leaves),
//! its world faces as polygons, and its visibility lump — the *reference* leaf PVS that
//! id's `vis` computed (`docs/methods/portals.md`). The 32-bit variants of large modern maps are read
//! too: `BSP2` (float node and leaf bounds) and `2PSB` (short bounds), whose nodes,
//! leaves, faces, edges and marksurfaces hold 32-bit indices (same lumps, same order).
//!
//! Layout (little-endian): `i32 version = 29`, then 15 lumps `(offset, length)`:
//! entities, planes, textures, vertexes, visibility, nodes, texinfo, faces, lighting,
//! clipnodes, leaves, marksurfaces, edges, surfedges, models. A node's child `c >= 0` is
//! a node, `c < 0` the leaf `-(c + 1)`; leaf 0 is the shared solid leaf; only leaves
//! `1 ..= models[0].visleafs` have a visibility row, and bit `j` of a row stands for
//! leaf `j + 1`.
//!
//! Every count, offset and index is checked: a bad file is an [`ImportError`] with a
//! one-line message, never a panic, and the node graph is verified to be a tree (so
//! walks over it terminate).
//!
//! ```no_run
//! use sightline_scene::import::bsp::load_bsp;
//! let level = load_bsp(std::path::Path::new("data/quake/dm1.bsp")).unwrap();
//! let leaf = level.point_leaf([0.0, 0.0, 0.0]);
//! let row = level.reference_row(leaf);
//! assert!(leaf == 0 || row.contains(&leaf));
//! ```

use super::ImportError;
use crate::{Mesh, Object, Scene};
use sightline_geom::{Aabb3, DVec3};
use std::path::Path;

/// Leaf contents (Quake's `CONTENTS_*`).
pub const CONTENTS_EMPTY: i32 = -1;
pub const CONTENTS_SOLID: i32 = -2;
pub const CONTENTS_WATER: i32 = -3;
pub const CONTENTS_SLIME: i32 = -4;
pub const CONTENTS_LAVA: i32 = -5;
pub const CONTENTS_SKY: i32 = -6;

const VERSION: i32 = 29;
const LUMPS: usize = 15;

/// The record layout of a file: Quake's version 29, or a 32-bit variant.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Bsp29,
    /// `BSP2`: float bounds in nodes and leaves.
    Bsp2,
    /// `2PSB`: short bounds, 32-bit indices.
    Bsp2Rmq,
}

impl Format {
    fn wide(self) -> bool {
        self != Format::Bsp29
    }
    fn node_size(self) -> usize {
        match self {
            Format::Bsp29 => 24,
            Format::Bsp2 => 44,
            Format::Bsp2Rmq => 32,
        }
    }
    fn leaf_size(self) -> usize {
        match self {
            Format::Bsp29 => 28,
            Format::Bsp2 => 44,
            Format::Bsp2Rmq => 32,
        }
    }
    fn face_size(self) -> usize {
        if self.wide() {
            28
        } else {
            20
        }
    }
    fn index_size(self) -> usize {
        if self.wide() {
            4
        } else {
            2
        }
    }
}
const MAX_DEPTH: usize = 4096;
const MAX_COORD: f64 = 1e6;

/// A plane `normal · p = dist`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BspPlane {
    pub normal: [f64; 3],
    pub dist: f64,
}

impl BspPlane {
    /// Signed distance of `p` (positive on the front side).
    pub fn distance(&self, p: [f64; 3]) -> f64 {
        self.normal[0] * p[0] + self.normal[1] * p[1] + self.normal[2] * p[2] - self.dist
    }
}

/// A node child: another node or a leaf.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Child {
    Node(u32),
    Leaf(u32),
}

impl Child {
    fn from_raw(c: i32) -> Child {
        if c >= 0 {
            Child::Node(c as u32)
        } else {
            Child::Leaf((-(c + 1)) as u32)
        }
    }
}

/// An inner node: its splitting plane; `children[0]` is in front, `children[1]` behind.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BspNode {
    pub plane: u32,
    pub children: [Child; 2],
}

/// A leaf: a convex region of one content.
#[derive(Clone, Debug, PartialEq)]
pub struct BspLeaf {
    pub contents: i32,
    /// Offset of the leaf's row in the visibility lump (negative: no row).
    pub visofs: i32,
    pub mins: [f64; 3],
    pub maxs: [f64; 3],
    /// World faces marked in this leaf (indices into [`BspLevel::faces`]).
    pub faces: Vec<u32>,
}

impl BspLeaf {
    /// Whether sight passes through the leaf's volume: empty space and liquids do;
    /// solid and sky do not.
    pub fn is_open(&self) -> bool {
        is_open(self.contents)
    }
}

/// Whether sight passes through a leaf of `contents` (empty, water, slime, lava).
pub fn is_open(contents: i32) -> bool {
    matches!(
        contents,
        CONTENTS_EMPTY | CONTENTS_WATER | CONTENTS_SLIME | CONTENTS_LAVA
    )
}

/// Whether a texture is a liquid surface (`*water…`, `*slime…`, `*lava…`, `*teleport…`):
/// see-through for visibility (vis floods through it), as Quake draws it.
pub fn is_liquid(texture: &str) -> bool {
    texture.starts_with('*')
}

/// A world face: its polygon and what it is made of.
#[derive(Clone, Debug, PartialEq)]
pub struct BspFace {
    pub polygon: Vec<[f64; 3]>,
    pub plane: u32,
    /// The face looks along the plane's normal (`false`) or against it (`true`).
    pub back: bool,
    /// Texture name (`"sky…"` sky, `"*…"` liquid surface); empty when missing.
    pub texture: String,
    /// Leaves that mark this face (from the leaves' marksurfaces).
    pub leaves: Vec<u32>,
}

/// A parsed level (model 0, the world).
#[derive(Clone, Debug, PartialEq)]
pub struct BspLevel {
    pub planes: Vec<BspPlane>,
    pub nodes: Vec<BspNode>,
    pub leaves: Vec<BspLeaf>,
    /// The world's faces; a face's id is its index here (= its index in the file, as
    /// the world model's faces come first).
    pub faces: Vec<BspFace>,
    pub headnode: Child,
    /// Leaves `1 ..= visleafs` have a reference visibility row.
    pub visleafs: u32,
    pub bounds: Aabb3,
    /// The raw visibility lump.
    pub vis: Vec<u8>,
}

struct Reader<'a> {
    data: &'a [u8],
    format: Format,
    lumps: [(usize, usize); LUMPS],
}

const LUMP_NAMES: [&str; LUMPS] = [
    "entities",
    "planes",
    "textures",
    "vertexes",
    "visibility",
    "nodes",
    "texinfo",
    "faces",
    "lighting",
    "clipnodes",
    "leaves",
    "marksurfaces",
    "edges",
    "surfedges",
    "models",
];

fn err(msg: impl Into<String>) -> ImportError {
    ImportError::Format(format!("BSP: {}", msg.into()))
}

fn i32_at(d: &[u8], o: usize) -> Option<i32> {
    Some(i32::from_le_bytes(d.get(o..o + 4)?.try_into().ok()?))
}
fn i16_at(d: &[u8], o: usize) -> Option<i16> {
    Some(i16::from_le_bytes(d.get(o..o + 2)?.try_into().ok()?))
}
fn u16_at(d: &[u8], o: usize) -> Option<u16> {
    Some(u16::from_le_bytes(d.get(o..o + 2)?.try_into().ok()?))
}
fn u32_at(d: &[u8], o: usize) -> Option<u32> {
    Some(u32::from_le_bytes(d.get(o..o + 4)?.try_into().ok()?))
}
fn f32_at(d: &[u8], o: usize) -> Option<f64> {
    Some(f32::from_le_bytes(d.get(o..o + 4)?.try_into().ok()?) as f64)
}

impl<'a> Reader<'a> {
    fn new(data: &'a [u8]) -> Result<Self, ImportError> {
        let version = i32_at(data, 0).ok_or_else(|| err("file too short for a header"))?;
        let format = match &data[..4] {
            b"BSP2" => Format::Bsp2,
            b"2PSB" => Format::Bsp2Rmq,
            _ if version == VERSION => Format::Bsp29,
            _ => {
                return Err(err(format!(
                    "version {version}, only Quake's version 29, BSP2 and 2PSB are supported"
                )))
            }
        };
        let mut lumps = [(0, 0); LUMPS];
        for (i, l) in lumps.iter_mut().enumerate() {
            let (o, n) = (
                i32_at(data, 4 + 8 * i).ok_or_else(|| err("truncated lump directory"))?,
                i32_at(data, 8 + 8 * i).ok_or_else(|| err("truncated lump directory"))?,
            );
            if o < 0 || n < 0 || (o as usize).saturating_add(n as usize) > data.len() {
                return Err(err(format!(
                    "lump {} (offset {o}, length {n}) lies outside the file ({} bytes)",
                    LUMP_NAMES[i],
                    data.len()
                )));
            }
            *l = (o as usize, n as usize);
        }
        Ok(Reader {
            data,
            format,
            lumps,
        })
    }

    fn lump(&self, i: usize) -> &'a [u8] {
        let (o, n) = self.lumps[i];
        &self.data[o..o + n]
    }

    /// The lump as `count` records of `size` bytes.
    fn records(&self, i: usize, size: usize) -> Result<(&'a [u8], usize), ImportError> {
        let l = self.lump(i);
        if !l.len().is_multiple_of(size) {
            return Err(err(format!(
                "lump {} has {} bytes, not a multiple of its {size}-byte records",
                LUMP_NAMES[i],
                l.len()
            )));
        }
        Ok((l, l.len() / size))
    }
}

fn finite3(p: [f64; 3], what: &str) -> Result<[f64; 3], ImportError> {
    if p.iter().all(|v| v.is_finite() && v.abs() <= MAX_COORD) {
        Ok(p)
    } else {
        Err(err(format!("{what} {p:?} is not finite or out of range")))
    }
}

/// Parse a BSP file (version 29).
pub fn read_bsp(data: &[u8]) -> Result<BspLevel, ImportError> {
    let r = Reader::new(data)?;
    let short = |what: &str| err(format!("truncated {what}"));

    // Planes: normal f32×3, dist f32, type i32.
    let (l, n) = r.records(1, 20)?;
    let mut planes = Vec::with_capacity(n);
    for i in 0..n {
        let o = 20 * i;
        let f = |k: usize| f32_at(l, o + 4 * k).ok_or_else(|| short("plane"));
        let normal = finite3([f(0)?, f(1)?, f(2)?], "plane normal")?;
        let dist = f(3)?;
        let len2 = normal.iter().map(|v| v * v).sum::<f64>();
        if !dist.is_finite() || dist.abs() > MAX_COORD || !(len2 > 0.5 && len2 < 2.0) {
            return Err(err(format!("plane {i} is not a unit plane")));
        }
        planes.push(BspPlane { normal, dist });
    }

    // Vertexes.
    let (l, n) = r.records(3, 12)?;
    let mut vertexes = Vec::with_capacity(n);
    for i in 0..n {
        let f = |k: usize| f32_at(l, 12 * i + 4 * k).ok_or_else(|| short("vertex"));
        vertexes.push(finite3([f(0)?, f(1)?, f(2)?], "vertex")?);
    }

    // Models: the world is model 0.
    let (l, n) = r.records(14, 64)?;
    if n == 0 {
        return Err(err("no models (the world model 0 is missing)"));
    }
    let m = |k: usize| i32_at(l, 36 + 4 * k).ok_or_else(|| short("model"));
    let headnode_raw = m(0)?;
    let visleafs = m(4)?;
    let (firstface, numfaces) = (m(5)?, m(6)?);

    // Leaves.
    let fmt = r.format;
    let (leaf_lump, numleaves) = r.records(10, fmt.leaf_size())?;
    if numleaves == 0 {
        return Err(err("no leaves"));
    }
    if visleafs < 0 || visleafs as usize >= numleaves {
        return Err(err(format!(
            "model 0 has {visleafs} visleafs but the file has {numleaves} leaves"
        )));
    }

    // Nodes: plane i32, children i16×2, mins/maxs i16×6, firstface u16, numfaces u16.
    // (BSP2 / 2PSB: children i32×2, then wider bounds and face range.)
    let (l, n) = r.records(5, fmt.node_size())?;
    let mut nodes = Vec::with_capacity(n);
    for i in 0..n {
        let o = fmt.node_size() * i;
        let plane = i32_at(l, o).ok_or_else(|| short("node"))?;
        if plane < 0 || plane as usize >= planes.len() {
            return Err(err(format!("node {i} refers to missing plane {plane}")));
        }
        let mut children = [Child::Leaf(0); 2];
        for (k, c) in children.iter_mut().enumerate() {
            let raw = if fmt.wide() {
                i32_at(l, o + 4 + 4 * k)
            } else {
                i16_at(l, o + 4 + 2 * k).map(i32::from)
            }
            .ok_or_else(|| short("node"))?;
            *c = Child::from_raw(raw);
            match *c {
                Child::Node(j) if j as usize >= n => {
                    return Err(err(format!("node {i} refers to missing node {j}")))
                }
                Child::Leaf(j) if j as usize >= numleaves => {
                    return Err(err(format!("node {i} refers to missing leaf {j}")))
                }
                _ => {}
            }
        }
        nodes.push(BspNode {
            plane: plane as u32,
            children,
        });
    }
    if headnode_raw < 0 || headnode_raw as usize >= nodes.len() {
        return Err(err(format!(
            "model 0's head node {headnode_raw} is missing ({} nodes)",
            nodes.len()
        )));
    }
    let headnode = Child::Node(headnode_raw as u32);
    check_tree(&nodes, headnode)?;

    // Edges, surfedges.
    let (edge_lump, numedges) = r.records(12, 2 * fmt.index_size())?;
    let (se_lump, numse) = r.records(13, 4)?;

    // Texture names through texinfo → miptex.
    let textures = texture_names(r.lump(2));
    let (texinfo_lump, numtexinfo) = r.records(6, 40)?;

    // Faces of model 0.
    let (face_lump, numfaces_all) = r.records(7, fmt.face_size())?;
    if firstface < 0
        || numfaces < 0
        || (firstface as usize).saturating_add(numfaces as usize) > numfaces_all
    {
        return Err(err(format!(
            "model 0's faces {firstface}+{numfaces} exceed the {numfaces_all} faces of the file"
        )));
    }
    let (firstface, numfaces) = (firstface as usize, numfaces as usize);
    let mut faces = Vec::with_capacity(numfaces);
    for fi in firstface..firstface + numfaces {
        let o = fmt.face_size() * fi;
        // BSP29: plane u16, side i16, firstedge i32, numedges i16, texinfo i16;
        // BSP2 / 2PSB: five i32.
        let (plane, side, first, count, texinfo) = if fmt.wide() {
            let f = |k: usize| i32_at(face_lump, o + 4 * k).ok_or_else(|| short("face"));
            (f(0)?, f(1)?, f(2)?, f(3)?, f(4)?)
        } else {
            let h = |k: usize| i16_at(face_lump, o + k).ok_or_else(|| short("face"));
            let plane = u16_at(face_lump, o).ok_or_else(|| short("face"))? as i32;
            let first = i32_at(face_lump, o + 4).ok_or_else(|| short("face"))?;
            (plane, h(2)? as i32, first, h(8)? as i32, h(10)? as i32)
        };
        let plane = usize::try_from(plane).unwrap_or(usize::MAX);
        if plane >= planes.len() {
            return Err(err(format!("face {fi} refers to missing plane {plane}")));
        }
        if first < 0 || count < 0 || (first as usize).saturating_add(count as usize) > numse {
            return Err(err(format!(
                "face {fi}'s edges {first}+{count} exceed the {numse} surfedges"
            )));
        }
        let mut polygon = Vec::with_capacity(count as usize);
        for k in first as usize..first as usize + count as usize {
            let se = i32_at(se_lump, 4 * k).ok_or_else(|| short("surfedge"))?;
            let (edge, end) = if se >= 0 {
                (se as usize, 0)
            } else {
                ((se as i64).unsigned_abs() as usize, 1)
            };
            if edge >= numedges {
                return Err(err(format!("surfedge {k} refers to missing edge {edge}")));
            }
            let v = if fmt.wide() {
                u32_at(edge_lump, 8 * edge + 4 * end).map(|v| v as usize)
            } else {
                u16_at(edge_lump, 4 * edge + 2 * end).map(usize::from)
            }
            .ok_or_else(|| short("edge"))?;
            let p = vertexes
                .get(v)
                .ok_or_else(|| err(format!("edge {edge} refers to missing vertex {v}")))?;
            polygon.push(*p);
        }
        let texture = if texinfo >= 0 && (texinfo as usize) < numtexinfo {
            i32_at(texinfo_lump, 40 * texinfo as usize + 32)
                .and_then(|m| usize::try_from(m).ok())
                .and_then(|m| textures.get(m).cloned())
                .unwrap_or_default()
        } else {
            String::new()
        };
        faces.push(BspFace {
            polygon,
            plane: plane as u32,
            back: side != 0,
            texture,
            leaves: Vec::new(),
        });
    }

    // Marksurfaces, then the leaves that use them.
    let (ms_lump, numms) = r.records(11, fmt.index_size())?;
    let mut leaves = Vec::with_capacity(numleaves);
    let mut bounds = Aabb3::EMPTY;
    for i in 0..numleaves {
        let o = fmt.leaf_size() * i;
        let contents = i32_at(leaf_lump, o).ok_or_else(|| short("leaf"))?;
        let visofs = i32_at(leaf_lump, o + 4).ok_or_else(|| short("leaf"))?;
        // Bounds: i16×6 (BSP29, 2PSB) or f32×6 (BSP2); then the marksurface range, u16×2
        // (BSP29) or u32×2.
        let c = |k: usize| -> Result<f64, ImportError> {
            match fmt {
                Format::Bsp2 => f32_at(leaf_lump, o + 8 + 4 * k).filter(|v| v.is_finite()),
                _ => i16_at(leaf_lump, o + 8 + 2 * k).map(f64::from),
            }
            .ok_or_else(|| short("leaf"))
        };
        let mins = [c(0)?, c(1)?, c(2)?];
        let maxs = [c(3)?, c(4)?, c(5)?];
        let (first, count) = match fmt {
            Format::Bsp29 => (
                u16_at(leaf_lump, o + 20).map(usize::from),
                u16_at(leaf_lump, o + 22).map(usize::from),
            ),
            Format::Bsp2Rmq => (
                u32_at(leaf_lump, o + 20).map(|v| v as usize),
                u32_at(leaf_lump, o + 24).map(|v| v as usize),
            ),
            Format::Bsp2 => (
                u32_at(leaf_lump, o + 32).map(|v| v as usize),
                u32_at(leaf_lump, o + 36).map(|v| v as usize),
            ),
        };
        let (first, count) = (
            first.ok_or_else(|| short("leaf"))?,
            count.ok_or_else(|| short("leaf"))?,
        );
        if first.saturating_add(count) > numms {
            return Err(err(format!(
                "leaf {i}'s marksurfaces {first}+{count} exceed the {numms} in the file"
            )));
        }
        if !(-6..=-1).contains(&contents) && i > 0 {
            return Err(err(format!("leaf {i} has unknown contents {contents}")));
        }
        let mut leaf_faces = Vec::with_capacity(count);
        for k in first..first + count {
            let f = if fmt.wide() {
                u32_at(ms_lump, 4 * k).map(|v| v as usize)
            } else {
                u16_at(ms_lump, 2 * k).map(usize::from)
            }
            .ok_or_else(|| short("marksurface"))?;
            // Faces of other models (doors, lifts) are not world objects.
            if (firstface..firstface + numfaces).contains(&f) {
                let id = (f - firstface) as u32;
                leaf_faces.push(id);
                faces[f - firstface].leaves.push(i as u32);
            }
        }
        if i >= 1 && i <= visleafs as usize {
            bounds = bounds.union(Aabb3::new(DVec3::from(mins), DVec3::from(maxs)));
        }
        leaves.push(BspLeaf {
            contents,
            visofs,
            mins,
            maxs,
            faces: leaf_faces,
        });
    }
    Ok(BspLevel {
        planes,
        nodes,
        leaves,
        faces,
        headnode,
        visleafs: visleafs as u32,
        bounds,
        vis: r.lump(4).to_vec(),
    })
}

/// The node graph below `head` must be a tree: no node reached twice, bounded depth.
fn check_tree(nodes: &[BspNode], head: Child) -> Result<(), ImportError> {
    let mut seen = vec![false; nodes.len()];
    let mut stack = vec![(head, 0usize)];
    while let Some((c, depth)) = stack.pop() {
        if let Child::Node(n) = c {
            if depth > MAX_DEPTH {
                return Err(err(format!("the tree is deeper than {MAX_DEPTH} nodes")));
            }
            let seen_n = &mut seen[n as usize];
            if *seen_n {
                return Err(err(format!("node {n} is reached twice (not a tree)")));
            }
            *seen_n = true;
            for ch in nodes[n as usize].children {
                stack.push((ch, depth + 1));
            }
        }
    }
    Ok(())
}

/// Texture names of the miptex lump (missing or malformed entries are empty).
fn texture_names(l: &[u8]) -> Vec<String> {
    let n = i32_at(l, 0).unwrap_or(0).clamp(0, (l.len() / 4) as i32) as usize;
    (0..n)
        .map(|i| {
            i32_at(l, 4 + 4 * i)
                .and_then(|o| usize::try_from(o).ok())
                .and_then(|o| l.get(o..o + 16))
                .map(|name| {
                    let end = name.iter().position(|&b| b == 0).unwrap_or(16);
                    String::from_utf8_lossy(&name[..end]).to_ascii_lowercase()
                })
                .unwrap_or_default()
        })
        .collect()
}

/// Read a `.bsp` file.
pub fn load_bsp(path: &Path) -> Result<BspLevel, ImportError> {
    let bytes = super::read(path)?;
    read_bsp(&bytes).map_err(|e| ImportError::Format(format!("{}: {e}", path.display())))
}

impl BspLevel {
    /// A level from its parts (tests, generated levels): the world's faces are `faces`;
    /// each face's `leaves` is filled from the leaves' `faces`. Fails on a bad index or
    /// a node graph that is not a tree.
    pub fn from_parts(
        planes: Vec<BspPlane>,
        nodes: Vec<BspNode>,
        leaves: Vec<BspLeaf>,
        mut faces: Vec<BspFace>,
        headnode: Child,
        visleafs: u32,
        vis: Vec<u8>,
    ) -> Result<BspLevel, ImportError> {
        for (i, n) in nodes.iter().enumerate() {
            if n.plane as usize >= planes.len() {
                return Err(err(format!("node {i} refers to missing plane {}", n.plane)));
            }
            for c in n.children {
                let ok = match c {
                    Child::Node(j) => (j as usize) < nodes.len(),
                    Child::Leaf(j) => (j as usize) < leaves.len(),
                };
                if !ok {
                    return Err(err(format!("node {i} refers to a missing child {c:?}")));
                }
            }
        }
        match headnode {
            Child::Node(j) if (j as usize) < nodes.len() => check_tree(&nodes, headnode)?,
            Child::Leaf(j) if (j as usize) < leaves.len() => {}
            _ => return Err(err("missing head node")),
        }
        if visleafs as usize >= leaves.len().max(1) {
            return Err(err("more visleafs than leaves"));
        }
        faces.iter_mut().for_each(|f| f.leaves.clear());
        for (i, l) in leaves.iter().enumerate() {
            for &f in &l.faces {
                faces
                    .get_mut(f as usize)
                    .ok_or_else(|| err(format!("leaf {i} refers to missing face {f}")))?
                    .leaves
                    .push(i as u32);
            }
        }
        let bounds = leaves
            .iter()
            .skip(1)
            .take(visleafs as usize)
            .fold(Aabb3::EMPTY, |b, l| {
                b.union(Aabb3::new(DVec3::from(l.mins), DVec3::from(l.maxs)))
            });
        Ok(BspLevel {
            planes,
            nodes,
            leaves,
            faces,
            headnode,
            visleafs,
            bounds,
            vis,
        })
    }

    /// The leaf holding `p` (leaf 0 or another solid leaf when `p` is inside a wall).
    /// On a node plane the point goes to the back side, as in Quake's `PointInLeaf`.
    pub fn point_leaf(&self, p: [f64; 3]) -> u32 {
        let mut c = self.headnode;
        loop {
            match c {
                Child::Leaf(l) => return l,
                Child::Node(n) => {
                    let node = &self.nodes[n as usize];
                    let d = self.planes[node.plane as usize].distance(p);
                    c = node.children[if d > 0.0 { 0 } else { 1 }];
                }
            }
        }
    }

    /// The reference PVS of `leaf` from the visibility lump: the leaves it sees, sorted
    /// ascending. Empty for leaf 0 and leaves without a row; every leaf of the level
    /// (`1 ..= visleafs`) when the level has no visibility data for it.
    pub fn reference_row(&self, leaf: u32) -> Vec<u32> {
        if leaf == 0 || leaf > self.visleafs {
            return Vec::new();
        }
        let Some(l) = self.leaves.get(leaf as usize) else {
            return Vec::new();
        };
        if l.visofs < 0 || self.vis.is_empty() {
            return (1..=self.visleafs).collect();
        }
        let row_bytes = (self.visleafs as usize).div_ceil(8);
        let mut out = Vec::new();
        let mut i = l.visofs as usize;
        let mut byte = 0usize;
        while byte < row_bytes {
            let Some(&b) = self.vis.get(i) else { break };
            i += 1;
            if b == 0 {
                let Some(&count) = self.vis.get(i) else { break };
                i += 1;
                byte += count as usize;
                continue;
            }
            for bit in 0..8 {
                let j = byte * 8 + bit;
                if b & (1 << bit) != 0 && j < self.visleafs as usize {
                    out.push(j as u32 + 1);
                }
            }
            byte += 1;
        }
        out
    }

    /// Whether `leaf` is a leaf a viewer can stand in (one of `1 ..= visleafs`, open).
    pub fn is_view_leaf(&self, leaf: u32) -> bool {
        leaf >= 1
            && leaf <= self.visleafs
            && self.leaves.get(leaf as usize).is_some_and(|l| l.is_open())
    }

    /// The scene: one mesh object per world face (id = face index, named by its
    /// texture), its polygon triangulated as a fan. Faces are thin, so no object has an
    /// inner (occluding) 2.5D bound: in the scene model nothing occludes, sky and liquid
    /// surfaces alike; occlusion indoors comes from the tree (solid and sky leaves are
    /// opaque, liquid leaves see-through), which the portal methods use.
    pub fn to_scene(&self) -> Scene {
        let objects = self
            .faces
            .iter()
            .map(|f| {
                let vertices: Vec<DVec3> = f.polygon.iter().map(|p| DVec3::from(*p)).collect();
                let triangles = (1..f.polygon.len().saturating_sub(1))
                    .map(|k| [0, k as u32, k as u32 + 1])
                    .collect();
                let mesh = Mesh {
                    vertices,
                    triangles,
                };
                let outer = super::mesh_bounds::outer_bound(&mesh);
                let name = (!f.texture.is_empty()).then(|| f.texture.clone());
                Object::mesh(name, mesh, Vec::new(), outer)
            })
            .collect();
        Scene::from_objects(objects)
    }
}

/// Where a player starts in a BSP file: the `origin` of the first `info_player_start`
/// entity of the entity lump (else of the first `info_player_deathmatch`), in level
/// units. Quake puts a player's origin 24 units above the floor and the eye 22 above the
/// origin. `None` when the file has no such entity or cannot be read.
pub fn player_start(data: &[u8]) -> Option<[f64; 3]> {
    let r = Reader::new(data).ok()?;
    let text = String::from_utf8_lossy(r.lump(0));
    let mut found: [Option<[f64; 3]>; 2] = [None, None];
    // Entities are `{ "key" "value" ... }` blocks; values never hold quotes.
    for block in text.split('{').skip(1) {
        let body = block.split('}').next().unwrap_or("");
        let quoted: Vec<&str> = body.split('"').skip(1).step_by(2).collect();
        let mut class = None;
        let mut origin = None;
        for kv in quoted.chunks(2) {
            match kv {
                ["classname", v] => class = Some(*v),
                ["origin", v] => {
                    let n: Vec<f64> = v
                        .split_whitespace()
                        .filter_map(|x| x.parse().ok())
                        .collect();
                    if let [x, y, z] = n[..] {
                        origin = finite3([x, y, z], "origin").ok();
                    }
                }
                _ => {}
            }
        }
        let slot = match class {
            Some("info_player_start") => 0,
            Some("info_player_deathmatch") => 1,
            _ => continue,
        };
        if found[slot].is_none() {
            found[slot] = origin;
        }
    }
    found[0].or(found[1])
}

/// The importer's entry point for [`super::load`].
pub fn parse(bytes: &[u8]) -> Result<Scene, ImportError> {
    Ok(read_bsp(bytes)?.to_scene())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_headers_are_errors() {
        assert!(read_bsp(&[]).is_err());
        let mut v = vec![0u8; 4 + 8 * LUMPS];
        v[0] = 30;
        assert!(read_bsp(&v).unwrap_err().to_string().contains("version 30"));
        v[0] = 29;
        // Lump 1 beyond the end.
        v[12] = 200;
        assert!(read_bsp(&v).unwrap_err().to_string().contains("planes"));
        v[12] = 0;
        assert!(read_bsp(&v).unwrap_err().to_string().contains("model"));
    }

    #[test]
    fn the_player_start_is_read_from_the_entities() {
        let text = br#"{ "classname" "worldspawn" "wad" "x.wad" }
{ "origin" "1 2 3" "classname" "info_player_deathmatch" }
{ "classname" "info_player_start" "origin" "-480 -352 88" "angle" "90" }
"#;
        let mut v = vec![0u8; 4 + 8 * LUMPS];
        v[0] = 29;
        let at = v.len() as i32;
        v[4..8].copy_from_slice(&at.to_le_bytes());
        v[8..12].copy_from_slice(&(text.len() as i32).to_le_bytes());
        v.extend_from_slice(text);
        assert_eq!(player_start(&v), Some([-480.0, -352.0, 88.0]));
        let only_dm = br#"{ "origin" "1 2 3" "classname" "info_player_deathmatch" }"#;
        v.truncate(4 + 8 * LUMPS);
        v[8..12].copy_from_slice(&(only_dm.len() as i32).to_le_bytes());
        v.extend_from_slice(only_dm);
        assert_eq!(player_start(&v), Some([1.0, 2.0, 3.0]));
        assert_eq!(player_start(&[1, 2]), None);
    }
}
