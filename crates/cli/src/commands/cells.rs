//! `sightline cells`: cover a scene with square viewcells whose free space is non-empty
//! and write them as a JSON array of `[x0,y0,z0,x1,y1,z1]` boxes.

use crate::cli::Command;
use crate::common::{load_scene, open_world, print_warnings, write_atomic};
use anyhow::{bail, Context};
use sightline_geom::{DVec2, Polygon, ViewCell};
use sightline_scene::cells;
use sightline_world::{SceneKind, Standing};
use std::path::Path;
use std::time::Instant;

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Cells {
        scene,
        size,
        smallest_hole,
        z,
        clip,
        out,
    } = cmd
    else {
        unreachable!("cells::run called with another command")
    };
    // No --size on a mesh level: its automatic cells.
    if size.is_none() && sightline_world::kind_of(&scene.scene) == SceneKind::Mesh {
        return automatic_cells(&scene, smallest_hole, &out, quiet);
    }
    let size = size.unwrap_or(50.0);
    // Check the cheap arguments before loading anything.
    if !(size.is_finite() && size > 0.0) {
        bail!("--size must be a positive number of metres, got {size}");
    }
    let (z0, z1) = parse_z_range(&z)?;
    let clip = clip.as_deref().map(read_clip).transpose()?;
    let t0 = Instant::now();
    let scene_data = load_scene(&scene)?;
    let t1 = Instant::now();
    let grid = cells::grid_cells_clipped(&scene_data, size, z0, z1, clip.as_deref())
        .with_context(|| format!("cannot make cells for {}", scene.scene.display()))?;
    let (nx, ny) = cells::grid_shape(&scene_data, size);
    write_atomic(&out, &cells_json(&grid)?)?;
    if !quiet {
        eprintln!(
            "loaded in {:.2} s, cells in {:.2} s",
            (t1 - t0).as_secs_f64(),
            t1.elapsed().as_secs_f64()
        );
    }
    println!(
        "{} cells of {size} m at z {z0}..{z1} (grid {nx} × {ny} = {}; {} dropped{}) → {}",
        grid.len(),
        nx * ny,
        nx * ny - grid.len() as u64,
        if clip.is_some() {
            ": inside buildings or outside the clip polygon"
        } else {
            ": inside buildings"
        },
        out.display()
    );
    Ok(())
}

/// `cells LEVEL.obj -o cells.json`: the automatic cells of a mesh level as boxes.
fn automatic_cells(
    scene: &crate::cli::SceneArg,
    smallest_hole: Option<f64>,
    out: &Path,
    quiet: bool,
) -> anyhow::Result<()> {
    let world = open_world(scene, smallest_hole, Standing::default())?;
    let spinner = crate::common::progress(1, quiet, "voxels, cells, portals, PVS of every cell");
    let cut = world.cut(false)?;
    spinner.finish_and_clear();
    print_warnings(&cut.warnings, quiet);
    let boxes = cut.auto.cell_boxes();
    write_atomic(out, &serde_json::to_vec(&boxes)?)?;
    let r = &cut.auto.report;
    println!(
        "{} automatic cells ({} portals; voxels {:?} of {:.3}: {} surface, {} air, {} solid) → {}",
        r.cells,
        r.portals,
        r.grid,
        r.smallest_hole,
        r.voxels.surface,
        r.voxels.air,
        r.voxels.solid,
        out.display()
    );
    Ok(())
}

/// `Z0:Z1` with `0 <= Z0 <= Z1`, both finite.
pub fn parse_z_range(s: &str) -> anyhow::Result<(f64, f64)> {
    let parts: Vec<&str> = s.split(':').collect();
    let [a, b] = parts.as_slice() else {
        bail!("--z must be Z0:Z1 (e.g. 1.5:2.0), got '{s}'");
    };
    let num = |p: &str| -> anyhow::Result<f64> {
        p.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .with_context(|| format!("--z: '{p}' is not a finite number"))
    };
    let (z0, z1) = (num(a)?, num(b)?);
    if z0 < 0.0 || z0 > z1 {
        bail!("--z must satisfy 0 <= Z0 <= Z1, got {z0}:{z1}");
    }
    Ok((z0, z1))
}

/// The cells as a JSON array, one box per line.
pub fn cells_json(cells: &[ViewCell]) -> anyhow::Result<Vec<u8>> {
    let mut out = b"[".to_vec();
    for (k, c) in cells.iter().enumerate() {
        out.extend_from_slice(if k == 0 { b"\n" } else { b",\n" });
        out.extend(serde_json::to_vec(c)?);
    }
    out.extend_from_slice(b"\n]\n");
    Ok(out)
}

/// Polygons of a GeoJSON file (FeatureCollection, Feature or bare geometry; Polygon
/// or MultiPolygon), in the scene's own projected metres.
pub fn read_clip(path: &Path) -> anyhow::Result<Vec<Polygon>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read clip polygon {}", path.display()))?;
    let v: serde_json::Value = serde_json::from_str(&text)
        .with_context(|| format!("{}: not valid JSON", path.display()))?;
    let mut polys = Vec::new();
    collect_polygons(&v, &mut polys).with_context(|| format!("{}", path.display()))?;
    if polys.is_empty() {
        bail!(
            "{}: no Polygon or MultiPolygon in the clip file",
            path.display()
        );
    }
    Ok(polys)
}

fn collect_polygons(v: &serde_json::Value, out: &mut Vec<Polygon>) -> anyhow::Result<()> {
    match v["type"].as_str() {
        Some("FeatureCollection") => {
            for (k, f) in v["features"].as_array().into_iter().flatten().enumerate() {
                collect_polygons(f, out).with_context(|| format!("feature {k}"))?;
            }
        }
        Some("Feature") => collect_polygons(&v["geometry"], out)?,
        Some("Polygon") => out.push(polygon(&v["coordinates"])?),
        Some("MultiPolygon") => {
            for p in v["coordinates"].as_array().into_iter().flatten() {
                out.push(polygon(p)?);
            }
        }
        Some(_) | None => {}
    }
    Ok(())
}

fn polygon(v: &serde_json::Value) -> anyhow::Result<Polygon> {
    let mut rings = Vec::new();
    for r in v.as_array().into_iter().flatten() {
        let mut ring = Vec::new();
        for p in r.as_array().into_iter().flatten() {
            let x = p[0].as_f64().filter(|x| x.is_finite());
            let y = p[1].as_f64().filter(|y| y.is_finite());
            let (Some(x), Some(y)) = (x, y) else {
                bail!("bad coordinate {p}");
            };
            ring.push(DVec2::new(x, y));
        }
        if ring.len() > 1 && ring.first() == ring.last() {
            ring.pop();
        }
        if ring.len() < 3 {
            bail!("a ring needs at least 3 distinct points");
        }
        rings.push(ring);
    }
    let mut rings = rings.into_iter();
    let Some(exterior) = rings.next() else {
        bail!("polygon without rings");
    };
    Ok(Polygon::new(exterior, rings.collect()).normalized())
}
