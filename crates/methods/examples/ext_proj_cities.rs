//! ext-proj on the street cells of a city, against the ground truth and erosion (run in
//! release):
//! `cargo run --release -p sightline-methods --example ext_proj_cities -- SCENE [SIZE] [COUNT] [CACHE]`
//!
//! Cells: `check::street_cells` (SIZE m, default 25, z 1.5..2, COUNT default 50). The
//! ground truth (default `TruthOptions`) is computed once and cached in `CACHE`
//! (default `/tmp/ext_proj_cities_<scene>_<size>_<count>.txt`), so variants of ext-proj
//! can be compared quickly; erosion runs on the same cells every time, timed as
//! ext-proj is. Prints, for erosion and per variant: missed, `over` = |PVS| / |VS|
//! median and p90, mean hidden %, median ms/cell (single thread, preparation excluded)
//! and the mean PVS size. `EXTPROJ_VARIANTS` selects the variants (comma-separated,
//! see [`variant`]: `default`, or settings such as `improved=0` or `res=512+sa=0`);
//! `EXTPROJ_DIAG=1` lists, per cell, the objects erosion hides and ext-proj keeps;
//! `EXTPROJ_DIAG=2` classifies them by their best plane: Projection off every plane,
//! or the fraction of its pixels covered by nearer occluders (≥ 90 %: a near miss).

use sightline_core::check::{ground_truth, street_cells, Clearance, TruthOptions};
use sightline_geom::ViewCell;
use sightline_methods::ext_proj::occludee_projection;
use sightline_methods::ext_proj::{depth_down, pixel_range};
use sightline_methods::ext_proj::{ExtProj, Params};
use sightline_methods::{create, MethodOptions, VisibilityMethod};
use sightline_scene::import::{load, ImportOptions};
use std::collections::BTreeSet;
use std::sync::Arc;
use std::time::Instant;

fn ids(s: &str) -> Vec<u32> {
    s.split_whitespace()
        .filter_map(|t| t.parse().ok())
        .collect()
}

fn join(v: &[u32]) -> String {
    v.iter()
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(" ")
}

fn read_cache(path: &str, n: usize) -> Option<Vec<Vec<u32>>> {
    let text = std::fs::read_to_string(path).ok()?;
    let lines: Vec<&str> = text.lines().collect();
    (lines.len() == n).then(|| lines.iter().map(|l| ids(l)).collect())
}

