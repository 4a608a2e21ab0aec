//! Time per cell of the four erosion methods on a generated grid city and, when the
//! vendored data is present, on Lyon 1er (25 m street cells).
//!
//! `cargo bench -p sightline-methods --bench erosion`

use criterion::{criterion_group, criterion_main, Criterion};
use sightline_core::check::{street_cells, Clearance};
use sightline_geom::{DVec2, Polygon};
use sightline_methods::{create, MethodOptions};
use sightline_scene::{Object, Scene};
use std::hint::black_box;
use std::sync::Arc;

/// A deterministic grid city: `n × n` blocks of 4 touching houses of varied heights,
/// 14 m streets.
fn grid_city(n: usize) -> Scene {
    let mut objs = Vec::new();
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed % 1000) as f64 / 1000.0
    };
    for i in 0..n {
        for j in 0..n {
            let (x0, y0) = (i as f64 * 54.0, j as f64 * 54.0);
            for k in 0..4 {
                let (dx, dy) = ((k % 2) as f64 * 20.0, (k / 2) as f64 * 20.0);
                let h = 6.0 + 30.0 * rnd() * rnd();
                objs.push(Object::block(
                    None,
                    Polygon::rect(
                        DVec2::new(x0 + dx, y0 + dy),
                        DVec2::new(x0 + dx + 20.0, y0 + dy + 20.0),
                    ),
                    0.0,
                    h,
                ));
            }
        }
    }
    Scene::from_objects(objs)
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("erosion");
    g.sample_size(10);
    // ~500 buildings, 50 m cells (paper: 458 buildings, 0.5 s per cell).
    let scene = Arc::new(grid_city(11));
    // 50 m cells are wider than the 14 m streets: those centred in a street.
    let cells = street_cells(&scene, 50.0, (1.5, 2.0), usize::MAX, Clearance::Centre);
    for m in [
        "erosion",
        "erosion-segment",
        "erosion-cell",
        "shrink-sphere",
    ] {
        let method = create(m, scene.clone(), &MethodOptions::default()).expect("method");
        // Warm the per-shape erosion cache (precomputed once per cell shape, §5.1).
        method.pvs(&cells[0]).expect("pvs");
        let mut k = 0;
        g.bench_function(format!("{m}/city484/50m"), |b| {
            b.iter(|| {
                k += 1;
                black_box(method.pvs(&cells[k % cells.len()]).expect("pvs"))
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
