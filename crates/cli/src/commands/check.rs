//! `sightline check`: a method's PVS against the ground truth on many cells.

use crate::cli::Command;
use crate::common::{method_options, open_world, print_json, print_warnings, progress};
use anyhow::{bail, Context};
use sightline_core::check::{report_json, street_cells, Clearance};
use sightline_geom::ViewCell;
use sightline_methods::{create, VisibilityMethod};
use sightline_pvs::{PvsFile, StoredPvs};
use sightline_world::{Evidence, SceneKind, Standing};

/// Side of the cells picked when `--cells` is a number (metres).
const AUTO_CELL_M: f64 = 10.0;

/// `--cells`: a cells.json file, or a number of street cells to pick in the scene.
fn read_cells(arg: &str, scene: &sightline_scene::Scene) -> anyhow::Result<Vec<ViewCell>> {
    if let Ok(k) = arg.parse::<usize>() {
        if k == 0 {
            bail!("--cells must name a cells.json or a positive number of cells");
        }
        let cells = street_cells(scene, AUTO_CELL_M, (1.5, 2.0), k, Clearance::Box);
        if cells.is_empty() {
            bail!("no free {AUTO_CELL_M} m street cell found in the scene");
        }
        return Ok(cells);
    }
    let text =
        std::fs::read_to_string(arg).with_context(|| format!("cannot read cells file {arg}"))?;
    let cells: Vec<ViewCell> = serde_json::from_str(&text)
        .with_context(|| format!("{arg}: expected a JSON array of [x0,y0,z0,x1,y1,z1] boxes"))?;
    if cells.is_empty() {
        bail!("{arg}: no cells");
    }
    Ok(cells)
}

/// `--cells K` as a positive count (20 when not given); `what` names it in the error.
fn count_arg(cells: Option<&str>, what: &str) -> anyhow::Result<usize> {
    match cells {
        None => Ok(20),
        Some(c) => c
            .parse()
            .ok()
            .filter(|&k| k > 0)
            .with_context(|| format!("{what}, got '{c}'")),
    }
}

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Check {
        scene,
        pvs,
        method,
        cells,
        resolution,
        sweep,
        planes,
        set,
        reference,
        smallest_hole,
        eye_height,
        spawn,
        view_volumes,
        view_volume_names,
        json,
    } = cmd
    else {
        bail!("internal: `check` called with another command");
    };
    let kind = sightline_world::kind_of(&scene.scene);
    let standing = Standing {
        eye_height,
        spawns: spawn,
        view_volumes,
        view_volume_names,
    };
    // A .pvs file is judged on its cells; else a level is judged on its own cells with
    // the method named, or its default (a mesh level's walkable viewcells).
    let level_method = match (&pvs, method.as_deref()) {
        (Some(_), _) => None,
        (None, None) if kind == SceneKind::Mesh => Some(sightline_world::default_method(kind)),
        (None, None) => None,
        (None, Some(name)) => {
            let m = sightline_world::resolve(kind, &scene.scene, Some(name))?;
            Some(m).filter(|&m| sightline_world::on_level_cells(m))
        }
    };
    if let Some(m) = level_method {
        return check_level(
            &scene,
            m,
            &cells,
            reference.is_some(),
            smallest_hole,
            standing,
            json,
            quiet,
        );
    }
    if standing.is_set() {
        bail!("--eye-height, --spawn and --view-volumes set the walkable viewcells of a mesh level (.obj, .gltf, .glb) with --method volumetric");
    }
    if smallest_hole.is_some() {
        bail!("--smallest-hole sets the automatic cells of a mesh level (.obj, .gltf, .glb) with --method portals or portals-fast");
    }
    if reference.is_some() {
        bail!("--reference vis compares a .bsp level's portal PVS with its own vis: it needs a .bsp and --method portals or portals-fast");
    }
    let world = open_world(&scene, None, Standing::default())?;
    let sc = world.scene().clone();
    let (m, cells): (Box<dyn VisibilityMethod>, Vec<ViewCell>) = if let Some(file) = pvs {
        if sweep || planes.is_some() {
            bail!("--sweep and --planes are options of --method ext-proj, not of a .pvs file");
        }
        if !set.is_empty() {
            bail!("--set sets knobs of a --method, not of a .pvs file");
        }
        // `check SCENE city.pvs --cells K`: K cells sampled evenly from the file.
        let f = PvsFile::open(&file).with_context(|| format!("cannot open {}", file.display()))?;
        f.check_scene(&sc).with_context(|| {
            format!(
                "{} does not belong to {}",
                file.display(),
                scene.scene.display()
            )
        })?;
        let k = count_arg(
            cells.as_deref(),
            "with a .pvs file, --cells is a number of cells to sample",
        )?;
        let stored = StoredPvs(f);
        let picked = stored.sample_cells(k);
        (Box::new(stored), picked)
    } else {
        let Some(method) = method else {
            bail!("check needs --method NAME (or a .pvs file)");
        };
        let cells_arg = cells.unwrap_or_else(|| "20".to_string());
        let cells = read_cells(&cells_arg, &sc)?;
        let opts = method_options(&method, resolution, sweep, planes, &set)?;
        let m = create(&method, sc.clone(), &opts)?;
        (m, cells)
    };
    let pb = progress(cells.len() as u64, quiet, "checking cells");
    let judgement = world.judge_boxes(m.as_ref(), &cells, &|| pb.inc(1))?;
    pb.finish_and_clear();
    let Evidence::Boxes(report) = &judgement.evidence else {
        bail!("internal: boxes judged without their report");
    };
    let json_report = report_json(report, m.as_ref());
    if json {
        print_json(&json_report)?;
    } else {
        println!(
            "{}: {} cells, missed {}, over median {:.3} p90 {:.3} max {:.3}, hidden {:.1} %, {:.2} ms/cell (truth {:.0} ms/cell)",
            report.method,
            report.cells,
            report.missed,
            report.over_median,
            report.over_p90,
            report.over_max,
            100.0 * report.hidden_fraction,
            report.pvs_ms_median,
            report.truth_ms_median
        );
        for x in json_report["missed_ids"].as_array().into_iter().flatten() {
            println!("missed: {x}");
        }
    }
    judgement.verdict()
}

