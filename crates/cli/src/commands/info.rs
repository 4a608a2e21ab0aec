//! `sightline info SCENE [--json]`: counts, bounds and warnings.

use crate::cli::Command;
use crate::common::{open_world, print_json};
use sightline_world::{BspInfo, Standing};

pub fn run(cmd: Command, _quiet: bool) -> anyhow::Result<()> {
    let Command::Info { scene: arg, json } = cmd else {
        anyhow::bail!("internal: info called with another command");
    };
    let world = open_world(&arg, None, Standing::default())?;
    let scene = world.scene();
    let b = scene.bounds;
    let info = scene.info(arg.scene.display().to_string());
    let bsp = world.bsp_info()?;
    if json {
        #[derive(serde::Serialize)]
        struct WithBsp<'a, T: serde::Serialize> {
            #[serde(flatten)]
            info: &'a T,
            #[serde(skip_serializing_if = "Option::is_none")]
            bsp: Option<&'a BspInfo>,
        }
        return print_json(&WithBsp {
            info: &info,
            bsp: bsp.as_ref(),
        });
    }
    if let Some(b) = &bsp {
        println!(
            "BSP:       {} leaves ({} visleafs, {} open), {} portals",
            b.leaves, b.visleafs, b.open_leaves, b.portals
        );
    }
    println!("scene:     {}", info.scene);
    println!(
        "objects:   {} ({} blocks, {} flat, {} meshes)",
        info.objects, info.blocks, info.flat, info.meshes
    );
    println!("triangles: {}", info.triangles);
    let s = b.size();
    println!(
        "bounds:    x {:.2}..{:.2}, y {:.2}..{:.2}, z {:.2}..{:.2} ({:.1} x {:.1} x {:.1} m)",
        b.min.x, b.max.x, b.min.y, b.max.y, b.min.z, b.max.z, s.x, s.y, s.z
    );
    println!("fingerprint: {}", info.fingerprint);
    println!("warnings:  {}", scene.warnings.len());
    for (kind, n) in &info.warning_counts {
        println!("  {kind}: {n}");
    }
    const SHOWN: usize = 20;
    for w in scene.warnings.iter().take(SHOWN) {
        match w.feature {
            Some(i) => println!("  - feature {i}: {} ({})", w.message, w.kind),
            None => println!("  - {} ({})", w.message, w.kind),
        }
    }
    if scene.warnings.len() > SHOWN {
        println!(
            "  ... {} more (--json lists all)",
            scene.warnings.len() - SHOWN
        );
    }
    Ok(())
}
