//! Walkable viewcells and the volumetric PVS on a mesh level, judged by the truth:
//! `cargo run --release -p sightline-autocells --example walk_levels -- LEVEL.obj [H|auto] [EYE] [K] [WIDTH]`
//! (H: smallest hole; EYE: eye height in scene units; K: viewcells judged; WIDTH:
//! viewcell side in voxels).

use sightline_autocells::viewcells::Walker;
use sightline_autocells::{AutoCells, Options};
use sightline_core::check::TruthOptions;
use sightline_scene::clusters::cluster_scene;
use sightline_scene::import::{load, ImportOptions};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .ok_or("usage: walk_levels LEVEL.obj [H|auto] [EYE] [K] [WIDTH]")?;
    let hole = args
        .get(2)
        .filter(|s| *s != "auto")
        .map(|s| s.parse::<f64>())
        .transpose()?;
    let eye: f64 = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(14.0);
    let k: usize = args.get(4).map(|s| s.parse()).transpose()?.unwrap_or(20);
    let width: usize = args.get(5).map(|s| s.parse()).transpose()?.unwrap_or(8);
    let t0 = Instant::now();
    let scene = load(std::path::Path::new(path), &ImportOptions::default())?;
    let opts = Options {
        smallest_hole: hole,
        full: false,
        ..Options::default()
    };
    let cluster_size = sightline_autocells::default_cluster_size(&scene, &opts);
    let clustered = cluster_scene(
        &scene,
        cluster_size,
        sightline_autocells::MAX_CLUSTER_TRIANGLES,
    );
    let auto = AutoCells::build(&clustered.scene, &opts)?;
    let t_auto = t0.elapsed().as_secs_f64();
    let found = auto.viewcells(&Walker {
        eye_height: eye,
        width,
    });
    let limit: usize = std::env::var("LIMIT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(usize::MAX);
    let step = (found.len() / limit.max(1)).max(1);
    let cells: Vec<_> = found.iter().copied().step_by(step).take(limit).collect();
    let vol = auto.volumetric();
    let t_pvs = Instant::now();
    let pvs: Vec<Vec<u32>> = {
        use rayon::prelude::*;
        cells
            .par_iter()
            .map(|b| auto.viewcell_pvs(&vol, b))
            .collect()
    };
    let seconds_pvs = t_pvs.elapsed().as_secs_f64();
    struct W {
        cells: Vec<sightline_autocells::cells::VoxelBox>,
        pvs: Vec<Vec<u32>>,
        found: usize,
        seconds_occluders: f64,
        seconds_pvs: f64,
    }
    let w = W {
        cells,
        pvs,
        found: found.len(),
        seconds_occluders: vol.seconds,
        seconds_pvs,
    };
    let total = t0.elapsed().as_secs_f64();
    let n = auto.objects as f64;
    let mut culled: Vec<f64> = w.pvs.iter().map(|p| 1.0 - p.len() as f64 / n).collect();
    culled.sort_by(f64::total_cmp);
    let med = |v: &[f64]| v.get(v.len() / 2).copied().unwrap_or(0.0);
    println!(
        "{path}: h {:.3}, grid {:?}, {} clusters, {} auto cells, {} viewcells ({} found); auto {t_auto:.1} s, occluders {:.1} s, PVS {:.1} s, total {total:.1} s, peak {:.0} MB",
        auto.report.smallest_hole,
        auto.report.grid,
        auto.objects,
        auto.len(),
        w.cells.len(),
        w.found,
        w.seconds_occluders,
        w.seconds_pvs,
        sightline_stats::memory_kib().1 as f64 / 1024.0
    );
    println!(
        "culled per viewcell: median {:.1} %, p10 {:.1} %, p90 {:.1} %",
        100.0 * med(&culled),
        100.0 * culled.get(culled.len() / 10).copied().unwrap_or(0.0),
        100.0 * culled.get(culled.len() * 9 / 10).copied().unwrap_or(0.0),
    );
    if k > 0 {
        let t = Instant::now();
        let judged = auto.judge_boxes(
            &clustered.scene,
            &w.cells,
            |c| w.pvs[c].clone(),
            k,
            &TruthOptions::default(),
        );
        let missed: usize = judged.iter().map(|j| j.missed.len()).sum();
        let mut over: Vec<f64> = judged
            .iter()
            .map(|j| j.pvs as f64 / j.truth.max(1) as f64)
            .collect();
        over.sort_by(f64::total_cmp);
        println!(
            "judged {} viewcells in {:.1} s: missed {missed}, PVS / truth median {:.2} (min {:.2}, max {:.2})",
            judged.len(),
            t.elapsed().as_secs_f64(),
            med(&over),
            over.first().copied().unwrap_or(0.0),
            over.last().copied().unwrap_or(0.0)
        );
        for j in &judged {
            println!(
                "  cell {} {:?}: truth {} pvs {} missed {}",
                j.cell,
                j.bounds,
                j.truth,
                j.pvs,
                j.missed.len()
            );
            for m in j.missed.iter().take(3) {
                println!(
                    "    missed {} from {:?} dir {:?}",
                    m.id, m.viewpoint, m.direction
                );
            }
        }
    }
    Ok(())
}
