//! Where `erosion` is loose on a real scene: `cargo run --release -p sightline-methods
//! --example erosion_loose -- SCENE CELLS.json [METHOD] [REFERENCE]` (CELLS.json from
//! `erosion_street_cells`; METHOD defaults to `erosion`, REFERENCE to `dual-ray`).
//!
//! For every cell: the ground truth (`check`'s sampled oracle), the PVS of METHOD and of
//! REFERENCE, and the objects METHOD keeps that are not seen, counted by their distance
//! to the cell, by their top height against the highest occluder top within 25 m of the
//! cell, and by whether REFERENCE keeps them too (then the looseness is shared: the
//! object is hard to prove hidden; otherwise it is METHOD's own). The ground truth of
//! each cell is kept in `CELLS.json.truth` (one line of ids per cell) and read from there
//! on later runs, so that variants of a method are compared on the same sets cheaply.

use rayon::prelude::*;
use sightline_core::check::{TruthOptions, TruthScene};
use sightline_geom::{Aabb2, ViewCell};
use sightline_methods::{create, MethodOptions};
use sightline_scene::import::{load, ImportOptions};
use std::sync::Arc;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: erosion_loose SCENE CELLS.json [METHOD] [REFERENCE]";
    let scene = Arc::new(load(
        std::path::Path::new(args.get(1).ok_or(usage)?),
        &ImportOptions::default(),
    )?);
    // A JSON array of `[x0, y0, z0, x1, y1, z1]` rows.
    let text = std::fs::read_to_string(args.get(2).ok_or(usage)?)?;
    let nums = text
        .split(|c: char| c == '[' || c == ']' || c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .map(str::parse::<f64>)
        .collect::<Result<Vec<f64>, _>>()?;
    let cells = nums
        .chunks_exact(6)
        .map(|c| ViewCell::from_array([c[0], c[1], c[2], c[3], c[4], c[5]]))
        .collect::<Result<Vec<ViewCell>, _>>()?;
    let name = args.get(3).map_or("erosion", |s| s.as_str());
    let reference = args.get(4).map_or("dual-ray", |s| s.as_str());
    let method = create(name, scene.clone(), &MethodOptions::default())?;
    let refm = create(reference, scene.clone(), &MethodOptions::default())?;
    let ts = TruthScene::new(&scene);
    let bands = [25.0, 50.0, 100.0, 200.0, f64::INFINITY];
    let mut by_dist = [[0usize; 2]; 5];
    let (mut taller, mut lower) = (0usize, 0usize);
    let mut overs = Vec::new();
    let mut ref_overs = Vec::new();
    let mut ms = Vec::new();
    let cache = format!("{}.truth", args[2]);
    let truths: Vec<Vec<u32>> = match std::fs::read_to_string(&cache) {
        Ok(text) if text.lines().count() == cells.len() => text
            .lines()
            .map(|l| l.split_whitespace().map(str::parse).collect())
            .collect::<Result<_, _>>()?,
        _ => {
            let t: Vec<Vec<u32>> = cells
                .par_iter()
                .map(|c| ts.ground_truth(c, &TruthOptions::default()).visible)
                .collect();
            let text: Vec<String> = t
                .iter()
                .map(|v| {
                    v.iter()
                        .map(|i| i.to_string())
                        .collect::<Vec<_>>()
                        .join(" ")
                })
                .collect();
            let tmp = format!("{cache}.tmp");
            std::fs::write(&tmp, text.join("\n") + "\n")?;
            std::fs::rename(&tmp, &cache)?;
            t
        }
    };
    let mut missed = 0usize;
    for (cell, visible) in cells.iter().zip(&truths) {
        let t = Instant::now();
        let pvs = method.pvs(cell)?;
        ms.push(t.elapsed().as_secs_f64() * 1e3);
        let rpvs = refm.pvs(cell)?;
        missed += visible
            .iter()
            .filter(|i| pvs.binary_search(i).is_err())
            .count();
        let vs = visible.len().max(1) as f64;
        overs.push(pvs.len() as f64 / vs);
        ref_overs.push(rpvs.len() as f64 / vs);
        let rect = Aabb2::new(cell.min.truncate(), cell.max.truncate());
        let near_top = scene
            .objects
            .iter()
            .filter(|o| o.bounds.xy().expand(0.0).intersects(&rect.expand(25.0)))
            .flat_map(|o| o.inner.iter().map(|p| p.top))
            .fold(0.0f64, f64::max);
        for &id in &pvs {
            if visible.binary_search(&id).is_ok() {
                continue;
            }
            let o = &scene.objects[id as usize];
            let b = o.bounds.xy();
            let dx = (b.min.x - rect.max.x).max(rect.min.x - b.max.x).max(0.0);
            let dy = (b.min.y - rect.max.y).max(rect.min.y - b.max.y).max(0.0);
            let d = dx.hypot(dy);
            let band = bands.iter().position(|&x| d < x).unwrap_or(4);
            let shared = rpvs.binary_search(&id).is_ok();
            by_dist[band][usize::from(shared)] += 1;
            if o.bounds.max.z > near_top {
                taller += 1;
            } else {
                lower += 1;
            }
        }
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        (v[v.len() / 2], v[(v.len() * 9 / 10).min(v.len() - 1)])
    };
    let (om, op) = med(&mut overs);
    let (rm, rp) = med(&mut ref_overs);
    let (mm, _) = med(&mut ms);
    println!(
        "{name}: {} cells, missed {missed}, over median {om:.3} p90 {op:.3}, {mm:.0} ms/cell; {reference}: over {rm:.3} / {rp:.3}",
        cells.len()
    );
    println!("kept but not seen, by distance to the cell (own / also kept by {reference}):");
    for (k, c) in by_dist.iter().enumerate() {
        let lo = if k == 0 { 0.0 } else { bands[k - 1] };
        println!("  {lo:>4} m and more: {} / {}", c[0], c[1]);
    }
    println!("  taller than every occluder within 25 m: {taller}, not: {lower}");
    Ok(())
}
