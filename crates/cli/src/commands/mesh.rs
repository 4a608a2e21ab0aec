//! Mesh levels (`.obj`, `.gltf`, `.glb`) with the portal methods on automatic cells
//! (`sightline-autocells`): `pvs LEVEL.obj --at X,Y,Z --method portals`, `build LEVEL.obj
//! --method portals -o L.pvs` (every automatic cell stored as its box), `cells LEVEL.obj`.
//! The PVS lists clusters (`visible`) and their source objects (`visible_sources`, in
//! `info`'s order); a `.pvs` carries the cluster → source mapping in its parameters.

use crate::cli::SceneArg;
use crate::common::{load_scene, print_json};
use anyhow::Context;
use serde::Serialize;
use sightline_autocells::cells::VoxelBox;
use sightline_autocells::judge::JudgedCell;
use sightline_autocells::{default_cluster_size, AutoCells, Options, MAX_CLUSTER_TRIANGLES};
use sightline_core::check::TruthOptions;
use sightline_core::Method;
use sightline_geom::ViewCell;
use sightline_scene::clusters::{cluster_scene, Clustered};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub fn is_mesh(path: &Path) -> bool {
    path.extension().is_some_and(|e| {
        ["obj", "gltf", "glb"]
            .iter()
            .any(|m| e.eq_ignore_ascii_case(m))
    })
}

/// The default eye height of a viewer on a mesh level: 1.7 (metres), or 3.5 smallest
/// holes when the voxels are coarser (a level in game units: pandora's 4-unit voxels
/// give 14, a Sauerbraten player's eye).
pub fn default_eye_height(smallest_hole: f64) -> f64 {
    (3.5 * smallest_hole).max(1.7)
}

/// Width of the walkable viewcells, in voxels.
pub const VIEWCELL_WIDTH: usize = 8;

/// Where viewers stand on a mesh level (`build`/`check` flags): the eye height, the
/// spawn points a walker floods from, or view volumes given instead of the floors.
#[derive(Clone, Debug, Default)]
pub struct Standing {
    /// `--eye-height` (else [`default_eye_height`]).
    pub eye_height: Option<f64>,
    /// `--spawn X,Y,Z`: keep the viewcells a walker reaches from these points.
    pub spawns: Vec<[f64; 3]>,
    /// `--view-volumes FILE.json`: boxes in scene units, used as the viewcells.
    pub view_volumes: Option<PathBuf>,
}

impl Standing {
    /// Whether anything but the defaults was asked (the flags apply to mesh levels only).
    pub fn is_set(&self) -> bool {
        self.eye_height.is_some() || !self.spawns.is_empty() || self.view_volumes.is_some()
    }
}

/// A view volume of `--view-volumes`.
#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct ViewVolume {
    min: [f64; 3],
    max: [f64; 3],
}

