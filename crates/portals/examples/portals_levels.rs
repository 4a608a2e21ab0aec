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
//!
//! The product form of this table, with plots and medians of repeated runs, is
//! `sightline bench --indoor-only --levels FOLDER` (same figures, from
//! `sightline_portals::reference`).

use sightline_portals::reference::compare_with_reference;
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
    sightline_stats::memory_kib().1 as f64 / 1024.0
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
        portals.solve_all(Mode::Full);
        let full_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        portals.solve_all(Mode::Fast);
        let fast_ms = t.elapsed().as_secs_f64() * 1e3;
        // The flows are cached: the comparisons cost the oracle only.
        let full = compare_with_reference(&portals, Mode::Full, sources_n, 16);
        let fast = compare_with_reference(&portals, Mode::Fast, 0, 16);
        if full.missed_pairs > 0 {
            eprintln!("{}: {} MISSED pairs", path.display(), full.missed_pairs);
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
            full.leaves_ratio(),
            fast.leaves_ratio(),
            full.faces_ratio(),
            fast.faces_ratio(),
            full.sources,
            full.missed_pairs,
            full.reference_only_pairs,
            full.reference_only_clear,
            peak_rss_mb()
        );
    }
}
