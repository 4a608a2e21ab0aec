//! `sightline frames`: from-point occlusion culling along a camera path (`docs/culling.md`), with
//! optional two-level culling inside the PVS of the eye's cell.

use crate::cli::Command;
use crate::cli::OccluderArg;
use crate::common::{load_scene, print_json, progress};
use anyhow::{bail, Context};
use sightline_culling::walk::{floor_frames, street_walk, PathFrame};
use sightline_culling::{method, CullScene, Frustum};
use sightline_geom::DVec3;
use sightline_pvs::PvsFile;
use sightline_scene::Geometry;
use std::sync::Arc;
use std::time::Instant;

/// Most frames of a generated walk.
pub const MAX_WALK: usize = 1_000_000;

/// `WIDTHxHEIGHT`.
fn parse_size(s: &str) -> anyhow::Result<(u32, u32)> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .with_context(|| format!("--size '{s}' is not WIDTHxHEIGHT"))?;
    let w: u32 = w
        .trim()
        .parse()
        .with_context(|| format!("--size '{s}': bad width"))?;
    let h: u32 = h
        .trim()
        .parse()
        .with_context(|| format!("--size '{s}': bad height"))?;
    Ok((w, h))
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

pub fn run(cmd: Command, quiet: bool) -> anyhow::Result<()> {
    let Command::Frames {
        scene,
        path,
        walk,
        seed,
        pvs,
        method: name,
        size,
        occluders,
        eye_height,
        json,
    } = cmd
    else {
        bail!("internal: `frames` called with another command");
    };
    let (width, height) = parse_size(&size)?;
    let sc = load_scene(&scene)?;
    let frames: Vec<PathFrame> = match (&path, walk) {
        (Some(p), _) => {
            let bytes = std::fs::read(p).with_context(|| format!("cannot read {}", p.display()))?;
            serde_json::from_slice(&bytes).with_context(|| {
                format!(
                    "{}: expected a JSON list of {{\"eye\": [x,y,z], \"dir\": [dx,dy,dz], \"fov_deg\": f}}",
                    p.display()
                )
            })?
        }
        (None, Some(n)) => {
            if n == 0 || n > MAX_WALK {
                bail!("--walk must be between 1 and {MAX_WALK}, got {n}");
            }
            let has_blocks = sc
                .objects
                .iter()
                .any(|o| matches!(o.geometry, Geometry::Blocks(_)));
            if has_blocks {
                let w = street_walk(&sc, n, seed, 60.0);
                if w.is_empty() {
                    bail!("no free street-level point found in the scene for --walk");
                }
                w
            } else {
                if !(eye_height.is_finite() && eye_height > 0.0) {
                    bail!("--eye-height must be a positive number, got {eye_height}");
                }
                let w = floor_frames(&sc, n, seed, eye_height, 60.0);
                if w.is_empty() {
                    bail!("no floor (upward-facing mesh triangle) in the scene for --walk");
                }
                w
            }
        }
        (None, None) => bail!("give --path FILE or --walk N"),
    };
    let pvs = match &pvs {
        Some(p) => {
            let f = PvsFile::open(p).with_context(|| format!("cannot open {}", p.display()))?;
            f.check_scene(&sc)
                .with_context(|| format!("{} was not built for this scene", p.display()))?;
            Some(f)
        }
        None => None,
    };
    let has_meshes = sc
        .objects
        .iter()
        .any(|o| matches!(o.geometry, Geometry::Mesh(_)));
    let surfaces = match occluders {
        OccluderArg::Auto => has_meshes,
        OccluderArg::Prisms => false,
        OccluderArg::Surfaces => true,
    };
    let cs = Arc::new(if surfaces {
        CullScene::with_surfaces(&sc)
    } else {
        CullScene::new(&sc)
    });
    let occluder_desc = format!(
        "{} prisms{}",
        cs.occluders.len() - cs.surface_occluders,
        if surfaces {
            format!(" + {} mesh surfaces", cs.surface_occluders)
        } else {
            String::new()
        }
    );
    let (cs_occluders, cs_surfaces) = (cs.occluders.len(), cs.surface_occluders);
    let culler = method(&name, cs)?;
    let bar = progress(frames.len() as u64, quiet, "frames");
    let mut out = Vec::with_capacity(frames.len());
    let (mut ms_all, mut culled_all, mut second_all) = (Vec::new(), Vec::new(), Vec::new());
    for (k, pf) in frames.iter().enumerate() {
        let f = Frustum::new(
            DVec3::from_array(pf.eye),
            DVec3::from_array(pf.dir),
            pf.fov_deg,
            width,
            height,
        )
        .with_context(|| format!("frame {k}"))?;
        let cell = match &pvs {
            Some(file) => file
                .query(f.eye)
                .with_context(|| format!("frame {k}: reading the PVS of the eye's cell"))?,
            None => None,
        };
        let t0 = Instant::now();
        let fr = culler.cull(&f, cell.as_ref().map(|(_, ids)| ids.as_slice()));
        let ms = t0.elapsed().as_secs_f64() * 1e3;
        // Culled share of the whole scene; with a PVS also of the cell's PVS alone.
        let objects = sc.objects.len();
        let culled_pct = if objects == 0 {
            0.0
        } else {
            100.0 * (objects - fr.visible.len()) as f64 / objects as f64
        };
        ms_all.push(ms);
        culled_all.push(culled_pct);
        let mut v = serde_json::json!({
            "visible": fr.visible,
            "culled_pct": culled_pct,
            "ms": ms,
            "frustum_culled": fr.frustum_culled,
            "occlusion_culled": fr.occlusion_culled,
            "occluder_tris": fr.occluder_tris,
        });
        if pvs.is_some() {
            match &cell {
                Some((c, ids)) => {
                    second_all.push(fr.culled_pct());
                    v["cell"] = serde_json::json!(c);
                    v["pvs_size"] = serde_json::json!(ids.len());
                    v["second_level_removed_pct"] = serde_json::json!(fr.culled_pct());
                }
                None => v["cell"] = serde_json::Value::Null,
            }
        }
        out.push(v);
        bar.inc(1);
    }
    bar.finish_and_clear();
    let n = out.len();
    if json {
        let mut report = serde_json::json!({
            "method": culler.name(),
            "conservative": culler.is_conservative(),
            "size": [width, height],
            "objects": sc.objects.len(),
            "frames": out,
            "median_ms": median(ms_all.clone()),
            "median_culled_pct": median(culled_all.clone()),
            "occluders": if surfaces { "surfaces" } else { "prisms" },
            "occluder_count": cs_occluders,
            "surface_occluders": cs_surfaces,
        });
        if pvs.is_some() {
            report["median_second_level_removed_pct"] = serde_json::json!(median(second_all));
        }
        print_json(&report)
    } else {
        println!(
            "{} frames, {} ({}), {width}x{height}, occluders {occluder_desc}: median {:.2} ms per frame, median {:.1} % of {} objects culled",
            n,
            culler.name(),
            if culler.is_conservative() { "conservative" } else { "approximate, NOT conservative" },
            median(ms_all),
            median(culled_all),
            sc.objects.len()
        );
        if pvs.is_some() {
            println!(
                "two-level: the second level removes a median {:.1} % of the cell's PVS ({} of {} frames in a cell)",
                median(second_all.clone()),
                second_all.len(),
                n
            );
        }
        Ok(())
    }
}
