//! Stability and time of the ground truth: for street cells of a
//! scene, the visible set with the default options, with twice the viewpoints and with
//! twice the cube-face resolution, and how much it changes.
//!
//! `cargo run --release -p sightline-methods --example truth_stability -- SCENE CELLS.json
//! [COUNT] [SAMPLES] [RESOLUTION] [RAYS]` where `CELLS.json` comes from `sightline cells SCENE
//! --size S -o CELLS.json`. Of its cells, those whose whole box is free space (street
//! cells, tested on a 5 × 5 grid at both heights) are kept and `COUNT` (default 10) of
//! them are taken evenly spread. `SAMPLES` / `RESOLUTION` / `RAYS` (targeted rays per object) override the
//! base options.
//!
//! The change of a variant is `|VS_base Δ VS_variant| / |VS_base|` (symmetric
//! difference, so an object gained and one lost count twice).

use sightline_core::check::{street_cells_among, Clearance, TruthOptions, TruthScene};
use sightline_geom::ViewCell;
use sightline_scene::import::{load, ImportOptions};
use std::time::Instant;

fn sym_diff(a: &[u32], b: &[u32]) -> usize {
    let (mut i, mut k, mut n) = (0, 0, 0);
    while i < a.len() || k < b.len() {
        match (a.get(i), b.get(k)) {
            (Some(x), Some(y)) if x == y => {
                i += 1;
                k += 1;
            }
            (Some(x), Some(y)) if x < y => {
                n += 1;
                i += 1;
            }
            (Some(_), Some(_)) => {
                n += 1;
                k += 1;
            }
            (Some(_), None) => {
                n += 1;
                i += 1;
            }
            (None, _) => {
                n += 1;
                k += 1;
            }
        }
    }
    n
}

/// CPU time of the whole process (all threads), seconds (Linux; 0 elsewhere). On a
/// shared, loaded machine this is the robust figure: unloaded wall time on `n` cores is
/// about CPU time / `n` for the parallel phases.
fn cpu_s() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the command name `(…)`: utime and stime are fields 14 and 15.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |k: usize| f.get(k).and_then(|t| t.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(11) + ticks(12)) / 100.0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: truth_stability SCENE CELLS.json [COUNT] [SAMPLES] [RESOLUTION] [RAYS]";
    let path = args.get(1).ok_or(usage)?;
    let cells_path = args.get(2).ok_or(usage)?;
    let count: usize = args.get(3).map_or(Ok(10), |s| s.parse())?;
    let mut base = TruthOptions::default();
    if let Some(s) = args.get(4) {
        base.samples = s.parse()?;
    }
    if let Some(r) = args.get(5) {
        base.resolution_px = r.parse()?;
    }
    if let Some(r) = args.get(6) {
        base.targeted_rays_per_object = r.parse()?;
    }
    let scene = load(std::path::Path::new(path), &ImportOptions::default())?;
    let ts = TruthScene::new(&scene);
    // The cells file is a JSON array of `[x0, y0, z0, x1, y1, z1]` arrays.
    let text = std::fs::read_to_string(cells_path)?;
    let nums = text
        .split(|c: char| !(c.is_ascii_digit() || matches!(c, '-' | '+' | '.' | 'e' | 'E')))
        .filter(|t| !t.is_empty())
        .map(str::parse::<f64>)
        .collect::<Result<Vec<f64>, _>>()?;
    if nums.len() % 6 != 0 {
        return Err(format!("{cells_path}: not a list of 6-number cells").into());
    }
    let all: Vec<[f64; 6]> = nums
        .chunks_exact(6)
        .map(|c| [c[0], c[1], c[2], c[3], c[4], c[5]])
        .collect();
    let boxes: Vec<ViewCell> = all
        .iter()
        .filter_map(|a| ViewCell::from_array(*a).ok())
        .collect();
    let free = street_cells_among(&ts, &boxes, usize::MAX, Clearance::Box);
    // `count` of them, spread evenly.
    let cells = street_cells_among(&ts, &free, count, Clearance::Box);
    let variants = [
        ("2× samples", {
            let mut o = base.clone();
            o.samples *= 2;
            o
        }),
        ("2× resolution", {
            let mut o = base.clone();
            o.resolution_px *= 2;
            o
        }),
    ];
    println!(
        "scene {path}: {} objects; {} of {} cells are street cells, {} taken; base: {} samples, {} px, {} targeted rays/object",
        scene.objects.len(),
        free.len(),
        all.len(),
        cells.len(),
        base.samples,
        base.resolution_px,
        base.targeted_rays_per_object
    );
    println!();
    println!("Times: wall ms / CPU ms (all threads).");
    println!();
    println!("| cell | VS | by rays | ms | Δ 2× samples | ms | Δ 2× resolution | ms |");
    println!("|---|---|---|---|---|---|---|---|");
    let mut base_ms = Vec::new();
    let mut base_cpu = Vec::new();
    let mut changes = vec![Vec::new(); variants.len()];
    let mut var_ms = vec![Vec::new(); variants.len()];
    for c in &cells {
        let (t, c0) = (Instant::now(), cpu_s());
        let b = ts.ground_truth(c, &base);
        let ms = t.elapsed().as_secs_f64() * 1e3;
        let cpu = (cpu_s() - c0) * 1e3;
        base_ms.push(ms);
        base_cpu.push(cpu);
        let mut row = format!(
            "| {c} | {} | {} | {ms:.0} / {cpu:.0} |",
            b.visible.len(),
            b.found_by_rays
        );
        for (k, (_, o)) in variants.iter().enumerate() {
            let (t, c0) = (Instant::now(), cpu_s());
            let v = ts.ground_truth(c, o);
            let vms = t.elapsed().as_secs_f64() * 1e3;
            let vcpu = (cpu_s() - c0) * 1e3;
            let d = sym_diff(&b.visible, &v.visible);
            let rel = d as f64 / b.visible.len().max(1) as f64;
            changes[k].push(rel * 100.0);
            var_ms[k].push(vms);
            row += &format!(" {d} ({:.2} %) | {vms:.0} / {vcpu:.0} |", rel * 100.0);
        }
        println!("{row}");
    }
    println!();
    println!(
        "base: truth ms/cell median {:.0}, max {:.0}; CPU ms/cell median {:.0}, max {:.0}",
        sightline_stats::median(&base_ms),
        base_ms.iter().copied().fold(0.0, f64::max),
        sightline_stats::median(&base_cpu),
        base_cpu.iter().copied().fold(0.0, f64::max)
    );
    for (k, (name, _)) in variants.iter().enumerate() {
        let max = changes[k].iter().copied().fold(0.0, f64::max);
        let mean = changes[k].iter().sum::<f64>() / changes[k].len().max(1) as f64;
        println!(
            "{name}: VS change median {:.2} %, mean {mean:.2} %, max {max:.2} %; ms/cell median {:.0}",
            sightline_stats::median(&changes[k]),
            sightline_stats::median(&var_ms[k])
        );
    }
    Ok(())
}