/// The eye height and the viewcells of a cut level, as `build` stores them: the
/// walkable viewcells (those a walker reaches from the spawn points, when given), or
/// the view volumes (rounded out to whole voxels).
pub fn walkable_viewcells(
    auto: &AutoCells,
    standing: &Standing,
) -> anyhow::Result<(f64, Vec<VoxelBox>)> {
    let h = auto.report.smallest_hole;
    let eye = standing.eye_height.unwrap_or_else(|| default_eye_height(h));
    anyhow::ensure!(
        eye.is_finite() && eye > 0.0,
        "--eye-height must be a positive number of scene units, got {eye}"
    );
    let g = &auto.voxels.grid;
    let to_voxels =
        |p: [f64; 3]| -> [f64; 3] { std::array::from_fn(|k| (p[k] - g.origin[k]) / g.size) };
    if let Some(path) = &standing.view_volumes {
        anyhow::ensure!(
            standing.spawns.is_empty(),
            "--view-volumes gives the viewcells: --spawn has nothing to flood"
        );
        let text = std::fs::read_to_string(path)
            .with_context(|| format!("cannot read {}", path.display()))?;
        let volumes: Vec<ViewVolume> = serde_json::from_str(&text).with_context(|| {
            format!(
                "{}: expected a JSON array of boxes {{\"min\": [x, y, z], \"max\": [x, y, z]}}",
                path.display()
            )
        })?;
        let mut out = Vec::with_capacity(volumes.len());
        for (i, v) in volumes.iter().enumerate() {
            let (lo, hi) = (to_voxels(v.min), to_voxels(v.max));
            anyhow::ensure!(
                (0..3).all(|k| lo[k].is_finite() && hi[k].is_finite() && lo[k] <= hi[k]),
                "{}: view volume {i} is not a box (min {:?}, max {:?})",
                path.display(),
                v.min,
                v.max
            );
            let b = VoxelBox {
                lo: std::array::from_fn(|k| (lo[k].floor().max(0.0) as usize).min(g.dims[k])),
                hi: std::array::from_fn(|k| (hi[k].ceil().max(0.0) as usize).min(g.dims[k])),
            };
            anyhow::ensure!(
                (0..3).all(|k| b.lo[k] < b.hi[k]),
                "{}: view volume {i} lies outside the level",
                path.display()
            );
            out.push(b);
        }
        return Ok((eye, out));
    }
    let viewcells = auto.viewcells(&sightline_autocells::viewcells::Walker {
        eye_height: eye,
        width: VIEWCELL_WIDTH,
    });
    if standing.spawns.is_empty() {
        return Ok((eye, viewcells));
    }
    let mut starts = Vec::new();
    for s in &standing.spawns {
        let p = to_voxels(*s);
        let inside = (0..3).all(|k| p[k].is_finite() && p[k] >= 0.0 && p[k] < g.dims[k] as f64);
        let c = p.map(|x| x as usize);
        anyhow::ensure!(
            inside && auto.voxels.is_open(g.index(c[0], c[1], c[2])),
            "spawn point {},{},{} lies in no open voxel (inside a wall or outside the level)",
            s[0],
            s[1],
            s[2]
        );
        starts.push(c);
    }
    // Walk space: open voxels up to twice the eye height above a floor.
    let reach = (2.0 * eye / h).ceil() as usize;
    let kept = sightline_autocells::viewcells::reachable(
        &auto.voxels,
        &auto.tris,
        &viewcells,
        &starts,
        reach,
    );
    Ok((eye, kept.into_iter().map(|c| viewcells[c]).collect()))
}

/// Up to `k` of `items`, spread evenly over the list (the viewcells `check` judges).
pub fn spread<T: Copy>(items: &[T], k: usize) -> Vec<T> {
    let step = (items.len() / k.max(1)).max(1);
    items.iter().copied().step_by(step).take(k).collect()
}

/// `build LEVEL.obj -o L.pvs` with `volumetric` (the default on a mesh level): the
/// walkable viewcells first, each with its volumetric ∩ portal PVS, then every
/// automatic cell with its portal PVS (any other point of free space: a flying
/// camera, flagged `free-space` by `query`). Parameters: the smallest hole, the eye
/// height, `viewcells` (how many cells are walkable viewcells), the cluster → source
/// mapping.
pub fn encode_volumetric(
    scene: &SceneArg,
    smallest_hole: Option<f64>,
    standing: &Standing,
    quiet: bool,
) -> anyhow::Result<(Level, usize)> {
    use rayon::prelude::*;
    let (clustered, auto) = prepare(scene, smallest_hole, false, quiet)?;
    let (eye, viewcells) = walkable_viewcells(&auto, standing)?;
    if viewcells.is_empty() && !quiet {
        eprintln!("warning: no walkable floor (no upward surface with room for the eye at {eye}): every cell is free space");
    }
    let vol = auto.volumetric();
    let bar = crate::common::progress(viewcells.len() as u64, quiet, "viewcells");
    let mut sets: Vec<roaring::RoaringBitmap> = viewcells
        .par_iter()
        .map(|b| {
            let s = auto.viewcell_pvs(&vol, b).into_iter().collect();
            bar.inc(1);
            s
        })
        .collect();
    bar.finish_and_clear();
    sets.extend(
        (0..auto.len()).map(|c| auto.pvs(c).into_iter().collect::<roaring::RoaringBitmap>()),
    );
    let mut boxes: Vec<ViewCell> = viewcells
        .iter()
        .map(|b| sightline_autocells::cells::world_box(&auto.voxels, b))
        .collect();
    boxes.extend(auto.cell_boxes());
    let cells: Vec<sightline_core::Cell> =
        boxes.into_iter().map(sightline_core::Cell::Box).collect();
    let extra = [
        ("eye_height".to_string(), eye.to_string()),
        ("viewcells".to_string(), viewcells.len().to_string()),
    ];
    let level = level_pvs(clustered, auto, Method::Volumetric, &extra, &cells, &sets)?;
    Ok((level, viewcells.len()))
}

