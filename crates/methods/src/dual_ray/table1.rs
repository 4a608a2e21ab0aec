//! Reproduction of Table 1 of Koltun et al. 2001: time per cell and over-estimation of
//! the discretized algorithm against the exact one, per resolution and cell size.
//!
//! Over-estimation is the paper's `(P_E - P_C) / P_E`, where `P_E` (`P_C`) is the size
//! of the area found occluded by the exact (conservative) planar algorithm; the size of
//! an occluded object is its footprint area (outer bounds), summed over the cells of a
//! row. Timings are single-threaded, wall clock, per cell.

use super::{DualRay, Planarity};
use sightline_geom::ViewCell;
use sightline_scene::Scene;
use std::sync::Arc;
use std::time::Instant;

/// One line of Table 1.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Table1Row {
    pub cell_size_m: f64,
    /// Rows of the ray space; `0` for the exact algorithm.
    pub resolution_px: u32,
    pub cells: usize,
    pub ms_median: f64,
    pub ms_mean: f64,
    pub pvs_mean: f64,
    /// `(P_E - P_C) / P_E` over the row's cells (0 for the exact row).
    pub overestimation: f64,
    pub planar_tests_mean: f64,
}

/// `n` cells of `size_m` (z 0..2 m) centred on street crossings of the generated
/// metropolis's 110 m grid, spread over the city by a fixed pseudo-random sequence (the
/// cells of the criterion bench and of the timing example).
pub fn crossing_cells(scene: &Scene, size_m: f64, n: usize) -> Vec<ViewCell> {
    let b = scene.bounds;
    let pitch = 110.0;
    let cols = ((b.max.x - b.min.x) / pitch).floor().max(1.0) as usize;
    let rows = ((b.max.y - b.min.y) / pitch).floor().max(1.0) as usize;
    let mut out = Vec::with_capacity(n);
    let mut k: u64 = 0x9E37_79B9;
    while out.len() < n {
        k = k
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let c = (k >> 33) as usize % cols;
        let r = (k >> 13) as usize % rows;
        let cx = b.min.x + c as f64 * pitch;
        let cy = b.min.y + r as f64 * pitch;
        let h = size_m / 2.0;
        if let Ok(cell) = ViewCell::from_array([cx - h, cy - h, 0.0, cx + h, cy + h, 2.0]) {
            out.push(cell);
        }
    }
    out
}

/// Total footprint area (m²) of the objects *not* in `pvs` (sorted): the occluded area.
pub(crate) fn occluded_area_m2(scene: &Scene, pvs: &[u32]) -> f64 {
    scene
        .objects
        .iter()
        .enumerate()
        .filter(|(i, _)| pvs.binary_search(&(*i as u32)).is_err())
        .map(|(_, o)| o.outer.iter().map(|p| p.footprint.area()).sum::<f64>())
        .sum()
}

/// Run Table 1: for each `(cell size, cells)` group, the exact algorithm once and the
/// discretized one at every resolution, sequentially (one thread).
pub fn table1(
    scene: Arc<Scene>,
    groups: &[(f64, Vec<ViewCell>)],
    resolutions: &[u32],
) -> Vec<Table1Row> {
    let exact = DualRay::new("dual-ray-exact", scene.clone(), Planarity::Exact);
    let mut rows = Vec::new();
    for (size, cells) in groups {
        let mut p_exact = Vec::with_capacity(cells.len());
        let mut times = Vec::with_capacity(cells.len());
        let (mut pvs_sum, mut tests) = (0usize, 0u64);
        for c in cells {
            let t = Instant::now();
            let (pvs, st) = exact.pvs_with_stats(c);
            times.push(t.elapsed().as_secs_f64() * 1e3);
            pvs_sum += pvs.len();
            tests += st.planar_tests;
            p_exact.push(occluded_area_m2(&scene, &pvs));
        }
        let n = cells.len().max(1) as f64;
        let mean = times.iter().sum::<f64>() / n;
        rows.push(Table1Row {
            cell_size_m: *size,
            resolution_px: 0,
            cells: cells.len(),
            ms_median: sightline_stats::median(&times),
            ms_mean: mean,
            pvs_mean: pvs_sum as f64 / n,
            overestimation: 0.0,
            planar_tests_mean: tests as f64 / n,
        });
        let pe: f64 = p_exact.iter().sum();
        for &r in resolutions {
            let m = DualRay::new(
                "dual-ray",
                scene.clone(),
                Planarity::Discrete { resolution_px: r },
            );
            let mut times = Vec::with_capacity(cells.len());
            let (mut pvs_sum, mut tests, mut pc) = (0usize, 0u64, 0.0);
            for c in cells {
                let t = Instant::now();
                let (pvs, st) = m.pvs_with_stats(c);
                times.push(t.elapsed().as_secs_f64() * 1e3);
                pvs_sum += pvs.len();
                tests += st.planar_tests;
                pc += occluded_area_m2(&scene, &pvs);
            }
            let mean = times.iter().sum::<f64>() / n;
            rows.push(Table1Row {
                cell_size_m: *size,
                resolution_px: r,
                cells: cells.len(),
                ms_median: sightline_stats::median(&times),
                ms_mean: mean,
                pvs_mean: pvs_sum as f64 / n,
                overestimation: if pe > 0.0 { (pe - pc) / pe } else { 0.0 },
                planar_tests_mean: tests as f64 / n,
            });
        }
    }
    rows
}
