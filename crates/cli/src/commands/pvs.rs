//! `sightline pvs`: the PVS of one viewcell (`--cell`) or of the level's cell holding a
//! point (`--at`) with one method, on any scene ([`sightline_world::World`]).

use crate::cli::Command;
use crate::common::{method_options, open_world, print_json};
use sightline_world::Standing;

pub fn run(cmd: Command, _quiet: bool) -> anyhow::Result<()> {
    let Command::Pvs {
        scene,
        cell,
        at,
        method,
        resolution,
        sweep,
        planes,
        set,
        smallest_hole,
        json,
    } = cmd
    else {
        unreachable!("dispatched by commands::run")
    };
    let opts = method_options(&method, resolution, sweep, planes, &set)?;
    // The method against the kind before loading anything.
    let kind = sightline_world::kind_of(&scene.scene);
    let m = sightline_world::resolve(kind, &scene.scene, Some(&method))?;
    if at.is_some() && sightline_world::portal_mode(m).is_none() {
        anyhow::bail!(
            "--at answers for the leaf holding a point: it needs a .bsp or mesh level (.obj, .gltf, .glb) and --method portals or portals-fast"
        );
    }
    let world = open_world(&scene, smallest_hole, Standing::default())?;
    let answer = match (at, cell) {
        (Some(p), _) => world.pvs_at(m, p)?,
        (None, Some(cell)) => world.pvs_of(m, &cell, &opts)?,
        (None, None) => anyhow::bail!("give --at X,Y,Z or --cell X0,Y0,Z0,X1,Y1,Z1"),
    };
    if json {
        return print_json(&answer);
    }
    let n = answer.visible.len();
    let from = answer.cell.map_or(String::new(), |c| c.to_string());
    match (&answer.visible_sources, answer.leaf, answer.visleafs) {
        (Some(sources), _, _) => println!(
            "{}: {n} of {} clusters ({} of {} source objects) potentially visible from {from} ({:.1} s)",
            answer.method,
            answer.objects,
            sources.len(),
            answer.sources.unwrap_or(0),
            answer.seconds
        ),
        (None, Some(leaf), Some(visleafs)) => println!(
            "{}: leaf {leaf}: {n} of {} faces and {} of {visleafs} leaves potentially visible ({:.1} ms)",
            answer.method,
            answer.objects,
            answer.visible_leaves.as_ref().map_or(0, Vec::len),
            answer.seconds * 1e3
        ),
        _ => println!(
            "{}: {n} of {} {} potentially visible from {from} ({:.1} ms)",
            answer.method,
            answer.objects,
            answer.unit(),
            answer.seconds * 1e3
        ),
    }
    Ok(())
}
