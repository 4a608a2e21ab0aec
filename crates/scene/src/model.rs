//! The scene: objects, their geometry and their 2.5D bounds.

use serde::{Deserialize, Serialize};
use sightline_geom::{Aabb3, DVec2, DVec3, Polygon};

/// A polygon footprint extruded from `base` to `top` (metres above the ground).
/// For blocks `top > base >= 0`; an outer bound of a flat object has `top == base`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Prism {
    pub footprint: Polygon,
    pub base: f64,
    pub top: f64,
}

impl Prism {
    pub fn new(footprint: Polygon, base: f64, top: f64) -> Self {
        Prism {
            footprint,
            base,
            top,
        }
    }

    pub fn aabb(&self) -> Aabb3 {
        let b = self.footprint.bbox();
        Aabb3::new(b.min.extend(self.base), b.max.extend(self.top))
    }

    /// Closed-surface triangles: walls (outward facing for a normalized footprint),
    /// the top cap and, when raised above the ground, the bottom cap. A prism with
    /// `top == base` yields its footprint once.
    pub fn triangles(&self) -> Vec<[DVec3; 3]> {
        let caps = self.footprint.triangulate();
        if self.top <= self.base {
            return caps
                .iter()
                .map(|t| t.map(|p| p.extend(self.base)))
                .collect();
        }
        let mut out = Vec::with_capacity(caps.len() * 2 + self.footprint.vertex_count() * 2);
        for (a, b) in self.footprint.edges() {
            let (a0, b0, a1, b1) = (
                a.extend(self.base),
                b.extend(self.base),
                a.extend(self.top),
                b.extend(self.top),
            );
            out.push([a0, b0, b1]);
            out.push([a0, b1, a1]);
        }
        for t in &caps {
            out.push(t.map(|p| p.extend(self.top)));
        }
        if self.base > 0.0 {
            for t in &caps {
                out.push([t[0], t[2], t[1]].map(|p| p.extend(self.base)));
            }
        }
        out
    }
}

/// A triangle mesh in scene coordinates.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Mesh {
    pub vertices: Vec<DVec3>,
    pub triangles: Vec<[u32; 3]>,
}

impl Mesh {
    pub fn triangle(&self, t: &[u32; 3]) -> [DVec3; 3] {
        t.map(|i| self.vertices[i as usize])
    }
}

/// The geometry of one object.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum Geometry {
    /// 2.5D buildings: prisms, possibly several (building parts), possibly overlapping.
    Blocks(Vec<Prism>),
    /// Ground polygons at z = 0: occludees only, never occluders.
    Flat(Vec<Polygon>),
    /// General triangles: an occludee, occluding only through its inner bound.
    Mesh(Mesh),
}

/// Which of the three kinds an object is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ObjectKind {
    Blocks,
    Flat,
    Mesh,
}

/// One object of the scene. Its id is its index in [`Scene::objects`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Object {
    /// The input's own identifier, if any.
    pub name: Option<String>,
    pub geometry: Geometry,
    /// Conservative *inner* 2.5D bound: contained in the object's solid. Used when the
    /// object occludes. Empty for objects that never occlude (flat, thin meshes).
    pub inner: Vec<Prism>,
    /// Conservative *outer* 2.5D bound: contains the object. Used when it is an occludee.
    pub outer: Vec<Prism>,
    /// Bounding box of the geometry.
    pub bounds: Aabb3,
}

impl Object {
    /// A single-prism building: inner = outer = the prism.
    pub fn block(name: Option<String>, footprint: Polygon, base: f64, top: f64) -> Self {
        Self::blocks(name, vec![Prism::new(footprint.normalized(), base, top)])
    }

