//! The mesh section (issue #48 item 5): mesh levels (OBJ, glTF) with `volumetric` on
//! their walkable viewcells, as `build LEVEL.obj` computes them and `check LEVEL.obj`
//! judges them. Per level: voxels, clusters, walkable viewcells, the setup time
//! (clusters, voxels, automatic cells and their flood, occluders) and the median time
//! per viewcell, peak memory, clusters culled per viewcell (median, p10, p90), PVS /
//! truth (median, max) and misses against the item-buffer truth sampled in the
//! viewcells' free voxels (`AutoCells::judge_boxes`, the judge of `check`).

use super::indoor::{peak_mib, reset_peak};
use super::plots::{line_chart, Scale, Series};
use super::report::{Report, Table};
use super::suite::Suite;
use anyhow::Context;
use rayon::prelude::*;
use serde::Serialize;
use sightline_core::check::TruthOptions;
use sightline_scene::Scene;
use sightline_stats::{median, quantile};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A mesh level of the section: the small generated level, or a file.
#[derive(Clone, Debug)]
pub enum MeshLevel {
    /// `autocells::testlevel::two_rooms_and_a_door`, smallest hole 0.5.
    Generated,
    File(PathBuf),
}

impl MeshLevel {
    pub fn name(&self) -> String {
        match self {
            MeshLevel::Generated => "two-rooms (generated)".into(),
            MeshLevel::File(p) => p
                .file_stem()
                .map_or_else(|| p.display().to_string(), |s| s.to_string_lossy().into()),
        }
    }

    /// The level and the smallest hole to cut it at (`None`: automatic, as `build`).
    fn load(&self) -> anyhow::Result<(Scene, Option<f64>)> {
        match self {
            MeshLevel::Generated => Ok((
                sightline_autocells::testlevel::two_rooms_and_a_door(0.0),
                Some(0.5),
            )),
            MeshLevel::File(p) => {
                anyhow::ensure!(
                    sightline_world::kind_of(p) == sightline_world::SceneKind::Mesh,
                    "{} is not a mesh level (.obj, .gltf, .glb)",
                    p.display()
                );
                let s = sightline_scene::import::load(p, &Default::default())
                    .with_context(|| format!("cannot load {}", p.display()))?;
                Ok((s, None))
            }
        }
    }
}

/// One viewcell's figures (the plot's points).
#[derive(Clone, Debug, Serialize)]
pub struct ViewcellFigures {
    /// Index in the level's walkable viewcell list (`build`'s order).
    pub viewcell: usize,
    pub pvs: usize,
    pub culled: f64,
    pub ms: f64,
}

/// The measured figures of one mesh level.
#[derive(Clone, Debug, Serialize)]
pub struct MeshRecord {
    pub level: String,
    pub triangles: usize,
    pub smallest_hole: f64,
    pub eye_height: f64,
    /// Voxels of the grid (all states) and its dimensions.
    pub voxels: usize,
    pub grid: [usize; 3],
    pub clusters: usize,
    /// Automatic cells (free space, portal flood) and walkable viewcells.
    pub cells: usize,
    pub viewcells: usize,
    /// Viewcells whose PVS was computed (spread over the list), and those judged.
    pub sampled: usize,
    pub judged: usize,
    /// Setup: clusters, voxels, automatic cells and their flood (`seconds_cut`), then
    /// the occluders of the volumetric test (`seconds_occluders`).
    pub seconds_cut: f64,
    pub seconds_occluders: f64,
    /// Per viewcell, each one's own wall time (on `threads` rayon threads).
    pub ms_median: f64,
    pub ms_p90: f64,
    pub threads: usize,
    /// Setup plus every viewcell at the median time, on `threads` threads.
    pub seconds_all_estimate: f64,
    /// The process's peak resident memory from the level's load to its last PVS
    /// (before the truth), MiB; 0 if unknown.
    pub peak_mib: f64,
    /// Share of the clusters culled per sampled viewcell.
    pub culled_median: f64,
    pub culled_p10: f64,
    pub culled_p90: f64,
    /// |PVS| / |truth| over the judged viewcells.
    pub over_median: f64,
    pub over_max: f64,
    /// Clusters the truth saw that a PVS lacks: must be 0.
    pub missed: usize,
    pub seconds_truth: f64,
    pub per_viewcell: Vec<ViewcellFigures>,
}

