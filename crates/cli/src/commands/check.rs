//! `sightline check`: a method's PVS against the ground truth on many cells.

use crate::cli::Command;
use crate::common::{load_scene, method_options, print_json, progress};
use anyhow::{bail, Context};
use sightline_geom::ViewCell;
use sightline_methods::check::{check_cells, street_cells, TruthOptions};
use sightline_methods::{create, MethodError, VisibilityMethod, METHOD_NAMES};
use sightline_pvs::PvsFile;
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
        sweep,
        planes,
        json,
    } = cmd
    else {
        bail!("internal: `check` called with another command");
    };
    let sc = Arc::new(load_scene(&scene)?);
    let (m, cells): (Box<dyn VisibilityMethod>, Vec<ViewCell>) = if let Some(file) = pvs {
        if sweep || planes.is_some() {
            bail!("--sweep and --planes are options of --method ext-proj, not of a .pvs file");
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
        let stored = f.stored();
        let k: usize = match cells.as_deref() {
            None => 20,
            Some(c) => c.parse().ok().filter(|&k| k > 0).with_context(|| {
                format!("with a .pvs file, --cells is a number of cells to sample, got '{c}'")
            })?,
        };
        let k = k.min(stored.len());
        let picked: Vec<ViewCell> = (0..k)
            .map(|i| f.cells()[stored[i * stored.len() / k] as usize])
            .collect();
        (Box::new(StoredPvs(f)), picked)
    } else {
        let Some(method) = method else {
            bail!("check needs --method NAME (or a .pvs file)");
        };
        let cells_arg = cells.unwrap_or_else(|| "20".to_string());
        let cells = read_cells(&cells_arg, &sc)?;
        let opts = method_options(&method, resolution, sweep, planes)?;
        let m = create(&method, sc.clone(), &opts)?;
        (m, cells)
    };
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
            "params": m.params().into_iter().collect::<std::collections::BTreeMap<_, _>>(),
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

/// A `.pvs` file answering as the method it was built with: the stored set of the cell.
struct StoredPvs(PvsFile);

impl VisibilityMethod for StoredPvs {
    fn name(&self) -> &'static str {
        let m = &self.0.header().method;
        METHOD_NAMES
            .iter()
            .find(|n| **n == m)
            .copied()
            .unwrap_or("pvs-file")
    }

    fn is_conservative(&self) -> bool {
        self.0.header().method != "sampled"
    }

    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        let i = self
            .0
            .cells()
            .iter()
            .position(|c| c == cell)
            .ok_or_else(|| MethodError::BadCell("not a cell of the .pvs file".into()))?;
        self.0.pvs(i).map_err(|e| MethodError::Other(e.to_string()))
    }
}
