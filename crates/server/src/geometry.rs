//! Compact binary geometry of objects, as sent to walkthrough clients.
//!
//! The client of a remote walkthrough holds no a-priori copy of the scene (dual ray
//! space paper, §1): it receives the geometry of each object once, when the object first
//! enters a PVS it needs. The encoding is made to be read in a browser without parsing:
//! every field is little-endian and 4-byte aligned, so a client wraps the position and
//! index arrays in `Float32Array` / `Uint32Array` views directly.
//!
//! ## `SLG1` — object geometry (`/api/objects`, binary WebSocket frames)
//! ```text
//! magic   4 bytes  "SLG1"
//! count   u32      number of object records
//! record × count:
//!   id            u32   object id
//!   kind          u32   0 = blocks, 1 = flat, 2 = mesh
//!   vertex_count  u32   V
//!   index_count   u32   I (a multiple of 3: triangles)
//!   positions     f32 × 3V   x, y, z in metres relative to the scene origin
//!   indices       u32 × I    counter-clockwise seen from outside
//! ```
//! The scene origin is `/api/scene`'s `origin` (the cell grid's origin and z = 0):
//! relative coordinates keep `f32` at millimetre precision across a 10 km city, where
//! absolute projected coordinates (10⁵–10⁶ m) would not.
//!
//! ## `SLB1` — object bounds (`/api/boxes`, for the mini-map)
//! ```text
//! magic "SLB1", count u32, then count × 6 f32: min x, y, z, max x, y, z (relative to origin)
//! ```

use sightline_geom::DVec3;
use sightline_scene::{Object, ObjectKind, Scene};
use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

pub const GEOMETRY_MAGIC: &[u8; 4] = b"SLG1";
pub const BOXES_MAGIC: &[u8; 4] = b"SLB1";

/// Encodes object records once and keeps them (objects are immutable while serving).
pub struct GeometryStore {
    scene: Arc<Scene>,
    origin: DVec3,
    records: Vec<OnceLock<Vec<u8>>>,
}

impl GeometryStore {
    pub fn new(scene: Arc<Scene>, origin: DVec3) -> Self {
        let records = (0..scene.objects.len()).map(|_| OnceLock::new()).collect();
        GeometryStore {
            scene,
            origin,
            records,
        }
    }

    pub fn len(&self) -> usize {
        self.records.len()
    }

    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The record of one object (`None` for an unknown id).
    pub fn record(&self, id: u32) -> Option<&[u8]> {
        let slot = self.records.get(id as usize)?;
        Some(
            slot.get_or_init(|| encode_object(id, &self.scene.objects[id as usize], self.origin))
                .as_slice(),
        )
    }

    /// An `SLG1` message with the records of `ids` (unknown ids are skipped; callers
    /// validate first).
    pub fn encode(&self, ids: &[u32]) -> Vec<u8> {
        let records: Vec<&[u8]> = ids.iter().filter_map(|&i| self.record(i)).collect();
        let len = 8 + records.iter().map(|r| r.len()).sum::<usize>();
        let mut out = Vec::with_capacity(len);
        out.extend_from_slice(GEOMETRY_MAGIC);
        out.extend_from_slice(&(records.len() as u32).to_le_bytes());
        for r in records {
            out.extend_from_slice(r);
        }
        out
    }

    /// The `SLB1` bounds of every object.
    pub fn boxes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(8 + self.scene.objects.len() * 24);
        out.extend_from_slice(BOXES_MAGIC);
        out.extend_from_slice(&(self.scene.objects.len() as u32).to_le_bytes());
        for o in &self.scene.objects {
            for v in [o.bounds.min - self.origin, o.bounds.max - self.origin] {
                for c in [v.x, v.y, v.z] {
                    out.extend_from_slice(&(c as f32).to_le_bytes());
                }
            }
        }
        out
    }
}

fn kind_code(k: ObjectKind) -> u32 {
    match k {
        ObjectKind::Blocks => 0,
        ObjectKind::Flat => 1,
        ObjectKind::Mesh => 2,
    }
}

