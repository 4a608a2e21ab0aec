//! `sightline check`: a method's PVS against the ground truth on many cells.

use crate::cli::Command;
use crate::common::{load_scene, method_options, print_json, progress};
use anyhow::{bail, Context};
use sightline_core::check::{check_cells, report_json, street_cells, Clearance, TruthOptions};
use sightline_geom::ViewCell;
use sightline_methods::{create, VisibilityMethod};
use sightline_pvs::{PvsFile, StoredPvs};
use std::sync::Arc;

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
        json,
    } = cmd
    else {
        bail!("internal: `check` called with another command");
    };
    let mesh = crate::commands::mesh::is_mesh(&scene.scene);
    let volumetric = sightline_core::Method::Volumetric.name();
    if mesh && pvs.is_none() && method.as_deref().is_none_or(|m| m == volumetric) {
        let k = count_arg(
            cells.as_deref(),
            "on a mesh level, --cells is a number of walkable viewcells to judge",
        )?;
        let standing = crate::commands::mesh::Standing {
            eye_height,
            spawns: spawn,
            view_volumes,
        };
        return crate::commands::mesh::check_volumetric(
            &scene,
            smallest_hole,
            &standing,
            k,
            json,
            quiet,
        );
    }
    if eye_height.is_some() || !spawn.is_empty() || view_volumes.is_some() {
        bail!("--eye-height, --spawn and --view-volumes set the walkable viewcells of a mesh level (.obj, .gltf, .glb) with --method volumetric");
    }
    if let Some(full) = method
        .as_deref()
        .and_then(|m| crate::commands::mesh::portal_mode(&scene.scene, m))
    {
        if reference.is_some() {
            bail!("--reference vis needs a .bsp level: a mesh level carries no reference PVS");
        }
        let k = count_arg(
            cells.as_deref(),
            "on a mesh level, --cells is a number of automatic cells to judge",
        )?;
        return crate::commands::mesh::check(&scene, full, smallest_hole, k, json, quiet);
    }
    if smallest_hole.is_some() {
        bail!("--smallest-hole sets the automatic cells of a mesh level (.obj, .gltf, .glb) with --method portals or portals-fast");
    }
    if let Some(mode) = method
        .as_deref()
        .map(|m| crate::commands::bsp::portal_mode(&scene.scene, m))
        .transpose()?
        .flatten()
    {
        let k = count_arg(
            cells.as_deref(),
            "on a .bsp level, --cells is a number of source leaves",
        )?;
        return crate::commands::bsp::check(&scene.scene, mode, k, json, quiet);
    }
    if reference.is_some() {
        bail!("--reference vis compares a .bsp level's portal PVS with its own vis: it needs a .bsp and --method portals or portals-fast");
    }
    let sc = Arc::new(load_scene(&scene)?);
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
    let report = check_cells(&sc, m.as_ref(), &cells, &TruthOptions::default(), &|| {
        pb.inc(1)
    })?;
    pb.finish_and_clear();
    let json_report = report_json(&report, m.as_ref());
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
    if m.is_conservative() && report.missed > 0 {
        bail!(
            "method {} missed {} visible object(s) — a conservativeness bug (witnesses above)",
            report.method,
            report.missed
        );
    }
    Ok(())
}
