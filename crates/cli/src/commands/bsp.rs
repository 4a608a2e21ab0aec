//! BSP levels (`.bsp`) with the portal methods: `pvs LEVEL.bsp --at X,Y,Z --method
//! portals` and the leaf/portal counts of `info`.

use crate::common::print_json;
use anyhow::Context;
use serde::Serialize;
use sightline_core::{Method, VisibilityMethod};
use sightline_geom::ViewCell;
use sightline_portals::{Mode, PortalMethod, Portals};
use sightline_scene::import::bsp::{load_bsp, BspLevel};
use std::path::Path;
use std::time::Instant;

pub fn is_bsp(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("bsp"))
}

/// The portal mode when `scene` is a BSP level and `method` a portal method; an error
/// for a portal method on another scene.
pub fn portal_mode(scene: &Path, method: &str) -> anyhow::Result<Option<Mode>> {
    let mode = match method.parse::<Method>() {
        Ok(Method::Portals) => Mode::Full,
        Ok(Method::PortalsFast) => Mode::Fast,
        _ => return Ok(None),
    };
    if !is_bsp(scene) {
        anyhow::bail!(
            "{method} works on BSP levels (.bsp); {} is not one",
            scene.display()
        );
    }
    Ok(Some(mode))
}

fn level(path: &Path) -> anyhow::Result<BspLevel> {
    load_bsp(path).with_context(|| format!("cannot load {}", path.display()))
}

fn prepare(level: &BspLevel) -> anyhow::Result<Portals> {
    Portals::build(level).context("cannot build the level's portals")
}

#[derive(Serialize)]
struct AtReport {
    method: &'static str,
    at: [f64; 3],
    leaf: u32,
    objects: usize,
    visible: Vec<u32>,
    visible_leaves: Vec<u32>,
    seconds: f64,
}

#[derive(Serialize)]
struct CellReport {
    method: &'static str,
    cell: ViewCell,
    objects: usize,
    visible: Vec<u32>,
    seconds: f64,
}

/// `pvs LEVEL.bsp (--at X,Y,Z | --cell ...) --method portals|portals-fast`.
pub fn pvs(
    path: &Path,
    mode: Mode,
    cell: Option<ViewCell>,
    at: Option<[f64; 3]>,
    json: bool,
) -> anyhow::Result<()> {
    let level = level(path)?;
    let objects = level.faces.len();
    let t = Instant::now();
    let m = PortalMethod::new(prepare(&level)?, mode);
    if let Some(p) = at {
        let leaf = level.point_leaf(p);
        if !level.is_view_leaf(leaf) {
            anyhow::bail!(
                "point {},{},{} is not in open space (leaf {leaf} is solid, sky or outside the level)",
                p[0],
                p[1],
                p[2]
            );
        }
        let pvs = m.leaf_pvs(leaf);
        let report = AtReport {
            method: m.name(),
            at: p,
            leaf,
            objects,
            visible: pvs.faces,
            visible_leaves: pvs.leaves,
            seconds: t.elapsed().as_secs_f64(),
        };
        if json {
            return print_json(&report);
        }
        println!(
            "{}: leaf {leaf}: {} of {} faces and {} of {} leaves potentially visible ({:.1} ms)",
            report.method,
            report.visible.len(),
            objects,
            report.visible_leaves.len(),
            level.visleafs,
            report.seconds * 1e3
        );
        return Ok(());
    }
    let Some(cell) = cell else {
        anyhow::bail!("give --at X,Y,Z or --cell X0,Y0,Z0,X1,Y1,Z1");
    };
    let visible = m.pvs(&cell)?;
    let report = CellReport {
        method: m.name(),
        cell,
        objects,
        visible,
        seconds: t.elapsed().as_secs_f64(),
    };
    if json {
        return print_json(&report);
    }
    println!(
        "{}: {} of {} faces potentially visible from {} ({:.1} ms)",
        report.method,
        report.visible.len(),
        objects,
        cell,
        report.seconds * 1e3
    );
    Ok(())
}

/// Leaf and portal counts of a BSP level, for `info`.
#[derive(Serialize)]
pub struct BspInfo {
    pub leaves: usize,
    pub visleafs: u32,
    pub open_leaves: usize,
    pub portals: usize,
}

pub fn info(path: &Path) -> anyhow::Result<BspInfo> {
    let level = level(path)?;
    let portals = prepare(&level)?;
    Ok(BspInfo {
        leaves: level.leaves.len(),
        visleafs: level.visleafs,
        open_leaves: (1..=level.visleafs)
            .filter(|&l| level.is_view_leaf(l))
            .count(),
        portals: portals.portals().len(),
    })
}

