//! Bytes and tiles a 3D Tiles client downloads along a street-level walk: the plain
//! tileset under screen-space-error refinement against the same client filtered by the
//! tile-level PVS (`docs/3d-tiles.md`, "Benchmark").
//!
//! ```text
//! cargo run --release -p sightline-tiles --example tiles_bench -- SCENE|metropolis:N \
//!     [--cell 25] [--steps 30] [--max-features 16] [--method dual-ray] [--no-truth]
//! ```
//!
//! The walk: on lines y = const every 20 m, points every 5 m at eye height 1.7 m, in
//! the middle of the scene (15 % margins in x, 20 % in y); the longest run of points outside every building is walked in 10 m steps, looking ahead
//! (the direction of the walk) and, every fifth step, turning round (looking back).
//! The client model is [`sightline_tiles::sse`] (1920 × 1080, 60° vertical field of
//! view, 16 px SSE, 5 km far plane); a tile is downloaded once (unbounded cache). The
//! PVS is the object PVS of the eye's cell on a grid of `--cell` metre cells at z
//! 1.5–2 m; with truth on (default) each cell's ground-truth visible set is computed
//! and a *missed* tile is one the plain client requests that holds a truly visible
//! feature but the PVS client does not request.

use sightline_core::check::{ground_truth, TruthScene};
use sightline_geom::{DVec3, ViewCell};
use sightline_scene::{generate, import, Scene};
use sightline_tiles::layout::Layout;
use sightline_tiles::sse::{requested, Camera};
use std::collections::{BTreeSet, HashMap};
use std::sync::Arc;
use std::time::Instant;

struct Args {
    scene: String,
    cell_m: f64,
    steps: usize,
    max_features: usize,
    method: String,
    truth: bool,
}

fn args() -> Result<Args, String> {
    let mut a = Args {
        scene: String::new(),
        cell_m: 25.0,
        steps: 30,
        max_features: 16,
        method: "dual-ray".into(),
        truth: true,
    };
    let mut it = std::env::args().skip(1);
    while let Some(s) = it.next() {
        let mut val = |name: &str| it.next().ok_or(format!("{name} needs a value"));
        match s.as_str() {
            "--cell" => a.cell_m = val("--cell")?.parse().map_err(|e| format!("--cell: {e}"))?,
            "--steps" => {
                a.steps = val("--steps")?
                    .parse()
                    .map_err(|e| format!("--steps: {e}"))?
            }
            "--max-features" => {
                a.max_features = val("--max-features")?
                    .parse()
                    .map_err(|e| format!("--max-features: {e}"))?
            }
            "--method" => a.method = val("--method")?,
            "--no-truth" => a.truth = false,
            _ if a.scene.is_empty() => a.scene = s,
            _ => return Err(format!("unexpected argument '{s}'")),
        }
    }
    if a.scene.is_empty() {
        return Err("usage: tiles_bench SCENE|metropolis:N [--cell M] [--steps N] [--max-features N] [--method M] [--no-truth]".into());
    }
    Ok(a)
}

fn load(spec: &str) -> Result<Scene, String> {
    if let Some(n) = spec.strip_prefix("metropolis:") {
        let n = n.parse().map_err(|e| format!("metropolis size: {e}"))?;
        return Ok(generate::metropolis(1, n));
    }
    import::load(std::path::Path::new(spec), &Default::default()).map_err(|e| e.to_string())
}

/// The longest free run along lines y = const (see the module doc), as walk points.
fn walk(scene: &Scene, free: &TruthScene, steps: usize) -> Vec<DVec3> {
    // Inside the middle of the city, not along its edge.
    let b = scene.bounds;
    let (margin_x, margin_y) = (0.15 * (b.max.x - b.min.x), 0.2 * (b.max.y - b.min.y));
    let mut best: Vec<DVec3> = vec![];
    let mut y = b.min.y + margin_y;
    while y < b.max.y - margin_y {
        let mut run: Vec<DVec3> = vec![];
        let mut x = b.min.x + margin_x;
        while x < b.max.x - margin_x {
            let p = DVec3::new(x, y, 1.7);
            if free.is_free(p)
                && free.is_free(p + DVec3::new(0.0, 2.0, 0.0))
                && free.is_free(p - DVec3::new(0.0, 2.0, 0.0))
            {
                run.push(p);
            } else {
                if run.len() > best.len() {
                    best = std::mem::take(&mut run);
                }
                run.clear();
            }
            x += 5.0;
        }
        if run.len() > best.len() {
            best = run;
        }
        y += 20.0;
    }
    best.into_iter().step_by(2).take(steps).collect()
}

