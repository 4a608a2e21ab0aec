//! Timings of `dual-ray` on a generated metropolis (Koltun et al. 2001, Table 1 setting):
//! `cargo run --release -p sightline-methods --example dual_ray_timing -- [BUILDINGS]
//! [CELL_SIZE] [CELLS] [RESOLUTION] [MODE]`.
//!
//! MODE is `cells` (default: median ms per cell, single thread, and the traversal
//! counters), `vo` (the same with the cell's strips and virtual occluders on),
//! `compare` (with and without them: medians, and the PVS with them is contained in the
//! one without), `seed` (the seed rays alone: CPU ms per cell), `nine` (the 9-cell
//! neighbourhood on a 2-thread pool), `check` (the discretized PVS contains the exact
//! one on every cell) or `table1` (the full table,
//! resolutions 16..256 × cells 50/100/300 m, CELLS cells per size) or `scaling`
//! (metropolises of 1k, 10k, 150k and 1M buildings up to BUILDINGS: median ms per cell,
//! |PVS|, ms per visible object, peak memory, and the fitted exponents of ms and |PVS|
//! against the number of buildings).

use sightline_geom::ViewCell;
use sightline_methods::dual_ray::{crossing_cells, table1, DualRay, Planarity};
use sightline_scene::generate::metropolis;
use std::sync::Arc;
use std::time::Instant;

/// Median, 0 for none (the printed tables' convention).
fn median(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        sightline_stats::median(v)
    }
}

/// CPU time of the calling thread (ns), from Linux's `/proc/thread-self/schedstat`:
/// steadier than wall time on a shared machine.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// Peak resident memory of the process (kB), from `/proc/self/status`.
fn peak_rss_kb() -> Option<u64> {
    Some(sightline_stats::memory_kib().1).filter(|&kb| kb > 0)
}

/// Timings of a run over cells.
struct Timing {
    /// Median wall and thread CPU ms per cell.
    ms: f64,
    cpu: f64,
    /// Thread CPU ms of the whole run.
    cpu_total: f64,
    pvs: Vec<Vec<u32>>,
}

/// Time `m` over `cells`, printing each cell unless `quiet`.
fn time_cells(m: &DualRay, cells: &[ViewCell], quiet: bool) -> Timing {
    let mut ms = Vec::new();
    let mut cpu = Vec::new();
    let mut out = Vec::new();
    for c in cells {
        let t = Instant::now();
        let c0 = thread_cpu_ns();
        let (pvs, st) = m.pvs_with_stats(c);
        let dt = t.elapsed().as_secs_f64() * 1e3;
        if let (Some(a), Some(b)) = (c0, thread_cpu_ns()) {
            cpu.push((b - a) as f64 * 1e-6);
        }
        if !quiet {
            println!("{c}: {dt:.1} ms, pvs {}, {st:?}", pvs.len());
        }
        ms.push(dt);
        out.push(pvs);
    }
    Timing {
        ms: median(&ms),
        cpu: median(&cpu),
        cpu_total: cpu.iter().sum(),
        pvs: out,
    }
}

