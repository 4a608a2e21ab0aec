//! `forest`: trees as meshes on open ground — the occlusion-sweep scene of the
//! extended-projection paper (Durand et al. 2000, §7.2: 7,750 trees × 1,000 leaves).
//!
//! Each tree is one mesh object: a closed trunk box and `leaves_per_tree` small leaf
//! quads (two triangles each) scattered with random orientations in an ellipsoidal
//! crown. No single leaf occludes much; only their aggregation does — which is what
//! the occlusion sweep is for.
//!
//! Bounds: the *inner* bound is the trunk prism (the only solid part; leaves
//! are not solid); the *outer* bound is two prisms, the trunk prism and the crown's
//! bounding prism (tighter than one prism over both, and still containing every
//! triangle).

use super::{snap_mm, Rng};
use crate::{Mesh, Object, Prism, Scene};
use rayon::prelude::*;
use sightline_geom::{Aabb2, DVec2, DVec3, Polygon, ViewCell};

/// Parameters of [`forest_with`].
#[derive(Clone, Debug, PartialEq)]
pub struct ForestParams {
    pub trees: usize,
    pub leaves_per_tree: usize,
    /// Mean distance between neighbouring trees, in metres.
    pub spacing_m: f64,
    /// Trunk height range (m): the crown's centre lies above it.
    pub trunk_height_m: (f64, f64),
    /// Horizontal crown radius range (m).
    pub crown_radius_m: (f64, f64),
    /// Range of the ratio of the crown's vertical radius to its horizontal one.
    pub crown_aspect: (f64, f64),
    /// Height of the crown's centre above the trunk's top, in vertical radii (a crown
    /// reaching below the ground is cut by it: no leaf centre lies below z = 0).
    pub crown_lift: f64,
    /// Leaf side range (m).
    pub leaf_size_m: (f64, f64),
}

impl Default for ForestParams {
    fn default() -> Self {
        ForestParams {
            trees: 500,
            leaves_per_tree: 200,
            spacing_m: 7.0,
            trunk_height_m: (2.5, 4.0),
            crown_radius_m: (1.8, 3.2),
            crown_aspect: (0.9, 1.3),
            crown_lift: 0.8,
            leaf_size_m: (0.15, 0.35),
        }
    }
}

impl ForestParams {
    /// `n` cells of side `size_m` at eye height, each centred between four trees of the
    /// forest grid, spread over the middle half of the forest.
    pub fn cells_between_trees(&self, size_m: f64, n: usize) -> Vec<ViewCell> {
        let p = self;
        let g = ((p.trees as f64).sqrt().ceil() as usize).max(2);
        let (lo, span) = (g / 4, (g / 2).max(1));
        (0..n)
            .filter_map(|k| {
                let i = lo + (k * 7 + 1) % span;
                let j = lo + (k * 5 + 2) % span;
                let (x, y) = (
                    (i as f64 + 0.5) * p.spacing_m,
                    (j as f64 + 0.5) * p.spacing_m,
                );
                let h = 0.5 * size_m;
                ViewCell::new(DVec3::new(x - h, y - h, 1.5), DVec3::new(x + h, y + h, 2.0)).ok()
            })
            .collect()
    }

    /// A dense forest for the occlusion sweep of the extended-projection paper (§7.2):
    /// crowns that reach the ground (their centre low, cut by it), 2.8–3.4 m wide, up
    /// to ~10 m tall, 4 m apart so that neighbours overlap, each with 1,500 leaves of
    /// 0.5–0.9 m. No leaf alone hides anything (a leaf is a tenth of a crown), but from
    /// eye height inside the forest a few metres of foliage stop every sight line: the
    /// ground truth sees only the nearest trees (~98 % hidden on 256 trees from cells
    /// of 0.25–2 m). The default forest, with crowns above eye height 7 m apart, hides
    /// nothing from inside it.
    pub fn dense(trees: usize) -> Self {
        ForestParams {
            trees,
            leaves_per_tree: 1500,
            spacing_m: 4.0,
            trunk_height_m: (0.3, 0.6),
            crown_radius_m: (2.8, 3.4),
            crown_aspect: (1.6, 2.0),
            crown_lift: 0.3,
            leaf_size_m: (0.5, 0.9),
        }
    }
}

/// A forest of `n_trees` trees with the default 200 leaves each.
pub fn forest(seed: u64, n_trees: usize) -> Scene {
    forest_with(
        seed,
        &ForestParams {
            trees: n_trees,
            ..ForestParams::default()
        },
    )
}