/// One object's record: its triangles with shared vertices merged (by their `f32` bits).
pub fn encode_object(id: u32, o: &Object, origin: DVec3) -> Vec<u8> {
    let mut index_of: HashMap<[u32; 3], u32> = HashMap::new();
    let mut positions: Vec<[f32; 3]> = Vec::new();
    let mut indices: Vec<u32> = Vec::new();
    for tri in o.triangles() {
        for v in tri {
            let r = v - origin;
            let p = [r.x as f32, r.y as f32, r.z as f32];
            let key = p.map(f32::to_bits);
            let i = *index_of.entry(key).or_insert_with(|| {
                positions.push(p);
                positions.len() as u32 - 1
            });
            indices.push(i);
        }
    }
    let mut out = Vec::with_capacity(16 + positions.len() * 12 + indices.len() * 4);
    for h in [
        id,
        kind_code(o.kind()),
        positions.len() as u32,
        indices.len() as u32,
    ] {
        out.extend_from_slice(&h.to_le_bytes());
    }
    for p in &positions {
        for c in p {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    for i in &indices {
        out.extend_from_slice(&i.to_le_bytes());
    }
    out
}

/// One decoded record (tests and the load-test client use it).
#[derive(Clone, Debug, PartialEq)]
pub struct DecodedObject {
    pub id: u32,
    pub kind: u32,
    pub positions: Vec<[f32; 3]>,
    pub indices: Vec<u32>,
}

/// Why an `SLG1` message is malformed.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("malformed SLG1 geometry: {0}")]
pub struct DecodeError(pub &'static str);

/// Decode an `SLG1` message, checking every length and index.
pub fn decode(bytes: &[u8]) -> Result<Vec<DecodedObject>, DecodeError> {
    let mut r = Reader { b: bytes, at: 0 };
    if r.take(4)? != GEOMETRY_MAGIC {
        return Err(DecodeError("bad magic"));
    }
    let count = r.u32()?;
    let mut out = Vec::new();
    for _ in 0..count {
        let id = r.u32()?;
        let kind = r.u32()?;
        let nv = r.u32()? as usize;
        let ni = r.u32()? as usize;
        if !ni.is_multiple_of(3) {
            return Err(DecodeError("index count not a multiple of 3"));
        }
        let pos = r.take(nv.checked_mul(12).ok_or(DecodeError("too long"))?)?;
        let positions = pos
            .chunks_exact(12)
            .map(|c| {
                let f = |k: usize| f32::from_le_bytes([c[k], c[k + 1], c[k + 2], c[k + 3]]);
                [f(0), f(4), f(8)]
            })
            .collect();
        let idx = r.take(ni.checked_mul(4).ok_or(DecodeError("too long"))?)?;
        let indices: Vec<u32> = idx
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .collect();
        if indices.iter().any(|&i| i as usize >= nv) {
            return Err(DecodeError("index out of range"));
        }
        out.push(DecodedObject {
            id,
            kind,
            positions,
            indices,
        });
    }
    if r.at != bytes.len() {
        return Err(DecodeError("trailing bytes"));
    }
    Ok(out)
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], DecodeError> {
        let end = self.at.checked_add(n).ok_or(DecodeError("too long"))?;
        let s = self.b.get(self.at..end).ok_or(DecodeError("truncated"))?;
        self.at = end;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, DecodeError> {
        let s = self.take(4)?;
        Ok(u32::from_le_bytes([s[0], s[1], s[2], s[3]]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use sightline_geom::{DVec2, Polygon};

    #[test]
    fn a_box_building_round_trips_with_shared_vertices() {
        let o = Object::block(
            None,
            Polygon::rect(DVec2::new(1000.0, 2000.0), DVec2::new(1010.0, 2020.0)),
            0.0,
            15.0,
        );
        let scene = Arc::new(Scene::from_objects(vec![o.clone(), o]));
        let store = GeometryStore::new(scene, DVec3::new(1000.0, 2000.0, 0.0));
        let bytes = store.encode(&[1]);
        assert_eq!(bytes.len() % 4, 0, "4-byte aligned");
        let d = decode(&bytes).unwrap();
        assert_eq!(d.len(), 1);
        assert_eq!(d[0].id, 1);
        assert_eq!(d[0].kind, 0);
        // 8 corners shared by 4 walls (8 triangles) and a top cap (2 triangles).
        assert_eq!(d[0].positions.len(), 8);
        assert_eq!(d[0].indices.len(), 30);
        assert!(d[0].positions.contains(&[10.0, 20.0, 15.0]));
        assert!(d[0].positions.iter().all(|p| p[0] >= 0.0 && p[1] >= 0.0));
    }

    #[test]
    fn boxes_cover_every_object() {
        let o = Object::block(
            None,
            Polygon::rect(DVec2::new(0.0, 0.0), DVec2::new(1.0, 2.0)),
            0.0,
            3.0,
        );
        let store = GeometryStore::new(Arc::new(Scene::from_objects(vec![o])), DVec3::ZERO);
        let b = store.boxes();
        assert_eq!(&b[..4], BOXES_MAGIC);
        assert_eq!(b.len(), 8 + 24);
        assert_eq!(f32::from_le_bytes([b[28], b[29], b[30], b[31]]), 3.0);
    }

    #[test]
    fn decode_rejects_truncated_and_corrupt_messages() {
        let o = Object::block(
            None,
            Polygon::rect(DVec2::new(0.0, 0.0), DVec2::new(1.0, 1.0)),
            0.0,
            3.0,
        );
        let store = GeometryStore::new(Arc::new(Scene::from_objects(vec![o])), DVec3::ZERO);
        let good = store.encode(&[0]);
        assert!(decode(&good[..good.len() - 1]).is_err());
        let mut bad = good.clone();
        bad[0] = b'X';
        assert!(decode(&bad).is_err());
        let mut huge = good.clone();
        huge[16..20].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(decode(&huge).is_err());
        assert!(decode(&[good.as_slice(), &[0u8]].concat()).is_err());
    }
}
