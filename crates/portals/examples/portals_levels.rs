//! Per level: leaves, portals, full and fast solve time, Σ|PVS| / Σ|vis reference|
//! for leaves, faces kept over the faces of the reference's visible leaves, misses
//! against the ray oracle, peak memory.
//!
//! ```text
//! cargo run --release -p sightline-portals --example portals_levels [LEVEL.bsp ...]
//! ```
//! Without arguments: every `../shared/data/quake/*.bsp` (else `data/quake/*.bsp`).
//! `PORTALS_SOURCES` (default 60) source leaves are checked against the oracle: 16
//! segments per pair outside both PVS, 256 per pair the reference has and we lack.

use sightline_portals::oracle::{pair_visible, sample_leaf, Rng};
use sightline_portals::{Mode, Portals};
use sightline_scene::import::bsp::load_bsp;
use std::path::PathBuf;
use std::time::Instant;

fn levels() -> Vec<PathBuf> {
    let args: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    if !args.is_empty() {
        return args;
    }
    for dir in ["../shared/data/quake", "data/quake", "../../data/quake"] {
        if let Ok(rd) = std::fs::read_dir(dir) {
            let mut v: Vec<PathBuf> = rd
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|e| e == "bsp"))
                .collect();
            v.sort();
            if !v.is_empty() {
                return v;
            }
        }
    }
    Vec::new()
}

fn peak_rss_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1)?.parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1024.0)
}

fn main() {
    let sources_n: usize = std::env::var("PORTALS_SOURCES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(60);
    println!("| level | leaves | visleafs | portals | build ms | full ms | fast ms | Σfull/Σref | Σfast/Σref | faces full/ref-leaf faces | faces fast/ref-leaf faces | sources | misses | ref-only pairs (oracle-clear) | peak MB |");
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for path in levels() {
        let level = match load_bsp(&path) {
            Ok(l) => l,
            Err(e) => {
                eprintln!("{e}");
                continue;
            }
        };
        let t = Instant::now();
        let portals = Portals::build(&level).expect("portals");
        let build_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let full = portals.solve_all(Mode::Full);
        let full_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let fast = portals.solve_all(Mode::Fast);
        let fast_ms = t.elapsed().as_secs_f64() * 1e3;
        let (mut sf, mut sfa, mut sr) = (0usize, 0usize, 0usize);
        let (mut ff, mut ffa, mut fr) = (0usize, 0usize, 0usize);
        for leaf in 1..=level.visleafs {
            let row = level.reference_row(leaf);
            sf += full[leaf as usize].leaves.len();
            sfa += fast[leaf as usize].leaves.len();
            sr += row.len();
            let mut ref_faces: Vec<u32> = row
                .iter()
                .flat_map(|&l| level.leaves[l as usize].faces.iter().copied())
                .collect();
            ref_faces.sort_unstable();
            ref_faces.dedup();
            fr += ref_faces.len();
            ff += full[leaf as usize].faces.len();
            ffa += fast[leaf as usize].faces.len();
        }
        // Oracle.
        let mut rng = Rng::new(7);
        let points: Vec<Vec<[f64; 3]>> = (0..=level.visleafs)
            .map(|l| {
                if level.is_view_leaf(l) {
                    sample_leaf(&level, l, 16, &mut rng)
                } else {
                    Vec::new()
                }
            })
            .collect();
        let open: Vec<u32> = (1..=level.visleafs)
            .filter(|&l| level.is_view_leaf(l))
            .collect();
        let k = sources_n.min(open.len());
        let (mut misses, mut ref_only, mut ref_only_clear) = (0usize, 0usize, 0usize);
        for i in 0..k {
            let s = open[i * open.len() / k];
            let row = level.reference_row(s);
            let pvs = &full[s as usize];
            for other in 1..=level.visleafs {
                if pvs.leaves.binary_search(&other).is_ok() {
                    continue;
                }
                let in_ref = row.binary_search(&other).is_ok();
                let segs = if in_ref { 256 } else { 16 };
                let clear = pair_visible(
                    &level,
                    &points[s as usize],
                    &points[other as usize],
                    segs,
                    &mut rng,
                );
                if in_ref {
                    ref_only += 1;
                    ref_only_clear += usize::from(clear);
                }
                if clear {
                    eprintln!("{}: MISS leaf {s} -> {other}", path.display());
                    misses += 1;
                }
            }
        }
        println!(
            "| {} | {} | {} | {} | {:.0} | {:.0} | {:.0} | {:.3} | {:.3} | {:.3} | {:.3} | {} | {} | {} ({}) | {:.0} |",
            path.file_stem().unwrap_or_default().to_string_lossy(),
            level.leaves.len(),
            level.visleafs,
            portals.portals().len(),
            build_ms,
            full_ms,
            fast_ms,
            sf as f64 / sr as f64,
            sfa as f64 / sr as f64,
            ff as f64 / fr as f64,
            ffa as f64 / fr as f64,
            k,
            misses,
            ref_only,
            ref_only_clear,
            peak_rss_mb()
        );
    }
}
