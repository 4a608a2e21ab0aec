//! `clusters LEVEL.obj [--json] [-o L.json | -o L.glb]`: a mesh level's clusters, the
//! ids its `.pvs` lists, in a form a client can draw (issue #48 item 4).
//!
//! * JSON: per cluster its id, source object (index in `info`'s order, and name), box
//!   (the scene's z-up frame, as `query --at` and the `.pvs` cells) and the indices of
//!   its triangles in the **file's face order after triangulation**: the triangles of
//!   the importer, object after object (OBJ: faces in file order, each polygon fanned
//!   from its first vertex, as tobj does; glTF: nodes depth-first, primitives in order).
//!   Index `i` is the `i`-th triangle of the whole file.
//! * GLB: one node (and mesh) per cluster, **named by its id** (`"17"`), in id order,
//!   each with that cluster's triangles in ascending file order (the JSON's order), in
//!   the file's own y-up frame; node `extras` hold `cluster`, `source`, `source_name`,
//!   the asset's `extras.sightline` the level's fingerprint (a `.pvs` header's).
//!
//! Cluster ids come from [`sightline_world::World::clusters`], as for `build`, `check` and `serve`:
//! with the same `--smallest-hole` (or `--pvs L.pvs`, which reads it from the file and
//! checks the fingerprint), the ids are the `.pvs`'s.

use crate::cli::{Command, SceneArg};
use crate::common::{open_world, print_json};
use anyhow::Context;
use serde::Serialize;
use sightline_geom::{DVec3, ViewCell};
use sightline_scene::clusters::Clustered;
use sightline_scene::export::glb::{scene_glb, GlbNode};
use sightline_scene::{Mesh, Object, Scene};
use sightline_world::{SceneKind, Standing, World};
use std::path::Path;

/// One source object of the level.
#[derive(Serialize)]
struct Source {
    id: u32,
    name: Option<String>,
    /// Its triangles are the file's triangles `first_triangle .. first_triangle + triangles`.
    first_triangle: u32,
    triangles: u32,
}

/// One cluster: a PVS id.
#[derive(Serialize)]
struct ClusterEntry {
    id: u32,
    source: u32,
    source_name: Option<String>,
    bounds: ViewCell,
    /// Indices in the file's triangle order, ascending.
    triangles: Vec<u32>,
}

#[derive(Serialize)]
struct Listing {
    level: String,
    /// `Scene::fingerprint` of the clustered level: the `.pvs` header's.
    fingerprint: String,
    smallest_hole: f64,
    cluster_size: f64,
    max_cluster_triangles: usize,
    /// Triangles of the whole file (after triangulation).
    triangles: usize,
    sources: Vec<Source>,
    clusters: Vec<ClusterEntry>,
}

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Clusters {
        scene,
        smallest_hole,
        pvs,
        json,
        out,
    } = cmd
    else {
        unreachable!("dispatched by commands::run")
    };
    let format = match &out {
        None => None,
        Some(p) => Some(output_format(p)?),
    };
    let (world, clustered, hole) = clustered_level(&scene, smallest_hole, pvs.as_deref())?;
    let raw: &Scene = world.scene();
    let listing = listing(&scene, raw, &clustered, hole)?;
    if let (Some(path), Some(format)) = (&out, format) {
        let bytes = match format {
            Format::Json => serde_json::to_vec_pretty(&listing)?,
            Format::Glb => glb(raw, &clustered, &listing)?,
        };
        crate::common::write_atomic(path, &bytes)
            .with_context(|| format!("cannot write {}", path.display()))?;
        if !quiet {
            eprintln!(
                "wrote {}: {} clusters of {} source objects, {} triangles, smallest hole {:.3}, {} bytes",
                path.display(),
                listing.clusters.len(),
                listing.sources.len(),
                listing.triangles,
                listing.smallest_hole,
                bytes.len()
            );
        }
    }
    if json {
        print_json(&listing)?;
    } else if out.is_none() {
        println!(
            "{}: {} clusters of {} source objects, {} triangles (cluster grid {:.3}, smallest hole {:.3}, fingerprint {}); --json or -o L.json lists them, -o L.glb writes them as glTF nodes",
            scene.scene.display(),
            listing.clusters.len(),
            listing.sources.len(),
            listing.triangles,
            listing.cluster_size,
            listing.smallest_hole,
            listing.fingerprint
        );
    }
    Ok(())
}

#[derive(Clone, Copy)]
enum Format {
    Json,
    Glb,
}

fn output_format(path: &Path) -> anyhow::Result<Format> {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("json") => Ok(Format::Json),
        Some("glb") => Ok(Format::Glb),
        _ => anyhow::bail!(
            "-o {}: give a .json (the listing) or a .glb (binary glTF, one node per cluster)",
            path.display()
        ),
    }
}

