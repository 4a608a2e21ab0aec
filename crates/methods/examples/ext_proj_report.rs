//! Figures for the ext-proj report (run in release):
//! `cargo run --release -p sightline-methods --example ext_proj_report -- SCENE.geojson [cells]`
//!
//! Street cells are picked on a grid over the scene (`check::street_cells`: 10 m, eye
//! height 1.5–2 m, free of blocks at their centre); prints ext-proj vs erosion (time, PVS), the resolution
//! curve (Fig. 12) and the improved-projection gain. With `forest` instead of a path
//! it builds a synthetic forest and prints plain vs sweep with 1, 5, 15 planes.

use sightline_core::check::{street_cells, Clearance};
use sightline_geom::{DVec2, DVec3, Polygon, ViewCell};
use sightline_methods::ext_proj::experiments::{improved_gain, resolution_curve, run, sweep_curve};
use sightline_methods::ext_proj::Params;
use sightline_methods::{create, MethodOptions};
use sightline_scene::{import, Mesh, Object, Prism, Scene};
use std::sync::Arc;
use std::time::Instant;

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
            let c = DVec2::new(i as f64 * 5.0, j as f64 * 5.0);
            let trunk = Prism::new(
                Polygon::rect(c - DVec2::splat(0.2), c + DVec2::splat(0.2)).normalized(),
                0.0,
                3.0,
            );
            let mut m = Mesh::default();
            for t in trunk.triangles() {
                let base = m.vertices.len() as u32;
                m.vertices.extend(t);
                m.triangles.push([base, base + 1, base + 2]);
            }
            for _ in 0..leaves {
                let p = DVec3::new(
                    c.x + rnd() * 4.0 - 2.0,
                    c.y + rnd() * 4.0 - 2.0,
                    1.0 + rnd() * 5.0,
                );
                let base = m.vertices.len() as u32;
                m.vertices.extend([
                    p,
                    p + DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 2.0,
                    p + DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * 2.0,
                ]);
                m.triangles.push([base, base + 1, base + 2]);
            }
            let outer = Prism::new(
                Polygon::rect(c - DVec2::splat(3.0), c + DVec2::splat(3.0)).normalized(),
                0.0,
                7.5,
            );
            objs.push(Object::mesh(None, m, vec![trunk], vec![outer]));
        }
    }
    Scene::from_objects(objs)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).cloned().unwrap_or_else(|| "forest".into());
    let want: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(50);
    if what == "forest" {
        let scene = Arc::new(forest(20, 300));
        // Cells in the gaps between trees.
        let cells: Vec<ViewCell> = (0..want)
            .map(|k| {
                let (i, j) = (3 + (k * 7) % 14, 3 + (k * 5) % 14);
                let (x, y) = (i as f64 * 5.0 + 2.5, j as f64 * 5.0 + 2.5);
                ViewCell::new(
                    DVec3::new(x - 0.4, y - 0.4, 1.5),
                    DVec3::new(x + 0.4, y + 0.4, 2.0),
                )
                .expect("cell")
            })
            .collect();
        let tris: usize = scene.objects.iter().map(|o| o.triangle_count()).sum();
        println!(
            "forest: {} trees, {} triangles, {} cells",
            scene.objects.len(),
            tris,
            cells.len()
        );
        for (k, s) in sweep_curve(&scene, &cells, &[1, 5, 15], &Params::default()) {
            println!(
                "{:>8}  culled objects {:5.1} %  culled triangles {:5.1} %  mean PVS {:6.1}  ms/cell median {:8.1} mean {:8.1}",
                k.map(|k| format!("sweep {k}")).unwrap_or("plain".into()),
                100.0 * s.hidden_fraction,
                100.0 * s.culled_triangles,
                s.mean_pvs,
                s.ms_median,
                s.ms_mean
            );
        }
        return;
    }
    let t = Instant::now();
    let scene = match import::load(std::path::Path::new(&what), &Default::default()) {
        Ok(s) => Arc::new(s),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let cells = street_cells(&scene, 10.0, (1.5, 2.0), want, Clearance::Centre);
    println!(
        "{}: {} objects, {} cells, loaded in {:.0} ms",
        what,
        scene.objects.len(),
        cells.len(),
        t.elapsed().as_secs_f64() * 1e3
    );
    let base = Params::default();
    let s = run(&scene, &cells, base.clone());
    println!(
        "ext-proj 256: mean PVS {:.1}, hidden {:.1} %, ms/cell median {:.1} mean {:.1}, prepare {:.0} ms",
        s.mean_pvs,
        100.0 * s.hidden_fraction,
        s.ms_median,
        s.ms_mean,
        s.prepare_ms
    );
    let t = Instant::now();
    if let Ok(er) = create("erosion", scene.clone(), &MethodOptions::default()) {
        let prep = t.elapsed().as_secs_f64() * 1e3;
        let mut times = Vec::new();
        let mut sizes = 0usize;
        let mut ratio = Vec::new();
        for (c, ep) in cells.iter().zip(&s.pvs) {
            let t = Instant::now();
            let p = er.pvs(c).unwrap_or_default();
            times.push(t.elapsed().as_secs_f64() * 1e3);
            sizes += p.len();
            ratio.push(ep.len() as f64 / p.len().max(1) as f64);
        }
        times.sort_by(f64::total_cmp);
        ratio.sort_by(f64::total_cmp);
        println!(
            "erosion: mean PVS {:.1}, ms/cell median {:.1}, prepare {:.0} ms; |ext-proj|/|erosion| median {:.2}",
            sizes as f64 / cells.len().max(1) as f64,
            times[times.len() / 2],
            prep,
            ratio[ratio.len() / 2]
        );
    }
    let (std, imp, gain) = improved_gain(&scene, &cells, &base);
    println!(
        "improved projection: mean PVS {:.1} -> {:.1} ({:.1} % smaller)",
        std.mean_pvs,
        imp.mean_pvs,
        100.0 * gain
    );
    for (r, s) in resolution_curve(&scene, &cells, &[64, 128, 256, 512, 1024], &base) {
        println!(
            "resolution {:5}: hidden {:5.1} %  mean PVS {:6.1}  ms/cell median {:7.1} mean {:7.1}",
            r,
            100.0 * s.hidden_fraction,
            s.mean_pvs,
            s.ms_median,
            s.ms_mean
        );
    }
}
