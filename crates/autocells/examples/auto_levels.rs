//! Automatic cells on a mesh level end to end, with the figures of issue #39:
//! `cargo run --release -p sightline-autocells --example auto_levels -- LEVEL.obj [H] [K]`
//! (H: smallest hole, default the automatic one; K: cells judged against the truth,
//! default 20; `fast`: the base flood only, `portals-fast`).

use sightline_autocells::{AutoCells, Options};
use sightline_core::check::TruthOptions;
use sightline_scene::clusters::cluster_scene;
use sightline_scene::import::{load, ImportOptions};
use std::time::Instant;

fn peak_mb() -> f64 {
    sightline_stats::memory_kib().1 as f64 / 1024.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .ok_or("usage: auto_levels LEVEL.obj [SMALLEST_HOLE|auto] [CELLS] [full|fast] [MAX_BOX] [GROUP_BLOCK]")?;
    let hole = args
        .get(2)
        .filter(|s| *s != "auto")
        .map(|s| s.parse::<f64>())
        .transpose()?;
    let k: usize = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(20);
    let t0 = Instant::now();
    let scene = load(std::path::Path::new(path), &ImportOptions::default())?;
    let t_load = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let opts = Options {
        smallest_hole: hole,
        full: args.get(4).is_none_or(|m| m != "fast"),
        max_box: match args.get(5) {
            Some(b) => b.parse()?,
            None => Options::default().max_box,
        },
        group_block: match args.get(6) {
            Some(b) => b.parse()?,
            None => Options::default().group_block,
        },
        axis_rule: std::env::var("AXIS_RULE").is_ok_and(|v| v == "1"),
        walls_bound_cells: std::env::var("WALLS_BOUND").is_ok_and(|v| v == "1"),
        flow_budget: match std::env::var("FLOW_BUDGET") {
            Ok(b) if b == "none" => None,
            Ok(b) => Some(b.parse()?),
            Err(_) => Options::default().flow_budget,
        },
        ..Options::default()
    };
    let cluster_size = sightline_autocells::default_cluster_size(&scene, &opts);
    let clustered = cluster_scene(
        &scene,
        cluster_size,
        sightline_autocells::MAX_CLUSTER_TRIANGLES,
    );
    let t_clusters = t1.elapsed().as_secs_f64();
    let mut auto = AutoCells::cut(&clustered.scene, &opts)?;
    let r = auto.report.clone();
    println!(
        "cut      {} cells, {} portals, {} solid voxels ({:.2} s)",
        r.cells,
        r.portals,
        r.voxels.solid,
        t1.elapsed().as_secs_f64()
    );
    auto.solve(opts.full, opts.group_block, opts.flow_budget);
    let total = t1.elapsed().as_secs_f64();
    let r = &auto.report;
    println!(
        "level    {path}: {} objects, {} triangles, bounds {:?} – {:?}",
        scene.objects.len(),
        scene
            .objects
            .iter()
            .map(|o| o.triangle_count())
            .sum::<usize>(),
        scene.bounds.min.to_array(),
        scene.bounds.max.to_array()
    );
    println!(
        "clusters {} of ≤ {} triangles, {cluster_size:.2} units ({t_clusters:.2} s)",
        clustered.scene.objects.len(),
        sightline_autocells::MAX_CLUSTER_TRIANGLES
    );
    println!(
        "voxels   {} ({:?}, smallest hole {:.3}{}): {} surface, {} air, {} solid; {} components, {} solid; {} closed faces; {} degenerate triangles ({:.2} s)",
        r.voxels.voxels,
        r.grid,
        r.smallest_hole,
        r.smallest_hole_asked.map_or(String::new(), |a| format!(", asked {a}")),
        r.voxels.surface,
        r.voxels.air,
        r.voxels.solid,
        r.voxels.components,
        r.voxels.solid_components,
        r.voxels.closed_faces,
        r.voxels.degenerate_triangles,
        r.seconds_voxels
    );
    println!(
        "cells    {} cells, {} portals ({:.2} s)",
        r.cells, r.portals, r.seconds_cells
    );
    println!(
        "pvs      every cell in {:.2} s ({} solver cells, {} portals)",
        r.seconds_pvs, r.groups, r.group_portals
    );
    if let Some(l) = &r.leak {
        println!(
            "leak     from {:?} to the border at {:?} ({} voxels)",
            l.inside,
            l.border,
            l.path.len()
        );
    }
    let mut culled: Vec<f64> = (0..auto.len())
        .map(|c| 1.0 - auto.pvs(c).len() as f64 / auto.objects as f64)
        .collect();
    culled.sort_by(f64::total_cmp);
    let median = culled.get(culled.len() / 2).copied().unwrap_or(0.0);
    println!(
        "total    load {t_load:.2} s, mesh → clusters → cells → portals → PVS of every cell {total:.2} s, peak {:.0} MB",
        peak_mb()
    );
    println!(
        "culled   median {:.1} % of {} clusters per cell (p10 {:.1} %, p90 {:.1} %)",
        median * 100.0,
        auto.objects,
        culled[culled.len() / 10] * 100.0,
        culled[culled.len() * 9 / 10] * 100.0
    );
    // The judge: the item-buffer truth from the free voxels of K cells spread over the
    // cell list (cells without an air voxel skipped).
    let topts = TruthOptions {
        samples: 16,
        resolution_px: 256,
        targeted_rays_per_object: 8,
        seed: 7,
    };
    let t3 = Instant::now();
    let judged_cells = auto.judge(&clustered.scene, k, &topts);
    let (judged, mut missed, mut seen) = (judged_cells.len(), 0, 0);
    for j in &judged_cells {
        if !j.missed.is_empty() {
            println!("MISS     cell {} {:?}", j.cell, j.bounds);
            for w in &j.missed {
                let o = sightline_geom::DVec3::from_array(w.viewpoint);
                let d = sightline_geom::DVec3::from_array(w.direction);
                // Voxel states along the witness ray, every half voxel, up to 64 voxels.
                let g = &auto.voxels.grid;
                let states: String = (0..128)
                    .filter_map(|i| g.locate(o + d * (i as f64 * 0.5 * g.size)))
                    .map(|c| match auto.voxels.state[g.index(c[0], c[1], c[2])] {
                        0 => 'a',
                        1 => 's',
                        _ => '#',
                    })
                    .collect();
                println!(
                    "witness  {} from {:?} along {:?} (cell {:?}): {states}",
                    w.id,
                    w.viewpoint,
                    w.direction,
                    auto.locate(w.viewpoint)
                );
            }
        }
        missed += j.missed.len();
        seen += j.truth;
        println!(
            "judge    cell {}: truth {} ⊆ pvs {} of {} ({} viewpoints)",
            j.cell, j.truth, j.pvs, auto.objects, j.viewpoints
        );
    }
    println!(
        "truth    {judged} cells, {missed} missed, {seen} seen in all ({:.1} s; {} viewpoints × 6 × {}², {} targeted rays/object)",
        t3.elapsed().as_secs_f64(),
        topts.samples,
        topts.resolution_px,
        topts.targeted_rays_per_object
    );
    Ok(())
}
