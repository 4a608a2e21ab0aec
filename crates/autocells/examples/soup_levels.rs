//! Quake levels read as triangle soups (issue #39 item 5): each level's world faces go
//! through the automatic-cell pipeline with no tree, and the face PVS at random
//! viewpoints is compared with the faces of vis's leaves, the BSP path's face PVS and
//! the ray oracle through the BSP tree ([`sightline_autocells::soup::judge`]).
//!
//! `cargo run --release -p sightline-autocells --example soup_levels -- LEVELS... [h=H]
//! [points=N] [bsp=fast|full] [auto=fast|full] [max_voxels=N] [group=G] [max_box=B] [obj=DIR]`
//! (LEVELS: `.bsp` files or folders of them; H: the smallest hole in Quake units,
//! default 4; N: viewpoints per level, default 60; G, B: `Options::group_block`
//! (0: every box a solver cell) and `Options::max_box`; `obj=DIR` also writes each soup as
//! `DIR/LEVEL.obj`, one `o face_N` per face).

use sightline_autocells::soup::{bsp_soup, judge, wall_thickness, JudgeOptions};
use sightline_autocells::{AutoCells, Options};
use sightline_portals::{Mode, Portals};
use sightline_scene::import::bsp::load_bsp;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn reset_peak() {
    std::fs::write("/proc/self/clear_refs", "5").ok();
}

fn peak_mb() -> f64 {
    sightline_stats::memory_kib().1 as f64 / 1024.0
}

fn levels(args: &[String]) -> Result<Vec<PathBuf>, Box<dyn std::error::Error>> {
    let mut out = Vec::new();
    for a in args.iter().filter(|a| !a.contains('=')) {
        let p = Path::new(a);
        if p.is_dir() {
            let mut v: Vec<PathBuf> = std::fs::read_dir(p)?
                .filter_map(|e| e.ok().map(|e| e.path()))
                .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("bsp")))
                .collect();
            v.sort();
            out.extend(v);
        } else {
            out.push(p.to_path_buf());
        }
    }
    Ok(out)
}