/// A forest with explicit parameters.
pub fn forest_with(seed: u64, p: &ForestParams) -> Scene {
    let g = ((p.trees as f64).sqrt().ceil() as usize).max(1);
    let objects: Vec<Object> = (0..p.trees)
        .into_par_iter()
        .map(|k| {
            let mut r = Rng::derive(seed, k as u64);
            let jitter = DVec2::new(r.range(-0.3, 0.3), r.range(-0.3, 0.3));
            let pos = (DVec2::new((k % g) as f64, (k / g) as f64) + jitter) * p.spacing_m;
            tree(&mut r, pos, p, format!("tree-{k}"))
        })
        .collect();
    Scene::from_objects(objects)
}

fn tree(r: &mut Rng, pos: DVec2, p: &ForestParams, name: String) -> Object {
    let leaves = p.leaves_per_tree;
    let trunk_h = r.range(p.trunk_height_m.0, p.trunk_height_m.1);
    let trunk_r = r.range(0.15, 0.3);
    let crown_r = r.range(p.crown_radius_m.0, p.crown_radius_m.1);
    let crown_rz = crown_r * r.range(p.crown_aspect.0, p.crown_aspect.1);
    let crown_c = pos.extend(trunk_h + p.crown_lift * crown_rz);

    let mut mesh = Mesh {
        vertices: Vec::with_capacity(8 + 4 * leaves),
        triangles: Vec::with_capacity(12 + 2 * leaves),
    };
    // Trunk: a closed box, counter-clockwise faces seen from outside.
    let (lo, hi) = (pos - DVec2::splat(trunk_r), pos + DVec2::splat(trunk_r));
    let foot = [lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
    for z in [0.0, trunk_h] {
        mesh.vertices.extend(foot.iter().map(|v| v.extend(z)));
    }
    for k in 0..4u32 {
        let (a, b) = (k, (k + 1) % 4);
        mesh.triangles.push([a, b, b + 4]);
        mesh.triangles.push([a, b + 4, a + 4]);
    }
    mesh.triangles
        .extend([[4, 5, 6], [4, 6, 7], [0, 2, 1], [0, 3, 2]]);

    // Leaves: small quads, centres uniform in the crown ellipsoid, random orientation.
    for _ in 0..leaves {
        let c = loop {
            let q = DVec3::new(r.range(-1.0, 1.0), r.range(-1.0, 1.0), r.range(-1.0, 1.0));
            let c = crown_c + q * DVec3::new(crown_r, crown_r, crown_rz);
            if q.length_squared() <= 1.0 && c.z > 0.0 {
                break c;
            }
        };
        let n = loop {
            let q = DVec3::new(r.normal(), r.normal(), r.normal());
            if q.length_squared() > 1e-6 {
                break q.normalize();
            }
        };
        let t1 = n.any_orthonormal_vector();
        let t2 = n.cross(t1);
        let half = 0.5 * r.range(p.leaf_size_m.0, p.leaf_size_m.1);
        let base = mesh.vertices.len() as u32;
        mesh.vertices.extend([
            c - (t1 + t2) * half,
            c + (t1 - t2) * half,
            c + (t1 + t2) * half,
            c - (t1 - t2) * half,
        ]);
        mesh.triangles.push([base, base + 1, base + 2]);
        mesh.triangles.push([base, base + 2, base + 3]);
    }

    for v in &mut mesh.vertices {
        // Leaves never reach below the ground (only possible with low crowns).
        *v = DVec3::new(snap_mm(v.x), snap_mm(v.y), snap_mm(v.z).max(0.0));
    }
    let foot = foot.map(|v| DVec2::new(snap_mm(v.x), snap_mm(v.y)));
    let trunk_h = snap_mm(trunk_h);
    let trunk = Prism::new(Polygon::new(foot.to_vec(), vec![]), 0.0, trunk_h);
    let mut outer = vec![trunk.clone()];
    if leaves > 0 {
        let crown = &mesh.vertices[8..];
        let bb = Aabb2::from_points(&crown.iter().map(|v| v.truncate()).collect::<Vec<_>>());
        let zmin = crown.iter().map(|v| v.z).fold(f64::INFINITY, f64::min);
        let zmax = crown.iter().map(|v| v.z).fold(f64::NEG_INFINITY, f64::max);
        outer.push(Prism::new(Polygon::rect(bb.min, bb.max), zmin, zmax));
    }
    Object::mesh(Some(name), mesh, vec![trunk], outer)
}
