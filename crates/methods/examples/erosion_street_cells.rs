//! Street cells of a scene as a cells.json for `sightline check --cells`:
//! `cargo run --release -p sightline-methods --example erosion_street_cells -- SCENE
//! [SIZE] [COUNT] > cells.json`.
//!
//! A street cell is a square of `SIZE` m at z 1.5..2.0 whose whole box is free of blocks
//! (`check::street_cells`: a 5 × 5 grid of probes at both heights), on the scene's grid
//! of `SIZE` and on the same grid shifted by half a cell in x, y and both (dense cities
//! have few free squares on one grid), without overlapping duplicates; `COUNT` of them
//! spread evenly over those nearest the scene's middle, in a deterministic order.

use sightline_core::check::{near_middle, street_cells, Clearance};
use sightline_geom::ViewCell;
use sightline_scene::import::{load, ImportOptions};
use sightline_scene::Scene;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let path = args
        .get(1)
        .ok_or("usage: erosion_street_cells SCENE [SIZE] [COUNT]")?;
    let size: f64 = args.get(2).map_or(Ok(25.0), |s| s.parse())?;
    let count: usize = args.get(3).map_or(Ok(50), |s| s.parse())?;
    let scene = load(std::path::Path::new(path), &ImportOptions::default())?;
    let mut all: Vec<ViewCell> = Vec::new();
    for (dx, dy) in [(0.0, 0.0), (0.5, 0.0), (0.0, 0.5), (0.5, 0.5)] {
        let shifted = shift_bounds(&scene, dx * size, dy * size);
        for c in street_cells(&shifted, size, (1.5, 2.0), usize::MAX, Clearance::Box) {
            // Keep a cell only if it overlaps none already kept.
            let overlaps = all.iter().any(|k| {
                k.min.x < c.max.x && c.min.x < k.max.x && k.min.y < c.max.y && c.min.y < k.max.y
            });
            if !overlaps {
                all.push(c);
            }
        }
    }
    eprintln!("{} free {size} m street cells in {path}", all.len());
    // As the bench's picker: prefer cells near the middle of the scene, then spread evenly
    // over the nearest 4 × COUNT.
    let mut picked = near_middle(&scene, &all, count, 4);
    picked.sort_by(|a, b| {
        (a.min.y, a.min.x)
            .partial_cmp(&(b.min.y, b.min.x))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    // JSON by hand (f64 `Debug` is valid JSON for finite numbers).
    let rows: Vec<String> = picked
        .iter()
        .map(|c| {
            let v: Vec<String> = c.to_array().iter().map(|x| format!("{x:?}")).collect();
            format!("[{}]", v.join(","))
        })
        .collect();
    println!("[\n{}\n]", rows.join(",\n"));
    Ok(())
}

/// The scene with its bounds moved by `(dx, dy)` at the low corner (so that
/// `street_cells`, which starts its grid there, uses a shifted grid).
fn shift_bounds(scene: &Scene, dx: f64, dy: f64) -> Scene {
    let mut s = scene.clone();
    s.bounds.min.x += dx;
    s.bounds.min.y += dy;
    s
}