/// `check LEVEL --method M` with a method on the level's own cells: `--cells K` source
/// leaves of a BSP level (against its `vis` and the ray oracle), automatic cells or
/// walkable viewcells of a mesh level (against the truth sampled in their free space).
#[allow(clippy::too_many_arguments)]
fn check_level(
    scene: &crate::cli::SceneArg,
    m: sightline_core::Method,
    cells: &Option<String>,
    reference: bool,
    smallest_hole: Option<f64>,
    standing: Standing,
    json: bool,
    quiet: bool,
) -> anyhow::Result<()> {
    use sightline_core::Method;
    let kind = sightline_world::kind_of(&scene.scene);
    let what = match (kind, m) {
        (SceneKind::Bsp, _) => "on a .bsp level, --cells is a number of source leaves",
        (_, Method::Volumetric) => {
            "on a mesh level, --cells is a number of walkable viewcells to judge"
        }
        _ => "on a mesh level, --cells is a number of automatic cells to judge",
    };
    if m != Method::Volumetric && standing.is_set() {
        bail!("--eye-height, --spawn and --view-volumes set the walkable viewcells of a mesh level (.obj, .gltf, .glb) with --method volumetric");
    }
    if kind == SceneKind::Mesh && reference {
        bail!("--reference vis needs a .bsp level: a mesh level carries no reference PVS");
    }
    if kind == SceneKind::Bsp && smallest_hole.is_some() {
        bail!("--smallest-hole sets the automatic cells of a mesh level (.obj, .gltf, .glb) with --method portals or portals-fast");
    }
    let k = count_arg(cells.as_deref(), what)?;
    let world = open_world(scene, smallest_hole, standing)?;
    let spinner = progress(1, quiet, "cells, PVS, then the ground truth");
    let (judgement, level) = world.judge(m, k)?;
    spinner.finish_and_clear();
    let name = m.name();
    match (&judgement.evidence, level) {
        (Evidence::Leaves(r), _) => {
            if json {
                print_json(r)?;
            } else {
                println!(
                    "{}: {} leaves, {} portals; Σ|PVS| {} leaves = {:.3} × vis ({}), {} faces = {:.3} × the faces of vis's visible leaves ({})",
                    r.mode,
                    r.visleafs,
                    r.portals,
                    r.leaves_ours,
                    r.leaves_ratio(),
                    r.leaves_reference,
                    r.faces_ours,
                    r.faces_ratio(),
                    r.faces_reference,
                );
                println!(
                    "oracle from {} source leaves: missed {} leaf pairs; pairs vis has and we lack: {} ({} with a clear segment); {:.1} s",
                    r.sources, r.missed_pairs, r.reference_only_pairs, r.reference_only_clear, r.seconds
                );
            }
        }
        (Evidence::Cells(judged), Some(level)) => {
            print_warnings(&level.cut.warnings, quiet);
            let viewcells = level.eye_height.is_some();
            let mut report = serde_json::json!({
                "method": name,
                "clusters": level.clusters,
                "judged": judgement.judged,
                "missed": judgement.missed,
                "over_median": judgement.over_median,
                "culled_median": judgement.culled_median,
                "seconds_pvs": level.seconds_pvs,
                "seconds_truth": level.seconds_truth,
                "judged_cells": judged,
            });
            if let Some(eye) = level.eye_height {
                report["viewcells"] = level.cells.into();
                report["eye_height"] = eye.into();
            } else {
                report["cells"] = level.cells.into();
                report["leak"] = level
                    .cut
                    .auto
                    .report
                    .leak
                    .as_ref()
                    .map(|l| serde_json::json!({"inside": l.inside, "void": l.border}))
                    .into();
            }
            if json {
                print_json(&report)?;
            } else {
                let (cells, cell, pvs) = if viewcells {
                    ("walkable viewcells", "viewcell", "PVS")
                } else {
                    ("cells", "cell", "PVS of every cell")
                };
                println!(
                    "{name}: {} {cells}, {} judged, missed {}, PVS / truth median {:.2}, median {cell} culls {:.1} % of {} clusters ({pvs} {:.1} s, truth {:.1} s)",
                    level.cells,
                    judgement.judged,
                    judgement.missed,
                    judgement.over_median,
                    100.0 * judgement.culled_median,
                    level.clusters,
                    level.seconds_pvs,
                    level.seconds_truth
                );
                for w in &judgement.witnesses {
                    println!(
                        "missed: cluster {} of {cell} {} seen from {:?} along {:?}",
                        w.id,
                        w.cell,
                        w.viewpoint.unwrap_or_default(),
                        w.direction.unwrap_or_default()
                    );
                }
            }
        }
        _ => bail!("internal: a level judged without its figures"),
    }
    judgement.verdict()
}
