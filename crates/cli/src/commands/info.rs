//! `sightline info SCENE [--json]`: counts, bounds and warnings.

use crate::cli::Command;
use crate::common::{load_scene, print_json};
use serde::Serialize;
use sightline_scene::{Geometry, ObjectKind, Scene, Warning};
use std::collections::BTreeMap;

/// The `info` JSON (extra fields allowed).
#[derive(Serialize)]
struct Info<'a> {
    scene: String,
    objects: usize,
    blocks: usize,
    flat: usize,
    meshes: usize,
    /// Triangles of the exact geometry (what the ground truth renders).
    triangles: usize,
    /// `[x0, y0, z0, x1, y1, z1]`.
    bounds: [f64; 6],
    fingerprint: String,
    /// Counted warnings by kind.
    warning_counts: BTreeMap<String, usize>,
    /// Every warning, in input order.
    warnings: &'a [Warning],
}

/// Triangle count without triangulating: a polygon with `n` vertices and `h` holes
/// triangulates into `n + 2h − 2` triangles; a prism adds two per wall edge.
fn triangle_count(scene: &Scene) -> usize {
    let caps =
        |p: &sightline_geom::Polygon| (p.vertex_count() + 2 * p.holes.len()).saturating_sub(2);
    scene
        .objects
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

pub fn run(cmd: Command, _quiet: bool) -> anyhow::Result<()> {
    let Command::Info { scene: arg, json } = cmd else {
        anyhow::bail!("internal: info called with another command");
    };
    let scene = load_scene(&arg)?;
    let count = |k: ObjectKind| scene.objects.iter().filter(|o| o.kind() == k).count();
    let b = scene.bounds;
    let info = Info {
        scene: arg.scene.display().to_string(),
        objects: scene.len(),
        blocks: count(ObjectKind::Blocks),
        flat: count(ObjectKind::Flat),
        meshes: count(ObjectKind::Mesh),
        triangles: triangle_count(&scene),
        bounds: [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z],
        fingerprint: format!("{:016x}", scene.fingerprint()),
        warning_counts: scene.warning_counts().into_iter().collect(),
        warnings: &scene.warnings,
    };
    if json {
        return print_json(&info);
    }
    println!("scene:     {}", info.scene);
    println!(
        "objects:   {} ({} blocks, {} flat, {} meshes)",
        info.objects, info.blocks, info.flat, info.meshes
    );
    println!("triangles: {}", info.triangles);
    let s = b.size();
    println!(
        "bounds:    x {:.2}..{:.2}, y {:.2}..{:.2}, z {:.2}..{:.2} ({:.1} x {:.1} x {:.1} m)",
        b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z, s.x, s.y, s.z
    );
    println!("fingerprint: {}", info.fingerprint);
    println!("warnings:  {}", scene.warnings.len());
    for (kind, n) in &info.warning_counts {
        println!("  {kind}: {n}");
    }
    const SHOWN: usize = 20;
    for w in scene.warnings.iter().take(SHOWN) {
        match w.feature {
            Some(i) => println!("  - feature {i}: {} ({})", w.message, w.kind),
            None => println!("  - {} ({})", w.message, w.kind),
        }
    }
    if scene.warnings.len() > SHOWN {
        println!(
            "  ... {} more (--json lists all)",
            scene.warnings.len() - SHOWN
        );
    }
    Ok(())
}
