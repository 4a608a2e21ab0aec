//! The occlusion-sweep experiment of the extended-projection paper (§7.2) on the dense
//! generated forest, against the ground truth (run in release):
//!
//! `cargo run --release -p sightline-methods --example ext_proj_forest -- [TREES] [CELLS] [CELL_M] [SAMPLES] [RES] [PLANES,..]`
//!
//! Defaults: 256 trees (`ForestParams::dense`), 6 cells of 0.5 m (eye height 1.5–2 m)
//! between trees near the middle, ground truth with 32 viewpoints at 512 px, and
//! plain `ext-proj` then the sweep with 1, 5, 15 planes. Prints, per variant, missed,
//! over (median / p90), hidden %, culled triangles % and ms/cell (median), and the
//! ground truth's own hidden fraction (an upper bound of what any conservative method
//! can cull).
//!
//! Environment: `RES=512` depth-map resolution (the CLI's default with `--sweep`);
//! `KERNEL`, `START`, `REACH` the sweep's kernel size (px), first-plane distance and
//! least reach (m); `EXT` the extension of the planes for the corner directions;
//! `CELL=x0,y0,z0,x1,y1,z1` one given cell; `SWEEP_DEBUG=DIR` writes the first cell's
//! sweep occlusion maps as PGM images to DIR; `LEAVES`, `LEAF=a:b`, `CROWN=a:b`,
//! `ASPECT=a:b`, `TRUNK=a:b`, `LIFT` override the dense preset (for tuning).

use rayon::prelude::*;
use sightline_core::check::{aggregate, compare, TruthOptions, TruthScene};
use sightline_geom::ViewCell;
use sightline_methods::ext_proj::{ExtProj, Params};
use sightline_methods::VisibilityMethod;
use sightline_scene::generate::{forest_with, ForestParams};
use std::sync::Arc;
use std::time::Instant;

