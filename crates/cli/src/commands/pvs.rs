//! `sightline pvs`: the PVS of one viewcell with one method.

use crate::cli::{Command, SceneArg};
use crate::common::{load_scene, method_options, print_json};
use serde::Serialize;
use sightline_geom::ViewCell;
use sightline_methods::{create, MethodOptions};
use std::sync::Arc;
use std::time::Instant;

#[derive(Serialize)]
struct PvsReport<'a> {
    method: &'a str,
    cell: ViewCell,
    objects: usize,
    visible: Vec<u32>,
    seconds: f64,
}

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
    if let Some(full) = crate::commands::mesh::portal_mode(&scene.scene, &method) {
        return crate::commands::mesh::pvs(&scene, full, smallest_hole, cell, at, json);
    }
    if let Some(mode) = crate::commands::bsp::portal_mode(&scene.scene, &method)? {
        return crate::commands::bsp::pvs(&scene.scene, mode, cell, at, json);
    }
    if at.is_some() {
        anyhow::bail!(
            "--at answers for the leaf holding a point: it needs a .bsp or mesh level (.obj, .gltf, .glb) and --method portals or portals-fast"
        );
    }
    let Some(cell) = cell else {
        anyhow::bail!("--cell is required");
    };
    pvs(&scene, &cell, &method, &opts, json)
}

fn pvs(
    scene_arg: &SceneArg,
    cell: &ViewCell,
    method: &str,
    opts: &MethodOptions,
    json: bool,
) -> anyhow::Result<()> {
    let scene = Arc::new(load_scene(scene_arg)?);
    let m = create(method, scene.clone(), opts)?;
    let t = Instant::now();
    let visible = m.pvs(cell)?;
    let seconds = t.elapsed().as_secs_f64();
    let report = PvsReport {
        method: m.name(),
        cell: *cell,
        objects: scene.objects.len(),
        visible,
        seconds,
    };
    if json {
        print_json(&report)
    } else {
        println!(
            "{}: {} of {} objects potentially visible from {} ({:.1} ms)",
            report.method,
            report.visible.len(),
            report.objects,
            report.cell,
            seconds * 1e3
        );
        Ok(())
    }
}
