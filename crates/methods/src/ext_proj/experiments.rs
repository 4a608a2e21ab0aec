//! The paper's experiments as functions the benchmark report can call:
//! the resolution curve of Fig. 12, plain projection against the occlusion sweep with
//! 1, 5, 15 planes (§7.2), and the gain of the improved projection (§7.1: "PVS 5 to
//! 10% smaller"). Timings are wall-clock per cell on the calling thread.

use super::{ExtProj, Params};
use crate::VisibilityMethod;
use sightline_geom::ViewCell;
use sightline_scene::Scene;
use std::sync::Arc;
use std::time::Instant;

/// Aggregate of one configuration over a set of cells.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RunStats {
    pub cells: usize,
    /// Mean PVS size (objects).
    pub mean_pvs: f64,
    /// Mean fraction of objects culled.
    pub hidden_fraction: f64,
    /// Mean fraction of the scene's triangles culled (the paper's "% of geometry").
    pub culled_triangles: f64,
    /// Median and mean milliseconds per cell (preparation excluded).
    pub ms_median: f64,
    pub ms_mean: f64,
    /// Preparation time of the method (ms).
    pub prepare_ms: f64,
    /// The PVS of every cell, in order.
    pub pvs: Vec<Vec<u32>>,
}

/// Run `ext-proj` with `params` on `cells`.
pub fn run(scene: &Arc<Scene>, cells: &[ViewCell], params: Params) -> RunStats {
    let t0 = Instant::now();
    let m = ExtProj::new(scene.clone(), params);
    let prepare_ms = t0.elapsed().as_secs_f64() * 1e3;
    let tri: Vec<usize> = scene.objects.iter().map(|o| o.triangle_count()).collect();
    let total_tri: usize = tri.iter().sum::<usize>().max(1);
    let n = scene.objects.len().max(1);
    let mut times = Vec::with_capacity(cells.len());
    let mut stats = RunStats {
        cells: cells.len(),
        prepare_ms,
        ..RunStats::default()
    };
    for c in cells {
        let t = Instant::now();
        let p = m.pvs(c).unwrap_or_else(|_| (0..n as u32).collect());
        times.push(t.elapsed().as_secs_f64() * 1e3);
        let kept_tri: usize = p.iter().map(|&i| tri[i as usize]).sum();
        stats.mean_pvs += p.len() as f64;
        stats.hidden_fraction += 1.0 - p.len() as f64 / n as f64;
        stats.culled_triangles += 1.0 - kept_tri as f64 / total_tri as f64;
        stats.pvs.push(p);
    }
    let k = cells.len().max(1) as f64;
    stats.mean_pvs /= k;
    stats.hidden_fraction /= k;
    stats.culled_triangles /= k;
    stats.ms_mean = times.iter().sum::<f64>() / k;
    times.sort_by(f64::total_cmp);
    stats.ms_median = times.get(times.len() / 2).copied().unwrap_or(0.0);
    stats
}

/// Fig. 12: time and hidden fraction against the depth-map resolution.
pub fn resolution_curve(
    scene: &Arc<Scene>,
    cells: &[ViewCell],
    resolutions: &[usize],
    base: &Params,
) -> Vec<(usize, RunStats)> {
    resolutions
        .iter()
        .map(|&r| {
            let p = Params {
                resolution_px: r.next_power_of_two(),
                ..base.clone()
            };
            (r, run(scene, cells, p))
        })
        .collect()
}

/// §7.2: plain extended projections (`None`) against the sweep with each plane count.
pub fn sweep_curve(
    scene: &Arc<Scene>,
    cells: &[ViewCell],
    plane_counts: &[usize],
    base: &Params,
) -> Vec<(Option<usize>, RunStats)> {
    let mut out = vec![(
        None,
        run(
            scene,
            cells,
            Params {
                sweep: false,
                ..base.clone()
            },
        ),
    )];
    for &k in plane_counts {
        let p = Params {
            sweep: true,
            sweep_planes: k,
            ..base.clone()
        };
        out.push((Some(k), run(scene, cells, p)));
    }
    out
}

/// §4 / §7.1: mean PVS with the standard occludee projection and with the improved
/// one, and the relative reduction `1 − improved / standard`.
pub fn improved_gain(
    scene: &Arc<Scene>,
    cells: &[ViewCell],
    base: &Params,
) -> (RunStats, RunStats, f64) {
    let std = run(
        scene,
        cells,
        Params {
            improved: false,
            ..base.clone()
        },
    );
    let imp = run(
        scene,
        cells,
        Params {
            improved: true,
            ..base.clone()
        },
    );
    let gain = if std.mean_pvs > 0.0 {
        1.0 - imp.mean_pvs / std.mean_pvs
    } else {
        0.0
    };
    (std, imp, gain)
}
