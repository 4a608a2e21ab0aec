//! `sightline truth`: the ground-truth visible set of one viewcell.

use crate::cli::Command;
use crate::common::{load_scene, print_json};
use anyhow::bail;
use sightline_core::check::{TruthOptions, TruthScene};
use std::io::IsTerminal;

/// Largest accepted cube-face resolution and sample count (memory and time stay sane).
pub const MAX_RESOLUTION: u32 = 8192;
pub const MAX_SAMPLES: u32 = 100_000;

/// Truth options from the command line, validated.
pub fn truth_options(
    samples: Option<u32>,
    resolution: Option<u32>,
) -> anyhow::Result<TruthOptions> {
    let mut opts = TruthOptions::default();
    if let Some(s) = samples {
        if s == 0 || s > MAX_SAMPLES {
            bail!("--samples must be between 1 and {MAX_SAMPLES}, got {s}");
        }
        opts.samples = s;
    }
    if let Some(r) = resolution {
        if !(8..=MAX_RESOLUTION).contains(&r) {
            bail!("--resolution must be between 8 and {MAX_RESOLUTION}, got {r}");
        }
        opts.resolution_px = r;
    }
    Ok(opts)
}

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Truth {
        scene,
        cell,
        samples,
        resolution,
        json,
    } = cmd
    else {
        bail!("internal: `truth` called with another command");
    };
    let opts = truth_options(samples, resolution)?;
    let sc = load_scene(&scene)?;
    let ts = TruthScene::new(&sc);
    let spinner = if quiet || !std::io::stderr().is_terminal() {
        indicatif::ProgressBar::hidden()
    } else {
        let s = indicatif::ProgressBar::new_spinner();
        s.set_message(format!("sampling {} viewpoints", opts.samples));
        s.enable_steady_tick(std::time::Duration::from_millis(120));
        s
    };
    let truth = ts.ground_truth(&cell, &opts);
    spinner.finish_and_clear();
    if truth.samples_used == 0 {
        bail!("viewcell {cell} has no free space (it lies inside a building or below the ground)");
    }
    if json {
        print_json(&serde_json::json!({
            "cell": cell,
            "samples": opts.samples,
            "samples_used": truth.samples_used,
            "resolution": opts.resolution_px,
            "targeted_rays_per_object": opts.targeted_rays_per_object,
            "objects": sc.objects.len(),
            "visible": truth.visible,
            "found_by_rays": truth.found_by_rays,
            "seconds": truth.seconds,
        }))
    } else {
        println!(
            "cell {cell}: {} of {} objects visible ({} viewpoints, {} px cube faces, {} found only by targeted rays) in {:.2} s",
            truth.visible.len(),
            sc.objects.len(),
            truth.samples_used,
            opts.resolution_px,
            truth.found_by_rays,
            truth.seconds
        );
        let ids: Vec<String> = truth.visible.iter().map(u32::to_string).collect();
        println!("visible: {}", ids.join(" "));
        Ok(())
    }
}
