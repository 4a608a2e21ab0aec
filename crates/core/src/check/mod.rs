//! Ground-truth visible sets and the checking of methods against them.
//!
//! The **visible set (VS)** of a cell is estimated by dense sampling (survey §7.6,
//! "aggressive" visibility): stratified viewpoints in the cell's free space each render
//! the full sphere of directions (six cube faces) into object-id buffers with the
//! standard coverage rule, and the ids seen are united. *Targeted* rays then look for
//! every object still unseen: segments from the viewpoints (and from fresh random points
//! of the cell's free space) to random points of the object's front faces (their area,
//! their highest edge: a roof line seen over other roofs, and their boundary), tested
//! exactly against every other object (a ray caster of its own, independent of the
//! rasterizer), so that objects seen only through gaps or as slivers narrower than a
//! pixel are found too. Every id reported comes with a [`Witness`]: the viewpoint and
//! the direction of a sample that saw it.
//!
//! The check is deliberately apart from the methods' occluder model (`occluders`): it
//! renders and casts rays against every object's full geometry, not the inner bounds
//! the methods occlude with, so an error in that model shows as a missed object instead
//! of being shared by the methods and their oracle.
//!
//! The VS is a *lower bound* of the true visible set: an object in the VS is visible,
//! so a conservative PVS must contain it. Grazing sight lines do not count
//!: a targeted ray is accepted only if it stays farther than [`GRAZE_M`] from
//! every other object, and the rasterizer's closed, watertight standard rule leaves no
//! crack along shared edges (a party wall seen edge-on shows no pixel of what lies
//! behind it).
//!
//! Viewpoints lie in the cell shrunk by [`INSET_M`] (a cell touching a facade then sees
//! the facade at a positive distance); points inside or within [`INSET_M`]/2 of a block
//! are not viewpoints, nor points at or below the ground.
//!
//! ```
//! use sightline_core::check::{ground_truth, TruthOptions};
//! use sightline_scene::{Scene, Object};
//! use sightline_geom::{Polygon, DVec2, ViewCell};
//! // A 10 m high wall at y = 10..11 hides a 5 m block behind it, not a 40 m tower.
//! let rect = |x0, y0, x1, y1| Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1));
//! let scene = Scene::from_objects(vec![
//!     Object::block(Some("wall".into()), rect(-50.0, 10.0, 50.0, 11.0), 0.0, 10.0),
//!     Object::block(Some("low".into()), rect(-5.0, 20.0, 5.0, 30.0), 0.0, 5.0),
//!     Object::block(Some("tower".into()), rect(10.0, 20.0, 20.0, 30.0), 0.0, 40.0),
//! ]);
//! let cell: ViewCell = "-2,0,1.5,2,4,2".parse().unwrap();
//! let opts = TruthOptions { samples: 16, resolution_px: 128, ..TruthOptions::default() };
//! let truth = ground_truth(&scene, &cell, &opts);
//! assert_eq!(truth.visible, vec![0, 2]);
//! ```

mod rays;
mod samples;
mod truth;

pub use rays::GRAZE_M;
pub use truth::{ground_truth, Truth, TruthOptions, TruthScene, Witness, INSET_M};

use crate::{MethodError, VisibilityMethod};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sightline_geom::{DVec2, UniformGrid, ViewCell};
use sightline_scene::Scene;
use std::time::Instant;

/// An object of the VS that the PVS lacks, with the sample that saw it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Missed {
    pub id: u32,
    pub viewpoint: [f64; 3],
    pub direction: [f64; 3],
}

/// A method's PVS of one cell against the ground truth.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CellCheck {
    pub cell: ViewCell,
    pub pvs_len: usize,
    pub vs_len: usize,
    pub missed: Vec<Missed>,
    /// |PVS| / |VS| (1 when both are empty; |PVS| when only the VS is).
    pub over: f64,
    /// 1 − |PVS| / objects.
    pub hidden_fraction: f64,
    pub pvs_seconds: f64,
    pub truth_seconds: f64,
}

/// Compare a PVS with a truth.
pub fn compare(objects: usize, pvs: &[u32], truth: &Truth, pvs_seconds: f64) -> CellCheck {
    let missed: Vec<Missed> = truth
        .witnesses
        .iter()
        .filter(|w| pvs.binary_search(&w.id).is_err())
        .map(|w| Missed {
            id: w.id,
            viewpoint: w.viewpoint,
            direction: w.direction,
        })
        .collect();
    let vs_len = truth.visible.len();
    let over = if vs_len == 0 {
        pvs.len().max(1) as f64
    } else {
        pvs.len() as f64 / vs_len as f64
    };
    CellCheck {
        cell: truth.cell,
        pvs_len: pvs.len(),
        vs_len,
        missed,
        over,
        hidden_fraction: if objects == 0 {
            0.0
        } else {
            1.0 - pvs.len() as f64 / objects as f64
        },
        pvs_seconds,
        truth_seconds: truth.seconds,
    }
}

