//! Criterion bench of the dual ray space method (Koltun et al. 2001, Table 1 setting):
//! one 100 × 100 × 2 m street cell of a generated metropolis at 128² (single thread),
//! and the 9-cell neighbourhood of §6 in parallel.
//!
//! The full Table 1 reproduction (resolutions 16..256 × cells 50/100/300 m, with the
//! exact algorithm as reference) is `sightline_methods::dual_ray::table1`, run by
//! `cargo bench -p sightline-methods --bench dual_ray -- table1` when
//! `DUAL_RAY_TABLE1=1` is set (it takes minutes, so it is opt-in).

use criterion::{criterion_group, criterion_main, Criterion};
use sightline_geom::ViewCell;
use sightline_methods::dual_ray::{crossing_cells, table1, DualRay, Planarity};
use sightline_scene::generate::metropolis;
use std::sync::Arc;

fn bench(c: &mut Criterion) {
    let scene = Arc::new(metropolis(1, 100_000));
    let m = DualRay::new(
        "dual-ray",
        scene.clone(),
        Planarity::Discrete { resolution_px: 128 },
    );
    let cells = crossing_cells(&scene, 100.0, 16);
    let mut g = c.benchmark_group("dual_ray");
    g.sample_size(10);
    let mut i = 0;
    g.bench_function("cell100_res128_single_thread", |b| {
        b.iter(|| {
            i = (i + 1) % cells.len();
            m.pvs_with_stats(&cells[i]).0.len()
        })
    });
    g.bench_function("neighbourhood9_res128", |b| {
        b.iter(|| {
            i = (i + 1) % cells.len();
            m.pvs_with_neighbours(&cells[i]).len()
        })
    });
    g.finish();
    if std::env::var("DUAL_RAY_TABLE1").is_ok() {
        let groups: Vec<(f64, Vec<ViewCell>)> = [50.0, 100.0, 300.0]
            .iter()
            .map(|s| (*s, crossing_cells(&scene, *s, 20)))
            .collect();
        let rows = table1(scene.clone(), &groups, &[16, 32, 64, 128, 256]);
        println!("size_m\tres\tcells\tms_median\tms_mean\tpvs_mean\tover_est\ttests");
        for r in rows {
            println!(
                "{}\t{}\t{}\t{:.2}\t{:.2}\t{:.1}\t{:.5}\t{:.0}",
                r.cell_size_m,
                r.resolution_px,
                r.cells,
                r.ms_median,
                r.ms_mean,
                r.pvs_mean,
                r.overestimation,
                r.planar_tests_mean
            );
        }
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
