//! `sightline build`, `sightline merge` and `sightline query`: the PVS store.

use crate::cli::{Command, SceneArg};
use crate::common::{load_scene, method_options, open_world, print_json, print_warnings, progress};
use anyhow::Context;
use serde::Serialize;
use sightline_geom::{DVec3, ViewCell};
use sightline_methods::{create, Method, MethodOptions};
use sightline_pvs::build::{journal_path, write_atomic};
use sightline_pvs::{build, merge, BuildOptions, PvsFile, Shard};
use sightline_world::{SceneKind, Standing, World};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    match cmd {
        Command::Build {
            scene,
            cells,
            method,
            resolution,
            sweep,
            planes,
            set,
            out,
            resume,
            shard,
            smallest_hole,
            eye_height,
            spawn,
            view_volumes,
            view_volume_names,
        } => {
            let standing = Standing {
                eye_height,
                spawns: spawn,
                view_volumes,
                view_volume_names,
            };
            let kind = sightline_world::kind_of(&scene.scene);
            // No --method: the kind's default (a mesh level's walkable viewcells).
            let m = sightline_world::resolve(kind, &scene.scene, method.as_deref())?;
            let opts = if m == Method::Volumetric {
                MethodOptions::default()
            } else {
                anyhow::ensure!(
                    !standing.is_set(),
                    "--eye-height, --spawn and --view-volumes set the viewcells of a mesh level (.obj, .gltf, .glb) with --method volumetric"
                );
                method_options(m.name(), resolution, sweep, planes, &set)?
            };
            if sightline_world::on_level_cells(m) {
                anyhow::ensure!(
                    cells.is_none() && shard.is_none() && !resume,
                    "{}",
                    match (kind, m) {
                        (SceneKind::Bsp, _) => "a .bsp level is built whole, every open leaf a cell: no --cells, --shard or --resume",
                        (_, Method::Volumetric) => "a mesh level is built whole on its walkable viewcells: no --cells, --shard or --resume",
                        _ => "a mesh level is built whole on its automatic cells: no --cells, --shard or --resume",
                    }
                );
                let world = open_world(&scene, smallest_hole, standing)?;
                return build_level(&world, m, &out, quiet);
            }
            let Some(cells) = cells else {
                anyhow::bail!(
                    "--cells is required (a cells.json of viewcells; `sightline cells` writes one)"
                );
            };
            run_build(
                &scene,
                &cells,
                m.name(),
                opts,
                &out,
                resume,
                shard.as_deref(),
                quiet,
            )
        }
        Command::Merge { inputs, out } => run_merge(&inputs, &out),
        Command::Query {
            pvs,
            at,
            can_see,
            seen_by,
            secondary,
            json,
        } => match at {
            Some(at) => run_query(&pvs, at, json),
            None => {
                let ask = crate::commands::gameplay::Questions {
                    can_see,
                    seen_by,
                    secondary,
                };
                crate::commands::gameplay::run(&pvs, &ask, json)
            }
        },
        _ => unreachable!("dispatched by commands::run"),
    }
}

/// `build LEVEL -o L.pvs` with a method on the level's own cells: every open leaf of a
/// BSP level, every automatic cell of a mesh level, or its walkable viewcells then its
/// automatic cells (`volumetric`).
fn build_level(world: &World, m: Method, out: &Path, quiet: bool) -> anyhow::Result<()> {
    let t = Instant::now();
    let spinner = progress(1, quiet, "cells, portals, PVS of every cell");
    let enc = world.encode(m)?;
    spinner.finish_and_clear();
    write_atomic(out, &enc.bytes).with_context(|| format!("cannot write {}", out.display()))?;
    if quiet {
        return Ok(());
    }
    let seconds = t.elapsed().as_secs_f64();
    let bytes = enc.bytes.len();
    match &enc.mesh {
        Some(f) => {
            print_warnings(&f.warnings, quiet);
            let cells = if m == Method::Volumetric {
                format!(
                    "{} walkable viewcells and {} free-space cells",
                    f.viewcells, f.auto_cells
                )
            } else {
                format!("{} automatic cells, {} portals", f.auto_cells, f.portals)
            };
            eprintln!(
                "wrote {}: {cells}, {} clusters of {} source objects, smallest hole {:.3}, method {}, {bytes} bytes, {seconds:.1} s",
                out.display(),
                f.clusters,
                f.sources,
                f.smallest_hole,
                m.name(),
            );
        }
        None => eprintln!(
            "wrote {}: {} leaves, method {}, {bytes} bytes ({:.0} B/leaf), {seconds:.1} s",
            out.display(),
            enc.cells,
            m.name(),
            bytes as f64 / enc.cells as f64,
        ),
    }
    Ok(())
}

/// Read a cells.json: a JSON array of `[x0,y0,z0,x1,y1,z1]` boxes.
pub fn read_cells(path: &Path) -> anyhow::Result<Vec<ViewCell>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let cells: Vec<ViewCell> = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: expected a JSON array of [x0,y0,z0,x1,y1,z1] cells",
            path.display()
        )
    })?;
    anyhow::ensure!(!cells.is_empty(), "{}: no cells", path.display());
    Ok(cells)
}