fn arg<T: std::str::FromStr>(args: &[String], key: &str) -> Result<Option<T>, String> {
    args.iter()
        .filter_map(|a| a.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
        .next_back()
        .map(|v| v.parse::<T>().map_err(|_| format!("bad value {key}={v}")))
        .transpose()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let paths = levels(&args)?;
    if paths.is_empty() {
        return Err("usage: soup_levels LEVELS... [h=H] [points=N] [bsp=fast|full] [auto=fast|full] [max_voxels=N] [group=G] [max_box=B] [obj=DIR]".into());
    }
    let h: f64 = arg(&args, "h")?.unwrap_or(4.0);
    let points: usize = arg(&args, "points")?.unwrap_or(60);
    let max_voxels: usize = arg(&args, "max_voxels")?.unwrap_or(1 << 27);
    let bsp_full = arg::<String>(&args, "bsp")?.is_some_and(|m| m == "full");
    let auto_full = arg::<String>(&args, "auto")?.is_some_and(|m| m == "full");
    let obj_dir: Option<PathBuf> = arg(&args, "obj")?;
    let group_block: usize = arg(&args, "group")?.unwrap_or(Options::default().group_block);
    let max_box: usize = arg(&args, "max_box")?.unwrap_or(Options::default().max_box);
    let bsp_mode = if bsp_full { Mode::Full } else { Mode::Fast };
    let mut rows = Vec::new();
    for path in &paths {
        let name = path.file_stem().map_or_else(
            || path.display().to_string(),
            |s| s.to_string_lossy().into(),
        );
        let level = load_bsp(path)?;
        reset_peak();
        let soup = bsp_soup(&level);
        if let Some(dir) = &obj_dir {
            let file = std::fs::File::create(dir.join(format!("{name}.obj")))?;
            soup.write_obj(std::io::BufWriter::new(file))?;
        }
        let mut thick: Vec<f64> = wall_thickness(&level, &soup, 0.25, 64.0)
            .into_iter()
            .flatten()
            .collect();
        thick.sort_by(f64::total_cmp);
        let under = |t: f64| thick.iter().filter(|&&x| x <= t).count();
        println!(
            "{name}: walls behind {} of {} faces within 64 units: thinnest {:.2}, p1 {:.2}, p5 {:.2}, median {:.2}; ≤ 2 h: {}, ≤ 4: {}, ≤ 8: {}, ≤ 16: {}",
            thick.len(),
            soup.faces.len(),
            thick.first().copied().unwrap_or(f64::NAN),
            thick.get(thick.len() / 100).copied().unwrap_or(f64::NAN),
            thick.get(thick.len() / 20).copied().unwrap_or(f64::NAN),
            thick.get(thick.len() / 2).copied().unwrap_or(f64::NAN),
            under(2.0 * h),
            under(4.0),
            under(8.0),
            under(16.0),
        );
        let opts = Options {
            smallest_hole: Some(h),
            max_voxels,
            full: auto_full,
            group_block,
            max_box,
            ..Options::default()
        };
        let t = Instant::now();
        let auto = AutoCells::build(&soup.scene, &opts)?;
        let seconds_auto = t.elapsed().as_secs_f64();
        let r = &auto.report;
        println!(
            "{name}: {} faces ({} liquid left out), h {:.3}{}, grid {:?} = {} voxels: {} surface, {} air, {} solid ({} of {} components solid), {} closed faces, {} sealed; {} cells, {} portals, solver {} cells / {} portals; voxels {:.2} s, cells {:.2} s, pvs {:.2} s, total {seconds_auto:.2} s{}",
            soup.faces.len(),
            soup.liquid_faces,
            r.smallest_hole,
            r.smallest_hole_asked.map_or(String::new(), |a| format!(" (asked {a})")),
            r.grid,
            r.voxels.voxels,
            r.voxels.surface,
            r.voxels.air,
            r.voxels.solid,
            r.voxels.solid_components,
            r.voxels.components,
            r.voxels.closed_faces,
            r.voxels.sealed,
            r.cells,
            r.portals,
            r.groups,
            r.group_portals,
            r.seconds_voxels,
            r.seconds_cells,
            r.seconds_pvs,
            r.leak.as_ref().map_or(String::new(), |l| format!(
                "; LEAK from {:?} to {:?}",
                l.inside, l.border
            )),
        );
        let t = Instant::now();
        let portals = Portals::build(&level)?;
        let jopts = JudgeOptions {
            viewpoints: points,
            bsp_mode,
            ..JudgeOptions::default()
        };
        let j = judge(&level, &soup, &auto, &portals, &jopts);
        let seconds_judge = t.elapsed().as_secs_f64();
        let peak = peak_mb();
        let (ours, vis, bsp) = (j.sum_ours(), j.sum_vis(), j.sum_bsp());
        println!(
            "{name}: {} viewpoints ({} drawn in solid voxels), Σours {ours} / Σvis-faces {vis} = {:.3}, / Σbsp-{} {bsp} = {:.3}; median culled: ours {:.1} %, vis {:.1} %, bsp {:.1} %; oracle {} segments, {} missed; {seconds_judge:.1} s, peak {peak:.0} MB",
            j.viewpoints.len(),
            j.viewpoints_in_solid,
            ours as f64 / vis.max(1) as f64,
            if bsp_full { "portals" } else { "portals-fast" },
            ours as f64 / bsp.max(1) as f64,
            100.0 * j.median_culled(|v| v.ours),
            100.0 * j.median_culled(|v| v.vis),
            100.0 * j.median_culled(|v| v.bsp),
            j.segments,
            j.missed,
        );
        for m in &j.misses {
            println!(
                "MISS     {name}: cell {} {:?} face {} ({}in vis) from {:?} to {:?}",
                m.cell,
                auto.cell_box(m.cell as usize),
                m.face,
                if m.in_vis { "" } else { "not " },
                m.from,
                m.to
            );
        }
        rows.push(format!(
            "| {name} | {:.2} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.1} % | {} ({} segments) | {:.0} |",
            r.smallest_hole,
            r.voxels.voxels,
            r.cells,
            r.portals,
            seconds_auto,
            ours as f64 / vis.max(1) as f64,
            ours as f64 / bsp.max(1) as f64,
            100.0 * j.median_culled(|v| v.ours),
            j.missed,
            j.segments,
            peak
        ));
    }
    println!(
        "\n| level | h | voxels | cells | portals | time {} (s) | Σours/Σvis faces | Σours/Σbsp-{} faces | median % faces culled | misses | peak MB |",
        if auto_full { "full" } else { "fast" },
        if bsp_full { "portals" } else { "portals-fast" }
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        println!("{r}");
    }
    Ok(())
}
