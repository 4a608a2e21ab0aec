//! BSP levels (`.bsp`): their open leaves are the cells, their portals come from the
//! tree, the portal methods solve them (`sightline-portals`, Teller & Séquin 1991,
//! [docs/methods/portals.md](../../../docs/methods/portals.md)).

use anyhow::Context;
use serde::Serialize;
use sightline_core::Method;
use sightline_portals::{Mode, Portals};
use sightline_scene::import::bsp::BspLevel;

/// Leaf and portal counts of a BSP level, for `info`.
#[derive(Clone, Debug, Serialize)]
pub struct BspInfo {
    pub leaves: usize,
    pub visleafs: u32,
    pub open_leaves: usize,
    pub portals: usize,
}

/// The portals of a level, from its tree.
pub fn portals(level: &BspLevel) -> anyhow::Result<Portals> {
    Portals::build(level).context("cannot build the level's portals")
}

/// The leaf and portal counts of `level`.
pub fn info(level: &BspLevel) -> anyhow::Result<BspInfo> {
    let portals = portals(level)?;
    Ok(BspInfo {
        leaves: level.leaves.len(),
        visleafs: level.visleafs,
        open_leaves: (1..=level.visleafs)
            .filter(|&l| level.is_view_leaf(l))
            .count(),
        portals: portals.portals().len(),
    })
}

/// The method of a portal mode.
pub fn method_of(mode: Mode) -> Method {
    match mode {
        Mode::Full => Method::Portals,
        Mode::Fast => Method::PortalsFast,
    }
}

/// The `.pvs` of a level (what `build` writes, what `serve` holds in memory) and its
/// number of cells: the face PVS of every open leaf and its visible leaves (the LEAF
/// section), each leaf stored as its convex cell (`query --at` locates by the leaf's
/// shape and answers as `pvs --at`).
pub fn encode(level: &BspLevel, mode: Mode) -> anyhow::Result<(Vec<u8>, usize)> {
    let scene = level.to_scene();
    let portals = portals(level)?;
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