    /// An axis-aligned box building on the ground: footprint `[x0, x1] × [y0, y1]`, top
    /// at `height` (fixtures and tests).
    pub fn rect_block(x0: f64, y0: f64, x1: f64, y1: f64, height: f64) -> Self {
        Self::block(
            None,
            Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1)),
            0.0,
            height,
        )
    }

    /// A multi-prism building: inner = outer = the prisms.
    pub fn blocks(name: Option<String>, prisms: Vec<Prism>) -> Self {
        let bounds = prisms.iter().fold(Aabb3::EMPTY, |b, p| b.union(p.aabb()));
        Object {
            name,
            inner: prisms.clone(),
            outer: prisms.clone(),
            geometry: Geometry::Blocks(prisms),
            bounds,
        }
    }

    /// Flat ground polygons: no inner bound, outer = the polygons at z = 0.
    pub fn flat(name: Option<String>, polygons: Vec<Polygon>) -> Self {
        let polygons: Vec<Polygon> = polygons.into_iter().map(Polygon::normalized).collect();
        let outer: Vec<Prism> = polygons
            .iter()
            .map(|p| Prism::new(p.clone(), 0.0, 0.0))
            .collect();
        let bounds = outer.iter().fold(Aabb3::EMPTY, |b, p| b.union(p.aabb()));
        Object {
            name,
            inner: vec![],
            outer,
            geometry: Geometry::Flat(polygons),
            bounds,
        }
    }

    /// A mesh with caller-supplied 2.5D bounds (importers derive them; see
    /// `mesh_bounds` helpers in the importers).
    pub fn mesh(name: Option<String>, mesh: Mesh, inner: Vec<Prism>, outer: Vec<Prism>) -> Self {
        let bounds = Aabb3::from_points(&mesh.vertices);
        Object {
            name,
            geometry: Geometry::Mesh(mesh),
            inner,
            outer,
            bounds,
        }
    }

    pub fn kind(&self) -> ObjectKind {
        match self.geometry {
            Geometry::Blocks(_) => ObjectKind::Blocks,
            Geometry::Flat(_) => ObjectKind::Flat,
            Geometry::Mesh(_) => ObjectKind::Mesh,
        }
    }

    /// The exact geometry as triangles (what the ground truth renders).
    pub fn triangles(&self) -> Vec<[DVec3; 3]> {
        match &self.geometry {
            Geometry::Blocks(prisms) => prisms.iter().flat_map(Prism::triangles).collect(),
            Geometry::Flat(polys) => polys.iter().flat_map(|p| p.triangulate_at(0.0)).collect(),
            Geometry::Mesh(m) => m.triangles.iter().map(|t| m.triangle(t)).collect(),
        }
    }

    /// Number of triangles of [`Object::triangles`] without building them.
    pub fn triangle_count(&self) -> usize {
        match &self.geometry {
            Geometry::Mesh(m) => m.triangles.len(),
            _ => self.triangles().len(),
        }
    }
}

/// A counted, repairable problem found while loading.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Warning {
    /// Short stable category, e.g. `"ring-not-closed"`, `"height-from-levels"`.
    pub kind: String,
    /// Index of the input feature/object it concerns, if any.
    pub feature: Option<usize>,
    pub message: String,
}

/// A scene: objects in input order (id = index) and what loading them reported.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scene {
    pub objects: Vec<Object>,
    /// Bounding box of all objects (EMPTY for an empty scene).
    pub bounds: Aabb3,
    pub warnings: Vec<Warning>,
}

impl Scene {
    pub fn from_objects(objects: Vec<Object>) -> Self {
        let bounds = objects.iter().fold(Aabb3::EMPTY, |b, o| b.union(o.bounds));
        Scene {
            objects,
            bounds,
            warnings: vec![],
        }
    }

    pub fn len(&self) -> usize {
        self.objects.len()
    }

    pub fn is_empty(&self) -> bool {
        self.objects.is_empty()
    }

    /// Counted warnings by kind, sorted by kind.
    pub fn warning_counts(&self) -> Vec<(String, usize)> {
        let mut m = std::collections::BTreeMap::<String, usize>::new();
        for w in &self.warnings {
            *m.entry(w.kind.clone()).or_default() += 1;
        }
        m.into_iter().collect()
    }

    /// A 64-bit fingerprint of the geometry (FNV-1a over every coordinate's bits, in
    /// object order): a `.pvs` is only ever used with the scene it was built for.
    /// Names and warnings do not count.
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv(0xcbf2_9ce4_8422_2325);
        h.u64(self.objects.len() as u64);
        for o in &self.objects {
            match &o.geometry {
                Geometry::Blocks(ps) => {
                    h.u64(1);
                    for p in ps {
                        h.polygon(&p.footprint);
                        h.f64(p.base);
                        h.f64(p.top);
                    }
                }
                Geometry::Flat(ps) => {
                    h.u64(2);
                    ps.iter().for_each(|p| h.polygon(p));
                }
                Geometry::Mesh(m) => {
                    h.u64(3);
                    m.vertices.iter().for_each(|v| h.vec3(*v));
                    m.triangles.iter().flatten().for_each(|i| h.u64(*i as u64));
                }
            }
        }
        h.0
    }
}

struct Fnv(u64);
impl Fnv {
    fn u64(&mut self, v: u64) {
        for b in v.to_le_bytes() {
            self.0 ^= b as u64;
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn f64(&mut self, v: f64) {
        self.u64(v.to_bits())
    }
    fn vec2(&mut self, v: DVec2) {
        self.f64(v.x);
        self.f64(v.y);
    }
    fn vec3(&mut self, v: DVec3) {
        self.f64(v.x);
        self.f64(v.y);
        self.f64(v.z);
    }
    fn polygon(&mut self, p: &Polygon) {
        for r in p.rings() {
            self.u64(r.len() as u64);
            r.iter().for_each(|v| self.vec2(*v));
        }
    }
}
