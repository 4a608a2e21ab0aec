//! `sightline demo`: the main job end to end on an embedded default scene — a
//! generated Vienna-like old town (seed 1, 500 buildings), no download needed.
//!
//! Steps: write the scene as GeoJSON and load it back through the importer, print its
//! summary, cover it with 50 m viewcells (`cells.json`), compute the ground truth of a
//! few cells near the middle, run every method of the registry on those cells and
//! measure it against the truth (`missed`, `over`: a summary table, `summary.md`,
//! `summary.json`), build the `.pvs` of the whole grid with `dual-ray` (`city.pvs`),
//! draw one cell's PVS against the truth (`map.png`), and print how to walk the result
//! in the browser viewer.

use crate::cli::Command;
use crate::commands::cells::cells_json;
use crate::commands::generate::{summary, write_scene, OutFormat};
use crate::commands::map::map_png;
use crate::common::write_atomic;
use anyhow::Context;
use rayon::prelude::*;
use serde::Serialize;
use sightline_core::check::{compare, CellCheck, Truth, TruthOptions, TruthScene};
use sightline_geom::ViewCell;
use sightline_methods::{create, Method, MethodOptions};
use sightline_pvs::{build, BuildOptions};
use sightline_scene::import::{self, ImportOptions};
use sightline_scene::{cells, generate, Scene};
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Cells each method is run on and measured against the ground truth (near the middle
/// of the city: cells at its edge see mostly empty ground).
const DEMO_CELLS: usize = 2;
/// Time budget per method: stop after this once at least one cell is done.
const METHOD_BUDGET: Duration = Duration::from_secs(3);
/// The method of the `.pvs` and of the map: the fastest conservative one.
const GRID_METHOD: Method = Method::DualRay;

#[derive(Serialize)]
struct MethodRow {
    method: String,
    status: String,
    /// What the registry claims; `missed` is what this run measured.
    conservative: bool,
    cells: usize,
    /// Objects of the ground truth missing from the PVS, summed over the cells.
    missed: Option<usize>,
    /// |PVS| / |VS| (median, max over the cells).
    over_median: Option<f64>,
    over_max: Option<f64>,
    pvs_median: Option<usize>,
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
    checked_cells: Vec<ViewCell>,
    truth_ms_per_cell: f64,
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

    // 3. The ground truth of the cells every method is measured on.
    let t = Instant::now();
    let picked = sightline_core::check::near_middle(&scene, &grid, DEMO_CELLS, 3);
    let ts = TruthScene::new(&scene);
    let truths: Vec<Truth> = picked
        .par_iter()
        .map(|c| ts.ground_truth(c, &TruthOptions::default()))
        .collect();
    let truth_ms = 1e3 * truths.iter().map(|t| t.seconds).sum::<f64>() / truths.len().max(1) as f64;
    println!(
        "truth   {} cells near the middle in {:.1} s ({truth_ms:.0} ms/cell; 128 viewpoints × 6 faces × 1024², targeted rays)",
        picked.len(),
        t.elapsed().as_secs_f64(),
    );

    // 4. Every method of the registry that works on a city (the portal family needs a
    // BSP level), measured against the truth.
    let scene = Arc::new(scene);
    let rows: Vec<MethodRow> = Method::ALL
        .iter()
        .filter(|m| m.works_on(sightline_core::SceneKind::City))
        .map(|&m| run_method(m, &scene, &truths, quiet))
        .collect();
    let table = render_table(&rows);
    println!("\n{table}");
    let summary = DemoSummary {
        scene: "generated city, seed 1, 500 buildings".into(),
        objects: scene.objects.len(),
        fingerprint: format!("{:016x}", scene.fingerprint()),
        cells: grid.len(),
        cell_size_m,
        checked_cells: picked.clone(),
        truth_ms_per_cell: truth_ms,
        methods: rows,
    };
    write_atomic(&out.join("summary.md"), table.as_bytes())?;
    write_atomic(
        &out.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;

    // 5. The `.pvs` of the whole grid and the map of one cell.
    let method = create(GRID_METHOD, scene.clone(), &MethodOptions::default())?;
    let pvs_path = out.join("city.pvs");
    write_pvs(&scene, method.as_ref(), &grid, &pvs_path)?;
    if let (Some(cell), Some(truth)) = (picked.first(), truths.first()) {
        let mut pvs = method.pvs(cell)?;
        pvs.sort_unstable();
        let png = map_png(
            &scene,
            cell,
            &truth.visible,
            Some((GRID_METHOD.name(), &pvs)),
        )?;
        let map_path = out.join("map.png");
        write_atomic(&map_path, &png)?;
        println!(
            "map     {} of cell {cell}: {} in the PVS, {} seen by the truth, {} objects → {}",
            GRID_METHOD.name(),
            pvs.len(),
            truth.visible.len(),
            scene.objects.len(),
            map_path.display()
        );
    }
    println!("wrote {}", out.display());
    println!(
        "next    sightline serve {} {}   # then open http://127.0.0.1:8080/ and walk",
        scene_path.display(),
        pvs_path.display()
    );
    Ok(())
}

/// Build the `.pvs` of every cell of the grid.
fn write_pvs(
    scene: &Scene,
    method: &dyn sightline_methods::VisibilityMethod,
    grid: &[ViewCell],
    path: &Path,
) -> anyhow::Result<()> {
    let t = Instant::now();
    let stats = build(
        scene,
        method,
        grid,
        path,
        &BuildOptions::default(),
        &|_, _| {},
    )
    .with_context(|| format!("building {}", path.display()))?;
    println!(
        "pvs     {} cells with {}, {} bytes ({:.0} B/cell) in {:.1} s → {}",
        stats.cells,
        method.name(),
        stats.bytes,
        stats.bytes as f64 / stats.cells.max(1) as f64,
        t.elapsed().as_secs_f64(),
        path.display()
    );
    Ok(())
}

fn run_method(m: Method, scene: &Arc<Scene>, truths: &[Truth], quiet: bool) -> MethodRow {
    let mut row = MethodRow {
        method: m.name().to_string(),
        status: String::new(),
        conservative: m.is_conservative(),
        cells: 0,
        missed: None,
        over_median: None,
        over_max: None,
        pvs_median: None,
        hidden_fraction: None,
        ms_per_cell: None,
    };
    let n = scene.objects.len();
    if m == Method::Sampled {
        // `sampled` with its default options is the truth just computed: not run twice.
        let checks: Vec<CellCheck> = truths
            .iter()
            .map(|t| compare(n, &t.visible, t, t.seconds))
            .collect();
        if checks.is_empty() {
            row.status = "no cells".into();
            return row;
        }
        row.status = "ok (the truth)".into();
        fill(&mut row, &checks);
        return row;
    }
    let method = match create(m, scene.clone(), &MethodOptions::default()) {
        Ok(m) => m,
        Err(e) => {
            row.status = format!("failed: {e}");
            return row;
        }
    };
    let pb = crate::common::progress(truths.len() as u64, quiet, m.name());
    let mut checks = Vec::new();
    let start = Instant::now();
    for truth in truths {
        let t = Instant::now();
        match method.pvs(&truth.cell) {
            Ok(mut v) => {
                v.sort_unstable();
                checks.push(compare(n, &v, truth, t.elapsed().as_secs_f64()));
            }
            Err(e) => {
                row.status = format!("failed on cell {}: {e}", truth.cell);
                break;
            }
        }
        pb.inc(1);
        if start.elapsed() > METHOD_BUDGET {
            break;
        }
    }
    pb.finish_and_clear();
    if checks.is_empty() {
        if row.status.is_empty() {
            row.status = "no cells".into();
        }
        return row;
    }
    if row.status.is_empty() {
        row.status = "ok".into();
    }
    fill(&mut row, &checks);
    row
}

/// The measured columns of `row` from its checked cells (at least one).
fn fill(row: &mut MethodRow, checks: &[CellCheck]) {
    row.cells = checks.len();
    let secs: f64 = checks.iter().map(|c| c.pvs_seconds).sum();
    row.ms_per_cell = Some(1e3 * secs / checks.len() as f64);
    row.missed = Some(checks.iter().map(|c| c.missed.len()).sum());
    let over: Vec<f64> = checks.iter().map(|c| c.over).collect();
    row.over_median = Some(sightline_stats::median(&over));
    row.over_max = over.iter().copied().reduce(f64::max);
    let mut sizes: Vec<usize> = checks.iter().map(|c| c.pvs_len).collect();
    sizes.sort_unstable();
    row.pvs_median = Some(sizes[sizes.len() / 2]);
    row.hidden_fraction =
        Some(checks.iter().map(|c| c.hidden_fraction).sum::<f64>() / checks.len() as f64);
}

fn render_table(rows: &[MethodRow]) -> String {
    let mut s = String::from(
        "| method | status | cells | missed | over median | over max | PVS median | hidden | ms/cell |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let opt = |v: Option<String>| v.unwrap_or_else(|| "–".into());
    for r in rows {
        // A miss of a method that claims no guarantee (the sampled truth) is expected.
        let missed = r.missed.map(|k| {
            if r.conservative {
                k.to_string()
            } else {
                format!("{k} (not conservative)")
            }
        });
        s.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            r.method,
            r.status,
            r.cells,
            opt(missed),
            opt(r.over_median.map(|v| format!("{v:.2}"))),
            opt(r.over_max.map(|v| format!("{v:.2}"))),
            opt(r.pvs_median.map(|v| v.to_string())),
            opt(r.hidden_fraction.map(|h| format!("{:.1} %", 100.0 * h))),
            opt(r.ms_per_cell.map(|m| format!("{m:.2}"))),
        ));
    }
    s
}
