//! Mesh levels (`.obj`, `.gltf`, `.glb`): clustered, cut into automatic cells by
//! `sightline-autocells` ([docs/methods/auto-cells.md](../../../docs/methods/auto-cells.md)),
//! with walkable viewcells where a player stands
//! ([docs/methods/volumetric.md](../../../docs/methods/volumetric.md)). The PVS lists
//! clusters; a `.pvs` carries the cluster → source mapping in its parameters.

use anyhow::Context;
use sightline_autocells::cells::VoxelBox;
use sightline_autocells::{default_cluster_size, AutoCells, Options, MAX_CLUSTER_TRIANGLES};
use sightline_core::{Cell, Method, SceneKind};
use sightline_geom::ViewCell;
use sightline_scene::clusters::{cluster_scene, Clustered};
use sightline_scene::Scene;
use std::path::{Path, PathBuf};

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
    /// `--view-volumes FILE`: the viewcells, in scene units: a JSON array of boxes, or
    /// a mesh file (`.obj`, `.gltf`, `.glb`) whose objects' bounding boxes are the
    /// volumes (as an editor's occlusion areas are placed).
    pub view_volumes: Option<PathBuf>,
    /// `--view-volume-names PATTERN`: of a mesh file of view volumes, only the objects
    /// (glTF nodes, OBJ objects) whose name matches (`*` any run, `?` one character).
    pub view_volume_names: Option<String>,
}

impl Standing {
    /// Whether anything but the defaults was asked (the flags apply to mesh levels only).
    pub fn is_set(&self) -> bool {
        self.eye_height.is_some()
            || !self.spawns.is_empty()
            || self.view_volumes.is_some()
            || self.view_volume_names.is_some()
    }
}

/// Whether `name` matches the glob `pattern` (`*` any run of characters, `?` one).
pub fn name_matches(pattern: &str, name: &str) -> bool {
    let (p, n): (Vec<char>, Vec<char>) = (pattern.chars().collect(), name.chars().collect());
    // Greedy matching with one backtrack point (the last `*`): linear in practice.
    let (mut i, mut j, mut star, mut mark) = (0, 0, None, 0);
    while j < n.len() {
        if i < p.len() && (p[i] == '?' || p[i] == n[j]) {
            i += 1;
            j += 1;
        } else if i < p.len() && p[i] == '*' {
            star = Some(i);
            mark = j;
            i += 1;
        } else if let Some(s) = star {
            i = s + 1;
            mark += 1;
            j = mark;
        } else {
            return false;
        }
    }
    p[i..].iter().all(|&c| c == '*')
}

