//! `serve LEVEL.bsp` and `serve LEVEL.obj|.gltf|.glb`: a level served on its own cells.
//!
//! The cells are those `build LEVEL --method portals[-fast]` stores — a BSP level's open
//! leaves (convex cells), a mesh level's automatic cells (boxes) — and the served
//! objects are those the `.pvs` lists: a BSP's world faces, a mesh's clusters (the level
//! clustered as `build` clusters it). With `--pvs` the file is served after checking it
//! was built for this scene; without, the same `.pvs` is built in memory first and
//! served from memory ([`sightline_server::source::FileSource::in_memory`]), so both
//! answer exactly as `query --at` does on the file.
//!
//! The viewer walks on the level's floors at `eye_height` (see the `--eye-height` help):
//! it starts at the BSP's `info_player_start` (its origin + 22, the eye of a Quake player
//! standing there) when the level has one and that point is in a cell, otherwise at the
//! centre of the largest cell whose centre lies in it.

use super::Served;
use crate::cli::SceneArg;
use crate::common::{open_world, print_warnings};
use anyhow::{bail, Context};
use sightline_core::Method;
use sightline_geom::DVec3;
use sightline_pvs::PvsFile;
use sightline_scene::Scene;
use sightline_server::source::{FileSource, PvsSource};
use sightline_server::ViewSettings;
use sightline_world::{SceneKind, Standing, World};
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Eye height in a BSP level: Quake's player origin is 24 units above the floor and its
/// eye 22 above the origin.
pub const BSP_EYE_HEIGHT: f64 = 46.0;
/// A Quake eye above the player's origin.
const BSP_EYE_ABOVE_ORIGIN: f64 = 22.0;

/// Load the level, build or open its `.pvs`, and say what is served.
pub(crate) fn prepare(
    scene: &SceneArg,
    pvs: Option<&Path>,
    method: &str,
    smallest_hole: Option<f64>,
    eye_height: Option<f64>,
    quiet: bool,
) -> anyhow::Result<Served> {
    let standing = Standing {
        eye_height,
        ..Standing::default()
    };
    let world = open_world(scene, smallest_hole, standing)?;
    if world.kind() == SceneKind::Bsp {
        bsp_level(&world, pvs, method, quiet)
    } else {
        mesh_level(&world, pvs, method, quiet)
    }
}

fn open(path: &Path) -> anyhow::Result<PvsFile> {
    PvsFile::open(path).with_context(|| format!("cannot open {}", path.display()))
}

/// The level's `.pvs` built in memory with `method` (a method on the level's cells):
/// the file, the served objects, and (method, bytes) for the description.
fn build_in_memory(
    world: &World,
    method: &str,
    quiet: bool,
) -> anyhow::Result<Option<(PvsFile, Scene, &'static str, usize)>> {
    let Some(m) = method
        .parse::<Method>()
        .ok()
        .filter(|&m| sightline_world::on_level_cells(m) && m.works_on(world.kind()))
    else {
        return Ok(None);
    };
    let enc = world.encode(m)?;
    if let Some(f) = &enc.mesh {
        print_warnings(&f.warnings, quiet);
    }
    let n = enc.bytes.len();
    Ok(Some((
        PvsFile::from_bytes(enc.bytes)?,
        enc.scene,
        m.name(),
        n,
    )))
}

fn bsp_level(
    world: &World,
    pvs: Option<&Path>,
    method: &str,
    quiet: bool,
) -> anyhow::Result<Served> {
    let path = world.path();
    let t = Instant::now();
    let scene = world.scene().clone();
    let (file, built) = match pvs {
        Some(p) => (open(p)?, None),
        None => {
            let Some((file, _, m, n)) = build_in_memory(world, method, quiet)? else {
                bail!("a .bsp level is served with its PVS built by portals or portals-fast (or --pvs L.pvs), not '{method}'");
            };
            (file, Some((m, n)))
        }
    };
    let src = source(file, &scene, pvs, built.is_some())?;
    let start = world
        .player_start()
        .map(|o| DVec3::new(o[0], o[1], o[2] + BSP_EYE_ABOVE_ORIGIN))
        .filter(|p| src.locate(*p).is_ok());
    let start = start.or_else(|| largest_cell_centre(&src));
    describe(
        path,
        pvs,
        &src,
        "leaves (convex cells)",
        built.map(|(m, n)| (m, n, t.elapsed().as_secs_f64())),
    );
    Ok(Served {
        scene,
        view: ViewSettings {
            kind: "level",
            eye_height: BSP_EYE_HEIGHT,
            start: start.map(|p| p.to_array()),
        },
        source: Arc::new(src),
    })
}

