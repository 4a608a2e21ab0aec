//! `sightline check`: a method's PVS against the ground truth on many cells (SPEC §5).

use crate::cli::Command;
use crate::common::{load_scene, print_json, progress};
use anyhow::{bail, Context};
use sightline_geom::ViewCell;
use sightline_methods::check::{check_cells, street_cells, TruthOptions};
use sightline_methods::{create, MethodOptions};
use std::sync::Arc;

/// Side of the cells picked when `--cells` is a number (metres).
const AUTO_CELL_M: f64 = 10.0;

/// `--cells`: a cells.json file, or a number of street cells to pick in the scene.
fn read_cells(arg: &str, scene: &sightline_scene::Scene) -> anyhow::Result<Vec<ViewCell>> {
    if let Ok(k) = arg.parse::<usize>() {
        if k == 0 {
            bail!("--cells must name a cells.json or a positive number of cells");
        }
        let cells = street_cells(scene, AUTO_CELL_M, (1.5, 2.0), k);
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

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Check {
        scene,
        pvs,
        method,
        cells,
        resolution,
        json,
    } = cmd
    else {
        bail!("internal: `check` called with another command");
    };
    if let Some(file) = pvs {
        // The .pvs path (SPEC §5 `check SCENE city.pvs`) belongs to the store.
        bail!(
            "checking a .pvs file ({}) is not supported by this build yet; use --method NAME --cells ...",
            file.display()
        );
    }
    let Some(method) = method else {
        bail!("check needs --method NAME (or a .pvs file)");
    };
    let cells_arg = cells.unwrap_or_else(|| "20".to_string());
    let sc = Arc::new(load_scene(&scene)?);
    let cells = read_cells(&cells_arg, &sc)?;
    let m = create(
        &method,
        sc.clone(),
        &MethodOptions {
            resolution_px: resolution,
            ..MethodOptions::default()
        },
    )?;
    let pb = progress(cells.len() as u64, quiet, "checking cells");
    let report = check_cells(&sc, m.as_ref(), &cells, &TruthOptions::default(), &|| {
        pb.inc(1)
    })?;
    pb.finish_and_clear();
    let missed: Vec<serde_json::Value> = report
        .per_cell
        .iter()
        .flat_map(|c| {
            c.missed.iter().map(move |x| {
                serde_json::json!({"cell": c.cell, "id": x.id, "viewpoint": x.viewpoint, "direction": x.direction})
            })
        })
        .collect();
    if json {
        print_json(&serde_json::json!({
            "method": report.method,
            "conservative": m.is_conservative(),
            "cells": report.cells,
            "missed": report.missed,
            "over_median": report.over_median,
            "over_p90": report.over_p90,
            "over_max": report.over_max,
            "hidden_fraction": report.hidden_fraction,
            "pvs_ms_median": report.pvs_ms_median,
            "truth_ms_median": report.truth_ms_median,
            "missed_ids": missed,
            "per_cell": report.per_cell.iter().map(|c| serde_json::json!({
                "cell": c.cell, "pvs": c.pvs_len, "vs": c.vs_len, "missed": c.missed.len(),
                "over": c.over, "hidden_fraction": c.hidden_fraction,
                "pvs_ms": c.pvs_seconds * 1e3, "truth_ms": c.truth_seconds * 1e3,
            })).collect::<Vec<_>>(),
        }))?;
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
        for x in &missed {
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
