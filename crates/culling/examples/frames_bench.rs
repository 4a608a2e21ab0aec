//! Benchmark of the from-point cullers on street-level walks through real cities.
//!
//! `cargo run --release -p sightline-culling --example frames_bench -- [--frames N]
//! [--size WxH] [--truth-every K] [--full-every K] [--raster-only] [--indoor EYE_HEIGHT]
//! [SCENE ...]` (`--indoor`: a BSP or mesh level, its surfaces as occluders, eyes above
//! random floor triangles) (default: the project's Lyon and Den Haag
//! extracts, 10,000 frames, 1920x1080). Reports per scene:
//! * occluder triangles/s on one core: the masked tile rasterizer of `hzb` against the
//!   full-resolution inner-union rasterizer of `sightline-raster`, same frames;
//! * culled % of each method and of the full-resolution depth buffer of the same
//!   occluders (the `sightline-raster` pyramid), and their ratio;
//! * median / p90 ms per frame per method;
//! * false culls against the item-buffer truth (on every K-th frame);
//! * two-level culling: the frame culled within a conservative PVS stand-in (the `hzb`
//!   answer of a wider frustum from the same eye), how much the second level removes.

use glam::DVec3;
use sightline_culling::masked::RasterPath;
use sightline_culling::measure::{full_res, full_res_occluded, masked_throughput, Throughput};
use sightline_culling::truth::FrameTruth;
use sightline_culling::walk::{floor_frames, street_walk};
use sightline_culling::{method, CullScene, Frustum};
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

fn p90(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[(v.len() * 9 / 10).min(v.len() - 1)]
}

