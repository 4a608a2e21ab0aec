//! Object clusters: a mesh that spans the whole level (one per material, as game
//! levels are exported) is split into spatially compact clusters, so a PVS can say
//! something about it.
//!
//! Rule: the triangles of each mesh object are bucketed by their centroid in a grid of
//! cubes of side `cluster_size` anchored at the scene's minimum corner; a bucket with
//! more than `max_triangles` triangles is halved along its longest axis (at the
//! median centroid) until every piece is under the cap. One cluster per (object,
//! piece), in object order then bucket order, so ids are deterministic. Blocks and
//! flat objects stay whole (one cluster each).
//!
//! Each cluster keeps, per triangle, its index in its source object
//! ([`Clustered::triangles`]), so a client can draw a cluster from the input file's own
//! triangles (`sightline clusters`).

use crate::{Mesh, Object, Scene};
use sightline_geom::DVec3;
use std::collections::BTreeMap;

/// A scene of clusters and, for each cluster, the source object it came from.
#[derive(Clone, Debug)]
pub struct Clustered {
    /// One object per cluster (its name is the source's name).
    pub scene: Scene,
    /// `source[c]` = id of the source object of cluster `c` (in the input scene).
    pub source: Vec<u32>,
    /// Names of the source objects, in the input order (`info`'s order).
    pub source_names: Vec<Option<String>>,
    /// `triangles[c][k]` = index, in its source object's [`Object::triangles`], of the
    /// `k`-th triangle of cluster `c`.
    pub triangles: Vec<Vec<u32>>,
}

impl Clustered {
    /// The sorted, deduplicated source objects of a set of cluster ids.
    pub fn sources_of(&self, clusters: &[u32]) -> Vec<u32> {
        let mut s: Vec<u32> = clusters
            .iter()
            .filter_map(|&c| self.source.get(c as usize).copied())
            .collect();
        s.sort_unstable();
        s.dedup();
        s
    }
}

/// Split every mesh object of `scene` into clusters (module doc for the rule).
/// `cluster_size` must be positive and finite; `max_triangles` at least 1.
pub fn cluster_scene(scene: &Scene, cluster_size: f64, max_triangles: usize) -> Clustered {
    let size = if cluster_size.is_finite() && cluster_size > 0.0 {
        cluster_size
    } else {
        f64::MAX
    };
    let cap = max_triangles.max(1);
    let origin = if scene.bounds.min.is_finite() {
        scene.bounds.min
    } else {
        DVec3::ZERO
    };
    let mut objects = Vec::new();
    let mut source = Vec::new();
    let mut triangles = Vec::new();
    for (id, o) in scene.objects.iter().enumerate() {
        let crate::Geometry::Mesh(mesh) = &o.geometry else {
            objects.push(o.clone());
            source.push(id as u32);
            triangles.push((0..o.triangle_count() as u32).collect());
            continue;
        };
        let mut buckets: BTreeMap<[i64; 3], Vec<u32>> = BTreeMap::new();
        for (t, tri) in mesh.triangles.iter().enumerate() {
            let c = centroid(&mesh.triangle(tri));
            let k = ((c - origin) / size).floor();
            let key = [k.x as i64, k.y as i64, k.z as i64];
            buckets.entry(key).or_default().push(t as u32);
        }
        for tris in buckets.into_values() {
            for piece in split_cap(mesh, tris, cap) {
                objects.push(sub_object(o.name.clone(), mesh, &piece));
                source.push(id as u32);
                triangles.push(piece);
            }
        }
    }
    let mut clustered = Scene::from_objects(objects);
    clustered.warnings = scene.warnings.clone();
    Clustered {
        scene: clustered,
        source,
        source_names: scene.objects.iter().map(|o| o.name.clone()).collect(),
        triangles,
    }
}

fn centroid(t: &[DVec3; 3]) -> DVec3 {
    (t[0] + t[1] + t[2]) / 3.0
}