/// `build LEVEL.obj -o L.pvs --method volumetric` (module doc of [`encode_volumetric`]).
pub fn build_volumetric(
    scene: &SceneArg,
    smallest_hole: Option<f64>,
    standing: &Standing,
    out: &Path,
    quiet: bool,
) -> anyhow::Result<()> {
    let t = Instant::now();
    let (level, viewcells) = encode_volumetric(scene, smallest_hole, standing, quiet)?;
    sightline_pvs::build::write_atomic(out, &level.bytes)
        .with_context(|| format!("cannot write {}", out.display()))?;
    if !quiet {
        let r = &level.auto.report;
        eprintln!(
            "wrote {}: {viewcells} walkable viewcells and {} free-space cells, {} clusters of {} source objects, smallest hole {:.3}, method {}, {} bytes, {:.1} s",
            out.display(),
            r.cells,
            level.auto.objects,
            level.clustered.source_names.len(),
            r.smallest_hole,
            Method::Volumetric.name(),
            level.bytes.len(),
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// `check LEVEL.obj [--method volumetric] [--cells K]`: K walkable viewcells spread
/// over the level, each one's volumetric PVS judged by the item-buffer truth sampled in
/// its free voxels; an error when a cluster the truth sees is missing.
pub fn check_volumetric(
    scene: &SceneArg,
    smallest_hole: Option<f64>,
    standing: &Standing,
    k: usize,
    json: bool,
    quiet: bool,
) -> anyhow::Result<()> {
    use rayon::prelude::*;
    let t = Instant::now();
    let (clustered, auto) = prepare(scene, smallest_hole, false, quiet)?;
    let (eye, viewcells) = walkable_viewcells(&auto, standing)?;
    anyhow::ensure!(
        !viewcells.is_empty(),
        "no walkable floor in {} (no upward surface with room for the eye at {eye})",
        scene.scene.display()
    );
    let picked = spread(&viewcells, k);
    let vol = auto.volumetric();
    let pvs: Vec<Vec<u32>> = picked
        .par_iter()
        .map(|b| auto.viewcell_pvs(&vol, b))
        .collect();
    let seconds_pvs = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let spinner = crate::common::progress(1, quiet, "ground truth in the judged viewcells");
    let judged = auto.judge_boxes(
        &clustered.scene,
        &picked,
        |c| pvs[c].clone(),
        picked.len(),
        &TruthOptions::default(),
    );
    spinner.finish_and_clear();
    let sum = Summary::of(&judged, pvs.iter().map(Vec::len), auto.objects);
    let name = Method::Volumetric.name();
    let report = serde_json::json!({
        "method": name,
        "viewcells": viewcells.len(),
        "eye_height": eye,
        "clusters": auto.objects,
        "judged": judged.len(),
        "missed": sum.missed,
        "over_median": sum.over_median,
        "culled_median": sum.culled_median,
        "seconds_pvs": seconds_pvs,
        "seconds_truth": t.elapsed().as_secs_f64(),
        "judged_cells": judged,
    });
    if json {
        print_json(&report)?;
    } else {
        println!(
            "{name}: {} walkable viewcells, {} judged, missed {}, PVS / truth median {:.2}, median viewcell culls {:.1} % of {} clusters (PVS {:.1} s, truth {:.1} s)",
            viewcells.len(),
            judged.len(),
            sum.missed,
            sum.over_median,
            100.0 * sum.culled_median,
            auto.objects,
            seconds_pvs,
            t.elapsed().as_secs_f64()
        );
    }
    sum.witnesses(name, "viewcell", &judged, json)
}

/// Whether `index` of a `.pvs` is a free-space cell (not a walkable viewcell): `Some`
/// only for files with walkable viewcells (`volumetric`).
pub fn free_space(params: &[(String, String)], index: usize) -> Option<bool> {
    let (_, n) = params.iter().find(|(k, _)| k == "viewcells")?;
    let n: usize = n.parse().ok()?;
    Some(index >= n)
}

/// `Some(full)` when `scene` is a mesh level and `method` a portal method.
pub fn portal_mode(scene: &Path, method: &str) -> Option<bool> {
    if !is_mesh(scene) {
        return None;
    }
    match method.parse::<Method>() {
        Ok(Method::Portals) => Some(true),
        Ok(Method::PortalsFast) => Some(false),
        _ => None,
    }
}

pub fn options(smallest_hole: Option<f64>, full: bool) -> anyhow::Result<Options> {
    if let Some(h) = smallest_hole {
        anyhow::ensure!(
            h.is_finite() && h > 0.0,
            "--smallest-hole must be a positive number of scene units, got {h}"
        );
    }
    Ok(Options {
        smallest_hole,
        full,
        ..Options::default()
    })
}

/// The clusters of a mesh level, the ids every `.pvs` of it lists: the one place that
/// decides them (`build`, `check`, `pvs`, `serve` and `clusters` all come here). They
/// depend on the level and on `opts` (the smallest hole and voxel budget set the
/// cluster grid, [`default_cluster_size`]).
pub fn cluster_level(raw: &sightline_scene::Scene, opts: &Options) -> Clustered {
    cluster_scene(raw, default_cluster_size(raw, opts), MAX_CLUSTER_TRIANGLES)
}

/// Load, cluster and cut the level into cells.
fn prepare(
    scene: &SceneArg,
    smallest_hole: Option<f64>,
    full: bool,
    quiet: bool,
) -> anyhow::Result<(Clustered, AutoCells)> {
    let raw = load_scene(scene)?;
    cut_level(
        &raw,
        &scene.scene.display().to_string(),
        smallest_hole,
        full,
        quiet,
    )
}

/// Cluster a loaded level (`name` for messages) and cut it into cells with their PVS
/// (`full`: the flow, else the base flood), as `build` does; warnings unless `quiet`.
pub fn cut_level(
    raw: &sightline_scene::Scene,
    name: &str,
    smallest_hole: Option<f64>,
    full: bool,
    quiet: bool,
) -> anyhow::Result<(Clustered, AutoCells)> {
    let opts = options(smallest_hole, full)?;
    let clustered = cluster_level(raw, &opts);
    let spinner = crate::common::progress(1, quiet, "voxels, cells, portals, PVS of every cell");
    let auto = AutoCells::build(&clustered.scene, &opts)
        .with_context(|| format!("cannot cut {name} into cells"))?;
    spinner.finish_and_clear();
    if !quiet {
        let r = &auto.report;
        if let Some(asked) = r.smallest_hole_asked {
            eprintln!(
                "warning: smallest hole raised from {asked} to {:.3} to fit the voxel budget",
                r.smallest_hole
            );
        }
        if r.voxels.degenerate_triangles > 0 {
            eprintln!(
                "warning: {} degenerate triangles (zero area or not finite) skipped",
                r.voxels.degenerate_triangles
            );
        }
        if let Some(l) = &r.leak {
            eprintln!(
                "warning: the level leaks: free space at {:?} reaches the border at {:?} ({} voxels); the answer stays conservative",
                l.inside,
                l.border,
                l.path.len()
            );
        }
    }
    Ok((clustered, auto))
}

fn method_name(full: bool) -> &'static str {
    if full {
        Method::Portals.name()
    } else {
        Method::PortalsFast.name()
    }
}

#[derive(Serialize)]
struct PvsReport {
    method: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    at: Option<[f64; 3]>,
    cell: ViewCell,
    #[serde(skip_serializing_if = "Option::is_none")]
    index: Option<u32>,
    objects: usize,
    sources: usize,
    visible: Vec<u32>,
    visible_sources: Vec<u32>,
    seconds: f64,
}

/// `pvs LEVEL.obj (--at X,Y,Z | --cell ...) --method portals|portals-fast`.
pub fn pvs(
    scene: &SceneArg,
    full: bool,
    smallest_hole: Option<f64>,
    cell: Option<ViewCell>,
    at: Option<[f64; 3]>,
    json: bool,
) -> anyhow::Result<()> {
    let t = Instant::now();
    let (clustered, auto) = prepare(scene, smallest_hole, full, true)?;
    let (index, cell, visible) = if let Some(p) = at {
        let c = auto.locate(p).with_context(|| {
            format!(
                "point {},{},{} is not in the level's free space (solid or outside)",
                p[0], p[1], p[2]
            )
        })?;
        (Some(c), auto.cell_box(c as usize), auto.pvs(c as usize))
    } else if let Some(cell) = cell {
        let mut v: Vec<u32> = (0..auto.len())
            .filter(|&c| {
                let b = auto.cell_box(c);
                (0..3).all(|k| b.min[k] <= cell.max[k] && b.max[k] >= cell.min[k])
            })
            .flat_map(|c| auto.pvs(c))
            .collect();
        v.sort_unstable();
        v.dedup();
        (None, cell, v)
    } else {
        anyhow::bail!("give --at X,Y,Z or --cell X0,Y0,Z0,X1,Y1,Z1");
    };
    let report = PvsReport {
        method: method_name(full),
        at,
        cell,
        index,
        objects: auto.objects,
        sources: clustered.source_names.len(),
        visible_sources: clustered.sources_of(&visible),
        visible,
        seconds: t.elapsed().as_secs_f64(),
    };
    if json {
        return print_json(&report);
    }
    println!(
        "{}: {} of {} clusters ({} of {} source objects) potentially visible from {} ({:.1} s)",
        report.method,
        report.visible.len(),
        report.objects,
        report.visible_sources.len(),
        report.sources,
        report.cell,
        report.seconds
    );
    Ok(())
}

/// `check LEVEL.obj --method portals|portals-fast [--cells K]`: K automatic cells
/// judged by the item-buffer truth sampled in their free space
/// (`AutoCells::judge`); an error when a cluster the truth sees is missing.
pub fn check(
    scene: &SceneArg,
    full: bool,
    smallest_hole: Option<f64>,
    k: usize,
    json: bool,
    quiet: bool,
) -> anyhow::Result<()> {
    let t = Instant::now();
    let (clustered, auto) = prepare(scene, smallest_hole, full, quiet)?;
    let seconds_pvs = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let spinner = crate::common::progress(1, quiet, "ground truth in the judged cells");
    let judged = auto.judge(&clustered.scene, k, &TruthOptions::default());
    spinner.finish_and_clear();
    let sum = Summary::of(
        &judged,
        (0..auto.len()).map(|c| auto.pvs(c).len()),
        auto.objects,
    );
    let report = serde_json::json!({
        "method": method_name(full),
        "cells": auto.len(),
        "clusters": auto.objects,
        "judged": judged.len(),
        "missed": sum.missed,
        "over_median": sum.over_median,
        "culled_median": sum.culled_median,
        "seconds_pvs": seconds_pvs,
        "seconds_truth": t.elapsed().as_secs_f64(),
        "leak": auto.report.leak.as_ref().map(|l| serde_json::json!({"inside": l.inside, "void": l.border})),
        "judged_cells": judged,
    });
    if json {
        print_json(&report)?;
    } else {
        println!(
            "{}: {} cells, {} judged, missed {}, PVS / truth median {:.2}, median cell culls {:.1} % of {} clusters (PVS of every cell {:.1} s, truth {:.1} s)",
            method_name(full),
            auto.len(),
            judged.len(),
            sum.missed,
            sum.over_median,
            100.0 * sum.culled_median,
            auto.objects,
            seconds_pvs,
            t.elapsed().as_secs_f64()
        );
    }
    sum.witnesses(method_name(full), "cell", &judged, json)
}

/// What `check` reports of judged cells: clusters missed, median PVS / truth, and
/// the median share of clusters a cell culls (over `sizes`, every cell's PVS size).
struct Summary {
    missed: usize,
    over_median: f64,
    culled_median: f64,
}

impl Summary {
    fn of(judged: &[JudgedCell], sizes: impl Iterator<Item = usize>, objects: usize) -> Summary {
        let median = |mut v: Vec<f64>| {
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied().unwrap_or(0.0)
        };
        Summary {
            missed: judged.iter().map(|j| j.missed.len()).sum(),
            over_median: median(
                judged
                    .iter()
                    .map(|j| j.pvs as f64 / j.truth.max(1) as f64)
                    .collect(),
            ),
            culled_median: median(
                sizes
                    .map(|n| 1.0 - n as f64 / objects.max(1) as f64)
                    .collect(),
            ),
        }
    }

    /// Print each miss's witness (text mode) and fail when there is one.
    fn witnesses(
        &self,
        method: &str,
        cell: &str,
        judged: &[JudgedCell],
        json: bool,
    ) -> anyhow::Result<()> {
        if !json {
            for j in judged {
                for w in &j.missed {
                    println!(
                        "missed: cluster {} of {cell} {} seen from {:?} along {:?}",
                        w.id, j.cell, w.viewpoint, w.direction
                    );
                }
            }
        }
        anyhow::ensure!(
            self.missed == 0,
            "method {method} missed {} visible cluster(s) — a conservativeness bug (witnesses above)",
            self.missed
        );
        Ok(())
    }
}

/// `build LEVEL.obj --method portals|portals-fast -o L.pvs`: every automatic cell,
/// stored as its box, with its cluster PVS; the parameters carry the smallest hole and
/// the cluster → source mapping.
pub fn build(
    scene: &SceneArg,
    full: bool,
    smallest_hole: Option<f64>,
    out: &Path,
    quiet: bool,
) -> anyhow::Result<()> {
    let t = Instant::now();
    let level = encode(scene, full, smallest_hole, quiet)?;
    sightline_pvs::build::write_atomic(out, &level.bytes)
        .with_context(|| format!("cannot write {}", out.display()))?;
    if !quiet {
        let r = &level.auto.report;
        eprintln!(
            "wrote {}: {} automatic cells, {} portals, {} clusters of {} source objects, smallest hole {:.3}, method {}, {} bytes, {:.1} s",
            out.display(),
            r.cells,
            r.portals,
            level.auto.objects,
            level.clustered.source_names.len(),
            r.smallest_hole,
            method_name(full),
            level.bytes.len(),
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

/// A mesh level cut into automatic cells with the `.pvs` of its clusters.
pub struct Level {
    pub clustered: Clustered,
    pub auto: AutoCells,
    /// The `.pvs` (what `build` writes, what `serve` holds in memory).
    pub bytes: Vec<u8>,
}

/// Cluster the level, cut it into cells, solve every cell and encode the `.pvs`.
pub fn encode(
    scene: &SceneArg,
    full: bool,
    smallest_hole: Option<f64>,
    quiet: bool,
) -> anyhow::Result<Level> {
    let (clustered, auto) = prepare(scene, smallest_hole, full, quiet)?;
    let cells: Vec<sightline_core::Cell> = auto
        .cell_boxes()
        .into_iter()
        .map(sightline_core::Cell::Box)
        .collect();
    let sets: Vec<roaring::RoaringBitmap> = (0..auto.len())
        .map(|c| auto.pvs(c).into_iter().collect())
        .collect();
    let method = if full {
        Method::Portals
    } else {
        Method::PortalsFast
    };
    level_pvs(clustered, auto, method, &[], &cells, &sets)
}

/// The `.pvs` of a mesh level: `cells` with their `sets`, the parameters every mesh
/// level carries (the smallest hole, then `extra`, then the cluster → source mapping).
fn level_pvs(
    clustered: Clustered,
    auto: AutoCells,
    method: Method,
    extra: &[(String, String)],
    cells: &[sightline_core::Cell],
    sets: &[roaring::RoaringBitmap],
) -> anyhow::Result<Level> {
    let mut params = vec![(
        "smallest_hole".to_string(),
        auto.report.smallest_hole.to_string(),
    )];
    params.extend_from_slice(extra);
    params.push(("sources".to_string(), join(&clustered.source)));
    params.push((
        "source_names".to_string(),
        serde_json::to_string(&clustered.source_names)?,
    ));
    let header = sightline_pvs::Header::new(
        clustered.scene.fingerprint(),
        method.name(),
        params,
        auto.objects,
        cells.len(),
    );
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    let bytes = sightline_pvs::format::encode_cells(
        &header,
        cells,
        &present,
        sets,
        &sightline_pvs::format::EncodeOptions::default(),
    )?;
    Ok(Level {
        clustered,
        auto,
        bytes,
    })
}

/// The clustered scene a `.pvs` of this level was built on: the level clustered as
/// `build` clusters it, with the smallest hole the file records (clusters depend on it).
pub fn clustered_for(scene: &SceneArg, file: &sightline_pvs::PvsFile) -> anyhow::Result<Clustered> {
    let hole = file
        .header()
        .params
        .iter()
        .find(|(k, _)| k == "smallest_hole")
        .and_then(|(_, v)| v.parse::<f64>().ok());
    let raw = load_scene(scene)?;
    let opts = options(hole, false)?;
    Ok(cluster_level(&raw, &opts))
}

fn join(ids: &[u32]) -> String {
    ids.iter()
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// The source objects of `visible` when a `.pvs`'s parameters carry the mapping.
pub fn sources_from_params(params: &[(String, String)], visible: &[u32]) -> Option<Vec<u32>> {
    let (_, s) = params.iter().find(|(k, _)| k == "sources")?;
    let map: Vec<u32> = s
        .split(',')
        .filter(|x| !x.is_empty())
        .map(|x| x.parse().ok())
        .collect::<Option<_>>()?;
    let mut out: Vec<u32> = visible
        .iter()
        .filter_map(|&c| map.get(c as usize).copied())
        .collect();
    out.sort_unstable();
    out.dedup();
    Some(out)
}

/// `cells LEVEL.obj -o cells.json`: the automatic cells as boxes.
pub fn cells(
    scene: &SceneArg,
    smallest_hole: Option<f64>,
    out: &Path,
    quiet: bool,
) -> anyhow::Result<()> {
    let (_, auto) = prepare(scene, smallest_hole, false, quiet)?;
    let boxes = auto.cell_boxes();
    crate::common::write_atomic(out, &serde_json::to_vec(&boxes)?)?;
    let r = &auto.report;
    println!(
        "{} automatic cells ({} portals; voxels {:?} of {:.3}: {} surface, {} air, {} solid) → {}",
        r.cells,
        r.portals,
        r.grid,
        r.smallest_hole,
        r.voxels.surface,
        r.voxels.air,
        r.voxels.solid,
        out.display()
    );
    Ok(())
}