/// The level as the importer reads it, its clusters (the ids of its `.pvs`) and the
/// smallest hole they were cut with.
fn clustered_level(
    scene: &SceneArg,
    smallest_hole: Option<f64>,
    pvs: Option<&Path>,
) -> anyhow::Result<(World, Clustered, f64)> {
    anyhow::ensure!(
        sightline_world::kind_of(&scene.scene) == SceneKind::Mesh,
        "{}: clusters are cut from mesh levels (.obj, .gltf, .glb)",
        scene.scene.display()
    );
    let world = open_world(scene, smallest_hole, Standing::default())?;
    let raw = world.scene();
    if let Some(w) = raw.warnings.iter().find(|w| w.kind == "skipped-feature") {
        anyhow::bail!(
            "{}: the importer skipped an object ({}): triangle indices would not match the file's faces; repair it",
            scene.scene.display(),
            w.message
        );
    }
    let (clustered, hole) = match pvs {
        Some(p) => {
            let file = sightline_pvs::PvsFile::open(p)
                .with_context(|| format!("cannot open {}", p.display()))?;
            let clustered = world.clustered_for(&file)?;
            anyhow::ensure!(
                file.header().fingerprint == clustered.scene.fingerprint(),
                "{} was not built from {} (fingerprints differ): its cluster ids are another level's",
                p.display(),
                scene.scene.display()
            );
            let hole = param(&file, "smallest_hole").unwrap_or(f64::NAN);
            (clustered, hole)
        }
        None => {
            let opts = world.cluster_options(smallest_hole)?;
            let hole = level_hole(raw, &opts)
                .with_context(|| format!("cannot cluster {}", scene.scene.display()))?;
            (world.clusters(&opts), hole)
        }
    };
    Ok((world, clustered, hole))
}

fn param(file: &sightline_pvs::PvsFile, key: &str) -> Option<f64> {
    let (_, v) = file.header().params.iter().find(|(k, _)| k == key)?;
    v.parse().ok()
}

/// The smallest hole `build` voxelizes the level at with `opts` (the budget may raise
/// it); the errors `build` gives for a hole it cannot use.
fn level_hole(
    raw: &Scene,
    opts: &sightline_autocells::Options,
) -> Result<f64, sightline_autocells::AutoError> {
    use sightline_autocells::AutoError;
    let b = raw.bounds;
    if !(b.min.is_finite() && b.max.is_finite()) {
        return Err(AutoError::NotFinite);
    }
    let asked = opts.smallest_hole.unwrap_or(0.5);
    let extent = (b.max - b.min).max_element();
    if asked > extent {
        return Err(AutoError::HoleTooLarge {
            hole: asked,
            extent,
        });
    }
    Ok(sightline_autocells::lattice_grid(b.min, b.max, asked, opts.max_voxels).size)
}

fn listing(
    scene: &SceneArg,
    raw: &Scene,
    clustered: &Clustered,
    hole: f64,
) -> anyhow::Result<Listing> {
    let mut first = Vec::with_capacity(raw.objects.len());
    let mut total = 0u32;
    for o in &raw.objects {
        first.push(total);
        total += o.triangle_count() as u32;
    }
    let sources = raw
        .objects
        .iter()
        .enumerate()
        .map(|(i, o)| Source {
            id: i as u32,
            name: o.name.clone(),
            first_triangle: first[i],
            triangles: o.triangle_count() as u32,
        })
        .collect();
    let clusters = clustered
        .scene
        .objects
        .iter()
        .enumerate()
        .map(|(c, o)| {
            let src = clustered.source[c];
            let mut triangles: Vec<u32> = clustered.triangles[c]
                .iter()
                .map(|&t| first[src as usize] + t)
                .collect();
            triangles.sort_unstable();
            ClusterEntry {
                id: c as u32,
                source: src,
                source_name: o.name.clone(),
                bounds: bounds(&o.triangles()),
                triangles,
            }
        })
        .collect();
    let opts = sightline_world::cluster_options(Some(hole).filter(|h| h.is_finite()))?;
    Ok(Listing {
        level: scene.scene.display().to_string(),
        fingerprint: format!("{:016x}", clustered.scene.fingerprint()),
        smallest_hole: hole,
        cluster_size: sightline_autocells::default_cluster_size(raw, &opts),
        max_cluster_triangles: sightline_autocells::MAX_CLUSTER_TRIANGLES,
        triangles: total as usize,
        sources,
        clusters,
    })
}

fn bounds(tris: &[[DVec3; 3]]) -> ViewCell {
    let (mut min, mut max) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
    for p in tris.iter().flatten() {
        min = min.min(*p);
        max = max.max(*p);
    }
    if tris.is_empty() {
        (min, max) = (DVec3::ZERO, DVec3::ZERO);
    }
    // + 0.0 writes −0 as 0.
    ViewCell {
        min: min + DVec3::ZERO,
        max: max + DVec3::ZERO,
    }
}

/// The level as a GLB, one node per cluster named by its id, each with its triangles
/// in the listing's (ascending file) order.
fn glb(raw: &Scene, clustered: &Clustered, listing: &Listing) -> anyhow::Result<Vec<u8>> {
    let file_tris: Vec<[DVec3; 3]> = raw.objects.iter().flat_map(Object::triangles).collect();
    let objects = listing
        .clusters
        .iter()
        .map(|c| {
            let mut mesh = Mesh::default();
            for &t in &c.triangles {
                let base = mesh.vertices.len() as u32;
                mesh.vertices.extend(file_tris[t as usize]);
                mesh.triangles.push([base, base + 1, base + 2]);
            }
            Object::mesh(c.source_name.clone(), mesh, vec![], vec![])
        })
        .collect();
    let level = Scene::from_objects(objects);
    let node = |i: usize| {
        let c = &listing.clusters[i];
        GlbNode {
            name: c.id.to_string(),
            extras: Some(serde_json::json!({
                "cluster": c.id,
                "source": c.source,
                "source_name": c.source_name,
            })),
        }
    };
    let asset = serde_json::json!({ "sightline": {
        "level": listing.level,
        "fingerprint": listing.fingerprint,
        "smallest_hole": listing.smallest_hole,
        "clusters": clustered.scene.objects.len(),
        "node_names": "cluster id (the ids a .pvs of this level lists)",
    }});
    Ok(scene_glb(&level, node, Some(asset))?)
}