/// Check `method` on one cell.
pub fn check_cell(
    scene: &Scene,
    method: &dyn VisibilityMethod,
    cell: &ViewCell,
    opts: &TruthOptions,
) -> Result<CellCheck, MethodError> {
    check_cell_prepared(&TruthScene::new(scene), method, cell, opts)
}

/// Check `method` on one cell of a prepared scene.
pub fn check_cell_prepared(
    truth_scene: &TruthScene,
    method: &dyn VisibilityMethod,
    cell: &ViewCell,
    opts: &TruthOptions,
) -> Result<CellCheck, MethodError> {
    let t0 = Instant::now();
    let mut pvs = method.pvs(cell)?;
    let pvs_seconds = t0.elapsed().as_secs_f64();
    pvs.sort_unstable();
    pvs.dedup();
    let truth = truth_scene.ground_truth(cell, opts);
    Ok(compare(truth_scene.objects, &pvs, &truth, pvs_seconds))
}

/// Aggregate of [`CellCheck`]s (the `check --json` report).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CheckReport {
    pub method: String,
    pub cells: usize,
    /// Total missed ids over all cells (must be 0 for a conservative method).
    pub missed: usize,
    pub over_median: f64,
    pub over_p90: f64,
    pub over_max: f64,
    /// Mean hidden fraction.
    pub hidden_fraction: f64,
    /// Median PVS time per cell (ms).
    pub pvs_ms_median: f64,
    /// Median ground-truth time per cell (ms).
    pub truth_ms_median: f64,
    pub per_cell: Vec<CellCheck>,
}

/// Nearest-rank quantile of an ascending slice; 0 for none (the report's convention).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        0.0
    } else {
        sightline_stats::quantile_sorted(sorted, q)
    }
}

/// Aggregate per-cell checks.
pub fn aggregate(method: &str, per_cell: Vec<CellCheck>) -> CheckReport {
    let mut overs: Vec<f64> = per_cell.iter().map(|c| c.over).collect();
    overs.sort_by(f64::total_cmp);
    let mut pvs_ms: Vec<f64> = per_cell.iter().map(|c| c.pvs_seconds * 1e3).collect();
    pvs_ms.sort_by(f64::total_cmp);
    let mut truth_ms: Vec<f64> = per_cell.iter().map(|c| c.truth_seconds * 1e3).collect();
    truth_ms.sort_by(f64::total_cmp);
    let n = per_cell.len();
    CheckReport {
        method: method.to_string(),
        cells: n,
        missed: per_cell.iter().map(|c| c.missed.len()).sum(),
        over_median: quantile(&overs, 0.5),
        over_p90: quantile(&overs, 0.9),
        over_max: overs.last().copied().unwrap_or(0.0),
        hidden_fraction: if n == 0 {
            0.0
        } else {
            per_cell.iter().map(|c| c.hidden_fraction).sum::<f64>() / n as f64
        },
        pvs_ms_median: quantile(&pvs_ms, 0.5),
        truth_ms_median: quantile(&truth_ms, 0.5),
        per_cell,
    }
}

