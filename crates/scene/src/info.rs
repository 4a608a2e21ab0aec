//! What `sightline info` reports of a scene (and the Python `Scene.info()`): counts,
//! triangles, bounds, fingerprint and warnings, in one serializable shape.

use crate::{Geometry, ObjectKind, Scene, Warning};
use serde::Serialize;
use std::collections::BTreeMap;

/// The `info` report of a scene (its JSON has these fields; extra ones may be added).
#[derive(Clone, Debug, Serialize)]
pub struct SceneInfo<'a> {
    /// What the scene was loaded from.
    pub scene: String,
    pub objects: usize,
    pub blocks: usize,
    pub flat: usize,
    pub meshes: usize,
    /// Triangles of the exact geometry (what the ground truth renders).
    pub triangles: usize,
    /// `[x0, y0, z0, x1, y1, z1]`.
    pub bounds: [f64; 6],
    pub fingerprint: String,
    /// Counted warnings by kind.
    pub warning_counts: BTreeMap<String, usize>,
    /// Every warning, in input order.
    pub warnings: &'a [Warning],
}

impl Scene {
    /// The `info` report of this scene, loaded from `source`.
    pub fn info(&self, source: impl Into<String>) -> SceneInfo<'_> {
        let count = |k: ObjectKind| self.objects.iter().filter(|o| o.kind() == k).count();
        let b = self.bounds;
        SceneInfo {
            scene: source.into(),
            objects: self.len(),
            blocks: count(ObjectKind::Blocks),
            flat: count(ObjectKind::Flat),
            meshes: count(ObjectKind::Mesh),
            triangles: self.triangle_count(),
            bounds: [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z],
            fingerprint: format!("{:016x}", self.fingerprint()),
            warning_counts: self.warning_counts().into_iter().collect(),
            warnings: &self.warnings,
        }
    }

    /// Triangle count without triangulating: a polygon with `n` vertices and `h` holes
    /// triangulates into `n + 2h − 2` triangles; a prism adds two per wall edge.
    pub fn triangle_count(&self) -> usize {
        let caps =
            |p: &sightline_geom::Polygon| (p.vertex_count() + 2 * p.holes.len()).saturating_sub(2);
        self.objects
            .iter()
            .map(|o| match &o.geometry {
                Geometry::Blocks(ps) => ps
                    .iter()
                    .map(|p| {
                        let c = caps(&p.footprint);
                        if p.top <= p.base {
                            c
                        } else {
                            2 * p.footprint.vertex_count() + c * if p.base > 0.0 { 2 } else { 1 }
                        }
                    })
                    .sum(),
                Geometry::Flat(ps) => ps.iter().map(caps).sum(),
                Geometry::Mesh(m) => m.triangles.len(),
            })
            .sum()
    }
}
