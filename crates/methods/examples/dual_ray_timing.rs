//! Timings of `dual-ray` on a generated metropolis (Koltun et al. 2001, Table 1 setting):
//! `cargo run --release -p sightline-methods --example dual_ray_timing -- [BUILDINGS]
//! [CELL_SIZE] [CELLS] [RESOLUTION] [MODE]`.
//!
//! MODE is `cells` (default: median ms per cell, single thread, and the traversal
//! counters), `nine` (the 9-cell neighbourhood on a 2-thread pool), `check` (the
//! discretized PVS contains the exact one on every cell) or `table1` (the full table,
//! resolutions 16..256 × cells 50/100/300 m, CELLS cells per size).

use sightline_geom::ViewCell;
use sightline_methods::dual_ray::{crossing_cells, table1, DualRay, Planarity};
use sightline_scene::generate::metropolis;
use std::sync::Arc;
use std::time::Instant;

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        0.0
    } else {
        v[v.len() / 2]
    }
}

/// CPU time of the calling thread (ns), from Linux's `/proc/thread-self/schedstat`:
/// steadier than wall time on a shared machine.
fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(Ok(100_000), |s| s.parse())?;
    let size: f64 = args.get(2).map_or(Ok(100.0), |s| s.parse())?;
    let count: usize = args.get(3).map_or(Ok(9), |s| s.parse())?;
    let res: u32 = args.get(4).map_or(Ok(128), |s| s.parse())?;
    let mode = args.get(5).map_or("cells", |s| s.as_str());
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
        "cells" => {
            let mut ms = Vec::new();
            let mut cpu = Vec::new();
            for c in &cells {
                let t = Instant::now();
                let c0 = thread_cpu_ns();
                let (pvs, st) = m.pvs_with_stats(c);
                let dt = t.elapsed().as_secs_f64() * 1e3;
                if let (Some(a), Some(b)) = (c0, thread_cpu_ns()) {
                    cpu.push((b - a) as f64 * 1e-6);
                }
                println!("{c}: {dt:.1} ms, pvs {}, {st:?}", pvs.len());
                ms.push(dt);
            }
            println!(
                "{size} m cells at {res}²: median {:.1} ms/cell over {} cells (single thread; \
                 CPU median {:.1} ms, total {:.0} ms)",
                median(&mut ms),
                cells.len(),
                median(&mut cpu),
                cpu.iter().sum::<f64>()
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
                median(&mut ms)
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
    Ok(())
}
