//! `sightline bench`: see [`crate::bench`].

use crate::bench::{find_levels, run as run_bench, MeshLevel, Sections, Suite};
use crate::cli::Command;
use std::path::PathBuf;

/// The indoor section's levels when `--levels` is not given.
const DEFAULT_LEVELS: &str = "data/quake";

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Bench {
        suite,
        scene,
        methods,
        levels,
        indoor_only,
        meshes,
        mesh_viewcells,
        out,
        only,
        vis_reference,
        vis_prt,
    } = cmd
    else {
        unreachable!("dispatched by commands::run")
    };
    let mut suite = Suite::named(&suite)?;
    suite.vis_reference = vis_reference.or_else(crate::bench::detect_vis_reference);
    suite.vis_prt = vis_prt;
    if let Some(n) = mesh_viewcells {
        suite.mesh_viewcells = (n > 0).then_some(n);
    }
    suite.only = only.map(|o| {
        o.split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect()
    });
    let methods = methods.map(|m| {
        m.split(',')
            .map(|s| s.trim().to_string())
            .filter(|s| !s.is_empty())
            .collect()
    });
    let levels = if levels.is_empty() {
        let default = PathBuf::from(DEFAULT_LEVELS);
        if default.is_dir() {
            find_levels(&[default])?
        } else {
            Vec::new()
        }
    } else {
        find_levels(&levels)?
    };
    // --meshes: the generated level first, then the files given.
    let meshes = meshes.map_or_else(Vec::new, |files| {
        std::iter::once(MeshLevel::Generated)
            .chain(files.into_iter().map(MeshLevel::File))
            .collect()
    });
    let sections = Sections {
        cities: !indoor_only,
        levels,
        meshes,
    };
    run_bench(suite, &scene, methods, &sections, &out, quiet)?;
    if !quiet {
        eprintln!("report written to {}", out.join("README.md").display());
    }
    Ok(())
}