/// `build LEVEL.bsp --method portals|portals-fast -o L.pvs`: the face PVS of every open
/// leaf and its visible leaves (the LEAF section), each leaf stored as its convex cell
/// (`query --at` locates by the leaf's shape and answers as `pvs --at`).
pub fn build(path: &Path, mode: Mode, out: &Path, quiet: bool) -> anyhow::Result<()> {
    let level = level(path)?;
    let t = Instant::now();
    let (bytes, cells) = encode(&level, mode)
        .with_context(|| format!("cannot build the PVS of {}", path.display()))?;
    sightline_pvs::build::write_atomic(out, &bytes)
        .with_context(|| format!("cannot write {}", out.display()))?;
    if !quiet {
        eprintln!(
            "wrote {}: {} leaves, method {}, {} bytes ({:.0} B/leaf), {:.1} s",
            out.display(),
            cells,
            method_of(mode).name(),
            bytes.len(),
            bytes.len() as f64 / cells as f64,
            t.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

fn method_of(mode: Mode) -> Method {
    match mode {
        Mode::Full => Method::Portals,
        Mode::Fast => Method::PortalsFast,
    }
}

/// The `.pvs` of a level (what `build` writes, what `serve` holds in memory) and its
/// number of cells.
pub fn encode(level: &BspLevel, mode: Mode) -> anyhow::Result<(Vec<u8>, usize)> {
    let scene = level.to_scene();
    let portals = prepare(level)?;
    let cells = sightline_portals::leaf_cells(level);
    anyhow::ensure!(!cells.is_empty(), "the level has no open leaf");
    let all = portals.solve_all(mode);
    let pvs_of = |c: &sightline_core::Cell| all.get(c.id().unwrap_or(0) as usize);
    let sets: Vec<roaring::RoaringBitmap> = cells
        .iter()
        .map(|c| {
            pvs_of(c)
                .map(|p| p.faces.iter().copied().collect())
                .unwrap_or_default()
        })
        .collect();
    let leaves: Vec<Vec<u32>> = cells
        .iter()
        .map(|c| pvs_of(c).map(|p| p.leaves.clone()).unwrap_or_default())
        .collect();
    let header = sightline_pvs::Header::new(
        scene.fingerprint(),
        method_of(mode).name(),
        Vec::new(),
        scene.objects.len(),
        cells.len(),
    );
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    let bytes = sightline_pvs::format::encode_cells_with_leaves(
        &header,
        &cells,
        &present,
        &sets,
        Some(&leaves),
        &sightline_pvs::format::EncodeOptions::default(),
    )?;
    Ok((bytes, cells.len()))
}

/// Load a level for `serve`.
pub fn load(path: &Path) -> anyhow::Result<BspLevel> {
    level(path)
}

/// `check LEVEL.bsp --method portals|portals-fast [--reference vis] [--cells K]`: the
/// level's PVS against its own reference (`vis`) and against the ray oracle from `k`
/// source leaves (16 segments per pair we call hidden, 256 for pairs the reference has).
pub fn check(path: &Path, mode: Mode, k: usize, json: bool, quiet: bool) -> anyhow::Result<()> {
    let level = level(path)?;
    let portals = prepare(&level)?;
    let spinner = crate::common::progress(1, quiet, "solving every leaf, then the oracle");
    let r = sightline_portals::reference::compare_with_reference(&portals, mode, k, 16);
    spinner.finish_and_clear();
    if json {
        return print_json(&r);
    }
    println!(
        "{}: {} leaves, {} portals; Σ|PVS| {} leaves = {:.3} × vis ({}), {} faces = {:.3} × the faces of vis's visible leaves ({})",
        r.mode,
        r.visleafs,
        r.portals,
        r.leaves_ours,
        r.leaves_ratio(),
        r.leaves_reference,
        r.faces_ours,
        r.faces_ratio(),
        r.faces_reference,
    );
    println!(
        "oracle from {} source leaves: missed {} leaf pairs; pairs vis has and we lack: {} ({} with a clear segment); {:.1} s",
        r.sources, r.missed_pairs, r.reference_only_pairs, r.reference_only_clear, r.seconds
    );
    anyhow::ensure!(
        r.missed_pairs == 0,
        "{} missed {} visible leaf pairs: a conservativeness bug",
        r.mode,
        r.missed_pairs
    );
    Ok(())
}
