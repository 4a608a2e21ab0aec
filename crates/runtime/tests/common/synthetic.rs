//! A generated city (`sightline_scene::generate::city`) with its grid of free cells at
//! eye height and PVS-like rows that need no visibility computation: the objects near
//! the cell, those along its street axes, and one tall object in 29 farther out. Used
//! where the size of the file matters and the sets do not (the query bench, the
//! allocation test).

use sightline_geom::ViewCell;

/// The city of `buildings` buildings covered by about `target_cells` cells.
pub fn city_file(buildings: usize, target_cells: usize) -> Vec<u8> {
    let scene = sightline_scene::generate::city(1, buildings);
    let b = scene.bounds;
    let area = (b.max.x - b.min.x) * (b.max.y - b.min.y);
    let mut size = (area / target_cells as f64).sqrt();
    let mut cells: Vec<ViewCell> = Vec::new();
    for _ in 0..8 {
        cells = sightline_scene::cells::grid_cells(&scene, size, 1.5, 2.0).unwrap();
        let ratio = cells.len() as f64 / target_cells as f64;
        if (0.97..=1.03).contains(&ratio) {
            break;
        }
        size *= ratio.sqrt();
    }
    let centres: Vec<(f64, f64)> = scene
        .objects
        .iter()
        .map(|o| {
            (
                0.5 * (o.bounds.min.x + o.bounds.max.x),
                0.5 * (o.bounds.min.y + o.bounds.max.y),
            )
        })
        .collect();
    let sets: Vec<Vec<u32>> = cells
        .iter()
        .map(|c| {
            let m = c.center();
            centres
                .iter()
                .enumerate()
                .filter(|(k, &(x, y))| {
                    let (dx, dy) = ((x - m.x).abs(), (y - m.y).abs());
                    let d2 = dx * dx + dy * dy;
                    d2 < 120.0 * 120.0
                        || (dx.min(dy) < 0.6 * size && d2 < 600.0 * 600.0)
                        || (k % 29 == 0 && d2 < 1500.0 * 1500.0)
                })
                .map(|(k, _)| k as u32)
                .collect()
        })
        .collect();
    let header = sightline_pvs::Header::new(
        scene.fingerprint(),
        "synthetic",
        vec![],
        scene.objects.len(),
        cells.len(),
    );
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    sightline_pvs::format::encode(&header, &cells, &present, &sets).unwrap()
}
