//! `sightline generate`: a deterministic synthetic scene written to a file
//! (GeoJSON for blocks, OBJ for anything — the forest's trees are meshes).

use crate::cli::{Command, GenerateKind};
use crate::common::write_atomic;
use anyhow::{bail, Context};
use sightline_scene::generate::{self, ForestParams};
use sightline_scene::{export, ObjectKind, Scene};
use std::path::Path;
use std::time::Instant;

/// Largest sizes accepted (memory stays within a few GB).
const MAX_BUILDINGS: usize = 5_000_000;
const MAX_TREES: usize = 200_000;
const MAX_LEAVES_TOTAL: usize = 20_000_000;

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Generate {
        kind,
        seed,
        size,
        leaves,
        dense,
        out,
    } = cmd
    else {
        unreachable!("generate::run called with another command")
    };
    let format = OutFormat::of(&out)?;
    if kind == GenerateKind::Forest && format == OutFormat::GeoJson {
        bail!(
            "{}: a forest is made of meshes, which GeoJSON cannot hold; write .obj instead",
            out.display()
        );
    }
    if leaves.is_some() && kind != GenerateKind::Forest {
        bail!("--leaves only applies to `generate forest`");
    }
    if dense && kind != GenerateKind::Forest {
        bail!("--dense only applies to `generate forest`");
    }
    let t0 = Instant::now();
    let (name, scene) = match kind {
        GenerateKind::City => {
            let n = check_size(size.unwrap_or(500), MAX_BUILDINGS, "buildings")?;
            ("city", generate::city(seed, n))
        }
        GenerateKind::Metropolis => {
            let n = check_size(size.unwrap_or(150_000), MAX_BUILDINGS, "buildings")?;
            ("metropolis", generate::metropolis(seed, n))
        }
        GenerateKind::Forest => {
            let trees = check_size(size.unwrap_or(500), MAX_TREES, "trees")?;
            let base = if dense {
                ForestParams::dense(trees)
            } else {
                ForestParams::default()
            };
            let leaves_per_tree = leaves.unwrap_or(base.leaves_per_tree);
            if trees.saturating_mul(leaves_per_tree) > MAX_LEAVES_TOTAL {
                bail!(
                    "{trees} trees × {leaves_per_tree} leaves is more than {MAX_LEAVES_TOTAL} leaves"
                );
            }
            let p = ForestParams {
                trees,
                leaves_per_tree,
                ..base
            };
            ("forest", generate::forest_with(seed, &p))
        }
    };
    let generated = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    write_scene(&scene, &out, format)?;
    let written = t1.elapsed().as_secs_f64();
    if !quiet {
        eprintln!(
            "generated {name} (seed {seed}) in {generated:.2} s, wrote {} in {written:.2} s",
            out.display()
        );
    }
    println!("{}", summary(&scene));
    Ok(())
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum OutFormat {
    GeoJson,
    Obj,
}

impl OutFormat {
    pub fn of(path: &Path) -> anyhow::Result<Self> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("geojson" | "json") => Ok(OutFormat::GeoJson),
            Some("obj") => Ok(OutFormat::Obj),
            _ => bail!(
                "{}: unknown output format (use .geojson, .json or .obj)",
                path.display()
            ),
        }
    }
}

fn check_size(n: usize, max: usize, what: &str) -> anyhow::Result<usize> {
    if n == 0 || n > max {
        bail!("--size must be between 1 and {max} {what}, got {n}");
    }
    Ok(n)
}

/// Write `scene` to `path` atomically in `format`.
pub fn write_scene(scene: &Scene, path: &Path, format: OutFormat) -> anyhow::Result<()> {
    let mut bytes = Vec::new();
    match format {
        OutFormat::GeoJson => export::write_geojson(scene, &mut bytes),
        OutFormat::Obj => export::write_obj(scene, &mut bytes),
    }
    .with_context(|| format!("cannot write {}", path.display()))?;
    write_atomic(path, &bytes)
}

/// One line: counts by kind, triangles and bounds.
pub fn summary(scene: &Scene) -> String {
    let count = |k| scene.objects.iter().filter(|o| o.kind() == k).count();
    let tris: usize = scene.objects.iter().map(|o| o.triangle_count()).sum();
    let b = scene.bounds;
    format!(
        "{} objects ({} blocks, {} flat, {} meshes), {} triangles, bounds [{:.1}, {:.1}, {:.1}] – [{:.1}, {:.1}, {:.1}]",
        scene.objects.len(),
        count(ObjectKind::Blocks),
        count(ObjectKind::Flat),
        count(ObjectKind::Mesh),
        tris,
        b.min.x,
        b.min.y,
        b.min.z,
        b.max.x,
        b.max.y,
        b.max.z
    )
}
