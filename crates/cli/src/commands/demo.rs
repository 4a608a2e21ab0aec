//! `sightline demo`: the main job end to end on an embedded default scene — a
//! generated Vienna-like old town (seed 1, 500 buildings), no download needed.
//!
//! Steps: write the scene as GeoJSON and load it back through the importer, print its
//! summary, cover it with 50 m viewcells, then run every method that is available on
//! a few cells and write a summary table (`summary.md`, `summary.json`).

use crate::cli::Command;
use crate::commands::cells::cells_json;
use crate::commands::generate::{summary, write_scene, OutFormat};
use crate::common::write_atomic;
use anyhow::Context;
use serde::Serialize;
use sightline_geom::ViewCell;
use sightline_methods::{create, MethodOptions, METHOD_NAMES};
use sightline_scene::import::{self, ImportOptions};
use sightline_scene::{cells, generate, Scene};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Cells each method is run on (spread over the whole grid).
const DEMO_CELLS: usize = 6;
/// Time budget per method: stop after this once at least one cell is done.
const METHOD_BUDGET: Duration = Duration::from_secs(8);

#[derive(Serialize)]
struct MethodRow {
    method: String,
    status: String,
    conservative: Option<bool>,
    cells: usize,
    pvs_median: Option<usize>,
    pvs_max: Option<usize>,
    hidden_fraction: Option<f64>,
    ms_per_cell: Option<f64>,
}

#[derive(Serialize)]
struct DemoSummary {
    scene: String,
    objects: usize,
    fingerprint: String,
    cells: usize,
    cell_size_m: f64,
    methods: Vec<MethodRow>,
}

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Demo { out } = cmd else {
        unreachable!("demo::run called with another command")
    };
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;

    // 1. The scene, written and read back the way a user's file would be.
    let generated = generate::city(1, 500);
    let scene_path = out.join("city.geojson");
    write_scene(&generated, &scene_path, OutFormat::GeoJson)?;
    let scene = match import::load(&scene_path, &ImportOptions::default()) {
        Ok(s) => {
            println!("scene   {} (generated city, seed 1)", scene_path.display());
            s
        }
        Err(e) => {
            println!(
                "scene   {} written; reading it back failed ({e}), using the generated scene",
                scene_path.display()
            );
            generated
        }
    };
    println!("info    {}", summary(&scene));
    if !scene.warnings.is_empty() {
        println!("        {} warnings", scene.warnings.len());
    }

    // 2. Viewcells.
    let cell_size_m = 50.0;
    let t = Instant::now();
    let grid = cells::grid_cells(&scene, cell_size_m, 1.5, 2.0)?;
    let cells_path = out.join("cells.json");
    write_atomic(&cells_path, &cells_json(&grid)?)?;
    let (nx, ny) = cells::grid_shape(&scene, cell_size_m);
    println!(
        "cells   {} of {} ({nx} × {ny}, {cell_size_m} m, z 1.5..2.0) in {:.2} s → {}",
        grid.len(),
        nx * ny,
        t.elapsed().as_secs_f64(),
        cells_path.display()
    );
    let picked: Vec<ViewCell> = spread(&grid, DEMO_CELLS);

    // 3. Every method that is available.
    let scene = Arc::new(scene);
    let mut rows = Vec::new();
    for &name in METHOD_NAMES {
        let row = run_method(name, &scene, &picked, quiet);
        rows.push(row);
    }
    let table = render_table(&rows);
    println!("\n{table}");
    let summary = DemoSummary {
        scene: "generated city, seed 1, 500 buildings".into(),
        objects: scene.objects.len(),
        fingerprint: format!("{:016x}", scene.fingerprint()),
        cells: grid.len(),
        cell_size_m,
        methods: rows,
    };
    write_atomic(&out.join("summary.md"), table.as_bytes())?;
    write_atomic(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    println!("wrote {}", out.display());
    Ok(())
}

/// `k` cells spread evenly through the list.
fn spread(cells: &[ViewCell], k: usize) -> Vec<ViewCell> {
    if cells.len() <= k {
        return cells.to_vec();
    }
    (0..k).map(|i| cells[i * cells.len() / k]).collect()
}

fn run_method(name: &str, scene: &Arc<Scene>, cells: &[ViewCell], quiet: bool) -> MethodRow {
    let mut row = MethodRow {
        method: name.to_string(),
        status: String::new(),
        conservative: None,
        cells: 0,
        pvs_median: None,
        pvs_max: None,
        hidden_fraction: None,
        ms_per_cell: None,
    };
    if name
        .parse::<sightline_core::Method>()
        .is_ok_and(|m| m.family() == sightline_core::Family::Portals)
    {
        row.status = "skipped: BSP levels only".into();
        return row;
    }
    let method = match create(name, scene.clone(), &MethodOptions::default()) {
        Ok(m) => m,
        Err(e) => {
            row.status = format!("failed: {e}");
            return row;
        }
    };
    row.conservative = Some(method.is_conservative());
    let pb = crate::common::progress(cells.len() as u64, quiet, name);
    let mut sizes = Vec::new();
    let start = Instant::now();
    for c in cells {
        match method.pvs(c) {
            Ok(v) => sizes.push(v.len()),
            Err(e) => {
                row.status = format!("failed on cell {c}: {e}");
                break;
            }
        }
        pb.inc(1);
        if start.elapsed() > METHOD_BUDGET {
            break;
        }
    }
    pb.finish_and_clear();
    let secs = start.elapsed().as_secs_f64();
    if sizes.is_empty() {
        if row.status.is_empty() {
            row.status = "no cells".into();
        }
        return row;
    }
    if row.status.is_empty() {
        row.status = "ok".into();
    }
    row.cells = sizes.len();
    row.ms_per_cell = Some(1e3 * secs / sizes.len() as f64);
    let mut sorted = sizes.clone();
    sorted.sort_unstable();
    row.pvs_median = Some(sorted[sorted.len() / 2]);
    row.pvs_max = sorted.last().copied();
    let n = scene.objects.len().max(1) as f64;
    row.hidden_fraction = Some(1.0 - sizes.iter().sum::<usize>() as f64 / (sizes.len() as f64 * n));
    row
}

fn render_table(rows: &[MethodRow]) -> String {
    let mut s = String::from(
        "| method | status | conservative | cells | PVS median | PVS max | hidden | ms/cell |\n\
         |---|---|---|---:|---:|---:|---:|---:|\n",
    );
    let opt = |v: Option<String>| v.unwrap_or_else(|| "–".into());
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.method,
            r.status,
            opt(r
                .conservative
                .map(|c| if c { "yes" } else { "no" }.to_string())),
            r.cells,
            opt(r.pvs_median.map(|v| v.to_string())),
            opt(r.pvs_max.map(|v| v.to_string())),
            opt(r.hidden_fraction.map(|h| format!("{:.1} %", 100.0 * h))),
            opt(r.ms_per_cell.map(|m| format!("{m:.2}"))),
        ));
    }
    s
}
