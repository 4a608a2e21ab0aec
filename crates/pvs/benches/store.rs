//! Storage and query figures of the `.pvs` store on a PVS-like synthetic metropolis
//! workload (`cargo bench -p sightline-pvs --bench store`).
//!
//! The workload stands in for a real method until a fast conservative one is available
//! at this scale: 150,000 buildings on a 25.8 m pitch over 10 km × 10 km, 10,000 cells of
//! 100 m, and per cell the objects within 150 m, those along the cell's two streets up to
//! 800 m away, and the towers (one object in 53) within 2 km. Neighbouring cells therefore
//! share most of their sets, as real PVSs do. Sizes: `SIGHTLINE_BENCH_SIDE` cells per
//! side (default 100).

use sightline_geom::{DVec2, DVec3, Polygon, ViewCell};
use sightline_methods::{MethodError, VisibilityMethod};
use sightline_pvs::format::{encode_with, EncodeOptions};
use sightline_pvs::{build, BuildOptions, PvsFile};
use sightline_scene::{Object, Scene};
use std::time::Instant;

const PITCH: f64 = 25.8;
const SIDE_OBJECTS: usize = 387; // 387² ≈ 150,000 buildings

struct Synthetic;

impl VisibilityMethod for Synthetic {
    fn name(&self) -> &'static str {
        "synthetic"
    }

    fn pvs(&self, cell: &ViewCell) -> Result<Vec<u32>, MethodError> {
        let c = cell.center();
        let (ci, cj) = ((c.x / PITCH) as i64, (c.y / PITCH) as i64);
        let mut ids = Vec::new();
        let r_near = (150.0 / PITCH) as i64;
        let r_street = (800.0 / PITCH) as i64;
        let r_tower = (2000.0 / PITCH) as i64;
        let n = SIDE_OBJECTS as i64;
        for j in (cj - r_tower).max(0)..(cj + r_tower + 1).min(n) {
            for i in (ci - r_tower).max(0)..(ci + r_tower + 1).min(n) {
                let (di, dj) = (i - ci, j - cj);
                let id = j * n + i;
                let near = di * di + dj * dj <= r_near * r_near;
                let street = (di.abs() <= 1 && dj.abs() <= r_street)
                    || (dj.abs() <= 1 && di.abs() <= r_street);
                let tower = id % 53 == 0 && di * di + dj * dj <= r_tower * r_tower;
                if near || street || tower {
                    ids.push(id as u32);
                }
            }
        }
        Ok(ids)
    }
}

fn main() {
    let side: usize = std::env::var("SIGHTLINE_BENCH_SIDE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(100);
    let objects: Vec<Object> = (0..SIDE_OBJECTS * SIDE_OBJECTS)
        .map(|k| {
            let p = DVec2::new(
                (k % SIDE_OBJECTS) as f64 * PITCH,
                (k / SIDE_OBJECTS) as f64 * PITCH,
            );
            Object::block(None, Polygon::rect(p, p + DVec2::splat(18.0)), 0.0, 12.0)
        })
        .collect();
    let scene = Scene::from_objects(objects);
    let size = SIDE_OBJECTS as f64 * PITCH / side as f64;
    let cells: Vec<ViewCell> = (0..side * side)
        .map(|k| {
            let (i, j) = ((k % side) as f64, (k / side) as f64);
            ViewCell::from_array([
                i * size,
                j * size,
                1.5,
                (i + 1.0) * size,
                (j + 1.0) * size,
                2.0,
            ])
            .unwrap()
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("city.pvs");
    let t = Instant::now();
    let stats = build(
        &scene,
        &Synthetic,
        &cells,
        &out,
        &BuildOptions::default(),
        &|_, _| {},
    )
    .unwrap();
    let build_s = t.elapsed().as_secs_f64();

    let file = PvsFile::open(&out).unwrap();
    let sets: Vec<roaring::RoaringBitmap> =
        (0..cells.len()).map(|i| file.bitmap(i).unwrap()).collect();
    let ids: u64 = sets.iter().map(|s| s.len()).sum();
    let n = cells.len() as f64;
    let present: Vec<u32> = (0..cells.len() as u32).collect();
    let whole = encode_with(
        file.header(),
        &cells,
        &present,
        &sets,
        &EncodeOptions { delta: false },
    )
    .unwrap();
    let roaring_raw: usize = sets.iter().map(|s| s.serialized_size()).sum();
    let (data, total) = file.sizes();
    let u32_list = ids as f64 * 4.0;
    let bitset = n * (scene.objects.len() as f64 / 8.0).ceil();
    println!(
        "synthetic metropolis: {} objects, {} cells, mean PVS {:.0} ids",
        scene.objects.len(),
        cells.len(),
        ids as f64 / n
    );
    println!(
        "build: {build_s:.2} s total ({:.1} s compute, {:.1} s encode), {:.0} cells/s",
        stats.compute_seconds,
        stats.encode_seconds,
        n / build_s
    );
    println!(
        "file: {total} B = {:.1} B/cell (data section {:.1} B/cell)",
        total as f64 / n,
        data as f64 / n
    );
    println!(
        "  vs sorted u32 lists ({:.0} B/cell): {:.2} %",
        u32_list / n,
        100.0 * total as f64 / u32_list
    );
    println!(
        "  vs raw bitsets ({:.0} B/cell): {:.3} %",
        bitset / n,
        100.0 * total as f64 / bitset
    );
    println!(
        "  vs plain roaring, no zstd ({:.0} B/cell): {:.2} %",
        roaring_raw as f64 / n,
        100.0 * total as f64 / roaring_raw as f64
    );
    println!(
        "  no delta (whole sets, roaring + zstd): {:.1} B/cell -> delta saves {:.1} %",
        whole.len() as f64 / n,
        100.0 * (1.0 - total as f64 / whole.len() as f64)
    );

    // Query latency from a warm file: random points, each timed.
    let mut rng = 0x1234_5678_u64;
    let mut next = || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let extent = SIDE_OBJECTS as f64 * PITCH;
    for _ in 0..2000 {
        let _ = file
            .query(DVec3::new(next() * extent, next() * extent, 1.7))
            .unwrap();
    }
    let mut times: Vec<f64> = (0..20_000)
        .map(|_| {
            let p = DVec3::new(next() * extent, next() * extent, 1.7);
            let t = Instant::now();
            let r = file.query(p).unwrap();
            let dt = t.elapsed().as_secs_f64() * 1e6;
            assert!(r.is_some());
            dt
        })
        .collect();
    times.sort_by(f64::total_cmp);
    println!(
        "query (random points, warm file): p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs",
        sightline_stats::quantile_sorted(&times, 0.5),
        sightline_stats::quantile_sorted(&times, 0.99),
        times[times.len() - 1]
    );
    // A walk: consecutive points 2 m apart (the server's pattern).
    let mut times: Vec<f64> = (0..20_000)
        .map(|k| {
            let x = (k as f64 * 2.0) % extent;
            let y = extent * 0.37 + (k as f64 * 2.0 / extent).floor() * 50.0;
            let t = Instant::now();
            let _ = file.query(DVec3::new(x, y % extent, 1.7)).unwrap();
            t.elapsed().as_secs_f64() * 1e6
        })
        .collect();
    times.sort_by(f64::total_cmp);
    println!(
        "query (walk): p50 {:.1} µs, p99 {:.1} µs",
        sightline_stats::quantile_sorted(&times, 0.5),
        sightline_stats::quantile_sorted(&times, 0.99)
    );
}