/// Measure one level: `sample` viewcells spread over its list (`None`: all), up to
/// `judge` of them judged by the truth.
pub fn measure_level(
    level: &MeshLevel,
    sample: Option<usize>,
    judge: usize,
    truth: &TruthOptions,
) -> anyhow::Result<MeshRecord> {
    let name = level.name();
    let (raw, hole) = level.load()?;
    reset_peak();
    let t = Instant::now();
    let sightline_world::CutLevel {
        clustered, auto, ..
    } = sightline_world::cut_level(&raw, &name, hole, false)?;
    let seconds_cut = t.elapsed().as_secs_f64();
    let (eye, viewcells) = sightline_world::walkable_viewcells(&auto, &Default::default())?;
    anyhow::ensure!(
        !viewcells.is_empty(),
        "no walkable floor in {name} (no upward surface with room for the eye at {eye})"
    );
    let picked: Vec<usize> = {
        let all: Vec<usize> = (0..viewcells.len()).collect();
        match sample {
            Some(k) if k > 0 => sightline_world::spread(&all, k),
            _ => all,
        }
    };
    let vol = auto.volumetric();
    let timed: Vec<(Vec<u32>, f64)> = picked
        .par_iter()
        .map(|&i| {
            let t = Instant::now();
            let s = auto.viewcell_pvs(&vol, &viewcells[i]);
            (s, t.elapsed().as_secs_f64() * 1e3)
        })
        .collect();
    let peak = peak_mib();
    let clusters = auto.objects;
    let per_viewcell: Vec<ViewcellFigures> = picked
        .iter()
        .zip(&timed)
        .map(|(&i, (s, ms))| ViewcellFigures {
            viewcell: i,
            pvs: s.len(),
            culled: 1.0 - s.len() as f64 / clusters.max(1) as f64,
            ms: *ms,
        })
        .collect();
    let t = Instant::now();
    let boxes: Vec<_> = picked.iter().map(|&i| viewcells[i]).collect();
    let judged = auto.judge_boxes(
        &clustered.scene,
        &boxes,
        |c| timed[c].0.clone(),
        judge.min(boxes.len()),
        truth,
    );
    let seconds_truth = t.elapsed().as_secs_f64();
    let over: Vec<f64> = judged
        .iter()
        .map(|j| j.pvs as f64 / j.truth.max(1) as f64)
        .collect();
    let culled: Vec<f64> = per_viewcell.iter().map(|v| v.culled).collect();
    let ms: Vec<f64> = per_viewcell.iter().map(|v| v.ms).collect();
    let threads = rayon::current_num_threads();
    let r = &auto.report;
    Ok(MeshRecord {
        level: name,
        triangles: auto.tris.len(),
        smallest_hole: r.smallest_hole,
        eye_height: eye,
        voxels: r.grid.iter().product(),
        grid: r.grid,
        clusters,
        cells: auto.len(),
        viewcells: viewcells.len(),
        sampled: picked.len(),
        judged: judged.len(),
        seconds_cut,
        seconds_occluders: vol.seconds,
        ms_median: median(&ms),
        ms_p90: quantile(&ms, 0.9),
        threads,
        seconds_all_estimate: seconds_cut
            + vol.seconds
            + median(&ms) * 1e-3 * viewcells.len() as f64 / threads.max(1) as f64,
        peak_mib: peak,
        culled_median: median(&culled),
        culled_p10: quantile(&culled, 0.1),
        culled_p90: quantile(&culled, 0.9),
        over_median: median(&over),
        over_max: over.iter().copied().fold(f64::NAN, f64::max),
        missed: judged.iter().map(|j| j.missed.len()).sum(),
        seconds_truth,
        per_viewcell,
    })
}

/// Measure `level` into `records` (a failure or a miss becomes a note).
pub fn measure_into(
    suite: &Suite,
    level: &MeshLevel,
    truth: &TruthOptions,
    records: &mut Vec<MeshRecord>,
    notes: &mut Vec<String>,
    quiet: bool,
) {
    if !quiet {
        eprintln!("bench: mesh level {}", level.name());
    }
    match measure_level(level, suite.mesh_viewcells, suite.mesh_judged, truth) {
        Ok(r) => {
            if r.missed > 0 {
                notes.push(format!(
                    "`volumetric` MISSED {} visible clusters on {} (a conservativeness bug)",
                    r.missed, r.level
                ));
            }
            records.push(r);
        }
        Err(e) => notes.push(format!("meshes: {}: {e:#}", level.name())),
    }
}

fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{:.1}", 100.0 * v)
    } else {
        "–".into()
    }
}

fn num(v: f64, digits: usize) -> String {
    if v.is_finite() {
        format!("{v:.digits$}")
    } else {
        "–".into()
    }
}