fn arg<T: std::str::FromStr>(args: &[String], i: usize, default: T) -> T {
    args.get(i).and_then(|s| s.parse().ok()).unwrap_or(default)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let trees: usize = arg(&args, 1, 256);
    let want: usize = arg(&args, 2, 6);
    let cell_m: f64 = arg(&args, 3, 0.5);
    let samples: u32 = arg(&args, 4, 32);
    let res: u32 = arg(&args, 5, 512);
    let planes: Vec<usize> = args
        .get(6)
        .map(|s| s.split(',').filter_map(|p| p.parse().ok()).collect())
        .unwrap_or_else(|| vec![1, 5, 15]);

    let mut p = ForestParams::dense(trees);
    // Optional overrides of the dense preset, for tuning: LEAVES=1500 LEAF=0.3:0.5.
    if let Some(l) = std::env::var("LEAVES").ok().and_then(|s| s.parse().ok()) {
        p.leaves_per_tree = l;
    }
    if let Some((a, b)) = std::env::var("ASPECT").ok().and_then(|s| {
        let (a, b) = s.split_once(':')?;
        Some((a.parse().ok()?, b.parse().ok()?))
    }) {
        p.crown_aspect = (a, b);
    }
    if let Some((a, b)) = std::env::var("CROWN").ok().and_then(|s| {
        let (a, b) = s.split_once(':')?;
        Some((a.parse().ok()?, b.parse().ok()?))
    }) {
        p.crown_radius_m = (a, b);
    }
    if let Some(l) = std::env::var("LIFT").ok().and_then(|s| s.parse().ok()) {
        p.crown_lift = l;
    }
    if let Some((a, b)) = std::env::var("TRUNK").ok().and_then(|s| {
        let (a, b) = s.split_once(':')?;
        Some((a.parse().ok()?, b.parse().ok()?))
    }) {
        p.trunk_height_m = (a, b);
    }
    if let Some((a, b)) = std::env::var("LEAF").ok().and_then(|s| {
        let (a, b) = s.split_once(':')?;
        Some((a.parse().ok()?, b.parse().ok()?))
    }) {
        p.leaf_size_m = (a, b);
    }
    let scene = Arc::new(forest_with(1, &p));
    let tris: usize = scene.objects.iter().map(|o| o.triangle_count()).sum();
    // Cells centred between four trees, spread over the middle half of the forest.
    let cells: Vec<ViewCell> =
        if let Some(c) = std::env::var("CELL").ok().and_then(|s| s.parse().ok()) {
            vec![c]
        } else {
            p.cells_between_trees(cell_m, want)
        };
    println!(
        "dense forest: {} trees, {} triangles, {} cells of {cell_m} m; truth {samples} viewpoints at {res} px; {} threads",
        scene.objects.len(),
        tris,
        cells.len(),
        rayon::current_num_threads()
    );
    let t = Instant::now();
    let ts = TruthScene::new(&scene);
    let opts = TruthOptions {
        samples,
        resolution_px: res,
        ..TruthOptions::default()
    };
    let truths: Vec<_> = cells
        .par_iter()
        .map(|c| ts.ground_truth(c, &opts))
        .collect();
    let n = scene.objects.len() as f64;
    let vs_hidden: f64 = truths
        .iter()
        .map(|t| 1.0 - t.visible.len() as f64 / n)
        .sum::<f64>()
        / truths.len().max(1) as f64;
    println!(
        "ground truth: {:.1} % hidden (mean |VS| {:.1}) in {:.1} s",
        100.0 * vs_hidden,
        truths.iter().map(|t| t.visible.len()).sum::<usize>() as f64 / truths.len().max(1) as f64,
        t.elapsed().as_secs_f64()
    );
    let tri: Vec<usize> = scene.objects.iter().map(|o| o.triangle_count()).collect();
    let base = Params {
        resolution_px: std::env::var("RES")
            .ok()
            .and_then(|s| s.parse::<usize>().ok())
            .map(|r| r.next_power_of_two())
            .unwrap_or(Params::default().resolution_px),
        kernel_px: std::env::var("KERNEL")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(Params::default().kernel_px),
        sweep_start_m: std::env::var("START")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(Params::default().sweep_start_m),
        sweep_reach_m: std::env::var("REACH")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(Params::default().sweep_reach_m),
        extension: std::env::var("EXT")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(Params::default().extension),
        ..Params::default()
    };
    let mut variants: Vec<(String, Params)> = vec![("plain".into(), base.clone())];
    for &k in &planes {
        variants.push((
            format!("sweep {k}"),
            Params {
                sweep: true,
                sweep_planes: k,
                ..base.clone()
            },
        ));
    }
    for (label, params) in variants {
        let t = Instant::now();
        let m = ExtProj::new(scene.clone(), params);
        let prep = t.elapsed().as_secs_f64();
        let mut per_cell = Vec::new();
        let mut culled_tri = 0.0;
        for (c, truth) in cells.iter().zip(&truths) {
            let t = Instant::now();
            let pvs = match m.pvs(c) {
                Ok(p) => p,
                Err(e) => {
                    eprintln!("error: {e}");
                    std::process::exit(1);
                }
            };
            let s = t.elapsed().as_secs_f64();
            let kept: usize = pvs.iter().map(|&i| tri[i as usize]).sum();
            culled_tri += 1.0 - kept as f64 / tris.max(1) as f64;
            per_cell.push(compare(scene.objects.len(), &pvs, truth, s));
        }
        if let (Some(dir), true) = (std::env::var_os("SWEEP_DEBUG"), m.params.sweep) {
            let dir = std::path::PathBuf::from(dir);
            let sw = sightline_methods::ext_proj::Sweep::run(&m, &cells[0], None);
            for (k, sp) in sw.planes.iter().enumerate() {
                let n = sp.umbra.n;
                let mut img = format!("P5 {n} {n} 255\n").into_bytes();
                for j in (0..n).rev() {
                    img.extend((0..n).map(|i| if sp.umbra.black[j * n + i] { 0u8 } else { 255 }));
                }
                let _ = std::fs::write(
                    dir.join(format!("plane-{:?}-{k:02}.pgm", sp.plane.dir)),
                    img,
                );
                println!(
                    "    {:?} w {:7.2} (cell far {:6.2}) black {:6} / {}",
                    sp.plane.dir,
                    sp.plane.x,
                    sp.cell.max.x,
                    sp.umbra.count(),
                    sp.umbra.n * sp.umbra.n
                );
            }
        }
        let r = aggregate(m.name(), per_cell);
        println!(
            "{label:>9}: missed {:3}  over median {:6.2} p90 {:6.2}  hidden {:5.1} %  culled triangles {:5.1} %  {:9.1} ms/cell median (prepare {:.1} s)",
            r.missed,
            r.over_median,
            r.over_p90,
            100.0 * r.hidden_fraction,
            100.0 * culled_tri / cells.len().max(1) as f64,
            r.pvs_ms_median,
            prep
        );
        for c in &r.per_cell {
            for x in &c.missed {
                println!(
                    "    missed id {} from {:?} dir {:?}",
                    x.id, x.viewpoint, x.direction
                );
            }
        }
    }
}