/// The view volumes of `--view-volumes FILE` as `(min, max)` boxes in scene units.
fn read_view_volumes(
    path: &Path,
    names: Option<&str>,
) -> anyhow::Result<Vec<([f64; 3], [f64; 3])>> {
    if crate::kind_of(path) == SceneKind::Mesh {
        let scene = sightline_scene::import::load(path, &Default::default())
            .with_context(|| format!("cannot load the view volumes {}", path.display()))?;
        let picked: Vec<([f64; 3], [f64; 3])> = scene
            .objects
            .iter()
            .filter(|o| names.is_none_or(|p| o.name.as_deref().is_some_and(|n| name_matches(p, n))))
            .map(|o| (o.bounds.min.to_array(), o.bounds.max.to_array()))
            .collect();
        anyhow::ensure!(
            !picked.is_empty(),
            "{}: no object named like '{}' ({} objects)",
            path.display(),
            names.unwrap_or("*"),
            scene.objects.len()
        );
        return Ok(picked);
    }
    anyhow::ensure!(
        names.is_none(),
        "--view-volume-names picks objects of a mesh file of view volumes (.obj, .gltf, .glb), not of {}",
        path.display()
    );
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let volumes: Vec<ViewVolume> = serde_json::from_str(&text).with_context(|| {
        format!(
            "{}: expected a JSON array of boxes {{\"min\": [x, y, z], \"max\": [x, y, z]}}, or a mesh file of view volumes",
            path.display()
        )
    })?;
    Ok(volumes.into_iter().map(|v| (v.min, v.max)).collect())
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
    anyhow::ensure!(
        standing.view_volume_names.is_none() || standing.view_volumes.is_some(),
        "--view-volume-names picks objects of the --view-volumes file: give one"
    );
    if let Some(path) = &standing.view_volumes {
        anyhow::ensure!(
            standing.spawns.is_empty(),
            "--view-volumes gives the viewcells: --spawn has nothing to flood"
        );
        let volumes = read_view_volumes(path, standing.view_volume_names.as_deref())?;
        let mut out = Vec::with_capacity(volumes.len());
        for (i, (min, max)) in volumes.iter().enumerate() {
            let (lo, hi) = (to_voxels(*min), to_voxels(*max));
            anyhow::ensure!(
                (0..3).all(|k| lo[k].is_finite() && hi[k].is_finite() && lo[k] <= hi[k]),
                "{}: view volume {i} is not a box (min {:?}, max {:?})",
                path.display(),
                min,
                max
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

/// Whether `index` of a `.pvs` is a free-space cell (not a walkable viewcell): `Some`
/// only for files with walkable viewcells (`volumetric`).
pub fn free_space(params: &[(String, String)], index: usize) -> Option<bool> {
    let (_, n) = params.iter().find(|(k, _)| k == "viewcells")?;
    let n: usize = n.parse().ok()?;
    Some(index >= n)
}

/// The cutting options of a mesh level: the smallest hole (checked), `full` for the
/// portal flow (`portals`) rather than the flood (`portals-fast`).
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
pub fn cluster_level(raw: &Scene, opts: &Options) -> Clustered {
    cluster_scene(raw, default_cluster_size(raw, opts), MAX_CLUSTER_TRIANGLES)
}

/// A mesh level clustered and cut into automatic cells, each with its PVS.
pub struct CutLevel {
    pub clustered: Clustered,
    pub auto: AutoCells,
    /// What the cut had to change or found (a raised hole, skipped triangles, a leak),
    /// one line each, for the face to print.
    pub warnings: Vec<String>,
}

/// Cluster a loaded level (`name` for messages) and cut it into cells with their PVS
/// (`full`: the flow, else the base flood), as `build` does.
pub fn cut_level(
    raw: &Scene,
    name: &str,
    smallest_hole: Option<f64>,
    full: bool,
) -> anyhow::Result<CutLevel> {
    let opts = options(smallest_hole, full)?;
    let clustered = cluster_level(raw, &opts);
    let auto = AutoCells::build(&clustered.scene, &opts)
        .with_context(|| format!("cannot cut {name} into cells"))?;
    let mut warnings = Vec::new();
    let r = &auto.report;
    if let Some(asked) = r.smallest_hole_asked {
        warnings.push(format!(
            "smallest hole raised from {asked} to {:.3} to fit the voxel budget",
            r.smallest_hole
        ));
    }
    if r.voxels.degenerate_triangles > 0 {
        warnings.push(format!(
            "{} degenerate triangles (zero area or not finite) skipped",
            r.voxels.degenerate_triangles
        ));
    }
    if let Some(l) = &r.leak {
        warnings.push(format!(
            "the level leaks: free space at {:?} reaches the border at {:?} ({} voxels); the answer stays conservative",
            l.inside,
            l.border,
            l.path.len()
        ));
    }
    Ok(CutLevel {
        clustered,
        auto,
        warnings,
    })
}

/// A mesh level with the `.pvs` of its clusters.
pub struct EncodedLevel {
    pub level: CutLevel,
    /// The walkable viewcells stored first (`volumetric`), 0 for the portal methods.
    pub viewcells: usize,
    /// The `.pvs` (what `build` writes, what `serve` holds in memory).
    pub bytes: Vec<u8>,
}

/// `build LEVEL.obj --method portals|portals-fast`: every automatic cell, stored as its
/// box, with its cluster PVS.
pub fn encode_portals(level: CutLevel, method: Method) -> anyhow::Result<EncodedLevel> {
    let auto = &level.auto;
    let cells: Vec<Cell> = auto.cell_boxes().into_iter().map(Cell::Box).collect();
    let sets: Vec<roaring::RoaringBitmap> = (0..auto.len())
        .map(|c| auto.pvs(c).into_iter().collect())
        .collect();
    let bytes = level_pvs(&level, method, &[], &cells, &sets)?;
    Ok(EncodedLevel {
        level,
        viewcells: 0,
        bytes,
    })
}

/// `build LEVEL.obj` with `volumetric` (the default on a mesh level): the walkable
/// viewcells first, each with its volumetric ∩ portal PVS, then every automatic cell
/// with its portal PVS (any other point of free space: a flying camera, flagged
/// `free-space` by `query`). Parameters: the smallest hole, the eye height,
/// `viewcells` (how many cells are walkable viewcells), the cluster → source mapping.
pub fn encode_volumetric(mut level: CutLevel, standing: &Standing) -> anyhow::Result<EncodedLevel> {
    use rayon::prelude::*;
    let auto = &level.auto;
    let (eye, viewcells) = walkable_viewcells(auto, standing)?;
    if viewcells.is_empty() {
        level.warnings.push(format!("no walkable floor (no upward surface with room for the eye at {eye}): every cell is free space"));
    }
    let auto = &level.auto;
    let vol = auto.volumetric();
    let mut sets: Vec<roaring::RoaringBitmap> = viewcells
        .par_iter()
        .map(|b| auto.viewcell_pvs(&vol, b).into_iter().collect())
        .collect();
    sets.extend(
        (0..auto.len()).map(|c| auto.pvs(c).into_iter().collect::<roaring::RoaringBitmap>()),
    );
    let mut boxes: Vec<ViewCell> = viewcells
        .iter()
        .map(|b| sightline_autocells::cells::world_box(&auto.voxels, b))
        .collect();
    boxes.extend(auto.cell_boxes());
    let cells: Vec<Cell> = boxes.into_iter().map(Cell::Box).collect();
    let extra = [
        ("eye_height".to_string(), eye.to_string()),
        ("viewcells".to_string(), viewcells.len().to_string()),
    ];
    let bytes = level_pvs(&level, Method::Volumetric, &extra, &cells, &sets)?;
    Ok(EncodedLevel {
        level,
        viewcells: viewcells.len(),
        bytes,
    })
}

/// The `.pvs` of a mesh level: `cells` with their `sets`, the parameters every mesh
/// level carries (the smallest hole, then `extra`, then the cluster → source mapping).
fn level_pvs(
    level: &CutLevel,
    method: Method,
    extra: &[(String, String)],
    cells: &[Cell],
    sets: &[roaring::RoaringBitmap],
) -> anyhow::Result<Vec<u8>> {
    let (clustered, auto) = (&level.clustered, &level.auto);
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
    Ok(sightline_pvs::format::encode_cells(
        &header,
        cells,
        &present,
        sets,
        &sightline_pvs::format::EncodeOptions::default(),
    )?)
}

fn join(ids: &[u32]) -> String {
    ids.iter()
        .map(|i| i.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// The smallest hole a `.pvs` of a mesh level records (its clusters depend on it).
pub fn smallest_hole_of(file: &sightline_pvs::PvsFile) -> Option<f64> {
    file.header()
        .params
        .iter()
        .find(|(k, _)| k == "smallest_hole")
        .and_then(|(_, v)| v.parse::<f64>().ok())
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

#[cfg(test)]
mod tests {
    use super::name_matches;

    #[test]
    fn view_volume_names_match_globs() {
        for (p, n, m) in [
            ("ViewVolume*", "ViewVolume_hall", true),
            ("ViewVolume*", "viewvolume_hall", false),
            ("*", "", true),
            ("*_?", "area_7", true),
            ("*_?", "area_77", false),
            ("a*b*c", "axxbyyc", true),
            ("a*b*c", "axxbyy", false),
            ("exact", "exact", true),
            ("exact", "exactly", false),
            ("**x", "yyx", true),
            ("é?", "éa", true),
        ] {
            assert_eq!(name_matches(p, n), m, "{p} ~ {n}");
        }
    }
}
