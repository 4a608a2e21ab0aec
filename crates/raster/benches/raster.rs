//! Rasterizer throughput: triangles/s and pixels/s per coverage rule, occlusion
//! queries/s, and a whole cube map in parallel (rayon across faces).
//! Anchor: Masked Occlusion Culling, about 5–14 M triangles/s on one core.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::DVec3;
use sightline_raster::{render_cube, Coverage, Face, Framebuffer, View};

#[path = "workload/mod.rs"]
mod workload;
use workload::triangles;

fn bench(c: &mut Criterion) {
    let eye = DVec3::ZERO;
    let view = View::cube_face(eye, Face::PosY, 512, 0.01);
    let tris = triangles(20_000, 2.0);
    let mut g = c.benchmark_group("draw_20k_triangles_512px");
    g.sample_size(10);
    g.measurement_time(std::time::Duration::from_secs(3));
    g.throughput(Throughput::Elements(tris.len() as u64));
    for (name, cov) in [
        ("standard", Coverage::Standard),
        ("inner", Coverage::Inner),
        ("outer", Coverage::Outer),
    ] {
        let mut fb = Framebuffer::for_view(&view);
        fb.draw_polygon(&view, &tris[0], 0, cov);
        // Pixels per triangle (each drawn alone) over a sample: pixels/s = triangles/s × this.
        let mut pixels = 0usize;
        let probes = 500;
        {
            let mut probe = Framebuffer::for_view(&view);
            for (k, t) in tris.iter().take(probes).enumerate() {
                probe.clear();
                probe.draw_triangle(&view, t, k as u32, cov);
                pixels += probe.ids.iter().filter(|&&i| i != u32::MAX).count();
            }
        }
        eprintln!(
            "{name}: ~{:.1} pixels per triangle",
            pixels as f64 / probes as f64
        );
        g.bench_function(name, |b| {
            b.iter(|| {
                fb.clear();
                for (k, t) in tris.iter().enumerate() {
                    fb.draw_triangle(&view, t, k as u32, cov);
                }
            })
        });
    }
    g.finish();

    let mut fb = Framebuffer::for_view(&view);
    for (k, t) in tris.iter().enumerate() {
        fb.draw_triangle(&view, t, k as u32, Coverage::Inner);
    }
    let pyr = fb.pyramid();
    let queries = triangles(20_000, 1.0);
    let mut g = c.benchmark_group("occlusion_queries_20k");
    g.sample_size(10);
    g.measurement_time(std::time::Duration::from_secs(3));
    g.throughput(Throughput::Elements(queries.len() as u64));
    g.bench_function("pyramid_triangle_occluded", |b| {
        b.iter(|| {
            queries
                .iter()
                .filter(|t| pyr.triangle_occluded(&view, t))
                .count()
        })
    });
    g.finish();

    let mut g = c.benchmark_group("cube_map_20k_triangles_512px");
    g.sample_size(10);
    g.measurement_time(std::time::Duration::from_secs(3));
    g.throughput(Throughput::Elements(tris.len() as u64));
    g.bench_function("standard_6_faces_rayon", |b| {
        b.iter(|| {
            render_cube(DVec3::new(0.0, 50.0, 0.0), 512, 0.01, |v, fb| {
                for (k, t) in tris.iter().enumerate() {
                    fb.draw_triangle(v, t, k as u32, Coverage::Standard);
                }
            })
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
