//! Phase timings of the erosion methods on a scene: `cargo run --release -p
//! sightline-methods --example erosion_timing -- SCENE [CELL_SIZE] [CELLS] [METHODS]`
//! (METHODS: comma-separated, default all five; CELLS is a number of street cells whose
//! centre column is free, `check::street_cells`, or a cells.json of
//! `erosion_street_cells`). With `EROSION_WARM=1` every cell is run once before the
//! timed run, so that the eroded occluders of every cell shape and fill threshold are
//! cached (§5.1: a preprocessing shared by all cells of a grid) and the times are
//! those of the per-cell tests alone. `EROSION_REPEAT=N` times every cell N times (for
//! profiles of the per-cell tests); `EROSION_BINS=N` sets the number of azimuth bins.

use sightline_core::check::{street_cells, Clearance};
use sightline_geom::ViewCell;
use sightline_methods::{create, MethodOptions};
use sightline_scene::import::{load, ImportOptions};
use std::sync::Arc;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .ok_or("usage: erosion_timing SCENE [SIZE] [CELLS] [METHODS]")?;
    let size: f64 = args.get(2).map_or(Ok(25.0), |s| s.parse())?;
    let cells_arg = args.get(3).map_or("10", |s| s.as_str());
    let t = Instant::now();
    let scene = Arc::new(load(std::path::Path::new(path), &ImportOptions::default())?);
    println!(
        "load {:.2}s, {} objects",
        t.elapsed().as_secs_f64(),
        scene.objects.len()
    );
    let cells = if cells_arg.ends_with(".json") {
        // A JSON array of `[x0, y0, z0, x1, y1, z1]` rows, one per line.
        let mut cells = Vec::new();
        for line in std::fs::read_to_string(cells_arg)?.lines() {
            let t = line.trim().trim_end_matches(',');
            if !t.starts_with("[[") && t.starts_with('[') && t.ends_with(']') {
                let v = t[1..t.len() - 1]
                    .split(',')
                    .map(|x| x.trim().parse::<f64>())
                    .collect::<Result<Vec<f64>, _>>()?;
                let a: [f64; 6] = v.try_into().map_err(|_| "a cell needs 6 numbers")?;
                cells.push(ViewCell::from_array(a)?);
            }
        }
        cells
    } else {
        street_cells(
            &scene,
            size,
            (1.5, 2.0),
            cells_arg.parse()?,
            Clearance::Centre,
        )
    };
    let only: Vec<String> = args
        .get(4)
        .map(|s| s.split(',').map(String::from).collect())
        .unwrap_or_default();
    for m in [
        "erosion",
        "erosion-segment",
        "erosion-cell",
        "shrink-sphere",
        "erosion-rays",
    ] {
        if !only.is_empty() && !only.iter().any(|o| o == m) {
            continue;
        }
        let t = Instant::now();
        let opts = MethodOptions {
            resolution_px: std::env::var("EROSION_BINS")
                .ok()
                .and_then(|v| v.parse().ok()),
            ..MethodOptions::default()
        };
        let method = create(m, scene.clone(), &opts)?;
        let prep = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let first = method.pvs(&cells[0])?.len();
        let first_s = t.elapsed().as_secs_f64();
        if std::env::var("EROSION_WARM").is_ok_and(|v| v == "1") {
            for cell in &cells {
                method.pvs(cell)?;
            }
        }
        let repeat: usize = std::env::var("EROSION_REPEAT")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(1);
        let mut ms = Vec::new();
        let mut lens = Vec::new();
        for cell in cells.iter().cycle().take(cells.len() * repeat.max(1)) {
            let t = Instant::now();
            lens.push(method.pvs(cell)?.len());
            ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
        ms.sort_by(f64::total_cmp);
        println!(
            "{m:16} prepare {prep:.2}s first cell {first_s:.2}s ({first}) median {:.1} ms/cell, max {:.1}; pvs sizes {:?}",
            ms[ms.len() / 2],
            ms[ms.len() - 1],
            lens
        );
    }
    Ok(())
}