/// Check `method` on many cells in parallel; `progress` is called once per finished cell.
pub fn check_cells(
    scene: &Scene,
    method: &dyn VisibilityMethod,
    cells: &[ViewCell],
    opts: &TruthOptions,
    progress: &(dyn Fn() + Sync),
) -> Result<CheckReport, MethodError> {
    let ts = TruthScene::new(scene);
    let per_cell = cells
        .par_iter()
        .map(|c| {
            let r = check_cell_prepared(&ts, method, c, opts);
            progress();
            r
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(aggregate(method.name(), per_cell))
}

/// Which part of a street cell must be free of blocks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Clearance {
    /// The whole box, probed on a 5 × 5 grid at both heights.
    Box,
    /// The centre column, probed at both heights: the cell may overlap facades (cells
    /// wider than the streets, or cells that meet the buildings on purpose).
    Centre,
}

/// Up to `k` square street cells of side `size_m` at heights `z = (z0, z1)` whose
/// `clearance` is free of blocks, among the whole cells of the grid of `size_m` from the
/// scene's minimum corner, spread evenly over the scene in a deterministic order.
///
/// ```
/// use sightline_core::check::{street_cells, Clearance};
/// use sightline_scene::{Object, Scene};
/// use sightline_geom::{DVec2, Polygon};
/// // A 100 × 100 m scene with a 25 m wide building along its west side.
/// let rect = |x0, y0, x1, y1| Polygon::rect(DVec2::new(x0, y0), DVec2::new(x1, y1));
/// let scene = Scene::from_objects(vec![
///     Object::block(None, rect(0.0, 0.0, 25.0, 100.0), 0.0, 10.0),
///     Object::block(None, rect(99.0, 99.0, 100.0, 100.0), 0.0, 1.0),
/// ]);
/// let cells = street_cells(&scene, 20.0, (1.5, 2.0), usize::MAX, Clearance::Box);
/// assert!(cells.iter().all(|c| c.min.x >= 40.0));
/// let wider = street_cells(&scene, 20.0, (1.5, 2.0), usize::MAX, Clearance::Centre);
/// // The cells at x = 20..40 have their centre in the street, their west side inside.
/// assert!(wider.iter().any(|c| c.min.x == 20.0));
/// ```
pub fn street_cells(
    scene: &Scene,
    size_m: f64,
    z: (f64, f64),
    k: usize,
    clearance: Clearance,
) -> Vec<ViewCell> {
    if scene.objects.is_empty() || k == 0 || !(size_m > 0.0) {
        return Vec::new();
    }
    let ts = TruthScene::new(scene);
    let b = scene.bounds.xy();
    let whole = |extent: f64| ((extent / size_m).floor() as u32).min(10_000);
    let grid = UniformGrid::square(b.min, size_m, whole(b.size().x), whole(b.size().y));
    let free: Vec<ViewCell> = (0..grid.len() as u32)
        .filter_map(|id| {
            let (i, j) = grid.coords(id)?;
            // Exactly `size_m` wide, probed every `size_m / 4`.
            let cell = ViewCell::from_rect(grid.rect_from_corner(i, j), z.0, z.1).ok()?;
            is_clear(&ts, &cell, DVec2::splat(size_m), clearance).then_some(cell)
        })
        .collect();
    spread(free, k)
}

/// Up to `k` of `cells` whose `clearance` is free of the blocks of `ts`, spread evenly
/// over them in their order.
pub fn street_cells_among(
    ts: &TruthScene,
    cells: &[ViewCell],
    k: usize,
    clearance: Clearance,
) -> Vec<ViewCell> {
    let free = cells
        .iter()
        .filter(|c| is_clear(ts, c, c.size().truncate(), clearance))
        .copied()
        .collect();
    spread(free, k)
}

/// Whether the `clearance` of `cell` (of sides `size`) is free of blocks, at both of
/// its heights.
fn is_clear(ts: &TruthScene, cell: &ViewCell, size: DVec2, clearance: Clearance) -> bool {
    let column = |p: DVec2| ts.is_free(p.extend(cell.min.z)) && ts.is_free(p.extend(cell.max.z));
    match clearance {
        Clearance::Centre => column(cell.center().truncate()),
        Clearance::Box => {
            let (lo, step) = (cell.min.truncate(), size / 4.0);
            (0..5).all(|u| (0..5).all(|v| column(lo + DVec2::new(u as f64, v as f64) * step)))
        }
    }
}

/// `k` of `items` spread evenly (the middle one of each of `k` equal runs), or all of
/// them if there are no more than `k`.
fn spread(items: Vec<ViewCell>, k: usize) -> Vec<ViewCell> {
    if items.len() <= k {
        return items;
    }
    (0..k)
        .map(|i| items[i * items.len() / k + items.len() / (2 * k)])
        .collect()
}

/// Up to `k` of `cells`, spread evenly over the `pool × k` of them nearest the middle of
/// the scene (cells at its edges see mostly empty ground), nearest first.
pub fn near_middle(scene: &Scene, cells: &[ViewCell], k: usize, pool: usize) -> Vec<ViewCell> {
    let c = scene.bounds.center().truncate();
    let mut sorted = cells.to_vec();
    sorted.sort_by(|a, b| {
        let da = a.center().truncate().distance(c);
        let db = b.center().truncate().distance(c);
        da.total_cmp(&db)
    });
    let pool = &sorted[..sorted.len().min(pool.saturating_mul(k))];
    if pool.len() <= k {
        return pool.to_vec();
    }
    (0..k).map(|i| pool[i * pool.len() / k]).collect()
}

/// The `check --json` report of `m` (the CLI's and the Python `check`'s): the aggregate,
/// the method's parameters, every missed object with the sample that saw it, and the
/// per-cell figures.
pub fn report_json(report: &CheckReport, m: &dyn VisibilityMethod) -> serde_json::Value {
    let missed: Vec<serde_json::Value> = report
        .per_cell
        .iter()
        .flat_map(|c| {
            c.missed.iter().map(move |x| {
                serde_json::json!({"cell": c.cell, "id": x.id, "viewpoint": x.viewpoint, "direction": x.direction})
            })
        })
        .collect();
    serde_json::json!({
        "method": report.method,
        "params": m.params().into_iter().collect::<std::collections::BTreeMap<_, _>>(),
        "conservative": m.is_conservative(),
        "cells": report.cells,
        "missed": report.missed,
        "over_median": report.over_median,
        "over_p90": report.over_p90,
        "over_max": report.over_max,
        "hidden_fraction": report.hidden_fraction,
        "pvs_ms_median": report.pvs_ms_median,
        "truth_ms_median": report.truth_ms_median,
        "missed_ids": missed,
        "per_cell": report.per_cell.iter().map(|c| serde_json::json!({
            "cell": c.cell, "pvs": c.pvs_len, "vs": c.vs_len, "missed": c.missed.len(),
            "over": c.over, "hidden_fraction": c.hidden_fraction,
            "pvs_ms": c.pvs_seconds * 1e3, "truth_ms": c.truth_seconds * 1e3,
        })).collect::<Vec<_>>(),
    })
}