/// Halve `tris` at the median centroid of its longest axis until each piece has at
/// most `cap` triangles.
fn split_cap(mesh: &Mesh, tris: Vec<u32>, cap: usize) -> Vec<Vec<u32>> {
    let mut out = Vec::new();
    let mut stack = vec![tris];
    while let Some(mut t) = stack.pop() {
        if t.len() <= cap {
            out.push(t);
            continue;
        }
        let cs: Vec<DVec3> = t
            .iter()
            .map(|&i| centroid(&mesh.triangle(&mesh.triangles[i as usize])))
            .collect();
        let (lo, hi) = cs.iter().fold(
            (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN)),
            |(lo, hi), c| (lo.min(*c), hi.max(*c)),
        );
        let ext = hi - lo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mut order: Vec<usize> = (0..t.len()).collect();
        order.sort_by(|&a, &b| cs[a][axis].total_cmp(&cs[b][axis]));
        let sorted: Vec<u32> = order.iter().map(|&i| t[i]).collect();
        t = sorted;
        let back = t.split_off(t.len() / 2);
        stack.push(back);
        stack.push(t);
    }
    out.reverse();
    out
}

fn sub_object(name: Option<String>, mesh: &Mesh, tris: &[u32]) -> Object {
    let mut map = std::collections::HashMap::new();
    let mut vertices = Vec::new();
    let mut triangles = Vec::with_capacity(tris.len());
    for &t in tris {
        let tri = mesh.triangles[t as usize].map(|v| {
            *map.entry(v).or_insert_with(|| {
                vertices.push(mesh.vertices[v as usize]);
                vertices.len() as u32 - 1
            })
        });
        triangles.push(tri);
    }
    // Clusters are occludees only here: the automatic cells' voxels occlude.
    Object::mesh(
        name,
        Mesh {
            vertices,
            triangles,
        },
        vec![],
        vec![],
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn strip(n: usize) -> Scene {
        let mut vertices = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..n {
            let x = i as f64;
            let b = vertices.len() as u32;
            vertices.extend([
                DVec3::new(x, 0.0, 0.0),
                DVec3::new(x + 1.0, 0.0, 0.0),
                DVec3::new(x, 1.0, 0.0),
            ]);
            triangles.push([b, b + 1, b + 2]);
        }
        let m = Mesh {
            vertices,
            triangles,
        };
        Scene::from_objects(vec![Object::mesh(Some("floor".into()), m, vec![], vec![])])
    }

    #[test]
    fn buckets_by_centroid_and_keeps_every_triangle() {
        let c = cluster_scene(&strip(100), 10.0, 1000);
        assert_eq!(c.scene.objects.len(), 10);
        let total: usize = c.scene.objects.iter().map(|o| o.triangle_count()).sum();
        assert_eq!(total, 100);
        assert!(c.source.iter().all(|&s| s == 0));
        assert_eq!(c.sources_of(&[3, 7]), vec![0]);
        assert_source_triangles(&strip(100), &c);
    }

    /// Every cluster triangle is its source's triangle at the recorded index, and every
    /// source triangle lands in exactly one cluster.
    fn assert_source_triangles(scene: &Scene, c: &Clustered) {
        let mut seen: Vec<Vec<bool>> = scene
            .objects
            .iter()
            .map(|o| vec![false; o.triangle_count()])
            .collect();
        for (k, o) in c.scene.objects.iter().enumerate() {
            let src = c.source[k] as usize;
            let from = scene.objects[src].triangles();
            assert_eq!(c.triangles[k].len(), o.triangle_count());
            for (t, &i) in o.triangles().iter().zip(&c.triangles[k]) {
                assert_eq!(*t, from[i as usize]);
                assert!(!std::mem::replace(&mut seen[src][i as usize], true));
            }
        }
        assert!(seen.iter().flatten().all(|&s| s));
    }

    #[test]
    fn caps_triangles_per_cluster() {
        let c = cluster_scene(&strip(100), 1000.0, 16);
        assert!(c.scene.objects.iter().all(|o| o.triangle_count() <= 16));
        let total: usize = c.scene.objects.iter().map(|o| o.triangle_count()).sum();
        assert_eq!(total, 100);
        assert_source_triangles(&strip(100), &c);
    }
}