fn main() {
    let mut frames = 10_000usize;
    let (mut w, mut h) = (1920u32, 1080u32);
    let mut truth_every = 50usize;
    let mut full_every = 10usize;
    let mut scenes: Vec<PathBuf> = Vec::new();
    // Only the occluder rasterization (scalar, SIMD), for profiling.
    let mut raster_only = false;
    // Indoor scenes (BSP, meshes): surfaces as occluders, eyes this high above floors.
    let mut indoor_eye: Option<f64> = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--frames" => {
                frames = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--frames N")
            }
            "--truth-every" => {
                truth_every = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--truth-every K")
            }
            "--full-every" => {
                full_every = args
                    .next()
                    .and_then(|v| v.parse().ok())
                    .expect("--full-every K")
            }
            "--raster-only" => raster_only = true,
            "--indoor" => {
                indoor_eye = Some(
                    args.next()
                        .and_then(|v| v.parse().ok())
                        .expect("--indoor EYE_HEIGHT"),
                )
            }
            "--size" => {
                let s = args.next().expect("--size WxH");
                let (a, b) = s.split_once('x').expect("--size WxH");
                w = a.parse().expect("width");
                h = b.parse().expect("height");
            }
            _ => scenes.push(PathBuf::from(a)),
        }
    }
    if scenes.is_empty() {
        let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data");
        scenes = vec![
            data.join("lyon1_bdtopo.geojson"),
            data.join("denhaag_tile01_lod2.geojson"),
        ];
    }
    println!("frames_bench: {frames} frames per scene, {w}x{h}, truth every {truth_every}, full-res every {full_every}; one thread");
    for path in scenes {
        let scene = sightline_scene::import::load(&path, &Default::default()).expect("scene loads");
        let cs = Arc::new(match indoor_eye {
            Some(_) => CullScene::with_surfaces(&scene),
            None => CullScene::new(&scene),
        });
        let truth = FrameTruth::new(&scene);
        let walk = match indoor_eye {
            Some(h) => floor_frames(&scene, frames, 42, h, 60.0),
            None => street_walk(&scene, frames, 42, 60.0),
        };
        let names = ["hzb", "hom", "hom-approx", "cplp"];
        let cullers: Vec<_> = names
            .iter()
            .map(|n| method(n, cs.clone()).unwrap())
            .collect();
        let mut ms = vec![Vec::new(); names.len()];
        let mut culled = vec![0usize; names.len()];
        let mut occl = vec![0usize; names.len()];
        let mut false_culls = vec![0usize; names.len()];
        let mut truth_frames = 0usize;
        let mut scalar_rates = Vec::new();
        let mut simd_rates = Vec::new();
        let mut full_rates = Vec::new();
        let (mut scalar_th, mut simd_th, mut full_th) = (
            Throughput::default(),
            Throughput::default(),
            Throughput::default(),
        );
        let (mut full_occl, mut hzb_occl_same) = (0usize, 0usize);
        let (mut two_cand, mut two_vis) = (0usize, 0usize);
        let mut total = 0usize;
        let mut hzb_tris = 0u64;
        for (k, pf) in walk.iter().enumerate() {
            let f = Frustum::new(
                DVec3::from_array(pf.eye),
                DVec3::from_array(pf.dir),
                pf.fov_deg,
                w,
                h,
            )
            .unwrap();
            total += cs.objects();
            let mut answers = Vec::new();
            for (m, c) in cullers.iter().enumerate().filter(|_| !raster_only) {
                let t0 = Instant::now();
                let fr = c.cull(&f, None);
                ms[m].push(t0.elapsed().as_secs_f64() * 1e3);
                culled[m] += fr.candidates - fr.visible.len();
                if m == 0 {
                    hzb_tris += fr.occluder_tris;
                }
                occl[m] += fr.occlusion_culled;
                answers.push(fr);
            }
            // Rasterizer throughput: every front face in the frustum (no skipping of
            // hidden prisms), the same faces the full-resolution reference draws.
            for (path, th, rates) in [
                (RasterPath::Scalar, &mut scalar_th, &mut scalar_rates),
                (RasterPath::Simd, &mut simd_th, &mut simd_rates),
            ] {
                let t = masked_throughput(&cs, &f, path);
                th.tris += t.tris;
                th.seconds += t.seconds;
                rates.push(t.tris_per_s());
            }
            if raster_only {
                continue;
            }
            if k % full_every == 0 {
                let (fb, t) = full_res(&cs, &f);
                full_th.tris += t.tris;
                full_th.seconds += t.seconds;
                full_rates.push(t.tris_per_s());
                full_occl += full_res_occluded(&cs, &f, &fb);
                hzb_occl_same += answers[0].occlusion_culled;
            }
            if k % truth_every == 0 {
                truth_frames += 1;
                let vs = truth.visible(&f);
                for (m, fr) in answers.iter().enumerate() {
                    false_culls[m] += vs
                        .iter()
                        .filter(|i| fr.visible.binary_search(i).is_err())
                        .count();
                }
                // Two-level: the first level is a conservative set for the eye (the hzb
                // answer of a 120° frustum around the same direction); the second culls
                // the frame within it.
                let wide = Frustum::new(f.eye, f.dir, 120.0, w, h).unwrap();
                let first = cullers[0].cull(&wide, None).visible;
                let second = cullers[0].cull(&f, Some(&first));
                two_cand += first.len();
                two_vis += second.visible.len();
            }
        }
        println!(
            "\n## {} ({} objects, {} occluders of which {} mesh surfaces, {} frames)",
            path.display(),
            cs.objects(),
            cs.occluders.len(),
            cs.surface_occluders,
            walk.len()
        );
        println!(
            "occluder tris/s (one core, median of frames / total): masked scalar {:.2} / {:.2} M; masked {} {:.2} / {:.2} M; sightline-raster full-res union {:.2} / {:.2} M ({} tris in {:.2} s masked, {:.2} s scalar)",
            median(&mut scalar_rates) / 1e6, scalar_th.tris_per_s() / 1e6,
            RasterPath::Simd.describe(),
            median(&mut simd_rates) / 1e6, simd_th.tris_per_s() / 1e6,
            median(&mut full_rates) / 1e6, full_th.tris_per_s() / 1e6,
            simd_th.tris, simd_th.seconds, scalar_th.seconds
        );
        println!(
            "hzb draws {:.0} occluder tris per frame (prisms already hidden are skipped) of {:.0} front-facing in the frustum",
            hzb_tris as f64 / walk.len().max(1) as f64,
            simd_th.tris as f64 / walk.len().max(1) as f64
        );
        println!(
            "occlusion-culled on the full-res frames: hzb {} vs full-res depth buffer {} ({:.1} %)",
            hzb_occl_same,
            full_occl,
            100.0 * hzb_occl_same as f64 / full_occl.max(1) as f64
        );
        println!("| method | conservative | culled % | occlusion-culled/frame | median ms | p90 ms | false culls / truth frames |");
        println!("|---|---|---|---|---|---|---|");
        for (m, c) in cullers.iter().enumerate() {
            println!(
                "| {} | {} | {:.1} | {:.1} | {:.2} | {:.2} | {} / {} |",
                c.name(),
                c.is_conservative(),
                100.0 * culled[m] as f64 / total.max(1) as f64,
                occl[m] as f64 / walk.len().max(1) as f64,
                median(&mut ms[m]),
                p90(&mut ms[m]),
                false_culls[m],
                truth_frames
            );
        }
        println!(
            "two-level (hzb, {} frames): first level {:.1} objects/frame, second keeps {:.1} ({:.1} % removed)",
            truth_frames, two_cand as f64 / truth_frames.max(1) as f64, two_vis as f64 / truth_frames.max(1) as f64,
            100.0 * (1.0 - two_vis as f64 / two_cand.max(1) as f64)
        );
    }
}
