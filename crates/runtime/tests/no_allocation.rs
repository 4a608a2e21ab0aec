//! Once its [`Query`] scratch is warm, a query allocates nothing: locate, decode a row
//! into a reused buffer, the visible leaves, the neighbours, and the gameplay queries
//! once their index is built. Counted by a global allocator (this file holds one test so
//! that no other thread allocates meanwhile).

#[path = "common/synthetic.rs"]
mod synthetic;

use sightline_runtime::{Pvs, Query};
use std::alloc::{GlobalAlloc, Layout, System};
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

#[test]
fn queries_allocate_nothing_once_warm() {
    let pvs = Pvs::from_vec(synthetic::city_file(400, 600)).unwrap();
    pvs.prepare_gameplay().unwrap();
    let points: Vec<[f64; 3]> = (0..pvs.cell_count())
        .map(|c| {
            let b = pvs.cell_box(c).unwrap();
            [0.5 * (b[0] + b[3]), 0.5 * (b[1] + b[4]), 1.7]
        })
        .collect();
    let mut q = Query::new();
    let (mut row, mut out) = (Vec::new(), Vec::new());
    let pass = |q: &mut Query, row: &mut Vec<u32>, out: &mut Vec<u32>| {
        let mut total = 0usize;
        for (c, p) in points.iter().enumerate() {
            let cell = pvs.locate(*p).unwrap();
            assert_eq!(cell as usize, c);
            pvs.visible_into(q, cell, row).unwrap();
            total += row.len() + pvs.visible(q, cell).unwrap().len();
            pvs.neighbours_into(cell, out);
            total += out.len();
            total += pvs.can_see(q, cell, (cell + 7) % pvs.cell_count()).unwrap() as usize;
            pvs.cells_seeing_into(q, cell, out).unwrap();
            pvs.secondary_into(q, cell, out).unwrap();
            total += out.len();
        }
        total
    };
    let warm = pass(&mut q, &mut row, &mut out);
    let before = ALLOCATIONS.load(Ordering::Relaxed);
    let again = pass(&mut q, &mut row, &mut out);
    let after = ALLOCATIONS.load(Ordering::Relaxed);
    assert_eq!(warm, again);
    assert_eq!(
        after - before,
        0,
        "{} allocations over {} cells",
        after - before,
        points.len()
    );
}