/// The `scaling` mode: one metropolis per size up to `max_n`.
fn scaling(max_n: usize, size: f64, count: usize, res: u32) {
    let mut ms_pts = Vec::new();
    let mut pvs_pts = Vec::new();
    println!(
        "| buildings | prepare s | ms/cell (wall) | PVS | ms per visible object | peak RSS GB |"
    );
    println!("|---|---|---|---|---|---|");
    for n in [1_000, 10_000, 150_000, 1_000_000] {
        if n > max_n {
            break;
        }
        let scene = Arc::new(metropolis(1, n));
        let t = Instant::now();
        let m = DualRay::new(
            "dual-ray",
            scene.clone(),
            Planarity::Discrete { resolution_px: res },
        );
        let prep = t.elapsed().as_secs_f64();
        let cells = crossing_cells(&scene, size, count);
        // Wall time: the thread CPU time of `schedstat` comes in scheduler ticks (4 ms on
        // the test VM), too coarse for the small cities.
        let Timing { ms: cpu, pvs, .. } = time_cells(&m, &cells, true);
        let sizes: Vec<f64> = pvs.iter().map(|p| p.len() as f64).collect();
        let pvs_med = median(&sizes);
        let rss = peak_rss_kb().map_or(f64::NAN, |kb| kb as f64 / 1048576.0);
        println!(
            "| {n} | {prep:.1} | {cpu:.1} | {pvs_med:.0} | {:.3} | {rss:.2} |",
            cpu / pvs_med.max(1.0)
        );
        ms_pts.push((n as f64, cpu));
        pvs_pts.push((n as f64, pvs_med));
    }
    if ms_pts.len() >= 2 {
        println!(
            "fitted exponents vs buildings: ms/cell {:.2}, |PVS| {:.2}",
            sightline_stats::loglog_slope(&ms_pts),
            sightline_stats::loglog_slope(&pvs_pts)
        );
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(Ok(100_000), |s| s.parse())?;
    let size: f64 = args.get(2).map_or(Ok(100.0), |s| s.parse())?;
    let count: usize = args.get(3).map_or(Ok(9), |s| s.parse())?;
    let res: u32 = args.get(4).map_or(Ok(128), |s| s.parse())?;
    let mode = args.get(5).map_or("cells", |s| s.as_str());
    if mode == "scaling" {
        scaling(n, size, count, res);
        if let Some(kb) = peak_rss_kb() {
            println!("peak RSS {:.2} GB", kb as f64 / 1048576.0);
        }
        return Ok(());
    }
    let t = Instant::now();
    let scene = Arc::new(metropolis(1, n));
    println!(
        "metropolis: {} objects, generated in {:.2}s",
        scene.objects.len(),
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let m = DualRay::new(
        "dual-ray",
        scene.clone(),
        Planarity::Discrete { resolution_px: res },
    );
    println!("prepared in {:.2}s", t.elapsed().as_secs_f64());
    let cells = crossing_cells(&scene, size, count);
    match mode {
        "compare" => {
            let with_vo = DualRay::new(
                "dual-ray",
                scene.clone(),
                Planarity::Discrete { resolution_px: res },
            )
            .with_virtual_occluders(true);
            let vo = time_cells(&with_vo, &cells, false);
            let plain = time_cells(&m, &cells, true);
            let mut sizes = (0usize, 0usize);
            for ((c, v), p) in cells.iter().zip(&vo.pvs).zip(&plain.pvs) {
                if let Some(id) = v.iter().find(|id| p.binary_search(id).is_err()) {
                    return Err(format!("{c}: object {id} only with virtual occluders").into());
                }
                sizes.0 += v.len();
                sizes.1 += p.len();
            }
            println!(
                "{size} m cells at {res}², {} cells: with VOs median {:.1} ms (CPU {:.1}), PVS \
                 total {}; without {:.1} ms (CPU {:.1}), PVS total {}",
                cells.len(),
                vo.ms,
                vo.cpu,
                sizes.0,
                plain.ms,
                plain.cpu,
                sizes.1
            );
        }
        "vo" => {
            let with_vo = DualRay::new(
                "dual-ray",
                scene.clone(),
                Planarity::Discrete { resolution_px: res },
            )
            .with_virtual_occluders(true);
            let t = time_cells(&with_vo, &cells, false);
            println!(
                "{size} m cells at {res}² with VOs: median {:.1} ms (CPU {:.1})",
                t.ms, t.cpu
            );
        }
        "cells" => {
            let t = time_cells(&m, &cells, false);
            println!(
                "{size} m cells at {res}²: median {:.1} ms/cell over {} cells (single thread; \
                 CPU median {:.1} ms, total {:.0} ms)",
                t.ms,
                cells.len(),
                t.cpu,
                t.cpu_total
            );
        }
        "seed" => {
            // The seed rays alone (crate::seed): wall ms per cell (the thread's CPU
            // time is counted in 4 ms ticks, as coarse as the figure).
            let mut ms = Vec::new();
            for c in &cells {
                let t = Instant::now();
                let seeded = m.seed_objects(c);
                ms.push(t.elapsed().as_secs_f64() * 1e3);
                println!("{c}: {} seeded", seeded.len());
            }
            println!(
                "{size} m cells: seed rays median {:.2} ms/cell over {} cells",
                median(&ms),
                cells.len()
            );
        }
        "nine" => {
            let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
            let mut ms = Vec::new();
            for c in &cells {
                let t = Instant::now();
                let nine = pool.install(|| m.pvs_with_neighbours(c));
                let dt = t.elapsed().as_secs_f64() * 1e3;
                let total: usize = nine.iter().map(|(_, p)| p.len()).sum();
                println!("{c}: 9 cells in {dt:.1} ms, {total} PVS entries");
                ms.push(dt);
            }
            println!(
                "9-cell neighbourhood of {size} m cells at {res}² on 2 threads: median {:.1} ms",
                median(&ms)
            );
        }
        "check" => {
            let exact = DualRay::new("dual-ray-exact", scene.clone(), Planarity::Exact);
            for c in &cells {
                let e = exact.pvs_with_stats(c).0;
                let d = m.pvs_with_stats(c).0;
                let lacking = e.iter().filter(|id| d.binary_search(id).is_err()).count();
                println!(
                    "{c}: exact {}, dual-ray {}, lacking {lacking}",
                    e.len(),
                    d.len()
                );
                if lacking > 0 {
                    return Err(format!("{c}: dual-ray lacks {lacking} exact objects").into());
                }
            }
        }
        "table1" => {
            let groups: Vec<(f64, Vec<ViewCell>)> = [50.0, 100.0, 300.0]
                .iter()
                .map(|s| (*s, crossing_cells(&scene, *s, count)))
                .collect();
            let rows = table1(scene.clone(), &groups, &[16, 32, 64, 128, 256]);
            println!(
                "| cell m | res | cells | ms median | ms mean | PVS mean | over-est. | tests |"
            );
            println!("|---|---|---|---|---|---|---|---|");
            for r in rows {
                println!(
                    "| {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.4} | {:.0} |",
                    r.cell_size_m,
                    if r.resolution_px == 0 {
                        "exact".to_string()
                    } else {
                        r.resolution_px.to_string()
                    },
                    r.cells,
                    r.ms_median,
                    r.ms_mean,
                    r.pvs_mean,
                    r.overestimation,
                    r.planar_tests_mean
                );
            }
        }
        other => return Err(format!("unknown mode {other}").into()),
    }
    if let Some(kb) = peak_rss_kb() {
        println!("peak RSS {:.2} GB", kb as f64 / 1048576.0);
    }
    Ok(())
}