#[allow(clippy::too_many_arguments)]
fn run_build(
    scene_arg: &SceneArg,
    cells_path: &Path,
    method: &str,
    method_opts: MethodOptions,
    out: &Path,
    resume: bool,
    shard: Option<&str>,
    quiet: bool,
) -> anyhow::Result<()> {
    let shard = shard
        .map(|s| Shard::parse(s, |k| std::env::var(k).ok()))
        .transpose()?;
    let cells = read_cells(cells_path)?;
    let scene = Arc::new(load_scene(scene_arg)?);
    let m = create(method, scene.clone(), &method_opts)?;
    let opts = BuildOptions {
        resume,
        shard,
        ..BuildOptions::default()
    };
    let pb = progress(cells.len() as u64, quiet, "build");
    let report = |done: usize, total: usize| {
        pb.set_length(total as u64);
        pb.set_position(done as u64);
    };
    let t = Instant::now();
    let stats = build(&scene, m.as_ref(), &cells, out, &opts, &report).with_context(|| {
        format!(
            "building {} (finished cells are kept in {}; rerun with --resume)",
            out.display(),
            journal_path(out).display()
        )
    })?;
    pb.finish_and_clear();
    let shard_note = shard.map_or(String::new(), |s| {
        format!(" (shard {}/{})", s.index, s.count)
    });
    if !quiet {
        eprintln!(
            "wrote {}{shard_note}: {} cells ({} resumed), method {}, {} bytes ({:.0} B/cell), {:.1} s ({:.1} cells/s)",
            out.display(),
            stats.cells,
            stats.resumed,
            m.name(),
            stats.bytes,
            stats.bytes as f64 / stats.cells as f64,
            t.elapsed().as_secs_f64(),
            stats.computed as f64 / stats.compute_seconds.max(1e-9),
        );
    }
    Ok(())
}

fn run_merge(inputs: &[PathBuf], out: &Path) -> anyhow::Result<()> {
    let files = inputs
        .iter()
        .map(|p| {
            PvsFile::open(p)
                .with_context(|| format!("cannot open {}", p.display()))
                .map(|f| (p.display().to_string(), f))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let bytes = merge(&files)?;
    write_atomic(out, &bytes).with_context(|| format!("cannot write {}", out.display()))?;
    eprintln!(
        "merged {} files into {}: {} cells, {} bytes",
        files.len(),
        out.display(),
        files[0].1.cells().len(),
        bytes.len()
    );
    Ok(())
}

#[derive(Serialize)]
struct QueryReport {
    cell: ViewCell,
    /// The cell's number in its source when it is not a box (a BSP leaf).
    #[serde(skip_serializing_if = "Option::is_none")]
    leaf: Option<u32>,
    index: usize,
    method: String,
    visible: Vec<u32>,
    /// The leaves the cell sees, when the file stores them (a BSP level's build).
    #[serde(skip_serializing_if = "Option::is_none")]
    visible_leaves: Option<Vec<u32>>,
    /// Mesh levels: the source objects of the visible clusters (`info`'s order).
    #[serde(skip_serializing_if = "Option::is_none")]
    visible_sources: Option<Vec<u32>>,
    /// Files with walkable viewcells (`volumetric`): `true` when the point lies in no
    /// viewcell and the answer is a free-space cell's (a flying camera: conservative,
    /// looser), `false` in a walkable viewcell.
    #[serde(skip_serializing_if = "Option::is_none")]
    free_space: Option<bool>,
}

fn run_query(path: &Path, at: [f64; 3], json: bool) -> anyhow::Result<()> {
    let file = PvsFile::open(path).with_context(|| format!("cannot open {}", path.display()))?;
    let p = DVec3::from_array(at);
    let index = file.locate(p).with_context(|| {
        format!(
            "no cell of {} contains the point {},{},{}",
            path.display(),
            at[0],
            at[1],
            at[2]
        )
    })?;
    let visible = file
        .pvs(index)
        .with_context(|| format!("cannot read cell {index} of {}", path.display()))?;
    let report = QueryReport {
        cell: file.cells()[index],
        leaf: file.cell(index).and_then(|c| c.id()),
        index,
        method: file.header().method.clone(),
        visible_sources: sightline_world::sources_from_params(&file.header().params, &visible),
        visible,
        visible_leaves: file.visible_leaves(index).map(<[u32]>::to_vec),
        free_space: sightline_world::free_space(&file.header().params, index),
    };
    if json {
        print_json(&report)
    } else {
        let c = report.cell.to_array();
        if let Some(l) = report.leaf {
            print!("leaf {l}, ");
        }
        let leaves = report
            .visible_leaves
            .as_ref()
            .map_or(String::new(), |l| format!(", {} leaves", l.len()));
        let leaves = match report.free_space {
            Some(true) => format!("{leaves}, free space (not a walkable viewcell: looser)"),
            Some(false) => format!("{leaves}, walkable viewcell"),
            None => leaves,
        };
        println!(
            "cell {index} [{}, {}, {}, {}, {}, {}] ({}): {} of {} objects visible{leaves}",
            c[0],
            c[1],
            c[2],
            c[3],
            c[4],
            c[5],
            report.method,
            report.visible.len(),
            file.header().object_count
        );
        let ids: Vec<String> = report.visible.iter().map(|i| i.to_string()).collect();
        println!("{}", ids.join(" "));
        if let Some(s) = &report.visible_sources {
            let ids: Vec<String> = s.iter().map(|i| i.to_string()).collect();
            println!("source objects ({}): {}", s.len(), ids.join(" "));
        }
        Ok(())
    }
}
