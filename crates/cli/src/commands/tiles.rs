//! `sightline tiles SCENE -o DIR [--max-features-per-tile N] [--pvs FILE] [--json]`: the
//! scene as a 3D Tiles 1.1 tileset, with the tile-level PVS sidecar when a `.pvs` is
//! given (`docs/3d-tiles.md`).

use crate::cli::Command;
use crate::common::{load_scene, print_json};
use anyhow::Context;
use serde::Serialize;
use sightline_tiles::layout::Layout;
use sightline_tiles::pvs::SIDECAR_FILE;

#[derive(Serialize)]
struct Report {
    tileset: String,
    objects: usize,
    tiles: usize,
    content_tiles: usize,
    features: usize,
    bytes: u64,
    /// Cells of the sidecar (0 without `--pvs`).
    pvs_cells: usize,
    /// Mean tiles listed per cell of the sidecar.
    pvs_tiles_per_cell: f64,
}

pub fn run(cmd: Command, _quiet: bool) -> anyhow::Result<()> {
    let Command::Tiles {
        scene: arg,
        out,
        max_features_per_tile,
        pvs,
        json,
    } = cmd
    else {
        anyhow::bail!("internal: tiles called with another command");
    };
    if max_features_per_tile == 0 {
        anyhow::bail!("--max-features-per-tile must be at least 1");
    }
    let scene = load_scene(&arg)?;
    let layout = Layout::build(&scene, max_features_per_tile)
        .with_context(|| format!("{}: the scene has no objects", arg.scene.display()))?;
    let mut extra = Vec::new();
    let (mut cells, mut listed) = (0, 0);
    if let Some(p) = &pvs {
        let file = sightline_pvs::PvsFile::open(p)
            .with_context(|| format!("cannot open {}", p.display()))?;
        let sidecar = sightline_tiles::sidecar_from_pvs(&scene, &layout, &file)
            .with_context(|| format!("{}", p.display()))?;
        cells = sidecar.cells.len();
        listed = sidecar.cells.iter().map(|c| c.tiles.len()).sum::<usize>();
        extra.push((SIDECAR_FILE, serde_json::to_vec(&sidecar)?));
    }
    let stats = sightline_tiles::export::write(&scene, &layout, &out, &extra)
        .with_context(|| format!("cannot write the tileset {}", out.display()))?;
    let report = Report {
        tileset: out.join("tileset.json").display().to_string(),
        objects: scene.len(),
        tiles: stats.tiles,
        content_tiles: stats.content_tiles,
        features: stats.features,
        bytes: stats.bytes,
        pvs_cells: cells,
        pvs_tiles_per_cell: if cells > 0 {
            listed as f64 / cells as f64
        } else {
            0.0
        },
    };
    if json {
        return print_json(&report);
    }
    print!(
        "wrote {}: {} objects in {} tiles ({} with content), {} bytes",
        report.tileset, report.objects, report.tiles, report.content_tiles, report.bytes
    );
    if cells > 0 {
        print!(
            "; {SIDECAR_FILE}: {cells} cells, {:.1} tiles per cell",
            report.pvs_tiles_per_cell
        );
    }
    println!();
    Ok(())
}
