//! Rasterizer throughput in **CPU time** of the measuring thread (robust on a shared,
//! loaded machine where criterion's wall-clock figures swing): the workloads of
//! `benches/raster.rs` (20 000 random triangles of about 2 m, 5–100 m ahead, one
//! 512 px view), triangles/s and pixels/s per coverage rule and occlusion queries/s.
//!
//! `cargo run --release -p sightline-raster --example raster_cpu [REPEATS]`. Linux
//! only (reads `/proc/thread-self/schedstat`); prints the median of `REPEATS` passes.

use glam::DVec3;
use sightline_raster::{Coverage, Face, Framebuffer, View};

#[path = "../benches/workload/mod.rs"]
mod workload;
use workload::triangles;

fn cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|t| t.parse().ok()))
        .unwrap_or(0)
}

/// Median CPU seconds of one call of `f`. The counter advances at scheduler ticks
/// only, so each pass repeats `f` for at least 0.25 s of wall time.
fn median_s(mut f: impl FnMut(), repeats: usize) -> f64 {
    let t: Vec<f64> = (0..repeats)
        .map(|_| {
            let (a, w) = (cpu_ns(), std::time::Instant::now());
            let mut n = 0u32;
            while n == 0 || w.elapsed().as_secs_f64() < 0.25 {
                f();
                n += 1;
            }
            (cpu_ns() - a) as f64 * 1e-9 / n as f64
        })
        .collect();
    sightline_stats::median(&t)
}

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(7);
    let view = View::cube_face(DVec3::ZERO, Face::PosY, 512, 0.01);
    let tris = triangles(20_000, 2.0);
    println!("20 000 triangles, 512 px view, median of {repeats} passes (thread CPU time)");
    let mut fb = Framebuffer::for_view(&view);
    for (name, cov) in [
        ("standard", Coverage::Standard),
        ("inner", Coverage::Inner),
        ("outer", Coverage::Outer),
    ] {
        let mut probe = Framebuffer::for_view(&view);
        let mut px = 0usize;
        for (k, t) in tris.iter().take(500).enumerate() {
            probe.clear();
            probe.draw_triangle(&view, t, k as u32, cov);
            px += probe.ids.iter().filter(|&&i| i != u32::MAX).count();
        }
        let px_per_tri = px as f64 / 500.0;
        let s = median_s(
            || {
                fb.clear();
                for (k, t) in tris.iter().enumerate() {
                    fb.draw_triangle(&view, t, k as u32, cov);
                }
            },
            repeats,
        );
        let tps = tris.len() as f64 / s;
        println!(
            "{name:>8}: {:6.2} M triangles/s, {:6.1} M pixels/s ({px_per_tri:.1} px/triangle)",
            tps * 1e-6,
            tps * px_per_tri * 1e-6
        );
    }
    fb.clear();
    for (k, t) in tris.iter().enumerate() {
        fb.draw_triangle(&view, t, k as u32, Coverage::Inner);
    }
    let pyr = fb.pyramid();
    let queries = triangles(20_000, 1.0);
    let mut hidden = 0;
    let s = median_s(
        || {
            hidden = queries
                .iter()
                .filter(|t| pyr.triangle_occluded(&view, t))
                .count()
        },
        repeats,
    );
    println!(
        "pyramid: {:6.2} M occlusion queries/s ({hidden} of {} hidden)",
        queries.len() as f64 / s * 1e-6,
        queries.len()
    );
    let s = median_s(
        || {
            std::hint::black_box(fb.pyramid());
        },
        repeats,
    );
    println!("pyramid build: {:.3} ms (512 px)", s * 1e3);
}