/// A variant: `default`, or `key=value` settings joined by `+` over the defaults
/// (`res`, `improved` 0/1, `ext`, `sa` solid angle, `cap` max occluders, `ppd`,
/// `cands`, `splits`, `budget` (none = off), `minm`).
fn variant(name: &str) -> Option<Params> {
    let mut p = Params::default();
    if name == "default" {
        return Some(p);
    }
    for kv in name.split('+') {
        let (k, v) = kv.split_once('=')?;
        match k {
            "res" => p.resolution_px = v.parse::<usize>().ok()?.next_power_of_two(),
            "improved" => p.improved = v == "1",
            "ext" => p.extension = v.parse().ok()?,
            "sa" => p.solid_angle = v.parse().ok()?,
            "cap" => p.max_occluders = v.parse().ok()?,
            "ppd" => p.planes_per_direction = v.parse().ok()?,
            "cands" => p.plane_candidates = v.parse().ok()?,
            "splits" => p.occludee_splits = v.parse().ok()?,
            "budget" => p.adaptive_budget = v.parse().ok(),
            "minm" => p.adaptive_min_m = v.parse().ok()?,
            _ => return None,
        }
    }
    Some(p)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .ok_or("usage: ext_proj_cities SCENE [SIZE] [COUNT] [CACHE]")?;
    let size: f64 = args.get(2).map_or(Ok(25.0), |s| s.parse())?;
    let count: usize = args.get(3).map_or(Ok(50), |s| s.parse())?;
    let stem = std::path::Path::new(path)
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("scene")
        .to_string();
    let cache = args
        .get(4)
        .cloned()
        .unwrap_or_else(|| format!("/tmp/ext_proj_cities_{stem}_{size}_{count}.txt"));
    let scene = Arc::new(load(std::path::Path::new(path), &ImportOptions::default())?);
    let cells: Vec<ViewCell> = street_cells(&scene, size, (1.5, 2.0), count, Clearance::Box);
    let n_obj = scene.objects.len();
    eprintln!("{stem}: {n_obj} objects, {} cells of {size} m", cells.len());
    let truth = match read_cache(&cache, cells.len()) {
        Some(c) => c,
        None => {
            let t = Instant::now();
            let truth: Vec<Vec<u32>> = cells
                .iter()
                .map(|c| ground_truth(&scene, c, &TruthOptions::default()).visible)
                .collect();
            eprintln!("truth: {:.1} s", t.elapsed().as_secs_f64());
            let mut text = String::new();
            for v in &truth {
                text.push_str(&join(v));
                text.push('\n');
            }
            std::fs::write(&cache, text)?;
            truth
        }
    };
    // Erosion on the same cells, timed the same way as ext-proj (single thread,
    // preparation excluded).
    let ero = create("erosion", scene.clone(), &MethodOptions::default())?;
    let mut erosion_ms = Vec::new();
    let erosion: Vec<Vec<u32>> = cells
        .iter()
        .map(|c| {
            let t = Instant::now();
            let p = ero.pvs(c).unwrap_or_else(|_| (0..n_obj as u32).collect());
            erosion_ms.push(t.elapsed().as_secs_f64() * 1e3);
            p
        })
        .collect();
    let over = |pvs: &[Vec<u32>]| -> (usize, Vec<f64>, f64, f64) {
        let mut missed = 0;
        let mut ratios = Vec::new();
        let mut hidden = 0.0;
        let mut mean = 0.0;
        for (p, t) in pvs.iter().zip(&truth) {
            let ps: BTreeSet<u32> = p.iter().copied().collect();
            missed += t.iter().filter(|i| !ps.contains(i)).count();
            ratios.push(p.len() as f64 / t.len().max(1) as f64);
            hidden += 1.0 - p.len() as f64 / n_obj.max(1) as f64;
            mean += p.len() as f64;
        }
        let k = pvs.len().max(1) as f64;
        (missed, ratios, 100.0 * hidden / k, mean / k)
    };
    let print = |name: &str, pvs: &[Vec<u32>], ms: f64| {
        let (missed, r, hidden, mean) = over(pvs);
        println!(
            "{stem} {name:>10}: cells {} missed {missed} over median {:.2} p90 {:.2} hidden {hidden:.1} % mean PVS {mean:.1} ms/cell {:.0}",
            pvs.len(),
            sightline_stats::quantile(&r, 0.5),
            sightline_stats::quantile(&r, 0.9),
            ms,
        );
    };
    print(
        "erosion",
        &erosion,
        sightline_stats::quantile(&erosion_ms, 0.5),
    );
    let variants = std::env::var("EXTPROJ_VARIANTS").unwrap_or_else(|_| "default".into());
    for name in variants.split(',') {
        let Some(params) = variant(name.trim()) else {
            eprintln!("unknown variant {name}");
            continue;
        };
        let m = ExtProj::new(scene.clone(), params);
        let mut ms = Vec::new();
        let mut pvs = Vec::new();
        for c in &cells {
            let t = Instant::now();
            pvs.push(m.pvs(c).unwrap_or_else(|_| (0..n_obj as u32).collect()));
            ms.push(t.elapsed().as_secs_f64() * 1e3);
        }
        print(name.trim(), &pvs, sightline_stats::quantile(&ms, 0.5));
        if std::env::var("EXTPROJ_DIAG").is_ok_and(|v| v == "2") {
            let (mut off, mut near, mut far, mut total) = (0usize, 0usize, 0usize, 0usize);
            for (k, (p, e)) in pvs.iter().zip(&erosion).enumerate() {
                let es: BTreeSet<u32> = e.iter().copied().collect();
                let maps = m.plane_maps(&cells[k]);
                for &id in p.iter().filter(|i| !es.contains(i)) {
                    total += 1;
                    let b = scene.objects[id as usize].bounds;
                    let mut best: Option<f64> = None;
                    for pm in &maps {
                        let occ = pm.plane.dir.box_to_local(b.min, b.max);
                        let Some((rect, depth)) =
                            occludee_projection(&pm.cell, &occ, pm.plane.x, true)
                        else {
                            continue;
                        };
                        let r = pixel_range(
                            pm.plane.to_px(rect.min),
                            pm.plane.to_px(rect.max),
                            pm.map.n,
                        );
                        let Some([i0, j0, i1, j1]) = r else { continue };
                        let d = depth_down(depth);
                        let mut ok = 0usize;
                        for j in j0..=j1 {
                            for i in i0..=i1 {
                                ok += (pm.map.at(i, j) < d) as usize;
                            }
                        }
                        let f = ok as f64 / ((i1 + 1 - i0) * (j1 + 1 - j0)) as f64;
                        best = Some(best.map_or(f, |g: f64| g.max(f)));
                    }
                    match best {
                        None => off += 1,
                        Some(f) if f >= 0.9 => near += 1,
                        Some(_) => far += 1,
                    }
                }
            }
            println!(
                "  kept but erosion-hidden: {total}: off every plane {off}, best plane >= 90 % covered {near}, < 90 % {far}"
            );
        }
        if std::env::var("EXTPROJ_DIAG").is_ok_and(|v| v == "1") {
            for (k, (p, e)) in pvs.iter().zip(&erosion).enumerate() {
                let es: BTreeSet<u32> = e.iter().copied().collect();
                let extra: Vec<u32> = p.iter().copied().filter(|i| !es.contains(i)).collect();
                println!(
                    "  cell {k} {} |VS| {} |erosion| {} |ext| {} kept-but-erosion-hidden {:?}",
                    cells[k],
                    truth[k].len(),
                    e.len(),
                    p.len(),
                    extra
                );
            }
        }
    }
    Ok(())
}
