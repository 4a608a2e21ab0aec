//! The leaf rows a level carries in its visibility lump (as written by `sightline vis`,
//! ericw-tools' `vis` or id's), checked against the ray oracle and compared with
//! another file's rows (say the level as shipped):
//!
//! ```text
//! cargo run --release -p sightline-portals --example vis_rows LEVEL.bsp [REFERENCE.bsp]
//! ```
//! Prints `sum=Σ|row| ref_sum=Σ|reference row| ratio=… sources=K misses=M`: `K`
//! (`VIS_SOURCES`, default 60) source leaves, evenly spread, each against every open
//! leaf its row lacks, 16 random segments per pair; a clear one is a miss.

use sightline_portals::oracle::{pair_visible, sample_leaf, Rng};
use sightline_scene::import::bsp::load_bsp;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        eprintln!("usage: vis_rows LEVEL.bsp [REFERENCE.bsp]");
        std::process::exit(2);
    };
    let level = match load_bsp(Path::new(path)) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    let rows: Vec<Vec<u32>> = (1..=level.visleafs)
        .map(|l| level.reference_row(l))
        .collect();
    let sum: usize = rows.iter().map(Vec::len).sum();
    let ref_sum = args.get(1).map(|r| match load_bsp(Path::new(r)) {
        Ok(r) => (1..=r.visleafs)
            .map(|l| r.reference_row(l).len())
            .sum::<usize>(),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    });
    let k: usize = std::env::var("VIS_SOURCES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(60);
    let view: Vec<u32> = (1..=level.visleafs)
        .filter(|&l| level.is_view_leaf(l))
        .collect();
    let mut rng = Rng::new(49);
    let points: Vec<Vec<[f64; 3]>> = (0..level.leaves.len() as u32)
        .map(|l| sample_leaf(&level, l, 12, &mut rng))
        .collect();
    let step = (view.len() / k.max(1)).max(1);
    let (mut sources, mut misses) = (0, 0);
    for &s in view.iter().step_by(step) {
        sources += 1;
        let row = &rows[s as usize - 1];
        for &t in &view {
            if row.binary_search(&t).is_err()
                && pair_visible(
                    &level,
                    &points[s as usize],
                    &points[t as usize],
                    16,
                    &mut rng,
                )
            {
                misses += 1;
            }
        }
    }
    let ratio = ref_sum.map_or(String::from("-"), |r| {
        format!("{:.4}", sum as f64 / r.max(1) as f64)
    });
    println!(
        "sum={sum} ref_sum={} ratio={ratio} sources={sources} misses={misses}",
        ref_sum.map_or(String::from("-"), |r| r.to_string())
    );
}
