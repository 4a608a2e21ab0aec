//! `sightline build`, `sightline merge` and `sightline query`: the PVS store.

use crate::cli::{Command, SceneArg};
use crate::common::{load_scene, method_options, print_json, progress};
use anyhow::Context;
use serde::Serialize;
use sightline_geom::{DVec3, ViewCell};
use sightline_methods::{create, Method, MethodOptions};
use sightline_pvs::build::{journal_path, write_atomic};
use sightline_pvs::{build, merge, BuildOptions, PvsFile, Shard};
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
        } => {
            let standing = crate::commands::mesh::Standing {
                eye_height,
                spawns: spawn,
                view_volumes,
            };
            let mesh = crate::commands::mesh::is_mesh(&scene.scene);
            let method = method.unwrap_or_else(|| {
                if mesh {
                    Method::Volumetric.name().to_string()
                } else {
                    Method::Erosion.name().to_string()
                }
            });
            if mesh && method == Method::Volumetric.name() {
                anyhow::ensure!(
                    cells.is_none() && shard.is_none() && !resume,
                    "a mesh level is built whole on its walkable viewcells: no --cells, --shard or --resume"
                );
                return crate::commands::mesh::build_volumetric(
                    &scene,
                    smallest_hole,
                    &standing,
                    &out,
                    quiet,
                );
            }
            anyhow::ensure!(
                !standing.is_set(),
                "--eye-height, --spawn and --view-volumes set the viewcells of a mesh level (.obj, .gltf, .glb) with --method volumetric"
            );
            let opts = method_options(&method, resolution, sweep, planes, &set)?;
            if let Some(full) = crate::commands::mesh::portal_mode(&scene.scene, &method) {
                anyhow::ensure!(
                    cells.is_none() && shard.is_none() && !resume,
                    "a mesh level is built whole on its automatic cells: no --cells, --shard or --resume"
                );
                return crate::commands::mesh::build(&scene, full, smallest_hole, &out, quiet);
            }
            if let Some(mode) = crate::commands::bsp::portal_mode(&scene.scene, &method)? {
                anyhow::ensure!(
                    cells.is_none() && shard.is_none() && !resume,
                    "a .bsp level is built whole, every open leaf a cell: no --cells, --shard or --resume"
                );
                return crate::commands::bsp::build(&scene.scene, mode, &out, quiet);
            }
            let Some(cells) = cells else {
                anyhow::bail!(
                    "--cells is required (a cells.json of viewcells; `sightline cells` writes one)"
                );
            };
            run_build(
                &scene,
                &cells,
                &method,
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
        visible_sources: crate::commands::mesh::sources_from_params(
            &file.header().params,
            &visible,
        ),
        visible,
        visible_leaves: file.visible_leaves(index).map(<[u32]>::to_vec),
        free_space: crate::commands::mesh::free_space(&file.header().params, index),
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