/// Per cell: the tiles of its PVS, of its ground truth (if computed), and the PVS time (ms).
type CellSets = (BTreeSet<usize>, Option<BTreeSet<usize>>, f64);

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let a = args()?;
    let scene = Arc::new(load(&a.scene)?);
    let layout = Layout::build(&scene, a.max_features).ok_or("empty scene")?;
    let origin = scene.bounds.min;
    let sizes: Vec<u64> = (0..layout.tiles.len())
        .map(|t| {
            let tile = &layout.tiles[t];
            if tile.objects.is_empty() {
                0
            } else {
                sightline_tiles::glb::tile_glb(&scene, &tile.objects, tile.bounds.center()).len()
                    as u64
            }
        })
        .collect();
    let truth_scene = TruthScene::new(&scene);
    let points = walk(&scene, &truth_scene, a.steps);
    if points.len() < 2 {
        return Err("no free street run found for a walk".into());
    }
    let method = sightline_methods::create(&a.method, scene.clone(), &Default::default())
        .map_err(|e| e.to_string())?;
    let cell_of = |p: DVec3| {
        let i = ((p.x - origin.x) / a.cell_m).floor();
        let j = ((p.y - origin.y) / a.cell_m).floor();
        (i as i64, j as i64)
    };
    let mut cell_sets: HashMap<(i64, i64), CellSets> = HashMap::new();
    let (mut plain_seen, mut pvs_seen) = (BTreeSet::new(), BTreeSet::new());
    let (mut plain_req, mut pvs_req, mut missed) = (0usize, 0usize, 0usize);
    for (k, &p) in points.iter().enumerate() {
        let heading = if k + 1 < points.len() {
            points[k + 1] - p
        } else {
            p - points[k - 1]
        };
        let mut az = heading.y.atan2(heading.x);
        if k % 5 == 4 {
            az += std::f64::consts::PI;
        }
        let key = cell_of(p);
        if let std::collections::hash_map::Entry::Vacant(e) = cell_sets.entry(key) {
            let min = DVec3::new(
                origin.x + key.0 as f64 * a.cell_m,
                origin.y + key.1 as f64 * a.cell_m,
                1.5,
            );
            let cell = ViewCell::new(min, DVec3::new(min.x + a.cell_m, min.y + a.cell_m, 2.0))
                .map_err(|e| e.to_string())?;
            let t0 = Instant::now();
            let ids = method.pvs(&cell).map_err(|e| e.to_string())?;
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            let tiles = |ids: &[u32]| -> BTreeSet<usize> {
                ids.iter()
                    .map(|&i| layout.placement[i as usize].tile as usize)
                    .collect()
            };
            let truth = a
                .truth
                .then(|| tiles(&ground_truth(&scene, &cell, &Default::default()).visible));
            e.insert((tiles(&ids), truth, ms));
        }
        let (pvs_tiles, truth_tiles, _) = &cell_sets[&key];
        let cam = Camera::street(p, az);
        let plain = requested(&layout, &cam, None);
        let filter = |t: usize| pvs_tiles.contains(&t);
        let pvs = requested(&layout, &cam, Some(&filter));
        if let Some(truth) = truth_tiles {
            missed += plain
                .iter()
                .filter(|t| truth.contains(t) && !pvs.contains(t))
                .count();
        }
        plain_req += plain.len();
        pvs_req += pvs.len();
        plain_seen.extend(plain);
        pvs_seen.extend(pvs);
    }
    let bytes = |s: &BTreeSet<usize>| s.iter().map(|&t| sizes[t]).sum::<u64>();
    let (bp, bv) = (bytes(&plain_seen), bytes(&pvs_seen));
    let total: u64 = sizes.iter().sum();
    let mut ms: Vec<f64> = cell_sets.values().map(|v| v.2).collect();
    ms.sort_by(f64::total_cmp);
    let len = points.len() as f64 * 10.0 - 10.0;
    println!(
        "scene {}: {} objects, {} content tiles ({} max features), {} bytes of content",
        a.scene,
        scene.len(),
        layout.content_tiles().count(),
        a.max_features,
        total
    );
    println!("walk: {} steps over {len:.0} m from {:.0},{:.0} at z 1.7 m; {} cells of {} m, {} PVS median {:.1} ms/cell", points.len(), points[0].x, points[0].y, cell_sets.len(), a.cell_m, a.method, ms[ms.len() / 2]);
    println!(
        "plain SSE: {} tiles, {} bytes downloaded ({} requests over the walk)",
        plain_seen.len(),
        bp,
        plain_req
    );
    println!(
        "PVS + SSE: {} tiles, {} bytes downloaded ({} requests over the walk)",
        pvs_seen.len(),
        bv,
        pvs_req
    );
    println!(
        "bytes saved: {:.1} %; tiles saved: {:.1} %",
        100.0 * (1.0 - bv as f64 / bp.max(1) as f64),
        100.0 * (1.0 - pvs_seen.len() as f64 / plain_seen.len().max(1) as f64)
    );
    if a.truth {
        println!("visible tiles missed: {missed}");
    } else {
        println!("visible tiles missed: not checked (--no-truth)");
    }
    Ok(())
}
