//! Locate a point and decode its cell's row on a 10,000-cell city `.pvs` (the project's
//! city generator, PVS-like synthetic rows: `tests/common/synthetic.rs`), with a warm
//! [`Query`] (its block cache holds the file's blocks after the first pass), and the
//! allocations per query counted by a global allocator.
//!
//! `cargo bench -p sightline-runtime --bench query` (target: median ≤ 2 µs, 0 allocations).

#[path = "../tests/common/synthetic.rs"]
mod synthetic;

use criterion::{criterion_group, criterion_main, Criterion};
use sightline_runtime::{Pvs, Query};
use std::alloc::{GlobalAlloc, Layout, System};
use std::hint::black_box;
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards to the system allocator, only counting.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn bench(c: &mut Criterion) {
    let t = std::time::Instant::now();
    let bytes = synthetic::city_file(5000, 10_000);
    let pvs = Pvs::from_vec(bytes).unwrap();
    let n = pvs.cell_count();
    // Random points of random cells (xorshift), not a walk: every block is visited.
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let points: Vec<[f64; 3]> = (0..4096)
        .map(|_| {
            let b = pvs.cell_box((next() % n as u64) as u32).unwrap();
            let f = |k: usize, r: u64| b[k] + (b[k + 3] - b[k]) * (r % 1000) as f64 / 1000.0;
            [f(0, next()), f(1, next()), f(2, next())]
        })
        .collect();
    let mut q = Query::new();
    let mut row = Vec::new();
    let mut total = 0usize;
    for p in &points {
        let cell = pvs.locate(*p).unwrap();
        pvs.visible_into(&mut q, cell, &mut row).unwrap();
        total += row.len();
    }
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    for p in &points {
        let cell = pvs.locate(*p).unwrap();
        pvs.visible_into(&mut q, cell, &mut row).unwrap();
    }
    let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
    eprintln!(
        "{n} cells, {} objects, mean row {:.0} ids; setup {:.1} s; {allocations} allocations over {} warm queries",
        pvs.object_count(),
        total as f64 / points.len() as f64,
        t.elapsed().as_secs_f64(),
        points.len()
    );
    let mut k = 0;
    c.bench_function("locate + decode a row (10,000-cell city, warm)", |b| {
        b.iter(|| {
            let p = &points[k % points.len()];
            k += 1;
            let cell = pvs.locate(black_box(*p)).unwrap();
            pvs.visible_into(&mut q, cell, &mut row).unwrap();
            black_box(row.len())
        })
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