fn mesh_level(
    world: &World,
    pvs: Option<&Path>,
    method: &str,
    quiet: bool,
) -> anyhow::Result<Served> {
    let path = world.path();
    let t = Instant::now();
    let (file, served, built) = match pvs {
        Some(p) => {
            let file = open(p)?;
            let clustered = world.clustered_for(&file)?;
            (file, clustered.scene, None)
        }
        None => {
            let Some((file, scene, m, n)) = build_in_memory(world, method, quiet)? else {
                bail!("a mesh level is served with its PVS built by volumetric, portals or portals-fast (or --pvs L.pvs), not '{method}'");
            };
            (file, scene, Some((m, n)))
        }
    };
    let param = |name: &str| {
        file.header()
            .params
            .iter()
            .find(|(k, _)| k == name)
            .and_then(|(_, v)| v.parse::<f64>().ok())
            .filter(|x| x.is_finite() && *x > 0.0)
    };
    // A volumetric file's walkable viewcells come first: start on the largest one's
    // floor, the eye at the file's eye height above it.
    let walk_eye = param("eye_height");
    let walkable = param("viewcells").map_or(0, |n| n as usize);
    let hole = param("smallest_hole");
    let scene = Arc::new(served);
    let src = source(file, &scene, pvs, built.is_some())?;
    let start = match walk_eye.filter(|_| walkable > 0) {
        Some(eye) => largest_floor_eye(&src, walkable, eye),
        None => largest_cell_centre(&src),
    };
    describe(
        path,
        pvs,
        &src,
        if walkable > 0 {
            "cells (walkable viewcells, then free space)"
        } else {
            "automatic cells"
        },
        built.map(|(m, n)| (m, n, t.elapsed().as_secs_f64())),
    );
    Ok(Served {
        scene,
        view: ViewSettings {
            kind: "level",
            eye_height: walk_eye
                .filter(|_| walkable > 0)
                .unwrap_or_else(|| mesh_eye_height(hole)),
            start: start.map(|p| p.to_array()),
        },
        source: Arc::new(src),
    })
}

/// A mesh level's eye height: 1.7 (metres, glTF's unit and the usual one of OBJ
/// exports), raised to 2.5 smallest holes when the voxels are coarser, so that the eye
/// stands in the free voxels above the floor's surface layer, inside a cell.
pub fn mesh_eye_height(smallest_hole: Option<f64>) -> f64 {
    smallest_hole.map_or(1.7, |h| (2.5 * h).max(1.7))
}

fn source(
    file: PvsFile,
    scene: &sightline_scene::Scene,
    pvs: Option<&Path>,
    in_memory: bool,
) -> anyhow::Result<FileSource> {
    let what = pvs.map_or_else(
        || "the level's PVS".to_string(),
        |p| p.display().to_string(),
    );
    let src = FileSource::cells(file, scene).with_context(|| format!("cannot serve {what}"))?;
    Ok(if in_memory { src.in_memory() } else { src })
}

/// The centre of the largest cell (by the volume of its box) whose centre is in it.
/// The eye of a viewer standing in the middle of the largest of the first `walkable`
/// cells (walkable viewcells, their boxes from the floor voxel up), `eye` above its
/// floor, when that point lies in it.
fn largest_floor_eye(src: &FileSource, walkable: usize, eye: f64) -> Option<DVec3> {
    let cells = src.file().cells();
    let area = |i: usize| cells[i].size().x * cells[i].size().y;
    (0..walkable.min(cells.len()))
        .max_by(|&a, &b| area(a).total_cmp(&area(b)).then(b.cmp(&a)))
        .map(|i| {
            let c = cells[i].center();
            DVec3::new(c.x, c.y, cells[i].min.z + eye)
        })
        .filter(|p| src.locate(*p).is_ok())
}

fn largest_cell_centre(src: &FileSource) -> Option<DVec3> {
    let cells = src.file().cells();
    let mut order: Vec<usize> = (0..cells.len()).collect();
    let volume = |i: usize| cells[i].size().x * cells[i].size().y * cells[i].size().z;
    order.sort_by(|&a, &b| volume(b).total_cmp(&volume(a)).then(a.cmp(&b)));
    order
        .into_iter()
        .map(|i| (i, cells[i].center()))
        .find(|(i, c)| src.locate(*c).ok() == Some(*i as u32))
        .map(|(_, c)| c)
}

/// The one line saying what is served.
fn describe(
    path: &Path,
    pvs: Option<&Path>,
    src: &FileSource,
    cells: &str,
    built: Option<(&str, usize, f64)>,
) {
    let n = src.layout().len();
    let method = src.info().method;
    match (pvs, built) {
        (_, Some((m, bytes, s))) => eprintln!(
            "serving {}: {n} {cells}, PVS built by {m} in {s:.2} s and held in memory ({bytes} bytes)",
            path.display()
        ),
        (Some(p), None) => eprintln!(
            "serving {}: {n} {cells} of {}, method {method}",
            path.display(),
            p.display()
        ),
        (None, None) => {}
    }
}