/// The section of the mesh levels measured: the table, and the plot written into `out`.
pub fn write_section(records: &[MeshRecord], rep: &mut Report, out: &Path) -> anyhow::Result<()> {
    rep.section("Mesh levels: volumetric on walkable viewcells");
    rep.para(
        "Each level as `build LEVEL.obj` computes it (method `volumetric`, the default on a mesh level): clusters, voxels at the smallest hole (automatic unless the level sets it), automatic cells and their `portals-fast` flood, walkable viewcells at the default eye height, occluders, then the PVS of the *sampled* viewcells, spread over the list (`bench --mesh-viewcells N`; all when not limited). *setup* = clusters, voxels, cells and flood, plus the occluders; *ms / viewcell* is each viewcell's own wall time (rayon threads share the cores); *all (est.)* = setup + every viewcell at the median time on those threads. *culled* = 1 − |PVS| / clusters per sampled viewcell. The truth (`check LEVEL.obj`'s judge: item-buffer sampling in each judged viewcell's free voxels) gives PVS / truth and *missed*, which must be 0. Peak memory: the process's high-water mark from the level's load to its last PVS, before the truth.",
    );
    let mut t = Table::new(&[
        "level",
        "triangles",
        "h",
        "voxels",
        "clusters",
        "cells",
        "viewcells",
        "sampled",
        "setup s",
        "ms / viewcell median (p90)",
        "threads",
        "all (est.) s",
        "peak MiB",
        "culled % median (p10–p90)",
        "judged",
        "PVS / truth median (max)",
        "missed",
    ]);
    for r in records {
        t.row(vec![
            r.level.clone(),
            r.triangles.to_string(),
            num(r.smallest_hole, 3),
            r.voxels.to_string(),
            r.clusters.to_string(),
            r.cells.to_string(),
            r.viewcells.to_string(),
            r.sampled.to_string(),
            num(r.seconds_cut + r.seconds_occluders, 2),
            format!("{} ({})", num(r.ms_median, 1), num(r.ms_p90, 1)),
            r.threads.to_string(),
            num(r.seconds_all_estimate, 1),
            format!("{:.0}", r.peak_mib),
            format!(
                "{} ({}–{})",
                pct(r.culled_median),
                pct(r.culled_p10),
                pct(r.culled_p90)
            ),
            r.judged.to_string(),
            format!("{} ({})", num(r.over_median, 2), num(r.over_max, 2)),
            r.missed.to_string(),
        ]);
    }
    rep.table(&t);
    if records.is_empty() {
        return Ok(());
    }
    // Culled share per viewcell, sorted, against the share of viewcells: a level's
    // curve reads as "x % of its viewcells cull at most y %".
    let series: Vec<Series> = records
        .iter()
        .map(|r| {
            let mut c: Vec<f64> = r.per_viewcell.iter().map(|v| 100.0 * v.culled).collect();
            c.sort_by(f64::total_cmp);
            let n = c.len().max(1) as f64;
            Series {
                name: r.level.clone(),
                points: c
                    .iter()
                    .enumerate()
                    .map(|(i, &y)| (100.0 * (i as f64 + 0.5) / n, y))
                    .collect(),
            }
        })
        .collect();
    line_chart(
        &out.join("meshes-culled.png"),
        "volumetric: clusters culled per viewcell (sorted)",
        "viewcells (%)",
        "clusters culled (%)",
        &series,
        Scale::Linear,
        Scale::Linear,
    )?;
    rep.image("meshes-culled.png", "clusters culled per viewcell, sorted");
    rep.para("One curve per level: its sampled viewcells sorted by the share of clusters they cull; the higher the curve, the more the PVS culls.");
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::machine::Machine;

    /// The section on the generated level: its facts, no miss, some culling, the table
    /// and the plot are written.
    #[test]
    fn mesh_section_on_the_generated_level() {
        let mut suite = Suite::named("quick").unwrap();
        suite.mesh_viewcells = Some(6);
        suite.mesh_judged = 2;
        let truth = TruthOptions {
            samples: 8,
            resolution_px: 64,
            ..TruthOptions::default()
        };
        let dir = tempfile::tempdir().unwrap();
        let mut rep = Report::new(&suite, &Machine::detect());
        let (mut records, mut notes) = (Vec::new(), Vec::new());
        let levels = [
            MeshLevel::Generated,
            MeshLevel::File(dir.path().join("city.geojson")),
        ];
        for level in &levels {
            measure_into(&suite, level, &truth, &mut records, &mut notes, true);
        }
        write_section(&records, &mut rep, dir.path()).unwrap();
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(notes[0].contains("not a mesh level"), "{notes:?}");
        let r = &records[0];
        assert_eq!(r.level, "two-rooms (generated)");
        assert_eq!(r.smallest_hole, 0.5);
        assert!(
            r.clusters >= 6,
            "six objects, the floor and walls cut: {r:?}"
        );
        assert!(r.viewcells >= 6 && r.sampled == 6, "{r:?}");
        assert_eq!(r.per_viewcell.len(), 6);
        assert!(r.judged >= 1 && r.judged <= 2, "{r:?}");
        assert_eq!(r.missed, 0);
        assert!(r.culled_p90 > 0.0 && r.culled_p10 <= r.culled_median);
        assert!(r.over_median >= 1.0 && r.over_max >= r.over_median);
        assert!(r.voxels > 0 && r.ms_median >= 0.0 && r.seconds_all_estimate > 0.0);
        let md = rep.markdown();
        assert!(md.contains("| two-rooms (generated) |"), "{md}");
        let img = image::open(dir.path().join("meshes-culled.png")).unwrap();
        assert_eq!(img.width(), 900);
    }
}
