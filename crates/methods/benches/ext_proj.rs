//! Criterion benchmark of `ext-proj`: time per cell, plain and with the occlusion sweep,
//! on a synthetic street grid and a synthetic forest (heavier scenes and the
//! paper's curves are in `sightline bench` through `ext_proj::experiments`).

use criterion::{criterion_group, criterion_main, Criterion};
use sightline_geom::{DVec2, DVec3, Polygon, ViewCell};
use sightline_methods::ext_proj::{ExtProj, Params};
use sightline_methods::VisibilityMethod;
use sightline_scene::{Mesh, Object, Prism, Scene};
use std::hint::black_box;
use std::sync::Arc;

fn grid_city(n: usize) -> Scene {
    let mut objs = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (i as f64 * 40.0, j as f64 * 40.0);
            for k in 0..4 {
                let x0 = x + 7.0 * k as f64;
                objs.push(Object::block(
                    None,
                    Polygon::rect(DVec2::new(x0, y), DVec2::new(x0 + 7.0, y + 28.0)),
                    0.0,
                    10.0 + ((i * 7 + j * 3 + k) % 9) as f64 * 3.0,
                ));
            }
        }
    }
    Scene::from_objects(objs)
}

fn forest(n: usize, leaves: usize) -> Scene {
    let mut s = 0x2545_f491_4f6c_dd1du64;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut objs = Vec::new();
    for i in 0..n {
        for j in 0..n {
            let c = DVec2::new(i as f64 * 5.0 + 5.0, j as f64 * 5.0 - 2.5 * n as f64);
            let trunk = Prism::new(
                Polygon::rect(c - DVec2::splat(0.2), c + DVec2::splat(0.2)).normalized(),
                0.0,
                3.0,
            );
            let mut m = Mesh::default();
            for _ in 0..leaves {
                let p = DVec3::new(
                    c.x + rnd() * 4.0 - 2.0,
                    c.y + rnd() * 4.0 - 2.0,
                    1.0 + rnd() * 5.0,
                );
                let base = m.vertices.len() as u32;
                m.vertices.extend([
                    p,
                    p + DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 1.5,
                    p + DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 1.5,
                ]);
                m.triangles.push([base, base + 1, base + 2]);
            }
            let outer = Prism::new(
                Polygon::rect(c - DVec2::splat(2.8), c + DVec2::splat(2.8)).normalized(),
                0.0,
                7.0,
            );
            objs.push(Object::mesh(None, m, vec![trunk], vec![outer]));
        }
    }
    Scene::from_objects(objs)
}

fn bench(c: &mut Criterion) {
    let city = Arc::new(grid_city(8));
    let cell: ViewCell = "130,29,1.5,140,39,2".parse().expect("cell");
    let plain = ExtProj::new(city.clone(), Params::default());
    c.bench_function("ext-proj city 256", |b| {
        b.iter(|| black_box(plain.pvs(&cell)))
    });

    let trees = Arc::new(forest(10, 120));
    let fcell: ViewCell = "0,-1,1.5,2,1,2".parse().expect("cell");
    let plain = ExtProj::new(trees.clone(), Params::default());
    c.bench_function("ext-proj forest plain", |b| {
        b.iter(|| black_box(plain.pvs(&fcell)))
    });
    let swept = ExtProj::new(
        trees.clone(),
        Params {
            sweep: true,
            sweep_planes: 5,
            ..Params::default()
        },
    );
    c.bench_function("ext-proj forest sweep 5", |b| {
        b.iter(|| black_box(swept.pvs(&fcell)))
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(10);
    targets = bench
}
criterion_main!(benches);
